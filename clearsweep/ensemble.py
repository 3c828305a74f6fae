"""Ensemble statistics: mean, spread and confidence intervals over the ``member`` dimension.

A sweep whose base sets ``ensemble.members > 1`` has a ``member`` dimension
(:mod:`clearsweep.sweeping`). For every numeric summary variable ``X`` of
:func:`clearsweep.summary.case_summary` (timing excluded), :func:`ensemble_statistics`
gives, per design (every other sweep dimension):

- ``X_mean``, ``X_std`` (sample standard deviation, ddof = 1),
- ``X_ci_low``, ``X_ci_high``: the 95 % confidence interval of the mean, Student t:
  mean -+ t(0.975, n - 1) std / sqrt(n),

over the members that ended with status ``ok`` and have a finite value (``n``); members
that stopped with another status are never averaged in: ``members_ok`` counts the
members with status ``ok`` per design, and reports print it beside every mean. With
fewer than two such members the interval is NaN.

Two designs are "not distinguishable" (:func:`welch_interval`) when the 95 % Welch t
interval of the difference of their means contains 0 (docs/physics.md section 10).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable

import numpy as np
import xarray as xr

from .outputs import MEMBER_DIM  # noqa: F401  (the ensemble's dimension, re-exported)
from .summary import PASS_THROUGH_VARIABLES, POINCARE_VARIABLES, SUMMARY_ORDER
from .variables import attrs_for

#: Confidence level of every interval.
CONFIDENCE_LEVEL = 0.95
#: Suffixes of the statistics of a summary variable, in storage order.
SUFFIXES = ("_mean", "_std", "_ci_low", "_ci_high")
CI_METHOD = ("Student t interval of the mean over the members with status ok and a finite "
             "value: mean -+ t(0.975, n - 1) std / sqrt(n), std with ddof = 1")
#: Summary variables that describe the run, not the mechanism, a category (a period in
#: revolutions, whose mean means nothing) or samples (the Poincaré sections, per revolution,
#: whose members start at different crank phases): no statistics.
_EXCLUDED = ("status", "wall_time", "period", *POINCARE_VARIABLES)


def summary_variables(ds: xr.Dataset, dim: str = MEMBER_DIM) -> list[str]:
    """Numeric summary variables of ``ds`` along ``dim`` that get ensemble statistics."""
    names = [n for n in SUMMARY_ORDER if n not in _EXCLUDED and n in ds]
    names += [n for n in PASS_THROUGH_VARIABLES if n not in names and n not in _EXCLUDED and n in ds]
    return [n for n in names if dim in ds[n].dims and ds[n].dtype.kind in "iuf"]


def t_quantile(n, level: float = CONFIDENCE_LEVEL):
    """t(0.5 + level / 2, n - 1); NaN where n < 2 (works on arrays and DataArrays)."""
    from scipy import stats  # imported here: 0.5 s that a plain run does not need

    df = np.asarray(n, dtype=float) - 1.0
    with np.errstate(invalid="ignore"):
        q = stats.t.ppf(0.5 + 0.5 * level, np.where(df >= 1.0, df, np.nan))
    return xr.DataArray(q, dims=n.dims, coords=n.coords) if isinstance(n, xr.DataArray) else q


def members_ok(ds: xr.Dataset, dim: str = MEMBER_DIM) -> xr.DataArray:
    """Per design, the members whose status is ``ok``."""
    ok = ds["status"].astype(str) == "ok"
    count = ok.sum(dim).astype(np.int64)
    count.attrs = attrs_for("members_ok")
    return count.rename("members_ok")


def _stat_attrs(source: dict, what: str, level: float) -> dict:
    attrs = {k: v for k, v in source.items() if k in ("units",)}
    attrs["long_name"] = f"{what} of {source.get('long_name', 'the value')}"
    if what.startswith("ensemble mean") or what.startswith("ensemble standard"):
        attrs["cell_methods"] = f"{MEMBER_DIM}: {'mean' if 'mean' in what else 'standard_deviation'}"
    else:
        attrs["confidence_level"] = level
        attrs["ci_method"] = CI_METHOD
    attrs["members_counted"] = "members with status ok (see members_ok)"
    return attrs


def ensemble_statistics(ds: xr.Dataset, dim: str = MEMBER_DIM,
                        level: float = CONFIDENCE_LEVEL) -> xr.Dataset:
    """Mean, standard deviation and the confidence interval of the mean of every summary
    variable over ``dim`` (module docstring), and ``members_ok``.

    Parameters
    ----------
    ds
        A sweep dataset with ``status`` and the summary variables along ``dim``.

    Returns
    -------
    xr.Dataset
        ``members_ok`` and ``<name>_mean``, ``<name>_std``, ``<name>_ci_low``,
        ``<name>_ci_high`` over the other dimensions, with units and the method in the
        attributes; attributes ``ensemble_confidence_level`` and ``ensemble_ci_method``.
    """
    if dim not in ds.dims:
        raise ValueError(f"no {dim!r} dimension: not an ensemble")
    ok = ds["status"].astype(str) == "ok"
    out: dict[str, xr.DataArray] = {"members_ok": members_ok(ds, dim)}
    for name in summary_variables(ds, dim):
        source = ds[name]
        values = source.astype(float).where(ok)
        n = values.count(dim)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)   # all-NaN designs give NaN
            mean = values.mean(dim, skipna=True)
            std = values.std(dim, ddof=1, skipna=True).where(n >= 2)
        half = t_quantile(n, level) * std / np.sqrt(n.where(n > 0))
        parts = (mean, std, mean - half, mean + half)
        whats = ("ensemble mean", "ensemble standard deviation",
                 f"lower bound of the {level:.0%} confidence interval of the ensemble mean",
                 f"upper bound of the {level:.0%} confidence interval of the ensemble mean")
        for suffix, da, what in zip(SUFFIXES, parts, whats):
            da = da.rename(name + suffix)
            da.attrs = _stat_attrs(source.attrs, what, level)
            out[name + suffix] = da
    result = xr.Dataset(out)
    result.attrs = {"ensemble_confidence_level": level, "ensemble_ci_method": CI_METHOD}
    return result


def half_width(ds: xr.Dataset, name: str) -> xr.DataArray:
    """Half-width of the confidence interval of ``name``'s ensemble mean."""
    return 0.5 * (ds[name + "_ci_high"] - ds[name + "_ci_low"])


def welch_interval(mean1: float, std1: float, n1: int, mean2: float, std2: float, n2: int,
                   level: float = CONFIDENCE_LEVEL) -> tuple[float, float, float]:
    """Difference of two means (2 - 1) and its Welch t confidence interval.

    Welch-Satterthwaite degrees of freedom; two ensembles without spread (std 0) give
    the exact difference as both bounds. NaN bounds when either has fewer than two members.
    """
    return contrast_interval([mean1, mean2], [std1, std2], [n1, n2], [-1.0, 1.0], level)


def contrast_interval(means, stds, counts, weights,
                      level: float = CONFIDENCE_LEVEL) -> tuple[float, float, float]:
    """A contrast sum(w_i m_i) of independent ensemble means and its t confidence interval:
    variance sum(w_i^2 s_i^2 / n_i), Welch-Satterthwaite degrees of freedom (two means with
    weights -1, +1: :func:`welch_interval`). Ensembles without spread give the exact value as
    both bounds; NaN bounds where one has fewer than two members."""
    from scipy import stats  # imported here: 0.5 s that a plain run does not need

    value = float(sum(w * m for w, m in zip(weights, means)))
    if min(counts) < 2 or not all(map(math.isfinite, (*means, *stds))):
        return value, math.nan, math.nan
    parts = [w * w * s * s / n for w, s, n in zip(weights, stds, counts)]
    se2 = sum(parts)
    if se2 == 0.0:
        return value, value, value
    df = se2 ** 2 / sum(v * v / (n - 1) for v, n in zip(parts, counts))
    half = float(stats.t.ppf(0.5 + 0.5 * level, df)) * math.sqrt(se2)
    return value, value - half, value + half


def distinguishable(low: float, high: float) -> bool | None:
    """Whether an interval of a difference excludes 0; None when it is undefined."""
    if not (math.isfinite(low) and math.isfinite(high)):
        return None
    return not (low <= 0.0 <= high)


def statistic_names(names: Iterable[str]) -> list[str]:
    """Every ``<name><suffix>`` of :data:`SUFFIXES` for ``names``."""
    return [n + s for n in names for s in SUFFIXES]
