"""A sweep that switches joints' clearance on and off, read as a two-level factorial design
(docs/mixed_clearances.md): which joint's clearance drives the slider's vibration, which
drives each joint's wear, and whether two clearances together do what each does alone.

A joint is a factor where its clearance (``selection.joint_clearances``) takes two values
along one design dimension, 0 (ideal) and one > 0. Over the other design dimensions (the
other factors and any further axis, such as the speed) every cell counts once:

- the main effect of joint j on a metric: the mean over the cells of (j with clearance) -
  (j ideal);
- the interaction of joints i and j: the mean over the other cells of
  m(i, j) - m(i) - m(j) + m(none), how far the pair's effect is from the sum of each
  alone (0: the effects add).

With an ensemble (a ``member`` dimension) each is formed member by member (every design's
member k draws the same perturbation). Its 95 % interval is value +- h with

    h = sqrt(h_m^2 + h_r^2),
    h_m = t(0.975, n - 1) s / sqrt(n)          (the members' spread: start phase, wear scatter)
    h_r = sqrt(mean over members of d_k^2)     (the run's length and settling)

where s is the standard deviation of the n members' contrasts and d_k is member k's contrast
of the metric's drift (``RUN_LENGTH``: for the settled RMS, ``slider_acceleration_rms_settled_drift``,
the RMS over the second half of the settled window minus that over its first half). h_r is
two standard errors of a settled window's mean where the halves are independent samples of a
steady motion (the whole window's mean has half the standard deviation of the halves'
difference), and bounds the bias of a contrast still settling where its transient falls by at
least 3x from one half to the next. A metric without a drift twin (the worn volume, which
grows with the run by construction) has h = h_m; without members, h = h_r where the drift is
there, else no interval. A drift that is NaN (a settled window under 2 revolutions: no two
whole halves) leaves the effect without an interval: its run-length uncertainty is unknown.

Averaged over a further axis (the speed), an effect whose values at that axis's settings
have opposite signs is also given at each setting (:func:`sign_changes`): the average of a
sign change is not an effect of either setting.
"""

from __future__ import annotations

import itertools
import textwrap

import numpy as np
import xarray as xr

from ..ensemble import distinguishable
from .selection import design_dims, is_ensemble, joint_clearances, value_text

#: A contrast below this fraction of the metric's largest magnitude is rounding: 0.
ROUNDING = 1e-12

#: What the report reads: the slider's vibration, and each joint's wear.
VIBRATION = ("slider_acceleration_rms_settled", "slider RMS acceleration, settled")
WEAR = ("wear_volume", "worn volume")
#: Metric -> its drift between the settled window's halves (``summary.DRIFT_VARIABLES``):
#: the run-length term h_r of the metric's intervals.
RUN_LENGTH = {"slider_acceleration_rms_settled": "slider_acceleration_rms_settled_drift"}


def clearance_factors(ds: xr.Dataset) -> dict[str, tuple[str, int, int]]:
    """Joint name -> (its design dimension, index where ideal, index with clearance), for
    each joint whose clearance is 0 at one position and > 0 at the other of one dimension
    and does not vary along another."""
    clearances = joint_clearances(ds)
    if clearances is None:
        return {}
    dims = design_dims(ds)
    out = {}
    for joint in clearances["joint"].values:
        gap = clearances.sel(joint=joint)
        varying = [d for d in gap.dims if d in dims and gap.sizes[d] > 1
                   and not bool((gap.max(d) == gap.min(d)).all())]
        if len(varying) != 1 or ds.sizes[varying[0]] != 2:
            continue
        d = varying[0]
        values = gap.isel({k: 0 for k in gap.dims if k != d}).values
        if values.min() == 0.0 < values.max():
            out[value_text(joint)] = (d, int(np.argmin(values)), int(np.argmax(values)))
    return out


def _values(ds: xr.Dataset, name: str, joint: str | None) -> xr.DataArray:
    """Metric ``name`` (joint ``joint``'s) of every case, NaN where a case is not ok."""
    values = ds[name]
    if joint is not None:
        values = values.sel(joint=joint)
    if "status" in ds:
        values = values.where(ds["status"].astype(str) == "ok")
    return values


def member_contrasts(ds: xr.Dataset, name: str, joint: str | None,
                     terms: dict[str, tuple[int, int]], factors: dict[str, tuple[str, int, int]],
                     where: dict[str, int] | None = None) -> np.ndarray | None:
    """Each member's contrast of metric ``name`` over the factors in ``terms`` (joint -> (+1
    index, -1 index); the sign of a cell is the product of its terms': a main effect has one
    term, an interaction two), averaged over every cell of the other design dimensions but
    those fixed by ``where`` (dim -> index) and over the cells where every value is finite;
    one value without members, None where no cell has values."""
    values = _values(ds, name, joint)
    where = dict(where or {})
    term_dims = [factors[j][0] for j in terms]
    others = [d for d in design_dims(ds) if d not in term_dims and d not in where]
    total = 0.0
    usable = 0
    for cell in itertools.product(*(range(ds.sizes[d]) for d in others)):
        part = 0.0
        for signs in itertools.product((0, 1), repeat=len(terms)):
            at = dict(where, **dict(zip(others, cell)))
            sign = 1.0
            for (j, (on, off)), s in zip(terms.items(), signs):
                at[factors[j][0]] = on if s else off
                sign *= 1.0 if s else -1.0
            part = part + sign * values.isel(at)
        if not bool(np.isfinite(part).all()):
            continue
        total = total + part
        usable += 1
    if not usable:
        return None
    per_member = np.atleast_1d(np.asarray(total, dtype=float)) / usable
    # what is left of terms that cancel, rounding of the metric's size: 0
    size = float(np.nanmax(np.abs(values.values))) if np.isfinite(values.values).any() else 0.0
    per_member[np.abs(per_member) <= ROUNDING * size] = 0.0
    return per_member


def half_widths(contrasts: np.ndarray, drifts: np.ndarray | None) -> tuple[float, float]:
    """(h_m, h_r) of the module's interval from the members' contrasts and their drifts'
    contrasts (None: the metric has no drift twin, h_r = 0): h_m NaN for fewer than 2
    members; h_r NaN where a drift is not finite."""
    from scipy import stats

    n = contrasts.size
    member = (float(stats.t.ppf(0.975, n - 1) * contrasts.std(ddof=1) / np.sqrt(n))
              if n >= 2 else float("nan"))
    run = 0.0 if drifts is None else float(np.sqrt(np.mean(np.square(drifts))))
    return member, run


def interval(value: float, member: float, run: float) -> tuple[float, float, float]:
    """(value, low, high) of half-width sqrt(member^2 + run^2); a NaN member term (no
    members) leaves the run term alone, or no interval without one."""
    if not np.isfinite(member):
        if not run > 0.0:
            return value, float("nan"), float("nan")
        member = 0.0
    half = float(np.hypot(member, run))
    return value, value - half, value + half


def contrast_parts(ds: xr.Dataset, name: str, joint: str | None,
                   terms: dict[str, tuple[int, int]], factors: dict[str, tuple[str, int, int]],
                   where: dict[str, int] | None = None):
    """(value, h_m, h_r) of the contrast (:func:`member_contrasts`), or None where no cell
    has values; h_m NaN without members."""
    per_member = member_contrasts(ds, name, joint, terms, factors, where)
    if per_member is None:
        return None
    drifts = None
    if name in RUN_LENGTH and RUN_LENGTH[name] in ds:
        drifts = member_contrasts(ds, RUN_LENGTH[name], joint, terms, factors, where)
        if drifts is None or drifts.size != per_member.size:
            drifts = np.full(per_member.size, np.nan)
    member, run = half_widths(per_member, drifts)
    if not is_ensemble(ds):
        member = float("nan")
    return float(per_member.mean()), member, run


def contrast(ds: xr.Dataset, name: str, joint: str | None, terms: dict[str, tuple[int, int]],
             factors: dict[str, tuple[str, int, int]], where: dict[str, int] | None = None):
    """The contrast of metric ``name`` over the factors in ``terms`` (:func:`member_contrasts`)
    with its 95 % interval: an ensemble's members draw the same perturbation in every design
    (``params.member_perturbation``: the seed and the member number alone), so the contrast
    is formed member by member (paired: the scatter common to the designs cancels), and the
    interval's half-width combines the members' spread with the run-length term (the module's
    formula). Returns (value, low, high), NaN bounds without either term, or None where no
    cell has values."""
    parts = contrast_parts(ds, name, joint, terms, factors, where)
    if parts is None:
        return None
    return interval(*parts)


def sign_changes(ds: xr.Dataset, name: str, joint: str | None,
                 terms: dict[str, tuple[int, int]], factors: dict[str, tuple[str, int, int]],
                 where: dict[str, int] | None = None) -> dict[str, list[tuple[str, tuple]]]:
    """For each design dimension that is no factor (the speed) and not fixed by ``where``:
    the contrast at each of its settings (setting's text, (value, low, high)), where the
    values have opposite signs (one above 0 and one below); dimensions without a sign
    change are left out."""
    where = dict(where or {})
    factor_dims = {f[0] for f in factors.values()}
    out = {}
    for dim in design_dims(ds):
        if dim in factor_dims or dim in where or ds.sizes[dim] < 2:
            continue
        found = [contrast(ds, name, joint, terms, factors, dict(where, **{dim: k}))
                 for k in range(ds.sizes[dim])]
        values = [f[0] for f in found if f is not None]
        if any(v > 0.0 for v in values) and any(v < 0.0 for v in values):
            coordinate = ds[dim].values
            out[dim] = [(value_text(coordinate[k]), f) for k, f in enumerate(found) if f is not None]
    return out


def _effect_text(found: tuple[float, float, float], units: str) -> str:
    """``+0.16 [+0.124, +0.196] m s-2``, and whether the interval holds 0."""
    value, low, high = found
    verdict = distinguishable(low, high)
    interval = f" [{low:+.3g}, {high:+.3g}]" if np.isfinite(low) else ""
    tail = {True: "", False: ", within the spread", None: ""}[verdict]
    return f"{value:+.3g}{interval} {units}{tail}".rstrip()


def metrics(ds: xr.Dataset, factors: dict[str, tuple[str, int, int]]) -> list[tuple[str, str | None]]:
    """What the design is read for: (variable, joint or None) of the slider's vibration,
    then each factor joint's worn volume (where the file has it)."""
    out: list[tuple[str, str | None]] = [(VIBRATION[0], None)]
    if WEAR[0] in ds:
        out += [(WEAR[0], j) for j in factors]
    return out


def main_effects(ds: xr.Dataset, name: str, joint: str | None,
                 factors: dict[str, tuple[str, int, int]]) -> dict[str, tuple[float, float, float]]:
    """Each other factor joint's effect (:func:`contrast`) on metric ``name`` of ``joint``
    (None: a metric of the mechanism); a joint's own wear is read where it has clearance,
    its own factor held on, and is not an effect of itself."""
    # a joint's wear exists where it has clearance: its own factor held on
    where = {factors[joint][0]: factors[joint][2]} if joint else {}
    effects = {}
    for j in factors:
        if j == joint:
            continue
        found = contrast(ds, name, joint, {j: (factors[j][2], factors[j][1])}, factors, where)
        if found is not None:
            effects[j] = found
    return effects


def _sign_change_lines(changes: dict[str, list[tuple[str, tuple]]], units: str,
                      indent: str) -> list[str]:
    """The lines giving a contrast at each setting of the dimensions where it changes sign."""
    lines = []
    for dim, found in changes.items():
        lines.append(f"{indent}its sign changes with {dim}; at each:")
        lines += [f"{indent}  {dim} {setting}: {_effect_text(f, units)}" for setting, f in found]
    return lines


def factorial_lines(ds: xr.Dataset) -> list[str]:
    """The report's section on a clearance factorial design (empty without two factors)."""
    factors = clearance_factors(ds)
    if len(factors) < 2 or VIBRATION[0] not in ds:
        return []
    names = list(factors)
    rest = [d for d in design_dims(ds) if d not in {f[0] for f in factors.values()}]
    over = f" and over {', '.join(rest)}" if rest else ""
    ensemble = is_ensemble(ds)
    source = "the members' spread" + (", and for the vibration the run's length (the settled "
                                      "window's halves)" if RUN_LENGTH[VIBRATION[0]] in ds else "")
    head = (f"Clearance as a two-level design over joints {', '.join(names)}: effects averaged over "
            f"the other joints' settings{over}" + (f" (95 % intervals: {source})" if ensemble else "")
            + ":")
    lines = ["", *textwrap.wrap(head, width=100, subsequent_indent="  ")]
    for name, joint in metrics(ds, factors):
        units = ds[name].attrs.get("units", "")
        label = f"{WEAR[1]} at {joint}" if joint else VIBRATION[1]
        lines.append(f"  {label} [{units}]" + (f" (cases with clearance at {joint})" if joint else "")
                     + ":")
        effects = main_effects(ds, name, joint, factors)
        where = {factors[joint][0]: factors[joint][2]} if joint else {}
        for j, found in effects.items():
            lines.append(f"    clearance at {j}: {_effect_text(found, units)}")
            lines += _sign_change_lines(
                sign_changes(ds, name, joint, {j: (factors[j][2], factors[j][1])}, factors, where),
                units, "      ")
        standing = {k: v for k, v in effects.items() if distinguishable(v[1], v[2]) is not False}
        if standing:
            top = max(standing, key=lambda k: abs(standing[k][0]))
            lines.append(f"    largest effect: clearance at {top}")
        elif effects:
            lines.append("    no joint's clearance changes it beyond the members' spread")
        for a, b in itertools.combinations([j for j in names if j != joint], 2):
            terms = {a: (factors[a][2], factors[a][1]), b: (factors[b][2], factors[b][1])}
            found = contrast(ds, name, joint, terms, factors, where)
            if found is None:
                continue
            word = {True: "they do not add", False: "they add", None: ""}[distinguishable(*found[1:])]
            lines.append(f"    {a} and {b} together minus each alone: "
                         f"{_effect_text(found, units).replace(', within the spread', '')}"
                         + (f"; {word}" if word else ""))
            lines += _sign_change_lines(sign_changes(ds, name, joint, terms, factors, where),
                                        units, "      ")
    return lines
