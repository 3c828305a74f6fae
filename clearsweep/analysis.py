"""Paper-style wear tables (Tables 4-6), per-case summaries and text reports.

Every function here takes a dataset as written by ``dataset.build_dataset``
(one case) or by the sweep driver (the same variables with extra sweep
dimensions in front, or only the summary variables for ``store: summary``)
and reduces over the case dimensions (``time``, ``angle``, ``polar``,
``azimuth``), so any sweep dimensions simply stay in the results. Units and
long names come from ``variables.SUMMARY_VARIABLES``.

Conventions (DESIGN.md section 5, paper Tables 4-6):

- Projection angles are the bin centres of ``wear_projection`` on
  (-180, 180] degrees. The minimum and maximum wear angles are the smallest
  and largest bin centres whose depth exceeds ``WEAR_THRESHOLD_FRACTION`` of
  that axis's maximum, and the wear range is their difference, as in the
  paper: a worn region that straddles +-180 degrees is not unwrapped and
  reads as a range close to 360 degrees (Table 4, one clearance, x).
  ``wear_arc`` is the circular alternative: the shortest arc holding every
  worn bin, equal to ``wear_range`` unless the worn region straddles +-180
  degrees (then a few degrees rather than nearly 360).
- A (joint, axis) without any wear has depth 0 and NaN angles and range.
- Table 6 "reduction" is reference minus case; a negative wear-range
  reduction means that the range grew. Percentages are relative to the
  reference.
"""

from __future__ import annotations

import csv
import difflib
import io
import itertools
import json
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass

import click
import numpy as np
import xarray as xr

from .variables import attrs_for

#: Dimensions of one case; every other dimension of a dataset is a sweep dimension.
CASE_DIMS = ("time", "joint", "axis", "polar", "azimuth", "angle")

#: A projection bin counts as worn above this fraction of its axis's maximum (DESIGN.md 5).
WEAR_THRESHOLD_FRACTION = 1.0e-3

#: Start-up transient left out of the ``*_settled`` acceleration metrics [s].
SETTLE_TIME_S = 0.05

#: Output formats of the reports.
REPORT_FORMATS = ("text", "markdown", "csv", "json")

#: Variables of the wear table, in the column order of the paper's Tables 4-5
#: (the angle of the maximum, which the paper does not print, last).
WEAR_TABLE_VARIABLES = ("wear_depth_axis_max", "wear_angle_max", "wear_angle_min", "wear_range",
                        "wear_angle_of_max", "wear_arc")

#: Scalars copied from the case dataset into its summary.
PASS_THROUGH_VARIABLES = ("energy_residual_relative", "substeps_used", "rk4_steps", "wall_time")

#: Order of the variables in ``case_summary``.
SUMMARY_ORDER = ("status", "slider_acceleration_peak", "slider_acceleration_rms",
                 "slider_acceleration_peak_settled", "slider_acceleration_rms_settled",
                 "normal_force_peak", "wear_depth_max_final", *WEAR_TABLE_VARIABLES,
                 *PASS_THROUGH_VARIABLES)

_MISSING_TEXT = "n/a"


class SelectionError(ValueError):
    """A sweep dimension, coordinate value or metric name that the dataset does not have.

    Attributes
    ----------
    name, value : str
        What was asked for.
    choices : list of str
        What the dataset offers.
    """

    def __init__(self, message: str, *, name: str = "", value: str = "", choices: Iterable = ()):
        super().__init__(message)
        self.name = name
        self.value = value
        self.choices = [str(c) for c in choices]


# --------------------------------------------------------------------------- cases and selections

def sweep_dims(obj: xr.Dataset | xr.DataArray) -> tuple[str, ...]:
    """The sweep dimensions of ``obj``: every dimension that is not a case dimension.

    Ordered as they first appear in the data variables (a dataset's own
    ``dims`` follow its coordinates, not its variables).
    """
    if isinstance(obj, xr.Dataset):
        ordered = dict.fromkeys(d for v in obj.data_vars.values() for d in v.dims)
        ordered.update(dict.fromkeys(obj.dims))
    else:
        ordered = dict.fromkeys(obj.dims)
    return tuple(str(d) for d in ordered if d not in CASE_DIMS)


def value_text(value) -> str:
    """Short text of a coordinate value (``0.00025``, ``PTFE``)."""
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, (float, np.floating)):
        return f"{float(value):g}"
    if isinstance(value, np.generic):
        return str(value.item())
    return str(value)


def label_text(label: Mapping[str, object]) -> str:
    """``"B_coating=PTFE, B_clearance=0.00025"`` from a case label."""
    return ", ".join(f"{k}={value_text(v)}" for k, v in label.items())


def iter_points(obj: xr.Dataset | xr.DataArray, dims: tuple[str, ...]) -> Iterator[tuple[dict, object]]:
    """Yield ``({dim: value}, obj at that point)`` over ``dims``.

    The value is the dimension's coordinate value, or the position along a
    dimension without a coordinate.
    """
    for index in itertools.product(*(range(obj.sizes[d]) for d in dims)):
        point = obj.isel(dict(zip(dims, index)))
        yield {d: point[d].values[()] if d in obj.coords else i for d, i in zip(dims, index)}, point


def iter_cases(obj: xr.Dataset | xr.DataArray) -> Iterator[tuple[dict[str, object], object]]:
    """Yield ``(label, case)`` for every combination of the sweep dimensions.

    ``label`` maps each sweep dimension to the case's coordinate value (its
    position where the dimension has no coordinate), in dimension order, then
    every other coordinate that lives on sweep dimensions only (the keys of a
    zip group, the levels of a stacked case index). A one-case dataset yields
    itself once with an empty label.
    """
    dims = sweep_dims(obj)
    extra = [str(n) for n, c in obj.coords.items()
             if n not in dims and c.dims and set(c.dims) <= set(dims)]
    for label, case in iter_points(obj, dims):
        yield {**label, **{n: case[n].values[()] for n in extra}}, case


def choice_message(kind: str, wanted: str, choices: list[str]) -> str:
    """``unknown KIND 'x' (did you mean ...?); choose from: ...``"""
    close = difflib.get_close_matches(wanted, choices, n=3)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    offer = ", ".join(choices) if choices else "none"
    return f"unknown {kind} {wanted!r}{hint}; choose from: {offer}"


def _match_value(coord: xr.DataArray, name: str, wanted) -> object:
    """The value of ``coord`` that ``wanted`` (text or value) names: exact text or equal number."""
    candidates = list(dict.fromkeys(coord.values.ravel().tolist()))
    text = value_text(wanted).strip()
    for value in candidates:
        if value_text(value) == text or str(value) == text:
            return value
    try:
        number = float(text)
    except ValueError:
        number = None
    if number is not None:
        for value in candidates:
            if (isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isclose(float(value), number, rel_tol=1e-9, abs_tol=0.0)):
                return value
    raise SelectionError(choice_message(f"value for {name}", text, [value_text(v) for v in candidates]),
                         name=name, value=text, choices=[value_text(v) for v in candidates])


def parse_selection(obj: xr.Dataset | xr.DataArray,
                    items: Mapping[str, object] | Iterable[str] | None, *,
                    dims_only: bool = False) -> dict[str, object]:
    """Turn ``DIM=VALUE`` strings (or a mapping) into a validated ``.sel`` dict.

    Parameters
    ----------
    obj
        Dataset (or array) with sweep dimensions.
    items
        ``["B_coating=PTFE", "B_clearance=2.5e-4"]`` or ``{"B_coating": "PTFE"}``.
        Values match a coordinate value by text, or numerically for numbers.
    dims_only
        Accept only sweep dimensions, not other indexed coordinates
        (levels of a stacked ``case`` dimension).

    Returns
    -------
    dict
        Names mapped to coordinate values of ``obj``.

    Raises
    ------
    SelectionError
        Malformed item, unknown name or value; the message lists the choices.
    """
    if not items:
        return {}
    dims = sweep_dims(obj)
    names = [d for d in dims if d in obj.coords]
    if not dims_only:
        names += [str(n) for n in obj.xindexes
                  if n not in names and set(obj[n].dims) <= set(dims)]
    pairs = list(items.items()) if isinstance(items, Mapping) else []
    if not isinstance(items, Mapping):
        for item in items:
            name, sep, text = str(item).partition("=")
            if not sep:
                raise SelectionError(f"expected DIM=VALUE, got {item!r}", name=str(item),
                                     choices=names)
            pairs.append((name.strip(), text))
    out = {}
    for name, wanted in pairs:
        if name not in names:
            raise SelectionError(choice_message("sweep dimension", name, names), name=name,
                                 value=value_text(wanted), choices=names)
        out[name] = _match_value(obj[name], name, wanted)
    return out


def select_cases(obj: xr.Dataset | xr.DataArray, items) -> xr.Dataset | xr.DataArray:
    """``obj.sel`` of the cases named by ``items`` (see ``parse_selection``)."""
    selection = parse_selection(obj, items)
    return obj.sel(selection) if selection else obj


# --------------------------------------------------------------------------- tables and summaries

def _with_attrs(da: xr.DataArray, name: str, **extra) -> xr.DataArray:
    da = da.rename(name)
    da.attrs = {**attrs_for(name), **extra}
    return da


def worn_arc_deg(worn: np.ndarray) -> float:
    """Shortest arc [degree] between bin centres that holds every worn bin of a full circle.

    Parameters
    ----------
    worn
        One flag per equal angle bin spanning 360 degrees.

    Returns
    -------
    float
        360 minus the widest circular run of unworn bins and one bin width:
        ``hi - lo`` for worn bins on [lo, hi] that do not wrap, 360 when
        every bin is worn, NaN when none is.
    """
    n = worn.size
    index = np.flatnonzero(worn)
    if index.size == 0:
        return math.nan
    width = 360.0 / n
    if index.size == n:
        return 360.0
    gaps = np.append(np.diff(index) - 1, index[0] + n - index[-1] - 1)
    return (n - 1 - int(gaps.max())) * width


def wear_table(ds: xr.Dataset) -> xr.Dataset:
    """Paper Tables 4-5: maximum projected wear depth and the angles with wear.

    Parameters
    ----------
    ds
        One-case or sweep dataset holding ``wear_projection(joint, axis,
        angle)`` [m], or already holding the wear-table variables (a summary
        sweep).

    Returns
    -------
    xr.Dataset
        Over (sweep dims..., joint, axis): ``wear_depth_axis_max`` [m] (max
        over angle), ``wear_angle_of_max`` [degree] (centre of the first bin
        holding the maximum), ``wear_angle_min`` and ``wear_angle_max``
        [degree] (smallest and largest bin centre with depth above
        ``WEAR_THRESHOLD_FRACTION`` of the maximum), ``wear_range`` [degree]
        (max - min); ``wear_arc`` [degree] (shortest arc between bin centres
        that holds every worn bin, see ``worn_arc_deg``). Without any wear on
        a (joint, axis): depth 0, angles, range and arc NaN. Cases whose
        projection is all NaN give NaN depth.
    """
    if "wear_projection" not in ds:
        missing = [v for v in WEAR_TABLE_VARIABLES if v not in ds]
        if missing:
            raise ValueError("a wear table needs wear_projection (a full dataset) or the "
                             f"summary variables {', '.join(WEAR_TABLE_VARIABLES)}; "
                             f"missing: {', '.join(missing)}")
        return xr.Dataset({name: ds[name] for name in WEAR_TABLE_VARIABLES})
    projection = ds["wear_projection"]
    angle = projection["angle"]
    depth = projection.max("angle")
    first_max = projection.fillna(-np.inf).argmax("angle")
    angle_of_max = angle.isel(angle=first_max).drop_vars("angle").where(depth > 0)
    worn = projection > WEAR_THRESHOLD_FRACTION * depth
    worn_angle = angle.where(worn)
    angle_min = worn_angle.min("angle")
    angle_max = worn_angle.max("angle")
    arc = xr.apply_ufunc(worn_arc_deg, worn, input_core_dims=[["angle"]], vectorize=True,
                         output_dtypes=[float])
    threshold = {"wear_threshold_fraction": WEAR_THRESHOLD_FRACTION}
    return xr.Dataset({
        "wear_depth_axis_max": _with_attrs(depth, "wear_depth_axis_max"),
        "wear_angle_max": _with_attrs(angle_max, "wear_angle_max", **threshold),
        "wear_angle_min": _with_attrs(angle_min, "wear_angle_min", **threshold),
        "wear_range": _with_attrs(angle_max - angle_min, "wear_range", **threshold),
        "wear_angle_of_max": _with_attrs(angle_of_max, "wear_angle_of_max"),
        "wear_arc": _with_attrs(arc, "wear_arc", **threshold),
    })


def case_summary(ds: xr.Dataset) -> xr.Dataset:
    """Per-case scalars (and joint / axis arrays) of a one-case or sweep dataset.

    Parameters
    ----------
    ds
        Full dataset, or one that already holds some summaries (a summary
        sweep): a summary whose source variable is absent is copied when
        present.

    Returns
    -------
    xr.Dataset
        ``status``; ``slider_acceleration_peak`` (max |a|) and
        ``slider_acceleration_rms`` [m s-2], the same two over time >=
        ``SETTLE_TIME_S`` (``*_settled``, attribute ``settle_time_s``; NaN for
        runs no longer than that); ``normal_force_peak(joint)`` [N];
        ``wear_depth_max_final(joint)`` [m] (max of ``wear_map``); the
        ``wear_table`` variables; ``energy_residual_relative``,
        ``substeps_used``, ``rk4_steps``, ``wall_time`` [s]. Dataset
        attributes (provenance) are kept.
    """
    out: dict[str, xr.DataArray] = {}
    if "slider_acceleration" in ds:
        acc = ds["slider_acceleration"]
        settled = acc.where(acc["time"] >= SETTLE_TIME_S)
        settle = {"settle_time_s": SETTLE_TIME_S}
        out["slider_acceleration_peak"] = _with_attrs(abs(acc).max("time"), "slider_acceleration_peak")
        out["slider_acceleration_rms"] = _with_attrs(np.sqrt((acc ** 2).mean("time")),
                                                     "slider_acceleration_rms")
        out["slider_acceleration_peak_settled"] = _with_attrs(
            abs(settled).max("time"), "slider_acceleration_peak_settled", **settle)
        out["slider_acceleration_rms_settled"] = _with_attrs(
            np.sqrt((settled ** 2).mean("time")), "slider_acceleration_rms_settled", **settle)
    if "normal_force" in ds:
        out["normal_force_peak"] = _with_attrs(ds["normal_force"].max("time"), "normal_force_peak")
    if "wear_map" in ds:
        out["wear_depth_max_final"] = _with_attrs(ds["wear_map"].max(("polar", "azimuth")),
                                                  "wear_depth_max_final")
    if "wear_projection" in ds:
        out.update(wear_table(ds).data_vars)
    for name in SUMMARY_ORDER:
        if name not in out and name in ds:
            out[name] = ds[name]
    summary = xr.Dataset({name: out[name] for name in SUMMARY_ORDER if name in out})
    summary.attrs = dict(ds.attrs)
    return summary


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
        "wear_depth_reduction": _with_attrs(depth, "wear_depth_reduction"),
        "wear_depth_reduction_percent": _with_attrs(depth_percent, "wear_depth_reduction_percent"),
        "wear_range_reduction": _with_attrs(width, "wear_range_reduction"),
        "wear_range_reduction_percent": _with_attrs(width_percent, "wear_range_reduction_percent"),
        "is_reference": _with_attrs(is_reference, "is_reference"),
    }, attrs={"reference": label_text(chosen)})


def metric_table(ds: xr.Dataset, metric: str) -> xr.DataArray:
    """One ``case_summary`` variable over the sweep dimensions.

    Raises
    ------
    SelectionError
        ``metric`` is not a summary variable of ``ds``; the message lists them.
    """
    summary = case_summary(ds)
    if metric not in summary:
        names = [str(n) for n in summary.data_vars]
        raise SelectionError(choice_message("metric", metric, names), name=metric, choices=names)
    return summary[metric]


# --------------------------------------------------------------------------- text reports

def _number(case: xr.Dataset, name: str, spec: str) -> str:
    """``"12.3 m s-2"``, or ``n/a`` when the variable is absent or NaN."""
    if name not in case:
        return _MISSING_TEXT
    value = float(case[name])
    if not np.isfinite(value):
        return _MISSING_TEXT
    units = case[name].attrs.get("units", "")
    text = format(value, spec)
    return f"{text} {units}" if units and units != "1" else text


def run_summary_text(ds: xr.Dataset) -> str:
    """A few lines on a finished run (one block per case for a sweep).

    Example::

        status: ok
        slider acceleration: peak 50 m s-2, RMS 4.625 m s-2; after 0.05 s: peak 3 m s-2, RMS 3 m s-2
        peak normal force: A 40 N, B 120 N
        sub-steps used: 4
        energy residual (relative): 2.50e-06
        wall time: 2 s (40,000 RK4 steps/s, 80,000 steps)
    """
    summary = case_summary(ds)
    blocks = []
    for label, case in iter_cases(summary):
        lines = [f"case {label_text(label)}"] if label else []
        status = value_text(case["status"].values[()]) if "status" in case else _MISSING_TEXT
        lines.append(f"status: {status}")
        lines.append(
            f"slider acceleration: peak {_number(case, 'slider_acceleration_peak', '.4g')}, "
            f"RMS {_number(case, 'slider_acceleration_rms', '.4g')}; after {SETTLE_TIME_S:g} s: "
            f"peak {_number(case, 'slider_acceleration_peak_settled', '.4g')}, "
            f"RMS {_number(case, 'slider_acceleration_rms_settled', '.4g')}")
        if "normal_force_peak" in case:
            forces = ", ".join(
                f"{value_text(j)} {_number(case.sel(joint=j), 'normal_force_peak', '.4g')}"
                for j in case["joint"].values)
            lines.append(f"peak normal force: {forces}")
        lines.append(f"sub-steps used: {_number(case, 'substeps_used', '.0f')}")
        lines.append(f"energy residual (relative): {_number(case, 'energy_residual_relative', '.2e')}")
        wall = f"wall time: {_number(case, 'wall_time', '.3g')}"
        if "rk4_steps" in case and "wall_time" in case:
            steps, seconds = float(case["rk4_steps"]), float(case["wall_time"])
            if np.isfinite(steps) and seconds > 0:
                wall += f" ({steps / seconds:,.0f} RK4 steps/s, {steps:,.0f} steps)"
        lines.append(wall)
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


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
    _Column("wear_depth_axis_max", "Max wear depth", ".4e"),
    _Column("wear_angle_max", "Max wear angle", ".1f"),
    _Column("wear_angle_min", "Min wear angle", ".1f"),
    _Column("wear_range", "Wear range", ".1f"),
    _Column("wear_angle_of_max", "Angle of max depth", ".1f"),
    _Column("wear_arc", "Worn arc", ".1f"),
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


def _cell(value, spec: str) -> str:
    value = _scalar(value)
    if value is None:
        return _MISSING_TEXT
    if isinstance(value, float):
        return format(value, spec)
    return value_text(value)


def _rows(obj: xr.Dataset, dims: tuple[str, ...], names: list[str]) -> list[dict[str, object]]:
    """One dict per point of ``dims``: the coordinates of ``dims``, then the variables ``names``."""
    return [{**keys, **{n: point[n].values[()] for n in names}}
            for keys, point in iter_points(obj, dims)]


def _case_groups(table: xr.Dataset, columns: tuple[_Column, ...], row_dims: tuple[str, ...],
                 keep=None) -> list[_Group]:
    """A group per sweep case, headed by its coordinates (and status where not ``ok``).

    Points that a sweep's ``skip:`` rules left out (status ``skipped``) are not listed.
    """
    groups = []
    for label, case in iter_cases(table):
        if keep is not None and not keep(case):
            continue
        if "status" in case and value_text(case["status"].values[()]) == "skipped":
            continue
        keys = dict(label)
        heading = label_text(label)
        if "status" in case:
            status = value_text(case["status"].values[()])
            keys["status"] = status
            if heading or status != "ok":
                heading = f"{heading} (status: {status})" if heading else f"status: {status}"
        groups.append(_Group(heading, keys, _rows(case, row_dims, [c.name for c in columns])))
    return groups


def _render(title: str, groups: list[_Group], key_names: tuple[str, ...],
            columns: tuple[_Column, ...], units: Mapping[str, str], fmt: str) -> str:
    """Lay groups of rows out as text or markdown blocks, or as one flat csv / json table.

    Parameters
    ----------
    key_names
        Row-key entries of each row (``joint``, ``axis``, sweep dims), printed first.
    units
        Units of each value column, for the headings.
    """
    if fmt not in REPORT_FORMATS:
        raise SelectionError(choice_message("format", fmt, list(REPORT_FORMATS)), name="format",
                             value=fmt, choices=REPORT_FORMATS)

    def heading(c: _Column) -> str:
        return f"{c.heading} [{units[c.name]}]" if units.get(c.name) else c.heading

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
            writer.writerow(["nan" if v is None else repr(v) if isinstance(v, float) else v
                             for v in record.values()])
        return buffer.getvalue().rstrip("\n")

    titles = [_KEY_HEADINGS.get(k, k) for k in key_names] + [heading(c) for c in columns]
    n_keys = len(key_names)
    out = [f"## {title}" if fmt == "markdown" else title]
    for group in groups:
        cells = [[value_text(r[k]) for k in key_names] + [_cell(r[c.name], c.spec) for c in columns]
                 for r in group.rows]
        if fmt == "markdown":
            out.append(f"\n### {group.heading}\n" if group.heading else "")
            out.append("| " + " | ".join(titles) + " |")
            out.append("|" + "|".join("---" if i < n_keys else "---:" for i in range(len(titles))) + "|")
            out.extend("| " + " | ".join(row) + " |" for row in cells)
            continue
        widths = [max(len(t), *(len(row[i]) for row in cells)) for i, t in enumerate(titles)]

        def line(row: list[str]) -> str:
            return "  ".join(c.ljust(w) if i < n_keys else c.rjust(w)
                             for i, (c, w) in enumerate(zip(row, widths))).rstrip()

        out.append(f"\n{group.heading}" if group.heading else "")
        out.append(line(titles))
        out.extend(line(row) for row in cells)
    return "\n".join(out)


def _units(table: xr.Dataset, columns: tuple[_Column, ...]) -> dict[str, str]:
    return {c.name: table[c.name].attrs.get("units", "") for c in columns}


def _with_status(ds: xr.Dataset, table: xr.Dataset) -> xr.Dataset:
    return table.assign(status=ds["status"]) if "status" in ds else table


def format_wear_table(ds: xr.Dataset, fmt: str = "text") -> str:
    """Paper Tables 4-5 as text, markdown, csv or json.

    Columns per joint and wear direction (axis): max wear depth [m], max wear
    angle, min wear angle, wear range and the angle of the maximum depth
    [degree]. Text and markdown print one block per sweep case, headed by its
    coordinates (and its status where not ``ok``); csv and json print one
    flat table with the sweep coordinates and the status as columns.
    """
    table = _with_status(ds, wear_table(ds))
    title = (f"Wear prediction (paper Tables 4-5; wear angles: depth > "
             f"{WEAR_THRESHOLD_FRACTION:g} of the axis maximum)")
    groups = _case_groups(table, _WEAR_COLUMNS, ("joint", "axis"))
    return _render(title, groups, ("joint", "axis"), _WEAR_COLUMNS, _units(table, _WEAR_COLUMNS), fmt)


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
    if "status" in ds and metric != "status":
        table["status"] = ds["status"]
    # like the wear tables: points a sweep's skip rules left out are not listed
    rows = [{**label, **row}
            for label, case in iter_cases(table)
            if "status" not in case or value_text(case["status"].values[()]) != "skipped"
            for row in _rows(case, inner, [metric])]
    keys = tuple(k for k in rows[0] if k != metric)
    return _render(f"{metric} ({column.heading})", [_Group("", {}, rows)], keys, (column,),
                   _units(table, (column,)), fmt)


# --------------------------------------------------------------------------- command line

def open_input(path: str) -> xr.Dataset:
    """Open the results file of a ``report`` or ``plot`` command; a file xarray cannot read
    is a usage error (exit 2), not a traceback."""
    try:
        return xr.open_dataset(path)
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or "no netCDF reader can open it"
        raise click.BadParameter(f"{path!r} is not a results file ({reason})",
                                 param_hint="'PATH'") from None


@click.command("report")
@click.argument("path", type=click.Path(exists=True, dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(REPORT_FORMATS), default="text", show_default=True,
              help="Output format.")
@click.option("--reference", multiple=True, metavar="DIM=VALUE",
              help="Reference case of a sweep (repeatable): print the change of every other case "
                   "against it (paper Table 6).")
@click.option("--metric", default=None, metavar="NAME",
              help="Print this summary metric over the sweep dimensions instead "
                   "(e.g. slider_acceleration_peak).")
def report_command(path: str, fmt: str, reference: tuple[str, ...], metric: str | None) -> None:
    """Print the wear table (paper Tables 4-5) of a results file PATH.

    With --reference, the reduction of the maximum wear depth and the change
    of the wear range against that case (Table 6); with --metric, one summary
    metric over the sweep dimensions.
    """
    if reference and metric:
        raise click.UsageError("--reference and --metric print different tables; give one of them")
    with open_input(path) as ds:
        try:
            if metric:
                text = format_metric_table(ds, metric, fmt)
            elif reference:
                text = format_reduction_table(ds, reference, fmt)
            else:
                text = format_wear_table(ds, fmt)
        except SelectionError as exc:
            raise click.UsageError(str(exc)) from exc
        except ValueError as exc:
            raise click.ClickException(f"{path}: {exc}") from exc
    click.echo(text)
