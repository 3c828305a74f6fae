"""Every plot kind, drawn at its default size, keeps its text inside the figure and apart.

The layout engine places the texts; this test reads where they went: after
``fig.canvas.draw()`` each visible text artist's ``get_window_extent`` must lie inside the
figure and overlap no other text's. Drawn from a single run, a sweep with and without
``--select``, an ensemble, a life run, a reliability sweep and a Sobol' result.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
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
