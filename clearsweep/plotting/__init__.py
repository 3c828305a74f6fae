"""Figures from results datasets (the paper's Figures 9-16), headless.

Figures are built on ``matplotlib.figure.Figure`` directly (no pyplot, no
global state, no display needed) and saved in the format the output
file's suffix names. Every axis and colour-bar label carries the units of the
variable drawn, from its ``units`` attribute; ``[-]`` marks a dimensionless
or categorical quantity. Lengths and forces are drawn in the unit that reads
directly (nm, µm, mm, kN: ``variables.DISPLAY_UNITS``), never with offset text; a swept or
selected value in one unit per quantity wherever it is written (legends, the ``--select``
line of the title, the axis over it: a clearance in mm, ``common.QUANTITY_UNITS``). The
title names the case or ``--select`` slice, the start (seated or centred), the joints with
clearance (the case's own, swept values included) and every
``--set`` override of the command line the file's ``history`` records. A joint that is ideal
in every case drawn (``analysis.ideal_joints``) has no panel and is named nowhere; a
per-joint kind of results whose joints are all ideal is refused (``PlotError``). The forces
on an ideal joint's ball (``forces``) are drawn: they are the constraint's, not n/a.

Kinds (``KINDS``):

``slider``
    slider position, velocity and acceleration against the crank angle or
    time, sweep cases overlaid (Figures 9, 12, 13).
``forces``
    reaction at O and the force on the ball of each joint: magnitude and
    x, y, z components, cases overlaid (Figures 10, 14, 15).
``wear-map``
    per joint, the socket wear map (polar x azimuth) and the same map on a
    sphere (Figures 11, 16); the bearing's wear around it; the guide's four
    walls as strips (along and across the guide, mm); one case.
``wear-polar``
    per joint and axis, the projected wear depth as a worn profile on the
    unit circle, exaggerated (Figures 11, 16); cases overlaid.
``orbit``
    ball-centre offset in the socket frame on the xy, xz and yz planes,
    inside the clearance circle (the journal's and the guide block's on yz, the
    block's inside its rectangular gap), in mm; cases overlaid. A planar mechanism's
    (the slider-crank's) joints one panel each, on the plane of the socket frame their
    centre moves in, naming any departure from it beyond round-off.
``poincare``
    the Poincare section, once per crank revolution: per clearance joint the ball-centre
    offset over the clearance on the plane of its two most spread axes, and the slider
    acceleration against the revolution; cases overlaid. Needs 2 revolutions at least.
``sweep``
    one summary metric (``analysis.case_summary``) over one sweep dimension
    (lines) or two (heat maps, their spread stated, a joint without data left out);
    on a sampling sweep, against each sampled input (scatter); for an ensemble (a ``member`` dimension), the
    ensemble mean over one or two design dimensions with its 95 % confidence
    interval as error bars, one line per value of the second dimension.
``life``
    a life run (``clearsweep life``): wear depth, effective clearance, coating
    remaining, settled peak normal force, RMS slider acceleration and impacts
    per revolution against revolutions (log axis), the limits that are set, and
    the wear map's evolution (snapshots, joint B or the worn joint).
``reliability``
    a reliability sweep (``store: reliability``): one panel per limit (and "any"),
    the Kaplan-Meier reliability R(N) of each design against revolutions (log axis)
    with its 95 % band; with ``b10=True`` (``--b10``), each design's B10 with its
    interval as error bars instead.
``spectrum``
    the slider acceleration's Welch power spectrum over the settled window against crank
    orders (log power), cases overlaid; the dominant order and the share of the power
    above order ``HIGH_ORDER`` in the title of one case (docs/physics.md section 11).
``bifurcation``
    a sweep over one parameter (``x``: the swept key, a sweep dimension or a key of a zip
    group): the Poincaré samples of each case's last ``BIFURCATION_REVOLUTIONS`` revolutions
    against the swept value, one panel for the slider acceleration and one per clearance
    joint (the offset component, scaled by the clearance, along which the samples spread
    most).
``dynamics-map``
    a grid sweep over two parameters (``x`` and ``y``: swept keys; every other swept key
    fixed by ``select``): each case's period (1 to 8, none, undetermined) as a categorical
    map with a discrete legend, and the 0-1 test's K on a continuous scale beside it.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import xarray as xr
import yaml
from matplotlib.figure import Figure

from ..analysis import SelectionError, choice_message, coordinate_for_key, parse_selection, sweep_dims
from ..choices import (  # noqa: F401
    DEFAULT_SWEEP_METRIC,
    DPI_RANGE,
    FIGURE_DPI,
    KINDS,
    OUTPUT_SUFFIXES,
    SWEPT_X_KINDS,
    X_AXES,
)
from ..dataset import replaced_on_success
from ..outputs import figure_metadata
from .common import (  # noqa: F401
    AXIS_LABEL_CHARACTERS,
    COLOURBAR_LABEL_CHARACTERS,
    DIMENSIONLESS,
    MAX_CYCLE_COLOURS,
    MAX_LEGEND_ENTRIES,
    MIN_RELATIVE_SPAN,
    NEGLIGIBLE_VARIATION,
    TITLE_CHARACTERS_PER_INCH,
    PlotError,
    axis_label,
    clearance_text,
    coordinate_text,
    file_figures,
    keep_relative_span,
    plain_ticks,
    point_text,
    run_config,
    selection_text,
    swept_config_value,
    wrapped_label,
)
from .dynamics import _draw_dynamics_map, map_axes  # noqa: F401
from .effects import _draw_effects
from .life import LIFE_SNAPSHOT_PANELS, _draw_life, snapshot_note  # noqa: F401
from .motion import (  # noqa: F401
    BIFURCATION_REVOLUTIONS,
    SPECTRUM_MAX_ORDER,
    _draw_bifurcation,
    _draw_spectrum,
    bifurcation_axis,
    bifurcation_selection,
)
from .orbit import _draw_orbit
from .poincare import _draw_poincare
from .reliability import _draw_reliability
from .series import _draw_forces, _draw_slider
from .sweep import (  # noqa: F401
    ANNOTATION_DARK_TEXT_ABOVE,
    HEATMAP_PANEL_INCHES,
    MAX_ANNOTATED_CELLS,
    MIN_FIGURE_WIDTH_INCHES,
    ROBUST_FENCE,
    ROBUST_MIN_CELLS,
    ROBUST_PERCENTILES,
    _draw_sweep,
    fit_cell_values,
    robust_limits,
)
from .wear import WEAR_POLAR_EXAGGERATION, _draw_wear_map, _draw_wear_polar, _life_wear_map  # noqa: F401


@dataclass(frozen=True)
class FigureKind:
    """How one figure kind is drawn: its size and its family's drawer."""

    #: Figure size (width, height) [inch].
    size_inches: tuple[float, float]
    #: ``draw(fig, ds, *options)``: draws the kind on ``fig``.
    draw: Callable[..., None]
    #: The options of :func:`figure` the drawer takes after ``ds``, by name (``x``,
    #: ``metric``, ``b10``); a ``metric`` or ``b10`` given to a kind without it is refused.
    options: tuple[str, ...] = ()


#: Every figure kind (``KINDS``), said once: :func:`figure` asks this table.
FIGURES = {
    "slider": FigureKind((8, 8), _draw_slider, ("x",)),
    "forces": FigureKind((15, 9), _draw_forces, ("x",)),
    "wear-map": FigureKind((11, 9), _draw_wear_map),
    "wear-polar": FigureKind((11, 9.5), _draw_wear_polar),
    "orbit": FigureKind((12, 8), _draw_orbit),
    "poincare": FigureKind((14, 5.4), _draw_poincare),
    "sweep": FigureKind((8, 5), _draw_sweep, ("metric",)),
    "life": FigureKind((16, 10), _draw_life),
    "reliability": FigureKind((14, 8), _draw_reliability, ("b10",)),
    "spectrum": FigureKind((9, 5.5), _draw_spectrum),
    "bifurcation": FigureKind((10, 9), _draw_bifurcation, ("x",)),
    "effects": FigureKind((15, 8), _draw_effects),
    "dynamics-map": FigureKind((18, 5.5), _draw_dynamics_map, ("x", "y")),
}


def _kinds_taking(option: str) -> str:
    """``"sweep"``: the kinds whose drawer takes ``option``, for a refusal."""
    return " or ".join(name for name, spec in FIGURES.items() if option in spec.options)


def figure(ds: xr.Dataset, kind: str, select=None, *, x: str | None = None,
           y: str | None = None, metric: str | None = None, b10: bool = False) -> Figure:
    """Build the figure of ``kind`` from ``ds`` (see the module docstring).

    Parameters
    ----------
    ds
        One-case or sweep dataset.
    kind
        One of ``KINDS``.
    select
        ``["DIM=VALUE", ...]`` or ``{dim: value}``: the cases to draw.
    x
        Abscissa of time series: ``"angle"`` (crank angle [degree], ``None``'s) or ``"time"``
        [s]; of ``kind="bifurcation"``, the swept key, by its coordinate's name or its dotted
        config key (``speed_rpm`` or ``mechanism.speed_rpm``; ``None``: the only one); of
        ``kind="dynamics-map"``, the swept key along the abscissa, named the same way.
    y
        ``kind="dynamics-map"``: the swept key along the ordinate.
    metric
        Summary metric of ``kind="sweep"`` (default ``DEFAULT_SWEEP_METRIC``).
    b10
        ``kind="reliability"``: draw B10 with its interval instead of R(N).

    Raises
    ------
    SelectionError
        Unknown kind, abscissa, sweep dimension, value or metric.
    PlotError
        The dataset lacks what the kind draws, or holds several cases where
        the kind draws one.
    """
    if kind not in KINDS:
        raise SelectionError(choice_message("plot kind", kind, list(KINDS)), name="kind",
                             value=kind, choices=KINDS)
    if y is not None and "y" not in FIGURES[kind].options:
        raise PlotError(f"--y applies to --kind {_kinds_taking('y')} only")
    if kind not in SWEPT_X_KINDS:
        x = "angle" if x is None else x
        if x not in X_AXES:
            raise SelectionError(choice_message("abscissa", x, list(X_AXES)), name="x", value=x,
                                 choices=X_AXES)
    elif x is not None:     # the swept key as the sweep file names it, or its dimension
        x = coordinate_for_key(ds, x)
    if y is not None:
        y = coordinate_for_key(ds, y)
    spec = FIGURES[kind]
    if metric is not None and "metric" not in spec.options:
        raise PlotError(f"a metric applies to --kind {_kinds_taking('metric')} only")
    if b10 and "b10" not in spec.options:
        raise PlotError(f"--b10 applies to --kind {_kinds_taking('b10')} only")
    if kind == "wear-map" and file_figures(ds).wear_map_snapshots and "wear_map_snapshot" in ds:
        ds, select = _life_wear_map(ds, select), None       # a life run: no sweep dimensions
    selection = (bifurcation_selection(ds, select, x) if kind == "bifurcation"
                 else parse_selection(ds, select))
    if kind == "dynamics-map":
        for option, key in (("--x", x), ("--y", y)):
            if key is not None and key in selection:
                raise PlotError(f"--select {key}=...: fixes the dimension of {option} {key}, "
                                "which --kind dynamics-map draws; --select fixes the other "
                                "swept dimensions")
    ds = ds.sel(selection) if selection else ds
    fig = Figure(figsize=spec.size_inches, layout="constrained")
    options = {"x": x, "y": y, "metric": metric, "b10": b10}
    spec.draw(fig, ds, *(options[name] for name in spec.options))
    plain_ticks(fig)
    _name_selection(fig, "; ".join(filter(None, [selection_text(ds, selection) or case_text(ds),
                                                 start_text(ds), clearance_text(ds),
                                                 overrides_text(ds)])))
    fit_cell_values(fig)
    return fig


def _name_selection(fig: Figure, line: str) -> None:
    """Add ``line`` (the ``--select`` slice or the case) to the figure's title, so that two
    slices never give figures with the same title; wrap the title to the figure's width."""
    title = next((t for t in fig.texts if t.get_text() == fig.get_suptitle()), None)
    if title is None:
        if not line:
            return
        title = fig.suptitle("")
    text = "\n".join(filter(None, [title.get_text(), line]))
    width = int(fig.get_figwidth() * TITLE_CHARACTERS_PER_INCH)
    title.set_text("\n".join(wrapped for part in text.split("\n")
                             for wrapped in (textwrap.wrap(part, width, break_on_hyphens=False) or [""])))


def case_text(ds: xr.Dataset) -> str:
    """``"case: two_clearances"`` for a one-case dataset whose config names it; "" otherwise."""
    if sweep_dims(ds) or "config" not in ds.attrs:
        return ""
    try:
        name = yaml.safe_load(ds.attrs["config"]).get("name")
    except (yaml.YAMLError, AttributeError):
        return ""
    return f"case: {name}" if isinstance(name, str) and name else ""


def start_text(ds: xr.Dataset) -> str:
    """``"start: seated"``: where the balls of the clearance joints started in the cases drawn:
    a swept ``initial.joints`` as the case ran it (one case chosen with ``--select``), else
    ``initial.joints`` of the config, or of a ``--set`` on the command line; "" where the
    cases drawn started differently or the file has no config."""
    if not {"config", "sweep_config"} & set(ds.attrs):
        return ""
    swept, start = swept_config_value(ds, "initial.joints")
    if swept:
        return f"start: {start}" if start is not None else ""
    initial = run_config(ds).get("initial")
    start = initial.get("joints") if isinstance(initial, dict) else None
    for override in _overrides(ds):
        key, _, value = override.partition("=")
        if key.strip() == "initial.joints":
            start = value.strip()
    return f"start: {start if isinstance(start, str) else 'seated'}"


def _overrides(ds: xr.Dataset) -> list[str]:
    """The ``--set`` overrides of the command line that made the file: the last ``clearsweep``
    line of its ``history`` (:func:`clearsweep.dataset.command_line`)."""
    import shlex

    sets: list[str] = []
    for line in str(ds.attrs.get("history", "")).splitlines():
        _, _, command = line.partition(": ")
        try:
            words = shlex.split(command)
        except ValueError:
            continue
        if words[:1] != ["clearsweep"]:
            continue
        sets = [b for a, b in zip(words, words[1:]) if a == "--set"]
        sets += [w.split("=", 1)[1] for w in words if w.startswith("--set=")]
    return sets


def overrides_text(ds: xr.Dataset) -> str:
    """``"--set joints.B.coating=PTFE"``: every ``--set`` override of the command line that
    made the file; "" where none."""
    sets = _overrides(ds)
    return "--set " + ", ".join(sets) if sets else ""


def plot(ds: xr.Dataset, kind: str, out_path, select=None, *, x: str | None = None,
         y: str | None = None, metric: str | None = None, dpi: int = FIGURE_DPI,
         b10: bool = False) -> Figure:
    """Draw ``kind`` from ``ds`` and save it to ``out_path`` (.png, .pdf or .svg).

    Parameters and errors as ``figure``; ``dpi`` sets the raster resolution.
    Missing parent folders are created. The file appears only once complete
    (temporary file, then rename); a failed write raises ``OSError``.

    Returns
    -------
    matplotlib.figure.Figure
        The saved figure.
    """
    out_path = Path(out_path)
    if out_path.suffix.lower() not in OUTPUT_SUFFIXES:
        raise SelectionError(choice_message("output suffix", out_path.suffix, list(OUTPUT_SUFFIXES)),
                             name="output", value=out_path.suffix, choices=OUTPUT_SUFFIXES)
    fig = figure(ds, kind, select, x=x, y=y, metric=metric, b10=b10)
    # a temporary file renamed into place: a full disk or a kill leaves no partial figure
    with replaced_on_success(out_path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=out_path.suffix.lower()[1:],
                    metadata=figure_metadata(out_path.suffix))
    return fig

