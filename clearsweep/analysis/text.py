"""Text reports of a results dataset: a finished run's summary lines and a sweep's
headline summary (its design axes, best and worst design per metric)."""

from __future__ import annotations

import collections
import math
import textwrap
from typing import Any

import numpy as np
import xarray as xr

from ..ensemble import MEMBER_DIM
from ..jointtypes import elastic
from ..motion import CHAOS_THRESHOLD, HIGH_ORDER, MAX_PERIOD, PERIOD_NONE, PERIOD_UNKNOWN
from ..outputs import SAMPLE_DIM  # noqa: F401
from ..summary import (
    OSCILLATION_CREST_FACTOR,
    PEAK_BY_IMPACTS,
    PEAK_BY_LOAD,
    PEAK_BY_OSCILLATION,
    case_summary,
    settle_time,
    settled_revolutions,
)
from .factorial import factorial_lines
from .selection import (
    _MISSING_TEXT,
    design_dims,
    is_ensemble,
    iter_cases,
    iter_points,
    joint_clearances,
    label_text,
    quantity_unit,
    value_text,
)
from .tables import report_summary

# --------------------------------------------------------------------------- text reports

def short_settled_window(ds: xr.Dataset) -> str | None:
    """What ``report`` warns of where a case's settled window holds less than one crank
    revolution (its settled statistics then cover part of a cycle), else None.

    One line for the file: the window of a run, or how many designs of a sweep (an
    ensemble's members share their design's window) and the shortest.
    """
    dims = design_dims(ds)
    frame = xr.Dataset(coords={n: c for n, c in ds.coords.items() if set(c.dims) <= set(dims)},
                       attrs=ds.attrs)
    short, cases = [], 0
    for label, case in iter_points(frame, dims):
        cases += 1
        revolutions = settled_revolutions(case)
        if revolutions < 1.0:
            short.append((revolutions, label, settle_time(case)))
    if not short:
        return None
    fewest, label, start = min(short, key=lambda item: item[0])
    held = f"{max(fewest, 0.0):.3g} crank revolution{'' if fewest == 1 else 's'}"
    where = (f"the settled window (t >= {start:g} s) holds {held}" if not dims else
             f"the settled window holds less than one crank revolution in {len(short)} of {cases} "
             f"designs (fewest: {held}, t >= {start:g} s, at {label_text(label)})")
    return (f"{where}: its statistics cover part of a cycle; set metrics.settle_revolutions "
            "and solver.revolutions for whole revolutions (docs/runs.md)")


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


def _pair(case: xr.Dataset, name: str, spec: str = ".4g") -> str:
    """``"settled (whole run)"`` of a statistic and its ``_settled`` twin."""
    return f"{_number(case, name + '_settled', spec)} ({_number(case, name, spec)})"


def run_summary_text(ds: xr.Dataset) -> str:
    """A few lines on a finished run (one block per case for a sweep).

    Example::

        status: ok
        every-step statistics, settled (t >= 0.05 s), whole run in brackets:
          slider acceleration: peak 3 m s-2 (50 m s-2), RMS 3 m s-2 (4.625 m s-2)
          crank torque: peak 2 N m (2.5 N m)
          peak normal force: A 40 N (45 N), B 120 N (130 N)
          impacts: A 3 (4), B 0 (0)
          contact fraction: A 0.9 (0.91), B 1 (1)
        sub-steps used: 4
        energy residual (relative): 2.50e-06
        wall time: 2 s (40,000 RK4 steps/s, 80,000 steps)
    """
    summary = report_summary(ds)
    blocks = []
    for label, case in iter_cases(summary):
        lines = [f"case {label_text(label)}"] if label else []
        status = value_text(case["status"].values[()]) if "status" in case else _MISSING_TEXT
        lines.append(f"status: {status}")
        settle = ds.attrs.get("settle_time_s")
        window = f"t >= {float(settle):g} s" if settle is not None else "settled"
        lines.append(f"every-step statistics, settled ({window}), whole run in brackets:")
        lines.append(
            f"  slider acceleration: peak {_pair(case, 'slider_acceleration_peak')}, "
            f"RMS {_pair(case, 'slider_acceleration_rms')}")
        lines.append(f"  crank torque: peak {_pair(case, 'crank_torque_peak')}")
        if "normal_force_peak" in case:
            for heading, name, spec in (("peak normal force", "normal_force_peak", ".4g"),
                                      ("impacts", "impact_count", ".0f"),
                                      ("contact fraction", "contact_fraction", ".3f")):
                if name not in case:
                    continue
                values = ", ".join(f"{value_text(j)} {_pair(case.sel(joint=j), name, spec)}"
                                   for j in case["joint"].values)
                lines.append(f"  {heading}: {values}")
        if "peak_force_source" in case and case["peak_force_source"].ndim == 0:
            lines.append(f"  peak force set by: {value_text(case['peak_force_source'].values[()])}")
        lines += _run_motion_lines(case)
        lines += _bushing_lines(ds)
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


def _period_text(period: int) -> str:
    if period == PERIOD_UNKNOWN:
        return "undetermined (fewer than 2 settled revolutions)"
    if period == PERIOD_NONE:
        return f"non-periodic (no period up to {MAX_PERIOD} revolutions)"
    return f"periodic, period {period}"


def _bushing_lines(ds: xr.Dataset) -> list[str]:
    """One line per joint that ran as an elastic bushing (its ``joint_<J>_type``
    attribute, ``clearsweep.params.joint_attributes``): its stiffness and damping, and its
    largest deflection where the run kept the joints' offsets."""
    lines = []
    for key, value in ds.attrs.items():
        if not (key.startswith("joint_") and key.endswith("_type") and elastic(value_text(value))):
            continue
        name = key[len("joint_"):-len("_type")]
        k, c = ([float(ds.attrs.get(f"joint_{name}_bushing_{way}_{what}", math.nan))
                 for way in ("radial", "axial")]
                for what in ("stiffness_N_per_m", "damping_N_s_per_m"))
        text = (f"joint {name}: bushing, stiffness {k[0]:.4g} / {k[1]:.4g} N m-1, damping "
                f"{c[0]:.4g} / {c[1]:.4g} N s m-1 (radial / axial)")
        if "eccentricity" in ds and "joint" in ds["eccentricity"].dims:
            peak = float(ds["eccentricity"].sel(joint=name).max())
            text += f"; largest deflection {peak:.3g} m"
        lines.append(text)
    return lines


def bushing_text(ds: xr.Dataset) -> str:
    """The lines of :func:`_bushing_lines` (the joints that ran as bushings), or ''."""
    return "\n".join(_bushing_lines(ds))


def _run_motion_lines(case: xr.Dataset) -> list[str]:
    """A run's spectrum and periodicity lines (docs/physics.md section 11), where it has them."""
    lines = []
    if "slider_acceleration_dominant_order" in case:
        dominant = float(case["slider_acceleration_dominant_order"])
        share = float(case["slider_acceleration_high_order_share"])
        lines.append("slider acceleration spectrum (settled): " + (
            f"dominant crank order {dominant:.3g}, {100.0 * share:.3g} % of the power above "
            f"order {HIGH_ORDER:g}" if np.isfinite(dominant)
            else "n/a (fewer than 2 crank revolutions in the settled window)"))
    if "period" in case:
        k = float(case["chaos_k"]) if "chaos_k" in case else math.nan
        test = (f"0-1 test K = {k:.2f}" if np.isfinite(k)
                else "0-1 test: n/a (fewer settled revolutions than it needs)")
        if "lyapunov_exponent" in case:
            lam = float(case["lyapunov_exponent"])
            test += ("; largest Lyapunov exponent " + (f"{lam:+.3f} per revolution" if np.isfinite(lam)
                                                       else "n/a (the run is too short, or a twin run stopped)"))
        line = f"motion (period in crank revolutions): {_period_text(int(case['period']))}; {test}"
        if "motion_class" in case:
            line += f"; class: {case['motion_class'].item()}"
        lines.append(line)
    return lines


#: Designs a motion line of the sweep summary names before it counts the rest, and the
#: width its lines are wrapped to.
MOTION_CASES_LISTED = 8
REPORT_LINE_CHARACTERS = 100


def _sweep_motion_lines(ds: xr.Dataset, summary: xr.Dataset, usable, dims: tuple[str, ...]) -> list[str]:
    """The sweep summary's periodic and chaotic designs, from ``period`` and ``chaos_k``."""
    if "period" not in summary or not dims:
        return []
    groups: dict[tuple[int, str], list[str]] = {}
    for label, point in iter_points(summary["period"], dims):
        index = {d: label[d] for d in dims}
        if not bool(usable.sel(index) if index else usable):
            continue
        period = int(point)
        k = float(summary["chaos_k"].sel(index)) if "chaos_k" in summary else math.nan
        design = _design_text(ds, label)
        lam = (float(summary["lyapunov_exponent"].sel(index)) if "lyapunov_exponent" in summary
               else math.nan)
        if period == PERIOD_NONE and np.isfinite(lam) and "motion_class" in summary:
            key = (f"non-periodic, {summary['motion_class'].sel(index).item()} by the Lyapunov "
                   "exponent and the 0-1 test")
            design += f" (lambda = {lam:+.3f}/rev, K = {k:.2f})"
        elif period == PERIOD_NONE and np.isfinite(k):
            chaotic = k > CHAOS_THRESHOLD
            key = (f"non-periodic, {'chaotic' if chaotic else 'regular'} by the 0-1 test "
                   f"(K {'>' if chaotic else '<='} {CHAOS_THRESHOLD:g})")
            design += f" (K = {k:.2f})"
        elif period == PERIOD_NONE:
            key = _period_text(period) + ", 0-1 test n/a (too few revolutions)"
        else:
            key = _period_text(period)
        order = period if period > 0 else MAX_PERIOD + 2 - period     # periodic first, by n
        groups.setdefault((order, key), []).append(design)
    if not groups:
        return []
    lines = ["", "Motion (settled Poincaré samples; periods in crank revolutions):"]
    for order, key in sorted(groups):
        designs = groups[(order, key)]
        listed = ", ".join(designs[:MOTION_CASES_LISTED])
        more = len(designs) - MOTION_CASES_LISTED
        line = (f"- {key}: {len(designs)} design{'s' if len(designs) > 1 else ''}: {listed}"
                + (f" and {more} more" if more > 0 else ""))
        lines += textwrap.wrap(line, REPORT_LINE_CHARACTERS, subsequent_indent="    ",
                               break_on_hyphens=False)
    return lines


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of each run of consecutive True in ``flags``."""
    runs: list[tuple[int, int]] = []
    for i in np.flatnonzero(flags):
        if runs and runs[-1][1] == i - 1:
            runs[-1] = (runs[-1][0], int(i))
        else:
            runs.append((int(i), int(i)))
    return runs


def _coordinate_text(ds: xr.Dataset, dim: str, first: int, last: int) -> str:
    """``"speed_rpm 80-95 r/min"``, ``"B_clearance 0.25 mm"``: a dimension's values from
    ``first`` to ``last`` in its quantity's unit, as the figures write them
    (:data:`QUANTITY_UNITS`: a clearance in mm, a speed in r/min)."""
    values = ds[dim].values
    factor, units = quantity_unit(ds[dim])

    def number(value) -> str:
        if factor == 1.0 or not isinstance(value, (int, float, np.number)):
            return value_text(value)
        return value_text(float(value) / factor)

    span = number(values[first]) + ("" if first == last else f"-{number(values[last])}")
    return f"{dim} {span}" + (f" {units}" if units else "")


def _periodic_window_lines(ds: xr.Dataset, summary: xr.Dataset, usable,
                           dims: tuple[str, ...]) -> list[str]:
    """A two-key grid's periodic windows (a dynamics map, ``plot --kind dynamics-map``): one
    line per period found, the ranges of its cells along the first key at each value of the
    second; cases whose status is not ok are left out."""
    varying = [d for d in dims if ds.sizes[d] > 1]
    if "period" not in summary or len(varying) != 2 or len(dims) != 2:
        return []
    if not all(d in ds.coords for d in varying):
        return []
    y, x = varying          # the ranges run along the last dimension of the data
    period = summary["period"].transpose(y, x).values
    ok = np.broadcast_to(np.asarray(usable.broadcast_like(summary["period"]).transpose(y, x)
                                    if getattr(usable, "ndim", 0) else usable, dtype=bool),
                         period.shape)
    found = sorted({int(p) for p, good in zip(period.ravel(), ok.ravel()) if good and p > 0})
    lines = ["", *textwrap.wrap(f"Periodic windows over {x} x {y} (periods in crank "
                                "revolutions; --kind dynamics-map draws the map):",
                                REPORT_LINE_CHARACTERS, break_on_hyphens=False)]

    def cells(flags: np.ndarray) -> str:
        parts = []
        for row in range(flags.shape[0]):
            runs = _runs(flags[row] & ok[row])
            if runs:
                spans = ", ".join(_coordinate_text(ds, x, a, b) for a, b in runs)
                parts.append(f"{_coordinate_text(ds, y, row, row)}: {spans}")
        return "; ".join(parts)

    if not found:
        lines.append(f"- none: no case has a period up to {MAX_PERIOD}")
    for p in found:
        lines += textwrap.wrap(f"- period {p}: " + cells(period == p), REPORT_LINE_CHARACTERS,
                               subsequent_indent="    ", break_on_hyphens=False)
    if "motion_class" in summary and summary["motion_class"].dims == summary["period"].dims:
        # the cells without a period, by the class the two chaos indicators give them
        classes = summary["motion_class"].transpose(y, x).values.astype(str)
        for name in sorted({str(c) for c, p, good in zip(classes.ravel(), period.ravel(), ok.ravel())
                            if good and p <= 0}):
            lines += textwrap.wrap(f"- {name}: " + cells((classes == name) & (period <= 0)),
                                   REPORT_LINE_CHARACTERS, subsequent_indent="    ",
                                   break_on_hyphens=False)
    return lines


# --------------------------------------------------------------------------- sweep summary

#: Headline metrics of a sweep's summary, in order (lower is better for each); a settled
#: statistic gives way to its whole-run twin where every run ends before the settled window.
HEADLINE_METRICS = ("slider_acceleration_rms_settled", "slider_acceleration_peak_settled",
                    "crank_torque_peak_settled", "normal_force_peak_settled",
                    "wear_depth_max_final", "wear_volume")


def _axis_line(ds: xr.Dataset, dim: str) -> str:
    """``  B_clearance (radial clearance of joint B) [m]: 5e-05, 0.0001 (6 values)``"""
    coord = ds[dim] if dim in ds.coords else None
    if coord is None:
        return f"  {dim}: {ds.sizes[dim]} positions"
    long_name = coord.attrs.get("long_name", "")
    units = coord.attrs.get("units", "")
    head = f"  {dim}" + (f" ({long_name})" if long_name and not long_name.startswith("sweep zip")
                         else "") + (f" [{units}]" if units else "")
    values = [value_text(v) for v in coord.values]
    text = ", ".join(values[:8]) + (f", ... ({len(values)} values)" if len(values) > 8 else "")
    companions = [n for n, c in ds.coords.items() if n != dim and c.dims == (dim,)]
    for name in companions:
        unit = ds[name].attrs.get("units", "")
        text += (f"; {name}{f' [{unit}]' if unit else ''}: "
                 + ", ".join(value_text(v) for v in ds[name].values[:8]))
    return f"{head}: {text}"


def _headline_values(ds: xr.Dataset, name: str, ensemble: bool) -> tuple[str, Any, Any] | None:
    """(variable shown, values, 95 % half-widths or None) of a headline metric, its settled
    statistic falling back to the whole run's; None when the file lacks both."""
    source = ds if ensemble else case_summary(ds)
    for candidate in (name, name.removesuffix("_settled")):
        if ensemble:
            if candidate + "_mean" not in ds:
                continue
            values = ds[candidate + "_mean"]
            half = 0.5 * (ds[candidate + "_ci_high"] - ds[candidate + "_ci_low"])
        else:
            if candidate not in source:
                continue
            values, half = source[candidate], None
        if bool(np.isfinite(values.values.astype(float)).any()):
            return candidate, values, half
    return None


def _metric_title(ds: xr.Dataset, shown: str, values: xr.DataArray, joint: str | None) -> str:
    long_name = (ds[shown].attrs.get("long_name") if shown in ds
                 else values.attrs.get("long_name")) or shown
    units = values.attrs.get("units", "")
    settle = ds.attrs.get("settle_time_s")
    if shown.endswith("_settled"):
        where = f", t >= {float(settle):g} s" if settle is not None else ""
    elif shown + "_settled" in HEADLINE_METRICS:
        where = ", whole run (the runs end before the settled window)"
    else:
        where = ""
    at = f", joint {joint}" if joint else ""
    return f"{long_name}{at}{where}" + (f" [{units}]" if units and units != "1" else "")


def _ranked(values: xr.DataArray, half: xr.DataArray | None, usable: xr.DataArray,
            dims: tuple[str, ...]) -> list[tuple[float, float, dict]]:
    """(value, half-width, design label) of every usable design with a finite value."""
    out = []
    for label, point in iter_points(values, dims):
        index = {d: label[d] for d in dims}
        if not bool(usable.sel(index) if index else usable):
            continue
        value = float(point)
        if math.isfinite(value):
            width = float(half.sel(index) if index else half) if half is not None else math.nan
            out.append((value, width, label))
    return sorted(out, key=lambda r: r[0])


def _design_text(ds: xr.Dataset, label: dict) -> str:
    """A design by its label and, along a dimension whose label is only a position (a
    ``sample:`` sweep's point number), by the inputs it carries as coordinates:
    ``sample=45 (B_clearance=0.000312, speed_rpm=52.3)``."""
    inputs = []
    for dim, value in label.items():
        if dim in ds.indexes and dim != SAMPLE_DIM:     # labelled by its values (grid, zip labels)
            continue
        at = {dim: value} if dim in ds.indexes else {dim: int(value)}
        for name, coord in ds.coords.items():
            if name != dim and coord.dims == (dim,):
                item = (coord.sel(at) if dim in ds.indexes else coord.isel(at)).values[()]
                text = f"{item:.4g}" if isinstance(item, float | np.floating) else value_text(item)
                inputs.append(f"{name}={text}")
    return label_text(label) + (f" ({', '.join(inputs)})" if inputs else "")


def _peak_contact_force(summary: xr.Dataset) -> xr.DataArray | None:
    """Each case's largest peak normal contact force [N] over its joints (an ideal joint has
    none: NaN), of the settled window where the case has one, else of the whole run."""
    whole = summary.get("normal_force_peak")
    settled = summary.get("normal_force_peak_settled")
    force = whole if settled is None else (settled if whole is None else settled.fillna(whole))
    if force is None or "joint" not in force.dims:
        return None
    return force.max("joint", skipna=True)


def drivers_line(ds: xr.Dataset, summary: xr.Dataset, usable, dims: tuple[str, ...]) -> str | None:
    """One line saying what drives the differences between a sweep's designs, built on each
    case's ``peak_force_source`` (:func:`clearsweep.summary.peak_force_source`): the source
    of the design with the highest peak contact force. ``impacts`` where it impacts;
    ``friction`` where it rides its socket in an in-contact oscillation (no impact, a crest
    factor above the threshold: docs/physics.md section 3.3); else ``nothing beyond the
    spread``, every design quasi-static and the peak forces no further apart than the
    mechanism's load makes them. None without the statistics or the sweep dimensions."""
    source, force = summary.get("peak_force_source"), _peak_contact_force(summary)
    if source is None or force is None or not dims:
        return None
    cases = []
    for label, point in iter_points(source, dims):
        index = {d: label[d] for d in dims}
        value = float(force.sel(index))
        if bool(usable.sel(index) if index else usable) and math.isfinite(value):
            cases.append((value, str(point.values[()]), label))
    if not cases:
        return None
    kinds = collections.Counter(text.split(" (")[0] for _, text, _ in cases)
    top, top_source, top_at = max(cases, key=lambda c: c[0])
    quiet = [f for f, text, _ in cases if text == PEAK_BY_LOAD]
    n = len(cases)

    def tally(kind: str) -> str:
        return f"{kinds[kind]} of {n} designs"

    def load_range() -> str:
        if not quiet:
            return "no design is quasi-static"
        return (f"the quasi-static designs reach {min(quiet):.4g}-{max(quiet):.4g} N" if
                len(quiet) > 1 else f"the quasi-static design reaches {quiet[0]:.4g} N")

    head = "What drives the differences between designs:"
    where = f"{top:.4g} N at {_design_text(ds, top_at)}"
    if top_source.startswith(PEAK_BY_IMPACTS):
        joints = sorted({j for _, text, _ in cases if text.startswith(PEAK_BY_IMPACTS)
                         for j in text.split("(")[1].rstrip(")").split(", ")})
        return (f"{head} impacts. {tally(PEAK_BY_IMPACTS)} impact (joint"
                f"{'s' if len(joints) > 1 else ''} {', '.join(joints)}) and set the highest "
                f"peak contact force, {where}; "
                f"{load_range()}.")
    if top_source.startswith(PEAK_BY_OSCILLATION):
        impacts = (f"{tally(PEAK_BY_IMPACTS)} impact, below it" if kinds[PEAK_BY_IMPACTS]
                   else "no design impacts")
        return (f"{head} friction. {tally(PEAK_BY_OSCILLATION)} stay in contact in a "
                f"friction-driven oscillation (crest factor above {OSCILLATION_CREST_FACTOR:g}) "
                f"and set the highest peak contact force, {where}; {impacts}; {load_range()}.")
    low = min(c[0] for c in cases)
    apart = (f"{100.0 * (top - low) / low:.2g} % apart" if low > 0 else "")
    others = "".join(f"; {tally(k)} {'impact' if k == PEAK_BY_IMPACTS else 'oscillate'}, "
                     "below it" for k in (PEAK_BY_IMPACTS, PEAK_BY_OSCILLATION) if kinds[k])
    return (f"{head} nothing beyond the spread. The highest peak contact force is the "
            f"quasi-static load, {where}{others}; peak contact forces {low:.4g}-{top:.4g} N"
            + (f" ({apart})" if apart else "") + ".")


def format_sweep_summary(ds: xr.Dataset, fmt: str = "text") -> str:
    """What a sweep answers, first: its design axes and, per headline metric, the lowest
    (best) and highest (worst) design and their spread; an ensemble's means with the
    half-width of their 95 % interval, and whether best and worst are distinguishable.

    Per-joint metrics leave out the cases where the joint is ideal (no clearance), and every
    metric the cases whose status is not ``ok`` (an ensemble: designs without a member ok).
    """
    from ..ensemble import distinguishable, welch_interval

    ensemble = is_ensemble(ds)
    dims = design_dims(ds)
    status = ds["status"].astype(str) if "status" in ds else None
    n = int(np.prod([ds.sizes[d] for d in dims])) if dims else 1
    if ensemble:
        usable = ds["members_ok"] > 0
        counted = f"{n} designs x {ds.sizes[MEMBER_DIM]} members"
    else:
        usable = (status == "ok") if status is not None else xr.DataArray(True)
        counted = f"{n} cases"
    if status is not None:
        tally = collections.Counter(status.values.ravel().tolist())
        counted += " (" + ", ".join(f"{k} {v}" for k, v in sorted(tally.items(),
                                                                  key=lambda kv: kv[0] != "ok")) + ")"
    name = ds.attrs.get("sweep_name", "")
    lines = [f"Sweep {name + ': ' if name else ''}{counted}; design axes:"]
    lines += [_axis_line(ds, d) for d in dims]
    lines.append("")
    lines.append("Headline metrics, lowest (best) and highest (worst) design"
                 + ("\n(ensemble mean +- half-width of its 95% interval)" if ensemble else "") + ":")
    clearances = joint_clearances(ds)
    for metric in HEADLINE_METRICS:
        found = _headline_values(ds, metric, ensemble)
        if found is None:
            continue
        shown, values, half = found
        joints = [value_text(j) for j in values["joint"].values] if "joint" in values.dims else [None]
        for joint in joints:
            v, h, ok = values, half, usable
            if joint is not None:
                v = values.sel(joint=joint)
                h = half.sel(joint=joint) if half is not None else None
                if clearances is not None:
                    gap = clearances.sel(joint=joint)
                    ok = ok & xr.DataArray(gap.values > 0, dims=gap.dims)
            ranked = _ranked(v, h, ok, dims)
            if not ranked:
                continue
            (low, low_h, low_at), (high, high_h, high_at) = ranked[0], ranked[-1]
            units = values.attrs.get("units", "")
            units = "" if units == "1" else f" {units}"
            spread = f"spread {high - low:.3g}{units}"
            if low > 0:
                spread += (f" (highest = {high / low:.3g} x lowest)" if high >= 2.0 * low
                           else f" ({100.0 * (high - low) / low:.2g} % of the lowest)")
            if ensemble and len(ranked) > 1:
                n_low = int(ds["members_ok"].sel({d: low_at[d] for d in dims}))
                n_high = int(ds["members_ok"].sel({d: high_at[d] for d in dims}))
                std = ds[shown + "_std"] if joint is None else ds[shown + "_std"].sel(joint=joint)
                s_low = float(std.sel({d: low_at[d] for d in dims}))
                s_high = float(std.sel({d: high_at[d] for d in dims}))
                _, lo, hi = welch_interval(low, s_low, n_low, high, s_high, n_high)
                verdict = {True: "distinguishable", False: "not distinguishable",
                           None: "not tested (fewer than 2 members)"}[distinguishable(lo, hi)]
                spread += f"; lowest vs highest: {verdict}"

            def shown_value(value: float, width: float) -> str:
                return f"{value:.4g}" + (f" +- {width:.2g}" if math.isfinite(width) else "")

            lines.append(f"- {_metric_title(ds, shown, values, joint)}")
            if len(ranked) == 1 or low == high:
                lines.append(f"    all {len(ranked)} equal: {shown_value(low, low_h)}")
                continue
            for word, value, width, at in (("lowest ", low, low_h, low_at),
                                           ("highest", high, high_h, high_at)):
                # a design of many axes continues under itself: lines of at most 100
                lines += textwrap.wrap(f"    {word} {shown_value(value, width):>16}  "
                                       f"{_design_text(ds, at)}", width=100,
                                       subsequent_indent=" " * 30, break_on_hyphens=False)
            lines.append(f"    {spread}")
    if not ensemble:
        summary = report_summary(ds)
        driver = drivers_line(ds, summary, usable, dims)
        if driver is not None:
            lines.append("")
            lines += textwrap.wrap(driver, REPORT_LINE_CHARACTERS, subsequent_indent="    ",
                                   break_on_hyphens=False)
        lines += _sweep_motion_lines(ds, summary, usable, dims)
        lines += _periodic_window_lines(ds, summary, usable, dims)
    lines += factorial_lines(ds)
    lines.append("")
    lines.append("Every case's tables: --full (text), or --format csv / json.")
    text = "\n".join(lines)
    if fmt == "markdown":
        return "## Summary\n\n```text\n" + text + "\n```"
    return text

