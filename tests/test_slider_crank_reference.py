"""The planar slider-crank (``mechanism.kind: slider_crank``, docs/mechanisms.md) against the
dense reference of tests/reference.py.

The reference's slider-crank is the RSSP's three bodies with the slider's guide along the
global axis ``p[P_GUIDE]`` = 1 (y): its prismatic rows hold the slider's offset from the
guide's line through (0, 0, z_s) along the two directions across it (e_z x e_y = -x, and z)
and its three angles, and leave y free; the rod is held in the plane (its centroid's offset
along the plane's normal e_guide x e_z, and alpha3 - pi/2), and the ideal pins A and B keep
the two rows of their offsets projected on the plane (the kernel holds x3 and alpha3 as
coordinates and writes the pins' y and z rows: the same constraints, written otherwise);
everything else (the dense KKT system, the
finite-difference Jacobians, the mass matrix, the contact forces through point Jacobians)
is the RSSP's. Its elastic law is the benchmark's, Hertz's power law with n = 3/2 at A, B
and O (``contact.elastic: hertz``), written from its formula.

1. The reference alone against the slider-crank's closed form (the slider along y, from
   |B - A| = l3 with the crank pin at (0, l2 sin theta, -l2 cos theta)): its ideal slider's
   acceleration at 60 and 5000 rpm, the peak r w^2 (1 + l2/l3) at top dead centre, and no
   guide load along the guide.
2. The kernel's ``dynamics.evaluate`` (its slider-crank build, tests/test_reference
   .SLIDER_CRANK_BUILD) against the reference, with tests/test_reference's ``compare``
   (every acceleration, the drive torque, the bearing's force at O, the joint forces, the
   contact diagnostics, the drive and dissipated powers; RTOL = 1e-7 of each quantity's
   scale, as the RSSP's): ideal; clearance at B, at A, at O, at A and B, at O, A and B,
   each pressed into contact (in the crank's plane, and in a random direction, which the
   spherical type also allows); a bushing at B, at O (with B's clearance) and at A; the
   paper's law at A and B; the benchmark's speed (5000 rpm); theta0, Baumgarte and gravity
   along the guide and across the plane; the kernel's own states along one crank turn at
   5000 rpm.
3. The contact mobility W_p of ``dynamics.point_mobility`` (its guide axis 1: the slider
   moves along y) against the reference's J_rel W J_rel^T, and the stiff rate at B.
"""

from __future__ import annotations

import numpy as np
import pytest
import reference as ref_mod
from test_reference import (
    RTOL,
    base_state,
    compare,
    contact_state,
    kernel_point_mobility,
    mobilities_agree,
    packed_case,
    perturb,
    place_balls,
    run_evaluate,
    set_contact_velocity,
    unit,
)
from test_revolute_reference import seat_journal

from clearsweep.core import layout as L
from clearsweep.core.joints import INDEX
from clearsweep.simulation import run_kernel

A, B, O = INDEX["A"], INDEX["B"], INDEX["O"]
CLEAR = 2.5e-4
#: The benchmark's crank speed [rpm] (Flores et al. 2008; docs/mechanisms.md).
BENCHMARK_RPM = 5000.0
BUSHING = {"type": "bushing", "bushing_stiffness": [2e6, 5e5], "bushing_damping": [400.0, 100.0]}
#: A pin's bushing (A, B): its axial pair the radial one (config validation refuses another)
PIN_BUSHING = {"type": "bushing", "bushing_stiffness": [2e6, 2e6],
               "bushing_damping": [400.0, 400.0]}
SC_JOINTS = {
    "ideal": {},
    "B": {"B": {"clearance": CLEAR}},
    "A": {"A": {"clearance": CLEAR}},
    "O": {"O": {"clearance": CLEAR}},
    "AB": {"A": {"clearance": CLEAR}, "B": {"clearance": CLEAR}},
    "OAB": {"O": {"clearance": CLEAR}, "A": {"clearance": CLEAR}, "B": {"clearance": CLEAR}},
}
SC_BUSHINGS = {
    "B_bushing": {"B": PIN_BUSHING},
    "O_bushing_B": {"O": BUSHING, "B": {"clearance": CLEAR}},
    "A_bushing_O": {"A": PIN_BUSHING, "O": {"clearance": CLEAR}},
}


def sc_case(joints, elastic="hertz", **sections):
    """The packed slider-crank (flores_benchmark) with ``joints`` (a joints section), the
    benchmark's elastic law unless ``elastic`` says otherwise."""
    sections = dict(sections)
    sections["mechanism"] = dict(sections.get("mechanism", {}), kind="slider_crank")
    sections["contact"] = dict(sections.get("contact", {}), elastic=elastic)
    pk = packed_case(joints, "flores_benchmark", **sections)
    assert pk.p[L.P_GUIDE] == 1.0
    return pk


def planar_contact_state(y, pk, rng, delta=2e-6, ddot=3e-3, slip=5e-2):
    """The pins of A and B (where they have clearance) pressed delta into their bearings in
    random directions of the crank's plane (y-z), approaching at ddot and slipping at
    ``slip`` in that plane; the rod and slider follow (test_reference.place_balls).
    ``delta`` and ``ddot``: one value for both, or a pair (A's, B's)."""
    p, jp = pk.p, pk.jp
    joints = [j for j in (A, B) if jp[j, L.J_CLEARANCE] != 0.0]
    deltas = dict(zip((A, B), np.broadcast_to(delta, 2), strict=True))
    ddots = dict(zip((A, B), np.broadcast_to(ddot, 2), strict=True))
    offsets = {}
    for j in joints:
        phi = rng.uniform(-np.pi, np.pi)
        offsets[j] = (jp[j, L.J_C] + deltas[j]) * np.array([0.0, np.cos(phi), np.sin(phi)])
    y = place_balls(y, p, jp, offsets)
    for j in joints:
        # the slip's direction: the plane's tangent of n (set_contact_velocity keeps it)
        y = set_contact_velocity(y, p, jp, j, ddots[j], slip * unit(np.array([0.0, 1.0, 1.0])))
    return y


def sc_state(pk, t, rng, planar=True, delta_o=2e-6, ddot_o=3e-3):
    """A drifted state at time t (test_reference.perturb of the ideal kinematics), O's
    journal seated (test_revolute_reference.seat_journal) where it has clearance, A and B
    pressed into contact where they have clearance: in the crank's plane (``planar``) or in
    random directions (test_reference.contact_state); the rod and slider follow the crank
    where a joint has clearance (else the drifted state as it is)."""
    p, jp = pk.p, pk.jp
    y = perturb(base_state(pk, p[L.P_THETA0] + p[L.P_OMEGA] * t), rng)
    if not jp[:, L.J_CLEARANCE].any():
        return y                                    # the ideal mechanism: drifted only
    if jp[O, L.J_CLEARANCE] != 0.0:
        y = seat_journal(y, p, jp, rng, delta_o, ddot_o)
    if planar:
        return planar_contact_state(y, pk, rng)
    return contact_state(y, p, jp, rng, drift=False)


def in_contact(res, pk):
    """Every clearance joint of the reference's result is in contact, approaching or
    receding, and slipping."""
    for j, c in res["reference"].contacts.items():
        if pk.jp[j, L.J_BUSHING] != 0.0:
            continue
        assert c.delta > 0.0 and c.fn > 0.0 and c.ddot != 0.0, j
        assert np.linalg.norm(c.vt) > pk.p[L.P_V0], j


def worst(results):
    return {key: max(res[key] for res in results)
            for key in ("qdd", "torque", "reaction_O", "joint_force")}


# ---------------------------------------------------------------------------
# 1. the reference against the closed form
# ---------------------------------------------------------------------------

def closed_form_acceleration(theta, omega, l2, l3, zs):
    """d^2 s / dt^2 of s = l2 sin(theta) + w, w = sqrt(l3^2 - u^2), u = z_s + l2 cos(theta),
    at constant omega: s'' = -l2 w^2 sin(theta) + w'', w'' = -(u'^2 + u u'' + w'^2) / w."""
    u = zs + l2 * np.cos(theta)
    ud = -l2 * omega * np.sin(theta)
    udd = -l2 * omega ** 2 * np.cos(theta)
    w = np.sqrt(l3 ** 2 - u ** 2)
    wd = -u * ud / w
    return -l2 * omega ** 2 * np.sin(theta) - (ud ** 2 + u * udd + wd ** 2) / w


@pytest.mark.parametrize("rpm", [60.0, BENCHMARK_RPM])
def test_reference_against_closed_form(rpm):
    """The reference's ideal slider-crank on its exact kinematics (params.initial_state) at
    eight crank angles: the slider's acceleration along y is the closed form's within 1e-10
    of its peak, r w^2 (1 + l2/l3) at top dead centre (theta = pi/2); its acceleration
    across the guide (x, z) and its angles' vanish, and the guide takes no load along y.
    The reference's finite differences are good to ~1e-10 relative (test_reference's
    docstring); measured 4.8e-12 of the peak at both speeds."""
    pk = sc_case({}, mechanism={"speed_rpm": rpm})
    p = pk.p
    l2, l3, zs, omega = p[L.P_L2], p[L.P_L3], p[L.P_ZS], p[L.P_OMEGA]
    peak = l2 * omega ** 2 * (1.0 + l2 / l3)
    for theta in np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False) + 0.3:
        t = theta / omega
        r = ref_mod.evaluate(t, base_state(pk, theta), p, pk.jp)
        want = closed_form_acceleration(theta, omega, l2, l3, zs)
        assert abs(r.qdd[13] - want) <= 1e-10 * peak, (theta, r.qdd[13], want)
        assert np.max(np.abs(r.qdd[[12, 14, 15, 16, 17]])) <= 1e-10 * peak
        assert r.joint_force[INDEX["P"], 1] == 0.0
    r = ref_mod.evaluate(0.5 * np.pi / omega, base_state(pk, 0.5 * np.pi), p, pk.jp)
    assert r.qdd[13] == pytest.approx(-peak, rel=1e-10)
    if rpm == BENCHMARK_RPM:
        assert peak == pytest.approx(1.942e4, rel=1e-3)     # docs/mechanisms.md's figure


# ---------------------------------------------------------------------------
# 2. the kernel's right-hand side against the reference
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("joints", list(SC_JOINTS))
def test_slider_crank_states(joints):
    """Drifted states at six crank angles (ideal: drifted only), each clearance joint pressed
    2e-6 m into contact, approaching at 3e-3 m/s and slipping at 5e-2 m/s in the crank's
    plane, with and without stored impact velocities; and the start (params.initial_state,
    seated by pack where a joint has clearance). The pins A and B touch in the plane only
    (was: two of the states in random directions across it, a ball's)."""
    pk = sc_case(SC_JOINTS[joints])
    rng = np.random.default_rng(200 + list(SC_JOINTS).index(joints))
    results = [compare(0.0, pk.y0, pk)]
    for t in (0.0, 0.13, 0.41, 0.77, 0.29, 0.6):
        y = sc_state(pk, t, rng)
        res = compare(t, y, pk)
        in_contact(res, pk)
        results.append(res)
        if joints != "ideal":
            results.append(compare(t, y, pk, dv0=(0.05, 0.02, 0.04)))
    # larger drift, so that the Baumgarte terms weigh well above the tolerance
    y = perturb(base_state(pk, 2.0), rng, pos=1e-5, ang=1e-4, vel=1e-3, rate=1e-2)
    results.append(compare(0.25, y, pk))
    assert all(v < RTOL for v in worst(results).values())


@pytest.mark.parametrize("joints", ["ideal", "B", "OAB"])
def test_slider_crank_benchmark_speed(joints):
    """At the benchmark's 5000 rpm (slider accelerations ~2e4 m/s^2, joint loads ~1e3 N):
    the same comparison at drifted states in contact (the journal's approach at 0.3 m/s).
    The contact points move at up to 33 m/s (the crank pin's w l2 = 26 m/s): the reference's
    approach rates and slips carry its point Jacobians' error there, up to 6.4e-12 m/s at A
    (2.5e-13 of the point's speed; the kernel's is within 1e-15 m/s of a complex-step
    Jacobian's), so ``compare`` takes the speed scale 2 w l2."""
    pk = sc_case(SC_JOINTS[joints], mechanism={"speed_rpm": BENCHMARK_RPM})
    rng = np.random.default_rng(300 + len(joints))
    speed = 2.0 * pk.p[L.P_OMEGA] * pk.p[L.P_L2]
    results = []
    for t in (0.0, 1.3e-3, 4.1e-3, 7.7e-3):
        y = sc_state(pk, t, rng, ddot_o=0.3)
        res = compare(t, y, pk, speed=speed)
        in_contact(res, pk)
        # the loads of the benchmark's speed: the ideal slider's inertia (~2e4 m/s^2 x
        # 0.14 kg), or the contacts' Hertz forces (~400 N at 2e-6 m), against ~3 N at 60 rpm
        assert np.max(np.abs(res["reference"].joint_force)) > 100.0
        results.append(res)
    assert all(v < RTOL for v in worst(results).values())


@pytest.mark.parametrize("joints", ["ideal", "B", "OAB"])
def test_slider_crank_other_parameters(joints):
    """theta0 != 0, another speed, the text's Baumgarte 50, gravity with parts along the guide
    (y) and across the plane (x): the guide's axis in the slider's equations and in its
    reaction, not only in its kinematics."""
    pk = sc_case(SC_JOINTS[joints],
                 mechanism={"theta0": 0.7, "speed_rpm": 90.0, "gravity": [1.5, -2.0, -9.81]},
                 solver={"baumgarte": [50.0, 50.0]})
    rng = np.random.default_rng(800 + len(joints))
    results = [compare(0.0, pk.y0, pk)]
    for t in (0.05, 0.5):
        res = compare(t, sc_state(pk, t, rng), pk)
        in_contact(res, pk)
        results.append(res)
    assert all(v < RTOL for v in worst(results).values())


@pytest.mark.parametrize("joints", list(SC_BUSHINGS))
def test_slider_crank_bushings(joints):
    """A bushing at B, at O (B with clearance) and at A (O with clearance), each deflected
    some micrometres and moving (test_bushing's drift), the clearance joint pressed into
    contact; the bushing's force in the joint forces and its power in the dissipation."""
    pk = sc_case(SC_BUSHINGS[joints])
    rng = np.random.default_rng(400 + list(SC_BUSHINGS).index(joints))
    for t in (0.013, 0.37):
        y = perturb(base_state(pk, pk.p[L.P_OMEGA] * t), rng, pos=5e-6, ang=2e-5, vel=1e-3,
                    rate=1e-2)
        if pk.jp[O, L.J_CLEARANCE] != 0.0:
            # the journal seated, the rod and slider following the crank with A's bushing
            # deflected 5e-6 m
            y = seat_journal(y, pk.p, pk.jp, rng, 2e-6, 3e-3)
            y = place_balls(y, pk.p, pk.jp, {A: 5e-6 * unit(rng.standard_normal(3))})
        if pk.jp[B, L.J_CLEARANCE] != 0.0:
            y = planar_contact_state(y, pk, rng)
        res = compare(t, y, pk)
        for j in np.nonzero(pk.jp[:, L.J_BUSHING])[0]:
            assert np.linalg.norm(res["reference"].contacts[j].force) > 1e-2   # loaded
        assert all(v < RTOL for v in worst([res]).values())


def test_slider_crank_paper_law():
    """Under the paper's elastic law (contact.elastic: paper) the slider-crank's pins A and B
    take the journal's Hertz law as O does (was: the paper's layered law at A and B, a
    ball's): the reference's journal branch for the pins."""
    pk = sc_case(SC_JOINTS["OAB"], elastic="paper")
    assert pk.p[L.P_EXPONENT] == 0.0
    rng = np.random.default_rng(500)
    results = []
    for t in (0.1, 0.55):
        res = compare(t, sc_state(pk, t, rng), pk)
        in_contact(res, pk)
        results.append(res)
    assert all(v < RTOL for v in worst(results).values())


@pytest.fixture(scope="module")
def benchmark_runs():
    """One crank turn (0.012 s) at the benchmark's 5000 rpm with clearance at B, and at O, A
    and B, from the seated start: the kernel's own states, the contacts as its dynamics
    leave them (B's ball pressed into its socket throughout, its F_N up to 5.6 kN)."""
    out = {}
    for joints in ("B", "OAB"):
        pk = sc_case(SC_JOINTS[joints], mechanism={"speed_rpm": BENCHMARK_RPM},
                     solver={"duration": 0.012})
        raw = run_kernel(pk)
        assert raw.status == "ok"
        out[joints] = (pk, raw)
    return out


@pytest.mark.parametrize("joints", ["B", "OAB"])
def test_slider_crank_simulated_states(benchmark_runs, joints):
    """The states at a third, two thirds and the end of the turn. The worst difference is the
    crank's angular acceleration (its scale 1 rad/s^2): the reference's -5.9e-9 rad/s^2 at the
    turn's end, the round-off of its second difference along (qd, 1) on the driver's row,
    whose terms grow as omega t (2 pi here), against the kernel's 0; the rest within 1e-9."""
    pk, raw = benchmark_runs[joints]
    speed = 2.0 * pk.p[L.P_OMEGA] * pk.p[L.P_L2]
    n = len(raw.t)
    results = []
    for k in (n // 3, 2 * n // 3, n - 1):
        res = compare(float(raw.t[k]), np.array(raw.y[k]), pk, speed=speed)
        assert res["reference"].contacts[B].delta > 0.0
        results.append(res)
    assert max(res["reference"].contacts[B].fn for res in results) > 100.0
    assert all(v < RTOL for v in worst(results).values())


# ---------------------------------------------------------------------------
# 3. contact mobility and stiff rate
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("joints", ["B", "AB", "OAB"])
def test_slider_crank_contact_mobility(joints):
    """W_p = J_rel W J_rel^T of every clearance joint, W = M^-1 - M^-1 Cq^T (Cq M^-1 Cq^T)^-1
    Cq M^-1, against dynamics.point_mobility with the guide's axis 1 (B's socket moves with
    the slider along y). The RSSP's axis (0) is off by far more than the tolerance at B."""
    pk = sc_case(SC_JOINTS[joints])
    rng = np.random.default_rng(600)
    for t, planar in ((0.0, True), (0.29, True), (0.6, False)):
        y = sc_state(pk, t, rng, planar)
        k, r = mobilities_agree(t, y, pk)
        wk0 = kernel_point_mobility(k, y, pk, B, axis=0)     # the RSSP's axis, wrongly
        assert np.max(np.abs(wk0 - ref_mod.point_mobility(r, B))) > 1e-2 * np.max(np.abs(wk0))


def test_slider_crank_stiff_rate_undamped():
    """c_r = 1, no friction, B pressed 3e-6 m and separating slowly (no predictive branch),
    A out of contact: the kernel's stiff rate is sqrt(dF/d delta / m_eff) with the
    reference's m_eff at B (the slider's mass along y)."""
    pk = sc_case(SC_JOINTS["AB"], contact={"restitution": 1.0}, friction={"enabled": False})
    rng = np.random.default_rng(700)
    for t in (0.0, 0.35):
        # in the plane: a pin's gap (was: random directions, a ball's)
        y = planar_contact_state(base_state(pk, pk.p[L.P_OMEGA] * t), pk, rng,
                                 delta=(-0.5 * CLEAR, 3e-6), ddot=(-1e-3, -1e-4))
        k = run_evaluate(t, y, pk.p, pk.jp)
        r = ref_mod.evaluate(t, y, pk.p, pk.jp)
        c = r.contacts[B]
        assert r.contacts[A].delta < 0.0 and c.delta > 0.0
        assert abs(c.dfn_dddot) < 1e-12 * c.dfn_ddelta
        elastic, _, m_eff = ref_mod.stiff_rates(r, B, pk.p, pk.jp)
        assert elastic == pytest.approx(np.sqrt(c.dfn_ddelta / m_eff), rel=1e-12)
        assert k["dg"][L.D_RATE] == pytest.approx(elastic, rel=RTOL, abs=0.0)


def test_place_balls_on_the_guide():
    """tests/test_reference's helpers handle the slider-crank's guide along y: place_balls
    keeps the slider on its guide's line (x = 0, z = z_s) and B's ball at its offset."""
    pk = sc_case(SC_JOINTS["B"])
    y = base_state(pk, 0.7)
    d_b = 1e-4 * unit(np.array([0.0, 1.0, -2.0]))
    y = place_balls(y, pk.p, pk.jp, {B: d_b})
    mech = ref_mod.Mechanism(pk.p, pk.jp)
    q = y[:L.N_Q]
    assert q[12] == 0.0 and q[14] == pk.p[L.P_ZS]
    ball = ref_mod.point(q, ref_mod.ROD, mech.u_B3)
    assert np.allclose(ball - q[12:15], d_b, rtol=0.0, atol=1e-15)
