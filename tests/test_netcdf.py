"""What the netCDF files say about themselves: coordinates without _FillValue, counters as
integers of the width they need, cell_methods on every reduced statistic, in one-case files
and in assembled sweeps alike."""

from pathlib import Path

import netCDF4
import pytest

from clearsweep.dataset import write_netcdf_atomic
from clearsweep.simulation import simulate
from clearsweep.sweeping import run_sweep

ROOT = Path(__file__).resolve().parent.parent
SHORT = ["solver.duration=0.02", "wear.map=[4,8]"]
BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.02}, "wear": {"map": [4, 8]}}
CELL_METHODS = {"slider_acceleration_peak": "time: maximum",
                "slider_acceleration_rms": "time: root_mean_square",
                "normal_force_peak": "time: maximum", "impact_count": "time: sum",
                "energy_residual_max": "time: maximum"}
SUMMARY_CELL_METHODS = {"wear_depth_max_final": "polar: azimuth: maximum",
                        "wear_depth_axis_max": "angle: maximum"}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("nc")
    write_netcdf_atomic(simulate(ROOT / "configs" / "two_clearances.yaml", SHORT), d / "case.nc")
    run_sweep({"base": BASE, "sweep": {"grid": {"joints.B.clearance": [1e-4, 2.5e-4]}}},
              d / "sweep.nc", workers=1, progress=False).close()
    return {"case": d / "case.nc", "sweep": d / "sweep.nc"}


@pytest.mark.parametrize("kind", ["case", "sweep"])
def test_coordinates_have_no_fill_value(files, kind):
    with netCDF4.Dataset(files[kind]) as nc:
        coords = [name for name in nc.variables if name in nc.dimensions] + (
            ["B_clearance"] if kind == "sweep" else [])
        assert {"time", "joint", "polar", "angle"} <= set(coords)
        assert [c for c in coords if "_FillValue" in nc[c].ncattrs()] == []


@pytest.mark.parametrize("kind", ["case", "sweep"])
def test_counters_are_int32_where_they_fit(files, kind):
    with netCDF4.Dataset(files[kind]) as nc:
        for name in ("impact_count", "impact_count_settled", "substeps_used"):
            assert nc[name].dtype == "int32", name
        assert nc["rk4_steps"].dtype == "int64"      # passes 2**31 with --allow-large


@pytest.mark.parametrize("kind", ["case", "sweep"])
def test_reduced_statistics_carry_cell_methods(files, kind):
    expected = {**CELL_METHODS, **(SUMMARY_CELL_METHODS if kind == "sweep" else {})}
    with netCDF4.Dataset(files[kind]) as nc:
        got = {name: getattr(nc[name], "cell_methods", None) for name in expected}
        assert got == expected
        assert nc["slider_acceleration_peak_settled"].cell_methods == "time: maximum"
