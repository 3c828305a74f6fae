"""The kernel's structured right-hand side against a slow dense reference (tests/reference.py).

The reference solves the full (18 + m) x (18 + m) KKT system of docs/physics.md section 2 with constraint
Jacobians, acceleration terms, mass matrix and velocity-quadratic forces all taken by finite
differences of plain formulas, and the contact law of docs/physics.md section 3 applied through
finite-difference point Jacobians. Compared: all 18 accelerations, the crank torque, the
reaction at O, the joint forces on the balls, the contact diagnostics, the dissipated and
drive powers, the constrained contact mobility W_p and the stiff rate of docs/physics.md section 4.

Tolerances. The reference's finite differences are fourth order (reference.STEP_*): the
constraint and point Jacobians carry relative errors ~1e-13; the acceleration term h, a
second difference along (qd, 1), carries round-off ~1e-10 m/s^2 in float64 (~1e-13 where
numpy's longdouble is extended, as on x86-64), amplified ~5x into the rod's angular
accelerations by its 0.19 m lever; the velocity-quadratic forces ~1e-10 of their size. The
dense KKT solve adds cond(KKT) * eps (masses from 1e-5 kg m^2 to 2.2 kg). Measured worst
differences, scaled as below: accelerations 2.7e-9 (3.8e-9 with h in float64; the worst
is the slider's, which inherits ~2e-11 relative noise of the rod's angular accelerations of
~1e3 rad/s^2 through joint B), torque, reaction at O and joint forces 2.4e-11, normal force
and dissipated power 1.4e-10 relative.
The tests accept RTOL = 1e-7 of each quantity's scale (the largest magnitude of its group:
linear or angular accelerations of one body, but at least 1; forces and torques of the
case, at least the total weight), 25x above the float64 noise; a wrong Baumgarte
coefficient, a missing velocity-quadratic force (anisotropic rod), friction or gravity
error of 1e-6, or a normal force off by 1e-5 all fail it.
"""

from __future__ import annotations

import numpy as np
import pytest
import reference as ref_mod

from clearsweep.config import load_config, resolve_materials
from clearsweep.core import jointset
from clearsweep.core import layout as L
from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate, point_mobility
from clearsweep.core.kinematics import gmat, mtv, mv, point_jacobian_rot, rot_mass, rotation, trig
from clearsweep.core.work import Model, Solve
from clearsweep.params import pack
from clearsweep.simulation import run_kernel

RTOL = 1e-7
CLEAR = 2.5e-4
JOINTS = {
    "ideal": {},
    "one": {"B": {"clearance": CLEAR}},
    "oneA": {"A": {"clearance": CLEAR}},
    "two": {"A": {"clearance": CLEAR}, "B": {"clearance": CLEAR}},
}


def packed_case(joints, preset="realistic", **sections):
    """The packed case with the joints ``joints`` (a key of JOINTS, or a joints section)."""
    # The drifted states below recede at up to ~1e-3 m/s; with a smaller impact-velocity
    # floor the damping term clamps F_N at 0 there, which leaves nothing to compare.
    cfg = {"joints": JOINTS[joints] if isinstance(joints, str) else joints,
           "mechanism": {"preset": preset},
           "contact": {"min_impact_velocity": 1.0e-2}}
    for key, val in sections.items():
        cfg[key] = dict(cfg.get(key, {}), **val)
    cfg = load_config(cfg)
    return pack(cfg, resolve_materials(cfg))


#: The kernel build that evaluates the slider-crank's cases here (``p[P_GUIDE]`` 1): its
#: guide along y, clearance or a bushing at any joint, each tested at run time (one compile).
SLIDER_CRANK_BUILD = jointset.Build(jointset.ANY | jointset.SLIDER_CRANK)


def run_evaluate(t, y, p, jp, dv0=(0.0, 0.0), wmap=None):
    """One kernel right-hand side with fresh work arrays (as rk4.integrate allocates them),
    on the wear map ``wmap`` (default unworn, 36 x 72); the RSSP's in the default build, the
    slider-crank's (``p[P_GUIDE]`` 1) in :data:`SLIDER_CRANK_BUILD`."""
    s = np.zeros((L.N_JOINTS, L.N_S))
    s[:len(dv0), L.S_DV0] = dv0
    wmap = np.zeros((L.N_JOINTS, 36, 72)) if wmap is None else wmap
    work = dict(wmap=wmap, dy=np.zeros(L.N_Y), dg=np.zeros(L.N_D),
                C=np.zeros((NZ, NZ)), S=np.zeros((NZ, NZ)), L=np.zeros((NZ, NZ)),
                vz=np.zeros((VZ_ROWS, NZ)))
    args = (t, np.array(y, float), Model(p, jp, s, work["wmap"]), work["dy"], work["dg"],
            True, Solve(work["C"], work["S"], work["L"], work["vz"]))
    st = evaluate(*args, SLIDER_CRANK_BUILD) if p[L.P_GUIDE] == 1.0 else evaluate(*args)
    assert st == L.ST_OK
    return work


# ---------------------------------------------------------------------------
# states
# ---------------------------------------------------------------------------

def perturb(y, rng, pos=1e-7, ang=1e-6, vel=1e-5, rate=1e-4):
    """Small random drift of every coordinate and velocity."""
    y = np.array(y, float)
    for b in range(3):
        i = 6 * b
        y[i:i + 3] += pos * rng.standard_normal(3)
        y[i + 3:i + 6] += ang * rng.standard_normal(3)
        y[L.Y_QD + i:L.Y_QD + i + 3] += vel * rng.standard_normal(3)
        y[L.Y_QD + i + 3:L.Y_QD + i + 6] += rate * rng.standard_normal(3)
    return y


def unit(v):
    return v / np.linalg.norm(v)


def place_balls(y, p, jp, offsets):
    """Move rod and slider (along its guide: x, the slider-crank's y) so that ball - socket =
    offsets[j] (global) for each clearance joint j given, the others centred; the crank and
    the slider's other coordinates and angles stay."""
    mech = ref_mod.Mechanism(p, jp)
    g = mech.guide
    across = [1 - g, 2]         # the slider's coordinates that its guide holds
    q = np.array(y[:L.N_Q], float)
    d_a = offsets.get(0, np.zeros(3)) if not mech.ideal[0] else np.zeros(3)
    d_b = offsets.get(1, np.zeros(3)) if not mech.ideal[1] else np.zeros(3)
    a3 = ref_mod.point(q, ref_mod.CRANK, mech.u_A2) - d_a
    rest = q[12:15][across] + d_b[across] - a3[across]
    x4 = a3[g] - d_b[g] + np.sqrt(mech.l3 ** 2 - rest @ rest)
    b3 = np.array(q[12:15]) + d_b
    b3[g] = x4 + d_b[g]
    u = (b3 - a3) / mech.l3
    y = np.array(y, float)
    y[6:9] = 0.5 * (a3 + b3)
    y[9] = np.arctan2(u[1], u[0])
    y[10] = -np.arcsin(u[2])
    y[12 + g] = x4
    return y


def set_contact_velocity(y, p, jp, j, ddot, slip):
    """Shift the socket body's centroid velocity so that the relative velocity at joint j's
    contact is ddot n + slip (slip turned tangential, its magnitude kept)."""
    mech = ref_mod.Mechanism(p, jp)
    q = y[:L.N_Q]
    qd = y[L.Y_QD:L.Y_QD + L.N_Q]
    c = ref_mod.contact(mech, j, q, qd)
    tangential = slip - (slip @ c.n) * c.n
    slip = np.linalg.norm(slip) * unit(tangential)
    target = ddot * c.n + slip
    v = c.j_rel @ qd
    socket = mech.joint_bodies(j)[2]
    y = np.array(y, float)
    y[L.Y_QD + 6 * socket:L.Y_QD + 6 * socket + 3] += v - target
    return y


def contact_state(y, p, jp, rng, delta=(2e-6, 2e-6), ddot=(3e-3, -2e-3), slip=(5e-2, 4e-4),
                  drift=True):
    """A drifted state (``drift``: else y as it is) with each spherical clearance joint j at
    penetration delta[j] (negative: a gap), approach rate ddot[j] and slip speed slip[j], in
    random directions."""
    y = perturb(y, rng) if drift else np.array(y, float)
    offsets = {}
    for j in range(2):
        if jp[j, L.J_CLEARANCE] != 0.0:
            n = unit(rng.standard_normal(3))
            offsets[j] = (jp[j, L.J_C] + delta[j]) * n
    y = place_balls(y, p, jp, offsets)
    for j in range(2):
        if jp[j, L.J_CLEARANCE] != 0.0:
            y = set_contact_velocity(y, p, jp, j, ddot[j], slip[j] * unit(rng.standard_normal(3)))
    return y


# ---------------------------------------------------------------------------
# comparison
# ---------------------------------------------------------------------------

def compare(t, y, pk, dv0=(0.0, 0.0), wmap=None, speed=1.0):
    """Kernel vs reference at (t, y) on the wear map ``wmap`` (default unworn); returns the
    largest scaled difference of each group. ``speed`` [m/s]: the contact points' speed scale,
    at least 1: the reference's approach rate and slip are differences of the contact points'
    velocities through its finite-difference point Jacobians (~1e-13 relative), accepted
    within 1e-12 s/m times it (the RSSP's points move below 1 m/s)."""
    p, jp = pk.p, pk.jp
    k = run_evaluate(t, y, p, jp, dv0, wmap)
    dy, dg = k["dy"], k["dg"]
    r = ref_mod.evaluate(t, y, p, jp, dv0, wmap)
    out = {}

    assert np.array_equal(dy[:L.N_Q], y[L.Y_QD:L.Y_QD + L.N_Q])
    qdd = dy[L.Y_QD:L.Y_QD + L.N_Q]
    worst = 0.0
    for i in range(6):  # per body, translations and rotations separately
        sl = slice(3 * i, 3 * i + 3)
        scale = max(np.max(np.abs(r.qdd[sl])), 1.0)
        err = np.max(np.abs(qdd[sl] - r.qdd[sl])) / scale
        assert err <= RTOL, (i, qdd[sl], r.qdd[sl])
        worst = max(worst, err)
    out["qdd"] = worst
    assert dg[L.D_SLIDER_ACC] == qdd[12 + int(p[L.P_GUIDE])]   # along the guide

    fscale = max(np.max(np.abs(r.joint_force)), np.max(np.abs(r.reaction_O)),
                 np.sum(np.abs(pk.p[L.P_M2:L.P_M4 + 1])) * 9.81)
    tscale = fscale * pk.p[L.P_L2]
    kf = {"torque": dg[L.D_TORQUE],
          "reaction_O": dg[L.D_REACTION_O:L.D_REACTION_O + 3],
          "joint_force": dg[L.D_JOINT_FORCE:L.D_JOINT_FORCE + 3 * L.N_JOINTS].reshape(L.N_JOINTS, 3)}
    rf = {"torque": r.torque, "reaction_O": r.reaction_O, "joint_force": r.joint_force}
    for name, scale in (("torque", tscale), ("reaction_O", fscale), ("joint_force", fscale)):
        err = np.max(np.abs(np.asarray(kf[name]) - rf[name])) / scale
        assert err <= RTOL, (name, kf[name], rf[name])
        out[name] = err

    # drive power: torque * gamma2_dot is the power of the driver's constraint force
    pscale = tscale * abs(y[L.Y_QD + 5])
    assert abs(dy[L.Y_WORK] - r.drive_power) <= RTOL * pscale
    assert abs(dg[L.D_PDRIVE] - r.drive_power) <= RTOL * pscale

    # contact diagnostics
    for j, c in r.contacts.items():
        assert dg[L.D_DELTA + j] == pytest.approx(c.delta, rel=1e-9, abs=1e-15)
        assert dg[L.D_ECC + j] == pytest.approx(c.ecc, rel=1e-12)
        assert dg[L.D_DDOT + j] == pytest.approx(c.ddot, rel=1e-9, abs=1e-12 * speed)
        vt = np.linalg.norm(c.vt) if c.delta > 0.0 else 0.0  # reported in contact only
        assert dg[L.D_VT + j] == pytest.approx(vt, rel=1e-9, abs=1e-12 * speed)
        assert dg[L.D_FN + j] == pytest.approx(c.fn, rel=1e-9, abs=1e-12)
        assert dg[L.D_FT + j] == pytest.approx(c.ft, rel=1e-9, abs=1e-9 * c.fn + 1e-12)
        assert np.allclose(dg[L.D_NGLOBAL + 3 * j:L.D_NGLOBAL + 3 * j + 3], c.n, atol=1e-12)
        if c.fn > 0.0:
            assert dg[L.D_DFD + j] == pytest.approx(c.dfn_ddelta, rel=1e-6)
            assert dg[L.D_DFDD + j] == pytest.approx(c.dfn_dddot, rel=1e-6)
    dscale = max(abs(r.dissipation), 1e-12)
    assert dy[L.Y_DISS] == pytest.approx(r.dissipation, rel=1e-9, abs=1e-9 * dscale)
    out["kernel"], out["reference"] = k, r
    return out


def worst_of(results, key):
    return max(res[key] for res in results)


CASES = [(j, preset) for j in JOINTS for preset in ("realistic", "paper")]


@pytest.mark.parametrize("joints,preset", CASES)
def test_initial_state(joints, preset):
    pk = packed_case(joints, preset)
    res = compare(0.0, pk.y0, pk)
    assert res["qdd"] < RTOL


@pytest.mark.parametrize("joints,preset", CASES)
def test_drifted_states_in_contact(joints, preset):
    """Position drift 1e-7 m / 1e-6 rad, velocity drift, balls pressed into their sockets
    with approach and slip (one joint with slip in the friction ramp), several crank angles
    and a stored impact velocity."""
    pk = packed_case(joints, preset)
    rng = np.random.default_rng(CASES.index((joints, preset)))
    results = []
    for t in (0.0, 0.13, 0.41, 0.77):
        y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
        y = contact_state(y0, pk.p, pk.jp, rng) if joints != "ideal" else perturb(y0, rng)
        res = compare(t, y, pk)
        for j, c in res["reference"].contacts.items():
            assert c.delta > 0.0 and c.fn > 0.0
            assert c.ddot != 0.0 and np.linalg.norm(c.vt) > pk.p[L.P_V0]
        results.append(res)
        if joints != "ideal":
            results.append(compare(t, y, pk, dv0=(0.05, 0.02)))
    # larger drift, so that the Baumgarte terms weigh well above the tolerance
    y = perturb(base_state(pk, 2.0), rng, pos=1e-5, ang=1e-4, vel=1e-3, rate=1e-2)
    results.append(compare(0.25, y, pk))
    assert worst_of(results, "qdd") < RTOL


@pytest.mark.parametrize("joints", list(JOINTS))
def test_other_parameters(joints):
    """theta0 != 0, another speed, the text's Baumgarte 50, gravity with x and y parts."""
    pk = packed_case(joints, "realistic",
                     mechanism={"theta0": 0.7, "speed_rpm": 90.0, "gravity": [1.5, -2.0, -9.81]},
                     solver={"baumgarte": [50.0, 50.0]})
    rng = np.random.default_rng(21)
    compare(0.0, pk.y0, pk)
    for t in (0.05, 0.5):
        y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
        y = contact_state(y0, pk.p, pk.jp, rng) if joints != "ideal" else perturb(y0, rng)
        compare(t, y, pk)


def base_state(pk, theta):
    """Ideal-kinematics state at crank angle theta (params.initial_state)."""
    from clearsweep.params import PRESETS, initial_state

    preset = next(v for v in PRESETS.values()
                  if v.rod_inertia_kgm2 == tuple(pk.p[L.P_J3:L.P_J3 + 3]))
    return initial_state(preset, theta, pk.p[L.P_OMEGA])


@pytest.fixture(scope="module")
def simulated_states():
    """States at t = 0.3 s of short runs (the contact then is as the run left it)."""
    out = {}
    for joints in JOINTS:
        pk = packed_case(joints, "realistic", solver={"duration": 0.3})
        raw = run_kernel(pk)
        assert raw.status == "ok"
        out[joints] = (pk, float(raw.t[-1]), np.array(raw.y[-1]))
    return out


@pytest.mark.parametrize("joints", list(JOINTS))
def test_simulated_state(simulated_states, joints):
    pk, t, y = simulated_states[joints]
    assert t == pytest.approx(0.3)
    compare(t, y, pk)
    # and pressed into contact there
    if joints != "ideal":
        rng = np.random.default_rng(7)
        compare(t, contact_state(y, pk.p, pk.jp, rng), pk)


# ---------------------------------------------------------------------------
# effective mass and stiff rate (docs/physics.md section 4)
# ---------------------------------------------------------------------------

def kernel_point_mobility(k, y, pk, j, axis=None):
    """Call dynamics.point_mobility with the intermediates evaluate() leaves (C, L) and
    rebuilds the rest as dynamics.rate_mobility does; ``axis``: the guide's axis it is given (default
    the case's, p[P_GUIDE])."""
    p, jp = pk.p, pk.jp
    t3 = trig(y[9], y[10], y[11])
    r3m = rotation(t3)
    g3 = gmat(t3)
    mr = rot_mass(tuple(p[L.P_J3:L.P_J3 + 3]), g3)
    det = mr[0] * mr[4] - mr[1] * mr[3]
    mr_inv = (mr[4] / det, -mr[1] / det, -mr[3] / det, mr[0] / det)
    # the crank's centroid free in the bearing's plane where O has clearance, else held
    minv = (1.0 / p[L.P_M3], 1.0 / p[L.P_M4],
            1.0 / p[L.P_M2] if jp[ref_mod.JOINT_O, L.J_CLEARANCE] != 0.0 else 0.0,
            1.0 / p[L.P_M4] if jp[ref_mod.JOINT_P, L.J_CLEARANCE] != 0.0 else 0.0)
    # the rows of A and B where ideal: three, the slider-crank's pins two (its rod held in
    # its plane: x3 and alpha3 immobile)
    planar = p[L.P_GUIDE] == 1.0
    nc = sum((2 if planar else 3) for i in range(2) if jp[i, L.J_CLEARANCE] == 0.0)
    if planar:
        mr_inv = (0.0, 0.0, 0.0, 1.0 / mr[4])
    minv = (*minv, 0.0 if planar else 1.0 / p[L.P_M3])
    dg = k["dg"]
    n = np.array(dg[L.D_NGLOBAL + 3 * j:L.D_NGLOBAL + 3 * j + 3])
    r3 = np.array(y[6:9])
    if j == 0:
        qrod = r3 + np.array(mv(r3m, (-0.5 * p[L.P_L3], 0.0, 0.0))) + jp[j, L.J_RI] * n
    else:
        qrod = r3 + np.array(mv(r3m, (0.5 * p[L.P_L3], 0.0, 0.0))) + jp[j, L.J_RJ] * n
    jr = point_jacobian_rot(r3m, mtv(r3m, tuple(qrod - r3)), g3)
    w = point_mobility(j, jr, k["C"], k["L"], nc, minv, mr_inv, np.zeros((VZ_ROWS, NZ)),
                       int(p[L.P_GUIDE]) if axis is None else axis)
    xx, xy, xz, yy, yz, zz = w
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


@pytest.mark.parametrize("joints,preset", [(j, pr) for j in ("one", "oneA", "two")
                                           for pr in ("realistic", "paper")])
def test_constrained_contact_mobility(joints, preset):
    """The full 3x3 W_p = J_rel W J_rel^T, W = M^-1 - M^-1 Cq^T (Cq M^-1 Cq^T)^-1 Cq M^-1."""
    pk = packed_case(joints, preset)
    rng = np.random.default_rng(11)
    for t in (0.0, 0.29, 0.6):
        y = contact_state(base_state(pk, pk.p[L.P_OMEGA] * t), pk.p, pk.jp, rng)
        mobilities_agree(t, y, pk)


def mobilities_agree(t, y, pk):
    """The kernel's W_p of every contact of the reference at (t, y) within RTOL of the
    reference's; returns the kernel's intermediates and the reference's result."""
    k = run_evaluate(t, y, pk.p, pk.jp)
    r = ref_mod.evaluate(t, y, pk.p, pk.jp)
    for j in r.contacts:
        wk = kernel_point_mobility(k, y, pk, j)
        wr = ref_mod.point_mobility(r, j)
        assert np.max(np.abs(wk - wr)) <= RTOL * np.max(np.abs(wr)), (j, wk, wr)
    return k, r


def rate_case(joints, preset, **contact):
    return packed_case(joints, preset, contact=contact, friction={"enabled": False})


@pytest.mark.parametrize("joints,preset,j", [("one", "realistic", 1), ("one", "paper", 1),
                                             ("oneA", "realistic", 0), ("oneA", "paper", 0),
                                             ("two", "realistic", 0), ("two", "realistic", 1),
                                             ("two", "paper", 0), ("two", "paper", 1)])
def test_stiff_rate_undamped(joints, preset, j):
    """c_r = 1 (no damping), no friction, separating slowly (no predictive branch), the
    other joint out of contact: rate = sqrt(dF/d delta / m_eff) with the reference m_eff."""
    pk = rate_case(joints, preset, restitution=1.0)
    rng = np.random.default_rng(5 + j)
    delta = [-0.5 * CLEAR, -0.5 * CLEAR]
    delta[j] = 3e-6
    ddot = [-1e-3, -1e-3]
    ddot[j] = -1e-4
    for t in (0.0, 0.35):
        y = contact_state(base_state(pk, pk.p[L.P_OMEGA] * t), pk.p, pk.jp, rng, delta=delta,
                          ddot=ddot)
        k = run_evaluate(t, y, pk.p, pk.jp)
        r = ref_mod.evaluate(t, y, pk.p, pk.jp)
        c = r.contacts[j]
        assert c.dfn_dddot == 0.0 or abs(c.dfn_dddot) < 1e-12 * c.dfn_ddelta
        elastic, _, m_eff = ref_mod.stiff_rates(r, j, pk.p, pk.jp)
        assert elastic == pytest.approx(np.sqrt(c.dfn_ddelta / m_eff), rel=1e-12)
        rate = k["dg"][L.D_RATE]
        assert rate == pytest.approx(elastic, rel=RTOL)
        # the effective mass it implies
        assert c.dfn_ddelta / rate ** 2 == pytest.approx(m_eff, rel=2 * RTOL)


@pytest.mark.parametrize("joints,preset", [("one", "realistic"), ("two", "paper")])
def test_stiff_rate_damped_and_friction(joints, preset):
    """Damping (c_r = 0.7) and friction with the slip in the ramp: rate = max(root of
    m_eff s^2 + dF/d delta_dot s + dF/d delta, mu F_N / (v1 - v0) * largest tangential
    inverse mass); separating, so the predictive impact rate stays out."""
    for friction in (False, True):
        pk = packed_case(joints, preset, friction={"enabled": friction})
        rng = np.random.default_rng(3)
        j = 1
        delta = [-0.5 * CLEAR, 4e-6]
        y = contact_state(base_state(pk, 1.0), pk.p, pk.jp, rng, delta=delta,
                          ddot=(-1e-3, -2e-3), slip=(1e-3, 5e-4))
        rate, elastic, fric = rates_in_ramp(0.2, y, pk, j)
        assert (fric > 0.0) == friction
        assert rate == pytest.approx(max(elastic, fric), rel=RTOL)


def rates_in_ramp(t, y, pk, j):
    """The kernel's stiff rate at (t, y) and the reference's elastic/damping and friction
    rates of clearance joint j, whose slip lies in the friction ramp (asserted, as is an
    active damping term)."""
    k = run_evaluate(t, y, pk.p, pk.jp)
    r = ref_mod.evaluate(t, y, pk.p, pk.jp)
    c = r.contacts[j]
    assert pk.p[L.P_V0] < np.linalg.norm(c.vt) < pk.p[L.P_V1]
    assert c.dfn_dddot > 0.0
    elastic, fric, _ = ref_mod.stiff_rates(r, j, pk.p, pk.jp)
    return k["dg"][L.D_RATE], elastic, fric


def test_stiff_rate_predictive():
    """Approaching (delta_dot > 0): the rate at delta_pred^3 = delta^3 + 3 m_eff delta_dot^2
    c / (4 K) (shared.one_point_force_rate) with the reference m_eff and F_N slopes there."""
    pk = rate_case("one", "realistic")
    rng = np.random.default_rng(9)
    y = contact_state(base_state(pk, 0.4), pk.p, pk.jp, rng, delta=(0.0, 1e-6),
                      ddot=(0.0, 0.05))
    k = run_evaluate(0.1, y, pk.p, pk.jp)
    r = ref_mod.evaluate(0.1, y, pk.p, pk.jp)
    c = r.contacts[1]
    elastic, _, m_eff = ref_mod.stiff_rates(r, 1, pk.p, pk.jp)
    jp = pk.jp[1]
    kk = 4.0 * np.pi * jp[L.J_EW] * jp[L.J_RI] / 5.0
    dpred = (c.delta ** 3 + 0.75 * m_eff * c.ddot ** 2 * jp[L.J_C] / kk) ** (1.0 / 3.0)

    def fn(d, v):
        return ref_mod.normal_force(d, v, jp[L.J_C], jp[L.J_EW], jp[L.J_RI], c.kappa)[0]

    kf = ref_mod.d1(lambda d: fn(d, c.ddot), dpred, 1e-3 * dpred)
    cf = ref_mod.d1(lambda v: fn(dpred, v), c.ddot, 1e-3 * c.ddot)
    pred = float(np.max(np.abs(np.roots([m_eff, cf, kf]))))
    assert pred > elastic
    assert k["dg"][L.D_RATE] == pytest.approx(pred, rel=1e-6)
