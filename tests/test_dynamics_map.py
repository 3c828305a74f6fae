"""``plot --kind dynamics-map`` (issue 45, item 8): the period of every case of a two-key grid
sweep as a categorical map, the 0-1 test's K beside it, and its refusals.

The sweep here is configs/dynamics_map.yaml cut to a 2 x 2 grid at 600 and 640 r/min with 6
crank revolutions a case (1 of start-up), so that it runs in seconds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep.analysis import PERIOD_NONE, PERIOD_UNKNOWN, report_summary
from clearsweep.cli import main
from clearsweep.plotting import PlotError, figure
from clearsweep.plotting.dynamics import category_text

ROOT = Path(__file__).resolve().parents[1]

#: The shipped map cut short: 2 speeds x 2 clearances, 6 revolutions at high speed.
SPEEDS = [600, 640]
CLEARANCES = [2.0e-4, 2.5e-4]


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _sweep(tmp: Path, name: str, grid: dict) -> Path:
    doc = yaml.safe_load((ROOT / "configs" / "dynamics_map.yaml").read_text())
    doc["base"]["solver"]["revolutions"] = 6
    doc["base"]["metrics"]["settle_revolutions"] = 1
    doc["sweep"]["grid"] = grid
    config = tmp / f"{name}.yaml"
    config.write_text(yaml.safe_dump(doc))
    out = tmp / f"{name}.nc"
    result = invoke("sweep", config, "--workers", "1", "--no-progress", "-q", "-o", out)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def small_map(tmp_path_factory) -> Path:
    return _sweep(tmp_path_factory.mktemp("map"), "map",
                  {"mechanism.speed_rpm": SPEEDS, "joints.B.clearance": CLEARANCES})


@pytest.fixture(scope="module")
def one_key(tmp_path_factory) -> Path:
    return _sweep(tmp_path_factory.mktemp("line"), "line", {"mechanism.speed_rpm": SPEEDS})


def test_the_shipped_map_sweeps_speed_and_the_clearance_of_b():
    doc = yaml.safe_load((ROOT / "configs" / "dynamics_map.yaml").read_text())
    grid = doc["sweep"]["grid"]
    assert set(grid) == {"mechanism.speed_rpm", "joints.B.clearance"}
    assert min(grid["mechanism.speed_rpm"]) <= 80 and max(grid["mechanism.speed_rpm"]) >= 110
    assert 2.5e-4 in grid["joints.B.clearance"] and len(grid["joints.B.clearance"]) >= 3
    assert doc["store"] == "summary"
    assert "revolutions" in doc["base"]["solver"]
    assert "settle_revolutions" in doc["base"]["metrics"]


def _mesh(fig, gid: str):
    return next(c for ax in fig.axes for c in ax.collections if c.get_gid() == gid)


@pytest.mark.parametrize("keys", [("speed_rpm", "B_clearance"),
                                  ("mechanism.speed_rpm", "joints.B.clearance")])
def test_the_map_draws_each_cells_period_and_k_as_the_file_holds_them(small_map, keys):
    with xr.open_dataset(small_map) as ds:
        summary = report_summary(ds)
        period = summary["period"].transpose("B_clearance", "speed_rpm").values
        k = summary["chaos_k"].transpose("B_clearance", "speed_rpm").values
        fig = figure(ds, "dynamics-map", x=keys[0], y=keys[1])
    # six settled revolutions: a period is found or none is, never undetermined
    assert (period != PERIOD_UNKNOWN).all()
    drawn = np.asarray(_mesh(fig, "period").get_array()).reshape(period.shape)
    np.testing.assert_array_equal(drawn, period)
    drawn_k = np.ma.getdata(_mesh(fig, "chaos_k").get_array()).reshape(k.shape)
    np.testing.assert_array_equal(np.isnan(k), np.ma.getmaskarray(
        _mesh(fig, "chaos_k").get_array()).reshape(k.shape))
    np.testing.assert_allclose(drawn_k[np.isfinite(k)], k[np.isfinite(k)])
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert sorted(legend) == sorted({category_text(int(p)) for p in period.ravel()})
    # each legend patch has the colour of its cells
    colours = _mesh(fig, "period").to_rgba(period.ravel())
    for patch, text in zip(ax.get_legend().get_patches(), legend):
        cells = [c for c, p in zip(colours, period.ravel()) if category_text(int(p)) == text]
        np.testing.assert_allclose(patch.get_facecolor(), cells[0])
    assert ax.get_xlabel().endswith("[r/min]") and ax.get_ylabel().endswith("[mm]")
    assert [t.get_text() for t in ax.get_xticklabels()] == ["600", "640"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["0.2", "0.25"]
    # the colour bars of the 0-1 test and of the Lyapunov exponent
    assert [a.get_ylabel().split(" [")[0] for a in fig.axes if a.get_label() == "<colorbar>"] == [
        "0-1 test K", "largest Lyapunov exponent"]


def test_the_map_draws_each_cells_lyapunov_exponent_and_marks_its_motion_class(small_map):
    """The shipped map asks for the exponent (metrics.lyapunov_revolutions): every case holds
    one, the third panel draws it, and each cell without a period carries its class's mark."""
    from clearsweep.plotting.dynamics import CLASS_MARKS

    with xr.open_dataset(small_map) as ds:
        summary = report_summary(ds)
        fig = figure(ds, "dynamics-map", x="speed_rpm", y="B_clearance")
    exponent = summary["lyapunov_exponent"].transpose("B_clearance", "speed_rpm").values
    assert np.isfinite(exponent).all()
    drawn = np.ma.getdata(_mesh(fig, "lyapunov_exponent").get_array()).reshape(exponent.shape)
    np.testing.assert_allclose(drawn, exponent)
    period = summary["period"].transpose("B_clearance", "speed_rpm").values
    classes = summary["motion_class"].transpose("B_clearance", "speed_rpm").values
    marks = sorted((t.get_position(), t.get_text(), t.get_gid()) for t in fig.axes[0].texts)
    expected = sorted(((float(col), float(row)), CLASS_MARKS[str(name)], f"motion_class:{name}")
                      for (row, col), name in np.ndenumerate(classes) if period[row, col] <= 0)
    assert marks == expected
    assert all(str(c) == "periodic" for c, p in zip(classes.ravel(), period.ravel()) if p > 0)


def test_the_maps_texts_stay_inside_the_figure_and_apart(small_map):
    from test_figure_layout import layout_problems

    with xr.open_dataset(small_map) as ds:
        fig = figure(ds, "dynamics-map", x="speed_rpm", y="B_clearance")
    assert layout_problems(fig) == []


def test_the_cli_draws_the_map(small_map, tmp_path):
    out = tmp_path / "map.png"
    result = invoke("plot", small_map, "--kind", "dynamics-map", "--x", "speed_rpm",
                    "--y", "joints.B.clearance", "--dpi", "30", "-o", out, "-q")
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0


def _refused(path, tmp_path, *options) -> str:
    out = tmp_path / "refused.png"
    result = invoke("plot", path, "--kind", "dynamics-map", *options, "-o", out)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.output
    assert not out.exists()
    return lines[0]


def test_a_one_parameter_sweep_is_refused(one_key, tmp_path):
    line = _refused(one_key, tmp_path, "--x", "speed_rpm", "--y", "speed_rpm")
    assert "two parameters" in line and "--kind bifurcation" in line


def test_a_map_without_both_keys_or_with_an_unknown_one_is_refused(small_map, tmp_path):
    assert "needs --x and --y" in _refused(small_map, tmp_path, "--x", "speed_rpm")
    line = _refused(small_map, tmp_path, "--x", "speed_rpm", "--y", "B_coating")
    assert "--y B_coating" in line and "B_clearance" in line
    line = _refused(small_map, tmp_path, "--x", "speed_rpm", "--y", "B_clearance",
                    "--select", "speed_rpm=600")
    assert "fixes the dimension of --x" in line


def test_a_third_swept_key_must_be_fixed_with_select(small_map):
    with xr.open_dataset(small_map) as ds:
        three = xr.concat([ds, ds], dim=xr.DataArray(["none", "PTFE"], dims="B_coating",
                                                     name="B_coating"))
    with pytest.raises(PlotError, match="also sweeps B_coating: choose one value"):
        figure(three, "dynamics-map", x="speed_rpm", y="B_clearance")
    fig = figure(three, "dynamics-map", ["B_coating=PTFE"], x="speed_rpm", y="B_clearance")
    assert _mesh(fig, "period").get_array().size == 4


def test_a_single_run_is_refused(tmp_path):
    out = tmp_path / "run.nc"
    result = invoke("run", ROOT / "configs" / "one_clearance.yaml", "--set",
                    "solver.duration=0.01", "-q", "-o", out)
    assert result.exit_code == 0, result.output
    assert "two parameters" in _refused(out, tmp_path, "--x", "a", "--y", "b")


def test_y_is_refused_for_other_kinds(small_map):
    with xr.open_dataset(small_map) as ds, pytest.raises(PlotError, match="--y applies"):
        figure(ds, "sweep", y="B_clearance")


def test_category_texts():
    assert category_text(3) == "period 3"
    assert category_text(PERIOD_NONE).startswith("none")
    assert category_text(PERIOD_UNKNOWN) == "undetermined"


def test_report_names_the_periodic_windows_of_a_map():
    """One line per period found: its cells' ranges along the speed at each clearance; a
    case that did not finish ok is left out, non-periodic and undetermined cases are not
    windows. The values in the figures' units (issue 45 item 6): a clearance in mm, a speed
    in r/min (before: 0.0002 m and min-1)."""
    from clearsweep.analysis.text import _periodic_window_lines

    speed = xr.DataArray([80.0, 85.0, 90.0, 95.0], dims="speed_rpm",
                         attrs={"units": "min-1", "config_key": "mechanism.speed_rpm"})
    clearance = xr.DataArray([2.0e-4, 2.5e-4], dims="B_clearance",
                             attrs={"units": "m", "config_key": "joints.B.clearance"})
    period = xr.DataArray([[1, 1, 0, 2], [1, 3, 1, PERIOD_UNKNOWN]],
                          dims=("B_clearance", "speed_rpm"),
                          coords={"B_clearance": clearance, "speed_rpm": speed})
    ds = xr.Dataset({"period": period})
    usable = xr.DataArray([[True, True, True, True], [True, False, True, True]],
                          dims=("B_clearance", "speed_rpm"))
    lines = _periodic_window_lines(ds, ds, usable, ("B_clearance", "speed_rpm"))
    assert lines[1].startswith("Periodic windows over speed_rpm x B_clearance")
    assert [line for line in lines if line.startswith(("-", "    "))] == [
        "- period 1: B_clearance 0.2 mm: speed_rpm 80-85 r/min; B_clearance 0.25 mm: "
        "speed_rpm 80 r/min,",
        "    speed_rpm 90 r/min",
        "- period 2: B_clearance 0.2 mm: speed_rpm 95 r/min"]
    none = _periodic_window_lines(ds, ds.assign(period=period * 0), usable,
                                  ("B_clearance", "speed_rpm"))
    assert none[-1] == "- none: no case has a period up to 8"
    assert _periodic_window_lines(ds.isel(B_clearance=[0]), ds.isel(B_clearance=[0]),
                                  usable.isel(B_clearance=[0]), ("B_clearance", "speed_rpm")) == []


def test_report_of_the_small_map_says_it_found_no_window(small_map):
    result = invoke("report", small_map)
    assert result.exit_code == 0, result.output
    with xr.open_dataset(small_map) as ds:
        periods = report_summary(ds)["period"].values
    if (periods > 0).any():
        assert "- period " in result.stdout
    else:
        assert "- none: no case has a period up to 8" in result.stdout
    assert "Periodic windows over speed_rpm x B_clearance" in result.stdout


def test_a_sweep_whose_runs_end_before_a_section_is_refused_saying_so(tmp_path):
    doc = yaml.safe_load((ROOT / "configs" / "dynamics_map.yaml").read_text())
    doc["base"]["solver"] = {"dt": 1.0e-5, "duration": 0.01}
    doc["base"]["metrics"] = {"settle_time": 0.005}
    doc["sweep"]["grid"] = {"mechanism.speed_rpm": SPEEDS, "joints.B.clearance": CLEARANCES}
    config = tmp_path / "short.yaml"
    config.write_text(yaml.safe_dump(doc))
    out = tmp_path / "short.nc"
    result = invoke("sweep", config, "--workers", "1", "--no-progress", "-q", "-o", out)
    assert result.exit_code == 0, result.output
    line = _refused(out, tmp_path, "--x", "speed_rpm", "--y", "B_clearance")
    assert "ended before their first section" in line


def test_a_period_per_member_is_refused_not_drawn(small_map):
    with xr.open_dataset(small_map) as ds:
        members = xr.concat([ds, ds], dim="member")
    with pytest.raises(PlotError, match="one per member too: choose one with --select"):
        figure(members, "dynamics-map", x="speed_rpm", y="B_clearance")


def test_report_names_the_class_of_each_cell_without_a_period():
    """Beside the periodic windows, one line per motion class of the cells without a period
    (the two chaos indicators together, summary.motion_class)."""
    from clearsweep.analysis.text import _periodic_window_lines

    speed = xr.DataArray([92.0, 93.0, 94.0, 96.0], dims="speed_rpm",
                         attrs={"units": "min-1", "config_key": "mechanism.speed_rpm"})
    clearance = xr.DataArray([2.5e-4], dims="B_clearance",
                             attrs={"units": "m", "config_key": "joints.B.clearance"})
    cells = {"B_clearance": clearance, "speed_rpm": speed}
    dims = ("B_clearance", "speed_rpm")
    ds = xr.Dataset({"period": xr.DataArray([[1, 0, 0, 0]], dims=dims, coords=cells),
                     "motion_class": xr.DataArray([["periodic", "transient", "quasi-periodic",
                                                    "chaotic"]], dims=dims, coords=cells)})
    usable = xr.DataArray([[True, True, True, True]], dims=dims)
    # a second clearance row so that the grid has two varying keys
    two = xr.concat([ds, ds.assign_coords(B_clearance=[3.0e-4])], dim="B_clearance")
    lines = _periodic_window_lines(two, two, xr.concat([usable, usable], dim="B_clearance"), dims)
    listed: list[str] = []
    for line in lines:          # the wrapped lines joined again
        if line.startswith("- "):
            listed.append(line)
        elif line.startswith("    "):
            listed[-1] += " " + line.strip()
    assert listed == [
        "- period 1: B_clearance 0.25 mm: speed_rpm 92 r/min; B_clearance 0.3 mm: speed_rpm 92 r/min",
        "- chaotic: B_clearance 0.25 mm: speed_rpm 96 r/min; B_clearance 0.3 mm: speed_rpm 96 r/min",
        "- quasi-periodic: B_clearance 0.25 mm: speed_rpm 94 r/min; B_clearance 0.3 mm: speed_rpm "
        "94 r/min",
        "- transient: B_clearance 0.25 mm: speed_rpm 93 r/min; B_clearance 0.3 mm: speed_rpm 93 r/min"]


def test_report_of_the_small_map_gives_each_cases_exponent_and_class(small_map):
    import json

    result = invoke("report", small_map, "--full", "--format", "json")
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert {"lyapunov_exponent", "motion_class"} <= set(report["columns"])
    with xr.open_dataset(small_map) as ds:
        summary = report_summary(ds)
    for row in report["rows"]:
        case = summary.sel(speed_rpm=row["speed_rpm"], B_clearance=row["B_clearance"])
        assert row["lyapunov_exponent"] == pytest.approx(float(case["lyapunov_exponent"]))
        assert row["motion_class"] == str(case["motion_class"].values)


def test_a_runs_report_gives_its_exponent_and_class():
    from clearsweep.analysis.text import _run_motion_lines

    case = xr.Dataset({"period": 0, "chaos_k": 0.81, "lyapunov_exponent": 0.026,
                       "motion_class": "quasi-periodic"})
    assert _run_motion_lines(case) == [
        "motion (period in crank revolutions): non-periodic (no period up to 8 revolutions); "
        "0-1 test K = 0.81; largest Lyapunov exponent +0.026 per revolution; class: quasi-periodic"]
    assert "n/a" in _run_motion_lines(case.assign(lyapunov_exponent=np.nan))[0]
