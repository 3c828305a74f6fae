"""Sampling sweeps and Sobol' indices: the Ishigami function's known indices, the sample
kind of a sweep file, and the sensitivity command on a short mechanism sweep."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import ConfigError
from clearsweep.sensitivity import (
    SensitivityError,
    format_indices,
    indices_figure,
    sobol_indices,
    sweep_indices,
)
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
    result = CliRunner().invoke(main, ["sensitivity", str(out), "--metric", "slider_acceleration_rms",
                                       "-o", str(figure)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert "Sobol' indices of slider_acceleration_rms (16 cases" in result.output
    assert "joints.B.clearance" in result.output and "mechanism.speed_rpm" in result.output
    assert figure.stat().st_size > 0
    # a per-joint output needs its joint chosen
    joint = CliRunner().invoke(main, ["sensitivity", str(out), "--metric", "normal_force_peak"])
    assert joint.exit_code == 2 and "--select joint=" in joint.output
    ok = CliRunner().invoke(main, ["sensitivity", str(out), "--metric", "normal_force_peak",
                                   "--select", "joint=B"])
    assert ok.exit_code == 0, ok.output
    # the figure's title names the output by its long name and the slice, as plot's titles do
    with xr.open_dataset(out) as ds:
        indices = sweep_indices(ds, "normal_force_peak", ["joint=B"])
        long_name = ds["normal_force_peak"].attrs["long_name"]
    title = indices_figure(indices)._suptitle.get_text()
    assert f"{long_name} (joint=B)" in title and "normal_force_peak " not in title


def test_sensitivity_needs_a_saltelli_design():
    ds = xr.Dataset({"y": ("sample", np.arange(4.0))},
                    attrs={"sweep_config": yaml.safe_dump({"sweep": {"sample": {"method": "lhs"}}})})
    with pytest.raises(SensitivityError, match="Saltelli"):
        sweep_indices(ds, "y")


RANGES = {"x1": [0.0, 1.0], "x2": [0.0, 1.0], "x3": [0.0, 1.0]}


def linear_sample(n: int, weights=(1.0, 0.6, 0.01)) -> xr.Dataset:
    """A Saltelli sampling sweep file of y = sum w_i x_i: ST about 0.73, 0.27, 0."""
    points = sample_points("saltelli", n, RANGES, seed=1)
    spec = {"sweep": {"sample": {"method": "saltelli", "n": n, "seed": 1, "ranges": RANGES}}}
    return xr.Dataset({"y": ("sample", points @ np.asarray(weights))},
                      attrs={"sweep_config": yaml.safe_dump(spec)})


def test_too_few_base_points_to_rank_the_inputs_warn_with_a_larger_n():
    small = sweep_indices(linear_sample(8), "y")
    # x1 0.68 +- 0.37 and x2 0.29 +- 0.18: the intervals overlap, the order is unknown
    assert small.unranked_pairs() == [(0, 1)]
    warning = small.ranking_warning()
    assert warning is not None and "n = 8 base points" in warning
    assert "try sweep.sample.n: 32" in warning and "\n" not in warning
    assert format_indices(small).splitlines()[1] == "ranked by ST: x1 ? x2 (ST < 0.05: x3)"
    enough = sweep_indices(linear_sample(64), "y")
    assert enough.unranked_pairs() == [] and enough.ranking_warning() is None
    assert format_indices(enough).splitlines()[1] == "ranked by ST: x1 > x2 (ST < 0.05: x3)"


def test_negligible_inputs_need_no_order_among_themselves():
    # one input acts alone: it is told from the others even with 8 base points, and
    # the inputs whose ST intervals stay below 0.05 are not ranked against each other
    result = sweep_indices(linear_sample(8, (1.0, 0.0, 0.0)), "y")
    assert result.ranking_warning() is None
    assert format_indices(result).splitlines()[1] == "ranked by ST: x1 (ST < 0.05: x2, x3)"


@pytest.mark.parametrize("n, warns", [(8, True), (64, False)])
def test_sensitivity_command_warns_on_stderr_when_the_inputs_cannot_be_ranked(tmp_path, n, warns):
    path = tmp_path / "linear.nc"
    linear_sample(n).to_netcdf(path)
    result = CliRunner().invoke(main, ["sensitivity", str(path), "--metric", "y"])
    assert result.exit_code == 0, result.output
    assert "ranked by ST: x1" in result.stdout
    lines = result.stderr.splitlines()
    if warns:
        assert len(lines) == 1 and lines[0].startswith("clearsweep: warning: ")
        assert "n = 8 base points" in lines[0] and "sweep.sample.n: 32" in lines[0]
    else:
        assert lines == []


@pytest.mark.slow
def test_the_shipped_sensitivity_example_is_a_saltelli_design_over_four_inputs():
    config = Path(__file__).resolve().parent.parent / "configs" / "sensitivity.yaml"
    spec = yaml.safe_load(config.read_text())["sweep"]["sample"]
    plan = expand(config)
    assert spec["method"] == "saltelli" and len(spec["ranges"]) == 4
    assert plan.dims == {"sample": spec["n"] * (len(spec["ranges"]) + 2)}
