"""Fixed-step classical RK4 with deterministic 2^k sub-stepping, wear, status (docs/physics.md sections 4-5).

Each output-grid step h is split into 2^k equal RK4 sub-steps, k the smallest level for
which the stiff rate of docs/physics.md section 4 (estimated at every sub-step's end) times h / 2^k stays
within the stability limit. A step whose rate grows past the limit during the step is
rejected and redone at a deeper level, wear and contact state restored; past the level
cap the case stops with ST_UNSTABLE_STEP. Wear, the contact's impact velocity and the
contact angle advance once per accepted sub-step.
"""

import math

import numpy as np
from numba import literally, njit, types

from . import jointkinds as kinds
from .compiled import compiled
from .contact import episode_impact_velocity, surface
from .dynamics import NZ, VZ_ROWS, evaluate
from .jointkinds import MULTI_ROW, is_multi, multi_free
from .joints import BODIES, JOINTS
from .jointset import ALL, guide_axis, has_clearance
from .kinematics import cross, gmat, mtv, mv, point_state, rotation, trig
from .kinematics import sub as vsub
from .layout import (
    CAP_SLOT_ROW,
    D_CONS,
    D_DDOT,
    D_DELTA,
    D_DFD,
    D_DFDD,
    D_ECC,
    D_FN,
    D_HWEAR,
    D_KE,
    D_NORMAL,
    D_PE_GRAV,
    D_RATE,
    D_SLIDER_ACC,
    D_TORQUE,
    D_UEL,
    D_VT,
    D_WORN,
    I_DEEPEST,
    I_SAVED,
    I_SECTIONS,
    I_STATUS,
    I_STEPS,
    I_SUBSTEPS,
    J_PEN_STOP,
    J_RI,
    M_ACC_PEAK,
    M_ACC_SQ,
    M_CONTACT_T,
    M_FN_PEAK,
    M_IMPACTS,
    M_PEN_PEAK,
    M_SAMPLES,
    M_TIME,
    M_TORQUE_PEAK,
    M_VIMP_MAX,
    N_ANGLE_BINS,
    N_CAP,
    N_CAP_ROWS,
    N_D,
    N_INFO,
    N_JOINTS,
    N_M,
    N_R,
    N_S,
    N_SEC,
    N_TRACK,
    N_WINDOWS,
    N_Y,
    P_AMPL,
    P_CONS_TOL,
    P_DT,
    P_DV0_MIN,
    P_ENERGY_TOL,
    P_L2,
    P_L3,
    P_MAX_LEVEL,
    P_OMEGA,
    P_ONSET,
    P_SECTION_PHASE,
    P_SETTLE,
    P_SLIP,
    P_STAB,
    P_THETA0,
    P_WEAR,
    P_ZS,
    R_FIRST_IMPACT,
    R_KE_PEAK,
    R_RESIDUAL_MAX,
    S_BETA,
    S_DV0,
    S_SLOT,
    SEC_OFFSET,
    SEC_RATE,
    SEC_SLIDER_ACC,
    SEC_TIME,
    ST_CONSTRAINT,
    ST_ENERGY,
    ST_EULER,
    ST_NONFINITE,
    ST_OK,
    ST_PENETRATION,
    ST_UNSTABLE_STEP,
    T_KE_PEAK,
    T_RESIDUAL_MAX,
    T_WORK_MAX,
    W_SETTLED,
    W_WHOLE,
    Y_CRANK_ANGLE,
    Y_DISS,
    Y_QD,
    Y_ROD_BETA,
    Y_SLIDER_X,
    Y_WORK,
)
from .target import on_device
from .wear import projection_bins
from .work import Model, Rk4Work, Solve, Wear

EULER_LIMIT = 80.0 * math.pi / 180.0  # |beta| stop of docs/physics.md section 1 [rad]


@compiled
def level_for(rate, h, limit):
    """Smallest k with rate * h / 2^k <= limit."""
    x = rate * h / limit
    if not x > 1.0:
        return 0
    return int(math.ceil(math.log2(x) - 1e-12))


@compiled
def energy_total(dg):
    e = dg[D_KE] + dg[D_PE_GRAV]
    for j in range(N_JOINTS):
        e += dg[D_UEL + j]
    return e


#: Local variables that Numba must type as plain values: a constant argument would otherwise
#: compile the callee once per value (a Literal specialisation), evaluate among them.
_NOT_LITERAL = {"stage": types.boolean, "step_end": types.boolean, "whole": types.int64,
                "settled": types.int64}


@compiled(inline="always", locals=_NOT_LITERAL)
def rk4_substep(t, hs, y, k1, ksum, kst, yt, dg, model, solve, stage, spec):
    """One RK4 step of size hs from (t, y) with k1 = f(t, y) given; y is advanced in place
    (``model``, ``solve``: :func:`dynamics.evaluate`'s; ``stage``: False, the caller's
    variable typed as a plain boolean: the stage derivatives only, no energies, no stiff
    rates; ``spec``: the build's joint set, ``jointset``).

    The stage derivatives k2, k3, k4 (at t + c hs, c = 1/2, 1/2, 1) come from one call of
    evaluate in a loop, each into the work array ``kst``; the work array ``ksum`` keeps
    k2, then k2 + k3 (the sum the update uses, formed as before: bit-identical). One call
    site because a GPU build inlines evaluate wherever it is called: three sites made the
    kernel's code, and the register spills that each copy brings, three times larger.

    Inlined into :func:`advance` (``inline="always"``; a GPU build inlines every device
    function anyway: registers and spills as before). As a call of its own it took its
    ten arguments' fields, about 110 stack words (each array is passed as its pointer,
    shape and strides), at every step, and after joint P the steps/s of cases without P
    clearance fell to 0.89-0.92 of the tree before, most of it in advance's own code, in
    those argument copies (benchmarks/README.md, "Joint P"). ``stage`` is an argument
    because an inlined function's ``locals`` do not reach its caller: a literal False
    here compiled evaluate a second time, and that copy ran slower (0.96-0.97 of
    c65bb49's ideal case against 1.05-1.07).
    """
    n = y.shape[0]
    copy_into(kst, k1)
    for i_stage in range(3):
        c = 1.0 if i_stage == 2 else 0.5
        for i in range(n):
            yt[i] = y[i] + c * hs * kst[i]
        st = evaluate(t + c * hs, yt, model, kst, dg, stage, solve, spec)
        if st != ST_OK:
            return st
        if i_stage == 0:
            copy_into(ksum, kst)
        elif i_stage == 1:
            for i in range(n):
                ksum[i] += kst[i]
    for i in range(n):
        y[i] += hs / 6.0 * (k1[i] + 2.0 * ksum[i] + kst[i])
    return ST_OK


#: Wear of consecutive steps is spread on the map as one cap while the contact direction
#: stays within this fraction of the cap's angular radius of the waiting wear's mean
#: direction and the cap area within WEAR_MERGE_AREA of its mean.
WEAR_MERGE_ANGLE = 0.05
WEAR_MERGE_AREA = 0.05


@compiled
def wear_mergeable(pend, cur, j, spec):
    """Whether joint j's wear of the step, ``cur[j]``, may join its waiting wear ``pend[j]``
    (rows as in integrate: sum V n, sum V, sum V A, and the surface's scale: R_i on a
    sphere, R_i L on a bearing) without moving the cap noticeably (its type's
    ``cap_mergeable``: within WEAR_MERGE_ANGLE of the cap's angular radius; ``spec``: the
    build's joint set, which gives the row's type)."""
    ap = pend[j, 4] / pend[j, 3]
    ac = cur[j, 4] / cur[j, 3]
    if abs(ac - ap) > WEAR_MERGE_AREA * ap:
        return False
    np_ = math.sqrt(pend[j, 0] * pend[j, 0] + pend[j, 1] * pend[j, 1] + pend[j, 2] * pend[j, 2])
    nc = math.sqrt(cur[j, 0] * cur[j, 0] + cur[j, 1] * cur[j, 1] + cur[j, 2] * cur[j, 2])
    d2 = 0.0
    for i in range(3):
        d = pend[j, i] / np_ - cur[j, i] / nc
        d2 += d * d
    return kinds.cap_mergeable(spec, j, d2, WEAR_MERGE_ANGLE, ap, pend[j, 5])


@compiled
def flush_wear(wmap, j, pend, scratch, spec):
    """Spread joint j's waiting wear on its map (volume-weighted mean direction and cap
    area, its type's ``deposit_cap`` in the build of joint set ``spec``); clear it; return
    the largest depth written [m]."""
    size = math.sqrt(pend[j, 0] * pend[j, 0] + pend[j, 1] * pend[j, 1] + pend[j, 2] * pend[j, 2])
    n = (pend[j, 0] / size, pend[j, 1] / size, pend[j, 2] / size)
    top = kinds.deposit_cap(spec, wmap, j, n, pend[j, 3], pend[j, 4] / pend[j, 3], pend[j, 5],
                            scratch)
    for i in range(6):
        pend[j, i] = 0.0
    return top


@compiled
def copy_into(dst, src):
    """dst[:] = src for 1-d arrays, without making a slice view."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@compiled
def zero_rows(a):
    """a[:, :] = 0 for 2-d arrays, without making a slice view."""
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            a[i, k] = 0.0


@compiled
def copy_rows_into(dst, src):
    """dst[:, :] = src for 2-d arrays, without making a slice view."""
    for i in range(src.shape[0]):
        for k in range(src.shape[1]):
            dst[i, k] = src[i, k]


@compiled
def copy_row(dst, row, src):
    """dst[row, :] = src, without making a slice view."""
    for i in range(src.shape[0]):
        dst[row, i] = src[i]


@compiled
def keep_accepted(s, ssave, stats, msave, first, first_save, ddot_prev, ddot_prev_save):
    """Copy what only an accepted sub-step changes (the contact state s, the statistics, the
    first impact times, the approach rates) into its keeping arrays (the second of each
    pair); called with the pairs swapped, it restores them."""
    copy_rows_into(ssave, s)
    copy_rows_into(msave, stats)
    copy_into(first_save, first)
    copy_into(ddot_prev_save, ddot_prev)


@compiled
def hermite_range(f0, f1, m0, m1, lo):
    """Smallest and largest value over u in [lo, 1] of the cubic Hermite H(u) with H(0) = f0,
    H(1) = f1, H'(0) = m0, H'(1) = m1 (slopes per unit u: the time slope times the step)."""
    c2 = 3.0 * (f1 - f0) - 2.0 * m0 - m1
    c3 = 2.0 * (f0 - f1) + m0 + m1
    low = f1
    high = f1
    if lo > 0.0:
        v = f0 + lo * (m0 + lo * (c2 + lo * c3))
        low = min(low, v)
        high = max(high, v)
    # interior extrema: H'(u) = m0 + 2 c2 u + 3 c3 u^2 = 0
    a = 3.0 * c3
    b = 2.0 * c2
    r1 = -1.0
    r2 = -1.0
    if a == 0.0:
        if b != 0.0:
            r1 = -m0 / b
    else:
        disc = b * b - 4.0 * a * m0
        if disc >= 0.0:
            q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
            r1 = q / a
            if q != 0.0:
                r2 = m0 / q
    for r in (r1, r2):
        if lo < r < 1.0:
            v = f0 + r * (m0 + r * (c2 + r * c3))
            low = min(low, v)
            high = max(high, v)
    return low, high


@compiled
def mean_slopes(f0, f1, mean):
    """End slopes (per unit step) of the quadratic through f0 and f1 whose mean over the step
    is ``mean``: the derivative of the cubic Hermite of the integral of f (its ends' values
    and rates f0, f1), so that :func:`hermite_range` reads the quadratic."""
    return 6.0 * mean - 4.0 * f0 - 2.0 * f1, -6.0 * mean + 2.0 * f0 + 4.0 * f1


@compiled
def hermite_value(f0, f1, m0, m1, u):
    """The cubic Hermite of :func:`hermite_range` at u."""
    c2 = 3.0 * (f1 - f0) - 2.0 * m0 - m1
    c3 = 2.0 * (f0 - f1) + m0 + m1
    return f0 + u * (m0 + u * (c2 + u * c3))


#: What :func:`record_sample` keeps of a (sub-)step's end for the next one's start, entries
#: of the work row ``prev``: slider acceleration, crank torque, slider velocity, drive work,
#: crank rate, then per joint F_N, delta, delta_dot, dF_N/d delta, dF_N/d delta_dot.
PV_ACC = 0
PV_TORQUE = 1
PV_V = 2
PV_WORK = 3
PV_RATE = 4
PV_FN = 5
PV_DELTA = PV_FN + N_JOINTS
PV_DDOT = PV_DELTA + N_JOINTS
PV_DFD = PV_DDOT + N_JOINTS
PV_DFDD = PV_DFD + N_JOINTS
N_PV = PV_DFDD + N_JOINTS

#: Largest |h10|, |h11| of the cubic Hermite basis on [0, 1]: a cubic Hermite never leaves
#: max(f0, f1) + HERMITE_REACH (|m0| + |m1|), so that a step whose bound stays below the
#: running peak needs no search for its maximum (the same statistics, fewer operations).
HERMITE_REACH = 4.0 / 27.0


@compiled
def keep_ends(prev, dg, y, spec):
    """prev = what :func:`record_sample` reads of a (sub-)step's start: the values of the
    state y and its diagnostics dg (PV_*)."""
    prev[PV_ACC] = dg[D_SLIDER_ACC]
    prev[PV_TORQUE] = dg[D_TORQUE]
    prev[PV_V] = y[Y_QD + Y_SLIDER_X + guide_axis(spec)]
    prev[PV_WORK] = y[Y_WORK]
    prev[PV_RATE] = y[Y_QD + Y_CRANK_ANGLE]
    for j in range(N_JOINTS):
        prev[PV_FN + j] = dg[D_FN + j]
        prev[PV_DELTA + j] = dg[D_DELTA + j]
        prev[PV_DDOT + j] = dg[D_DDOT + j]
        prev[PV_DFD + j] = dg[D_DFD + j]
        prev[PV_DFDD + j] = dg[D_DFDD + j]


@compiled
def step_peak(f0, f1, m0, m1, floor, absolute):
    """The largest value over a step of the cubic Hermite through f0, f1 with slopes m0, m1
    (per unit step; of its absolute value with ``absolute``), searched for only where its
    bound max(f0, f1) + HERMITE_REACH (|m0| + |m1|) exceeds ``floor``; else |f1| or f1,
    which then changes no running peak at or above floor."""
    if absolute:
        if max(abs(f0), abs(f1)) + HERMITE_REACH * (abs(m0) + abs(m1)) <= floor:
            return abs(f1)
        low, high = hermite_range(f0, f1, m0, m1, 0.0)
        return max(-low, high)
    if max(f0, f1) + HERMITE_REACH * (abs(m0) + abs(m1)) <= floor:
        return f1
    _, high = hermite_range(f0, f1, m0, m1, 0.0)
    return high


@compiled
def fold_peak(m, i, peak, settled_lo, f0, f1, m0, m1, absolute):
    """Fold a step's peak (:func:`step_peak`, over the whole step) into column i of both
    windows: the whole run's, and the settled window's where settled_lo >= 0, over the
    step's part u >= settled_lo (searched again where that is not the whole step)."""
    m[W_WHOLE, i] = max(m[W_WHOLE, i], peak)
    if settled_lo > 0.0:
        low, high = hermite_range(f0, f1, m0, m1, settled_lo)
        m[W_SETTLED, i] = max(m[W_SETTLED, i], max(-low, high) if absolute else high)
    elif settled_lo == 0.0:
        m[W_SETTLED, i] = max(m[W_SETTLED, i], peak)


@compiled
def record_windows(m, prev, dg, y, jp, weight, settled_lo, spec):
    """:func:`record_sample`'s statistics in a loop over the windows (the device build's
    arrangement): the same values, one copy of the peak search where the build inlines it."""
    for w in range(N_WINDOWS if settled_lo >= 0.0 else 1):
        lo = 0.0 if w == W_WHOLE else settled_lo
        acc = dg[D_SLIDER_ACC]
        acc_peak = abs(acc)
        torque_peak = abs(dg[D_TORQUE])
        if weight > 0.0:
            a0 = prev[PV_ACC]
            m0, m1 = mean_slopes(a0, acc, (y[Y_QD + Y_SLIDER_X + guide_axis(spec)] - prev[PV_V])
                                 / weight)
            low, high = hermite_range(a0, acc, m0, m1, lo)
            acc_peak = max(-low, high)
            rate = 0.5 * (prev[PV_RATE] + y[Y_QD + Y_CRANK_ANGLE])
            t0 = prev[PV_TORQUE]
            m0, m1 = mean_slopes(t0, dg[D_TORQUE], (y[Y_WORK] - prev[PV_WORK]) / (weight * rate))
            low, high = hermite_range(t0, dg[D_TORQUE], m0, m1, lo)
            torque_peak = max(-low, high)
        m[w, M_ACC_PEAK] = max(m[w, M_ACC_PEAK], acc_peak)
        m[w, M_ACC_SQ] += acc * acc * weight
        m[w, M_TORQUE_PEAK] = max(m[w, M_TORQUE_PEAK], torque_peak)
        m[w, M_TIME] += weight
        m[w, M_SAMPLES] += 1.0
        for j in range(N_JOINTS):
            if not has_clearance(spec, jp, j):
                continue
            fn_peak = dg[D_FN + j]
            pen_peak = dg[D_DELTA + j]
            if weight > 0.0:
                d0 = prev[PV_DELTA + j]
                v0 = prev[PV_DDOT + j] * weight
                v1 = dg[D_DDOT + j] * weight
                _, pen_peak = hermite_range(d0, pen_peak, v0, v1, lo)
                f0 = prev[PV_FN + j]
                if f0 > 0.0 or fn_peak > 0.0:
                    dd = v1 - v0
                    s0 = prev[PV_DFD + j] * v0 + prev[PV_DFDD + j] * dd / weight
                    s1 = dg[D_DFD + j] * v1 + dg[D_DFDD + j] * dd / weight
                    _, fn_peak = hermite_range(f0, fn_peak, s0, s1, lo)
            m[w, M_FN_PEAK + j] = max(m[w, M_FN_PEAK + j], fn_peak)
            m[w, M_PEN_PEAK + j] = max(m[w, M_PEN_PEAK + j], pen_peak)
            if dg[D_DELTA + j] > 0.0:
                m[w, M_CONTACT_T + j] += weight


@compiled
def record_sample(m, prev, dg, y, jp, weight, settled_lo, spec):
    """Fold one accepted (sub-)step into the running statistics m: the step from the start
    that ``prev`` holds (:func:`keep_ends`) to the state y (diagnostics dg), of length
    ``weight`` [s] (0: the initial state alone, prev unused), into the whole-run window
    and, where ``settled_lo`` >= 0, the settled one over the step's part u >= settled_lo;
    then prev keeps this step's end for the next. ``spec``: the build's joint set
    (``jointset``), whose joints alone have peaks to read.

    Time integrals (RMS, time in contact) use the right-end value over each (sub-)step.
    Peaks are read within the step (u = (t - t_start) / weight in [0, 1], or [settled_lo,
    1] where the settled window begins inside the step) from a cubic in time through the
    step's end values and their rates (docs/physics.md section 8.1):

    - slider acceleration a: the slider velocity v is a state, so the quadratic through
      a0, a1 with the step's mean acceleration (v1 - v0) / weight (the derivative of the
      cubic Hermite of v); crank torque T likewise from the drive work W, dW/dt = T
      theta_dot;
    - penetration delta: the cubic Hermite through delta and its rate delta_dot (the
      normal approach rate, an exact derivative);
    - normal force F_N(delta, delta_dot): the cubic Hermite through F_N with the end rates
      dF_N/dt = dF_N/d delta delta_dot + dF_N/d delta_dot delta_ddot (D_DFD, D_DFDD), the
      approach acceleration delta_ddot taken as delta_dot's change over the step. The
      chain rule rather than F_N's finite change: the end rates are then the contact law's
      at each end, so that a step in which the force turns over gets its interior maximum.
      delta_ddot from delta_dot, not from a Hermite of delta: delta jumps where the contact
      direction crosses into a wear-map bin of another depth (c_eff is read from the bin),
      delta_dot does not, and a jump read as motion gave end rates that overshot the force.

    A step's peak is searched for once for both windows, and only where the cubic's bound
    exceeds the settled window's peak (or the whole run's before the window), which is the
    smaller: below it, neither window's peak can move (the same statistics, fewer
    operations). A device build (``target.on_device``) takes the same values in a loop
    over the windows instead, with one copy of the search (fewer registers spilled).
    """
    if on_device():
        record_windows(m, prev, dg, y, jp, weight, settled_lo, spec)
        keep_ends(prev, dg, y, spec)
        return
    settled = settled_lo >= 0.0
    w_floor = W_SETTLED if settled else W_WHOLE
    acc = dg[D_SLIDER_ACC]
    torque = dg[D_TORQUE]
    a0 = acc
    t0 = torque
    ma0 = 0.0
    ma1 = 0.0
    mt0 = 0.0
    mt1 = 0.0
    if weight > 0.0:
        a0 = prev[PV_ACC]
        ma0, ma1 = mean_slopes(a0, acc, (y[Y_QD + Y_SLIDER_X + guide_axis(spec)] - prev[PV_V])
                               / weight)
        rate = 0.5 * (prev[PV_RATE] + y[Y_QD + Y_CRANK_ANGLE])
        t0 = prev[PV_TORQUE]
        mt0, mt1 = mean_slopes(t0, torque, (y[Y_WORK] - prev[PV_WORK]) / (weight * rate))
    fold_peak(m, M_ACC_PEAK, step_peak(a0, acc, ma0, ma1, m[w_floor, M_ACC_PEAK], True),
              settled_lo, a0, acc, ma0, ma1, True)
    fold_peak(m, M_TORQUE_PEAK, step_peak(t0, torque, mt0, mt1, m[w_floor, M_TORQUE_PEAK],
                                          True), settled_lo, t0, torque, mt0, mt1, True)
    for w in range(N_WINDOWS if settled else 1):
        m[w, M_ACC_SQ] += acc * acc * weight
        m[w, M_TIME] += weight
        m[w, M_SAMPLES] += 1.0
    for j in range(N_JOINTS):
        if not has_clearance(spec, jp, j):
            continue
        d1 = dg[D_DELTA + j]
        f1 = dg[D_FN + j]
        d0 = d1
        v0 = 0.0
        v1 = 0.0
        f0 = f1
        s0 = 0.0
        s1 = 0.0
        if weight > 0.0:
            d0 = prev[PV_DELTA + j]
            v0 = prev[PV_DDOT + j] * weight
            v1 = dg[D_DDOT + j] * weight
            f0 = prev[PV_FN + j]
            if f0 > 0.0 or f1 > 0.0:
                # delta_ddot * weight^2, the same at both ends: delta_dot's change
                dd = v1 - v0
                s0 = prev[PV_DFD + j] * v0 + prev[PV_DFDD + j] * dd / weight
                s1 = dg[D_DFD + j] * v1 + dg[D_DFDD + j] * dd / weight
        fold_peak(m, M_PEN_PEAK + j, step_peak(d0, d1, v0, v1, m[w_floor, M_PEN_PEAK + j],
                                               False), settled_lo, d0, d1, v0, v1, False)
        fold_peak(m, M_FN_PEAK + j, step_peak(f0, f1, s0, s1, m[w_floor, M_FN_PEAK + j],
                                              False), settled_lo, f0, f1, s0, s1, False)
        if d1 > 0.0:
            for w in range(N_WINDOWS if settled else 1):
                m[w, M_CONTACT_T + j] += weight
    keep_ends(prev, dg, y, spec)


# --------------------------------------------------------------------------- Poincare sections

TWO_PI = 2.0 * math.pi


def _attachment_row(att):
    """An attachment of the joint table (joints.Attachment) as floats: (state index of its
    body's centroid, of its Euler angles, packed index of the length that scales it, the
    three factors); -1 for a body outside the state (the ground: a fixed point, global
    frame) or for no length (the centroid)."""
    body = {b.name: b for b in BODIES if b.y_r is not None}.get(att.body)
    lengths = {"l2": P_L2, "l3": P_L3, "zs": P_ZS}
    return (float(body.y_r) if body else -1.0, float(body.y_phi) if body else -1.0,
            float(lengths[att.length]) if att.length else -1.0) + tuple(map(float, att.factors))


#: Each joint's ball attachment, then its socket's (rows 2 j, 2 j + 1), for the sections.
SECTION_ATTACHMENTS = tuple(_attachment_row(a) for joint in JOINTS for a in (joint.ball, joint.socket))


@compiled
def section_lead(p, t0):
    """Time from t0 to the first Poincare section [s]: the driven crank angle
    theta(t) = theta0 + omega t reaches p[P_SECTION_PHASE] + 2 pi k; a crossing at t0 itself
    (within 1e-9 rad) is not taken."""
    x = p[P_SECTION_PHASE] - p[P_THETA0] - p[P_OMEGA] * t0
    x -= TWO_PI * math.floor(x / TWO_PI)
    if x >= TWO_PI:
        x = 0.0
    if x < 1e-9:
        x += TWO_PI
    return x / p[P_OMEGA]


@compiled
def section_time(p, t0, k):
    """Time of section k (0-based: revolution k + 1) of a run from t0 [s]."""
    return t0 + section_lead(p, t0) + TWO_PI * k / p[P_OMEGA]


@compiled
def section_count(p, t0, n_steps):
    """Sections a run of n_steps output-grid steps from t0 holds (within 1e-9 of a
    revolution of its end): the rows of ``Out.sec`` that the integrators fill."""
    turns = (n_steps * p[P_DT] - section_lead(p, t0)) * p[P_OMEGA] / TWO_PI
    if turns < -1e-9:
        return 0
    return int(math.floor(turns + 1e-9)) + 1


#: Entries of the work row ``Rk4Work.secnext``: the next section's time [s] (NaN: none
#: left), its row of Out.sec, the slider acceleration there while its step is under way.
SN_TIME = 0
SN_ROW = 1
SN_ACC = 2


@compiled
def next_section(sec, secnext, k):
    """secnext: section row k next (its planned time, NaN past the rows planned)."""
    secnext[SN_ROW] = k
    secnext[SN_TIME] = sec[k, SEC_TIME] if k < sec.shape[0] else math.nan


@compiled
def section_in(secnext, t, sub, hs, last):
    """(Whether the next section (``secnext``, :func:`next_section`) falls in sub-step
    ``sub`` of the step from t, of sub-steps hs: in (t + sub hs, t + (sub + 1) hs], at or
    before its end for sub 0, with no upper bound in the run's ``last`` sub-step; its time).
    ``sub`` = -1 with hs = the whole step: at or before the step's end. The bounds are the
    same products for adjacent sub-steps, so that each section falls in exactly one. Reads
    a work row alone: no pointer to the results stays live across the step (a GPU
    thread's registers)."""
    tk = secnext[SN_TIME]
    if not tk == tk:
        return False, tk
    if sub < 0:
        return last or tk <= t + hs, tk
    if sub > 0 and not tk > t + sub * hs:
        return False, tk
    return last or tk <= t + (sub + 1) * hs, tk


@compiled
def plan_sections(p, t0, n_steps, sec):
    """Every section row NaN (an ideal joint's offsets and rates stay so) but the times of
    the sections a run from t0 of n_steps holds (:func:`section_count`, as many as fit)."""
    n = min(sec.shape[0], section_count(p, t0, n_steps))
    for k in range(sec.shape[0]):
        for i in range(N_SEC):
            sec[k, i] = math.nan
        if k < n:
            sec[k, SEC_TIME] = section_time(p, t0, k)


@compiled
def end_sections(sec, taken):
    """At the end of a run: the rows past the ``taken`` sections NaN (a run that stopped)."""
    for k in range(taken, sec.shape[0]):
        for i in range(N_SEC):
            sec[k, i] = math.nan


@compiled
def hermite_state(out, u, hs, y0, f0, y1, f1):
    """out = the cubic Hermite at t0 + u hs of the step from (y0, f0 = y0') to (y1, f1)."""
    v = 1.0 - u
    h00 = (1.0 + 2.0 * u) * v * v
    h10 = u * v * v * hs
    h01 = u * u * (3.0 - 2.0 * u)
    h11 = -u * u * v * hs
    for i in range(y0.shape[0]):
        out[i] = h00 * y0[i] + h10 * f0[i] + h01 * y1[i] + h11 * f1[i]


@compiled
def attachment_state(p, y, row):
    """(position, velocity, rotation, body angular velocity) of the attachment
    SECTION_ATTACHMENTS[row] at state y: the ball or socket centre and its body's frame."""
    a = SECTION_ATTACHMENTS[row]
    length = p[int(a[2])] if a[2] >= 0.0 else 0.0
    u = (length * a[3], length * a[4], length * a[5])
    if a[0] < 0.0:
        eye = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
        return u, (0.0, 0.0, 0.0), eye, (0.0, 0.0, 0.0)
    r_at = int(a[0])
    phi_at = int(a[1])
    tr = trig(y[phi_at], y[phi_at + 1], y[phi_at + 2])
    R = rotation(tr)
    w = mv(gmat(tr), (y[Y_QD + phi_at], y[Y_QD + phi_at + 1], y[Y_QD + phi_at + 2]))
    pos, vel = point_state((y[r_at], y[r_at + 1], y[r_at + 2]),
                           (y[Y_QD + r_at], y[Y_QD + r_at + 1], y[Y_QD + r_at + 2]), R, w, u)
    return pos, vel, R, w


@compiled
def section_offsets(p, jp, ys, sec, k, spec):
    """Section row k's offsets from the state ys at the section: each clearance joint's
    ball-centre offset d_s = R_s^T (p_ball - p_socket) in its socket frame over c (as the
    diagnostics D_OFFSET), and its rate R_s^T (v_ball - v_socket) - w_s x d_s over c, from
    the joint table's attachments (kinematics alone: no evaluation of the equations of
    motion, whose every call site a device build inlines), each over its clearance by its
    type's ``section_offsets``; ``spec``: the build's joint set (``jointset``)."""
    # one loop over the attachments, ball then socket of each joint (one copy of
    # attachment_state where a device build inlines it)
    pb = (0.0, 0.0, 0.0)
    vb = (0.0, 0.0, 0.0)
    for row in range(2 * N_JOINTS):
        j = row // 2
        if not has_clearance(spec, jp, j):
            continue
        pos, vel, R, w = attachment_state(p, ys, row)
        if row % 2 == 0:
            pb = pos
            vb = vel
            continue
        d = mtv(R, vsub(pb, pos))
        rate = vsub(mtv(R, vsub(vb, vel)), cross(w, d))
        off, off_rate = kinds.section_offsets(spec, jp, j, kinds.type_vector(spec, j, d),
                                              kinds.type_vector(spec, j, rate))
        sec[k, SEC_OFFSET + 3 * j] = off[0]
        sec[k, SEC_RATE + 3 * j] = off_rate[0]
        sec[k, SEC_OFFSET + 3 * j + 1] = off[1]
        sec[k, SEC_RATE + 3 * j + 1] = off_rate[1]
        sec[k, SEC_OFFSET + 3 * j + 2] = off[2]
        sec[k, SEC_RATE + 3 * j + 2] = off_rate[2]


@compiled
def accept_substep(hs, in_settled, model, dg, stats, wear, nbuf, ddot_prev, spec=ALL):
    """What an accepted (sub-)step of length hs changes besides the state: wear (into the
    projections, the worn volume, the step's cap ``cur`` and the undo buffer at row ``nbuf``
    of ``wear``, a :data:`work.Wear`), the contact angle and episode impact velocity in
    ``model.s``, impact counts and velocities.

    The one-point rule: each joint's contact episode from its diagnostics, its wear on its
    type's surface (``paper_angle``, ``wear_surface``). A multi-contact joint's points take
    their type's own rules (:func:`accept_multi`, called beside this where such a joint has
    clearance): their wear waits in ``cur`` until the step is accepted, and needs no undo.

    ``spec``: the build's joint set (``jointset``; default every joint, each tested at
    run time). Returns (whether the contact state changed, so that the step-end evaluation
    must be redone; the next free undo-buffer row).
    """
    p = model.p
    jp = model.jp
    s = model.s
    proj = wear.proj
    wvol = wear.wvol
    cur = wear.cur
    buf_i = wear.buf_i
    buf_v = wear.buf_v
    wear_on = p[P_WEAR] != 0.0
    paper_slip = p[P_SLIP] != 0.0
    ampl = p[P_AMPL]
    changed = False
    for j in range(N_JOINTS):
        if not has_clearance(spec, jp, j) or is_multi(j):
            continue
        ddot = dg[D_DDOT + j]
        if dg[D_DELTA + j] > 0.0:
            fn = dg[D_FN + j]
            ri = jp[j, J_RI]
            e = dg[D_ECC + j]
            pen = dg[D_DELTA + j] + dg[D_HWEAR + j]  # against the unworn radii
            # the contact angle matters to the paper's slip rule only, where the type
            # follows it (a sphere; a bearing: pi)
            beta = math.pi
            paper = False
            if paper_slip:
                beta, paper = kinds.paper_angle(spec, jp, j, pen, e)
            if wear_on and fn > 0.0:
                if not paper:
                    ds = dg[D_VT + j] * hs
                else:
                    ds = ri * abs(beta - s[j, S_BETA])
                _, _, k_wear = surface(jp, j, dg[D_WORN + j] != 0.0)
                vol = ampl * k_wear * fn * ds
                nrm = (dg[D_NORMAL + 3 * j], dg[D_NORMAL + 3 * j + 1],
                       dg[D_NORMAL + 3 * j + 2])
                # the type's surface: a sphere's cap (weights |n|), a bearing's strip 2 psi
                # R_i L (its depth projected about the bearing's axis)
                area, wx, wy, wz, scale_j = kinds.wear_surface(spec, jp, j, pen, e, nrm)
                bx, by, bz = projection_bins(nrm, N_ANGLE_BINS)
                buf_i[nbuf, 0] = j
                buf_i[nbuf, 1] = bx
                buf_i[nbuf, 2] = by
                buf_i[nbuf, 3] = bz
                buf_v[nbuf, 0] = vol
                buf_v[nbuf, 1] = vol * wx / area
                buf_v[nbuf, 2] = vol * wy / area
                buf_v[nbuf, 3] = vol * wz / area
                for i in range(3):
                    cur[j, i] += vol * nrm[i]
                cur[j, 3] += vol
                cur[j, 4] += vol * area
                cur[j, 5] = scale_j
                proj[j, 0, bx] += buf_v[nbuf, 1]
                proj[j, 1, by] += buf_v[nbuf, 2]
                proj[j, 2, bz] += buf_v[nbuf, 3]
                wvol[j] += vol
                nbuf += 1
            s[j, S_BETA] = beta
            dv0 = episode_impact_velocity(s[j, S_DV0], ddot, p[P_DV0_MIN], p[P_ONSET] != 0.0)
            if s[j, S_DV0] == 0.0:
                # onset of a contact episode: an impact
                s[j, S_DV0] = dv0
                changed = True
                vimp = max(ddot, ddot_prev[j])
                stats[W_WHOLE, M_IMPACTS + j] += 1.0
                stats[W_WHOLE, M_VIMP_MAX + j] = max(stats[W_WHOLE, M_VIMP_MAX + j],
                                                     vimp)
                if in_settled:
                    stats[W_SETTLED, M_IMPACTS + j] += 1.0
                    stats[W_SETTLED, M_VIMP_MAX + j] = max(
                        stats[W_SETTLED, M_VIMP_MAX + j], vimp)
            elif dv0 != s[j, S_DV0]:
                s[j, S_DV0] = dv0
                changed = True
        elif s[j, S_DV0] != 0.0:
            s[j, S_DV0] = 0.0
            s[j, S_BETA] = math.pi
            changed = True
        ddot_prev[j] = ddot
    return changed, nbuf


@compiled
def accept_multi(hs, in_settled, model, stats, cur, y, spec):
    """:func:`accept_substep`'s part for the multi-contact joint with clearance
    (``jointkinds.MULTI_ROW``, a constant; ``spec``: the build's joint set): its points'
    impacts and wear (its type's ``accept``) from its ball's body state in y
    (``jointkinds.type_body``). A call of its own beside accept_substep, so that the step's
    bookkeeping of every case without such a joint is what it was before the prismatic
    joint (steps/s, benchmarks/README.md). Returns whether a point's episode changed."""
    if multi_free(spec, model.jp):
        return kinds.accept(spec, MULTI_ROW, model, kinds.type_body(spec, MULTI_ROW, y), hs,
                            in_settled, stats, cur)
    return False


@compiled
def step_checks(y, dg, p, jp, status, e0, track, spec):
    """Status after an accepted output-grid step (docs/physics.md section 4): non-finite
    state, Euler-angle limit, penetration, constraint drift, energy residual. ``track``
    (peak kinetic energy, largest |drive work|, largest |residual| [J]) is updated in place;
    ``spec``: the build's joint set (``jointset``).
    """
    for i in range(N_Y):
        if not math.isfinite(y[i]):
            status = ST_NONFINITE
    if status == ST_OK and abs(y[Y_ROD_BETA]) > EULER_LIMIT:
        status = ST_EULER
    for j in range(N_JOINTS):
        if has_clearance(spec, jp, j) and dg[D_DELTA + j] > jp[j, J_PEN_STOP]:
            status = ST_PENETRATION
    track[T_KE_PEAK] = max(track[T_KE_PEAK], dg[D_KE])
    track[T_WORK_MAX] = max(track[T_WORK_MAX], abs(y[Y_WORK]))
    res = energy_total(dg) - y[Y_WORK] + y[Y_DISS] - e0
    track[T_RESIDUAL_MAX] = max(track[T_RESIDUAL_MAX], abs(res))
    if status == ST_OK and not (dg[D_CONS] <= p[P_CONS_TOL]):
        status = ST_CONSTRAINT
    if status == ST_OK:
        throughput = max(track[T_KE_PEAK], max(track[T_WORK_MAX], y[Y_DISS]))
        if not (abs(res) <= p[P_ENERGY_TOL] * throughput):
            status = ST_ENERGY
    return status


#: The CUDA batch kernel (core/device.py) keeps advance's work arrays grouped, one batched
#: array per group with the case as its first axis (:func:`work_shapes`), and hands advance
#: their rows; the CPU path (:func:`integrate`) allocates each work array on its own, so that
#: no array view is made or passed in the hot loop. Rows of each group, in advance's
#: argument order:
#: vec: y, its copy at the step's start, k1, k1's copy, k2 (+ k3), the stage derivative,
#: the stage state, y and k1 at the start of a sub-step with a section, the next section's
#: bookkeeping;
#: diag: dg, its copy at the step's start, the sub-step start's values for record_sample; cstate: contact state
#: s and its copy; pairs: ddot_prev, its copy, the largest depth written per joint, the
#: first impact times and their copy; mats: C, S, L of evaluate; caps: the wear of the step
#: being taken and the accepted wear waiting to be spread.
VEC_ROWS = 10
DIAG_ROWS = 3
CSTATE_ROWS = 2
PAIR_ROWS = 5
#: row of ``pairs`` holding each joint's first impact time (the next row: its copy)
PAIR_FIRST = 3
MAT_ROWS = 3
CAP_ROWS = 2


@compiled
def undo_rows(max_level):
    """Rows of the undo buffer: one per joint and accepted sub-step of the deepest level."""
    return N_JOINTS * (1 << max_level)


#: The grouped work arrays whose entries are int64 (the rest are float64).
INT_WORK = frozenset({"buf_i"})


def work_shapes(max_level, npolar):
    """Shapes of the grouped work arrays by name (vec, diag, cstate, msave, pairs, mats, vz,
    buf_i, buf_v, caps, scratch: the order of run_cases' arguments) for a case of the given
    sub-step level cap and wear-map polar bins; those in :data:`INT_WORK` are int64."""
    nbuf_max = undo_rows(max_level)
    return {"vec": (VEC_ROWS, N_Y), "diag": (DIAG_ROWS, N_D), "cstate": (CSTATE_ROWS, N_JOINTS, N_S),
            "msave": (N_WINDOWS, N_M), "pairs": (PAIR_ROWS, N_JOINTS), "mats": (MAT_ROWS, NZ, NZ),
            "vz": (VZ_ROWS, NZ), "buf_i": (nbuf_max, 4), "buf_v": (nbuf_max, 4),
            "caps": (CAP_ROWS, N_CAP_ROWS, N_CAP), "scratch": (4 * npolar, 3)}


@compiled(inline="always")
def case_views(case, work):
    """The :data:`work.Model`, :data:`work.Solve` and :data:`work.Wear` of a case and the work
    arrays of either integrator (:data:`work.Rk4Work`, :data:`work.Dopri5Work`)."""
    return (Model(case.p, case.jp, work.s, case.wmap), Solve(work.C, work.S, work.L, work.vz),
            Wear(case.proj, case.wvol, work.cur, work.pend, work.buf_i, work.buf_v, work.wmax,
                 work.scratch))


@compiled(locals=_NOT_LITERAL)
def begin_case(t0, y, model, k1, dg, solve, ddot_prev, stats, prev, spec):
    """First evaluation of a case at (t0, y) into k1 and dg; seated balls start in contact
    (their episode begins without an impact); statistics cleared and the initial state
    recorded (``spec``: the build's joint set, ``jointset``). Returns the evaluation's
    status."""
    p = model.p
    jp = model.jp
    s = model.s
    step_end = True
    for w in range(N_WINDOWS):
        for i in range(N_M):
            stats[w, i] = 0.0
    for j in range(N_JOINTS):
        s[j, S_DV0] = 0.0
        s[j, S_BETA] = math.pi
        for k in range(S_SLOT, N_S):
            s[j, k] = 0.0           # a prismatic joint's corner-wall pairs: none in contact
    # evaluated again (one call site: see rk4_substep) when a ball starts on the socket wall
    # (seated start): it is in contact, not an impact
    for again in range(2):
        st = evaluate(t0, y, model, k1, dg, step_end, solve, spec)
        if st != ST_OK:
            return st
        if again == 1:
            break
        seated = False
        for j in range(N_JOINTS):
            ddot_prev[j] = dg[D_DDOT + j]
            # a clearance joint in contact: its type's seated start
            if has_clearance(spec, jp, j) and dg[D_DELTA + j] > 0.0:
                if kinds.seat(spec, j, model, dg, kinds.type_body(spec, j, y)):
                    seated = True
        if not seated:
            break
    record_sample(stats, prev, dg, y, jp, 0.0, 0.0 if t0 >= p[P_SETTLE] else -1.0, spec)
    return ST_OK


@compiled
def merge_wear(wmap, cur, pend, wmax, scratch, spec):
    """After an accepted step: its wear ``cur`` joins the waiting cap ``pend`` when close
    enough (wear_mergeable), else the waiting cap is spread on the map first; a joint
    without wear this step spreads its waiting cap. ``wmax`` keeps the deepest bin [m].
    A multi-contact joint's points spread theirs in :func:`deposit_multi`."""
    for j in range(N_JOINTS):
        if is_multi(j):
            continue
        if cur[j, 3] > 0.0:
            if pend[j, 3] > 0.0 and not wear_mergeable(pend, cur, j, spec):
                wmax[j] = max(wmax[j], flush_wear(wmap, j, pend, scratch, spec))
            for i in range(6):
                pend[j, i] += cur[j, i]
            pend[j, 5] = cur[j, 5]
        elif pend[j, 3] > 0.0:
            wmax[j] = max(wmax[j], flush_wear(wmap, j, pend, scratch, spec))


@compiled
def deposit_multi(wmap, cur, wmax, jp, wvol, spec):
    """After an accepted step, where the multi-contact joint has clearance
    (``jointkinds.MULTI_ROW``, a constant; ``spec``: the build's joint set): its points'
    wear of the step on its map (its type's ``deposit_step``, which adds it to the worn
    volume ``wvol``); ``wmax`` keeps the deepest bin [m]."""
    if multi_free(spec, jp):
        wmax[MULTI_ROW] = max(wmax[MULTI_ROW], kinds.deposit_step(spec, wmap, MULTI_ROW, jp, cur,
                                                                  wvol))


@compiled
def flush_all_wear(wmap, pend, wmax, scratch, spec=ALL):
    """At the end of a run: spread every joint's waiting wear on its map (``wmax`` keeps the
    deepest bin [m]). Every integrator ends with it."""
    for j in range(N_JOINTS):
        if not is_multi(j) and pend[j, 3] > 0.0:
            wmax[j] = max(wmax[j], flush_wear(wmap, j, pend, scratch, spec))


@compiled
def note_first_impact(first, stats, t):
    """Record t as a joint's first impact time when its impact count has just left 0."""
    for j in range(N_JOINTS):
        if first[j] < 0.0 and stats[W_WHOLE, M_IMPACTS + j] > 0.0:
            first[j] = t


@njit(cache=True)
def kernel_result(track, first):
    """What an integrator returns: (largest |energy residual| [J], peak kinetic energy [J],
    first impact time at A, at B [s], NaN when none)."""
    out = np.empty(N_R)
    out[R_RESIDUAL_MAX] = track[T_RESIDUAL_MAX]
    out[R_KE_PEAK] = track[T_KE_PEAK]
    for j in range(N_JOINTS):
        out[R_FIRST_IMPACT + j] = first[j] if first[j] >= 0.0 else np.nan
    return out


@njit(cache=True, locals=_NOT_LITERAL)
def integrate(case, t0, n_steps, save_every, out, spec):
    """Integrate one case over n_steps output-grid steps of size p[P_DT].

    Parameters
    ----------
    case : work.Case
        p, jp : packed parameters; y0 : initial state (layout.N_Y);
        wmap : float64[2, npolar, nazim]   wear map, updated in place [m];
        proj : float64[2, 3, 360]          paper projections, updated in place [m];
        wvol : float64[2]                  worn volume, updated in place [m^3].
    t0 : float
        Start time [s].
    out : work.Out
        t, y, d, wmax : output rows (n_save = n_steps // save_every + 1);
        info : int64[N_INFO] (layout.I_*: status, saved rows, deepest level, RK4 sub-steps
        taken, output-grid steps completed, the stopping step included);
        stats : float64[2, N_M] running statistics (layout.M_*), whole run and settled
        window (time >= p[P_SETTLE]), accumulated at every accepted (sub-)step;
        track : float64[N_TRACK] (layout.T_*); first : float64[2] first impact times.

    Returns
    -------
    float64[N_R] : (largest |energy residual| [J], peak kinetic energy [J], first impact time
        at A and at B [s], NaN where none; layout.R_*); see kernel_result.

    spec : int
        The joint set the kernel is built for (``params.build_of``, at least the case's
        ``jointset.of(case.jp)``): a compile-time constant (a ``jointset.Build``, typed as
        the literal it holds, or an int made one by ``numba.literally``), one build, cached
        on disk, per set.

    The CPU entry point: allocates every work array on its own (no row views) and runs
    :func:`advance`, which the CUDA batch kernel (core/device.py) runs per thread too.
    """
    literally(spec)
    nbuf_max = undo_rows(int(case.p[P_MAX_LEVEL]))
    work = Rk4Work(np.zeros(N_Y), np.zeros(N_Y), np.zeros(N_Y), np.zeros(N_Y), np.zeros(N_Y),
                   np.zeros(N_Y), np.zeros(N_Y),
                   np.zeros(N_D), np.zeros(N_D), np.zeros((N_JOINTS, N_S)),
                   np.zeros((N_JOINTS, N_S)), np.zeros((N_WINDOWS, N_M)), np.zeros(N_JOINTS),
                   np.zeros(N_JOINTS), np.zeros(N_JOINTS), np.zeros(N_JOINTS),
                   np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((VZ_ROWS, NZ)),
                   np.zeros((nbuf_max, 4), dtype=np.int64), np.zeros((nbuf_max, 4)),
                   np.zeros((N_CAP_ROWS, N_CAP)), np.zeros((N_CAP_ROWS, N_CAP)),
                   np.zeros((4 * case.wmap.shape[1], 3)), np.zeros(N_Y), np.zeros(N_D),
                   np.zeros(N_Y), np.zeros(N_Y))
    advance(case, t0, n_steps, save_every, True, out, work, spec)
    return kernel_result(out.track, out.first)


@compiled
def clear_work(work, out):
    """Zero the work arrays that :func:`advance` reads before writing (their contents on
    entry do not matter), the tracked extremes and the counters of ``out``."""
    zero_rows(work.msave)
    zero_rows(work.vz)
    zero_rows(work.ssave)
    zero_rows(work.C)
    zero_rows(work.S)
    zero_rows(work.L)
    zero_rows(work.scratch)
    zero_rows(work.buf_v)
    zero_rows(work.buf_i)
    zero_rows(work.cur)
    zero_rows(work.pend)
    for i in range(N_Y):
        work.ysave[i] = 0.0
        work.k1save[i] = 0.0
        work.ksum[i] = 0.0
        work.kst[i] = 0.0
        work.yt[i] = 0.0
    for i in range(N_D):
        work.dg[i] = 0.0
        work.dgsave[i] = 0.0
        work.prev[i] = 0.0
    for i in range(N_Y):
        work.ysub[i] = 0.0
        work.k1sub[i] = 0.0
        work.secnext[i] = 0.0
    for j in range(N_JOINTS):
        work.ddot_prev_save[j] = 0.0
        work.wmax[j] = 0.0
        work.first_save[j] = 0.0
    for i in range(N_TRACK):
        out.track[i] = 0.0
    for i in range(I_DEEPEST, N_INFO):
        out.info[i] = 0


@compiled(inline="always")
def clear_attempt(cur, slides):
    """An attempt's wear accumulators (``cur``): each joint's, and a multi-contact joint's
    edge-line rows where one has clearance (``slides``)."""
    for j in range(N_JOINTS):
        for i in range(6):
            cur[j, i] = 0.0
    if slides:
        for j in range(CAP_SLOT_ROW, N_CAP_ROWS):
            for i in range(N_CAP):
                cur[j, i] = 0.0


@compiled(inline="always")
def substep_section(secnext, tk, ts, hs, y, k1, ysub, k1sub, spec):
    """The Poincare section at time tk inside the sub-step from ts (state ysub, derivative
    k1sub) to ts + hs (y, k1): the slider acceleration from the cubic Hermite of the slider
    velocity (``record_sample``'s quadratic) into secnext, the state from the sub-step's
    cubic Hermite into k1sub (in place), whose offsets are read once the step is accepted."""
    u = min(1.0, max(0.0, (tk - ts) / hs))
    v = Y_QD + Y_SLIDER_X + guide_axis(spec)
    a0 = k1sub[v]
    a1 = k1[v]
    m0, m1 = mean_slopes(a0, a1, (y[v] - ysub[v]) / hs)
    secnext[SN_ACC] = hermite_value(a0, a1, m0, m1, u)
    hermite_state(k1sub, u, hs, ysub, k1sub, y, k1)


@compiled(inline="always")
def attempt_step(t, level, last, model, solve, wear, out, work, kept, spec, step_end, stage):
    """One attempt at the output-grid step from t at sub-step level ``level`` (``last``: the
    run's last step): 2**level RK4 sub-steps, each accepted (wear, contact episodes,
    statistics, sections) unless the stiff rate needs a deeper level. Returns (status, need,
    nbuf, nsub, kept): ``need`` the level the rate asks for (-1: every sub-step taken),
    ``nbuf`` the undo buffer's rows, ``kept`` whether the step's start was kept for a
    rejection (:func:`keep_accepted`)."""
    y = work.y
    k1 = work.k1
    dg = work.dg
    slides = multi_free(spec, model.jp)    # a multi-contact joint with clearance
    nsub = 1 << level
    hs = model.p[P_DT] / nsub
    nbuf = 0
    need = -1
    status = ST_OK
    clear_attempt(work.cur, slides)
    for sub in range(nsub):
        ts = t + sub * hs
        if sub == 0:
            keep_ends(work.prev, dg, y, spec)      # the step's start (again after a rejection)
        due, _ = section_in(work.secnext, t, sub, hs, last and sub == nsub - 1)
        if due:
            # a section in this sub-step: its start for the cubic Hermite
            copy_into(work.ysub, y)
            copy_into(work.k1sub, k1)
        st = rk4_substep(ts, hs, y, k1, work.ksum, work.kst, work.yt, dg, model, solve, stage,
                         spec)
        if st == ST_OK:
            st = evaluate(ts + hs, y, model, k1, dg, step_end, solve, spec)
        if st != ST_OK:
            status = st
            break
        need, in_settled, kept, changed, nbuf = accept_end(ts, hs, nsub, kept, nbuf, slides,
                                                           model, wear, out, work, spec)
        if need >= 0:
            break
        if changed:
            st = evaluate(ts + hs, y, model, k1, dg, step_end, solve, spec)
            if st != ST_OK:
                status = st
                break
        finish_substep(t, sub, ts, hs, nsub, last, in_settled, model, out, work, spec)
    return status, need, nbuf, nsub, kept


@compiled(inline="always")
def accept_end(ts, hs, nsub, kept, nbuf, slides, model, wear, out, work, spec):
    """The sub-step from ts, evaluated at its end (``work.dg``), accepted unless the stiff
    rate asks for a deeper level: its wear, contact episodes and first impacts, the step's
    start kept first where a rejection may still undo them (``kept``, :func:`keep_accepted`).
    Returns (need, in_settled, kept, changed, nbuf): ``need`` the level the rate asks for
    (-1: accepted), ``changed`` whether the contact state changed (the end to evaluate
    again). The one acceptance of :func:`attempt_step` and ``onestep``'s attempt."""
    p = model.p
    dg = work.dg
    stats = out.stats
    if dg[D_RATE] * hs > p[P_STAB]:
        return level_for(dg[D_RATE], p[P_DT], p[P_STAB]), False, kept, False, nbuf
    in_settled = ts + hs >= p[P_SETTLE]
    if nsub > 1 and not kept:
        keep_accepted(work.s, work.ssave, stats, work.msave, out.first, work.first_save,
                      work.ddot_prev, work.ddot_prev_save)
        kept = True
    changed, nbuf = accept_substep(hs, in_settled, model, dg, stats, wear, nbuf,
                                   work.ddot_prev, spec)
    if slides and accept_multi(hs, in_settled, model, stats, work.cur, work.y, spec):
        changed = True
    note_first_impact(out.first, stats, ts + hs)
    return -1, in_settled, kept, changed, nbuf


@compiled(inline="always")
def finish_substep(t, sub, ts, hs, nsub, last, in_settled, model, out, work, spec):
    """An accepted sub-step from ts, evaluated at its end: its sample in the statistics
    (weighted from the settling time where it straddles it) and the Poincare section that
    falls in it (:func:`substep_section`)."""
    settle = model.p[P_SETTLE]
    record_sample(out.stats, work.prev, work.dg, work.y, model.jp, hs,
                  max(0.0, (settle - ts) / hs) if in_settled else -1.0, spec)
    due, tk = section_in(work.secnext, t, sub, hs, last and sub == nsub - 1)
    if due:
        substep_section(work.secnext, tk, ts, hs, work.y, work.k1, work.ysub, work.k1sub, spec)


@compiled(inline="always")
def undo_attempt(nbuf, case, out, work, kept):
    """Undo a rejected attempt: its wear (the undo buffer's nbuf rows, from the
    projections and the worn volume), the state, k1 and the diagnostics, and where ``kept``
    the contact state, the statistics, the first impact times and the approach rates."""
    buf_i = work.buf_i
    buf_v = work.buf_v
    for b in range(nbuf - 1, -1, -1):
        j = buf_i[b, 0]
        case.proj[j, 0, buf_i[b, 1]] -= buf_v[b, 1]
        case.proj[j, 1, buf_i[b, 2]] -= buf_v[b, 2]
        case.proj[j, 2, buf_i[b, 3]] -= buf_v[b, 3]
        case.wvol[j] -= buf_v[b, 0]
    copy_into(work.y, work.ysave)
    copy_into(work.k1, work.k1save)
    copy_into(work.dg, work.dgsave)
    if kept:
        keep_accepted(work.ssave, work.s, work.msave, out.stats, work.first_save, out.first,
                      work.ddot_prev_save, work.ddot_prev)


@compiled(inline="always")
def keep_stopping_wear(cur, pend):
    """A run stopped by a status other than an unstable step: the stopping attempt's wear
    stays in the projections and the worn volume, so the map keeps the same volume (an
    unstable step's last attempt was rejected and undone); a multi-contact joint's wear of
    the attempt reached neither."""
    for j in range(N_JOINTS):
        if is_multi(j):
            continue
        for i in range(5):
            pend[j, i] += cur[j, i]
        if cur[j, 3] > 0.0:
            pend[j, 5] = cur[j, 5]


@compiled(inline="always")
def save_row(out, n_saved, t, y, dg, wmax):
    """Output row n_saved: time t, the state, the diagnostics and the largest depths."""
    out.t[n_saved] = t
    copy_row(out.y, n_saved, y)
    copy_row(out.d, n_saved, dg)
    copy_row(out.wmax, n_saved, wmax)


@compiled(locals=_NOT_LITERAL)
def advance(case, t0, n_steps, save_every, keep_rows, out, work, spec):
    """:func:`integrate` without allocation: every work array is a field of ``work`` (a
    :data:`work.Rk4Work`, one array each, so that the CPU path passes no views; the CUDA
    kernel passes rows of :func:`work_shapes`' groups), their contents on entry do not
    matter. ``keep_rows`` False writes no output rows (out.t, out.y, out.d, out.wmax are not
    touched; info[I_SAVED] still counts the rows a run would save). ``out.track``
    (float64[N_TRACK]) receives the peak kinetic energy, the largest |drive work| and the
    largest |energy residual| [J] (layout.T_*); ``out.first`` (float64[2]) each joint's
    first impact time [s] (-1: none). ``spec``: the joint set of the build (``jointset``),
    a compile-time constant in both builds.
    """
    p = case.p
    jp = case.jp
    y = work.y
    dg = work.dg
    secnext = work.secnext
    sec = out.sec
    model, solve, wear = case_views(case, work)
    h = p[P_DT]
    stab = p[P_STAB]
    max_level = int(p[P_MAX_LEVEL])
    slides = multi_free(spec, jp)   # a multi-contact joint with clearance (the guide's block)
    step_end = True  # evaluations at a (sub-)step's end: energies and stiff rates too
    stage = False    # the stage evaluations: the derivative only
    clear_work(work, out)
    plan_sections(p, t0, n_steps, sec)
    # the Poincare sections: the next one's index and time
    next_section(sec, secnext, 0)
    copy_into(y, case.y0)
    # begin_case clears the statistics and sets the contact state
    status = begin_case(t0, y, model, work.k1, dg, solve, work.ddot_prev, out.stats, work.prev,
                        spec)
    if status != ST_OK:
        out.info[I_STATUS] = status
        out.info[I_SAVED] = 0
        return
    e0 = energy_total(dg)
    out.track[T_KE_PEAK] = dg[D_KE]
    for j in range(N_JOINTS):
        out.first[j] = -1.0    # time of each joint's first impact [s]; -1: none yet
    if keep_rows:
        out.t[0] = t0
        copy_row(out.y, 0, y)
        copy_row(out.d, 0, dg)
    n_saved = 1
    deepest = 0
    total = 0
    steps_done = 0
    for step in range(n_steps):
        t = t0 + step * h
        steps_done = step + 1
        last = step == n_steps - 1
        level = level_for(dg[D_RATE], h, stab)
        # a rejected attempt undoes what it changed (docs/physics.md section 4). Every step
        # keeps the state, k1 and the diagnostics of its start: a sub-step changes them
        # before its stability check. The contact state, the statistics, the first impact
        # times and the approach rates change only when a sub-step is accepted, so that
        # only an attempt of several sub-steps can be rejected after changing them: they
        # are kept at the first such acceptance of the step (``kept``), still the step's
        # start, and restored only then (the same values as a copy at every step's start).
        copy_into(work.ysave, y)
        copy_into(work.k1save, work.k1)
        copy_into(work.dgsave, dg)
        kept = False
        while True:
            if level > max_level:
                status = ST_UNSTABLE_STEP
                break
            status, need, nbuf, nsub, kept = attempt_step(t, level, last, model, solve, wear,
                                                          out, work, kept, spec, step_end,
                                                          stage)
            if status != ST_OK or need < 0:
                break
            # reject: undo this step's wear and state, go deeper
            undo_attempt(nbuf, case, out, work, kept)
            level = max(level + 1, need)
        if status != ST_OK:
            if status != ST_UNSTABLE_STEP:
                keep_stopping_wear(work.cur, work.pend)
            break
        total += 1 << level
        deepest = max(deepest, level)
        merge_wear(case.wmap, work.cur, work.pend, work.wmax, work.scratch, spec)
        if slides:
            deposit_multi(case.wmap, work.cur, work.wmax, jp, case.wvol, spec)
        # the accepted step's section (at most one: a step turns the crank 0.05 rad at most):
        # its offsets from the state kept in k1sub (here, where few values are live: a GPU
        # thread's registers), and it counts
        due, _ = section_in(secnext, t, -1, nsub * (h / nsub), last)
        if due:
            k = int(secnext[SN_ROW])
            sec[k, SEC_SLIDER_ACC] = secnext[SN_ACC]
            section_offsets(p, jp, work.k1sub, sec, k, spec)
            next_section(sec, secnext, k + 1)
        status = step_checks(y, dg, p, jp, status, e0, out.track, spec)
        if (step + 1) % save_every == 0:
            if keep_rows:
                save_row(out, n_saved, t + h, y, dg, work.wmax)
            n_saved += 1
        if status != ST_OK:
            break
    flush_all_wear(case.wmap, work.pend, work.wmax, work.scratch, spec)
    out.info[I_SECTIONS] = int(secnext[SN_ROW])
    end_sections(sec, out.info[I_SECTIONS])
    if keep_rows and status == ST_OK and n_saved > 0:
        copy_row(out.wmax, n_saved - 1, work.wmax)
    out.info[I_STATUS] = status
    out.info[I_SAVED] = n_saved
    out.info[I_DEEPEST] = deepest
    out.info[I_SUBSTEPS] = total
    out.info[I_STEPS] = steps_done
