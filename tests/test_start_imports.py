"""A plain ``clearsweep run`` imports only what it uses (issue 32, the cached start).

Was: xarray imported ``dask.array`` (with scipy's fft, sparse and special modules) at the
first ``Variable`` a run built, and ``dask`` at the first array it asked about, whenever
dask is installed: most of a short run's start beyond the imports it needs
(benchmarks/README.md, issue 32). ``clearsweep.xarray_compat`` defers both until a dask
object can exist; these tests check that a run no longer imports them, and that xarray
still treats dask arrays as dask arrays once dask is imported."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parent.parent

#: Modules a plain run of one case does not use: dask (the sweeps' Dask backend, chunked
#: reading), figures, the spectrum's scipy.signal, the sensitivity and survival libraries.
NOT_IMPORTED = ("dask", "dask.array", "distributed", "matplotlib", "scipy.signal", "SALib",
                "lifelines")

#: The ``clearsweep`` console script, with the modules loaded written at its exit.
ENTRY = """
import atexit, json, os, sys
atexit.register(lambda: open(os.environ["MODULES_JSON"], "w").write(json.dumps(sorted(sys.modules))))
from clearsweep.cli import main
sys.exit(main())
"""


def test_a_plain_run_does_not_import_what_it_does_not_use(tmp_path):
    modules = tmp_path / "modules.json"
    out = tmp_path / "one.nc"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MODULES_JSON": str(modules)}
    argv = ["run", "configs/one_clearance.yaml", "--set", "solver.duration=0.005", "-o", str(out)]
    for _ in range(2):      # the second run replaces the first's file (it reads its config)
        proc = subprocess.run([sys.executable, "-c", ENTRY, *argv], cwd=ROOT, env=env,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        imported = set(json.loads(modules.read_text()))
        assert "clearsweep.simulation" in imported and "xarray" in imported
        assert [m for m in NOT_IMPORTED if m in imported] == []
    assert "replacing the result of" in proc.stderr and "made with the same values" in proc.stderr
    assert proc.stdout.startswith("status: ok")      # the run's summary on stdout
    with xr.open_dataset(out) as ds:
        assert str(ds["status"].values) == "ok" and ds.sizes["time"] > 1


def test_xarray_still_tells_dask_arrays_once_dask_is_imported(monkeypatch):
    """The deferral answers "not dask" only while no dask object can exist: once dask.array
    is imported, a Variable keeps a dask array lazy and chunked, as xarray does without it."""
    da = pytest.importorskip("dask.array")
    from xarray.namedarray import pycompat
    from xarray.namedarray import utils as namedarray_utils
    from xarray.namedarray.utils import is_duck_dask_array

    from clearsweep.xarray_compat import _DeferredDask, defer_dask_array

    # a fresh deferral, as a run's first dataset meets it (this process may have asked before)
    monkeypatch.setitem(pycompat._cached_duck_array_modules, "dask",
                        _DeferredDask(pycompat.DuckArrayModule))
    monkeypatch.setattr(namedarray_utils, "is_dask_collection", namedarray_utils.is_dask_collection)
    assert defer_dask_array()
    assert pycompat.array_type("dask") == (da.Array,)
    assert pycompat.mod_version("dask") == pycompat.DuckArrayModule("dask").version
    lazy = da.arange(6.0, chunks=3)
    variable = xr.Variable(("x",), lazy)
    assert isinstance(variable.data, da.Array) and variable.chunks == ((3, 3),)
    assert is_duck_dask_array(lazy) and not is_duck_dask_array(np.arange(3.0))
    ds = xr.Dataset({"a": ("x", lazy)})
    assert isinstance(ds["a"].data, da.Array) and float(ds["a"].sum()) == 15.0
    # a masked numpy array is still filled with NaN, as xarray does
    masked = np.ma.masked_array([1.0, 2.0], mask=[False, True])
    np.testing.assert_array_equal(xr.Variable(("x",), masked).values, [1.0, np.nan])


def test_chunked_reading_of_a_results_file_is_unchanged(tmp_path):
    """open_dataset(chunks=...) after the deferral: dask arrays, the same values."""
    pytest.importorskip("dask.array")
    import clearsweep.dataset  # noqa: F401  (puts the deferral in place)

    path = tmp_path / "f.nc"
    xr.Dataset({"a": (("x", "y"), np.arange(12.0).reshape(3, 4))}).to_netcdf(path)
    with xr.open_dataset(path, chunks={"x": 1}) as ds:
        assert ds["a"].chunks == ((1, 1, 1), (4,))
        np.testing.assert_array_equal(ds["a"].values, np.arange(12.0).reshape(3, 4))
