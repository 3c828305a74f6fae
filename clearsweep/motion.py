"""Spectra and periodicity of a run's motion: pure functions over numpy arrays.

- :func:`order_spectrum`: the Welch spectrum of a signal sampled in time, on an abscissa of
  crank orders (frequency / crank frequency), with segments of whole crank revolutions so
  that every integer order falls on a frequency bin; :func:`spectrum_summary` reads its
  dominant order and the share of its power above ``HIGH_ORDER``.
- :func:`detect_period`: the period n of a sequence of Poincaré samples (one point per
  crank revolution): the smallest n with every point within a tolerance of the point n
  revolutions before.
- :func:`zero_one_test`: the 0-1 test for chaos of Gottwald and Melbourne (2004, 2009), the
  correlation method: K near 0 for regular motion, near 1 for chaotic motion.

docs/physics.md section 11 states the rules and their references. The summaries of a case
(``summary.case_summary``) and the figures (``plotting``) call these; nothing here knows of
datasets. scipy is imported where it is used (a plain run does not need it).
"""

from __future__ import annotations

import numpy as np

#: Share of the spectrum's power above this crank order (``slider_acceleration_high_order_share``).
#: The ideal mechanism's slider acceleration is a smooth periodic function of the crank angle
#: whose harmonics fall off about as (l2 / l3)^k: above order 10 it holds under 1e-8 of the
#: power (tests/test_motion.py), so what a clearance run has there comes from its impacts.
HIGH_ORDER = 10.0

#: Fewest whole crank revolutions of a Welch segment: with a periodic Hann window and
#: segments of R >= 2 revolutions, order k falls on bin R k and the other harmonics of a
#: periodic signal leak nothing into it (the window's transform vanishes 2 bins and more
#: from its centre).
MIN_SEGMENT_REVOLUTIONS = 2
#: Segments a settled window is cut into, about (50 % overlap): segments of
#: max(MIN_SEGMENT_REVOLUTIONS, revolutions // SEGMENTS) whole revolutions.
SEGMENTS = 4

#: Longest period looked for by :func:`detect_period` [revolutions].
MAX_PERIOD = 8
#: Two Poincaré points are the same point within this fraction of the samples' scale
#: (the clearance for offsets scaled by it; the largest magnitude for other samples).
PERIOD_RTOL = 1.0e-2
#: ``period`` of a case without enough samples to tell (fewer than 2 settled revolutions,
#: or NaN samples); 0 means that no period up to ``MAX_PERIOD`` was found.
PERIOD_UNKNOWN = -1
PERIOD_NONE = 0

#: 0-1 test: number of random frequencies c in (pi / 5, 4 pi / 5), the seed that draws them
#: (deterministic results), the largest lag as a fraction of the samples, and the fewest
#: samples it is computed on (below, K is NaN: with a few dozen samples it cannot tell a
#: period-8 orbit from chaos).
ZERO_ONE_FREQUENCIES = 100
ZERO_ONE_SEED = 20090101
ZERO_ONE_LAG_FRACTION = 0.1
ZERO_ONE_MIN_SAMPLES = 100
#: Samples that vary by no more than this fraction of their magnitude are a fixed point
#: (K = 0): the correlation of integration noise with the lag is noise, not chaos.
ZERO_ONE_FIXED_POINT = 1.0e-8
#: ``chaos_k`` above this reads as chaotic in reports, below 1 - it as regular.
CHAOS_THRESHOLD = 0.5


def segment_revolutions(revolutions: float) -> int:
    """Whole crank revolutions of one Welch segment for a window of ``revolutions``; 0 where
    the window holds fewer than ``MIN_SEGMENT_REVOLUTIONS``."""
    whole = int(np.floor(revolutions + 1e-9))
    if whole < MIN_SEGMENT_REVOLUTIONS:
        return 0
    return max(MIN_SEGMENT_REVOLUTIONS, whole // SEGMENTS)


def order_spectrum(t: np.ndarray, signal: np.ndarray, omega: float,
                   start: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Welch power spectrum of ``signal(t)`` over ``t >= start`` against crank orders.

    Parameters
    ----------
    t
        Sample times [s], equally spaced (a run's saved rows); trailing NaN rows (a padded
        sweep case) are dropped.
    signal
        Samples, in any unit U.
    omega
        Crank speed [rad s-1]; order = frequency / (omega / 2 pi).
    start
        Start of the window [s] (the settled window's).

    Returns
    -------
    (orders, power) : tuple of numpy arrays
        Orders [1] and the power spectrum [U^2] (``scaling="spectrum"``: a harmonic of
        amplitude A on a bin reads A^2 / 2), Hann windows of
        :func:`segment_revolutions` whole revolutions, 50 % overlap, the mean removed.
        Both empty where the window holds fewer than ``MIN_SEGMENT_REVOLUTIONS`` revolutions.
    """
    t = np.asarray(t, dtype=float)
    signal = np.asarray(signal, dtype=float)
    keep = np.isfinite(t) & np.isfinite(signal) & (t >= start - 1e-12)
    t, signal = t[keep], signal[keep]
    empty = np.empty(0), np.empty(0)
    if t.size < 4 or not omega > 0:
        return empty
    dt = float(np.median(np.diff(t)))
    per_revolution = 2.0 * np.pi / (omega * dt)          # samples per revolution
    revolutions = signal.size / per_revolution
    seg = segment_revolutions(revolutions)
    if seg == 0:
        return empty
    from scipy.signal import welch  # here: a run too short for a spectrum does not import it

    nperseg = min(int(round(seg * per_revolution)), signal.size)
    freq, power = welch(signal, fs=1.0 / dt, window="hann", nperseg=nperseg,
                        noverlap=nperseg // 2, detrend="constant", scaling="spectrum")
    return freq / (omega / (2.0 * np.pi)), power


def spectrum_summary(orders: np.ndarray, power: np.ndarray,
                     high_order: float = HIGH_ORDER) -> tuple[float, float]:
    """(dominant order, share of the power above ``high_order``) of an order spectrum.

    The dominant order is that of the largest bin above order 0 (the mean is removed); the
    share is the power of the bins above ``high_order`` over that of every bin above
    order 0. NaN both for an empty spectrum or one without power.
    """
    positive = orders > 0
    total = float(power[positive].sum()) if orders.size else 0.0
    if not total > 0:
        return float("nan"), float("nan")
    dominant = float(orders[positive][np.argmax(power[positive])])
    return dominant, float(power[orders > high_order].sum()) / total


def detect_period(samples: np.ndarray, scale=None, rtol: float = PERIOD_RTOL,
                  max_period: int = MAX_PERIOD) -> int:
    """The period, in revolutions, of Poincaré samples (one point per revolution).

    Parameters
    ----------
    samples
        (revolution,) or (revolution, feature): the last revolutions' points, in order.
    scale
        Scale of each feature (scalar or one per feature): points within ``rtol * scale`` of
        each other in every feature are the same point. Default: each feature's largest
        magnitude over the samples.
    rtol, max_period
        Tolerance and longest period looked for.

    Returns
    -------
    int
        The smallest n <= ``max_period`` with every point within the tolerance of the one n
        revolutions before it, the samples holding at least two points of each of the n
        (2 n samples): 1 for a single repeated point, n for n points visited in turn;
        ``PERIOD_NONE`` (0) where no such n exists (quasi-periodic or chaotic motion, or a
        period beyond what the samples can show); ``PERIOD_UNKNOWN`` (-1) for fewer than 2
        samples or a NaN among them.
    """
    x = np.asarray(samples, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if x.shape[0] < 2 or not np.isfinite(x).all():
        return PERIOD_UNKNOWN
    if scale is None:
        scale = np.abs(x).max(axis=0)
    scale = np.broadcast_to(np.asarray(scale, dtype=float), x.shape[1:])
    tolerance = rtol * np.where(scale > 0, scale, 1.0)
    for n in range(1, min(max_period, x.shape[0] // 2) + 1):
        if (np.abs(x[n:] - x[:-n]) <= tolerance).all():
            return n
    return PERIOD_NONE


def zero_one_test(samples: np.ndarray, frequencies: int = ZERO_ONE_FREQUENCIES,
                  seed: int = ZERO_ONE_SEED) -> float:
    """K of the 0-1 test for chaos (Gottwald and Melbourne 2004, 2009), correlation method.

    For each of ``frequencies`` values of c drawn uniformly from (pi / 5, 4 pi / 5) by a
    generator seeded with ``seed``: the translation variables p(n) = sum_j phi_j cos(j c),
    q(n) = sum_j phi_j sin(j c); the mean square displacement M(n) over j for lags
    n = 1 .. N / 10 (``ZERO_ONE_LAG_FRACTION``), less its oscillating term
    (E phi)^2 (1 - cos n c) / (1 - cos c) (the 2009 modification); K_c the correlation of
    that with n. K is the median of K_c: near 0 for regular (periodic or quasi-periodic)
    samples, near 1 for chaotic ones.

    Parameters
    ----------
    samples
        A scalar observable, one value per revolution (or per forcing period).

    Returns
    -------
    float
        K, clipped to [0, 1]; NaN for fewer than ``ZERO_ONE_MIN_SAMPLES`` samples, a NaN
        among them; 0 for samples constant within ``ZERO_ONE_FIXED_POINT`` (a fixed point).
    """
    phi = np.asarray(samples, dtype=float).ravel()
    n_samples = phi.size
    if n_samples < ZERO_ONE_MIN_SAMPLES or not np.isfinite(phi).all():
        return float("nan")
    if np.ptp(phi) <= ZERO_ONE_FIXED_POINT * max(np.abs(phi).max(), 1e-300):
        return 0.0
    rng = np.random.default_rng(seed)
    cs = rng.uniform(np.pi / 5.0, 4.0 * np.pi / 5.0, frequencies)
    n_cut = max(int(ZERO_ONE_LAG_FRACTION * n_samples), 2)
    lags = np.arange(1, n_cut + 1)
    span = n_samples - n_cut                    # the same j range for every lag
    j = np.arange(1, n_samples + 1)
    mean_sq = phi.mean() ** 2
    ks = np.empty(frequencies)
    for i, c in enumerate(cs):
        p = np.cumsum(phi * np.cos(j * c))
        q = np.cumsum(phi * np.sin(j * c))
        m = np.array([np.mean((p[n:n + span] - p[:span]) ** 2 + (q[n:n + span] - q[:span]) ** 2)
                      for n in lags])
        d = m - mean_sq * (1.0 - np.cos(lags * c)) / (1.0 - np.cos(c))
        ks[i] = np.corrcoef(lags, d)[0, 1] if np.ptp(d) > 0 else 0.0
    return float(np.clip(np.median(ks), 0.0, 1.0))
