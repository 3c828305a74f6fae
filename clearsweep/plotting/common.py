"""Helpers shared by the figure families: labels with units, the cases of a dataset and
their colours, legends, y-axis spans and title lines."""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import xarray as xr
from matplotlib import colormaps

from ..analysis import (  # noqa: F401 (QUANTITY_UNITS, quantity_*: the figures' names)
    QUANTITY_UNITS,
    file_config,
    ideal_joints,
    iter_cases,
    joint_clearances,
    quantity_of,
    quantity_text,
    quantity_unit,
    results_kind,
    sweep_dims,
    value_text,
)
from ..jointtypes import JointKind
from ..outputs import RESULTS_KINDS
from ..variables import display_unit

#: Overlaid cases beyond this many take colours from a continuous colour map.
MAX_CYCLE_COLOURS = 10

#: Overlaid lines beyond this many get no per-line legend (it would hide the plot); the
#: title says so and points to --select.
MAX_LEGEND_ENTRIES = 12

#: A line panel whose data vary by less than ``NEGLIGIBLE_VARIATION`` of their mean magnitude
#: is drawn on a y-axis ``MIN_RELATIVE_SPAN`` of the mean wide (at least), centred on the
#: data, so that a negligible change looks negligible; the panel's title says so.
NEGLIGIBLE_VARIATION = 0.05
MIN_RELATIVE_SPAN = 0.1

#: Long y-axis labels of line plots are wrapped to lines of at most this many characters.
AXIS_LABEL_CHARACTERS = 40

#: Figure titles are wrapped to lines of at most this many characters per inch of width.
TITLE_CHARACTERS_PER_INCH = 10

#: Unit text of dimensionless and categorical quantities.
DIMENSIONLESS = "-"

#: Colour-bar labels are wrapped to lines of at most this many characters, so that the
#: layout engine can keep them inside a figure of the default size.
COLOURBAR_LABEL_CHARACTERS = 36


def quantity_values(coord: xr.DataArray) -> tuple[np.ndarray, str]:
    """A numeric coordinate's values in its quantity's unit, and its axis label."""
    factor, unit = quantity_unit(coord)
    return np.asarray(coord.values, dtype=float) / factor, axis_label(coord, units=unit)


def labelled_case(ds: xr.Dataset | xr.DataArray, label: dict) -> str:
    """``"B_coating=PTFE, B_clearance=0.25 mm"``: a case's label (``analysis.iter_cases``),
    each value in its quantity's unit (:func:`quantity_text`)."""
    return ", ".join(f"{k}={quantity_text(ds[k], v)}" if k in ds.coords else f"{k}={value_text(v)}"
                     for k, v in label.items())


def run_config(ds: xr.Dataset) -> dict:
    """The run's config (``config``), or a sweep's base (``sweep_config``); {} if unreadable
    (:func:`clearsweep.analysis.file_config`)."""
    return file_config(ds)


def guide_extent(ds: xr.Dataset) -> tuple[float, float, float, float] | None:
    """(x0, x span, half height + c_z, half width + c_y) [m] of joint P's wall maps, from
    the run's config (``params.guide_row``: the walls' bins along the guide and across each
    wall); None where the file's config cannot be read."""
    from ..config import ConfigError, load_config
    from ..core import layout as L
    from ..params import PRESETS, guide_row

    base = run_config(ds)
    if not base:
        return None
    try:
        cfg = load_config(base)
    except (ConfigError, TypeError, ValueError):
        return None
    row = np.zeros(L.N_JP)
    guide_row(row, cfg.joints.P, PRESETS[cfg.mechanism.preset])
    return (float(row[L.J_X0]), float(row[L.J_XSPAN]), 0.5 * row[L.J_HEIGHT] + row[L.J_CZ],
            0.5 * row[L.J_WIDTH] + row[L.J_CY])


def clearance_text(ds: xr.Dataset) -> str:
    """``"clearance at A, B"``: the joints with a clearance in every case of ``ds`` (a swept
    or selected clearance as the case ran, else its config's); ``"no clearance (ideal
    joints)"``; "" where the cases drawn differ in which joints have one (their legend
    or selection names them) or the file does not say."""
    clearances = joint_clearances(ds) if "joint" in ds.dims and "joint" in ds.coords else None
    if clearances is None:
        return ""
    cases = [d for d in clearances.dims if d != "joint"]
    has = (clearances > 0.0).transpose("joint", *cases).values.reshape(clearances.sizes["joint"], -1)
    if not (has.all(axis=1) | ~has.any(axis=1)).all():
        return ""
    joints = [value_text(j) for j, row in zip(clearances["joint"].values, has) if row.all()]
    return "clearance at " + ", ".join(joints) if joints else "no clearance (ideal joints)"


def swept_config_value(ds: xr.Dataset, key: str) -> tuple[bool, object]:
    """Whether a sweep coordinate sets the dotted config ``key`` in ``ds``, and its one value
    over the cases of ``ds`` (a case chosen with ``--select`` keeps it as a scalar
    coordinate); None where the cases drawn differ in it."""
    coord = next((c for c in ds.coords.values() if c.attrs.get("config_key") == key), None)
    if coord is None:
        return False, None
    values = {value_text(v) for v in np.ravel(coord.values)}
    return True, (values.pop() if len(values) == 1 else None)


_SINGLE_CASE_COLOUR = "tab:red"

class PlotError(ValueError):
    """The dataset cannot give the figure asked for (missing variables, too many cases)."""


def joint_name(joint, ds: xr.Dataset | None = None) -> str:
    """``"bearing O"``, ``"guide P"``, ``"joint A"``: a joint named as what it is (the type
    ``ds`` records, the slider-crank's pins "bearing A", "bearing B"; else the joint
    table's)."""
    from ..jointtypes import kind_of

    name = str(joint)
    kind = kind_of(name, None if ds is None else ds.attrs)
    return f"{'joint' if kind is None else kind.title} {name}"


def joint_kind(ds: xr.Dataset | None, joint) -> JointKind:
    """The host description of ``joint`` (a name, or a coordinate's value) in ``ds``
    (``jointtypes.kind_of``: the type ``ds`` records, else the joint table's); a name that
    is no joint's reads as a ball in a socket."""
    from ..jointtypes import describe

    return describe(value_text(joint), None if ds is None else ds.attrs)


def axis_label(obj: xr.DataArray, text: str | None = None, units: str | None = None) -> str:
    """``"text [units]"`` from a variable's attributes.

    Parameters
    ----------
    obj
        Variable or coordinate; its ``long_name`` (or name) and ``units``.
    text, units
        Override the attribute values.
    """
    name = text or obj.attrs.get("long_name") or str(obj.name)
    unit = obj.attrs.get("units", "") if units is None else units
    # a speed in revolutions per minute reads r/min (its units attribute is "min-1", and a
    # swept ``speed_rpm`` written without one is no dimensionless number)
    if unit == "min-1" or (unit in ("", "1") and str(obj.name).endswith("speed_rpm")):
        unit = "r/min"
    return f"{name} [{DIMENSIONLESS if unit in ('', '1') else unit}]"


def display_scale(values, units: str) -> tuple[float, str]:
    """(factor, unit text) to draw ``values`` given in ``units``: draw ``values / factor``.
    The rule reports use too (``variables.display_unit``), with µm for um.

    >>> display_scale([2.5e-4, 1e-4], "m")
    (1e-06, '\u00b5m')
    >>> display_scale([850.0], "N")
    (1.0, 'N')
    >>> display_scale([2.0], "m s-2")
    (1.0, 'm s-2')
    """
    found = display_unit(np.asarray(values, dtype=float).ravel(), units)
    if found is None:
        return 1.0, units
    factor, symbol = found
    return factor, symbol.replace("um", "\u00b5m")


def scaled(obj: xr.DataArray, values=None) -> tuple[float, str]:
    """:func:`display_scale` of a variable from its ``units`` attribute and its values (or
    ``values``, where another selection of it sets the scale)."""
    return display_scale(obj.values if values is None else values, str(obj.attrs.get("units", "")))


def plain_ticks(fig) -> None:
    """No offset text and no "x 1e-9" multiplier on any linear axis or colour bar of ``fig``:
    the values drawn are scaled to read directly (:func:`display_scale`)."""
    from matplotlib.ticker import ScalarFormatter

    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            formatter = axis.get_major_formatter()
            if type(formatter) is ScalarFormatter:
                formatter.set_useOffset(False)
                formatter.set_scientific(False)


def log_ticks(axis, low: float, high: float) -> None:
    """Labels of a log axis that never run into each other: the decades only, or where the
    view spans less than two decades, 1, 2 and 5 times them (and 3 times them within one
    decade); unlabelled minor ticks."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    first, last = int(np.floor(np.log10(low))), int(np.ceil(np.log10(high)))
    subs = (1.0,) if last - first > 2 else (1.0, 2.0, 5.0) if high / low > 10 else (1.0, 2.0, 3.0, 5.0)
    ticks = [m * 10.0 ** d for d in range(first, last + 1) for m in subs
             if low * (1 - 1e-9) <= m * 10.0 ** d <= high * (1 + 1e-9)]
    formatter = _power_text
    if len(ticks) < 2:      # a view narrower than 1-2-3-5 steps: plain values, never no label
        from matplotlib.ticker import MaxNLocator

        ticks = [t for t in MaxNLocator(4).tick_values(low, high)
                 if low * (1 - 1e-9) <= t <= high * (1 + 1e-9)]
        formatter = _plain_text
    axis.set_major_locator(FixedLocator(ticks))
    axis.set_major_formatter(FuncFormatter(formatter))
    axis.set_minor_formatter(NullFormatter())


def _plain_text(value: float, _position=None) -> str:
    """``"1.5e+05"``, ``"250"``: a tick label of a log axis narrower than its 1-2-3-5 steps."""
    return f"{value:.3g}"


def _power_text(value: float, _position=None) -> str:
    """``"$2\\times10^{5}$"``, ``"$10^{5}$"``: a log-axis tick label."""
    exponent = int(np.floor(np.log10(value) + 1e-9))
    mantissa = value / 10.0 ** exponent
    power = f"10^{{{exponent}}}"
    return f"${power}$" if round(mantissa) == 1 else f"${mantissa:.0f}\\times{power}$"


def percent_text(fraction: float) -> str:
    """``"1.9 %"``, ``"290 %"``: a fraction as a percentage of two significant digits, never
    in exponent notation."""
    value = 100.0 * fraction
    return f"{value:.0f} %" if value >= 10 else f"{value:.2g} %"


def wrapped_label(label: str, width: int = COLOURBAR_LABEL_CHARACTERS) -> str:
    """``label`` on lines of at most ``width`` characters; its ``[units]`` never split.

    >>> wrapped_label("peak absolute slider acceleration after start-up [m s-2]")
    'peak absolute slider acceleration\\nafter start-up [m s-2]'
    """
    match = re.fullmatch(r"(.*?)\s*(\[[^\]]*\])", label)
    name, units = (match.group(1), match.group(2)) if match else (label, "")
    lines = textwrap.wrap(name, width) or [""]
    if units:
        if len(lines[-1]) + 1 + len(units) <= width:
            lines[-1] = f"{lines[-1]} {units}".strip()
        else:
            lines.append(units)
    return "\n".join(lines)


@dataclass(frozen=True)
class FileFigures:
    """What one kind of results file (a key of ``outputs.RESULTS_KINDS``) gives the figures:
    the figure code asks :func:`file_figures` instead of testing the kind's name."""

    #: Why a file of this kind lacks a variable a figure needs (after "which this dataset
    #: lacks"), given the file.
    lacks: Callable[[xr.Dataset], str]
    #: Its runs keep Poincare sections whenever they last a revolution: without them,
    #: ``--kind poincare`` says the runs were too short rather than naming variables.
    sections: bool = False
    #: ``--kind wear-map`` draws its blocks' wear-map snapshots (a life run).
    wear_map_snapshots: bool = False


def _sweep_lacks(ds: xr.Dataset) -> str:
    if ds.attrs.get("sweep_store") == "full":
        return ""
    return " (a summary-only sweep holds no time series or wear maps: keep them with store: full)"


def _a_file_of(kind: str) -> Callable[[xr.Dataset], str]:
    return lambda ds: f" (a file of {RESULTS_KINDS[kind]})"


#: Every kind of results file, said once for the figures.
FILE_FIGURES = {
    **{kind: FileFigures(_a_file_of(kind)) for kind in RESULTS_KINDS},
    "run": FileFigures(lambda ds: "", sections=True),
    "sweep": FileFigures(_sweep_lacks, sections=True),
    "life": FileFigures(lambda ds: " (a life run keeps its blocks' summaries and wear maps)",
                        wear_map_snapshots=True),
}


def file_figures(ds: xr.Dataset) -> FileFigures:
    """What the kind of results file ``ds`` is (``analysis.results_kind``) gives the figures."""
    return FILE_FIGURES[results_kind(ds)]


def _require(ds: xr.Dataset, names: tuple[str, ...], what: str) -> None:
    """Raise ``PlotError`` unless ``ds`` holds ``names``; ``what`` asked for them (``--kind slider``)."""
    missing = [n for n in names if n not in ds]
    if missing:
        raise PlotError(f"{what} needs {', '.join(missing)}, which this dataset lacks"
                        + file_figures(ds).lacks(ds))


def values_offer(ds: xr.Dataset, dims) -> str:
    """The values of each of ``dims`` a --select may choose ("DIM: v1, v2; ..."), or the
    count of its cases where it has no coordinate: what a refusal that asks for --select
    offers."""
    return "; ".join(f"{d}: {', '.join(value_text(v) for v in ds[d].values)}"
                     if d in ds.coords else f"{d}: {ds.sizes[d]} cases" for d in dims)


def _one_case(ds: xr.Dataset, kind: str) -> xr.Dataset:
    dims = sweep_dims(ds)
    if not dims:
        return ds
    raise PlotError(f"--kind {kind} draws one case; choose it with --select DIM=VALUE "
                    f"({values_offer(ds, dims)})")


def _clearance_joints(ds: xr.Dataset, values: xr.DataArray, kind: str) -> list:
    """The joints of ``values`` that have a clearance in some case of ``ds``: those a figure
    of ``kind`` may draw or name (:func:`clearsweep.analysis.ideal_joints`; all of them
    where ``ds`` does not say).

    Raises
    ------
    PlotError
        Every joint is ideal: the figure would have nothing to draw.
    """
    ideal = ideal_joints(ds)
    named = [j for j in values["joint"].values if value_text(j) not in ideal]
    if not named:
        raise PlotError(f"--kind {kind} draws the joints with a clearance, and every joint of "
                        "these results is ideal (joints.*.clearance 0): there is nothing to draw")
    return named


def _cases(ds: xr.Dataset) -> list[tuple[str, xr.Dataset, object]]:
    """``(legend text, case, colour)`` of every case of ``ds`` that ran (skipped grid points
    have no data to draw). The keys of a zip group are left out of the text: its label
    names them."""
    zipped = {str(n) for n, c in ds.coords.items()
              if c.ndim == 1 and c.dims[0] != n and ds.coords.get(c.dims[0]) is not None
              and ds[c.dims[0]].attrs.get("config_keys")}
    cases = [({k: v for k, v in label.items() if k not in zipped}, case)
             for label, case in iter_cases(ds)
             if not ("status" in case and case["status"].ndim == 0
                     and str(case["status"].values) == "skipped")]
    if len(cases) == 1:
        colours = [_SINGLE_CASE_COLOUR]
    elif len(cases) <= MAX_CYCLE_COLOURS:
        colours = [f"C{i}" for i in range(len(cases))]
    else:
        colours = list(colormaps["viridis"](np.linspace(0.0, 0.95, len(cases))))
    return [(labelled_case(ds, label), case, colour) for (label, case), colour in zip(cases, colours)]


def _legend(ax, cases) -> None:
    """The overlaid cases' legend (the lines of ``ax``), below the panels: inside a panel of
    time series it covered lines wherever it went (tests/test_figure_layout.py,
    ``legends_over_data``)."""
    if 1 < len(cases) <= MAX_LEGEND_ENTRIES:
        handles, labels = ax.get_legend_handles_labels()
        ax.figure.legend(handles, labels, loc="outside lower center", fontsize="x-small",
                         ncol=min(len(labels), 2 if max(map(len, labels)) > 40 else 3))


def figure_legend(fig) -> None:
    """One legend below the panels: every panel's entries once, in the order they first
    appear (two columns where a label is long)."""
    entries: dict[str, object] = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    if entries:
        fig.legend(list(entries.values()), list(entries), loc="outside lower center",
                   ncol=min(len(entries), 2 if max(map(len, entries)) > 40 else 3),
                   fontsize="x-small")


def _legend_note(n: int) -> str:
    """Title line saying that ``n`` overlaid lines have no legend ("" when they have one)."""
    if n <= MAX_LEGEND_ENTRIES:
        return ""
    return (f"\n{n} cases overlaid, no legend above {MAX_LEGEND_ENTRIES}: choose cases with "
            "--select DIM=VALUE")


def _case_label(text: str, n: int, default: str) -> str:
    """A line's legend label; hidden (``_nolegend_``) when ``n`` cases are too many to list."""
    return "_nolegend_" if n > MAX_LEGEND_ENTRIES else (text or default)


def _abscissa(ds: xr.Dataset, case: xr.Dataset, x: str) -> tuple[np.ndarray, str]:
    """Crank angle [degree] or time [s] of a case, and its label."""
    if x == "time":
        return case["time"].values, axis_label(ds["time"])
    _require(ds, ("crank_angle",), "--x angle")
    return np.degrees(case["crank_angle"].values), axis_label(ds["crank_angle"], units="degree")


def _edges(centres: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Edges of equal bins with these centres; one bin spans [lo, hi]."""
    if len(centres) == 1:
        return np.array([lo, hi])
    step = centres[1] - centres[0]
    return np.append(centres - step / 2, centres[-1] + step / 2)


def keep_relative_span(ax, values, axis: str = "y", scale: float | None = None) -> str:
    """Widen ``ax``'s y-axis (``axis="x"``: its x-axis) to at least :data:`MIN_RELATIVE_SPAN`
    of the mean magnitude of ``values`` (the data drawn; or of ``scale``, a magnitude that
    the caller gives), centred on the current view, where they vary by less than
    :data:`NEGLIGIBLE_VARIATION` of it.

    Returns
    -------
    str
        The note for the panel ("varies by 0.15 % of its mean; axis spans 10 % of it"), or
        "" where the axis was wide enough already.
    """
    data = np.asarray(values, dtype=float).ravel()
    data = data[np.isfinite(data)]
    if data.size == 0:
        return ""
    scale = abs(float(data.mean())) if scale is None else scale
    low, high = ax.get_ylim() if axis == "y" else ax.get_xlim()
    if (not scale > 0 or float(np.ptp(data)) >= NEGLIGIBLE_VARIATION * scale
            or high - low >= MIN_RELATIVE_SPAN * scale):
        return ""
    centre, half = 0.5 * (low + high), 0.5 * MIN_RELATIVE_SPAN * scale
    (ax.set_ylim if axis == "y" else ax.set_xlim)(centre - half, centre + half)
    return (f"varies by {percent_text(float(np.ptp(data)) / scale)} of its mean; "
            f"axis spans {MIN_RELATIVE_SPAN:.0%} of it")


def _note_span(ax, values) -> None:
    """:func:`keep_relative_span`, its note as the panel's (small) title."""
    note = keep_relative_span(ax, values)
    if note:
        ax.set_title(note, fontsize="x-small")


def coordinate_text(coord: xr.DataArray, value) -> str:
    """``"B_clearance 0.25 mm"``: a sweep coordinate's name and value in its quantity's unit
    (:func:`quantity_text`)."""
    return f"{coord.name} {quantity_text(coord, value)}"


def point_text(obj: xr.Dataset | xr.DataArray, keys: dict) -> str:
    """``"B_coating PTFE, B_clearance 0.25 mm"`` of a point of :func:`iter_points`."""
    return ", ".join(coordinate_text(obj[d], v) if d in obj.coords else f"{d} {value_text(v)}"
                     for d, v in keys.items())


def _dim_name(obj: xr.Dataset | xr.DataArray, dim: str) -> str:
    """A sweep dimension's long name with its name: ``"radial clearance (B_clearance)"``."""
    long_name = obj[dim].attrs.get("long_name") if dim in obj.coords else None
    if not long_name or dim in long_name:      # "sweep zip group coating_joints": the name
        return dim
    return f"{long_name} ({dim})"


def selection_text(ds: xr.Dataset, selection: dict) -> str:
    """The ``--select`` slice as a title line: ``"selection: clearance_joints=AB (A_clearance
    0.25 mm, B_clearance 0.25 mm), ..."``; numbers in their quantity's unit
    (:func:`quantity_text`), a zip group's label with the values the case ran with."""
    if not selection:
        return ""
    parts = []
    for name, value in selection.items():
        text = f"{name}={quantity_text(ds[name], value) if name in ds.coords else value_text(value)}"
        keys = str(ds[name].attrs.get("config_keys", "")).split() if name in ds.coords else []
        # a zip group's label: the values the case ran with ("AB (A_coating PTFE, ...)")
        zipped = [coordinate_text(c, c.values) for n, c in ds.coords.items()
                  if n != name and c.ndim == 0 and c.attrs.get("config_key") in keys]
        parts.append(text + (f" ({', '.join(zipped)})" if zipped else ""))
    return "selection: " + ", ".join(parts)


def section_axes(offset: np.ndarray, names) -> tuple[str, str]:
    """The two axes (of ``names``, the last dimension of ``offset``: samples x axes, any
    cases before) along which the offsets spread most, in axis order; the first two where
    none spreads (a point, or no data): ``poincare``'s plane of the sections, ``orbit``'s
    plane of a planar mechanism's joint."""
    flat = offset.reshape(-1, offset.shape[-1])
    flat = flat[np.isfinite(flat).all(axis=1)]
    spread = flat.std(axis=0) if len(flat) else np.zeros(offset.shape[-1])
    keep = sorted(np.argsort(-spread, kind="stable")[:2])
    return str(names[keep[0]]), str(names[keep[1]])
