"""Spectra and periodicity of a run's motion: pure functions over numpy arrays.

- :func:`order_spectrum`: the Welch spectrum of a signal sampled in time, on an abscissa of
  crank orders (frequency / crank frequency), with segments of whole crank revolutions so
  that every integer order falls on a frequency bin; :func:`spectrum_summary` reads its
  dominant order and the share of its power above ``HIGH_ORDER``.
- :func:`detect_period`: the period n of a sequence of Poincaré samples (one point per
  crank revolution): the smallest n whose n points each stay within a tolerance over the
  whole window.
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
#: The n points of a period n must be distinct: the spread of each (its samples over the
#: window) at most this fraction of the distance between any two of them. A decaying spiral
#: whose phases stay within the tolerance converges on one point: its phases' spreads are
#: as large as their distance apart.
PERIOD_SEPARATION = 0.5
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
        The smallest n <= ``max_period`` whose n points each stay within the tolerance over
        the whole window (the samples n revolutions apart, x[r], x[r + n], x[r + 2 n], ...,
        span no more than the tolerance in every feature, for each r < n), the samples
        holding at least two points of each of the n (2 n samples), and the n points
        distinct: each one's spread no more than ``PERIOD_SEPARATION`` of the distance
        between any two of them (in the tolerance's units, the largest feature). 1 for a
        single repeated point, n for n points visited in turn. The whole window, not each
        point against the one n revolutions before, and distinct points: a decaying spiral
        around a fixed point, turning about 1 / n of a turn a revolution, moves little in n
        revolutions, and its n phases converge on one point; it is not period n;
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
    scaled = x / tolerance                 # 1: the tolerance, in every feature
    for n in range(1, min(max_period, x.shape[0] // 2) + 1):
        phases = [scaled[r::n] for r in range(n)]
        spread = max(float(np.ptp(phase, axis=0).max()) for phase in phases)
        if spread > 1.0:
            continue
        if n > 1:
            centres = np.array([phase.mean(axis=0) for phase in phases])
            apart = min(float(np.abs(centres[a] - centres[b]).max())
                        for a in range(n) for b in range(a + 1, n))
            if spread > PERIOD_SEPARATION * apart:
                continue
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


#: Largest Lyapunov exponent: the size of the twin's offset from the reference, renormalised
#: to it after every block (Benettin et al. 1980), in the norm of :func:`largest_lyapunov`'s
#: ``scale``.
LYAPUNOV_PERTURBATION = 1.0e-9
#: The seed of the twin's first offset direction (a fixed draw: the estimate is deterministic).
LYAPUNOV_SEED = 19800101


def largest_lyapunov(advance, x0, blocks: int, scale=1.0, size: float = LYAPUNOV_PERTURBATION,
                     seed: int = LYAPUNOV_SEED, base=None, logs: list | None = None) -> float:
    """The largest Lyapunov exponent per block by twin runs renormalised after every block:
    Benettin, Galgani, Giorgilli and Strelcyn (1980), Wolf, Swift, Swinney and Vastano (1985).

    A twin starts ``size`` away from the reference state, in a fixed random direction
    (``seed``), in the norm |d| = sqrt(sum (d_i / scale_i)^2). After each block the twin's
    offset from the reference has grown by g_k; it is scaled back to ``size`` along its new
    direction, and the exponent is mean_k ln g_k.

    Parameters
    ----------
    advance
        ``advance(k, reference, twin) -> (reference_end, twin_end)``: both states (1-D
        arrays) carried over block k by the same flow.
    x0
        The reference's state at the start of block 0.
    blocks
        Blocks to average over.
    scale
        Each component's scale (scalar or one per component); a component of scale ``inf``
        is left unperturbed and out of the norm.
    base
        ``base(k) -> state``: the reference's state at the start of block k >= 1 (a
        trajectory computed beforehand, continuously); default: the previous block's
        ``reference_end``.
    logs
        A list that receives each block's ln g_k (to follow the estimate's convergence).

    Returns
    -------
    float
        The exponent per block [1 / block]; NaN where a state turns non-finite or the twin
        lands on the reference (no offset left to renormalise).
    """
    x = np.array(x0, dtype=float)
    weight = 1.0 / np.broadcast_to(np.asarray(scale, dtype=float), x.shape)
    direction = np.random.default_rng(seed).standard_normal(x.shape) * (weight > 0)
    offset = direction / weight.clip(min=1e-300) * (weight > 0)
    offset *= size / np.linalg.norm(offset * weight)
    total = 0.0
    for k in range(blocks):
        if k > 0 and base is not None:
            x = np.array(base(k), dtype=float)
        reference, twin = advance(k, x, x + offset)
        diff = np.asarray(twin, dtype=float) - np.asarray(reference, dtype=float)
        grown = float(np.linalg.norm(diff * weight))
        if not (np.isfinite(grown) and grown > 0.0 and np.isfinite(reference).all()):
            return float("nan")
        total += np.log(grown / size)
        if logs is not None:
            logs.append(float(np.log(grown / size)))
        offset = diff * (size / grown) * (weight > 0)
        x = np.asarray(reference, dtype=float)
    return total / blocks if blocks > 0 else float("nan")


#: An exponent from -LYAPUNOV_ZERO_BELOW to +LYAPUNOV_ZERO_ABOVE [1 / revolution] reads as
#: zero (quasi-periodic motion): a twin's offset along a neutral direction grows like the time,
#: not exponentially, so a zero exponent estimated over N revolutions reads about ln(N) / N
#: high (0.078 at N = 50); and the estimate wanders by about 1 / N either way. Measured
#: (docs/physics.md section 11.6, B at 0.25 mm): 94 r/min, regular by the 0-1 test over 990
#: samples, reads +0.026 to +0.030 over 25 to 99 revolutions; 95 r/min, converging onto a
#: period-7 orbit, -0.026 over 50 and -0.042 over 99; 96 r/min, chaotic, +0.55.
LYAPUNOV_ZERO_BELOW = 0.02
LYAPUNOV_ZERO_ABOVE = 0.1
#: The classes :func:`classify_motion` gives.
PERIODIC = "periodic"
QUASI_PERIODIC = "quasi-periodic"
CHAOTIC = "chaotic"
TRANSIENT = "transient"
NON_PERIODIC = "non-periodic"
UNDETERMINED = "undetermined"


def classify_motion(period: int, chaos_k: float, exponent: float = float("nan")) -> str:
    """The motion's class from the period test, the 0-1 test's K and the largest Lyapunov
    exponent [1 / revolution] (NaN: not computed); docs/physics.md section 11.6.

    - ``periodic``: a period n >= 1 (the period test speaks first);
    - ``chaotic``: no period, the exponent above ``LYAPUNOV_ZERO_ABOVE`` and K above
      ``CHAOS_THRESHOLD``;
    - ``quasi-periodic``: no period, the exponent from -``LYAPUNOV_ZERO_BELOW`` to
      ``LYAPUNOV_ZERO_ABOVE``, whatever K (with a hundred samples a quasi-periodic orbit
      can read K near 1: 0.81 at 94 r/min);
    - ``transient``: no period, the exponent below -``LYAPUNOV_ZERO_BELOW``: the motion
      contracts onto an orbit it has not reached in the window (a slowly decaying spiral) or
      whose period exceeds ``MAX_PERIOD``;
    - without an exponent: ``chaotic`` where K > ``CHAOS_THRESHOLD``, else ``non-periodic``;
    - ``undetermined``: too few samples (period -1), or the two indicators disagree (an
      exponent above zero with K at or below the threshold), or neither is known.
    """
    if period >= 1:
        return PERIODIC
    if period != PERIOD_NONE:
        return UNDETERMINED
    if not np.isfinite(exponent):
        if not np.isfinite(chaos_k):
            return UNDETERMINED
        return CHAOTIC if chaos_k > CHAOS_THRESHOLD else NON_PERIODIC
    if exponent < -LYAPUNOV_ZERO_BELOW:
        return TRANSIENT
    if exponent <= LYAPUNOV_ZERO_ABOVE:
        return QUASI_PERIODIC
    return CHAOTIC if chaos_k > CHAOS_THRESHOLD else UNDETERMINED
