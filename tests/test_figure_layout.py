"""Every plot kind, drawn at its default size, keeps its text inside the figure and apart.

The layout engine places the texts; this test reads where they went: after
``fig.canvas.draw()`` each visible text artist's ``get_window_extent`` (titles, axis labels,
tick labels, annotations, offset texts, colour-bar labels, legends) must lie inside the
figure and overlap no other text's, pairwise. Drawn from a single run, a sweep with and
without ``--select``, an ensemble, a life run, a reliability sweep and a Sobol' result, and
from results with the structure of the shipped examples (the main job ``configs/paper.yaml``,
the reliability example, ``configs/life_sweep.yaml`` and the sensitivity example): the
same dimensions, coordinates and value ranges, but short durations and few members, built
once per test module (``tests/shipped.py`` says how each differs from the real run).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shipped
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Text
from synthetic import case, heat_map_sweep, sweep_ds  # noqa: F401  (pytest fixtures)
from test_ensemble import synthetic_ensemble

from clearsweep.config import load_config
from clearsweep.plotting import figure
from clearsweep.sensitivity import SobolIndices, indices_figure

#: Texts may touch: overlaps and overhangs up to this many pixels (at 100 dpi) are not counted.
TOLERANCE_PX = 1.0

CONFIG = "configs/one_clearance.yaml"
#: A short life run: 300 r/min (0.2 s blocks), a coarse map, wear x300, to 70 um of wear.
TINY_LIFE = ["mechanism.speed_rpm=300", "metrics.settle_time=0.02", "wear.map=[8,16]",
             "wear.interpolate=true", "solver.energy_tolerance=0.5", "wear.amplification=300",
             "life.cycles=1e5", "life.jump_clearance_fraction=0.1",
             "life.max_clearance_growth=7e-5"]


def _drawn_texts(fig) -> list[tuple[str, object]]:
    """Draw ``fig``; (text, window extent) of every non-blank text artist drawn (tick labels
    outside the view limits exist but are not drawn)."""
    drawn: dict[int, Text] = {}
    original = Text.draw

    def record(self, renderer):
        drawn[id(self)] = self
        return original(self, renderer)

    FigureCanvasAgg(fig)
    fig.set_dpi(100)
    Text.draw = record  # type: ignore[method-assign]
    try:
        fig.canvas.draw()
    finally:
        Text.draw = original  # type: ignore[method-assign]
    renderer = fig.canvas.get_renderer()
    found = []
    for artist in drawn.values():
        if not artist.get_visible() or not artist.get_text().strip():
            continue
        box = artist.get_window_extent(renderer)
        if box.width > 0 and box.height > 0:
            found.append((artist.get_text(), box))
    return found


def layout_problems(fig) -> list[str]:
    """Texts that leave the figure, and pairs of texts that overlap."""
    texts = _drawn_texts(fig)
    frame = fig.bbox
    problems = [f"leaves the figure: {text!r}" for text, box in texts
                if box.x0 < frame.x0 - TOLERANCE_PX or box.y0 < frame.y0 - TOLERANCE_PX
                or box.x1 > frame.x1 + TOLERANCE_PX or box.y1 > frame.y1 + TOLERANCE_PX]
    for (a, box_a), (b, box_b) in itertools.combinations(texts, 2):
        dx = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)
        dy = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
        if dx > TOLERANCE_PX and dy > TOLERANCE_PX:
            problems.append(f"overlap: {a!r} and {b!r}")
    return problems


@pytest.fixture(scope="module")
def life_ds():
    from clearsweep.service_life import life

    return life(load_config(CONFIG, TINY_LIFE))


@pytest.fixture(scope="module")
def reliability_ds(tmp_path_factory):
    from clearsweep.sweeping import run_sweep

    base = load_config(CONFIG, TINY_LIFE).to_dict()
    doc = {"store": "reliability",
           "base": {**base, "reliability": {"members": 3, "seed": 2, "wear_coefficient_cv": 0.3}},
           "sweep": {"grid": {"joints.B.clearance": [1.5e-4, 2.5e-4]}}}
    path = tmp_path_factory.mktemp("rel") / "rel.nc"
    run_sweep(doc, path, workers=1, progress=False).close()
    with xr.open_dataset(path) as ds:
        yield ds.load()


SINGLE_KINDS = ["slider", "forces", "wear-map", "wear-polar", "orbit"]
#: kind -> selection of the synthetic sweep (coating x clearance of B) it is drawn with
SWEEP_SELECTIONS = [
    ("slider", None), ("slider", ["B_coating=PTFE"]),
    ("forces", None), ("forces", ["B_clearance=2.5e-4"]),
    ("wear-map", ["B_coating=PTFE", "B_clearance=1e-4"]),
    ("wear-polar", None), ("wear-polar", ["B_coating=none"]),
    ("orbit", None), ("orbit", ["B_coating=none"]),
    ("sweep", None), ("sweep", ["B_coating=PTFE"]), ("sweep", ["B_clearance=1e-4"]),
]


@pytest.mark.parametrize("kind", SINGLE_KINDS)
def test_a_single_run_figure_keeps_its_text_apart(case, kind):
    assert layout_problems(figure(case, kind)) == []


@pytest.mark.parametrize("kind, select", SWEEP_SELECTIONS,
                         ids=[f"{k}-{'-'.join(s) if s else 'all'}" for k, s in SWEEP_SELECTIONS])
@pytest.mark.slow
def test_a_sweep_figure_keeps_its_text_apart(sweep_ds, kind, select):
    assert layout_problems(figure(sweep_ds, kind, select)) == []


@pytest.mark.parametrize("metric", ["wear_depth_axis_max", "normal_force_peak"])
def test_a_sweep_heat_map_of_per_joint_metrics_keeps_its_text_apart(sweep_ds, metric):
    assert layout_problems(figure(sweep_ds, "sweep", metric=metric)) == []


def test_a_heat_map_with_an_outlier_keeps_its_text_apart():
    grid = np.arange(24.0).reshape(4, 6)
    grid[3, 0] = 300.0
    fig = figure(heat_map_sweep(grid), "sweep")
    assert "percentile" in fig.axes[1].get_ylabel()
    assert layout_problems(fig) == []


def test_an_ensemble_figure_keeps_its_text_apart():
    fig = figure(synthetic_ensemble(), "sweep", metric="wear_depth_max_final")
    assert layout_problems(fig) == []


def test_a_life_figure_keeps_its_text_apart(life_ds):
    assert layout_problems(figure(life_ds, "life")) == []


@pytest.mark.slow
@pytest.mark.parametrize("b10", [False, True])
def test_a_reliability_figure_keeps_its_text_apart(reliability_ds, b10):
    assert layout_problems(figure(reliability_ds, "reliability", b10=b10)) == []


def test_a_sensitivity_figure_keeps_its_text_apart():
    names = ("joints.B.clearance", "joints.B.coating_thickness", "contact.restitution",
             "mechanism.speed_rpm")
    result = SobolIndices(names, np.array([0.79, 0.01, 0.0, 0.17]), np.full(4, 0.1),
                          np.array([0.78, 0.0, 0.02, 0.17]), np.full(4, 0.08),
                          output="normal_force_peak_settled", samples=3072, base_points=512,
                          output_label="peak normal force in the settled window (joint=B)")
    assert layout_problems(indices_figure(result)) == []


def test_the_check_finds_overlapping_and_escaping_text():
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    ax = fig.add_subplot()
    ax.set_title("a title far too long to fit in a figure three inches wide, at any font size")
    ax.text(0.5, 0.5, "here")
    ax.text(0.5, 0.5, "there")
    problems = layout_problems(fig)
    assert any(p.startswith("leaves the figure: 'a title") for p in problems)
    assert "overlap: 'here' and 'there'" in problems


# --- no legend over data (issue 45 item 6) ---------------------------------------------------

def _segments_cross(xy: np.ndarray, box) -> bool:
    """Whether the polyline ``xy`` (display coordinates, NaN breaks it) enters ``box``: the
    Liang-Barsky clip of each segment against the box, all segments at once."""
    x0, y0, x1, y1 = xy[:-1, 0], xy[:-1, 1], xy[1:, 0], xy[1:, 1]
    keep = np.isfinite(x0) & np.isfinite(y0) & np.isfinite(x1) & np.isfinite(y1)
    x0, y0, x1, y1 = x0[keep], y0[keep], x1[keep], y1[keep]
    low, high = np.zeros_like(x0), np.ones_like(x0)
    inside = np.ones_like(x0, dtype=bool)
    for p, q in ((x0 - x1, x0 - box.x0), (x1 - x0, box.x1 - x0),
                 (y0 - y1, y0 - box.y0), (y1 - y0, box.y1 - y0)):
        parallel = p == 0
        inside &= ~(parallel & (q < 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(parallel, 0.0, q / np.where(parallel, 1.0, p))
        low = np.where(~parallel & (p < 0), np.maximum(low, t), low)
        high = np.where(~parallel & (p > 0), np.minimum(high, t), high)
    return bool((inside & (low <= high)).any())


def _points_inside(xy: np.ndarray, box) -> bool:
    xy = xy[np.isfinite(xy).all(axis=1)]
    return bool(((xy[:, 0] > box.x0) & (xy[:, 0] < box.x1)
                 & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)).any())


def _covered(ax, box, renderer) -> list[str]:
    """The data of ``ax`` (lines and their markers, bars, error bars, scatter points) that
    the display box ``box`` covers."""
    from matplotlib.collections import LineCollection, PathCollection
    from matplotlib.patches import Rectangle

    found = []
    for line in ax.get_lines():
        if not line.get_visible():
            continue
        xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
        drawn = line.get_linestyle() not in ("None", "none", "", " ")
        if (drawn and _segments_cross(xy, box)) or _points_inside(xy, box):
            found.append(f"line {line.get_label()!r}")
    for coll in ax.collections:
        if not coll.get_visible():
            continue
        if isinstance(coll, LineCollection):       # error bars
            if any(_segments_cross(coll.get_transform().transform(np.asarray(seg, dtype=float)), box)
                   for seg in coll.get_segments() if len(seg) > 1):
                found.append(f"error bars {coll.get_label()!r}")
        elif isinstance(coll, PathCollection):      # scatter points
            offsets = np.asarray(coll.get_offsets(), dtype=float)
            if offsets.size and _points_inside(coll.get_offset_transform().transform(offsets), box):
                found.append(f"points {coll.get_label()!r}")
    for patch in ax.patches:
        if isinstance(patch, Rectangle) and patch.get_visible() and patch.get_fill():
            extent = patch.get_window_extent(renderer)
            if extent.width > 0 and extent.height > 0 and extent.overlaps(box):
                found.append(f"bar {patch.get_label()!r}")
    return found


def legends_over_data(fig) -> list[str]:
    """Legends (of a panel, or of the figure) whose box, drawn at 100 dpi and shrunk by
    :data:`TOLERANCE_PX`, covers a panel's data: a line (its segments, or its markers), a
    bar, an error bar or a scatter point, in display coordinates, within the panel."""
    from matplotlib.transforms import Bbox

    FigureCanvasAgg(fig)
    fig.set_dpi(100)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legends = [a.get_legend() for a in fig.axes if a.get_legend() is not None] + list(fig.legends)
    problems = []
    for legend in legends:
        if not legend.get_visible():
            continue
        box = legend.get_window_extent(renderer).padded(-TOLERANCE_PX)
        entries = ", ".join(t.get_text() for t in legend.get_texts()[:2])
        for ax in fig.axes:
            if ax.name == "3d":
                continue
            inside = Bbox.intersection(box, ax.bbox)
            if inside is None or inside.width <= 0 or inside.height <= 0:
                continue
            problems += [f"legend ({entries}) covers {what} in {ax.get_title() or ax.get_ylabel()!r}"
                         for what in _covered(ax, inside, renderer)]
    return problems


def test_the_legend_check_finds_a_legend_over_a_line_a_bar_and_error_bars():
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    ax.plot([0.0, 1.0], [0.95, 0.95], label="a line along the top")
    ax.set_ylim(0.0, 1.0)
    ax.legend(loc="upper right")
    assert any("covers line 'a line along the top'" in p for p in legends_over_data(fig))
    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    ax.bar([0, 1, 2], [1.0, 1.0, 1.0], label="bars")
    ax.errorbar([0, 1, 2], [0.5, 0.5, 0.5], yerr=0.5, ls="none", label="error bars")
    ax.set_ylim(0.0, 1.0)
    ax.legend(loc="center")
    problems = legends_over_data(fig)
    assert any("covers bar" in p for p in problems) and any("covers error bars" in p for p in problems)
    fig = Figure(figsize=(4, 3), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0.0, 1.0], [0.0, 0.2], label="low")
    ax.set_ylim(0.0, 1.0)
    ax.legend(loc="upper right")
    fig.legend(["outside"], loc="outside lower center")
    assert legends_over_data(fig) == []


# --- results with the shipped examples' structure -------------------------------------------

@pytest.fixture(scope="module")
def main_job(tmp_path_factory):
    return shipped.main_job(tmp_path_factory.mktemp("main"))


@pytest.fixture(scope="module")
def reliability_example():
    return shipped.reliability_example()


@pytest.fixture(scope="module")
def life_sweep(tmp_path_factory):
    return shipped.life_sweep(tmp_path_factory.mktemp("life_sweep"))


@pytest.fixture(scope="module")
def sensitivity_example(tmp_path_factory):
    return shipped.sensitivity_example(tmp_path_factory.mktemp("sensitivity"))


#: (kind, --select, options) drawn from the main job: the commands of docs/reproduction.md
#: and the per-joint heat maps.
MAIN_JOB_FIGURES = [
    ("slider", ["coating_joints=none"], {}),
    ("slider", ["clearance_joints=AB"], {}),
    ("forces", ["clearance_joints=AB", "coating_joints=none"], {}),
    ("forces", ["clearance_joints=AB", "coating_joints=B"], {}),
    ("wear-polar", ["clearance_joints=B", "coating_joints=none"], {}),
    ("wear-polar", ["clearance_joints=AB", "coating_joints=AB"], {}),
    ("wear-map", ["clearance_joints=AB", "coating_joints=none"], {}),
    ("wear-map", ["clearance_joints=B", "coating_joints=none"], {}),
    ("orbit", ["clearance_joints=AB", "coating_joints=none"], {}),
    ("orbit", ["clearance_joints=B", "coating_joints=B"], {}),
    ("sweep", None, {"metric": "slider_acceleration_peak_settled"}),
    ("sweep", None, {"metric": "wear_depth_max_final"}),
    ("sweep", None, {"metric": "normal_force_peak_settled"}),
    ("sweep", ["clearance_joints=AB"], {"metric": "wear_depth_max_final"}),
]


def _offset_texts(fig) -> list[str]:
    return [t for ax in fig.axes for axis in (ax.xaxis, ax.yaxis)
            if (t := axis.get_offset_text().get_text())]


@pytest.mark.slow
@pytest.mark.parametrize("kind, select, options", MAIN_JOB_FIGURES,
                         ids=[f"{k}-{'-'.join(s) if s else 'all'}-{'-'.join(o.values())}"
                              for k, s, o in MAIN_JOB_FIGURES])
def test_a_main_job_figure_keeps_its_text_apart_without_offset_text(main_job, kind, select,
                                                                    options):
    fig = figure(main_job, kind, select, **options)
    assert layout_problems(fig) == []
    assert _offset_texts(fig) == []


@pytest.mark.slow
@pytest.mark.parametrize("b10", [False, True])
def test_the_reliability_example_figure_keeps_its_text_apart(reliability_example, b10):
    """The example's revolutions span 5e4 to 6e5: minor tick labels 3x10^5 and 4x10^5 ran
    into each other."""
    assert layout_problems(figure(reliability_example, "reliability", b10=b10)) == []


@pytest.mark.slow
@pytest.mark.parametrize("metric", ["wear_depth_max_final", "cycles_reached",
                                    "clearance_effective_final"])
def test_a_life_sweep_figure_keeps_its_text_apart(life_sweep, metric):
    fig = figure(life_sweep, "sweep", metric=metric)
    assert layout_problems(fig) == []
    assert _offset_texts(fig) == []


@pytest.mark.slow
@pytest.mark.parametrize("metric", ["normal_force_peak_settled", "slider_acceleration_rms_settled"])
def test_a_sampling_sweep_is_drawn_against_its_inputs(sensitivity_example, metric):
    """3,072 sample points joined by a line over the point number read as a signal: each
    input gets a scatter panel instead."""
    fig = figure(sensitivity_example, "sweep", metric=metric)
    assert layout_problems(fig) == []
    assert not [line for ax in fig.axes for line in ax.get_lines() if len(line.get_xdata()) > 2]
    assert [ax.get_xlabel().split(" [")[0] for ax in fig.axes] == \
        ["B_clearance", "B_coating_thickness", "restitution", "speed_rpm"]
    # each quantity in its one unit (issue 45 item 6): a clearance in mm, a coating in um
    assert [ax.get_xlabel() for ax in fig.axes[:2]] == ["B_clearance [mm]",
                                                        "B_coating_thickness [\u00b5m]"]


def test_the_reliability_bands_are_hatched_and_in_the_legend(reliability_example):
    from matplotlib.collections import PolyCollection

    fig = figure(reliability_example, "reliability")
    bands = [c for c in fig.axes[0].collections if isinstance(c, PolyCollection)]
    assert len(bands) == 4
    assert len({band.get_hatch() for band in bands}) == 4
    legend_texts = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert sum(text.endswith("95% band") for text in legend_texts) == 4


def test_a_small_spread_on_a_heat_map_is_stated_and_looks_small():
    """Values within 1.9 % of each other: two cells printed alike must not get far-apart
    colours."""
    grid = 1.46 + 0.028 * np.linspace(0.0, 1.0, 24).reshape(4, 6)
    fig = figure(heat_map_sweep(grid), "sweep")
    ax = fig.axes[0]
    assert "varies by 1.9 % of its mean" in ax.get_title()
    low, high = ax.images[0].get_clim()
    assert high - low >= 0.099 * grid.mean()
    assert layout_problems(fig) == []


def test_cell_values_are_drawn_only_where_they_fit():
    """Values that need six digits to tell apart (``2.37001e-09``) do not fit a cell of a
    4 x 16 map: they are left out rather than run over each other and the cell border."""
    grid = 2.37e-9 * (1.0 + 1e-5 * np.arange(64.0).reshape(4, 16))
    narrow = heat_map_sweep(np.zeros((4, 6))).drop_vars("slider_acceleration_peak_settled")
    narrow = narrow.assign_coords(B_clearance=np.arange(16) * 1e-5)
    narrow["slider_acceleration_peak_settled"] = (("B_coating", "B_clearance"), grid,
                                                  {"units": "m", "long_name": "settled peak"})
    fig = figure(narrow, "sweep")
    assert layout_problems(fig) == []
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    for text in ax.texts:
        x, y = text.get_position()
        (x0, y0), (x1, y1) = ax.transData.transform([(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)])
        box = text.get_window_extent(renderer)
        assert x0 <= box.x0 and box.x1 <= x1 and y0 <= box.y0 and box.y1 <= y1, text.get_text()
    wide = figure(heat_map_sweep(np.arange(24.0).reshape(4, 6) + 1.0), "sweep")
    assert len(wide.axes[0].texts) == 24          # short values fit and are all drawn


def test_a_heat_map_draws_no_panel_for_a_joint_without_data(life_sweep):
    """Joints A and O of the life sweep are ideal: no wear anywhere, which drew a flat panel
    with a made-up -0.1..0.1 colour bar. A joint ideal in every case has no panel and no
    mention (its metric is n/a throughout); a joint with clearance and no value is named
    (tests/test_plotting.py: joint A's unworn axis z)."""
    assert float(life_sweep["wear_depth_max_final"].sel(joint="A").fillna(0.0).max()) == 0.0
    fig = figure(life_sweep, "sweep", metric="wear_depth_max_final")
    assert [ax.get_title().split("\n")[0] for ax in fig.axes if ax.images] == ["joint B"]
    assert "joint A" not in fig.get_suptitle() and "joint O" not in fig.get_suptitle()


def test_the_title_names_the_overrides_and_the_start(case):
    ds = case.copy()
    ds.attrs["history"] = ("2026-01-01T00:00:00Z: created by clearsweep\n2026-01-01T00:00:00Z: "
                           "clearsweep run configs/one_clearance.yaml --set joints.B.coating=PTFE "
                           "--set initial.joints=centred -o out.nc")
    ds.attrs["config"] = ds.attrs["config"] + "\ninitial: {joints: centred}\n"
    title = " ".join(figure(ds, "slider").get_suptitle().split())
    assert "--set joints.B.coating=PTFE, initial.joints=centred" in title
    assert "start: centred" in title
    # a sweep's file keeps its config as written: the start is the --set one
    ds.attrs["config"] = case.attrs["config"]
    assert "start: centred" in figure(ds, "slider").get_suptitle()


def test_a_run_records_its_command_line_and_its_figure_names_the_overrides(tmp_path):
    """A PTFE run made with --set read "case: one_clearance": the file's history now records
    the command line, and the title every --set of it."""
    from click.testing import CliRunner

    from clearsweep.cli import main

    out = tmp_path / "run.nc"
    result = CliRunner().invoke(main, ["run", CONFIG, "--set", "solver.duration=0.004",
                                       "--set", "joints.B.coating=PTFE", "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    with xr.open_dataset(out) as ds:
        ds.load()
    assert ds.attrs["history"].splitlines()[-1].endswith(
        f"clearsweep run {CONFIG} --set solver.duration=0.004 --set joints.B.coating=PTFE "
        f"-o {out} -q")
    title = " ".join(figure(ds, "slider").get_suptitle().split())
    assert ("case: one_clearance; start: seated; clearance at B; --set solver.duration=0.004, "
            "joints.B.coating=PTFE") in title


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["wear-map", "wear-polar", "orbit"])
def test_a_joint_without_data_gets_no_panel(main_job, kind):
    """With a clearance at B alone, joint A is ideal: no wear, the ball at the centre. It
    gets no panel, and the title does not name it (nor O, ideal throughout)."""
    fig = figure(main_job, kind, ["clearance_joints=B", "coating_joints=none"])
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles and not any(title.startswith("joint A") for title in titles)
    assert "joint A" not in fig.get_suptitle() and "joint O" not in fig.get_suptitle()
    assert layout_problems(fig) == []


def test_a_life_run_records_its_command_line(short_life_cli):
    from test_service_life import SHORT_LIFE

    out, _ = short_life_cli
    with xr.open_dataset(out) as ds:
        history = ds.attrs["history"]
        title = " ".join(figure(ds.load(), "life").get_suptitle().split())
    assert history.splitlines()[-1].split(": ", 1)[1].startswith("clearsweep life ")
    assert "--set " + ", ".join(SHORT_LIFE) in title


@pytest.fixture(scope="module")
def poincare_runs() -> xr.Dataset:
    """Two short one_clearance runs at 600 r/min (three revolutions each) as a sweep over B's
    clearance."""
    from clearsweep.simulation import simulate

    runs = [simulate(CONFIG, ["mechanism.speed_rpm=600", "solver.duration=0.3",
                              f"joints.B.clearance={c}"]) for c in (2.5e-4, 1e-4)]
    names = ["poincare_offset", "poincare_velocity", "poincare_slider_acc", "poincare_time"]
    ds = xr.concat([r[names] for r in runs], "B_clearance").assign_coords(B_clearance=[2.5e-4, 1e-4])
    ds.attrs = runs[0].attrs
    return ds


@pytest.mark.parametrize("select", [None, ["B_clearance=1e-4"]])
def test_a_poincare_figure_keeps_its_text_apart(poincare_runs, select):
    fig = figure(poincare_runs, "poincare", select)
    assert layout_problems(fig) == []
    assert len(fig.axes) == 2       # joint B (A is ideal) and the slider acceleration


# --- tick labels on every axis that has data (issue 45 item 6) -------------------------------

def _unlabelled_axes(fig) -> list[str]:
    """The x or y axes of panels with data whose drawn tick labels are all empty."""
    fig.canvas.draw()
    missing = []
    for ax in fig.axes:
        if not (ax.get_lines() or ax.collections or ax.patches) or ax.name == "polar":
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            texts = [t.get_text() for t in axis.get_ticklabels(which="both")
                     if t.get_visible() and axis.get_visible()]
            if not any(t.strip() for t in texts):
                missing.append(f"{ax.get_title()!r}: {name}")
    return missing


@pytest.mark.parametrize("b10", [False, True])
def test_a_reliability_figure_labels_the_ticks_of_every_axis_with_data(reliability_ds, b10):
    assert _unlabelled_axes(figure(reliability_ds, "reliability", b10=b10)) == []


def test_a_log_axis_narrower_than_its_one_two_three_five_steps_still_has_tick_labels():
    # a B10 axis of designs between 1.2e5 and 1.8e5 revolutions had no label at all
    from matplotlib.figure import Figure

    from clearsweep.plotting.common import log_ticks

    fig = Figure()
    ax = fig.add_subplot()
    ax.bar([0, 1], [1.2e5, 1.8e5])
    ax.set_yscale("log")
    ax.set_ylim(1.15e5, 1.85e5)
    log_ticks(ax.yaxis, *ax.get_ylim())
    assert _unlabelled_axes(fig) == []


def test_a_poincare_fixed_point_draws_as_one_point(poincare_runs):
    # period 1: the section's slider acceleration repeats to round-off (a 1e-11 relative spread)
    acc = poincare_runs["poincare_slider_acc"]
    level = float(np.abs(acc).max())
    fixed = poincare_runs.assign(poincare_slider_acc=acc * 0 + level * (1 + 1e-11 * (acc.revolution % 3)))
    ax = figure(fixed, "poincare").axes[-1]
    low, high = ax.get_ylim()
    assert high - low > 1e-3 * level


def test_a_life_limit_far_above_the_data_does_not_set_the_axis(life_ds):
    import re

    from clearsweep.plotting.common import scaled

    depth = float(life_ds["wear_depth_max"].max())
    config = re.sub(r"max_clearance_growth: .*", f"max_clearance_growth: {100 * depth!r}",
                    life_ds.attrs["config"])
    assert config != life_ds.attrs["config"]
    fig = figure(life_ds.assign_attrs(config=config), "life")
    factor, _ = scaled(life_ds["wear_depth_max"])
    (ax,) = [a for a in fig.axes if a.get_ylabel().startswith("maximum wear depth")]
    assert ax.get_ylim()[1] < 2.0 * depth / factor      # the axis stays on the data
    assert any("max_clearance_growth" in t.get_text() for t in ax.texts)   # the limit is noted
