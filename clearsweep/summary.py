"""Per-case summaries: the kernel's statistics and the paper's wear table (Tables 4-5).

A summary reduces a one-case or sweep dataset over the case dimensions
(``time``, ``angle``, ``polar``, ``azimuth``); sweep dimensions stay. The
sweep workers summarize every case with :func:`case_summary`; reports
(:mod:`clearsweep.analysis`) build on it. Wear-table conventions: docs/physics.md
section 5 and the :mod:`clearsweep.analysis` docstring.
"""

from __future__ import annotations

import functools

import numpy as np
import xarray as xr

from . import motion
from .variables import POINCARE, STATISTICS, attrs_for

#: A projection bin counts as worn above this fraction of its axis's maximum (docs/physics.md section 5).
WEAR_THRESHOLD_FRACTION = 1.0e-3

#: Variables of the wear table, in the column order of the paper's Tables 4-5
#: (the angle of the maximum, which the paper does not print, last).
WEAR_TABLE_VARIABLES = ("wear_depth_axis_max", "wear_angle_max", "wear_angle_min", "wear_range",
                        "wear_angle_of_max")

#: Scalars copied from the case dataset into its summary.
PASS_THROUGH_VARIABLES = ("first_impact_time", "energy_residual_relative", "substeps_used", "rk4_steps",
                          "wall_time")

#: The kernel's every-step statistics (``variables.STATISTICS``), settled window first.
STATISTIC_VARIABLES = tuple(n for n in STATISTICS if n.endswith("_settled")) + tuple(
    n for n in STATISTICS if not n.endswith("_settled"))

#: The spectrum's and the periodicity's summaries (:func:`motion_summary`, docs/physics.md
#: section 11).
SPECTRUM_VARIABLES = ("slider_acceleration_dominant_order", "slider_acceleration_high_order_share")
#: The change of the settled RMS between the settled window's halves (:func:`_drift_values`):
#: how far a settled statistic still moves with the run's length (clearsweep.analysis.factorial).
DRIFT_VARIABLES = ("slider_acceleration_rms_settled_drift",)
PERIODICITY_VARIABLES = ("period", "chaos_k")
#: The largest Lyapunov exponent (a run's, where ``metrics.lyapunov_revolutions`` asks for it)
#: and the class the indicators give together (:func:`motion_class`).
LYAPUNOV = "lyapunov_exponent"
MOTION_CLASS = "motion_class"

#: The Poincaré samples a periodicity summary reads (one point per crank revolution).
POINCARE_TIME = "poincare_time"
POINCARE_SLIDER = "poincare_slider_acc"
POINCARE_OFFSET = "poincare_offset"
#: The Poincaré samples, copied into every summary (a few numbers a revolution): a
#: ``store: summary`` sweep keeps them for its bifurcation diagram.
POINCARE_VARIABLES = tuple(POINCARE)

#: Order of the variables in ``case_summary``.
SUMMARY_ORDER = ("status", *STATISTIC_VARIABLES, *SPECTRUM_VARIABLES, *DRIFT_VARIABLES,
                 *PERIODICITY_VARIABLES, LYAPUNOV, MOTION_CLASS,
                 "wear_depth_max_final", "wear_volume", *WEAR_TABLE_VARIABLES,
                 *PASS_THROUGH_VARIABLES, *POINCARE_VARIABLES)
REVOLUTION_DIM = "revolution"
#: The names a swept ``metrics.settle_time`` takes in a sweep file (clearsweep.sweeping's
#: naming: ``metrics`` is not a dropped first component).
SETTLE_TIME_COORDINATES = ("metrics_settle_time", "settle_time")


def with_attrs(da: xr.DataArray, name: str, **extra) -> xr.DataArray:
    da = da.rename(name)
    da.attrs = {**attrs_for(name), **extra}
    return da


def worn_arc(worn: np.ndarray) -> tuple[int, int, int]:
    """The smallest arc of a full circle of equal bins that holds every worn bin.

    Parameters
    ----------
    worn
        One flag per equal angle bin spanning 360 degrees, in angle order.

    Returns
    -------
    (first, last, bins) : tuple of int
        Index of the arc's first and last worn bin going up in angle (``first > last``
        where the arc crosses the end of the bin range, +-180 degrees) and the bin
        centres it spans, ``last - first`` modulo the bins: the circle minus its widest
        run of unworn bins (of equal arcs, one that does not cross +-180 degrees, else
        the one whose last bin comes first). Every bin worn: ``(0, n - 1, n)``, the whole circle;
        none: ``(-1, -1, -1)``.
    """
    n = worn.size
    index = np.flatnonzero(worn)
    if index.size == 0:
        return -1, -1, -1
    if index.size == n:
        return 0, n - 1, n
    # unworn runs after each worn bin, the one across +-180 degrees first so that, of equal
    # arcs, the one that does not cross it is taken
    gaps = np.append(index[0] + n - index[-1] - 1, np.diff(index) - 1)
    widest = int(np.argmax(gaps))        # the unworn run after index[widest - 1]
    last, first = int(index[widest - 1]), int(index[widest])
    return first, last, n - 1 - int(gaps[widest])


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
        holding the maximum), ``wear_angle_min`` and ``wear_angle_max`` [degree]
        (the centres of the first and last bin, going up in angle, of the smallest
        arc that holds every bin with depth above ``WEAR_THRESHOLD_FRACTION`` of the
        maximum, :func:`worn_arc`; min > max where the arc crosses +-180 degrees),
        ``wear_range`` [degree] (that arc: max - min on the circle, so that it
        agrees with the polar plot). Without any wear on a (joint, axis): depth 0,
        angles and range NaN. Cases whose
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
    if projection.dims[-1] != "angle":
        projection = projection.transpose(..., "angle")
    coords = {k: v for k, v in projection.coords.items() if "angle" not in v.dims}
    return xr.Dataset({name: xr.DataArray(var, coords=coords, name=name)
                       for name, var in _wear_table_variables(ds).items()})


def _wear_table_variables(ds: xr.Dataset) -> dict[str, xr.Variable]:
    """:func:`wear_table`'s variables of ``ds`` (holding ``wear_projection``), bare: a
    DataArray's construction per variable was most of a case summary's cost."""
    projection = ds.variables["wear_projection"]
    if projection.dims[-1] != "angle":
        projection = projection.transpose(..., "angle")
    dims = projection.dims[:-1]
    p = projection.values
    angle = (ds.variables["angle"].values if "angle" in ds.variables
             else np.arange(p.shape[-1]))       # a dimension without its coordinate
    # numpy over the last axis: the same reductions as xarray's (NaN skipped), a small
    # fraction of the cost for the one-case datasets that sweep workers summarize
    with np.errstate(invalid="ignore"):
        all_nan = np.isnan(p).all(axis=-1)
        depth = np.where(all_nan, np.nan, np.nanmax(np.where(np.isnan(p), -np.inf, p), axis=-1))
        first_max = np.argmax(np.where(np.isnan(p), -np.inf, p), axis=-1)
        angle_of_max = np.where(depth > 0, angle[first_max], np.nan)
        worn = p > WEAR_THRESHOLD_FRACTION * depth[..., None]
    arcs = (np.apply_along_axis(worn_arc, -1, worn) if worn.size
            else np.full((*worn.shape[:-1], 3), -1))
    any_worn = arcs[..., 2] >= 0
    width = 360.0 / angle.size
    angle_min = np.where(any_worn, angle[np.maximum(arcs[..., 0], 0)], np.nan)
    angle_max = np.where(any_worn, angle[np.maximum(arcs[..., 1], 0)], np.nan)
    # bins spanned between the end centres; the whole circle when every bin is worn
    spanned = np.where(arcs[..., 2] == angle.size, 360.0, arcs[..., 2] * width)
    wear_range = np.where(any_worn, spanned, np.nan)
    threshold = {"wear_threshold_fraction": WEAR_THRESHOLD_FRACTION}

    def var(name: str, values: np.ndarray, **extra) -> xr.Variable:
        return xr.Variable(dims, values, {**attrs_for(name), **extra})

    return {
        "wear_depth_axis_max": var("wear_depth_axis_max", depth),
        "wear_angle_max": var("wear_angle_max", angle_max, **threshold),
        "wear_angle_min": var("wear_angle_min", angle_min, **threshold),
        "wear_range": var("wear_range", wear_range, **threshold),
        "wear_angle_of_max": var("wear_angle_of_max", angle_of_max),
    }


#: The coordinate names of a swept key that a one-case dataset may hold (clearsweep.sweeping's
#: naming: the short name, or the full one where the short one is taken).
SETTING_COORDINATES = {
    "metrics.settle_time": SETTLE_TIME_COORDINATES,
    "metrics.settle_revolutions": ("metrics_settle_revolutions", "settle_revolutions"),
    "solver.duration": ("duration", "solver_duration"),
    "solver.revolutions": ("revolutions", "solver_revolutions"),
    "mechanism.speed_rpm": ("speed_rpm", "mechanism_speed_rpm"),
}


@functools.lru_cache(maxsize=8)
def _parsed(text: str, base: bool) -> dict | None:
    """A config text's document (a sweep's: its base), parsed once for every case that
    reads it; not to be changed."""
    import yaml

    try:
        doc = yaml.safe_load(text) or {}
        doc = doc.get("base", {}) if base else doc
    except (yaml.YAMLError, AttributeError):
        return None
    return doc if isinstance(doc, dict) else None


def _config_docs(ds: xr.Dataset) -> list[dict]:
    """The case configs a dataset's text holds: its ``config`` (a run), else its sweep's base."""
    docs = []
    for name, base in (("config", False), ("sweep_config", True)):
        if name in ds.attrs:
            doc = _parsed(str(ds.attrs[name] or ""), base)
            if doc is not None:
                docs.append(doc)
    return docs


def _swept(ds: xr.Dataset, key: str) -> float | None:
    for name in SETTING_COORDINATES[key]:
        if name in ds.coords and ds[name].ndim == 0:
            return float(ds[name].values)
    return None


def _given(doc: dict, key: str) -> float | None:
    section, _, name = key.partition(".")
    try:
        value = doc[section][name]
        return None if value is None else float(value)
    except (KeyError, TypeError, ValueError):
        return None


def _speed_rpm(ds: xr.Dataset) -> float:
    swept = _swept(ds, "mechanism.speed_rpm")
    if swept is not None:
        return swept
    for doc in _config_docs(ds):
        given = _given(doc, "mechanism.speed_rpm")
        if given is not None:
            return given
    from .config import MechanismConfig

    return float(MechanismConfig().speed_rpm)


def _length(ds: xr.Dataset, seconds: str, revolutions: str, default: float) -> float | None:
    """A one-case dataset's length of ``seconds`` [s], given in seconds or as ``revolutions``
    (clearsweep.config.ALTERNATIVES): a swept key (it replaces the base's length), else its
    config's, else its sweep base's, else ``default``; None for a file without a config."""
    docs = _config_docs(ds)
    pairs = [(_swept(ds, seconds), _swept(ds, revolutions)),
             *((_given(doc, seconds), _given(doc, revolutions)) for doc in docs)]
    for in_seconds, in_revolutions in pairs:
        if in_seconds is not None:
            return in_seconds
        if in_revolutions is not None:
            return in_revolutions * 60.0 / _speed_rpm(ds)
    return default if docs else None


def settle_time(ds: xr.Dataset) -> float:
    """Start of the settled window [s] (``metrics.settle_time``, or
    ``metrics.settle_revolutions`` * 60 / speed_rpm) of a one-case dataset: the
    ``settle_time_s`` attribute a run records; in a case of a sweep file, its swept key
    (``metrics_settle_time``, ``metrics_settle_revolutions``, with a swept ``speed_rpm``)
    or the sweep's base config (its default where the config does not set it); 0 for a file
    without a config."""
    if "settle_time_s" in ds.attrs:
        return float(ds.attrs["settle_time_s"])
    from .config import MetricsConfig

    start = _length(ds, "metrics.settle_time", "metrics.settle_revolutions",
                    MetricsConfig().settle_time)
    return 0.0 if start is None else start


def settled_revolutions(ds: xr.Dataset) -> float:
    """Crank revolutions in the settled window of a one-case dataset: (end of the run -
    :func:`settle_time`) * speed_rpm / 60, the end the ``simulated_duration_s`` a run
    records, else the case's ``solver.duration`` (or ``solver.revolutions``) as for
    :func:`settle_time`; NaN for a file without a config."""
    from .config import SolverConfig

    end = ds.attrs.get("simulated_duration_s")
    if end is None:
        end = _length(ds, "solver.duration", "solver.revolutions", SolverConfig().duration)
    if end is None:
        return float("nan")
    return (float(end) - settle_time(ds)) * _speed_rpm(ds) / 60.0


def crank_speed(t: np.ndarray, crank_angle: np.ndarray) -> float:
    """Crank speed omega [rad s-1] of a run's rows: the slope of ``crank_angle`` (theta0 +
    omega t, driven at constant speed) between its first and last finite rows."""
    keep = np.isfinite(t) & np.isfinite(crank_angle)
    if keep.sum() < 2:
        return float("nan")
    t, theta = t[keep], crank_angle[keep]
    return float((theta[-1] - theta[0]) / (t[-1] - t[0]))


def _case_dims(var: xr.Variable, own: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(str(d) for d in var.dims if d not in own)


def _spectrum_values(ds: xr.Dataset) -> dict[str, xr.Variable]:
    """The spectrum's summaries of every case of ``ds`` (with ``slider_acceleration`` and
    ``crank_angle`` on ``time``)."""
    acc = ds.variables["slider_acceleration"]
    angle = ds.variables["crank_angle"]
    dims = _case_dims(acc, ("time",))
    acc_v = acc.transpose(*dims, "time").values
    angle_v = angle.transpose(*_case_dims(angle, ("time",)), "time").values
    angle_v = np.broadcast_to(angle_v, acc_v.shape)
    t = ds["time"].values.astype(float)
    start = settle_time(ds)
    dominant = np.full(acc_v.shape[:-1], np.nan)
    share = np.full(acc_v.shape[:-1], np.nan)
    for index in np.ndindex(*acc_v.shape[:-1]):
        orders, power = motion.order_spectrum(t, acc_v[index], crank_speed(t, angle_v[index]),
                                                start)
        dominant[index], share[index] = motion.spectrum_summary(orders, power)
    extra = {"high_order": motion.HIGH_ORDER}
    return {"slider_acceleration_dominant_order":
            xr.Variable(dims, dominant, attrs_for("slider_acceleration_dominant_order")),
            "slider_acceleration_high_order_share":
            xr.Variable(dims, share, {**attrs_for("slider_acceleration_high_order_share"), **extra})}


def settled_halves_rms(t: np.ndarray, acc: np.ndarray, start: float,
                       period: float | None = None) -> tuple[float, float]:
    """RMS of the saved rows ``acc`` at times ``t`` [s] over the two halves of the settled
    window, from ``start`` [s] to the last finite row. With the crank's ``period`` [s]: the
    first and the last n whole revolutions of the window, n = half its revolutions rounded
    down (an odd number of settled revolutions leaves the middle one out: a part of a
    revolution would weigh the harmonics by where the cut falls in it); without it, the
    window split at its middle. NaN where a half holds fewer than 2 rows (or n is 0)."""
    keep = np.isfinite(t) & np.isfinite(acc) & is_settled(t, start)
    if keep.sum() < 4:
        return float("nan"), float("nan")
    t, acc = t[keep], acc[keep]
    begin, end = float(t[0]), float(t[-1])
    if period is not None and np.isfinite(period) and period > 0.0:
        tol = 0.25 * float(np.min(np.diff(t)))
        span = np.floor((end - begin + tol) / period / 2.0) * period
        if span <= 0.0:
            return float("nan"), float("nan")
        first, second = acc[t < begin + span - tol], acc[t > end - span + tol]
    else:
        middle = 0.5 * (begin + end)
        first, second = acc[t < middle], acc[t >= middle]
    if first.size < 2 or second.size < 2:
        return float("nan"), float("nan")
    return float(np.sqrt(np.mean(first ** 2))), float(np.sqrt(np.mean(second ** 2)))


def _drift_values(ds: xr.Dataset) -> dict[str, xr.Variable]:
    """``slider_acceleration_rms_settled_drift`` of every case of ``ds`` (with
    ``slider_acceleration`` on ``time``): the second half's RMS minus the first's
    (:func:`settled_halves_rms`, whole revolutions where ``crank_angle`` gives the speed)."""
    acc = ds.variables["slider_acceleration"]
    dims = _case_dims(acc, ("time",))
    acc_v = acc.transpose(*dims, "time").values
    angle_v = None
    if "crank_angle" in ds:
        angle = ds.variables["crank_angle"]
        angle_v = np.broadcast_to(angle.transpose(*_case_dims(angle, ("time",)), "time").values,
                                  acc_v.shape)
    t = ds["time"].values.astype(float)
    start = settle_time(ds)
    drift = np.full(acc_v.shape[:-1], np.nan)
    for index in np.ndindex(*acc_v.shape[:-1]):
        period = None
        if angle_v is not None:
            omega = crank_speed(t, angle_v[index])
            period = 2.0 * np.pi / abs(omega) if np.isfinite(omega) and omega != 0.0 else None
        first, second = settled_halves_rms(t, acc_v[index], start, period)
        drift[index] = second - first
    return {DRIFT_VARIABLES[0]: xr.Variable(dims, drift, attrs_for(DRIFT_VARIABLES[0]))}


def is_settled(time, start: float):
    """Whether Poincaré sample times ``time`` (an array or a DataArray) [s] lie in the
    settled window from ``start`` [s] on (within 1e-12 s: a section at the window's start
    counts)."""
    return time >= start - 1e-12


def poincare_points(ds: xr.Dataset, start: float | None = None
                    ) -> tuple[xr.DataArray, xr.DataArray, xr.DataArray | None]:
    """The settled Poincaré samples of ``ds``: (time, slider acceleration, offsets / clearance
    or None), each NaN at the revolutions before ``start`` (default: :func:`settle_time`)."""
    start = settle_time(ds) if start is None else start
    time = ds[POINCARE_TIME]
    settled = is_settled(time, start)
    offset = ds[POINCARE_OFFSET].where(settled) if POINCARE_OFFSET in ds else None
    return time.where(settled), ds[POINCARE_SLIDER].where(settled), offset


def _periodicity_values(ds: xr.Dataset) -> dict[str, xr.Variable]:
    """``period`` and ``chaos_k`` of every case of ``ds`` (with the Poincaré samples), from
    the settled samples of :func:`poincare_points`, masked here on the arrays (three
    ``where`` on the DataArrays were half of a summary case's summaries)."""
    time = ds[POINCARE_TIME]
    dims = tuple(str(d) for d in time.dims if d != REVOLUTION_DIM)
    time_v = time.transpose(*dims, REVOLUTION_DIM).values
    settled = is_settled(time_v, settle_time(ds))
    time_v = np.where(settled, time_v, np.nan)
    slider_v = np.where(settled, ds[POINCARE_SLIDER].transpose(*dims, REVOLUTION_DIM).values, np.nan)
    offset_v = None
    if POINCARE_OFFSET in ds:
        offset_v = ds[POINCARE_OFFSET].transpose(*dims, REVOLUTION_DIM, ...).values
        offset_v = np.where(settled.reshape(settled.shape + (1,) * (offset_v.ndim - settled.ndim)),
                            offset_v, np.nan)
    period = np.full(time_v.shape[:-1], motion.PERIOD_UNKNOWN, dtype=np.int64)
    chaos = np.full(time_v.shape[:-1], np.nan)
    for index in np.ndindex(*time_v.shape[:-1]):
        rows = np.isfinite(time_v[index])
        a = slider_v[index][rows]
        features, scales = [a[:, None]], [np.abs(a).max() if a.size else 1.0]
        if offset_v is not None:
            d = offset_v[index][rows]
            d = d.reshape(d.shape[0], int(np.prod(d.shape[1:])))
            clearance_joints = ~np.isnan(d).all(axis=0)      # NaN: an ideal joint
            features.append(d[:, clearance_joints])
            scales += [1.0] * int(clearance_joints.sum())    # offsets are / clearance
        period[index] = motion.detect_period(np.concatenate(features, axis=1), np.array(scales))
        chaos[index] = motion.zero_one_test(a)
    rules = {"period_rtol": motion.PERIOD_RTOL, "max_period": motion.MAX_PERIOD}
    return {"period": xr.Variable(dims, period, {**attrs_for("period"), **rules}),
            "chaos_k": xr.Variable(dims, chaos, {**attrs_for("chaos_k"),
                                                 "zero_one_min_samples": motion.ZERO_ONE_MIN_SAMPLES,
                                                 "zero_one_seed": motion.ZERO_ONE_SEED})}


def motion_summary(ds: xr.Dataset) -> dict[str, xr.Variable]:
    """The spectrum's summaries (where ``ds`` holds the slider acceleration's time series)
    and the periodicity's (where it holds Poincaré samples), for every case of ``ds``;
    a summary ``ds`` already holds is not computed again (docs/physics.md section 11)."""
    out: dict[str, xr.Variable] = {}
    if ("slider_acceleration" in ds and "crank_angle" in ds and "time" in ds.dims
            and not all(n in ds for n in SPECTRUM_VARIABLES)):
        out.update(_spectrum_values(ds))
    if ("slider_acceleration" in ds and "time" in ds.dims
            and not all(n in ds for n in DRIFT_VARIABLES)):
        out.update(_drift_values(ds))
    if (POINCARE_TIME in ds and POINCARE_SLIDER in ds
            and not all(n in ds for n in PERIODICITY_VARIABLES)):
        out.update(_periodicity_values(ds))
    if MOTION_CLASS not in ds:
        found = {n: out[n] if n in out else ds.variables[n]
                 for n in (*PERIODICITY_VARIABLES, LYAPUNOV) if n in out or n in ds.variables}
        if all(n in found for n in PERIODICITY_VARIABLES):
            out[MOTION_CLASS] = motion_class(found["period"], found["chaos_k"], found.get(LYAPUNOV))
    return out


def motion_class(period: xr.Variable, chaos_k: xr.Variable,
                 exponent: xr.Variable | None = None) -> xr.Variable:
    """Each case's class (:func:`clearsweep.motion.classify_motion`) from its ``period``,
    ``chaos_k`` and, where computed, ``lyapunov_exponent`` (docs/physics.md section 11.6)."""
    parts = [period, chaos_k] + ([exponent] if exponent is not None else [])
    dims: list[str] = []
    for part in parts:
        dims += [str(d) for d in part.dims if d not in dims]
    sizes = {d: n for part in parts for d, n in zip(part.dims, part.shape)}
    shape = tuple(sizes[d] for d in dims)

    def values(var: xr.Variable) -> np.ndarray:
        return np.broadcast_to(var.set_dims(dict(zip(dims, shape))).transpose(*dims).values, shape)

    p, k = values(period), values(chaos_k)
    lam = values(exponent) if exponent is not None else np.full(shape, np.nan)
    out = np.empty(shape, dtype=object)
    for index in np.ndindex(*shape):
        out[index] = motion.classify_motion(int(p[index]), float(k[index]), float(lam[index]))
    rules = {"lyapunov_zero_below": motion.LYAPUNOV_ZERO_BELOW,
             "lyapunov_zero_above": motion.LYAPUNOV_ZERO_ABOVE,
             "chaos_threshold": motion.CHAOS_THRESHOLD}
    return xr.Variable(tuple(dims), out.astype(str), {**attrs_for(MOTION_CLASS), **rules})


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
        ``status``; the kernel's every-step statistics (``variables.STATISTICS``:
        peaks, RMS, impacts, contact fraction; settled window first, then the whole
        run), copied as they are, never recomputed from the saved rows;
        ``wear_depth_max_final(joint)`` [m] (max of ``wear_map``);
        ``wear_volume(joint)`` [m^3] (the worn volume, which unlike a largest bin does not
        depend on the map's grid); the spectrum's and the periodicity's summaries
        (:func:`motion_summary`) where ``ds`` holds the time series or Poincaré samples;
        the ``wear_table`` variables; ``energy_residual_relative``, ``substeps_used``,
        ``rk4_steps``, ``wall_time`` [s]; the Poincaré samples (``POINCARE_VARIABLES``) as
        they are. Dataset attributes (provenance) are kept.
    """
    # Built from Variables, not DataArrays: a one-case summary is made for every case of a
    # sweep, and xarray's per-DataArray construction and alignment were most of its cost.
    out: dict[str, xr.Variable] = {}
    if "wear_map" in ds:
        wmap = ds.variables["wear_map"]
        dims = tuple(d for d in wmap.dims if d not in ("polar", "azimuth"))
        axes = tuple(i for i, d in enumerate(wmap.dims) if d in ("polar", "azimuth"))
        values = wmap.values.max(axis=axes)
        if np.isnan(values).any():      # NaN skipped, as xarray's max does; all-NaN stays NaN
            finite = np.where(np.isnan(wmap.values), -np.inf, wmap.values).max(axis=axes)
            values = np.where(np.isnan(wmap.values).all(axis=axes), np.nan, finite)
        out["wear_depth_max_final"] = xr.Variable(dims, values, attrs_for("wear_depth_max_final"))
    if "wear_projection" in ds:
        out.update(_wear_table_variables(ds))
    out.update(motion_summary(ds))
    for name in SUMMARY_ORDER:
        if name not in out and name in ds.data_vars:
            out[name] = ds.variables[name]
    used = {d for v in out.values() for d in v.dims}
    coords = {k: ds.variables[k] for k in ds.coords if set(ds.variables[k].dims) <= used}
    summary = xr.Dataset({name: out[name] for name in SUMMARY_ORDER if name in out}, coords=coords)
    summary.attrs = dict(ds.attrs)
    return summary


#: Crest factor (peak / RMS) of the slider acceleration above which a case whose clearance
#: joints stay in contact without impacts reads as an in-contact oscillation
#: (:func:`peak_force_source`). A steady one-revolution motion stays well below it: the ideal
#: mechanism's settled crest factor is 2.395 / 1.427 = 1.68 at 60 r/min, a sine's sqrt(2);
#: PTFE at B with 0.05 mm clearance read 17.5 (35.42 / 2.027, 1 s; seated before the seat
#: balanced friction, docs/physics.md 3.3), 1.68 with friction off
#: (docs/physics.md section 3.3).
OSCILLATION_CREST_FACTOR = 3.0
#: What :func:`peak_force_source` says sets a case's peak force.
PEAK_BY_IMPACTS = "impacts"
PEAK_BY_OSCILLATION = "in-contact oscillation"
PEAK_BY_LOAD = "quasi-static"


def _statistic(summary: xr.Dataset, name: str, settled: xr.DataArray | None) -> xr.DataArray | None:
    """The statistic ``name`` of the settled window where ``settled`` (the cases whose run
    reaches it), else of the whole run."""
    whole = summary.get(name)
    if settled is None or name + "_settled" not in summary:
        return whole
    return summary[name + "_settled"].where(settled, whole) if whole is not None else None


def peak_force_source(summary: xr.Dataset) -> xr.DataArray | None:
    """What sets each case's peak contact force, from the kernel's statistics (docs/physics.md
    section 3.3): ``impacts (J...)`` where clearance joints J began contact episodes (impact
    count > 0); else ``in-contact oscillation (J...)`` where clearance joints J stayed in
    contact (contact fraction > 0) and the slider acceleration's crest factor, peak / RMS,
    exceeds ``OSCILLATION_CREST_FACTOR``: the force grows in an oscillation that never
    leaves contact (with friction, the ball's whirl around its socket); else ``quasi-static``:
    the load the mechanism's motion puts through its joints (the ideal mechanism, or a ball
    that rides its socket smoothly). The settled window's statistics where the case has them,
    else the whole run's. None where ``summary`` lacks the statistics."""
    names = ("impact_count", "contact_fraction", "slider_acceleration_peak",
             "slider_acceleration_rms")
    # one window for every statistic of a case: a run that ends before the settled window
    # has NaN settled peaks but settled counts of 0
    peak = summary.get("slider_acceleration_peak_settled")
    settled = None if peak is None else peak.notnull()
    found = {n: _statistic(summary, n, settled) for n in names}
    stats = {n: v for n, v in found.items() if v is not None}
    if len(stats) < len(names) or "joint" not in stats["impact_count"].dims:
        return None
    impacts = stats["impact_count"].transpose(..., "joint")
    contact = stats["contact_fraction"].transpose(..., "joint")
    with np.errstate(invalid="ignore", divide="ignore"):
        crest = (stats["slider_acceleration_peak"] / stats["slider_acceleration_rms"])
    dims = tuple(str(d) for d in impacts.dims if d != "joint")
    crest_v = crest.broadcast_like(impacts.isel(joint=0, drop=True)).transpose(*dims).values
    joints = [str(j) for j in impacts["joint"].values]
    impacts_v, contact_v = impacts.values, contact.values
    out = np.empty(impacts.shape[:-1], dtype=object)
    for index in np.ndindex(*out.shape):
        hit = [j for j, n in zip(joints, impacts_v[index]) if n > 0]
        touching = [j for j, f in zip(joints, contact_v[index]) if f > 0]
        if hit:
            out[index] = f"{PEAK_BY_IMPACTS} ({', '.join(hit)})"
        elif touching and crest_v[index] > OSCILLATION_CREST_FACTOR:
            out[index] = f"{PEAK_BY_OSCILLATION} ({', '.join(touching)})"
        else:
            out[index] = PEAK_BY_LOAD
    coords = {k: v for k, v in impacts.coords.items() if "joint" not in v.dims}
    return with_attrs(xr.DataArray(out.astype(str), dims=dims, coords=coords), "peak_force_source",
                      oscillation_crest_factor=OSCILLATION_CREST_FACTOR)

