"""Embedded Dormand-Prince 5(4) with error control, FSAL, dense output and contact-onset
location (docs/physics.md section 4.4).

The same right-hand side, per-step rules and statuses as the fixed-step RK4 of
:mod:`.rk4`: every accepted step goes through ``accept_substep`` (wear, contact episode,
impacts), ``record_sample`` (running statistics), ``merge_wear`` and ``step_checks``.
What differs is the step: its length follows the local error estimate of the embedded
4th-order solution, weighted per state group (positions, velocities, the two energy
integrals) by ``atol + rtol * |y|``; a step over which a clearance joint's gap closes is
shortened until it is at most ``onset_tolerance`` long, so that contact onsets are located
in time within that tolerance; output rows at the fixed sample times come from the
method's 4th-order continuous extension, with the diagnostics evaluated there.
"""

import math

import numpy as np
from numba import literally, njit

from . import jointkinds as kinds
from .compiled import compiled
from .dynamics import NZ, VZ_ROWS, evaluate
from .jointkinds import contacts, is_multi, multi_free, type_body
from .jointset import ALL, has_clearance
from .layout import (
    D_DELTA,
    D_KE,
    D_SLIDER_ACC,
    I_DEEPEST,
    I_SAVED,
    I_SECTIONS,
    I_STATUS,
    I_STEPS,
    I_SUBSTEPS,
    N_CAP,
    N_CAP_ROWS,
    N_D,
    N_JOINTS,
    N_R,
    N_S,
    N_TRACK,
    N_Y,
    P_ATOL_E,
    P_ATOL_Q,
    P_ATOL_V,
    P_DT,
    P_HMAX,
    P_MAX_LEVEL,
    P_ONSET_TOL,
    P_RTOL,
    P_SETTLE,
    SEC_SLIDER_ACC,
    SEC_TIME,
    ST_OK,
    ST_UNSTABLE_STEP,
    T_KE_PEAK,
    Y_QD,
    Y_WORK,
)
from .rk4 import (
    _NOT_LITERAL,
    accept_multi,
    accept_substep,
    begin_case,
    case_views,
    copy_into,
    copy_row,
    deposit_multi,
    end_sections,
    energy_total,
    flush_all_wear,
    keep_ends,
    kernel_result,
    merge_wear,
    note_first_impact,
    plan_sections,
    record_sample,
    section_count,
    section_offsets,
    section_time,
    step_checks,
    zero_rows,
)
from .work import Dopri5Work

# Dormand & Prince (1980) coefficients; E = b5 - b4 (error weights); D: the 4th-order
# continuous extension of Hairer, Norsett & Wanner, Solving ODEs I, section II.6.
C2, C3, C4, C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63, A64, A65 = (9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0,
                           -5103.0 / 18656.0)
A71, A73, A74, A75, A76 = (35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                           11.0 / 84.0)
E1, E3, E4, E5, E6, E7 = (71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                          22.0 / 525.0, -1.0 / 40.0)
D1 = -12715105075.0 / 11282082432.0
D3 = 87487479700.0 / 32700410799.0
D4 = -10690763975.0 / 1880347072.0
D5 = 701980252875.0 / 199316789632.0
D6 = -1453857185.0 / 822651844.0
D7 = 69997945.0 / 29380423.0

#: Step-size controller: safety factor, largest shrink and growth per step.
SAFETY = 0.9
SHRINK_MIN = 0.2
GROW_MAX = 5.0


@compiled
def dense_row(out, row, theta, h, y0, y1, k1, k3, k4, k5, k6, k7):
    """out[row, :] = the continuous extension at t0 + theta h of the step y0 -> y1."""
    t1 = 1.0 - theta
    for i in range(y0.shape[0]):
        dy = y1[i] - y0[i]
        b = h * k1[i] - dy
        r4 = dy - h * k7[i] - b
        r5 = h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i])
        out[row, i] = y0[i] + theta * (dy + t1 * (b + theta * (r4 + t1 * r5)))


@compiled
def error_norm(p, h, y0, y1, k1, k3, k4, k5, k6, k7):
    """RMS over the state of the embedded error estimate, each component scaled by its
    group's atol + rtol * max(|y0|, |y1|); <= 1 accepts the step."""
    rtol = p[P_RTOL]
    acc = 0.0
    for i in range(y0.shape[0]):
        if i < Y_QD:
            atol = p[P_ATOL_Q]
        elif i < Y_WORK:
            atol = p[P_ATOL_V]
        else:
            atol = p[P_ATOL_E]
        sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
        e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i])
        acc += (e / sc) ** 2
    return math.sqrt(acc / y0.shape[0])


@compiled(locals=_NOT_LITERAL)
def dopri5_trial(t, h, work, model, solve, spec):
    """Stages 2-7 of one trial step of length h from (t, y) with k1 = f(t, y): the 5th-order
    solution into y1, k7 = f(t + h, y1) with its diagnostics (energies, rates) into dg1
    (y, k1 ... k7, yt, y1, dg1: fields of ``work``, a :data:`work.Dopri5Work`; ``spec``: the
    build's joint set, ``jointset``)."""
    y = work.y
    k1 = work.k1
    k2 = work.k2
    k3 = work.k3
    k4 = work.k4
    k5 = work.k5
    k6 = work.k6
    k7 = work.k7
    yt = work.yt
    y1 = work.y1
    dg1 = work.dg1
    stage = False
    step_end = True
    n = y.shape[0]
    scratch = dg1
    for i in range(n):
        yt[i] = y[i] + h * A21 * k1[i]
    st = evaluate(t + C2 * h, yt, model, k2, scratch, stage, solve, spec)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
    st = evaluate(t + C3 * h, yt, model, k3, scratch, stage, solve, spec)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
    st = evaluate(t + C4 * h, yt, model, k4, scratch, stage, solve, spec)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
    st = evaluate(t + C5 * h, yt, model, k5, scratch, stage, solve, spec)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i]
                            + A65 * k5[i])
    st = evaluate(t + h, yt, model, k6, scratch, stage, solve, spec)
    if st != ST_OK:
        return st
    for i in range(n):
        y1[i] = y[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i]
                            + A76 * k6[i])
    return evaluate(t + h, y1, model, k7, dg1, step_end, solve, spec)


@compiled(inline="always")
def onset_within(d0, d1, h, tol, shorter):
    """``shorter``, or the step that ends just after a gap d0 <= 0 closes to d1 > 0 (linear
    estimate) where that is shorter."""
    if d0 <= 0.0 < d1:
        theta = d0 / (d0 - d1)     # linear estimate of the onset in the step
        hj = max(theta * h + 0.5 * tol, tol)
        hj = min(hj, 0.5 * h) if hj >= h else hj
        shorter = hj if shorter == 0.0 else min(shorter, hj)
    return shorter


@compiled
def onset_step(p, jp, dg0, dg1, h, model, y0, y1, spec=ALL):
    """0 when no clearance joint's gap closes over the step, or the step is within the
    onset tolerance; else a shorter step that ends just after the estimated onset. A
    multi-contact joint's gaps are its points' (its type's ``penetration``: the guide's 16
    corner-wall pairs), from its ball's body states at y0 and y1 (its diagnostics hold the
    deepest point's only, which stays in contact while others close). ``spec``: the build's
    joint set (``jointset``; default every joint, each tested at run time)."""
    tol = p[P_ONSET_TOL]
    if h <= tol:
        return 0.0
    shorter = 0.0
    for j in range(N_JOINTS):
        if not has_clearance(spec, jp, j):
            continue
        if is_multi(j):
            s0 = type_body(spec, j, y0)
            s1 = type_body(spec, j, y1)
            for k in range(contacts(spec, j)):
                shorter = onset_within(kinds.penetration(spec, j, model, k, s0),
                                       kinds.penetration(spec, j, model, k, s1), h, tol,
                                       shorter)
            continue
        # signed: the gap is -delta before contact
        shorter = onset_within(dg0[D_DELTA + j], dg1[D_DELTA + j], h, tol, shorter)
    return shorter


@njit(cache=True, locals=_NOT_LITERAL)
def integrate_dopri5(case, t0, n_steps, save_every, out, spec):
    """Integrate one case to t0 + n_steps * p[P_DT] with adaptive Dormand-Prince 5(4).

    Arguments and outputs as :func:`.rk4.integrate`; output rows at the same times
    (every ``save_every`` grid steps). ``info[I_DEEPEST]`` holds the level k of the
    shortest accepted step (h >= p[P_DT] / 2^k), ``info[I_SUBSTEPS]`` the accepted steps.
    Steps are bounded by p[P_HMAX] and p[P_DT] / 2^P_MAX_LEVEL; a step that the error
    control would make shorter stops the case with ST_UNSTABLE_STEP. Allocates the work
    arrays and runs :func:`advance_dopri5`; ``spec``, the joint set of the build, a
    compile-time constant as :func:`.rk4.integrate`'s.
    """
    literally(spec)
    ny = N_Y
    work = Dopri5Work(np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny),
                      np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(ny),
                      np.zeros(ny), np.zeros((1, ny)), np.zeros(ny), np.zeros(N_D),
                      np.zeros(N_D), np.zeros(N_D), np.zeros((N_JOINTS, N_S)),
                      np.zeros(N_JOINTS), np.zeros(N_JOINTS), np.zeros((NZ, NZ)),
                      np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((VZ_ROWS, NZ)),
                      np.zeros((N_JOINTS, 4), dtype=np.int64), np.zeros((N_JOINTS, 4)),
                      np.zeros((N_CAP_ROWS, N_CAP)), np.zeros((N_CAP_ROWS, N_CAP)),
                      np.zeros((4 * case.wmap.shape[1], 3)), np.zeros(N_D))
    advance_dopri5(case, t0, n_steps, save_every, out, work, spec)
    if out.info[I_SAVED] == 0 and out.info[I_STATUS] != ST_OK:
        return np.full(N_R, np.nan)
    return kernel_result(out.track, out.first)


@compiled(locals=_NOT_LITERAL)
def advance_dopri5(case, t0, n_steps, save_every, out, work, spec):
    """:func:`integrate_dopri5` without allocation: every work array is a field of ``work``
    (a :data:`work.Dopri5Work`; their contents on entry do not matter). ``out.track`` and
    ``out.first`` receive what :func:`.rk4.kernel_result` reports. Every status an
    evaluation returns stops the case, the dense-output evaluations of the sample rows
    included. ``spec``: the build's joint set (``jointset``).
    """
    model, solve, wear = case_views(case, work)
    p = case.p
    jp = case.jp
    wmap = case.wmap
    stats = out.stats
    y = work.y
    y1 = work.y1
    k1 = work.k1
    k3 = work.k3
    k4 = work.k4
    k5 = work.k5
    k6 = work.k6
    k7 = work.k7
    kt = work.kt
    row = work.row
    yrow = work.yrow
    dg = work.dg
    dg1 = work.dg1
    dgo = work.dgo
    ddot_prev = work.ddot_prev
    wmax = work.wmax
    cur = work.cur
    pend = work.pend
    scratch = work.scratch
    step_end = True
    grid = p[P_DT]
    settle = p[P_SETTLE]
    hmax = p[P_HMAX]
    hmin = grid / (1 << int(p[P_MAX_LEVEL]))
    t_end = t0 + n_steps * grid
    ny = N_Y
    copy_into(y, case.y0)
    zero_rows(work.buf_i)
    zero_rows(work.buf_v)
    zero_rows(cur)
    zero_rows(pend)
    for j in range(N_JOINTS):
        wmax[j] = 0.0
    for i in range(N_D):
        dg[i] = 0.0
        dg1[i] = 0.0
        dgo[i] = 0.0
    for i in range(N_TRACK):
        out.track[i] = 0.0
    for j in range(N_JOINTS):
        out.first[j] = -1.0
    sec = out.sec
    plan_sections(p, t0, n_steps, sec)
    nsec = min(sec.shape[0], section_count(p, t0, n_steps))
    ksec = 0
    tsec = section_time(p, t0, ksec)

    status = begin_case(t0, y, model, k1, dg, solve, ddot_prev, stats, work.prev, spec)
    if status != ST_OK:
        out.info[I_STATUS] = status
        out.info[I_SAVED] = 0
        return
    e0 = energy_total(dg)
    out.track[T_KE_PEAK] = dg[D_KE]
    out.t[0] = t0
    copy_row(out.y, 0, y)
    copy_row(out.d, 0, dg)
    n_saved = 1
    n_save = out.t.shape[0]
    accepted = 0
    h_small = hmax
    t = t0
    h = min(hmax, grid)
    while t < t_end and status == ST_OK:
        hh = min(h, t_end - t)
        last = hh >= t_end - t
        if hh < hmin and not last:
            status = ST_UNSTABLE_STEP
            break
        st = dopri5_trial(t, hh, work, model, solve, spec)
        if st != ST_OK:
            if hh <= hmin:
                status = st
                break
            h = max(0.25 * hh, hmin)
            continue
        err = error_norm(p, hh, y, y1, k1, k3, k4, k5, k6, k7)
        if not err <= 1.0:
            if not math.isfinite(err):
                h = max(0.25 * hh, hmin)
            else:
                h = max(hh * max(SHRINK_MIN, SAFETY * err ** -0.2), min(hmin, 0.5 * hh))
            if hh <= hmin:
                status = ST_UNSTABLE_STEP
                break
            continue
        shorter = onset_step(p, jp, dg, dg1, hh, model, y, y1, spec)
        if shorter > 0.0:
            h = shorter
            continue
        # ---- accepted: the same per-step rules as RK4 ----
        in_settled = t + hh >= settle
        for j in range(N_CAP_ROWS):
            for i in range(N_CAP):
                cur[j, i] = 0.0
        changed, _ = accept_substep(hh, in_settled, model, dg1, stats, wear, 0, ddot_prev, spec)
        if multi_free(spec, jp) and accept_multi(hh, in_settled, model, stats, cur, y1, spec):
            changed = True
        note_first_impact(out.first, stats, t + hh)
        if changed:
            st = evaluate(t + hh, y1, model, k7, dg1, step_end, solve, spec)
            if st != ST_OK:
                status = st
                break
        keep_ends(work.prev, dg, y, spec)
        record_sample(stats, work.prev, dg1, y1, jp, hh,
                      max(0.0, (settle - t) / hh) if in_settled else -1.0, spec)
        merge_wear(wmap, cur, pend, wmax, scratch, spec)
        if multi_free(spec, jp):
            deposit_multi(wmap, cur, wmax, jp, case.wvol, spec)
        # output rows inside the step, from the continuous extension (before y moves on)
        while n_saved < n_save and t0 + (n_saved * save_every) * grid <= t + hh * (1.0 + 1e-12):
            # the sample's time from its grid-step count: the same for any save_every
            ts = t0 + (n_saved * save_every) * grid
            theta = (ts - t) / hh
            if theta >= 1.0 - 1e-12:
                copy_row(out.y, n_saved, y1)
                copy_row(out.d, n_saved, dg1)
            else:
                dense_row(row, 0, theta, hh, y, y1, k1, k3, k4, k5, k6, k7)
                for i in range(ny):
                    yrow[i] = row[0, i]
                st = evaluate(ts, yrow, model, kt, dgo, step_end, solve, spec)
                if st != ST_OK:
                    status = st
                    break
                copy_row(out.y, n_saved, yrow)
                copy_row(out.d, n_saved, dgo)
            out.t[n_saved] = ts
            copy_row(out.wmax, n_saved, wmax)
            n_saved += 1
        if status != ST_OK:
            break
        # Poincare sections inside the step, from the continuous extension
        while ksec < nsec and (tsec <= t + hh or last):
            theta = min(1.0, max(0.0, (tsec - t) / hh))
            dense_row(row, 0, theta, hh, y, y1, k1, k3, k4, k5, k6, k7)
            for i in range(ny):
                yrow[i] = row[0, i]
            section_offsets(p, jp, yrow, sec, ksec, spec)
            st = evaluate(tsec, yrow, model, kt, dgo, step_end, solve, spec)
            sec[ksec, SEC_SLIDER_ACC] = dgo[D_SLIDER_ACC] if st == ST_OK else math.nan
            sec[ksec, SEC_TIME] = tsec
            ksec += 1
            tsec = section_time(p, t0, ksec)
        copy_into(y, y1)
        copy_into(k1, k7)
        copy_into(dg, dg1)
        t += hh
        accepted += 1
        if not last:
            h_small = min(h_small, hh)
        status = step_checks(y, dg, p, jp, status, e0, out.track, spec)
        grow = GROW_MAX if err == 0.0 else min(GROW_MAX, SAFETY * err ** -0.2)
        h = min(hh * grow, hmax)
    flush_all_wear(wmap, pend, wmax, scratch, spec)
    if status == ST_OK and n_saved > 0:
        copy_row(out.wmax, n_saved - 1, wmax)
    deepest = 0
    while grid / (1 << deepest) > h_small * (1.0 + 1e-12) and deepest < 62:
        deepest += 1
    out.info[I_STATUS] = status
    out.info[I_SAVED] = n_saved
    out.info[I_DEEPEST] = deepest
    out.info[I_SUBSTEPS] = accepted
    out.info[I_SECTIONS] = ksec
    end_sections(sec, ksec)
    out.info[I_STEPS] = min(n_steps, int(math.floor((t - t0) / grid + 1e-9)) + (0 if status == ST_OK else 1))
