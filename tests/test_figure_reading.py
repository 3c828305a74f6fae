"""Figures that a user reads right the first time: a negligible change looks negligible,
the life figure says which wear-map snapshots it draws, titles name the ``--select`` slice,
legends tell clearance circles apart and carry units (issue: figures and reports)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.figure import Figure
from synthetic import case, heat_map_sweep, sweep_ds  # noqa: F401  (pytest fixtures)
from test_ensemble import synthetic_ensemble
from test_figure_layout import layout_problems, legends_over_data, life_ds  # noqa: F401  (pytest fixture)

from clearsweep.ensemble import ensemble_statistics
from clearsweep.plotting import (
    MIN_RELATIVE_SPAN,
    NEGLIGIBLE_VARIATION,
    figure,
    keep_relative_span,
)


def _span(ax) -> float:
    low, high = ax.get_ylim()
    return high - low


@settings(max_examples=60, deadline=None)
@given(mean=st.floats(1e-9, 1e6), sign=st.sampled_from([1.0, -1.0]),
       variation=st.floats(0.0, 0.99 * NEGLIGIBLE_VARIATION),
       shape=st.lists(st.floats(-0.5, 0.5), min_size=2, max_size=12))
def test_data_that_vary_negligibly_get_an_axis_wide_relative_to_their_mean(mean, sign, variation,
                                                                          shape):
    values = sign * mean * (1.0 + variation * np.asarray(shape))
    ax = Figure().add_subplot()
    ax.plot(values)
    keep_relative_span(ax, values)
    assert _span(ax) >= (1.0 - 1e-9) * MIN_RELATIVE_SPAN * abs(values.mean())
    low, high = ax.get_ylim()
    assert low <= values.min() and values.max() <= high


def test_data_that_vary_a_lot_keep_their_axis():
    values = np.array([1.0, 1.5, 2.0])
    ax = Figure().add_subplot()
    ax.plot(values)
    before = ax.get_ylim()
    assert keep_relative_span(ax, values) == ""
    assert ax.get_ylim() == before


def _life_panel(fig, ylabel_start: str):
    return next(ax for ax in fig.axes if ax.get_ylabel().startswith(ylabel_start))


def test_the_life_figure_draws_a_015_percent_rms_change_small_and_says_so(life_ds):
    ds = life_ds.copy()
    n = ds.sizes["cycle"]
    ds["slider_acceleration_rms_settled"] = (
        "cycle", np.linspace(1.4327, 1.4349, n), ds["slider_acceleration_rms_settled"].attrs)
    fig = figure(ds, "life")
    ax = _life_panel(fig, "settled RMS slider acceleration")
    assert _span(ax) >= 0.99 * MIN_RELATIVE_SPAN * 1.4338     # 0.0022 m/s^2 was the whole axis
    assert "varies by 0.15 % of its mean" in ax.get_title()
    assert layout_problems(fig) == []


def test_the_life_figure_says_which_snapshots_it_leaves_out(life_ds):
    ds = life_ds
    n = ds.sizes["snapshot"]
    # seven stored snapshots, one more than the panels
    extra = 7 - n
    picks = np.r_[np.arange(n), np.full(max(extra, 0), n - 1)][:7]
    seven = ds.isel(snapshot=picks)
    seven = seven.assign(snapshot_cycle=("snapshot", np.arange(1.0, 8.0) * 10.0))
    title = figure(seven, "life").get_suptitle()
    assert "6 of the 7 stored snapshots" in title
    drawn = {float(c) for c in np.round(np.linspace(0, 6, 6)).astype(int) * 10.0 + 10.0}
    (left,) = set(np.arange(1.0, 8.0) * 10.0) - drawn
    assert f"not drawn: {left:.3g} revolutions" in title
    assert "all" in figure(ds.isel(snapshot=[0, n - 1]), "life").get_suptitle()


@pytest.mark.parametrize("kind", ["slider", "forces", "wear-polar", "orbit", "sweep"])
def test_two_slices_never_get_the_same_title(sweep_ds, kind):
    a = figure(sweep_ds, kind, ["B_coating=none"]).get_suptitle()
    b = figure(sweep_ds, kind, ["B_coating=PTFE"]).get_suptitle()
    assert a != b
    assert "selection: B_coating=PTFE" in b


def test_a_sweep_title_uses_long_names(sweep_ds):
    title = figure(sweep_ds, "sweep", ["B_coating=none"]).get_suptitle()
    long_name = sweep_ds["slider_acceleration_peak_settled"].attrs["long_name"]
    assert title.startswith(long_name)
    assert "slider_acceleration_peak_settled" not in title


def test_orbit_clearance_circles_are_told_apart_in_one_legend(sweep_ds):
    # joint A: 0.25 mm from the config; joint B: 0.1 and 0.25 mm swept
    fig = figure(sweep_ds, "orbit", ["B_coating=none"])
    (legend,) = fig.legends
    circles = {t.get_text(): (str(h.get_linestyle()), str(h.get_color()))
               for h, t in zip(legend.legend_handles, legend.get_texts())
               if "clearance " in t.get_text()}
    assert set(circles) == {"joint A clearance 0.25 mm (config)",
                            "joint B clearance 0.1 mm (swept)",
                            "joint B clearance 0.25 mm (swept)"}
    # one style per radius: the two 0.25 mm circles alike, the 0.1 mm one different
    assert circles["joint A clearance 0.25 mm (config)"] == circles[
        "joint B clearance 0.25 mm (swept)"]
    assert circles["joint B clearance 0.1 mm (swept)"] != circles[
        "joint B clearance 0.25 mm (swept)"]
    assert layout_problems(fig) == []


def test_orbit_leaves_out_skipped_cases(sweep_ds):
    ds = sweep_ds.copy()
    ds["status"] = ds["status"].where(ds["B_clearance"] != ds["B_clearance"][1], "skipped")
    fig = figure(ds, "orbit", ["B_coating=none"])
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    skipped = f"B_clearance={1e3 * float(ds['B_clearance'][1]):g} mm"
    assert any(f"B_clearance={1e3 * float(ds['B_clearance'][0]):g} mm" in t for t in texts)
    assert not any(t.startswith(skipped) or f", {skipped}" in t for t in texts)


def test_the_ensemble_legend_carries_units():
    ds = synthetic_ensemble()
    two = xr.concat([ds[["status", "wear_depth_max_final"]]] * 2, dim="B_clearance")
    two = two.assign_coords(B_clearance=("B_clearance", [1e-4, 2.5e-4],
                                         {"units": "m", "long_name": "radial clearance of B"}))
    two = two.sel(joint="B").transpose("B_coating", "B_clearance", "member")
    ensemble = xr.merge([two, ensemble_statistics(two)], combine_attrs="override")
    fig = figure(ensemble, "sweep", metric="wear_depth_max_final")
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert texts == ["B_clearance 0.1 mm", "B_clearance 0.25 mm"]
    assert layout_problems(fig) == []


def test_a_heat_map_with_the_long_names_of_a_sweep_file_keeps_its_title_inside():
    """The paper's sweep: two zip groups, a metric with a long name (its title was clipped
    on both sides)."""
    ds = heat_map_sweep(np.arange(24.0).reshape(4, 6)).rename(
        B_coating="coating_joints", B_clearance="clearance_joints")
    ds["slider_acceleration_peak_settled"].attrs["long_name"] = (
        "peak absolute slider acceleration after start-up")
    for dim in ("coating_joints", "clearance_joints"):
        ds[dim].attrs["long_name"] = f"sweep zip group {dim}"
    fig = figure(ds, "sweep")
    assert layout_problems(fig) == []
    assert "(coating_joints)" not in fig.get_suptitle()


def test_a_single_run_figure_names_its_case(case):
    assert "case: " in figure(case, "slider").get_suptitle()


def test_the_poincare_figure_draws_each_section_once_on_its_most_spread_axes():
    """A period-2 motion known by construction: joint B's sections alternate between two
    points that differ along y and z only, the slider acceleration between two values. The
    panel draws those points on the y-z plane (x does not spread), the revolutions against
    their acceleration; joint A, ideal, gets no panel and the title says so."""
    from clearsweep.core import layout as L
    from clearsweep.dataset import build_dataset

    n = 6
    offset = np.full((n, L.N_JOINTS, 3), np.nan)      # B with clearance; A and O ideal
    offset[:, 1, 0] = 0.1
    offset[:, 1, 1] = np.where(np.arange(n) % 2 == 0, 0.6, -0.5)
    offset[:, 1, 2] = np.where(np.arange(n) % 2 == 0, -0.7, -0.8)
    acc = np.where(np.arange(n) % 2 == 0, 3.0, -4.0)
    ds = build_dataset({"poincare_offset": offset, "poincare_velocity": offset,
                        "poincare_slider_acc": acc, "poincare_time": np.arange(1.0, n + 1)},
                       np.zeros(1))
    fig = figure(ds, "poincare")
    joint_ax, acc_ax = fig.axes
    assert joint_ax.get_xlabel().startswith("d_y / c") and joint_ax.get_ylabel().startswith("d_z / c")
    points = joint_ax.lines[0]
    np.testing.assert_array_equal(points.get_xdata(), offset[:, 1, 1])
    np.testing.assert_array_equal(points.get_ydata(), offset[:, 1, 2])
    np.testing.assert_array_equal(acc_ax.lines[0].get_xdata(), np.arange(1, n + 1))
    np.testing.assert_array_equal(acc_ax.lines[0].get_ydata(), acc)
    assert "m s-2" in acc_ax.get_ylabel()
    assert "not drawn: joint A" in fig.get_suptitle()


def test_a_poincare_figure_of_a_run_shorter_than_two_revolutions_says_what_it_needs(tmp_path):
    from click.testing import CliRunner

    from clearsweep.cli import main
    from clearsweep.dataset import write_netcdf_atomic
    from clearsweep.simulation import simulate

    path = tmp_path / "short.nc"
    write_netcdf_atomic(simulate("configs/one_clearance.yaml", ["solver.duration=0.01"]), path)
    result = CliRunner().invoke(main, ["plot", str(path), "--kind", "poincare", "-o",
                                       str(tmp_path / "p.png")])
    assert result.exit_code != 0
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: ")
    assert "at least 2 crank revolutions" in lines[0] and "hold 0" in lines[0]
    assert "solver.duration" in lines[0]
    assert not (tmp_path / "p.png").exists()


# ------------------------------------------------------- ideal joints are named nowhere

#: one_clearance.yaml has its clearance at B alone: joints A and O are ideal.
ONE_CLEARANCE = "configs/one_clearance.yaml"


def _figure_texts(fig) -> list[str]:
    """Every text of ``fig``: titles, labels, legend entries, annotations."""
    from matplotlib.text import Text

    return [t.get_text() for t in fig.findobj(Text) if t.get_text().strip()]


def _named_joints(fig) -> set[str]:
    """The joints that a text of ``fig`` names ("joint A", "joint A, O")."""
    import re

    named: set[str] = set()
    for text in _figure_texts(fig):
        for match in re.finditer(r"\bjoints? ((?:[ABOP](?:, |,\s*| and )?)+)", " ".join(text.split())):
            named |= set(re.findall(r"[ABOP]", match.group(1)))
    return named


@pytest.fixture(scope="module")
def b_alone():
    """A run of configs/one_clearance.yaml (B with clearance, A and O ideal), 0.005 s."""
    from clearsweep.simulation import simulate

    return simulate(ONE_CLEARANCE, ["solver.duration=0.005"])


@pytest.mark.parametrize("kind", ["wear-map", "wear-polar", "orbit"])
def test_a_single_run_figure_names_no_ideal_joint(b_alone, kind):
    """The titles said "not drawn: joint A, O, no wear", "joint A: no wear; joint O: no
    wear" and "not drawn: joint A, O, ball at the centre (ideal joint)": a joint that is
    ideal in the run is named nowhere in its figure, as in the sweep figures."""
    fig = figure(b_alone, kind)
    assert _named_joints(fig) == {"B"}, _figure_texts(fig)


def test_a_poincare_figure_names_no_ideal_joint():
    """Two revolutions at 3000 r/min: the title said "not drawn: joint A, O (ideal joint)"."""
    from clearsweep.simulation import simulate

    ds = simulate(ONE_CLEARANCE, ["mechanism.speed_rpm=3000", "solver.duration=0.041"])
    fig = figure(ds, "poincare")
    assert len(fig.axes) == 2                   # joint B and the slider acceleration
    assert _named_joints(fig) == {"B"}, _figure_texts(fig)


def test_a_life_snapshot_figure_names_no_ideal_joint(short_life_cli):
    """A life run's wear-map snapshot lost the run's config, and with it which joints are
    ideal: its title said "not drawn: joint A, O, no wear". It now reads as the final map's
    (the case and the start as well)."""
    ds = xr.load_dataset(short_life_cli[0])
    snapshot = figure(ds, "wear-map", ["snapshot=1"])
    assert _named_joints(snapshot) == {"B"}, _figure_texts(snapshot)
    final = figure(ds, "wear-map")
    assert _named_joints(final) == {"B"}
    assert snapshot.get_suptitle().split("\n")[-1] == final.get_suptitle().split("\n")[-1]


def test_a_clearance_joint_without_wear_is_still_named():
    """With wear off, B (with clearance) has no wear: the figure says so; A and O, ideal,
    are not named."""
    from clearsweep.simulation import simulate

    ds = simulate(ONE_CLEARANCE, ["solver.duration=0.005", "wear.enabled=false"])
    fig = figure(ds, "wear-polar")
    assert "joint B: no wear" in " ".join(fig.get_suptitle().split())
    assert _named_joints(fig) == {"B"}
    fig = figure(ds, "wear-map")
    assert "not drawn: joint B, no wear" in fig.get_suptitle() and not fig.axes


@pytest.mark.parametrize("kind", ["wear-map", "wear-polar", "orbit"])
def test_a_figure_of_the_ideal_mechanism_is_refused_in_one_line(kind, tmp_path):
    """Every joint ideal: wear-polar and orbit drew a row of panels per ideal joint, named,
    and wear-map a title over no panel; now one line says there is nothing to draw."""
    from click.testing import CliRunner

    from clearsweep.cli import main
    from clearsweep.dataset import write_netcdf_atomic
    from clearsweep.simulation import simulate

    path = tmp_path / "ideal.nc"
    write_netcdf_atomic(simulate("configs/ideal.yaml", ["solver.duration=0.005"]), path)
    result = CliRunner().invoke(main, ["plot", str(path), "--kind", kind, "-o",
                                       str(tmp_path / "f.png")])
    assert result.exit_code != 0
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.output
    assert f"--kind {kind} draws the joints with a clearance" in lines[0]
    assert not (tmp_path / "f.png").exists()


@pytest.mark.parametrize("shipped", ["revolute_clearance", "contact_laws"])
def test_a_sweep_files_figures_name_the_start_its_base_config_gives(tmp_path, monkeypatch, shipped):
    """Every figure of these sweeps said "start: seated" though their base starts centred: a
    sweep file has no run ``config`` attribute, and the empty one was read as an empty config
    before the sweep's own ``sweep_config`` (issue 45)."""
    from pathlib import Path

    import yaml

    from clearsweep.sweeping import run_sweep

    spec = yaml.safe_load((Path(__file__).parents[1] / "configs" / f"{shipped}.yaml").read_text())
    start = spec["base"]["initial"]["joints"]
    key = next(iter(spec["sweep"]["grid"]))
    spec["sweep"] = {"grid": {key: spec["sweep"]["grid"][key][:1]}}
    monkeypatch.chdir(tmp_path)
    ds = run_sweep(spec, workers=1, overrides=["solver.duration=0.002"], progress=False)
    assert "config" not in ds.attrs
    title = figure(ds, "slider").get_suptitle()
    assert f"start: {start}" in title and start != "seated"


def said(title: str, part: str) -> bool:
    """Whether a part of ``title`` (parts end at ";" or the title's end; the title's lines
    rejoined where it was wrapped) ends in ``part``."""
    return any(p.strip().endswith(part) for p in " ".join(title.split()).split(";"))


@pytest.fixture(scope="module")
def start_and_clearance_sweep(tmp_path_factory):
    """A sweep of the start (seated, centred) by A's clearance (none, 0.25 mm), B at 0.25 mm
    in its base: four cases of 2 ms."""
    from clearsweep.sweeping import run_sweep

    spec = {"base": {"name": "starts", "mechanism": {"speed_rpm": 600.0},
                     "joints": {"A": {"clearance": 0.0}, "B": {"clearance": 2.5e-4}},
                     "solver": {"duration": 0.002, "dt": 1e-5},
                     "metrics": {"settle_time": 0.001}, "wear": {"map": [6, 12]}},
            "sweep": {"grid": {"initial.joints": ["seated", "centred"],
                               "joints.A.clearance": [0.0, 2.5e-4]}}}
    return run_sweep(spec, workers=1, progress=False)


@pytest.mark.parametrize("kind", ["slider", "forces", "wear-map", "wear-polar", "orbit"])
@pytest.mark.parametrize(("start", "a_clearance", "joints"),
                         [("centred", "0", "B"), ("seated", "2.5e-4", "A, B"),
                          ("centred", "2.5e-4", "A, B")])
def test_a_selected_case_s_title_names_its_own_start_and_joints_with_clearance(
        start_and_clearance_sweep, kind, start, a_clearance, joints):
    """One case chosen with --select was titled with the base's start ("seated") whatever
    start it ran, and no figure said which joints had a clearance (issue 45)."""
    ds = start_and_clearance_sweep
    title = figure(ds, kind, [f"initial_joints={start}", f"A_clearance={a_clearance}"]).get_suptitle()
    assert said(title, f"start: {start}") and said(title, f"clearance at {joints}")


def test_cases_drawn_together_are_titled_with_what_they_share_only(start_and_clearance_sweep):
    """Overlaid cases of both starts have no "start:" in the title; those of one start that
    differ in A's clearance name neither A nor B as the joints with clearance."""
    ds = start_and_clearance_sweep
    both = figure(ds, "slider", ["A_clearance=0"]).get_suptitle()
    assert "start:" not in both and said(both, "clearance at B")
    one = figure(ds, "slider", ["initial_joints=centred"]).get_suptitle()
    assert said(one, "start: centred") and "clearance at" not in one


def test_a_life_figure_draws_and_names_the_joint_its_config_gives_a_clearance():
    """A life run with a clearance at the bearing O only: its wear maps were of joint B (an
    ideal joint, zero wear), chosen between A and B alone (issue 45)."""
    from test_figure_layout import CONFIG, TINY_LIFE

    from clearsweep.config import load_config
    from clearsweep.service_life import life

    ds = life(load_config(CONFIG, [*TINY_LIFE, "joints.B.clearance=0", "joints.O.clearance=1e-4",
                                   "life.max_blocks=2"]))
    title = figure(ds, "life").get_suptitle()
    assert "wear maps of bearing O" in title and said(title, "clearance at O")
# --- the guide P drawn as what it is (issue 45 item 5) ---------------------------------------

@pytest.fixture(scope="module")
def guide_run() -> xr.Dataset:
    """A short one_clearance run with a clearance in the guide P: 0.2 mm across y, 0.1 mm
    across z, so that the gap is not a circle."""
    from clearsweep.simulation import simulate

    return simulate("configs/one_clearance.yaml", ["joints.P.clearance_y=2e-4",
                                                   "joints.P.clearance_z=1e-4",
                                                   "solver.duration=0.05"])


def test_the_orbit_draws_the_guide_gap_as_a_rectangle_with_the_block_inside(guide_run):
    fig = figure(guide_run, "orbit")
    factor = 1e-3       # in mm, the unit of every clearance on a figure
    (ax,) = [a for a in fig.axes if "P" in a.get_title()]       # one panel: across the guide
    assert "yz" in ax.get_title()
    d = guide_run["ball_offset"].sel(joint="P")
    y, z = d.sel(axis="y").values, d.sel(axis="z").values
    gaps = [ln for ln in ax.get_lines() if "gap" in str(ln.get_label())]
    assert len(gaps) == 1
    gx, gy = gaps[0].get_xdata() * factor, gaps[0].get_ydata() * factor
    # the rectangle's corners are the configured half-gaps [m]
    assert max(gx) == pytest.approx(2e-4) and max(gy) == pytest.approx(1e-4)
    assert min(gx) == pytest.approx(-2e-4) and min(gy) == pytest.approx(-1e-4)
    # the block's path lies inside it (up to the contact's penetration, well under 5 %)
    assert np.abs(y).max() > 1.2e-4                 # beyond the smaller clearance: no circle holds it
    assert np.abs(y).max() <= max(gx) * 1.05 and np.abs(z).max() <= max(gy) * 1.05


def test_the_wear_polar_figure_calls_the_guide_not_applicable_not_unworn(guide_run):
    # the guide's walls wear (wear-map shows it), but a profile about an axis is not theirs
    assert float(guide_run["wear_map"].sel(joint="P").max()) > 0.0
    fig = figure(guide_run, "wear-polar")
    title = " ".join(fig.get_suptitle().split())
    assert "guide P: not applicable" in title
    assert "P: no wear" not in title
    assert not [a for a in fig.axes if "P" in a.get_title()]


@pytest.mark.parametrize("attrs", [{"units": "min-1"}, {}])
def test_a_speed_in_revolutions_per_minute_is_labelled_r_per_min(attrs):
    from clearsweep.plotting.common import axis_label

    speed = xr.DataArray([60.0, 120.0], dims="speed_rpm", name="speed_rpm", attrs=attrs)
    assert axis_label(speed).endswith("[r/min]")


def test_the_orbit_names_the_guide_p_a_guide(guide_run):
    titles = [a.get_title() for a in figure(guide_run, "orbit").axes]
    assert any(t.startswith("guide P") for t in titles)
    assert any(t.startswith("joint B") for t in titles)
    assert not any(t.startswith("joint P") for t in titles)


# --- the figure fixes (issue 45 item 6) ------------------------------------------------------

@pytest.fixture(scope="module")
def three_joints() -> xr.Dataset:
    """A run with clearance at the bearing O, the socket B and the guide P: 600 r/min for
    2.5 revolutions (Poincaré sections), a coarse map."""
    from clearsweep.simulation import simulate

    return simulate("configs/one_clearance.yaml", [
        "joints.O.clearance=1e-4", "joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4",
        "mechanism.speed_rpm=600", "solver.duration=0.25", "metrics.settle_time=0.05",
        "wear.map=[8,16]"])


@pytest.mark.parametrize("kind", ["forces", "poincare", "wear-map", "wear-polar", "orbit"])
def test_the_figures_call_o_the_bearing_and_p_the_guide(three_joints, kind):
    """The wear, forces and Poincaré figures called O and P "joint O", "joint P" and "reaction
    at O"; the orbit figure alone said "bearing O" and "guide P"."""
    import re

    fig = figure(three_joints, kind)
    texts = " ".join(" ".join(t.split()) for t in _figure_texts(fig))
    assert not re.search(r"\bjoints? [OP]\b|\bat O\b", texts), texts
    assert "bearing O" in texts
    assert "guide P" in texts or kind == "poincare"     # the block has no section offset
    assert "joint B" in texts
    # the bearing's, the socket's and the guide's panels together, texts apart
    assert layout_problems(fig) == [] and legends_over_data(fig) == []


def test_an_orbit_at_a_fixed_point_draws_as_one_point(case):
    """A ball that stays at one offset (a round-off spread about it) and no clearance to draw
    (the file says none): the orbit was that spread drawn at full scale, a scribble across the
    panel; each axis now spans at least MIN_RELATIVE_SPAN of the offset's magnitude."""
    from clearsweep.plotting.common import MIN_RELATIVE_SPAN

    offset = case["ball_offset"]
    point = xr.DataArray([1.0e-4, -6.0e-5, 2.0e-5], dims="axis", coords={"axis": offset["axis"]})
    noise = 1e-12 * np.sin(np.arange(offset.sizes["time"]))
    fixed = (offset.sel(joint="B") * 0 + point * (1 + xr.DataArray(noise, dims="time"))).expand_dims(
        joint=["B"])
    ds = case.drop_vars(["eccentricity"], errors="ignore").assign(
        ball_offset=fixed.transpose(*[d for d in offset.dims]))
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != "config"}
    fig = figure(ds, "orbit")
    assert not [ln for ax in fig.axes for ln in ax.get_lines() if "clearance" in str(ln.get_label())]
    size = 1e3 * float(np.abs(point).max())        # mm
    for ax in fig.axes:
        for low, high in (ax.get_xlim(), ax.get_ylim()):
            assert high - low >= MIN_RELATIVE_SPAN * size * (1 - 1e-9), ax.get_title()


def test_a_clearance_is_written_in_mm_in_legends_titles_and_axes(sweep_ds):
    """One unit per quantity: the synthetic sweep's B clearances (0.1 and 0.25 mm) read
    "B_clearance=0.0001" in a legend, "B_clearance=0.00025 m" in a --select title, "[m]" on
    a line's axis, "[um]" on a heat map's and "100 um" in the orbit's legend."""
    slider = figure(sweep_ds, "slider")
    legend = [t.get_text() for t in slider.legends[0].get_texts()]
    assert "B_coating=none, B_clearance=0.1 mm" in legend
    title = " ".join(figure(sweep_ds, "slider", ["B_clearance=2.5e-4"]).get_suptitle().split())
    assert "selection: B_clearance=0.25 mm" in title
    line = figure(sweep_ds, "sweep", ["B_coating=PTFE"]).axes[0]
    assert line.get_xlabel().endswith("[mm]")
    np.testing.assert_allclose(line.get_lines()[0].get_xdata(), [0.1, 0.25])
    heat = figure(sweep_ds, "sweep", metric="normal_force_peak")
    (ax, *_) = [a for a in heat.axes if a.images]
    labels = [ax.get_xlabel(), ax.get_ylabel()]
    ticks = [t.get_text() for t in (ax.get_xticklabels() if "clearance" in labels[0]
                                    else ax.get_yticklabels())]
    assert any("clearance" in label and label.endswith("[mm]") for label in labels)
    assert ticks == ["0.1", "0.25"]
    orbit = [t.get_text() for t in figure(sweep_ds, "orbit", ["B_coating=none"]).legends[0].get_texts()]
    assert "joint B clearance 0.25 mm (swept)" in orbit


@pytest.mark.parametrize("value", ["0.25mm", "0.25 mm", "250um", "250 \u00b5m", "2.5e-4m", "2.5e-4"])
def test_select_takes_a_value_in_any_unit_of_its_quantity(sweep_ds, value):
    """``--select B_clearance=0.25mm`` (the unit the figures write) was refused: "unknown
    value for B_clearance '0.25mm'"."""
    fig = figure(sweep_ds, "slider", [f"B_clearance={value}", "B_coating=none"])
    assert "selection: B_clearance=0.25 mm" in " ".join(fig.get_suptitle().split())


@pytest.mark.parametrize("value", ["60rpm", "60 r/min", "60min-1", "60"])
def test_select_takes_a_speed_in_r_per_min(value):
    from clearsweep.analysis import parse_selection

    ds = xr.Dataset({"v": ("speed_rpm", [1.0, 2.0])}, coords={"speed_rpm": [60.0, 120.0]})
    assert parse_selection(ds, [f"speed_rpm={value}"]) == {"speed_rpm": 60.0}
