"""Fixed-step classical RK4 with deterministic 2^k sub-stepping, wear, status (DESIGN 4-5).

Each output-grid step h is split into 2^k equal RK4 sub-steps, k the smallest level for
which the stiff rate of DESIGN 4 (estimated at every sub-step's end) times h / 2^k stays
within the stability limit. A step whose rate grows past the limit during the step is
rejected and redone at a deeper level, wear and contact state restored; past the level
cap the case stops with ST_UNSTABLE_STEP. Wear, the contact's impact velocity and the
contact angle advance once per accepted sub-step.
"""

import math

import numpy as np
from numba import njit

from .contact import contact_angle, contact_area
from .dynamics import evaluate
from .layout import (D_CONS, D_DDOT, D_DELTA, D_ECC, D_FN, D_HWEAR, D_KE, D_NORMAL, D_PE_GRAV,
                     D_RATE, D_UEL, D_VT, J_C, J_CLEARANCE, J_K, J_RI, J_RJ, N_ANGLE_BINS, N_D,
                     N_S, N_Y, P_AMPL, P_CONS_TOL, P_DT, P_DV0_MIN, P_ENERGY_TOL, P_MAX_LEVEL,
                     P_PEN_FRAC, P_SLIP, P_STAB, P_WEAR, S_BETA, S_DV0, ST_CONSTRAINT, ST_ENERGY,
                     ST_EULER, ST_NONFINITE, ST_OK, ST_PENETRATION, ST_UNSTABLE_STEP)
from .wear import bin_area, map_bin, projection_bins

EULER_LIMIT = 80.0 * math.pi / 180.0  # |beta| stop of DESIGN 1 [rad]


@njit(cache=True)
def level_for(rate, h, limit):
    """Smallest k with rate * h / 2^k <= limit."""
    x = rate * h / limit
    if not x > 1.0:
        return 0
    return int(math.ceil(math.log2(x) - 1e-12))


@njit(cache=True)
def energy_total(dg):
    return dg[D_KE] + dg[D_PE_GRAV] + dg[D_UEL] + dg[D_UEL + 1]


@njit(cache=True)
def rk4_substep(t, hs, y, k1, k2, k3, k4, yt, p, jp, s, wmap, dg, C, S, L, vz):
    """One RK4 step of size hs from (t, y) with k1 = f(t, y) given; y is advanced in place."""
    n = y.shape[0]
    for i in range(n):
        yt[i] = y[i] + 0.5 * hs * k1[i]
    st = evaluate(t + 0.5 * hs, yt, p, jp, s, wmap, k2, dg, False, C, S, L, vz)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + 0.5 * hs * k2[i]
    st = evaluate(t + 0.5 * hs, yt, p, jp, s, wmap, k3, dg, False, C, S, L, vz)
    if st != ST_OK:
        return st
    for i in range(n):
        yt[i] = y[i] + hs * k3[i]
    st = evaluate(t + hs, yt, p, jp, s, wmap, k4, dg, False, C, S, L, vz)
    if st != ST_OK:
        return st
    for i in range(n):
        y[i] += hs / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])
    return ST_OK


@njit(cache=True)
def integrate(p, jp, y0, t0, n_steps, save_every, wmap, proj, wvol, out_t, out_y, out_d,
              out_wmax, info):
    """Integrate one case over n_steps output-grid steps of size p[P_DT].

    Parameters
    ----------
    p, jp : packed parameters; y0 : initial state (layout.N_Y); t0 : start time [s].
    wmap : float64[2, npolar, nazim]   wear map, updated in place [m].
    proj : float64[2, 3, 360]          paper projections, updated in place [m].
    wvol : float64[2]                  worn volume, updated in place [m^3].
    out_t, out_y, out_d, out_wmax : output rows (n_save = n_steps // save_every + 1).
    info : int64[5] -> (status, saved rows, deepest level, RK4 sub-steps taken,
        output-grid steps completed, the stopping step included).

    Returns
    -------
    float64[2] : (largest |energy residual| [J], peak kinetic energy [J]).
    """
    h = p[P_DT]
    stab = p[P_STAB]
    max_level = int(p[P_MAX_LEVEL])
    wear_on = p[P_WEAR] != 0.0
    ampl = p[P_AMPL]
    npolar = wmap.shape[1]
    nazim = wmap.shape[2]
    ny = N_Y
    y = y0.copy()
    ysave = np.empty(ny)
    k1 = np.empty(ny)
    k1save = np.empty(ny)
    k2 = np.empty(ny)
    k3 = np.empty(ny)
    k4 = np.empty(ny)
    yt = np.empty(ny)
    dg = np.zeros(N_D)
    dgsave = np.zeros(N_D)
    s = np.zeros((2, N_S))
    ssave = np.zeros((2, N_S))
    for j in range(2):
        s[j, S_BETA] = math.pi
    C = np.zeros((6, 6))
    S = np.zeros((6, 6))
    L = np.zeros((6, 6))
    vz = np.zeros((8, 6))
    nbuf_max = 2 * (1 << max_level)
    buf_i = np.zeros((nbuf_max, 6), dtype=np.int64)   # joint, ip, ia, bx, by, bz
    buf_v = np.zeros((nbuf_max, 5))                   # map depth, proj x, y, z, volume
    wmax = np.zeros(2)

    status = ST_OK
    st = evaluate(t0, y, p, jp, s, wmap, k1, dg, True, C, S, L, vz)
    if st != ST_OK:
        info[0] = st
        info[1] = 0
        return np.zeros(2)
    e0 = energy_total(dg)
    ke_peak = dg[D_KE]
    res_max = 0.0
    work_abs = 0.0
    n_saved = 0
    out_t[0] = t0
    out_y[0, :] = y
    out_d[0, :] = dg
    n_saved = 1
    deepest = 0
    total = 0

    steps_done = 0
    for step in range(n_steps):
        t = t0 + step * h
        steps_done = step + 1
        level = level_for(dg[D_RATE], h, stab)
        ysave[:] = y
        k1save[:] = k1
        dgsave[:] = dg
        ssave[:, :] = s
        while True:
            if level > max_level:
                status = ST_UNSTABLE_STEP
                break
            nsub = 1 << level
            hs = h / nsub
            nbuf = 0
            need = -1
            for sub in range(nsub):
                ts = t + sub * hs
                st = rk4_substep(ts, hs, y, k1, k2, k3, k4, yt, p, jp, s, wmap, dg, C, S, L, vz)
                if st == ST_OK:
                    st = evaluate(ts + hs, y, p, jp, s, wmap, k1, dg, True, C, S, L, vz)
                if st != ST_OK:
                    status = st
                    break
                if dg[D_RATE] * hs > stab:
                    need = level_for(dg[D_RATE], h, stab)
                    break
                changed = False
                for j in range(2):
                    if jp[j, J_CLEARANCE] == 0.0:
                        continue
                    if dg[D_DELTA + j] > 0.0:
                        fn = dg[D_FN + j]
                        ri = jp[j, J_RI]
                        rj = jp[j, J_RJ]
                        e = dg[D_ECC + j]
                        pen = dg[D_DELTA + j] + dg[D_HWEAR + j]  # against the unworn radii
                        beta = contact_angle(pen, e, ri, rj)
                        if wear_on and fn > 0.0:
                            if p[P_SLIP] == 0.0:
                                ds = dg[D_VT + j] * hs
                            else:
                                ds = ri * abs(beta - s[j, S_BETA])
                            vol = ampl * jp[j, J_K] * fn * ds
                            area = contact_area(pen, e, ri, rj)
                            nrm = (dg[D_NORMAL + 3 * j], dg[D_NORMAL + 3 * j + 1],
                                   dg[D_NORMAL + 3 * j + 2])
                            ip, ia = map_bin(nrm, npolar, nazim)
                            bx, by, bz = projection_bins(nrm, N_ANGLE_BINS)
                            dmap = vol / bin_area(ip, npolar, nazim, ri)
                            buf_i[nbuf, 0] = j
                            buf_i[nbuf, 1] = ip
                            buf_i[nbuf, 2] = ia
                            buf_i[nbuf, 3] = bx
                            buf_i[nbuf, 4] = by
                            buf_i[nbuf, 5] = bz
                            buf_v[nbuf, 0] = dmap
                            buf_v[nbuf, 1] = vol * abs(nrm[0]) / area
                            buf_v[nbuf, 2] = vol * abs(nrm[1]) / area
                            buf_v[nbuf, 3] = vol * abs(nrm[2]) / area
                            buf_v[nbuf, 4] = vol
                            wmap[j, ip, ia] += dmap
                            proj[j, 0, bx] += buf_v[nbuf, 1]
                            proj[j, 1, by] += buf_v[nbuf, 2]
                            proj[j, 2, bz] += buf_v[nbuf, 3]
                            wvol[j] += vol
                            nbuf += 1
                        s[j, S_BETA] = beta
                        if s[j, S_DV0] == 0.0:
                            s[j, S_DV0] = max(dg[D_DDOT + j], p[P_DV0_MIN])
                            changed = True
                    elif s[j, S_DV0] != 0.0:
                        s[j, S_DV0] = 0.0
                        s[j, S_BETA] = math.pi
                        changed = True
                if changed:
                    st = evaluate(ts + hs, y, p, jp, s, wmap, k1, dg, True, C, S, L, vz)
                    if st != ST_OK:
                        status = st
                        break
            if status != ST_OK or need < 0:
                break
            # reject: undo this step's wear and state, go deeper
            for b in range(nbuf - 1, -1, -1):
                j = buf_i[b, 0]
                wmap[j, buf_i[b, 1], buf_i[b, 2]] -= buf_v[b, 0]
                proj[j, 0, buf_i[b, 3]] -= buf_v[b, 1]
                proj[j, 1, buf_i[b, 4]] -= buf_v[b, 2]
                proj[j, 2, buf_i[b, 5]] -= buf_v[b, 3]
                wvol[j] -= buf_v[b, 4]
            y[:] = ysave
            k1[:] = k1save
            dg[:] = dgsave
            s[:, :] = ssave
            level = max(level + 1, need)
        if status != ST_OK:
            break
        total += 1 << level
        deepest = max(deepest, level)
        for b in range(nbuf):
            j = buf_i[b, 0]
            wmax[j] = max(wmax[j], wmap[j, buf_i[b, 1], buf_i[b, 2]])

        # ---- checks ----
        for i in range(ny):
            if not math.isfinite(y[i]):
                status = ST_NONFINITE
        if status == ST_OK and abs(y[10]) > EULER_LIMIT:
            status = ST_EULER
        for j in range(2):
            if jp[j, J_CLEARANCE] != 0.0 and dg[D_DELTA + j] > p[P_PEN_FRAC] * jp[j, J_C]:
                status = ST_PENETRATION
        ke_peak = max(ke_peak, dg[D_KE])
        work_abs = max(work_abs, abs(y[36]))
        res = energy_total(dg) - y[36] + y[37] - e0
        res_max = max(res_max, abs(res))
        if status == ST_OK and not (dg[D_CONS] <= p[P_CONS_TOL]):
            status = ST_CONSTRAINT
        if status == ST_OK:
            throughput = max(ke_peak, max(work_abs, y[37]))
            if not (abs(res) <= p[P_ENERGY_TOL] * throughput):
                status = ST_ENERGY
        if (step + 1) % save_every == 0:
            out_t[n_saved] = t + h
            out_y[n_saved, :] = y
            out_d[n_saved, :] = dg
            out_wmax[n_saved, 0] = wmax[0]
            out_wmax[n_saved, 1] = wmax[1]
            n_saved += 1
        if status != ST_OK:
            break
    info[0] = status
    info[1] = n_saved
    info[2] = deepest
    info[3] = total
    info[4] = steps_done
    out = np.empty(2)
    out[0] = res_max
    out[1] = ke_peak
    return out
