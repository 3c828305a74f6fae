"""Paper-style tables of a results dataset (Tables 4-6, the every-step statistics, one
metric, an ensemble's statistics and design comparisons), laid out as text, markdown,
csv or json."""

from __future__ import annotations

import collections
import csv
import io
import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..choices import REPORT_FORMATS
from ..ensemble import MEMBER_DIM
from ..jointtypes import describe
from ..motion import HIGH_ORDER, PERIOD_UNKNOWN
from ..summary import (
    WEAR_THRESHOLD_FRACTION,
    case_summary,
    peak_force_source,
    wear_table,
    with_attrs,
)
from ..variables import length_unit
from .selection import (
    _MISSING_TEXT,
    CASE_DIMS,
    SelectionError,
    _drop_ideal_rows,
    choice_message,
    design_dims,
    ideal_joints,
    iter_cases,
    iter_points,
    joint_clearances,
    label_text,
    parse_selection,
    sweep_dims,
    value_text,
)

# --------------------------------------------------------------------------- tables and summaries

def reduction_table(ds: xr.Dataset, reference: Mapping[str, object] | Iterable[str]) -> xr.Dataset:
    """Paper Table 6: change of maximum wear depth and wear range against a reference case.

    Parameters
    ----------
    ds
        Sweep dataset (full or summary).
    reference
        The reference case, ``{"B_coating": "none"}`` or ``["B_coating=none"]``.
        Only the named sweep dimensions are fixed: each case is compared with
        the reference that shares its other sweep coordinates.

    Returns
    -------
    xr.Dataset
        Over (sweep dims..., joint, axis): ``wear_depth_reduction`` [m]
        (reference - case), ``wear_depth_reduction_percent`` [%] (relative to
        the reference; NaN where the reference has no wear),
        ``wear_range_reduction`` [degree] (reference - case; negative where the
        range grew) and ``wear_range_reduction_percent`` [%]; the boolean
        ``is_reference`` marks the reference cases and the attribute
        ``reference`` names them.

    Raises
    ------
    SelectionError
        ``reference`` names no sweep dimension or an unknown value.
    """
    table = wear_table(ds)
    chosen = parse_selection(table, reference, dims_only=True)
    if not chosen:
        raise SelectionError("a reference case needs at least one DIM=VALUE",
                             choices=sweep_dims(table))
    # drop the chosen dims' coordinates, zip-group companions (e.g. A_coating along
    # coating_joints) included, so that the reference broadcasts against every case
    along = [c for c in table.coords if set(table[c].dims) & set(chosen)]
    ref = table.sel(chosen).drop_vars(along)
    order = table["wear_depth_axis_max"].dims

    def reduction(name: str) -> tuple[xr.DataArray, xr.DataArray]:
        ref_value = ref[name]
        change = (ref_value - table[name]).transpose(*order)
        percent = (100.0 * change / ref_value.where(ref_value > 0)).transpose(*order)
        return change, percent

    depth, depth_percent = reduction("wear_depth_axis_max")
    width, width_percent = reduction("wear_range")
    is_reference = xr.DataArray(True)
    for dim, value in chosen.items():
        is_reference = is_reference & (table[dim] == value)
    return xr.Dataset({
        "wear_depth_reduction": with_attrs(depth, "wear_depth_reduction"),
        "wear_depth_reduction_percent": with_attrs(depth_percent, "wear_depth_reduction_percent"),
        "wear_range_reduction": with_attrs(width, "wear_range_reduction"),
        "wear_range_reduction_percent": with_attrs(width_percent, "wear_range_reduction_percent"),
        "is_reference": with_attrs(is_reference, "is_reference"),
    }, attrs={"reference": label_text(chosen)})


#: The guide's walls as its map's bands hold them (``core.prismatic.WALLS``: rows 0 .. n/4 - 1
#: the +y wall, then -y, +z and -z; docs/physics.md 5.7), and the name of each wall's column
#: of the corners' track depth in reports.
GUIDE_WALLS = ("+y", "-y", "+z", "-z")
TRACK_DEPTH_COLUMNS = {wall: "track_depth_max_" + ("plus_" if wall[0] == "+" else "minus_") + wall[1]
                       for wall in GUIDE_WALLS}


def _has_tracks(ds: xr.Dataset, joint) -> bool:
    """Whether ``joint``'s type reports its walls' track depths (``jointtypes``: its
    ``report_columns``)."""
    return "track_depth" in describe(value_text(joint), ds.attrs).report_columns


def guide_track_depths(ds: xr.Dataset) -> dict[str, xr.DataArray]:
    """The largest track depth [m] on each wall of every prismatic joint of ``ds`` (the
    largest bin of the wall's band of ``wear_map``), by its column name
    (:data:`TRACK_DEPTH_COLUMNS`), NaN for the other joints; {} where ``ds`` has no wear map
    (a summary-only sweep) or no prismatic joint with a clearance."""
    if "wear_map" not in ds or "joint" not in ds["wear_map"].dims:
        return {}
    wmap = ds["wear_map"]
    ideal = ideal_joints(ds)
    guide = xr.DataArray([_has_tracks(ds, j) and value_text(j) not in ideal
                          for j in wmap["joint"].values], dims="joint", coords={"joint": wmap["joint"]})
    if not bool(guide.any()) or wmap.sizes["polar"] < len(GUIDE_WALLS):
        return {}
    band = wmap.sizes["polar"] // len(GUIDE_WALLS)
    out = {}
    for w, wall in enumerate(GUIDE_WALLS):
        depth = wmap.isel(polar=slice(w * band, (w + 1) * band)).max(("polar", "azimuth"))
        out[TRACK_DEPTH_COLUMNS[wall]] = depth.where(guide).assign_attrs(
            units="m", long_name=f"largest track depth on the guide's {wall} wall")
    return out


def report_summary(ds: xr.Dataset) -> xr.Dataset:
    """:func:`clearsweep.summary.case_summary` of ``ds`` as the reports read it, with what sets
    each case's peak force (:func:`clearsweep.summary.peak_force_source`): a ``period``
    that a case lacks (a run too short for a Poincaré section, beside cases that have them:
    NaN in the sweep's file) is ``PERIOD_UNKNOWN``, as a run's own undetermined period is,
    and the periods are integers."""
    summary = case_summary(ds)
    if "period" in summary and summary["period"].dtype.kind == "f":
        values = summary["period"].values
        summary["period"] = summary["period"].copy(
            data=np.where(np.isnan(values), PERIOD_UNKNOWN, values).astype(np.int64))
    source = peak_force_source(summary)
    if source is not None:
        summary["peak_force_source"] = source
    # the guide's walls: the track depth per wall, beside the whole map's largest bin
    return summary.assign(guide_track_depths(ds))


def metric_table(ds: xr.Dataset, metric: str) -> xr.DataArray:
    """One ``case_summary`` variable over the sweep dimensions.

    Raises
    ------
    SelectionError
        ``metric`` is not a summary variable of ``ds``; the message lists them.
    """
    summary = report_summary(ds)
    if metric in summary:
        return without_ideal_joints(summary[metric], ds)
    # a life or reliability sweep's own per-case numbers (cycles_reached, b10, ...)
    dims = set(sweep_dims(ds)) | {"joint"}
    own = [str(n) for n, v in ds.data_vars.items() if n not in summary and v.dtype.kind in "fiu"
           and v.dims and set(v.dims) <= dims]
    if metric in own:
        return without_ideal_joints(ds[metric], ds)
    names = [str(n) for n in summary.data_vars] + own
    raise SelectionError(choice_message("metric", metric, names), name=metric, choices=names)


def without_ideal_joints(values: xr.DataArray, ds: xr.Dataset) -> xr.DataArray:
    """``values`` without the joints that are ideal in every case of ``ds`` (joint O of a
    mechanism with spherical clearance only): their per-joint metrics are n/a throughout,
    so a table has no row and a figure no panel for them. All of them where every joint is
    ideal (the ideal mechanism), or where ``ds`` does not say which joints have clearance."""
    ideal = ideal_joints(ds) if "joint" in values.dims else []
    if not ideal:
        return values
    kept = [j for j in values["joint"].values if value_text(j) not in ideal]
    return values.sel(joint=kept) if kept else values


@dataclass(frozen=True)
class _Column:
    """One value column of a report: variable name, heading and text format."""

    name: str
    heading: str
    spec: str


@dataclass
class _Group:
    """Rows printed under one heading; ``keys`` become columns in csv and json."""

    heading: str
    keys: dict[str, object]
    rows: list[dict[str, object]]


_WEAR_COLUMNS = (
    _Column("wear_depth_axis_max", "Max projected depth", ".4e"),
    _Column("wear_angle_max", "Max wear angle", ".1f"),
    _Column("wear_angle_min", "Min wear angle", ".1f"),
    _Column("wear_range", "Wear range", ".1f"),
    _Column("wear_angle_of_max", "Angle of max depth", ".1f"),
)
_REDUCTION_COLUMNS = (
    _Column("wear_depth_reduction", "Reduction of max wear depth", ".3e"),
    _Column("wear_depth_reduction_percent", "Percentage of reduction", ".2f"),
    _Column("wear_range_reduction", "Reduction of wear range", ".2f"),
    _Column("wear_range_reduction_percent", "Percentage of range reduction", ".2f"),
)
_KEY_HEADINGS = {"joint": "Joint", "axis": "Wear direction"}


def _scalar(value):
    """Python scalar of a numpy value; NaN as None (JSON null)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


#: The widest line a text report prints [characters].
REPORT_WIDTH = 100


def _two_lines(text: str) -> tuple[str, str]:
    """``text`` split at the space nearest its middle (a column heading on two lines)."""
    spaces = [i for i, ch in enumerate(text) if ch == " "]
    if not spaces:
        return text, ""
    cut = min(spaces, key=lambda i: abs(i - len(text) / 2))
    return text[:cut], text[cut + 1:]


def _cell(value, spec: str, scale: float | None = None) -> str:
    value = _scalar(value)
    if value is None:
        return _MISSING_TEXT
    if isinstance(value, float):
        if scale is not None:       # a length in the column's unit: four significant digits
            return format(value / scale, ".4g")
        return format(value, spec)
    return value_text(value)


def _rows(obj: xr.Dataset, dims: tuple[str, ...], names: list[str]) -> list[dict[str, object]]:
    """One dict per point of ``dims``: the coordinates of ``dims``, then the variables ``names``."""
    return [{**keys, **{n: point[n].values[()] for n in names}}
            for keys, point in iter_points(obj, dims)]


def _case_groups(table: xr.Dataset, columns: tuple[_Column, ...], row_dims: tuple[str, ...],
                 keep=None, bare: bool = False) -> list[_Group]:
    """A group per sweep case, headed by its coordinates (and status where not ``ok``).

    Points that a sweep's ``skip:`` rules left out (status ``skipped``) are not listed.
    A case whose every row is of an ideal joint has no rows; with ``bare``, one row instead,
    its ``row_dims`` None and its columns over them None: the case's own values (the flat
    table of csv and json keeps every case).
    """
    groups = []
    clearances = joint_clearances(table)
    if clearances is not None:
        table = table.assign(joint_clearance=clearances)
    for label, case in iter_cases(table):
        if keep is not None and not keep(case):
            continue
        if "status" in case and value_text(case["status"].values[()]) == "skipped":
            continue
        clearance = case["joint_clearance"] if clearances is not None else None
        keys = dict(label)
        heading = label_text(label)
        if "status" in case:
            status = value_text(case["status"].values[()])
            keys["status"] = status
            if heading or status != "ok":
                heading = f"{heading} (status: {status})" if heading else f"status: {status}"
        rows = _drop_ideal_rows(_rows(case, row_dims, [c.name for c in columns]), clearance)
        if bare and not rows:
            rows = [{**dict.fromkeys(row_dims),
                     **{c.name: None if set(case[c.name].dims) & set(row_dims)
                        else case[c.name].values[()] for c in columns}}]
        groups.append(_Group(heading, keys, rows))
    return groups


#: What a text or markdown table says in place of rows where a case has none: every
#: joint of it is ideal (its per-joint rows are left out).
NO_CLEARANCE_ROWS = "none: every joint is ideal (joints.*.clearance 0)"


def _render(title: str, groups: list[_Group], key_names: tuple[str, ...],
            columns: tuple[_Column, ...], units: Mapping[str, str], fmt: str,
            empty: str = NO_CLEARANCE_ROWS) -> str:
    """Lay groups of rows out as text or markdown blocks, or as one flat csv / json table.

    Parameters
    ----------
    key_names
        Row-key entries of each row (``joint``, ``axis``, sweep dims), printed first.
    units
        Units of each value column, for the headings.
    empty
        Text and markdown: printed under the heading of a group without rows, and after
        the title (one line for the table) where no group has rows.
    """
    if fmt not in REPORT_FORMATS:
        raise SelectionError(choice_message("format", fmt, list(REPORT_FORMATS)), name="format",
                             value=fmt, choices=REPORT_FORMATS)

    def heading(c: _Column) -> str:
        return f"{c.heading} [{units[c.name]}]" if units.get(c.name) else c.heading

    units_given = units
    scale: dict[str, float] = {}
    if fmt not in ("csv", "json"):      # lengths to read in um or mm; csv and json stay SI
        units = dict(units)
        for c in columns:
            if units.get(c.name) == "m":
                scale[c.name], units[c.name] = length_unit(
                    [v for g in groups for r in g.rows if (v := _scalar(r[c.name])) is not None])

    if fmt in ("csv", "json"):
        records = [{**{k: _scalar(v) for k, v in g.keys.items()},
                    **{k: _scalar(r[k]) for k in key_names},
                    **{c.name: _scalar(r[c.name]) for c in columns}}
                   for g in groups for r in g.rows]
        if fmt == "json":
            meta = {c.name: {"heading": c.heading, "units": units.get(c.name, "")} for c in columns}
            return json.dumps({"title": title, "columns": meta, "rows": records}, indent=2)
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        group_keys = list(groups[0].keys) if groups else []
        writer.writerow(group_keys + list(key_names) + [heading(c) for c in columns])
        for record in records:
            # a row without joint or wear direction (a case of ideal joints only): empty keys
            writer.writerow(["" if v is None and k in key_names else "nan" if v is None
                             else repr(v) if isinstance(v, float) else v
                             for k, v in record.items()])
        return buffer.getvalue().rstrip("\n")

    if not any(g.rows for g in groups):
        return f"## {title}\n\n{empty}" if fmt == "markdown" else f"{title}: {empty}"
    titles = [_KEY_HEADINGS.get(k, k) for k in key_names] + [heading(c) for c in columns]
    n_keys = len(key_names)
    if fmt == "text" and len(columns) > 1:
        # too wide even with two-line headings: the columns in parts, each under the row keys
        def width(i: int, t: str) -> int:
            values = [len(value_text(r[key_names[i]])) if i < n_keys
                      else len(_cell(r[columns[i - n_keys].name], columns[i - n_keys].spec,
                                     scale.get(columns[i - n_keys].name)))
                      for g in groups for r in g.rows]
            return max(max(len(x) for x in _two_lines(t)), *values, 0) + 2
        widths = [width(i, t) for i, t in enumerate(titles)]
        parts: list[list[_Column]] = [[]]
        used = sum(widths[:n_keys])
        for c, w in zip(columns, widths[n_keys:]):
            if parts[-1] and used + w > REPORT_WIDTH:
                parts.append([])
                used = sum(widths[:n_keys])
            parts[-1].append(c)
            used += w
        if len(parts) > 1:
            return "\n\n".join(_render(title if i == 0 else f"{title}, continued", groups, key_names,
                                        tuple(part), units_given, fmt, empty)
                                for i, part in enumerate(parts))
    out = [f"## {title}" if fmt == "markdown" else title]
    for group in groups:
        cells = [[value_text(r[k]) for k in key_names]
                 + [_cell(r[c.name], c.spec, scale.get(c.name)) for c in columns]
                 for r in group.rows]
        if not cells:
            heading_line = f"\n### {group.heading}\n" if fmt == "markdown" else f"\n{group.heading}"
            out += [heading_line if group.heading else "", empty]
            continue
        if fmt == "markdown":
            out.append(f"\n### {group.heading}\n" if group.heading else "")
            out.append("| " + " | ".join(titles) + " |")
            out.append("|" + "|".join("---" if i < n_keys else "---:" for i in range(len(titles))) + "|")
            out.extend("| " + " | ".join(row) + " |" for row in cells)
            continue
        # headings on two lines where one would make the table wider than a report line
        head = [_two_lines(t) if len(t) > max(len(row[i]) for row in cells)
                and sum(max([len(t), *(len(r[i]) for r in cells)]) + 2 for i, t in enumerate(titles))
                > REPORT_WIDTH else (t, "") for i, t in enumerate(titles)]
        widths = [max(len(h[0]), len(h[1]), *(len(row[i]) for row in cells))
                  for i, h in enumerate(head)]

        def line(row: list[str]) -> str:
            return "  ".join(c.ljust(w) if i < n_keys else c.rjust(w)
                             for i, (c, w) in enumerate(zip(row, widths))).rstrip()

        out.append(f"\n{group.heading}" if group.heading else "")
        out.append(line([h[0] for h in head]))
        if any(h[1] for h in head):
            out.append(line([h[1] for h in head]))
        out.extend(line(row) for row in cells)
    return "\n".join(out)


def _units(table: xr.Dataset, columns: tuple[_Column, ...]) -> dict[str, str]:
    return {c.name: table[c.name].attrs.get("units", "") for c in columns}


def _with_status(ds: xr.Dataset, table: xr.Dataset) -> xr.Dataset:
    """``table`` with the status of ``ds`` and its attributes (the config that says which
    joints are ideal)."""
    out = table.assign(status=ds["status"]) if "status" in ds else table.copy()
    out.attrs = {**ds.attrs, **table.attrs}
    return out


def format_wear_table(ds: xr.Dataset, fmt: str = "text", with_statistics: bool = False) -> str:
    """Paper Tables 4-5 as text, markdown, csv or json.

    Columns per joint and wear direction (axis): max wear depth [m], max wear
    angle, min wear angle, wear range and the angle of the maximum depth
    [degree]. Text and markdown print one block per sweep case, headed by its
    coordinates (and its status where not ``ok``); csv and json print one
    flat table with the sweep coordinates and the status as columns.

    ``with_statistics``: every row also carries its case's and joint's every-step
    statistics and final wear (:func:`format_statistics_table`'s columns, each case's
    value on each of its rows): the one flat table of ``report --format csv / json``.
    """
    wear = wear_table(ds)
    columns: tuple[_Column, ...] = _WEAR_COLUMNS
    # a guide's walls have no projections about the axes (docs/physics.md 5.7): its wear is in
    # the final-wear table; the flat csv / json table keeps its row for its statistics
    flat = [j for j in wear["joint"].values if describe(value_text(j), ds.attrs).wear_profile]
    empty = NO_CLEARANCE_ROWS
    if not with_statistics and len(flat) < wear.sizes["joint"]:
        guides = [value_text(j) for j in wear["joint"].values if j not in flat
                  and value_text(j) not in ideal_joints(ds)]
        if guides:
            empty = (f"none: no ball or bearing joint has a clearance (the wear of guide "
                     f"{', '.join(guides)} is in the table of the wear at the end of the run)")
        wear = wear.sel(joint=flat)
    if with_statistics:
        summary = report_summary(ds)
        extra = tuple(c for c in (*_MOTION_COLUMNS, *_CHARACTER_COLUMNS, *_CONTACT_COLUMNS,
                                  *_FINAL_WEAR_COLUMNS, *_TRACK_COLUMNS) if c.name in summary)
        # each on its own dims: a row takes its case's (and joint's) value, and a case of
        # ideal joints only (one bare row) its case values
        wear = wear.assign({c.name: summary[c.name] for c in extra})
        columns = extra + _WEAR_COLUMNS
    table = _with_status(ds, wear)
    title = (f"Wear prediction (paper Tables 4-5; wear angles: depth > "
             f"{WEAR_THRESHOLD_FRACTION:g} of the axis maximum)")
    groups = _case_groups(table, columns, ("joint", "axis"), bare=with_statistics)
    return _render(title, groups, ("joint", "axis"), columns, _units(table, columns), fmt, empty)


_MOTION_COLUMNS = (
    _Column("peak_force_source", "Peak force set by", ""),
    _Column("slider_acceleration_peak_settled", "Peak slider acc., settled", ".4g"),
    _Column("slider_acceleration_peak", "Peak slider acc., whole run", ".4g"),
    _Column("slider_acceleration_rms_settled", "RMS slider acc., settled", ".4g"),
    _Column("slider_acceleration_rms", "RMS slider acc., whole run", ".4g"),
    _Column("crank_torque_peak_settled", "Peak crank torque, settled", ".4g"),
    _Column("crank_torque_peak", "Peak crank torque, whole run", ".4g"),
)
#: The motion's character (docs/physics.md section 11): spectrum and periodicity.
_CHARACTER_COLUMNS = (
    _Column("slider_acceleration_dominant_order", "Dominant order of slider acc.", ".3g"),
    _Column("slider_acceleration_high_order_share", f"Power share above order {HIGH_ORDER:g}", ".3g"),
    _Column("period", "Period in revolutions (0: none, -1: n/a)", ""),
    _Column("chaos_k", "0-1 test K", ".2f"),
    _Column("lyapunov_exponent", "Largest Lyapunov exponent per revolution", ".3g"),
    _Column("motion_class", "Motion class", ""),
)
_CONTACT_COLUMNS = (
    _Column("normal_force_peak_settled", "Peak normal force, settled", ".4g"),
    _Column("normal_force_peak", "Peak normal force, whole run", ".4g"),
    _Column("impact_count_settled", "Impacts, settled", ""),
    _Column("impact_count", "Impacts, whole run", ""),
    _Column("impact_velocity_max_settled", "Largest impact velocity, settled", ".3g"),
    _Column("contact_fraction_settled", "Contact fraction, settled", ".3f"),
)
_FINAL_WEAR_COLUMNS = (
    _Column("wear_depth_max_final", "Max depth, largest map bin", ".4g"),
    _Column("wear_volume", "Worn volume", ".4g"),
)
#: The slider-crank's guide (along y) names its walls in the prismatic type's frame turned
#: into it (``core.prismatic.PLANAR_GUIDE``): the reports' note.
PLANAR_WALLS_NOTE = ("; the slider-crank's guide along y: +y and -y its side walls across the "
                     "plane, at -x and +x, +z and -z its upper and lower walls")
#: A guide's walls: the corners' track depth on each (docs/physics.md 5.7), where the
#: results keep the wear map.
_TRACK_COLUMNS = tuple(_Column(TRACK_DEPTH_COLUMNS[wall], f"Track depth, {wall} wall", ".4g")
                       for wall in GUIDE_WALLS)


def format_statistics_table(ds: xr.Dataset, fmt: str = "text") -> str:
    """The kernel's every-step statistics: settled window first, whole run beside it.

    Four tables: slider and crank (one row per case), contacts and the wear at the end
    (largest depth of the wear map beside the worn volume; one row per case and joint), and
    the motion's spectrum and periodicity where the file has them (one row per case).
    A file without the statistics gives an empty string.
    """
    summary = report_summary(ds)
    settle = ds.attrs.get("settle_time_s")
    window = f"settled = t >= {float(settle):g} s" if settle is not None else "settled window"
    blocks = []
    statistics = f"every-step statistics; {window}"
    specs: tuple[tuple[str, tuple[_Column, ...], tuple[str, ...]], ...] = (
        (f"Slider and crank ({statistics})", _MOTION_COLUMNS, ()),
        (f"Contacts ({statistics})", _CONTACT_COLUMNS, ("joint",)),
        ("Wear at the end of the run (the worn volume does not depend on the map's grid)",
         _FINAL_WEAR_COLUMNS, ("joint",)),
        ("Guide walls at the end of the run (the largest depth of the corners' track on each "
         "wall" + (PLANAR_WALLS_NOTE if ds.attrs.get("mechanism") == "slider_crank" else "")
         + ")", _TRACK_COLUMNS, ("joint",)),
        (f"Motion: spectrum and periodicity ({window})", _CHARACTER_COLUMNS, ()))
    for heading, wanted, dims in specs:
        # a column with no value in any case (the settled window of runs that end before
        # it) is left out, not printed as a column of n/a
        columns = tuple(c for c in wanted if c.name in summary
                        and bool(summary[c.name].notnull().any()))
        if not columns:
            continue
        table = _with_status(ds, summary[[c.name for c in columns]])
        if wanted is _TRACK_COLUMNS:    # the guides' rows only: a socket has no walls
            table = table.sel(joint=[j for j in table["joint"].values
                                     if _has_tracks(ds, j)])
        keys: tuple[str, ...]
        if dims:
            groups = _case_groups(table, columns, dims)
            keys = dims
        else:
            # one row per case, keyed by its sweep coordinates
            rows = [{**label, "status": value_text(case["status"].values[()]),
                     **{c.name: case[c.name].values[()] for c in columns}}
                    for label, case in iter_cases(table)
                    if value_text(case["status"].values[()]) != "skipped"]
            groups = [_Group("", {}, rows)]
            if all(r["status"] == "ok" for r in rows):
                for r in rows:
                    del r["status"]
            keys = tuple(k for k in (rows[0] if rows else {}) if k not in {c.name for c in columns})
        blocks.append(_render(heading, groups, keys, columns, _units(table, columns), fmt))
    return "\n\n".join(blocks)


def format_reduction_table(ds: xr.Dataset, reference, fmt: str = "text") -> str:
    """Paper Table 6 (``reduction_table``) for every case except the reference ones."""
    table = _with_status(ds, reduction_table(ds, reference))
    title = (f"Comparison of wear prediction against {table.attrs['reference']} "
             "(paper Table 6; reduction = reference - case)")
    groups = _case_groups(table, _REDUCTION_COLUMNS, ("joint", "axis"),
                          keep=lambda case: not bool(case["is_reference"]))
    return _render(title, groups, ("joint", "axis"), _REDUCTION_COLUMNS,
                   _units(table, _REDUCTION_COLUMNS), fmt)


def format_metric_table(ds: xr.Dataset, metric: str, fmt: str = "text") -> str:
    """One summary metric (``metric_table``) as a flat table.

    A row per case (and joint / axis where the metric has them), keyed by the
    case's sweep coordinates (``iter_cases`` labels, zip-group keys included).
    """
    values = metric_table(ds, metric)
    column = _Column(metric, values.attrs.get("long_name", metric),
                     ".6g" if values.dtype.kind == "f" else "")
    inner = tuple(d for d in values.dims if d in CASE_DIMS)
    table = values.to_dataset(name=metric)
    # (a reliability design's b10 has no member dimension: no member's status marks it)
    if "status" in ds and metric != "status" and set(ds["status"].dims) <= set(values.dims):
        table["status"] = ds["status"]
    # like the wear tables: points a sweep's skip rules left out are not listed
    rows = [{**label, **row}
            for label, case in iter_cases(table)
            if "status" not in case or value_text(case["status"].values[()]) != "skipped"
            for row in _rows(case, inner, [metric])]
    keys = tuple(k for k in rows[0] if k != metric)
    return _render(f"{metric} ({column.heading})", [_Group("", {}, rows)], keys, (column,),
                   _units(table, (column,)), fmt)


# --------------------------------------------------------------------------- ensembles

#: Metrics of the ensemble report, in order; the settled statistic is replaced by its
#: whole-run twin where the run ends before the settled window (all NaN).
ENSEMBLE_METRICS = ("slider_acceleration_rms_settled", "slider_acceleration_peak_settled",
                    "crank_torque_peak_settled", "normal_force_peak_settled",
                    "impact_count_settled", "contact_fraction_settled", "wear_depth_max_final",
                    "wear_volume")
#: Metrics whose designs the ensemble report compares.
COMPARED_METRICS = ("wear_depth_max_final", "wear_volume", "slider_acceleration_rms_settled",
                    "normal_force_peak_settled")

_ENSEMBLE_COLUMNS = (
    _Column("mean", "Mean", ".4g"),
    _Column("half_width", "+- 95% CI", ".2g"),
    _Column("std", "Std", ".3g"),
    _Column("members_ok", "Members ok", ""),
)
_COMPARISON_COLUMNS = (
    _Column("difference", "Difference", ".3g"),
    _Column("ci_low", "95% CI low", ".3g"),
    _Column("ci_high", "95% CI high", ".3g"),
    _Column("verdict", "Verdict", ""),
)


def _present_metric(ds: xr.Dataset, name: str) -> str | None:
    """``name`` if its mean is stored and not all NaN, else its whole-run twin, else None."""
    for candidate in (name, name.removesuffix("_settled")):
        mean = ds.get(candidate + "_mean")
        if mean is not None and bool(np.isfinite(mean.values.astype(float)).any()):
            return candidate
    return None


def _metric_heading(ds: xr.Dataset, name: str) -> str:
    units = ds[name + "_mean"].attrs.get("units", "")
    long_name = ds[name].attrs.get("long_name", name) if name in ds else name
    return f"{name}: {long_name}" + (f" [{units}]" if units and units != "1" else "")


def format_ensemble_table(ds: xr.Dataset, fmt: str = "text",
                          metrics: Iterable[str] = ENSEMBLE_METRICS) -> str:
    """Ensemble mean -+ the half-width of its 95 % Student t interval, the standard deviation
    and the members counted, per design (and joint), one block per metric."""
    from ..ensemble import CI_METHOD

    dims = design_dims(ds)
    # designs that a sweep's skip rules left out are not listed
    skipped = (ds["status"].astype(str) == "skipped").all(MEMBER_DIM)
    groups = []
    for wanted in metrics:
        name = _present_metric(ds, wanted)
        if name is None:
            continue
        table = xr.Dataset({"mean": ds[name + "_mean"], "std": ds[name + "_std"],
                            "half_width": 0.5 * (ds[name + "_ci_high"] - ds[name + "_ci_low"]),
                            "members_ok": ds["members_ok"], "skipped": skipped})
        inner = tuple(d for d in table["mean"].dims if d in CASE_DIMS)
        rows = [{**keys, **row} for keys, point in iter_points(table, dims)
                if not bool(point["skipped"])
                for row in _rows(point, inner, [c.name for c in _ENSEMBLE_COLUMNS])]
        groups.append(_Group(_metric_heading(ds, name), {"metric": name}, rows))
    n = ds.sizes[MEMBER_DIM]
    title = (f"Ensemble statistics over {n} members (mean +- half-width of the 95% confidence "
             f"interval of the mean; {CI_METHOD}; members that stopped with another status are "
             "left out and counted in 'Members ok')")
    return _render(title, groups, dims + _joint_key(groups), _ENSEMBLE_COLUMNS, {}, fmt)


def _joint_key(groups: list[_Group]) -> tuple[str, ...]:
    """``("joint",)`` when some rows have a joint (the others then get an empty one)."""
    if not any("joint" in r for g in groups for r in g.rows):
        return ()
    for group in groups:
        for row in group.rows:
            row.setdefault("joint", "")
    return ("joint",)


def _reference_values(ds: xr.Dataset, dims: tuple[str, ...], reference) -> dict[str, object]:
    chosen = parse_selection(ds, reference, dims_only=True) if reference else {}
    return {d: chosen.get(d, ds[d].values[0] if d in ds.coords else 0) for d in dims}


def ensemble_comparisons(ds: xr.Dataset, reference=None,
                         metrics: Iterable[str] = COMPARED_METRICS) -> list[_Group]:
    """Each design against the reference value of one design dimension, the others held:
    difference of the ensemble means, its 95 % Welch interval and whether it excludes 0.

    The reference of a dimension is its ``reference`` value (``DIM=VALUE``), else its first.
    A pair that is equal without spread (an ideal joint's zero wear) is not listed.
    """
    from ..ensemble import distinguishable, welch_interval

    dims = design_dims(ds)
    refs = _reference_values(ds, dims, reference)
    groups = []
    for wanted in metrics:
        name = _present_metric(ds, wanted)
        if name is None:
            continue
        mean, std, n_ok = ds[name + "_mean"], ds[name + "_std"], ds["members_ok"]
        inner = tuple(d for d in mean.dims if d in CASE_DIMS)
        rows = []
        for dim in dims:
            if ds.sizes[dim] < 2:
                continue
            others = tuple(d for d in dims if d != dim)
            for held, _ in iter_points(mean.isel({dim: 0}), others) if others else [({}, None)]:
                ref = {**held, dim: refs[dim]}
                for value in ds[dim].values:
                    if value_text(value) == value_text(refs[dim]):
                        continue
                    case = {**held, dim: value}
                    for where, _ in iter_points(mean.isel({d: 0 for d in dims}), inner) if inner else [({}, None)]:
                        a, b = {**ref, **where}, {**case, **where}
                        m1, s1, n1 = float(mean.sel(a)), float(std.sel(a)), int(n_ok.sel(ref))
                        m2, s2, n2 = float(mean.sel(b)), float(std.sel(b)), int(n_ok.sel(case))
                        if not (np.isfinite(m1) and np.isfinite(m2)) or (s1 == s2 == 0.0 and m1 == m2):
                            continue
                        diff, low, high = welch_interval(m1, s1, n1, m2, s2, n2)
                        verdict = {True: "distinguishable", False: "not distinguishable",
                                   None: "n/a (fewer than 2 members)"}[distinguishable(low, high)]
                        rows.append({"compared": f"{dim}: {value_text(value)} vs {value_text(refs[dim])}",
                                     "held": label_text(held), **{k: value_text(v) for k, v in where.items()},
                                     "difference": diff, "ci_low": low, "ci_high": high,
                                     "verdict": verdict})
        if rows:
            groups.append(_Group(_metric_heading(ds, name), {"metric": name}, rows))
    return groups


def format_ensemble_comparisons(ds: xr.Dataset, fmt: str = "text", reference=None) -> str:
    """:func:`ensemble_comparisons` as a table, and a closing count of the verdicts."""
    groups = ensemble_comparisons(ds, reference)
    if not groups:
        return ""
    title = ("Design comparisons (case minus reference, ensemble means; 95% Welch t interval of "
             "the difference; 'not distinguishable': the interval contains 0)")
    text = _render(title, groups, ("compared", "held", *_joint_key(groups)), _COMPARISON_COLUMNS,
                   {}, fmt)
    if fmt in ("text", "markdown"):
        verdicts = collections.Counter(r["verdict"] for g in groups for r in g.rows)
        text += "\n\n" + ", ".join(f"{n} {v}" for v, n in sorted(verdicts.items())) + "."
    return text


def format_ensemble_report(ds: xr.Dataset, fmt: str = "text", reference=None) -> str:
    """The ensemble statistics and the design comparisons of an ensemble sweep."""
    parts = [format_ensemble_table(ds, fmt)]
    status = ds["status"].astype(str)
    failed = int(((status != "ok") & (status != "skipped")).sum())
    if failed and fmt in ("text", "markdown"):
        parts.append(f"{failed} member(s) stopped with a status other than ok and are not "
                     "averaged in (see the status and message variables).")
    if fmt in ("text", "markdown"):
        parts.append(format_ensemble_comparisons(ds, fmt, reference))
    return "\n\n".join(p for p in parts if p)

