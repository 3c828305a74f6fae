"""clearsweep: dynamics and wear of the RSSP mechanism with clearance and coated spherical joints."""

__version__ = "0.1.0"

__all__ = ["__version__", "simulate", "sweep", "open_results", "load_config"]


def __getattr__(name):
    # Lazy public API: importing the package stays cheap (no Numba compile, no xarray).
    if name == "simulate":
        from .simulation import simulate
        return simulate
    if name == "sweep":
        from .sweeps import sweep
        return sweep
    if name == "open_results":
        from .sweeps import open_results
        return open_results
    if name == "load_config":
        from .config import load_config
        return load_config
    # Module names differ from the function names so that importing a submodule
    # never shadows the public function on the package.
    raise AttributeError(f"module 'clearsweep' has no attribute {name!r}")
