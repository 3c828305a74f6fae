"""Kernel arrays -> labelled ``xr.Dataset`` with CF attributes and provenance."""

from __future__ import annotations

import datetime as _dt
import os
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import xarray as xr

from .variables import AXES, CASE_VARIABLES, JOINTS, attrs_for


def versions() -> dict[str, str]:
    """Versions of the package and of the libraries that shape its numbers."""
    import numba

    from . import __version__

    return {
        "clearsweep_version": __version__,
        "numba_version": numba.__version__,
        "numpy_version": np.__version__,
        "xarray_version": xr.__version__,
        "python_version": sys.version.split()[0],
    }


def bin_centres_deg(n: int, lo: float, hi: float) -> np.ndarray:
    """Centres of ``n`` equal bins spanning [lo, hi] degrees."""
    edges = np.linspace(lo, hi, n + 1)
    return 0.5 * (edges[:-1] + edges[1:])


def build_dataset(arrays: dict[str, np.ndarray], time_s: np.ndarray, *,
                  config_text: str = "", attrs: dict | None = None) -> xr.Dataset:
    """Label the arrays of one case.

    Parameters
    ----------
    arrays
        Mapping from registered variable names (``variables.CASE_VARIABLES``)
        to arrays shaped as the registry's dims; ``status`` may be a string.
    time_s
        Output times [s].
    config_text
        The resolved configuration as YAML text (provenance).
    attrs
        Further dataset attributes.
    """
    data_vars = {}
    sizes = {"time": len(time_s), "joint": len(JOINTS), "axis": len(AXES)}
    for name, value in arrays.items():
        if name == "status":
            continue
        spec = CASE_VARIABLES[name]
        value = np.asarray(value)
        if value.ndim != len(spec.dims):
            raise ValueError(f"{name}: expected dims {spec.dims}, got shape {value.shape}")
        for d, n in zip(spec.dims, value.shape):
            sizes.setdefault(d, n)
        data_vars[name] = (spec.dims, value, attrs_for(name))
    coords = {
        "time": ("time", np.asarray(time_s, dtype=float), attrs_for("time")),
        "joint": ("joint", list(JOINTS), attrs_for("joint")),
        "axis": ("axis", list(AXES), attrs_for("axis")),
    }
    if "polar" in sizes:
        coords["polar"] = ("polar", bin_centres_deg(sizes["polar"], 0.0, 180.0), attrs_for("polar"))
        coords["azimuth"] = ("azimuth", bin_centres_deg(sizes["azimuth"], -180.0, 180.0),
                             attrs_for("azimuth"))
    if "angle" in sizes:
        coords["angle"] = ("angle", bin_centres_deg(sizes["angle"], -180.0, 180.0), attrs_for("angle"))
    ds = xr.Dataset(data_vars, coords=coords)
    status = arrays.get("status", "ok")
    ds["status"] = ((), str(status), {"long_name": "simulation status",
                                      "description": "ok, or the reason the case stopped"})
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    ds.attrs.update({
        "title": "clearsweep RSSP mechanism simulation",
        "Conventions": "CF-1.8",
        "source": "clearsweep",
        "history": f"{now}: created by clearsweep",
        "config": config_text,
    })
    ds.attrs.update(versions())
    if attrs:
        ds.attrs.update(attrs)
    return ds


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: Permissions of a new file: what ``open(path, "w")`` would give (0666 less the umask).
_FILE_MODE = 0o666 & ~_umask()


@contextmanager
def replaced_on_success(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    On any failure (``KeyboardInterrupt`` included) the temporary file is removed
    and ``path`` is left as it was. The file gets the permissions of an ordinary
    new file (``tempfile.mkstemp`` creates it readable by its owner only).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, _FILE_MODE)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    os.replace(tmp, path)


def write_netcdf_atomic(ds: xr.Dataset, path: str | os.PathLike, *, encoding: dict | None = None,
                        engine: str = "netcdf4") -> Path:
    """Write ``ds`` to ``path`` via a temporary file in the same folder and an atomic rename.

    A failure at any point leaves no file at ``path`` (and no temporary file).
    """
    path = Path(path)
    with replaced_on_success(path) as tmp:
        ds.to_netcdf(tmp, engine=engine, encoding=encoding)
    return path
