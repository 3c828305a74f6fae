"""Every figure kind renders headless from synthetic datasets, with units on every axis."""

from __future__ import annotations

import errno
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
import synthetic as syn
import xarray as xr
from click.testing import CliRunner
from matplotlib.image import imread
from synthetic import case, sweep_ds, sweep_file  # noqa: F401  (pytest fixtures)

from clearsweep.analysis import SelectionError, case_summary, run_summary_text
from clearsweep.cli import main, plot_command, report_command
from clearsweep.plotting import KINDS, PlotError, plot

TEST_DPI = 40
UNITS = re.compile(r"\[[^\]]+\]")

# kind -> selection that leaves the cases the kind can draw from the sweep
SWEEP_SELECTION = {
    "slider": None,
    "forces": ["B_clearance=2.5e-4"],
    "wear-map": ["B_coating=PTFE", "B_clearance=1e-4"],
    "wear-polar": None,
    "orbit": ["B_coating=none"],
    "poincare": None,
    "sweep": None,
}


def labels(fig) -> list[str]:
    """Every non-empty axis label of the figure (colour bars and 3-D axes included)."""
    found = []
    for ax in fig.axes:
        getters = [ax.get_xlabel, ax.get_ylabel] + ([ax.get_zlabel] if hasattr(ax, "get_zlabel") else [])
        found += [text for text in (g() for g in getters) if text]
    return found


def assert_rendered(path, fig) -> None:
    image = imread(path)
    pixels = image[..., :3].reshape(-1, 3)
    assert image.std() > 0
    assert len(np.unique(pixels, axis=0)) > 1
    found = labels(fig)
    assert found, "the figure has no axis labels"
    for text in found:
        assert UNITS.search(text), f"axis label without units in brackets: {text!r}"


#: kinds drawn from one case or a sweep (``life`` needs a life dataset: tests/test_service_life.py;
#: ``reliability`` a reliability sweep: tests/test_reliability.py; ``spectrum`` two settled
#: revolutions, which the synthetic 0.2 s do not hold, and ``bifurcation`` Poincaré samples:
#: tests/test_motion_figures.py; ``effects`` a sweep that switches joints' clearance on and
#: off: tests/test_factorial.py; ``dynamics-map`` a grid over two keys with Poincaré samples:
#: tests/test_dynamics_map.py)
CASE_KINDS = [k for k in KINDS if k not in ("life", "reliability", "spectrum", "bifurcation",
                                            "effects", "dynamics-map")]


@pytest.mark.parametrize("kind", [k for k in CASE_KINDS if k != "sweep"])
def test_every_kind_renders_one_case(tmp_path, case, kind):
    path = tmp_path / f"{kind}.png"
    fig = plot(case, kind, path, dpi=TEST_DPI)
    assert_rendered(path, fig)


@pytest.mark.parametrize("kind", CASE_KINDS)
def test_every_kind_renders_from_a_sweep(tmp_path, sweep_ds, kind):
    path = tmp_path / f"{kind}.png"
    fig = plot(sweep_ds, kind, path, SWEEP_SELECTION[kind], dpi=TEST_DPI)
    assert_rendered(path, fig)


def test_slider_overlays_cases_with_coordinate_legends(tmp_path, sweep_ds):
    fig = plot(sweep_ds, "slider", tmp_path / "s.png", x="time", dpi=TEST_DPI)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend == ["B_coating=none, B_clearance=0.1 mm", "B_coating=none, B_clearance=0.25 mm",
                      "B_coating=PTFE, B_clearance=0.1 mm", "B_coating=PTFE, B_clearance=0.25 mm"]
    assert fig.axes[-1].get_xlabel() == "time [s]"
    assert fig.axes[0].get_ylabel() == "slider position along its guide [mm]"


def test_slider_angle_axis_in_degrees(tmp_path, case):
    fig = plot(case, "slider", tmp_path / "s.png", dpi=TEST_DPI)
    assert fig.axes[-1].get_xlabel() == "crank angle theta [degree]"
    line = fig.axes[-1].get_lines()[0]
    assert line.get_xdata()[-1] == pytest.approx(np.degrees(syn.OMEGA_RAD_S * syn.DURATION_S))


def test_forces_panels_say_which_body_the_joint_force_acts_on(tmp_path, case):
    """Each joint's panels name the body its force acts on: the ball's (A, B), the slider
    (the guide P); the bearing O's is the reaction on the crank."""
    fig = plot(case, "forces", tmp_path / "f.png", dpi=TEST_DPI)
    titles = {ax.get_title().split(":")[0] for ax in fig.axes if ax.get_title()}
    assert {"joint A (on the ball)", "joint B (on the ball)", "guide P (on the slider)"} <= titles


def test_sweep_heatmap_and_lines(tmp_path, sweep_ds):
    heat = plot(sweep_ds, "sweep", tmp_path / "h.png", metric="wear_depth_axis_max", dpi=TEST_DPI)
    # joint x axis panels; joint A's wear about z is 0 everywhere: no panel, the title says so
    assert len([ax for ax in heat.axes if ax.images]) == 5
    assert "not drawn: joint A, axis z, all 0 or missing" in heat.get_suptitle()
    line = plot(sweep_ds, "sweep", tmp_path / "l.png", ["B_coating=PTFE"], dpi=TEST_DPI)
    ax = line.axes[0]
    # a clearance in mm, as in every figure's legends and titles (issue 45 item 6)
    assert ax.get_xlabel() == "radial clearance of B [mm]"
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), [0.1, 0.25])
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), [syn.SWEEP_ACC_LEVEL["PTFE"]] * 2)


def test_sweep_plot_from_summary_only_dataset(tmp_path, sweep_ds):
    path = tmp_path / "summary.png"
    fig = plot(case_summary(sweep_ds), "sweep", path, metric="normal_force_peak", dpi=TEST_DPI)
    assert_rendered(path, fig)
    with pytest.raises(PlotError, match="summary-only"):
        plot(case_summary(sweep_ds), "slider", tmp_path / "x.png")


def test_orbit_circle_uses_the_swept_clearance(tmp_path, sweep_ds):
    fig = plot(sweep_ds, "orbit", tmp_path / "o.png", ["B_coating=none"], dpi=TEST_DPI)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "joint B clearance 0.1 mm (swept)" in legend
    assert "joint B clearance 0.25 mm (swept)" in legend


def test_one_case_kinds_refuse_several_cases(tmp_path, sweep_ds):
    with pytest.raises(PlotError, match="--select"):
        plot(sweep_ds, "wear-map", tmp_path / "w.png")


@pytest.mark.parametrize("suffix", [".pdf", ".svg"])
def test_vector_outputs(tmp_path, case, suffix):
    path = tmp_path / f"slider{suffix}"
    plot(case, "slider", path)
    assert path.stat().st_size > 1000


def test_bad_arguments(tmp_path, case, sweep_ds):
    with pytest.raises(SelectionError, match="output suffix"):
        plot(case, "slider", tmp_path / "x.jpg")
    with pytest.raises(SelectionError, match="wear-map"):
        plot(case, "wearmap", tmp_path / "x.png")
    with pytest.raises(SelectionError, match="B_coating"):
        plot(sweep_ds, "slider", tmp_path / "x.png", ["coating=PTFE"])


def test_cli_writes_the_file(tmp_path, sweep_file):
    out = tmp_path / "figs" / "wear.png"
    result = CliRunner().invoke(plot_command, [sweep_file, "--kind", "wear-polar", "-o", str(out),
                                               "--select", "B_clearance=0.00025", "--dpi", "40"])
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0
    assert imread(out).std() > 0


@pytest.mark.parametrize("args, names", [
    (["--kind", "slider", "--select", "B_coat=PTFE"], ["B_coating", "B_clearance"]),
    (["--kind", "slider", "--select", "B_coating=teflon"], ["none", "PTFE"]),
    (["--kind", "wear-map"], ["--select", "B_coating: none, PTFE"]),
    (["--kind", "sweep", "--metric", "acceleration"], ["slider_acceleration_peak"]),
    (["--kind", "slider", "--metric", "wall_time"], ["--kind sweep"]),
    (["--kind", "blob"], ["blob"]),
])
def test_cli_bad_selection_exit_2(tmp_path, sweep_file, args, names):
    out = tmp_path / "x.png"
    result = CliRunner().invoke(plot_command, [sweep_file, "-o", str(out), *args])
    assert result.exit_code == 2
    for name in names:
        assert name in result.output
    assert not out.exists()


def test_cli_file_that_is_not_netcdf_exit_2(tmp_path):
    path, out = tmp_path / "empty.nc", tmp_path / "x.png"
    path.write_bytes(b"")
    result = CliRunner().invoke(plot_command, [str(path), "--kind", "slider", "-o", str(out)])
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit)
    assert "is not a results file" in result.output
    assert not out.exists()


def test_cli_bad_suffix_exit_2(tmp_path, sweep_file):
    result = CliRunner().invoke(plot_command, [sweep_file, "--kind", "slider", "-o",
                                               str(tmp_path / "x.gif")])
    assert result.exit_code == 2
    assert ".png" in result.output


@pytest.mark.slow
def test_short_simulation_renders_every_kind_and_reports(tmp_path):
    """0.02 s of the real simulator through the real sweep driver: two coatings at B, stored
    in full and as summaries; every figure, the three reports and the run summary."""
    from clearsweep import sweeping as sweeps
    spec = {"base": {"solver": {"duration": 0.02},
                     "joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}}},
            "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]}}}
    paths = {}
    for store in ("full", "summary"):
        paths[store] = tmp_path / f"{store}.nc"
        sweeps.run_sweep({**spec, "store": store}, paths[store], workers=1, progress=False).close()
    with xr.open_dataset(paths["full"]) as full:
        assert list(full["status"].values) == ["ok", "ok"]
        assert "status: ok" in run_summary_text(full.sel(B_coating="none"))
        for kind in CASE_KINDS:
            if kind == "poincare":      # 0.02 s holds no crank revolution: said in one line
                with pytest.raises(PlotError, match="needs at least 2 crank revolutions"):
                    plot(full, kind, tmp_path / f"{kind}.png", dpi=TEST_DPI)
                continue
            select = ["B_coating=PTFE"] if kind == "wear-map" else None
            fig = plot(full, kind, tmp_path / f"{kind}.png", select, dpi=TEST_DPI)
            assert_rendered(tmp_path / f"{kind}.png", fig)
        orbit = plot(full, "orbit", tmp_path / "orbit.png", dpi=TEST_DPI)
        legend = [t.get_text() for t in orbit.legends[0].get_texts()]
        assert "joint B clearance 0.25 mm (config)" in legend  # the base case of sweep_config
    for path in paths.values():
        for args in ([], ["--reference", "B_coating=none"], ["--metric", "normal_force_peak"]):
            result = CliRunner().invoke(report_command, [str(path), "--format", "json", *args])
            assert result.exit_code == 0, result.output
            assert json.loads(result.output)["rows"]
    out = tmp_path / "cli.png"
    result = CliRunner().invoke(plot_command, [str(paths["summary"]), "--kind", "sweep", "-o",
                                               str(out), "--metric", "wear_depth_max_final",
                                               "--dpi", str(TEST_DPI)])
    assert result.exit_code == 0, result.output
    assert imread(out).std() > 0


@pytest.mark.parametrize("error", [errno.ENOSPC, errno.EACCES], ids=["disk_full", "read_only"])
def test_cli_unwritable_figure_is_one_error_line_and_no_partial_file(tmp_path, sweep_file,
                                                                     monkeypatch, error):
    """A full disk (or a folder we may not write: tests may run as root) half-way through."""
    from matplotlib.figure import Figure

    def fail(self, fname, *args, **kwargs):
        Path(fname).write_bytes(b"\x89PNG half a figure")
        raise OSError(error, os.strerror(error))

    monkeypatch.setattr(Figure, "savefig", fail)
    out = tmp_path / "figs" / "s.png"
    result = CliRunner().invoke(main, ["plot", sweep_file, "--kind", "sweep", "-o", str(out)])
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    reason = (f"the disk is full ({os.strerror(error)})" if error == errno.ENOSPC
              else os.strerror(error))
    assert result.stderr == f"clearsweep: error: cannot write {out}: {reason}\n"
    assert list(out.parent.iterdir()) == []


@pytest.mark.parametrize("dpi", ["100000", "5"])
def test_cli_dpi_out_of_range_exit_2(tmp_path, sweep_file, dpi):
    out = tmp_path / "s.png"
    result = CliRunner().invoke(plot_command, [sweep_file, "--kind", "sweep", "-o", str(out),
                                               "--dpi", dpi])
    assert result.exit_code == 2 and "--dpi" in result.output and "1200" in result.output
    assert not out.exists()


@pytest.mark.slow
def test_many_overlaid_cases_get_a_note_instead_of_a_legend(tmp_path, case):
    many = xr.concat([case] * 13, dim="rep").assign_coords(rep=np.arange(13))
    for kind in ("slider", "forces", "orbit", "wear-polar"):
        fig = plot(many, kind, tmp_path / f"{kind}.png", dpi=TEST_DPI)
        entries = [t.get_text() for leg in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
                   if leg is not None for t in leg.get_texts()]
        assert not any(e.startswith("rep=") for e in entries), (kind, entries)
        assert "13 cases overlaid" in fig.get_suptitle() and "--select" in fig.get_suptitle()
    few = plot(many.isel(rep=slice(0, 3)), "slider", tmp_path / "few.png", dpi=TEST_DPI)
    assert len(few.legends[0].get_texts()) == 3 and "overlaid" not in few.get_suptitle()


def test_heat_map_marks_failed_cases(tmp_path, sweep_ds):
    ds = sweep_ds.copy(deep=True)
    where = {"B_coating": "PTFE", "B_clearance": ds["B_clearance"].values[0]}
    ds["status"].loc[where] = "penetration_exceeded"
    ds["slider_acceleration"].loc[where] = np.nan
    fig = plot(ds, "sweep", tmp_path / "h.png", dpi=TEST_DPI)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert texts.count("failed") == 1 and any(p.get_hatch() for p in fig.axes[0].patches)
    assert "hatched: 1 case(s) that failed" in fig.get_suptitle()
    clean = plot(sweep_ds, "sweep", tmp_path / "c.png", dpi=TEST_DPI)
    assert "failed" not in [t.get_text() for t in clean.axes[0].texts]


def test_life_kind_on_a_case_dataset_says_what_it_needs(tmp_path, case):
    with pytest.raises(PlotError, match="--kind life needs cycle"):
        plot(case, "life", tmp_path / "x.png", dpi=TEST_DPI)


def test_categorical_axes_draw_points_and_numeric_axes_lines(sweep_ds):
    from test_ensemble import synthetic_ensemble

    from clearsweep.plotting import figure

    coatings = figure(sweep_ds, "sweep", ["B_clearance=1e-4"])        # x: B_coating
    assert coatings.axes[0].get_xlabel() == "coating of B [-]"
    assert {line.get_linestyle() for line in coatings.axes[0].get_lines()} == {"None"}
    clearances = figure(sweep_ds, "sweep", ["B_coating=PTFE"])         # x: B_clearance
    assert {line.get_linestyle() for line in clearances.axes[0].get_lines()} == {"-"}
    ensemble = figure(synthetic_ensemble(), "sweep", metric="wear_depth_max_final")
    bars = ensemble.axes[0].containers
    assert bars and all(c.lines[0].get_linestyle() == "None" for c in bars)


def test_one_outlier_does_not_set_the_heat_map_colour_scale():
    from clearsweep.plotting import figure, robust_limits

    grid = np.arange(24.0).reshape(4, 6)
    plain = figure(syn.heat_map_sweep(grid), "sweep")
    assert plain.axes[0].images[0].get_clim() == (0.0, 23.0)
    assert "percentile" not in plain.axes[1].get_ylabel()
    grid[3, 0] = 300.0                                   # one outlier among 24 cells
    fig = figure(syn.heat_map_sweep(grid), "sweep")
    assert fig.axes[0].images[0].get_clim() == (0.0, 23.0)
    outlined = [p for p in fig.axes[0].patches if p.get_edgecolor()[:3] == (1.0, 0.0, 0.0)]
    assert len(outlined) == 1 and outlined[0].get_xy() == (-0.5, 2.5)
    assert "scale stops at the 98th percentile" in fig.axes[1].get_ylabel()
    assert "1 outlying cell(s)" in fig.axes[1].get_ylabel()
    grid[0, 0] = -300.0                                  # and one below
    assert robust_limits(grid) == (1.0, 23.0)
    assert robust_limits(grid[:1, :6]) is None           # too few cells to call one an outlier
