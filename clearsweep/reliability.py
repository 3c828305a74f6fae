"""Reliability over service life (docs/reliability.md): the probability that a design
survives N crank revolutions, and which scatter decides it.

A sweep with ``store: reliability`` runs every design as ``reliability.members`` life runs
(:func:`clearsweep.service_life.life`). Member m draws, from ``(reliability.seed, m)``
only, the inputs a manufacturer cannot pin down: each clearance joint's initial radial
clearance in its tolerance band, the wear coefficient of its socket surface and its
coating thickness (lognormal factors of mean 1), and the crank speed (:func:`member_draws`,
:func:`member_config`). A member runs on until every limit it watches is reached or
``life.cycles``; a limit not reached by then is right-censored at the revolutions
reached, never a failure there (:func:`reliability_summary`).

Per design and limit (and "any"), :func:`reliability_estimate` gives the Kaplan-Meier
reliability R(N) with its Greenwood band, B10 and B50 with intervals, a two-parameter
Weibull fit with censoring (lifelines), and the Spearman rank correlation of each scattered
input with the revolutions to the limit, with a Fisher-z interval; its square is the share
of the rank variance that input explains.

lifelines (and pandas under it) is imported where the estimate is made, never by
``clearsweep run``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .config import Config, ConfigError
from .service_life import CRITERIA, LifeState, life, life_summary
from .variables import JOINTS

if TYPE_CHECKING:
    import xarray as xr

#: Confidence level of every band and interval.
CONFIDENCE_LEVEL = 0.95
#: Points of the log-spaced revolution grid R(N) is given on.
GRID_POINTS = 61
#: Name of the "first limit reached, whichever it is" event.
ANY_LIMIT = "any"
#: The wear-through event (``life.stop_at_wear_through``).
WEAR_THROUGH = "wear_through"
#: Clearance draws of the normal distribution are cut at this many standard deviations;
#: the tolerance band is -+ this many of them.
NORMAL_BAND_SIGMAS = 3.0
#: Variance factor of Fisher's z for Spearman's rho (Fieller, Hartley & Pearson,
#: Biometrika 44, 1957): se(z) = sqrt(1.06 / (n - 3)).
SPEARMAN_VARIANCE_FACTOR = 1.06
#: Fewest events for a Weibull fit.
MIN_WEIBULL_EVENTS = 2

KM_METHOD = ("Kaplan-Meier estimate (lifelines KaplanMeierFitter) over the members, a "
             "member that reached life.cycles (or stopped) without reaching the limit "
             "right-censored at the revolutions it reached; band: Greenwood variance on the "
             "log(-log) scale (lifelines' exponential Greenwood)")
PERCENTILE_METHOD = ("first revolutions at which the Kaplan-Meier curve (bounds: its lower and "
                     "upper band) falls to R = 0.9 (B10) or 0.5 (B50) (lifelines "
                     "qth_survival_times); inf: not within the revolutions reached")
WEIBULL_METHOD = ("two-parameter Weibull R(N) = exp(-(N / scale)^shape) fitted by maximum "
                  "likelihood with right censoring (lifelines WeibullFitter); parameter "
                  "intervals: Wald; B10 interval: delta method on log N")
RANK_METHOD = ("Spearman rank correlation between the input drawn and the revolutions to the "
               "limit over the members (censored members rank at their censoring revolutions, "
               "above every failure when all are censored at life.cycles); interval: Fisher z "
               "with se = sqrt(1.06 / (n - 3)); share: rho^2")


# ---------------------------------------------------------------------------- members

@dataclass(frozen=True)
class MemberDraws:
    """What member ``reliability.member`` draws (docs/reliability.md).

    Attributes
    ----------
    clearance : np.ndarray
        (2,) initial radial clearance of joints A, B [m] (0: ideal joint).
    wear_factor : np.ndarray
        (2,) factor on the socket surface's wear coefficient (lognormal, mean 1).
    coating_factor : np.ndarray
        (2,) factor on the coating thickness (lognormal, mean 1).
    speed_factor : float
        Factor on the crank speed (lognormal, mean 1).
    """

    clearance: np.ndarray
    wear_factor: np.ndarray
    coating_factor: np.ndarray
    speed_factor: float


def lognormal_factor(cv: float, z: float) -> float:
    """exp(sigma z - sigma^2 / 2), sigma^2 = ln(1 + cv^2): a lognormal factor of mean 1 and
    coefficient of variation ``cv`` for a standard normal draw ``z`` (exactly 1 at cv = 0)."""
    sigma = math.sqrt(math.log1p(cv ** 2))
    return math.exp(sigma * z - 0.5 * sigma ** 2)


def member_draws(cfg: Config) -> MemberDraws:
    """The draws of member ``cfg.reliability.member``, from ``(seed, member)`` only.

    The generator is ``np.random.SeedSequence(seed, spawn_key=(member,))``, so a member's
    draw depends on neither the other members, the workers nor the order cases finish.
    Every draw is made whatever the amplitudes, in a fixed order (per joint A, B: clearance
    uniform, clearance normal, wear, coating; then the speed; then joint O likewise), so
    switching one scatter on or off leaves the others' values unchanged, and a member of a
    mechanism with spherical clearance only draws as it did before joint O existed.
    """
    rc = cfg.reliability
    rng = np.random.default_rng(np.random.SeedSequence(rc.seed, spawn_key=(rc.member,)))
    items = cfg.joints.items()
    clearance, wear, coating = np.zeros(len(items)), np.ones(len(items)), np.ones(len(items))
    speed = 1.0
    for j, (name, joint) in enumerate(items):
        if name == "O":
            speed = lognormal_factor(rc.speed_cv, rng.standard_normal())
        u, z_c, z_k, z_t = rng.uniform(-1.0, 1.0), rng.standard_normal(), rng.standard_normal(), \
            rng.standard_normal()
        shift = u if rc.clearance_distribution == "uniform" else (
            float(np.clip(z_c, -NORMAL_BAND_SIGMAS, NORMAL_BAND_SIGMAS)) / NORMAL_BAND_SIGMAS)
        if joint.clearance > 0.0:
            clearance[j] = joint.clearance + rc.clearance_tolerance * shift
            wear[j] = lognormal_factor(rc.wear_coefficient_cv, z_k)
            coating[j] = lognormal_factor(rc.coating_thickness_cv, z_t)
    return MemberDraws(clearance, wear, coating, speed)


def member_config(cfg: Config) -> Config:
    """The config of member ``cfg.reliability.member`` with its draws applied; ``cfg``
    itself when nothing is scattered (the nominal life run, bit for bit).

    Sets each clearance joint's ``clearance``, ``coating_thickness`` (coated joints) and
    ``wear_coefficient`` (the socket surface's own times the factor), and
    ``mechanism.speed_rpm``; values left unscattered are not touched. With a clearance
    tolerance, ``reliability.clearance_tolerance`` is 0 in the member's config: the band
    was checked on the nominal config (its ends, docs/reliability.md), the member holds
    one drawn clearance.
    """
    rc = cfg.reliability
    if not rc.any:
        return cfg
    from .config import resolve_materials
    from .params import surface_material

    draws = member_draws(cfg)
    materials = resolve_materials(cfg)
    values: dict[str, Any] = {}
    for j, (name, joint) in enumerate(cfg.joints.items()):
        if joint.clearance <= 0.0:
            continue
        if rc.clearance_tolerance > 0.0:
            # the section's keys that give it the drawn clearance (a guide's two move
            # together by the draw)
            values.update(joint.clearance_overrides(name, float(draws.clearance[j])))
            # the member is one part, its clearance drawn: no band of its own, else the
            # band's check around the draw (not the nominal) would let the seed decide
            values["reliability__clearance_tolerance"] = 0.0
        if rc.wear_coefficient_cv > 0.0:
            k = joint.wear_coefficient
            k = surface_material(joint, materials).wear_coefficient_m2_per_N if k is None else k
            values[f"joints__{name}__wear_coefficient"] = k * float(draws.wear_factor[j])
        if rc.coating_thickness_cv > 0.0 and joint.coating != "none":
            values[f"joints__{name}__coating_thickness"] = (joint.coating_thickness
                                                            * float(draws.coating_factor[j]))
    if rc.speed_cv > 0.0:
        values["mechanism__speed_rpm"] = cfg.mechanism.speed_rpm * draws.speed_factor
    return cfg.replace(**values)


def watched_limits(cfg: Config) -> list[str]:
    """The limits a reliability member watches: each ``life.max_*`` set, and
    ``wear_through`` with ``life.stop_at_wear_through``."""
    names = [name for name, (key, _) in CRITERIA.items() if cfg.get(key) is not None]
    return names + ([WEAR_THROUGH] if cfg.life.stop_at_wear_through else [])


def check_reliability(cfg: Config, source: str = "<config>") -> None:
    """Refuse a reliability design whose limits can never be reached (ConfigError naming
    the key): no limit set, a wear or contact limit without a clearance joint, a
    motion-error limit on an ideal mechanism, wear-through without a coated clearance joint."""
    if not watched_limits(cfg):
        raise ConfigError("life", None, "at least one limit (life.max_clearance_growth, "
                          "max_normal_force, max_rms_acceleration, max_motion_error or "
                          "stop_at_wear_through: true): a reliability run counts revolutions to "
                          "a limit", source, got="no limit set")
    clearance = [j for _, j in cfg.joints.items() if j.clearance > 0.0]
    if not clearance:
        for key in ("life.max_clearance_growth", "life.max_normal_force", "life.max_motion_error"):
            if cfg.get(key) is not None:
                raise ConfigError(key, cfg.get(key), "null without a clearance joint (an ideal "
                                  "mechanism neither wears, nor has contact forces or motion "
                                  "error: the limit can never be reached)", source)
    if cfg.life.stop_at_wear_through and not any(j.coating != "none" for j in clearance):
        raise ConfigError("life.stop_at_wear_through", True, "false without a coated clearance "
                          "joint (nothing can be worn through)", source)


def _all_reached(cfg: Config, row: dict[str, Any], state: LifeState) -> str | None:
    """Stop rule of a member: once every watched limit has been reached, the name of the
    one reached last (the first of those reached in this block, in :data:`CRITERIA` order;
    with one limit, what a plain life run names); else None."""
    previous = state.rows[-2]["cycle"] if len(state.rows) > 1 else -math.inf
    now = []
    for name in watched_limits(cfg):
        if name == WEAR_THROUGH:
            cycles = [w[0] for w in state.wear_through if w is not None]
            if not cycles:
                return None
            now += [name] if min(cycles) > previous else []
            continue
        key, var = CRITERIA[name]
        hit = [np.nanmax(np.atleast_1d(r[var])) >= cfg.get(key) for r in state.rows
               if np.isfinite(r[var]).any()]
        if not any(hit):
            return None
        now += [name] if hit[-1] and not any(hit[:-1]) else []
    return now[0] if now else "all_limits"


def reliability_case(config) -> xr.Dataset:
    """One member as a sweep case (``store: reliability``): the life run of
    :func:`member_config`, stopped when every watched limit is reached, with the member's
    draws (``member_clearance``, ``member_wear_factor``, ``member_coating_thickness``,
    ``member_speed``). ``status`` is ``ok`` whenever the run gives revolutions to
    count: a block that stops with another status ends the member there (``stop_reason``),
    and its limits not reached by then are censored."""
    import xarray as xr

    from .config import load_config

    cfg = load_config(config)
    member = member_config(cfg)
    ds = life(member, allow_large=True, stop_rule=_all_reached)   # the sweep checked budgets
    draws = member_draws(cfg)
    ideal = draws.clearance <= 0.0
    coated = np.array([j.coating != "none" and not i for (_, j), i in zip(member.joints.items(), ideal)])
    ds["member_clearance"] = ("joint", np.where(ideal, np.nan, [j.clearance for _, j in member.joints.items()]),
                              {"units": "m", "long_name": "initial radial clearance drawn"})
    ds["member_wear_factor"] = ("joint", np.where(ideal, np.nan, draws.wear_factor),
                                {"units": "1", "long_name": "factor on the socket surface's wear "
                                 "coefficient drawn"})
    ds["member_coating_thickness"] = ("joint", np.where(coated, [j.coating_thickness for _, j in
                                                                member.joints.items()], np.nan),
                                      {"units": "m", "long_name": "coating thickness drawn"})
    ds["member_speed"] = ((), member.mechanism.speed_rpm,
                          {"units": "min-1", "long_name": "crank speed drawn"})
    ds["status"] = xr.DataArray("ok", attrs={"long_name": "life run status"})
    return ds


def _event(ds: xr.Dataset, name: str) -> float:
    return float(ds[f"cycles_to_{name}"])


def reliability_summary(ds: xr.Dataset) -> xr.Dataset:
    """What a reliability sweep keeps of one member: :func:`life_summary`, the draws, and
    per limit (coordinate ``limit``: each watched limit, then ``any``) the revolutions to
    it (``revolutions_to_limit``; where not reached, the revolutions reached) and
    ``censored`` (not reached)."""
    import xarray as xr

    from .config import load_config

    cfg = load_config(dict(_config_dict(ds)))
    names = watched_limits(cfg)
    reached = float(ds.cycle[-1])
    times = np.array([_event(ds, n) for n in names])
    hit = np.isfinite(times)
    first = float(np.min(times[hit])) if hit.any() else reached
    revolutions = np.append(np.where(hit, times, reached), first)
    censored = np.append(~hit, not hit.any())
    summary = life_summary(ds)
    extra = {name: ds[name] for name in ("member_clearance", "member_wear_factor",
                                          "member_coating_thickness", "member_speed") if name in ds}
    summary = summary.assign(extra)
    summary["revolutions_to_limit"] = xr.DataArray(revolutions, dims="limit", attrs={
        "units": "1", "long_name": "crank revolutions to the limit, or reached where censored"})
    summary["censored"] = xr.DataArray(censored, dims="limit", attrs={
        "long_name": "limit not reached (right-censored at revolutions_to_limit)"})
    # the joint that reached each limit first ("": none, or a limit of the slider's)
    joints = [str(ds[f"first_joint_to_{n}"].values) if f"first_joint_to_{n}" in ds else ""
              for n in names]
    joints.append(joints[int(np.argmin(np.where(hit, times, np.inf)))] if hit.any() else "")
    summary["first_joint"] = xr.DataArray(np.array(joints, dtype=object), dims="limit", attrs={
        "long_name": "the joint that reached the limit first (empty: none, or the slider's)"})
    summary = summary.assign_coords(limit=("limit", [*names, ANY_LIMIT],
                                           {"long_name": "life limit (any: the first reached)"}))
    return summary


def _config_dict(ds: xr.Dataset) -> dict:
    from .schema import parse_yaml

    return parse_yaml(ds.attrs["config"])


# ---------------------------------------------------------------------------- estimate

@dataclass
class LimitEstimate:
    """The estimate of one design and one limit (:func:`estimate_limit`)."""

    reliability: np.ndarray
    reliability_low: np.ndarray
    reliability_high: np.ndarray
    b10: tuple[float, float, float]
    b50: tuple[float, float, float]
    weibull_shape: tuple[float, float, float]
    weibull_scale: tuple[float, float, float]
    b10_weibull: tuple[float, float, float]
    events: int
    members: int


_NAN3 = (math.nan, math.nan, math.nan)


def estimate_limit(revolutions: np.ndarray, censored: np.ndarray, grid: np.ndarray,
                   level: float = CONFIDENCE_LEVEL) -> LimitEstimate:
    """Kaplan-Meier R(N) on ``grid`` with its Greenwood band, B10 and B50 with intervals,
    and a Weibull fit, from the members' revolutions and censoring flags (NaN members left
    out). R is NaN beyond the largest revolutions observed when that member is censored
    (nothing is known there); 0 when every member has reached the limit."""
    from lifelines import KaplanMeierFitter, WeibullFitter
    from lifelines.utils import qth_survival_times

    keep = np.isfinite(revolutions)
    t = np.asarray(revolutions, dtype=float)[keep]
    e = ~np.asarray(censored, dtype=bool)[keep]
    nan = np.full(len(grid), np.nan)
    if t.size == 0:
        return LimitEstimate(nan, nan, nan, _NAN3, _NAN3, _NAN3, _NAN3, _NAN3, 0, 0)
    kmf = KaplanMeierFitter(alpha=1.0 - level).fit(t, e)
    timeline = kmf.survival_function_.index.to_numpy(dtype=float)
    surv = kmf.survival_function_.to_numpy(dtype=float)[:, 0]
    band = kmf.confidence_interval_survival_function_
    low_high = band.to_numpy(dtype=float)
    idx = np.searchsorted(timeline, grid, side="right") - 1
    last = t == t.max()
    beyond = (grid > t.max()) & bool((~e[last]).any())
    r = np.where(beyond, np.nan, surv[idx])
    r_low = np.where(beyond, np.nan, low_high[idx, 0])
    r_high = np.where(beyond, np.nan, low_high[idx, 1])

    def percentile(q: float) -> tuple[float, float, float]:
        bounds = qth_survival_times(q, band).to_numpy(dtype=float).ravel()
        with warnings.catch_warnings():     # "approximating using survival_function_": the
            warnings.simplefilter("ignore")  # KM curve is that step function, so exact here
            return float(kmf.percentile(q)), float(bounds[0]), float(bounds[1])

    shape = scale = b10w = _NAN3
    if int(e.sum()) >= MIN_WEIBULL_EVENTS:
        shape, scale, b10w = _weibull(t, e, level, WeibullFitter)
    return LimitEstimate(r, r_low, r_high, percentile(0.9), percentile(0.5), shape, scale, b10w,
                         int(e.sum()), int(t.size))


def _weibull(t: np.ndarray, e: np.ndarray, level: float, fitter) -> tuple[tuple, tuple, tuple]:
    """Shape, scale and B10 of a Weibull fit with censoring, each (value, low, high)."""
    from scipy import stats

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            wf = fitter(alpha=1.0 - level).fit(t, e)
    except Exception:       # lifelines' ConvergenceError and its numerical failures
        return _NAN3, _NAN3, _NAN3
    summary = wf.summary.loc[["lambda_", "rho_"]]
    ci = summary[[c for c in summary.columns if c.startswith("coef lower")]
                 + [c for c in summary.columns if c.startswith("coef upper")]].to_numpy(dtype=float)
    lam, rho = float(wf.lambda_), float(wf.rho_)
    # B10 = lam (-ln 0.9)^(1 / rho); log B10 by the delta method
    a = math.log(-math.log(0.9))
    b10 = lam * math.exp(a / rho)
    grad = np.array([1.0 / lam, -a / rho ** 2])
    var = float(grad @ wf.variance_matrix_.to_numpy(dtype=float) @ grad)
    half = float(stats.norm.ppf(0.5 + 0.5 * level)) * math.sqrt(max(var, 0.0))
    return ((rho, float(ci[1, 0]), float(ci[1, 1])), (lam, float(ci[0, 0]), float(ci[0, 1])),
            (b10, b10 * math.exp(-half), b10 * math.exp(half)))


def rank_correlation(x: np.ndarray, y: np.ndarray, level: float = CONFIDENCE_LEVEL
                     ) -> tuple[float, float, float]:
    """Spearman's rho of ``x`` and ``y`` (finite pairs) with a Fisher-z interval; NaN
    when either is constant or fewer than 4 pairs remain."""
    from scipy import stats

    ok = np.isfinite(x) & np.isfinite(y)
    x, y = np.asarray(x)[ok], np.asarray(y)[ok]
    n = x.size
    if n < 4 or np.ptp(x) == 0.0 or np.ptp(y) == 0.0:
        return _NAN3
    rho = float(stats.spearmanr(x, y).statistic)
    z = math.atanh(min(max(rho, -0.999999), 0.999999))
    half = float(stats.norm.ppf(0.5 + 0.5 * level)) * math.sqrt(SPEARMAN_VARIANCE_FACTOR / (n - 3))
    return rho, math.tanh(z - half), math.tanh(z + half)


#: Scattered inputs: (name, member variable, joint index or None, config key of the scatter),
#: per joint of the table (variables.JOINTS, in its order), then the speed.
INPUTS = tuple(
    (f"{what}_{joint}", var, j, key)
    for what, var, key in (("clearance", "member_clearance", "reliability.clearance_tolerance"),
                           ("wear_coefficient", "member_wear_factor", "reliability.wear_coefficient_cv"),
                           ("coating_thickness", "member_coating_thickness",
                            "reliability.coating_thickness_cv"))
    for j, joint in enumerate(JOINTS)
) + (("speed", "member_speed", None, "reliability.speed_cv"),)


def revolution_grid(first: float, last: float, points: int = GRID_POINTS) -> np.ndarray:
    """Log-spaced revolutions from ``first`` to ``last``."""
    return np.geomspace(first, max(last, first * (1.0 + 1e-9)), points)


def reliability_estimate(ds: xr.Dataset, level: float = CONFIDENCE_LEVEL) -> xr.Dataset:
    """The estimate of a reliability sweep ``ds`` per design (every dimension but ``member``):
    R(N) with its band on a revolution grid, B10, B50, the Weibull fit and the rank
    correlations, per limit (module docstring)."""
    import xarray as xr

    from .analysis import file_config

    rev = ds["revolutions_to_limit"]
    design_dims = [d for d in rev.dims if d not in ("member", "limit")]
    order = [*design_dims, "member", "limit"]
    shape = tuple(ds.sizes[d] for d in design_dims)
    n_design = int(np.prod(shape)) if shape else 1
    n_member, n_limit = ds.sizes["member"], ds.sizes["limit"]
    ok = (ds["status"].astype(str) == "ok").transpose(*design_dims, "member").to_numpy()
    ok = ok.reshape(n_design, n_member)
    times = rev.transpose(*order).to_numpy().astype(float).reshape(n_design, n_member, n_limit)
    cens = ds["censored"].transpose(*order).to_numpy().reshape(n_design, n_member, n_limit)
    times = np.where(ok[..., None], times, np.nan)
    base = file_config(ds)      # the sweep's base, as the figures and the report read it
    # from half the earliest revolutions observed (at least one block) to the largest
    first = float(base.get("life", {}).get("block_revolutions", 1))
    seen = np.isfinite(times).any()
    grid = revolution_grid(max(first, 0.5 * float(np.nanmin(times))) if seen else first,
                           float(np.nanmax(times)) if seen else first)
    inputs = [(name, var, j) for name, var, j, _ in INPUTS if var in ds
              and np.isfinite(ds[var].isel(joint=j) if j is not None else ds[var]).any()]
    draws = np.full((n_design, n_member, len(inputs)), np.nan)
    for i, (_, var, j) in enumerate(inputs):
        da = ds[var].isel(joint=j) if j is not None else ds[var]
        draws[:, :, i] = da.transpose(*design_dims, "member").to_numpy().reshape(n_design, n_member)

    out: dict[str, np.ndarray] = {}

    def put(name: str, d: int, li: int, value: Any, extra: tuple[int, ...] = ()) -> None:
        if name not in out:
            out[name] = np.full((n_design, n_limit, *extra), np.nan)
        out[name][d, li] = value

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for d in range(n_design):
            for li in range(n_limit):
                est = estimate_limit(times[d, :, li], cens[d, :, li], grid, level)
                put("reliability", d, li, est.reliability, (len(grid),))
                put("reliability_ci_low", d, li, est.reliability_low, (len(grid),))
                put("reliability_ci_high", d, li, est.reliability_high, (len(grid),))
                for stat in ("b10", "b50", "weibull_shape", "weibull_scale", "b10_weibull"):
                    value, low, high = getattr(est, stat)
                    put(stat, d, li, value)
                    put(stat + "_ci_low", d, li, low)
                    put(stat + "_ci_high", d, li, high)
                put("members_reached", d, li, est.events)
                put("members_counted", d, li, est.members)
                for i in range(len(inputs)):
                    rho, low, high = rank_correlation(draws[d, :, i], times[d, :, li], level)
                    for name, value in (("rank_correlation", rho), ("rank_correlation_ci_low", low),
                                        ("rank_correlation_ci_high", high),
                                        ("variance_share", rho * rho)):
                        if name not in out:
                            out[name] = np.full((n_design, n_limit, len(inputs)), np.nan)
                        out[name][d, li, i] = value
    dims_of = {"reliability": ("limit", "revolutions"), "rank": ("limit", "input")}
    data = {}
    for name, values in out.items():
        extra = (dims_of["reliability"] if name.startswith("reliability") else
                 dims_of["rank"] if name.startswith(("rank", "variance")) else ("limit",))
        array = values.reshape(*shape, *values.shape[1:])
        if name.startswith("members_"):
            array = array.astype(np.int64)
        data[name] = ((*design_dims, *extra), array, _attrs(name, level))
    result = xr.Dataset(data, coords={
        "revolutions": ("revolutions", grid, {"units": "1", "long_name": "crank revolutions N"}),
        "input": ("input", [n for n, _, _ in inputs], {"long_name": "scattered input"})})
    result.attrs = {"reliability_confidence_level": level, "reliability_km_method": KM_METHOD,
                    "reliability_percentile_method": PERCENTILE_METHOD,
                    "reliability_weibull_method": WEIBULL_METHOD,
                    "reliability_rank_method": RANK_METHOD}
    return result


_LONG_NAMES = {
    "reliability": ("1", "reliability R(N): fraction of members that have not reached the limit"),
    "b10": ("1", "B10 life: revolutions at R = 0.9 (Kaplan-Meier)"),
    "b50": ("1", "B50 life: revolutions at R = 0.5 (Kaplan-Meier)"),
    "weibull_shape": ("1", "Weibull shape (slope) of the revolutions to the limit"),
    "weibull_scale": ("1", "Weibull scale (characteristic life) of the revolutions to the limit"),
    "b10_weibull": ("1", "B10 life of the Weibull fit"),
    "members_reached": ("1", "members that reached the limit"),
    "members_counted": ("1", "members counted (status ok)"),
    "rank_correlation": ("1", "Spearman rank correlation of the input with the revolutions to "
                              "the limit"),
    "variance_share": ("1", "share of the rank variance of the revolutions to the limit the "
                            "input explains (rank_correlation squared)"),
}


def _attrs(name: str, level: float) -> dict[str, Any]:
    for suffix, what in (("_ci_low", "lower"), ("_ci_high", "upper")):
        if name.endswith(suffix):
            units, long_name = _LONG_NAMES[name[: -len(suffix)]]
            return {"units": units, "long_name": f"{what} bound of the {level:.0%} confidence "
                    f"interval of the {long_name}", "confidence_level": level}
    units, long_name = _LONG_NAMES[name]
    return {"units": units, "long_name": long_name}


def add_reliability_estimate(path) -> None:
    """Append :func:`reliability_estimate` to the sweep file at ``path`` (its members'
    revolutions, censoring flags and draws are read, nothing else)."""
    import netCDF4
    import xarray as xr

    with xr.open_dataset(path) as ds:
        names = [n for n in ("status", "revolutions_to_limit", "censored", *{v for _, v, _, _ in INPUTS})
                 if n in ds]
        part = ds[names].load()
        part.attrs = dict(ds.attrs)
    result = reliability_estimate(part)
    with netCDF4.Dataset(path, "a") as nc:
        nc.setncatts(result.attrs)
    result.attrs = {}
    result.to_netcdf(path, mode="a", engine="netcdf4")


# ---------------------------------------------------------------------------- report

def _life_text(value: float, horizon: float) -> str:
    if math.isnan(value):
        return "n/a"
    return f"> {horizon:.3g}" if math.isinf(value) else f"{value:.3g}"


def _first_joints(flat: xr.Dataset, limit: str, rows) -> list[str]:
    """``first to reach it: joint B in 12 members, P in 4`` per design, where the members
    name the joint (``first_joint``); nothing for a file without it."""
    if "first_joint" not in flat:
        return []
    out = []
    for label, case in rows:
        names = [str(v) for v in np.atleast_1d(case["first_joint"].values) if str(v)]
        if names:
            counts = sorted(((names.count(j), j) for j in set(names)), reverse=True)
            out.append(f"  {label}: first to reach it: " + ", ".join(
                f"joint {j} in {n} member{'s' if n != 1 else ''}" for n, j in counts))
    return [f"which joint reaches {limit} first:", *out] if out else []


def reliability_text(ds: xr.Dataset, limits: Sequence[str] | None = None) -> str:
    """Designs ranked by B10 per limit, with intervals, B50, the Weibull fit and which
    designs cannot be told apart; then what decides the life (rank correlations)."""
    design_dims = [d for d in ds["b10"].dims if d != "limit"]
    flat = ds.stack(design=design_dims) if design_dims else ds.expand_dims(design=[0])
    horizon = float(ds["revolutions"].max())
    level = float(ds.attrs.get("reliability_confidence_level", CONFIDENCE_LEVEL))
    lines = [f"Reliability over service life ({ds.sizes['member']} members per design; "
             f"{level:.0%} intervals; censored members are not failures)"]
    for limit in (limits or [str(v) for v in ds["limit"].values]):
        lines += ["", f"limit {limit}: designs ranked by B10 (Kaplan-Meier)"]
        rows = []
        for k in range(flat.sizes["design"]):
            case = flat.isel(design=k).sel(limit=limit)
            label = ", ".join(f"{d}={case[d].values.item()}" for d in design_dims) or "design"
            rows.append((label, case))
        rows.sort(key=lambda r: -np.nan_to_num(float(r[1]["b10"]), nan=-np.inf))
        head = ["design", "reached", "B10 [rev]", f"B10 {level:.0%} interval", "B50 [rev]",
                "Weibull shape", "Weibull scale [rev]", "Weibull B10 [rev]"]
        table = [head]
        for label, c in rows:
            table.append([
                label, f"{int(c['members_reached'])}/{int(c['members_counted'])}",
                _life_text(float(c["b10"]), horizon),
                f"[{_life_text(float(c['b10_ci_low']), horizon)}, "
                f"{_life_text(float(c['b10_ci_high']), horizon)}]",
                _life_text(float(c["b50"]), horizon),
                f"{float(c['weibull_shape']):.3g}", f"{float(c['weibull_scale']):.3g}",
                f"{_life_text(float(c['b10_weibull']), horizon)} "
                f"[{_life_text(float(c['b10_weibull_ci_low']), horizon)}, "
                f"{_life_text(float(c['b10_weibull_ci_high']), horizon)}]"])
        widths = [max(len(r[i]) for r in table) for i in range(len(head))]
        lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in table]
        lines += _distinguishable(rows)
        lines += _first_joints(flat, limit, rows)
        if ds.sizes.get("input", 0):
            lines.append(f"what decides it: Spearman rank correlation with the revolutions to "
                         f"{limit} [{level:.0%} interval], share of the rank variance")
            for label, c in rows:
                parts = []
                for name in ds["input"].values:
                    rho = float(c["rank_correlation"].sel(input=name))
                    if math.isfinite(rho):
                        parts.append(f"{name} {rho:+.2f} [{float(c['rank_correlation_ci_low'].sel(input=name)):+.2f}, "
                                     f"{float(c['rank_correlation_ci_high'].sel(input=name)):+.2f}] "
                                     f"{float(c['variance_share'].sel(input=name)):.0%}")
                lines.append(f"  {label}: " + ("; ".join(parts) or "no finite correlation"))
    return "\n".join(lines)


def _distinguishable(rows: list) -> list[str]:
    """Pairs of designs ranked next to each other whose B10 intervals overlap."""
    out = []
    for (a, ca), (b, cb) in zip(rows, rows[1:]):
        lo_a, hi_a = float(ca["b10_ci_low"]), float(ca["b10_ci_high"])
        lo_b, hi_b = float(cb["b10_ci_low"]), float(cb["b10_ci_high"])
        if any(math.isnan(v) for v in (lo_a, hi_a, lo_b, hi_b)):
            out.append(f"  {a} vs {b}: B10 interval undefined, not compared")
        elif lo_a <= hi_b and lo_b <= hi_a:
            out.append(f"  {a} and {b}: not distinguishable (B10 intervals overlap)")
    return out
