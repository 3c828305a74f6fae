"""Sampling sweeps and Sobol' indices: the Ishigami function's known indices, the sample
kind of a sweep file, and the sensitivity command on a short mechanism sweep."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import ConfigError
from clearsweep.sensitivity import SensitivityError, sobol_indices, sweep_indices
from clearsweep.sweeping import expand, run_sweep
from clearsweep.sweeping.plan import sample_points

A, B = 7.0, 0.1
#: Analytic Sobol' indices of the Ishigami function (a = 7, b = 0.1).
_V1 = 0.5 * (1 + B * math.pi ** 4 / 5) ** 2
_V2 = A ** 2 / 8
_V13 = B ** 2 * math.pi ** 8 * (1 / 18 - 1 / 50)
_V = _V1 + _V2 + _V13
ISHIGAMI_S1 = (_V1 / _V, _V2 / _V, 0.0)
ISHIGAMI_ST = ((_V1 + _V13) / _V, _V2 / _V, _V13 / _V)


def ishigami(x: np.ndarray) -> np.ndarray:
    return np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0])


def test_ishigami_indices_are_recovered_within_0_05():
    ranges = {f"x{i}": [-math.pi, math.pi] for i in (1, 2, 3)}
    points = sample_points("saltelli", 2048, ranges, seed=3)
    result = sobol_indices(list(ranges), list(ranges.values()), ishigami(points), seed=3)
    assert np.max(np.abs(result.S1 - ISHIGAMI_S1)) < 0.05
    assert np.max(np.abs(result.ST - ISHIGAMI_ST)) < 0.05
    assert np.all(result.S1_conf > 0) and np.all(result.ST_conf < 0.1)


@pytest.mark.parametrize("method", ["sobol", "lhs", "saltelli"])
def test_sample_points_are_seeded_and_in_range(method):
    ranges = {"a": [1.0, 2.0], "b": [-5.0, 5.0]}
    p = sample_points(method, 16, ranges, seed=4)
    assert np.array_equal(p, sample_points(method, 16, ranges, seed=4))
    assert not np.array_equal(p, sample_points(method, 16, ranges, seed=5))
    assert p.shape == ((16 * 4 if method == "saltelli" else 16), 2)
    assert p[:, 0].min() >= 1.0 and p[:, 0].max() <= 2.0 and p[:, 1].min() >= -5.0


BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.005},
        "wear": {"map": [12, 24]}}


def sample_doc(method="saltelli", n=4, **extra):
    return {"name": "smp", "store": "summary", "base": BASE,
            "sweep": {"sample": {"method": method, "n": n, "seed": 1,
                                 "ranges": {"joints.B.clearance": [1.0e-4, 4.0e-4],
                                            "mechanism.speed_rpm": [40.0, 80.0]}, **extra}}}


def test_sample_sweep_is_one_dimension_with_the_keys_as_coordinates():
    plan = expand(sample_doc("lhs", 8))
    assert plan.dims == {"sample": 8}
    coords = plan.to_dataset()
    assert coords["B_clearance"].dims == ("sample",)
    assert coords["B_clearance"].attrs["units"] == "m"
    assert float(coords["speed_rpm"].min()) >= 40.0


@pytest.mark.parametrize("change, key", [
    ({"method": "random"}, "sweep.sample.method"),
    ({"n": 0}, "sweep.sample.n"),
    ({"ranges": {"joints.B.clearance": [4e-4, 1e-4]}}, "sweep.sample.ranges.joints.B.clearance"),
    ({"ranges": {"joints.B.clearence": [1e-4, 2e-4]}}, "sweep.sample.ranges.joints.B.clearence"),
])
def test_bad_sample_sections_name_the_key(change, key):
    doc = sample_doc()
    doc["sweep"]["sample"].update(change)
    with pytest.raises(ConfigError) as info:
        expand(doc)
    assert info.value.key == key


def test_sensitivity_command_on_a_mechanism_sampling_sweep(tmp_path):
    out = tmp_path / "smp.nc"
    ds = run_sweep(sample_doc(), out, workers=1, progress=False)
    ds.close()
    figure = tmp_path / "sobol.png"
    result = CliRunner().invoke(main, ["sensitivity", str(out), "--output", "slider_acceleration_rms",
                                       "--plot", str(figure)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert "Sobol' indices of slider_acceleration_rms (16 cases" in result.output
    assert "joints.B.clearance" in result.output and "mechanism.speed_rpm" in result.output
    assert figure.stat().st_size > 0
    # a per-joint output needs its joint chosen
    joint = CliRunner().invoke(main, ["sensitivity", str(out), "--output", "normal_force_peak"])
    assert joint.exit_code == 2 and "--select joint=" in joint.output
    ok = CliRunner().invoke(main, ["sensitivity", str(out), "--output", "normal_force_peak",
                                   "--select", "joint=B"])
    assert ok.exit_code == 0, ok.output


def test_sensitivity_needs_a_saltelli_design():
    ds = xr.Dataset({"y": ("sample", np.arange(4.0))},
                    attrs={"sweep_config": yaml.safe_dump({"sweep": {"sample": {"method": "lhs"}}})})
    with pytest.raises(SensitivityError, match="Saltelli"):
        sweep_indices(ds, "y")
