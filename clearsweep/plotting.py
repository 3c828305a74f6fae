"""Figures from results datasets (the paper's Figures 9-16), headless.

Figures are built on ``matplotlib.figure.Figure`` directly (no pyplot, no
global state, no display needed) and saved in the format the output
file's suffix names. Every axis and colour-bar label carries the units of the
variable drawn, from its ``units`` attribute; ``[-]`` marks a dimensionless
or categorical quantity.

Kinds (``KINDS``):

``slider``
    slider position, velocity and acceleration against the crank angle or
    time, sweep cases overlaid (Figures 9, 12, 13).
``forces``
    reaction at O and the force on the ball of each joint: magnitude and
    x, y, z components, cases overlaid (Figures 10, 14, 15).
``wear-map``
    per joint, the socket wear map (polar x azimuth) and the same map on a
    sphere (Figures 11, 16); one case.
``wear-polar``
    per joint and axis, the projected wear depth as a worn profile on the
    unit circle, exaggerated (Figures 11, 16); cases overlaid.
``orbit``
    ball-centre offset in the socket frame on the xy, xz and yz planes,
    inside the clearance circle; cases overlaid.
``sweep``
    one summary metric (``analysis.case_summary``) over one sweep dimension
    (lines) or two (heat maps); for an ensemble (a ``member`` dimension), the
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
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import xarray as xr
import yaml
from matplotlib import colormaps
from matplotlib.artist import Artist
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from .analysis import (
    CASE_DIMS,
    MEMBER_DIM,
    SelectionError,
    choice_message,
    configured_clearances,
    iter_cases,
    iter_points,
    label_text,
    metric_table,
    parse_selection,
    sweep_dims,
    value_text,
)
from .choices import (  # noqa: F401
    DEFAULT_SWEEP_METRIC,
    DPI_RANGE,
    FIGURE_DPI,
    KINDS,
    OUTPUT_SUFFIXES,
    X_AXES,
)
from .dataset import replaced_on_success
from .outputs import figure_metadata

#: On ``wear-polar`` the largest depth of a joint is drawn as this fraction of the unit radius.
WEAR_POLAR_EXAGGERATION = 0.3

#: Overlaid cases beyond this many take colours from a continuous colour map.
MAX_CYCLE_COLOURS = 10

#: Overlaid lines beyond this many get no per-line legend (it would hide the plot); the
#: title says so and points to --select.
MAX_LEGEND_ENTRIES = 12

#: Heat-map cells are annotated with their values up to this many cells.
MAX_ANNOTATED_CELLS = 64

#: Size of one heat-map panel of ``--kind sweep`` (width, height) [inch].
HEATMAP_PANEL_INCHES = (4.2, 3.4)

#: Narrowest figure of ``--kind sweep``, so that its title fits [inch].
MIN_FIGURE_WIDTH_INCHES = 7.0

#: Robust colour limits of a heat map (one outlier would flatten the others): with at least
#: ``ROBUST_MIN_CELLS`` values, a value farther than ``ROBUST_FENCE`` times the range between
#: these percentiles beyond them is an outlier, and the scale stops at the percentile on its side.
ROBUST_PERCENTILES = (2.0, 98.0)
ROBUST_MIN_CELLS = 8
ROBUST_FENCE = 1.0

#: Heat-map annotations turn dark on cells brighter than this (normalised colour value).
ANNOTATION_DARK_TEXT_ABOVE = 0.6

#: A line panel whose data vary by less than ``NEGLIGIBLE_VARIATION`` of their mean magnitude
#: is drawn on a y-axis ``MIN_RELATIVE_SPAN`` of the mean wide (at least), centred on the
#: data, so that a negligible change looks negligible; the panel's title says so.
NEGLIGIBLE_VARIATION = 0.05
MIN_RELATIVE_SPAN = 0.1

#: The life figure draws at most this many wear-map snapshots (the first, the last and
#: evenly spread ones between); it says which stored snapshots it leaves out.
LIFE_SNAPSHOT_PANELS = 6

#: Long y-axis labels of line plots are wrapped to lines of at most this many characters.
AXIS_LABEL_CHARACTERS = 40

#: Figure titles are wrapped to lines of at most this many characters per inch of width.
TITLE_CHARACTERS_PER_INCH = 10

#: Unit text of dimensionless and categorical quantities.
DIMENSIONLESS = "-"

#: Colour-bar labels are wrapped to lines of at most this many characters, so that the
#: layout engine can keep them inside a figure of the default size.
COLOURBAR_LABEL_CHARACTERS = 36

#: Line styles of the clearance circles of ``orbit``, one per clearance drawn.
_CIRCLE_STYLES = ("--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 2)))

_AXIS_COLOURS = {"magnitude": "black", "x": "tab:blue", "y": "tab:orange", "z": "tab:green"}
_SINGLE_CASE_COLOUR = "tab:red"


class PlotError(ValueError):
    """The dataset cannot give the figure asked for (missing variables, too many cases)."""


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
    return f"{name} [{DIMENSIONLESS if unit in ('', '1') else unit}]"


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


def _require(ds: xr.Dataset, names: tuple[str, ...], what: str) -> None:
    """Raise ``PlotError`` unless ``ds`` holds ``names``; ``what`` asked for them (``--kind slider``)."""
    missing = [n for n in names if n not in ds]
    if missing:
        raise PlotError(f"{what} needs {', '.join(missing)}, which this dataset lacks "
                        "(a summary-only sweep holds no time series or wear maps)")


def _one_case(ds: xr.Dataset, kind: str) -> xr.Dataset:
    dims = sweep_dims(ds)
    if not dims:
        return ds
    offer = "; ".join(f"{d}: {', '.join(value_text(v) for v in ds[d].values)}"
                      if d in ds.coords else f"{d}: {ds.sizes[d]} cases" for d in dims)
    raise PlotError(f"--kind {kind} draws one case; choose it with --select DIM=VALUE ({offer})")


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
    return [(label_text(label), case, colour) for (label, case), colour in zip(cases, colours)]


def _legend(ax, cases) -> None:
    if 1 < len(cases) <= MAX_LEGEND_ENTRIES:
        ax.legend(fontsize="x-small", ncol=1 + len(cases) // 6)


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


def keep_relative_span(ax, values) -> str:
    """Widen ``ax``'s y-axis to at least :data:`MIN_RELATIVE_SPAN` of the mean magnitude of
    ``values`` (the data drawn), centred on the current view, where they vary by less than
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
    scale = abs(float(data.mean()))
    low, high = ax.get_ylim()
    if (not scale > 0 or float(np.ptp(data)) >= NEGLIGIBLE_VARIATION * scale
            or high - low >= MIN_RELATIVE_SPAN * scale):
        return ""
    centre, half = 0.5 * (low + high), 0.5 * MIN_RELATIVE_SPAN * scale
    ax.set_ylim(centre - half, centre + half)
    return (f"varies by {float(np.ptp(data)) / scale:.2%} of its mean; "
            f"axis spans {MIN_RELATIVE_SPAN:.0%} of it")


def _note_span(ax, values) -> None:
    """:func:`keep_relative_span`, its note as the panel's (small) title."""
    note = keep_relative_span(ax, values)
    if note:
        ax.set_title(note, fontsize="x-small")


def coordinate_text(coord: xr.DataArray, value) -> str:
    """``"B_clearance 0.00025 m"``: a sweep coordinate's name, value and units (if any)."""
    unit = coord.attrs.get("units", "")
    return f"{coord.name} {value_text(value)}" + (f" {unit}" if unit not in ("", "1") else "")


def point_text(obj: xr.Dataset | xr.DataArray, keys: dict) -> str:
    """``"B_coating PTFE, B_clearance 0.00025 m"`` of a point of :func:`iter_points`."""
    return ", ".join(coordinate_text(obj[d], v) if d in obj.coords else f"{d} {value_text(v)}"
                     for d, v in keys.items())


def _dim_name(obj: xr.Dataset | xr.DataArray, dim: str) -> str:
    """A sweep dimension's long name with its name: ``"radial clearance (B_clearance)"``."""
    long_name = obj[dim].attrs.get("long_name") if dim in obj.coords else None
    if not long_name or dim in long_name:      # "sweep zip group coating_joints": the name
        return dim
    return f"{long_name} ({dim})"


def selection_text(ds: xr.Dataset, selection: dict) -> str:
    """The ``--select`` slice as a title line: ``"selection: clearance_joints=AB, ..."``;
    numbers with the coordinate's units."""
    if not selection:
        return ""
    parts = []
    for name, value in selection.items():
        unit = ds[name].attrs.get("units", "") if name in ds.coords else ""
        parts.append(f"{name}={value_text(value)}" + (f" {unit}" if unit not in ("", "1") else ""))
    return "selection: " + ", ".join(parts)


# --------------------------------------------------------------------------- kinds

def _draw_slider(fig: Figure, ds: xr.Dataset, x: str) -> None:
    names = ("slider_position", "slider_velocity", "slider_acceleration")
    _require(ds, names, "--kind slider")
    cases = _cases(ds)
    axes = fig.subplots(len(names), 1, sharex=True)
    for ax, name in zip(axes, names):
        for text, case, colour in cases:
            xs, xlabel = _abscissa(ds, case, x)
            ax.plot(xs, case[name].values, color=colour, lw=0.8, label=text)
        ax.set_ylabel(axis_label(ds[name]))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(xlabel)
    _legend(axes[0], cases)
    fig.suptitle("Slider dynamics" + _legend_note(len(cases)))


def _draw_forces(fig: Figure, ds: xr.Dataset, x: str) -> None:
    _require(ds, ("reaction_O", "joint_force"), "--kind forces")
    # (panel title, variable, joint or None)
    rows = [("reaction at O (ground on crank)", "reaction_O", None)]
    rows += [(f"joint {value_text(j)} (on the ball)", "joint_force", j) for j in ds["joint"].values]
    components = ("magnitude", *(str(a) for a in ds["axis"].values))
    cases = _cases(ds)
    axes = fig.subplots(len(rows), len(components), sharex=True, squeeze=False)
    for r, (title, name, joint) in enumerate(rows):
        for text, case, colour in cases:
            xs, xlabel = _abscissa(ds, case, x)
            vector = case[name] if joint is None else case[name].sel(joint=joint)
            series = [np.sqrt((vector ** 2).sum("axis"))] + [vector.sel(axis=a) for a in components[1:]]
            for ax, values, component in zip(axes[r], series, components):
                ax.plot(xs, values.values, lw=0.7, label=text,
                        color=colour if len(cases) > 1 else _AXIS_COLOURS.get(component, colour))
        for ax, component in zip(axes[r], components):
            symbol = "|F|" if component == "magnitude" else f"F_{component}"
            ax.set_title(f"{title}: {symbol}", fontsize="small")
            ax.set_ylabel(axis_label(ds[name], symbol))
            ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)
    _legend(axes[0, 0], cases)
    fig.suptitle("Joint forces (global frame)" + _legend_note(len(cases)))


def _life_wear_map(ds: xr.Dataset, select) -> xr.Dataset:
    """The wear map of a life run (``clearsweep life``) as a one-case dataset: the final
    map, or with ``--select snapshot=K`` its K-th snapshot (0-based, in revolutions order).

    Raises
    ------
    SelectionError
        Any other selection; the message lists the snapshots and their revolutions.
    """
    cycles = ds["snapshot_cycle"].values if "snapshot_cycle" in ds else np.full(ds.sizes["snapshot"], np.nan)
    offer = ", ".join(f"{k} ({float(c):.4g} revolutions)" for k, c in enumerate(cycles))
    items = list(select.items()) if isinstance(select, Mapping) else \
        [tuple(str(i).partition("=")[::2]) for i in (select or ())]
    if not items:
        return ds[["wear_map"]]
    name, text = items[0]
    k = int(text) if str(text).strip().lstrip("-").isdigit() else -1
    if len(items) > 1 or name != "snapshot" or not 0 <= k < ds.sizes["snapshot"]:
        raise SelectionError(
            f"a life run's --kind wear-map draws its final map (no --select) or one snapshot: "
            f"--select snapshot=K, K one of {offer}", name=str(name), value=str(text),
            choices=[str(k) for k in range(ds.sizes["snapshot"])])
    snapshot = ds["wear_map_snapshot"].isel(snapshot=k, drop=True)
    return xr.Dataset({"wear_map": snapshot.assign_attrs(ds["wear_map"].attrs)},
                      attrs={"snapshot": f"{k} at {float(cycles[k]):.4g} revolutions"})


def _draw_wear_map(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("wear_map",), "--kind wear-map")
    ds = _one_case(ds, "wear-map")
    wear = ds["wear_map"]
    polar = np.radians(_edges(wear["polar"].values, 0.0, 180.0))
    azimuth = np.radians(_edges(wear["azimuth"].values, -180.0, 180.0))
    grid_p, grid_a = np.meshgrid(polar, azimuth, indexing="ij")
    sphere = (np.sin(grid_p) * np.cos(grid_a), np.sin(grid_p) * np.sin(grid_a), np.cos(grid_p))
    cmap = colormaps["viridis"]
    joints = wear["joint"].values
    for j, joint in enumerate(joints):
        depth = wear.sel(joint=joint)
        peak = float(depth.max())
        norm = Normalize(0.0, peak if np.isfinite(peak) and peak > 0 else 1.0)
        ax = fig.add_subplot(len(joints), 2, 2 * j + 1)
        mesh = ax.pcolormesh(np.degrees(azimuth), np.degrees(polar), depth.values, cmap=cmap,
                             norm=norm, shading="flat")
        ax.set_ylim(180.0, 0.0)
        ax.set_xlabel(axis_label(ds["azimuth"], "azimuth"))
        ax.set_ylabel(axis_label(ds["polar"], "polar angle from +z"))
        ax.set_title(f"joint {value_text(joint)}: socket wear map (max {peak:.3g} m)", fontsize="small")
        fig.colorbar(mesh, ax=ax).set_label(axis_label(wear, "wear depth"))
        ax3 = fig.add_subplot(len(joints), 2, 2 * j + 2, projection="3d")
        ax3.plot_surface(*sphere, facecolors=cmap(norm(depth.values)), rstride=1, cstride=1,
                         shade=False, linewidth=0, antialiased=False)
        ax3.set_box_aspect((1, 1, 1))
        if peak > 0:
            # Look at the most worn bin.
            ip, ia = np.unravel_index(int(np.nanargmax(depth.values)), depth.shape)
            ax3.view_init(elev=90.0 - float(depth["polar"][ip]), azim=float(depth["azimuth"][ia]))
        # the axes name the socket frame's directions; tick labels of the unit sphere would
        # only crowd the panel title
        for set_label, set_ticks, name in ((ax3.set_xlabel, ax3.set_xticks, "x"),
                                           (ax3.set_ylabel, ax3.set_yticks, "y"),
                                           (ax3.set_zlabel, ax3.set_zticks, "z")):
            set_ticks([-1.0, 0.0, 1.0], ["", "", ""])
            set_label(f"{name} [{DIMENSIONLESS}]", labelpad=-12)
        ax3.set_title(f"joint {value_text(joint)}: unit sphere, socket frame", fontsize="small",
                      pad=12)
        fig.colorbar(ScalarMappable(norm, cmap), ax=ax3, shrink=0.7).set_label(
            axis_label(wear, "wear depth"))
    snapshot = ds.attrs.get("snapshot")     # a life run's snapshot (_life_wear_map)
    fig.suptitle("Socket wear depth" + (f", snapshot {snapshot}" if snapshot else ""))


def _draw_wear_polar(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("wear_projection",), "--kind wear-polar")
    projection = ds["wear_projection"]
    theta = np.radians(projection["angle"].values)
    closed = np.append(theta, theta[0])
    cases = _cases(ds)
    joints, axes_names = projection["joint"].values, projection["axis"].values
    scales = []
    for j, joint in enumerate(joints):
        peak = float(projection.sel(joint=joint).max())
        scale = WEAR_POLAR_EXAGGERATION / peak if np.isfinite(peak) and peak > 0 else 0.0
        # a no-break space keeps the value and its unit on one line of the wrapped title
        scales.append(f"joint {value_text(joint)}: {peak:.3g}\u00a0m" if scale else
                      f"joint {value_text(joint)}: no wear")
        for k, axis in enumerate(axes_names):
            ax = fig.add_subplot(len(joints), len(axes_names), j * len(axes_names) + k + 1,
                                 projection="polar")
            ax.plot(closed, np.ones_like(closed), ls="--", lw=0.8, color="0.5", label="unworn")
            for text, case, colour in cases:
                depth = np.nan_to_num(case["wear_projection"].sel(joint=joint, axis=axis).values)
                radius = 1.0 + scale * depth
                ax.plot(closed, np.append(radius, radius[0]), lw=1.0, color=colour,
                        label=_case_label(text, len(cases), "worn profile"))
            # a PolarAxes (projection="polar"); matplotlib's stubs type add_subplot as Axes
            ax.set_thetalim(-np.pi, np.pi)  # type: ignore[attr-defined]
            ax.set_rlim(  # type: ignore[attr-defined]
                0.0, 1.0 + 1.15 * WEAR_POLAR_EXAGGERATION)
            ax.set_yticks([])
            ax.set_title(f"joint {value_text(joint)}, about {axis}", fontsize="small")
            ax.set_xlabel(axis_label(ds["angle"], f"angle about {axis}"), fontsize="small")
    handles, labels = fig.axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 3),
               fontsize="small")
    fig.suptitle("Projected wear profile, radius 1 + depth x scale; largest depth drawn as "
                 f"{WEAR_POLAR_EXAGGERATION:g} of the radius ({'; '.join(scales)})"
                 + _legend_note(len(cases)), fontsize="medium")


def _clearance(case: xr.Dataset, joint: str, configured: dict[str, float]) -> tuple[float, str] | None:
    """Radial clearance of ``joint`` in ``case`` [m] and where it came from; None for an ideal joint.

    A swept clearance (sweep coordinate ``{joint}_clearance``, or
    ``joints_{joint}_clearance`` where the short name was taken) wins over the
    ``configured`` one; without either, the largest eccentricity stands in.
    """
    for name in (f"{joint}_clearance", f"joints_{joint}_clearance"):
        if name in case.coords and case[name].ndim == 0:
            swept = float(case[name])
            return (swept, "swept") if swept > 0 else None
    if joint in configured:
        return (configured[joint], "config") if configured[joint] > 0 else None
    if "eccentricity" in case:
        largest = float(case["eccentricity"].sel(joint=joint).max())
        if np.isfinite(largest) and largest > 0:
            return largest, "max eccentricity"
    return None


def _draw_orbit(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("ball_offset",), "--kind orbit")
    offset = ds["ball_offset"]
    planes = (("x", "y"), ("x", "z"), ("y", "z"))
    cases = _cases(ds)
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    joints = offset["joint"].values
    configured = configured_clearances(ds)
    per_joint: list[dict[float, str]] = []   # per joint: clearance [m] -> where it was read
    for joint in joints:
        found_here: dict[float, str] = {}
        for _, case, _ in cases:
            found = _clearance(case, str(joint), configured)
            if found is not None:
                found_here.setdefault(found[0], found[1])
        per_joint.append(found_here)
    # one style per clearance in the whole figure, so that the legend tells the circles apart
    radii = sorted({r for found_here in per_joint for r in found_here})
    styles = {r: (_CIRCLE_STYLES[k % len(_CIRCLE_STYLES)],
                  str(0.15 + 0.5 * k / max(len(radii) - 1, 1))) for k, r in enumerate(radii)}
    for j, (joint, clearances) in enumerate(zip(joints, per_joint)):
        for p, (a, b) in enumerate(planes):
            ax = fig.add_subplot(len(joints), len(planes), j * len(planes) + p + 1)
            for text, case, colour in cases:
                d = case["ball_offset"].sel(joint=joint)
                ax.plot(d.sel(axis=a).values, d.sel(axis=b).values, lw=0.6, color=colour,
                        label=_case_label(text, len(cases), "ball centre"))
            for radius, source in sorted(clearances.items()):
                ax.plot(radius * np.cos(circle), radius * np.sin(circle), lw=0.9,
                        ls=styles[radius][0], color=styles[radius][1],
                        label=f"joint {value_text(joint)} clearance {radius:.3g} m ({source})")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel(axis_label(offset, f"d_{a}"))
            ax.set_ylabel(axis_label(offset, f"d_{b}"))
            ax.ticklabel_format(style="sci", scilimits=(-3, 3))
            ideal = "" if clearances else " (ideal joint)"
            ax.set_title(f"joint {value_text(joint)}{ideal}: {a}{b} plane", fontsize="small")
            ax.grid(alpha=0.3)
    # one legend below the panels: the cases, then each joint's clearance circles once
    entries: dict[str, Artist] = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    if entries:
        fig.legend(list(entries.values()), list(entries), loc="outside lower center",
                   ncol=min(len(entries), 2 if max(map(len, entries)) > 40 else 3),
                   fontsize="x-small")
    fig.suptitle("Ball-centre orbit in the socket frame" + _legend_note(len(cases)))


def _category_positions(coord: xr.DataArray) -> tuple[np.ndarray, list[str] | None]:
    """Numeric coordinates as they are; others at 0, 1, ... with their text as tick labels."""
    if coord.dtype.kind in "fiu":
        return coord.values, None
    return np.arange(coord.size), [value_text(v) for v in coord.values]


def _draw_ensemble_sweep(fig: Figure, ds: xr.Dataset, metric: str) -> None:
    """Ensemble mean of ``metric`` with its confidence interval as error bars, over the
    first design dimension; a line per value of the second (and per joint / axis)."""
    mean = ds[metric + "_mean"]
    dims = tuple(d for d in sweep_dims(mean))
    if not dims or len(dims) > 2:
        raise PlotError(f"--kind sweep draws an ensemble mean over one or two design dimensions; "
                        f"this dataset has {len(dims)} ({', '.join(dims) or 'none'}): fix the "
                        "others with --select DIM=VALUE")
    low, high = ds[metric + "_ci_low"], ds[metric + "_ci_high"]
    ax = fig.add_subplot()
    xs, ticks = _category_positions(mean[dims[0]])
    series = tuple(str(d) for d in mean.dims if d != dims[0])
    lines: list[tuple[dict, xr.DataArray]] = []
    empty: list[tuple[dict, xr.DataArray]] = []
    for keys, line in iter_points(mean, series):
        # an ideal joint's wear (all 0, no spread) or a metric it lacks (NaN): nothing to show
        values = np.nan_to_num(line.values.astype(float))
        (empty if not values.any() else lines).append((keys, line))
    step = (np.ptp(xs) if len(xs) > 1 else 1.0) * 0.01
    for k, (keys, line) in enumerate(lines):
        y = line.transpose(dims[0]).values.astype(float)
        lo = low.sel(keys).transpose(dims[0]).values.astype(float) if keys else low.values
        hi = high.sel(keys).transpose(dims[0]).values.astype(float) if keys else high.values
        text = point_text(mean, keys)
        # nudge the lines apart so that their error bars do not hide each other
        ax.errorbar(xs + (k - 0.5 * (len(lines) - 1)) * step, y, yerr=[y - lo, hi - y], marker="o",
                    capsize=3, linestyle="none" if ticks is not None else "-",
                    label=_case_label(text, len(lines), metric))
    if ticks is not None:
        ax.set_xticks(xs, ticks)
    ax.set_xlabel(axis_label(mean[dims[0]]))
    ax.set_ylabel(wrapped_label(axis_label(mean), AXIS_LABEL_CHARACTERS))
    ax.grid(alpha=0.3)
    _note_span(ax, [low.values, high.values, mean.values])
    if series and len(lines) <= MAX_LEGEND_ENTRIES:
        ax.legend(fontsize="x-small")
    n = ds.sizes[MEMBER_DIM]
    left_out = f"\n{_left_out_text(mean, [k for k, _ in empty], [k for k, _ in lines])}" if empty else ""
    fig.suptitle(f"{mean.attrs.get('long_name', metric)} over {_dim_name(mean, dims[0])}, "
                 f"{n} members per design,\nbars: 95% confidence interval of the mean (Student t)"
                 f"{left_out}")


def _left_out_text(obj: xr.DataArray, empty: list[dict], drawn: list[dict]) -> str:
    """What the lines left out have in common ("joint A"), or their count."""
    common = {d: v for d, v in empty[0].items()
              if all(k[d] == v for k in empty) and not any(k[d] == v for k in drawn)}
    what = point_text(obj, common) if common else f"{len(empty)} line(s)"
    return f"not drawn: {what}, all 0 or missing"


def _draw_sweep(fig: Figure, ds: xr.Dataset, metric: str | None) -> None:
    metric = metric or DEFAULT_SWEEP_METRIC
    if MEMBER_DIM in ds.dims and metric + "_mean" in ds:
        _draw_ensemble_sweep(fig, ds, metric)
        return
    values = metric_table(ds, metric)
    if values.dtype.kind not in "fiub":
        raise PlotError(f"metric {metric!r} is not numeric; --kind sweep plots numbers")
    dims = sweep_dims(values)
    inner = tuple(d for d in values.dims if d in CASE_DIMS)
    if not dims or len(dims) > 2:
        raise PlotError(f"--kind sweep draws a metric over one or two sweep dimensions; this "
                        f"dataset has {len(dims)} ({', '.join(dims) or 'none'}): fix the others "
                        "with --select DIM=VALUE")
    panels = [(point_text(values, keys), panel) for keys, panel in iter_points(values, inner)]
    label = axis_label(values)
    title = values.attrs.get("long_name", metric)
    if len(dims) == 1:
        ax = fig.add_subplot()
        xs, ticks = _category_positions(values[dims[0]])
        for text, panel in panels:
            # categories are not ordered: points, not lines between them
            ax.plot(xs, panel.transpose(dims[0]).values, marker="o",
                    linestyle="none" if ticks is not None else "-",
                    label=_case_label(text, len(panels), metric))
        if ticks is not None:
            ax.set_xticks(xs, ticks)
        ax.set_xlabel(axis_label(values[dims[0]]))
        ax.set_ylabel(wrapped_label(label, AXIS_LABEL_CHARACTERS))
        ax.grid(alpha=0.3)
        _note_span(ax, values.values)
        if inner and len(panels) <= MAX_LEGEND_ENTRIES:
            ax.legend(fontsize="x-small")
        fig.suptitle(f"{title} over {_dim_name(values, dims[0])}"
                     + (_legend_note(len(panels)) if inner else ""))
        return
    failed = _failed_cells(ds, values, dims)
    ncols = min(3, len(panels))
    nrows = -(-len(panels) // ncols)
    fig.set_size_inches(max(HEATMAP_PANEL_INCHES[0] * ncols, MIN_FIGURE_WIDTH_INCHES),
                        HEATMAP_PANEL_INCHES[1] * nrows + 0.6)
    for i, (text, panel) in enumerate(panels):
        ax = fig.add_subplot(nrows, ncols, i + 1)
        grid = panel.transpose(*dims).values.astype(float)
        limits = robust_limits(grid)
        vmin, vmax = limits if limits else (None, None)
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=vmin,
                          vmax=vmax)
        for axis_dim, set_ticks in zip(dims, (ax.set_yticks, ax.set_xticks)):
            coord = values[axis_dim]
            set_ticks(np.arange(coord.size), [value_text(v) for v in coord.values])
        ax.tick_params(axis="x", labelrotation=30)
        ax.set_ylabel(axis_label(values[dims[0]]))
        ax.set_xlabel(axis_label(values[dims[1]]))
        if grid.size <= MAX_ANNOTATED_CELLS:
            for (r, c), v in np.ndenumerate(grid):
                if failed is not None and failed[r, c]:
                    continue
                bright = float(image.norm(v)) > ANNOTATION_DARK_TEXT_ABOVE  # type: ignore[arg-type]  # a scalar in, a scalar out
                ax.text(c, r, format(v, ".3g"), ha="center", va="center", fontsize="x-small",
                        color="black" if bright else "white")
        if failed is not None:
            for r, c in zip(*np.nonzero(failed)):
                ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, hatch="xx",
                                       edgecolor="0.4", lw=0.0))
                ax.text(c, r, "failed", ha="center", va="center", fontsize="x-small", color="0.2")
        if text:
            ax.set_title(text, fontsize="small")
        if limits is None:
            fig.colorbar(image, ax=ax).set_label(wrapped_label(label))
            continue
        below, above = grid < limits[0], grid > limits[1]
        for r, c in zip(*np.nonzero(below | above)):
            ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, edgecolor="red",
                                   lw=1.5))
        extend = {(True, True): "both", (True, False): "min", (False, True): "max"}.get(
            (bool(below.any()), bool(above.any())), "neither")
        stops = " and ".join(f"{q:g}th" for q, side in zip(ROBUST_PERCENTILES, (below, above))
                             if side.any())
        fig.colorbar(image, ax=ax, extend=extend).set_label(
            f"{wrapped_label(label)}\nscale stops at the {stops} percentile;\n"
            f"red outline: {int((below | above).sum())} outlying cell(s)")
    note = ""
    if failed is not None and failed.any():
        note = (f"\nhatched: {int(failed.sum())} case(s) that failed, no value (see the status "
                "and message variables)")
    fig.suptitle(f"{title}\nover {_dim_name(values, dims[0])} and {_dim_name(values, dims[1])}"
                 f"{note}")


def robust_limits(grid: np.ndarray) -> tuple[float, float] | None:
    """Colour limits of a heat map that an outlier cannot flatten, or None where the full
    range serves (few cells, no outlier); see :data:`ROBUST_PERCENTILES`.

    >>> robust_limits(np.array([*range(47), 900.0]))
    (0.0, 46.0)
    """
    values = grid[np.isfinite(grid)]
    if values.size < ROBUST_MIN_CELLS:
        return None
    # the values nearest inside the percentiles, not interpolated towards an outlier
    p_lo = float(np.percentile(values, ROBUST_PERCENTILES[0], method="higher"))
    p_hi = float(np.percentile(values, ROBUST_PERCENTILES[1], method="lower"))
    fence = ROBUST_FENCE * (p_hi - p_lo)
    if not fence > 0:
        return None
    lo = p_lo if values.min() < p_lo - fence else float(values.min())
    hi = p_hi if values.max() > p_hi + fence else float(values.max())
    return (lo, hi) if (lo, hi) != (values.min(), values.max()) else None


def _failed_cells(ds: xr.Dataset, values: xr.DataArray, dims: tuple) -> np.ndarray | None:
    """Cells of a heat map over ``dims`` whose case failed (status neither ok nor skipped).

    ``None`` when ``ds`` has no per-case status over exactly these dimensions.
    """
    if "status" not in ds or set(ds["status"].dims) != set(dims):
        return None
    status = ds["status"]
    try:
        status = status.sel({d: values[d].values for d in dims if d in status.indexes})
    except (KeyError, ValueError):
        pass
    status = status.transpose(*dims)
    if status.shape != tuple(values.sizes[d] for d in dims):
        return None
    return ~np.isin(status.values.astype(str), ["ok", "skipped"])


def _draw_life(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("cycle", "wear_depth_max", "wear_map_snapshot", "stop_reason"), "--kind life")
    cycles = ds["cycle"].values
    xlabel = axis_label(ds["cycle"], "crank revolutions")
    limits = {"wear_depth_max": "life.max_clearance_growth",
              "normal_force_peak_settled": "life.max_normal_force",
              "slider_acceleration_rms_settled": "life.max_rms_acceleration"}
    try:
        config = yaml.safe_load(ds.attrs.get("config") or "") or {}
    except yaml.YAMLError:
        config = {}
    if not isinstance(config, dict):     # a config attribute edited into a list or a scalar
        config = {}
    panels = ("wear_depth_max", "clearance_effective", "coating_remaining", "normal_force_peak_settled",
              "slider_acceleration_rms_settled", "impacts_per_revolution")
    grid = fig.add_gridspec(3, 4)
    for k, name in enumerate(panels):
        ax = fig.add_subplot(grid[k // 2, k % 2])
        var = ds[name]
        if "joint" in var.dims:
            for joint in var["joint"].values:
                values = var.sel(joint=joint).values
                if np.isfinite(values).any():
                    ax.plot(cycles, values, marker=".", label=f"joint {value_text(joint)}")
        else:
            ax.plot(cycles, var.values, marker=".")
        limit = _life_limit(config, limits.get(name))
        if limit is not None:
            ax.axhline(limit, color="r", linestyle="--", label=limits[name])
        _note_span(ax, var.values)
        ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(axis_label(var, var.attrs.get("long_name", name)))
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="x-small")
    snaps = ds["wear_map_snapshot"]
    joint = "B" if float(snaps.sel(joint="B").max()) >= float(snaps.sel(joint="A").max()) else "A"
    picks = np.unique(np.linspace(0, snaps.sizes["snapshot"] - 1, LIFE_SNAPSHOT_PANELS)
                      .round().astype(int))
    maps = snaps.sel(joint=joint)
    peak = float(maps.max())
    norm = Normalize(0.0, peak if np.isfinite(peak) and peak > 0 else 1.0)
    polar = _edges(ds["polar"].values, 0.0, 180.0)
    azimuth = _edges(ds["azimuth"].values, -180.0, 180.0)
    mesh = None
    for k, s in enumerate(picks):
        ax = fig.add_subplot(grid[k // 2, 2 + k % 2])
        mesh = ax.pcolormesh(azimuth, polar, maps.isel(snapshot=s).values, cmap="viridis", norm=norm,
                             shading="flat")
        ax.set_ylim(180.0, 0.0)
        ax.set_title(f"joint {joint}, {float(ds['snapshot_cycle'][s]):.3g} revolutions", fontsize="small")
        ax.set_xlabel(axis_label(ds["azimuth"], "azimuth"), fontsize="x-small")
        ax.set_ylabel(axis_label(ds["polar"], "polar"), fontsize="x-small")
    if mesh is not None:
        fig.colorbar(mesh, ax=fig.axes[-len(picks):]).set_label(axis_label(snaps, "wear depth"))
    fig.suptitle(f"Service life: stopped by {ds['stop_reason'].values}\n"
                 + snapshot_note(ds["snapshot_cycle"].values, picks, joint))


def snapshot_note(cycles: np.ndarray, picks: np.ndarray, joint: str) -> str:
    """Which of the stored wear-map snapshots (at ``cycles`` revolutions) the life figure
    draws (positions ``picks``).

    >>> snapshot_note(np.array([1.0, 10.0, 100.0]), np.array([0, 1, 2]), "B")
    'wear maps of joint B: all 3 stored snapshots'
    >>> snapshot_note(np.array([1.0, 10.0, 100.0]), np.array([0, 2]), "B")
    'wear maps of joint B: 2 of the 3 stored snapshots (not drawn: 10 revolutions)'
    """
    n = len(cycles)
    if len(picks) == n:
        return f"wear maps of joint {joint}: all {n} stored snapshots"
    left = [float(c) for i, c in enumerate(cycles) if i not in set(picks.tolist())]
    listed = ", ".join(f"{c:.3g}" for c in left[:4]) + (", ..." if len(left) > 4 else "")
    return (f"wear maps of joint {joint}: {len(picks)} of the {n} stored snapshots "
            f"(not drawn: {listed} revolutions)")


def _life_limit(config: dict, key: str | None) -> float | None:
    """The value of a life limit ``key`` ("life.max_...") in the dataset's config, if set."""
    if key is None:
        return None
    value = config.get("life", {}).get(key.split(".")[1])
    return None if value is None else float(value)


def _draw_reliability(fig: Figure, ds: xr.Dataset, b10: bool) -> None:
    _require(ds, ("reliability", "reliability_ci_low", "reliability_ci_high", "b10"),
             "--kind reliability")
    if "limit" in ds.coords and "limit" not in ds.dims:    # --select limit=NAME: that limit alone
        ds = ds.expand_dims("limit")
    limits = [str(v) for v in ds["limit"].values]
    designs = [d for d in ds["b10"].dims if d != "limit"]
    flat = ds.stack(design=designs) if designs else ds.expand_dims(design=[0])
    labels = [", ".join(f"{d}={value_text(flat[d].values[k])}" for d in designs) or "design"
              for k in range(flat.sizes["design"])]
    colours = colormaps["tab10"] if len(labels) <= MAX_CYCLE_COLOURS else colormaps["viridis"]
    ncols = min(3, len(limits))
    nrows = -(-len(limits) // ncols)
    level = float(ds.attrs.get("reliability_confidence_level", 0.95))
    for k, limit in enumerate(limits):
        ax = fig.add_subplot(nrows, ncols, k + 1)
        case = flat.sel(limit=limit)
        for i, label in enumerate(labels):
            colour = colours(i if len(labels) <= MAX_CYCLE_COLOURS else i / max(len(labels) - 1, 1))
            one = case.isel(design=i)
            if b10:
                value = float(one["b10"])
                low, high = float(one["b10_ci_low"]), float(one["b10_ci_high"])
                top = float(ds["revolutions"].max())
                shown = value if np.isfinite(value) else top
                err = [[max(shown - low, 0.0) if np.isfinite(low) else 0.0],
                       [max((high if np.isfinite(high) else top) - shown, 0.0)]]
                ax.errorbar([i], [shown], yerr=err, fmt="o" if np.isfinite(value) else "^",
                            color=colour, capsize=4)
                continue
            n = ds["revolutions"].values
            ax.step(n, one["reliability"].values, where="post", color=colour, label=label)
            ax.fill_between(n, one["reliability_ci_low"].values, one["reliability_ci_high"].values,
                            step="post", color=colour, alpha=0.2)
        ax.set_title(f"limit: {limit}", fontsize="medium")
        if b10:
            ax.set_yscale("log")
            ax.set_xticks(range(len(labels)), labels, rotation=30, ha="right", fontsize="x-small")
            ax.set_ylabel(f"B10 [revolutions], bars: {level:.0%} interval")
        else:
            ax.set_xscale("log")
            ax.set_xlim(float(ds["revolutions"].min()), float(ds["revolutions"].max()))
            ax.set_ylim(-0.02, 1.02)
            ax.axhline(0.9, color="0.5", lw=0.8, ls=":")
            ax.set_xlabel(axis_label(ds["revolutions"], "crank revolutions N"))
            ax.set_ylabel("reliability R(N) [-]")
            if k == 0:
                ax.legend(fontsize="x-small")
        ax.grid(alpha=0.3)
    what = "B10 per design (triangle: beyond the revolutions reached)" if b10 else \
        f"Kaplan-Meier reliability per design, bands: {level:.0%} Greenwood"
    fig.suptitle(f"{what}; {ds.sizes.get('member', 0)} members per design")


_SIZES = {"life": (16, 10), "reliability": (14, 8), "slider": (8, 8),
          "forces": (15, 9), "wear-map": (11, 9), "wear-polar": (11, 9.5),
          "orbit": (12, 8), "sweep": (8, 5)}


def figure(ds: xr.Dataset, kind: str, select=None, *, x: str = "angle",
           metric: str | None = None, b10: bool = False) -> Figure:
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
        Abscissa of time series: ``"angle"`` (crank angle [degree]) or ``"time"`` [s].
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
    if x not in X_AXES:
        raise SelectionError(choice_message("abscissa", x, list(X_AXES)), name="x", value=x,
                             choices=X_AXES)
    if metric is not None and kind != "sweep":
        raise PlotError("a metric applies to --kind sweep only")
    if b10 and kind != "reliability":
        raise PlotError("--b10 applies to --kind reliability only")
    if kind == "wear-map" and "wear_map_snapshot" in ds and "snapshot" not in ds.coords:
        ds, select = _life_wear_map(ds, select), None       # a life run: no sweep dimensions
    selection = parse_selection(ds, select)
    ds = ds.sel(selection) if selection else ds
    fig = Figure(figsize=_SIZES[kind], layout="constrained")
    if kind == "slider":
        _draw_slider(fig, ds, x)
    elif kind == "forces":
        _draw_forces(fig, ds, x)
    elif kind == "wear-map":
        _draw_wear_map(fig, ds)
    elif kind == "wear-polar":
        _draw_wear_polar(fig, ds)
    elif kind == "orbit":
        _draw_orbit(fig, ds)
    elif kind == "life":
        _draw_life(fig, ds)
    elif kind == "reliability":
        _draw_reliability(fig, ds, b10)
    else:
        _draw_sweep(fig, ds, metric)
    _name_selection(fig, selection_text(ds, selection) or case_text(ds))
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


def plot(ds: xr.Dataset, kind: str, out_path, select=None, *, x: str = "angle",
         metric: str | None = None, dpi: int = FIGURE_DPI, b10: bool = False) -> Figure:
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
    fig = figure(ds, kind, select, x=x, metric=metric, b10=b10)
    # a temporary file renamed into place: a full disk or a kill leaves no partial figure
    with replaced_on_success(out_path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=out_path.suffix.lower()[1:],
                    metadata=figure_metadata(out_path.suffix))
    return fig
