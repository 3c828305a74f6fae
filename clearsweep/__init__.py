"""clearsweep: dynamics and wear of the RSSP mechanism and the planar slider-crank with
clearance and coatings in any of their joints (the crank's bearing O, the crank pin A, the
rod-slider joint B, the slider's guide P)."""

from .version import __version__

__all__ = ["__version__", "simulate", "life", "sweep", "open_results", "load_config"]


def __getattr__(name):
    # Lazy public API: importing the package stays cheap (no Numba compile, no xarray).
    if name == "simulate":
        from .simulation import simulate
        return simulate
    if name == "life":
        from .service_life import life
        return life
    if name == "sweep":
        from .sweeping.run import run_sweep
        return run_sweep
    if name == "open_results":
        from .dataset import open_results
        return open_results
    if name == "load_config":
        from .config import load_config
        return load_config
    # Module names differ from the function names (simulation / simulate, service_life / life, the package
    # sweeping / sweep) so that importing a submodule never shadows the public function
    # on the package: `import clearsweep.sweep` would bind the module over the function.
    raise AttributeError(f"module 'clearsweep' has no attribute {name!r}")
