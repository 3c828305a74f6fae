"""Joint O (the crank's journal in its bearing, core/revolute.py) against independent models.

1. The kernel's right-hand side with O's clearance (alone, with A, with B, with both) against
   the dense reference of tests/reference.py, which keeps the revolute's axial row and applies
   the journal's contact force (Hertz's law of internal cylinders, n = 3/2, with damping and
   friction written from their formulas) at its contact point on the crank: accelerations,
   joint forces, the bearing's force on the crank, the drive torque, the contact diagnostics
   (tests/test_reference.py's ``compare``, its tolerances), the contact mobility W_p, and
   the stiff rate (docs/physics.md section 4) of the journal's contact, predictive included.
   Measured worst differences, scaled as ``compare`` scales them: accelerations 3.9e-11,
   torque 7.5e-12, the bearing's force and the joint forces 1.1e-11, O's F_N and friction
   force 1.1e-11 relative (the reference's finite-difference approach rate), W_p 6.4e-13;
   RTOL = 1e-7.
2. One journal impact of the full kernel against scipy's integration of the 1-DOF model
   m2 delta'' = -F_N(delta, delta') + m2 a_ext.
3. The worn volume at O against k * sum(F_N |v_t| dt) of the kernel's rows, and the bearing
   map's volume against the worn volume.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import reference as ref_mod
from impacts import hertz_modulus_steel, kernel_impact, scipy_impact
from test_reference import (
    RTOL,
    base_state,
    compare,
    contact_state,
    kernel_point_mobility,
    packed_case,
    perturb,
    rates_in_ramp,
    run_evaluate,
)

from clearsweep.config import load_config, resolve_materials
from clearsweep.core import layout as L
from clearsweep.core.joints import INDEX
from clearsweep.params import pack
from clearsweep.simulation import case_dataset, prepare_kernel, run_kernel

ROOT = Path(__file__).resolve().parents[1]
A, B, O = INDEX["A"], INDEX["B"], INDEX["O"]
CLEAR = 2.5e-4
#: Joint O with clearance, alone and with A, B or both.
O_JOINTS = {
    "O": {"O": {"clearance": CLEAR}},
    "OA": {"O": {"clearance": CLEAR}, "A": {"clearance": CLEAR}},
    "OB": {"O": {"clearance": CLEAR}, "B": {"clearance": CLEAR}},
    "OAB": {"O": {"clearance": CLEAR}, "A": {"clearance": CLEAR}, "B": {"clearance": CLEAR}},
}
CASES = [(j, preset) for j in O_JOINTS for preset in ("realistic", "paper")]


def o_case(joints, preset="realistic", **sections):
    return packed_case(O_JOINTS[joints], preset, **sections)


# ---------------------------------------------------------------------------
# 1. the right-hand side against the dense reference
# ---------------------------------------------------------------------------

def seat_journal(y, p, jp, rng, delta, ddot, slip=None):
    """Shift the crank in the bearing's plane so that the journal centre sits at
    (c + delta) n, n a random in-plane direction, and its centroid velocity in the plane so
    that the journal approaches the bearing wall at ddot (the crank's rotation as it is) and,
    where ``slip`` is given, slides along it at that speed (else at about omega R_j)."""
    mech = ref_mod.Mechanism(p, jp)
    y = np.array(y, float)
    phi = rng.uniform(-np.pi, np.pi)
    n = np.array([0.0, np.cos(phi), np.sin(phi)])
    tangent = np.array([0.0, -n[2], n[1]])
    p_o = ref_mod.point(y[:L.N_Q], ref_mod.CRANK, mech.u_O)
    y[L.Y_R2 + 1:L.Y_R2 + 3] += (jp[O, L.J_C] + delta) * n[1:] - p_o[1:]
    c = ref_mod.journal_contact(mech, y[:L.N_Q], y[L.Y_QD:L.Y_QD + L.N_Q])
    assert np.allclose(c.n, n, atol=1e-12)
    shift = (ddot - c.ddot) * n
    if slip is not None:
        shift += (slip - c.vt @ tangent) * tangent
    y[L.Y_QD + L.Y_R2 + 1:L.Y_QD + L.Y_R2 + 3] += shift[1:]
    return y


def journal_state(y0, pk, rng, delta_o=2e-6, ddot_o=3e-3, slip_o=None, **spherical):
    """A drifted state (tests/test_reference.perturb) with the journal pressed into the bearing
    wall (seat_journal) and A, B where they have clearance pressed into their sockets
    (tests/test_reference.contact_state; the rod and slider follow the crank)."""
    y = perturb(y0, rng)
    y = seat_journal(y, pk.p, pk.jp, rng, delta_o, ddot_o, slip_o)
    return contact_state(y, pk.p, pk.jp, rng, drift=False, **spherical)


@pytest.mark.parametrize("joints,preset", CASES)
def test_journal_in_contact(joints, preset):
    """Journal pressed 2e-6 m (or 5e-6 m) into the bearing, approaching or receding, sliding
    at about omega R_j = 0.06 m/s (full friction) or in the friction ramp, several crank
    angles, A and B pressed where they have clearance, with and without stored impact
    velocities: every quantity of ``compare`` within RTOL of the reference."""
    pk = o_case(joints, preset)
    rng = np.random.default_rng(100 + CASES.index((joints, preset)))
    results = []
    for t, delta_o, ddot_o, slip_o in ((0.0, 2e-6, 3e-3, None), (0.13, 5e-6, -2e-3, None),
                                       (0.41, 2e-6, 1e-3, 5e-4), (0.77, 5e-6, 4e-3, None)):
        y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
        y = journal_state(y0, pk, rng, delta_o, ddot_o, slip_o)
        res = compare(t, y, pk)
        r = res["reference"]
        c = r.contacts[O]
        assert c.delta > 0.0 and c.fn > 0.0 and c.ft > 0.0
        assert c.ddot == pytest.approx(ddot_o, rel=1e-9)
        slip = np.linalg.norm(c.vt)
        if slip_o is None:
            assert slip > pk.p[L.P_V1]
        else:
            assert pk.p[L.P_V0] < slip < pk.p[L.P_V1]
        # the bearing's force: the journal's contact force (in its plane) and the axial row's
        # reaction (compare also checks the torque, which carries the friction's moment)
        assert np.linalg.norm(r.reaction_O[1:]) > 0.5 * c.fn
        results.append(res)
        results.append(compare(t, y, pk, dv0=(0.05, 0.02, 0.04)))
    for key in ("qdd", "torque", "reaction_O", "joint_force"):
        assert max(res[key] for res in results) < RTOL


@pytest.mark.parametrize("joints", list(O_JOINTS))
def test_journal_other_parameters(joints):
    """theta0 != 0, another speed, the text's Baumgarte 50, gravity with x and y parts; the
    initial state too (the seated start: the journal leans on the bearing under the load)."""
    pk = o_case(joints, "realistic",
                mechanism={"theta0": 0.7, "speed_rpm": 90.0, "gravity": [1.5, -2.0, -9.81]},
                solver={"baumgarte": [50.0, 50.0]})
    rng = np.random.default_rng(23)
    res = compare(0.0, pk.y0, pk)
    assert res["reference"].contacts[O].fn > 0.0
    for t in (0.05, 0.5):
        y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
        compare(t, journal_state(y0, pk, rng), pk)


@pytest.mark.parametrize("joints,preset", CASES)
def test_journal_contact_mobility(joints, preset):
    """W_p = J_rel W J_rel^T of O (the journal's contact point on the crank) and of A and B
    with the crank's centroid free in the bearing's plane, against dynamics.point_mobility."""
    pk = o_case(joints, preset)
    rng = np.random.default_rng(31)
    m2 = pk.p[L.P_M2]
    for t in (0.0, 0.29, 0.6):
        y = journal_state(base_state(pk, pk.p[L.P_OMEGA] * t), pk, rng)
        k = run_evaluate(t, y, pk.p, pk.jp)
        r = ref_mod.evaluate(t, y, pk.p, pk.jp)
        assert O in r.contacts
        for j in r.contacts:
            wk = kernel_point_mobility(k, y, pk, j)
            wr = ref_mod.point_mobility(r, j)
            assert np.max(np.abs(wk - wr)) <= RTOL * np.max(np.abs(wr)), (j, wk, wr)
        if joints == "OAB":
            # nothing holds the crank in the bearing's plane: the journal's mass is m2 there
            assert np.allclose(ref_mod.point_mobility(r, O), np.diag([0.0, 1.0, 1.0]) / m2,
                               rtol=0.0, atol=RTOL / m2)



#: contact_state's arguments that leave A and B (where they have clearance) out of contact
#: and separating.
OUT_OF_CONTACT = {"delta": (-0.5 * CLEAR, -0.5 * CLEAR), "ddot": (-1e-3, -1e-3)}


@pytest.mark.parametrize("joints,preset", CASES)
def test_journal_stiff_rate_undamped(joints, preset):
    """c_r = 1, no friction, the journal separating slowly, A and B out of contact: the stiff
    rate (dg[D_RATE]) is sqrt(dF/d delta / m_eff) with the reference's m_eff of the journal."""
    pk = o_case(joints, preset, contact={"restitution": 1.0}, friction={"enabled": False})
    rng = np.random.default_rng(41)
    for t in (0.0, 0.35):
        y0 = base_state(pk, pk.p[L.P_OMEGA] * t)
        y = journal_state(y0, pk, rng, 3e-6, -1e-4, **OUT_OF_CONTACT)
        k = run_evaluate(t, y, pk.p, pk.jp)
        r = ref_mod.evaluate(t, y, pk.p, pk.jp)
        c = r.contacts[O]
        assert all(r.contacts[j].delta < 0.0 for j in r.contacts if j != O)
        assert abs(c.dfn_dddot) < 1e-12 * c.dfn_ddelta
        elastic, _, m_eff = ref_mod.stiff_rates(r, O, pk.p, pk.jp)
        assert k["dg"][L.D_RATE] == pytest.approx(elastic, rel=RTOL, abs=0.0)
        assert elastic == pytest.approx(np.sqrt(c.dfn_ddelta / m_eff), rel=1e-12, abs=0.0)
        if joints == "OAB":
            assert m_eff == pytest.approx(pk.p[L.P_M2], rel=1e-12, abs=0.0)


@pytest.mark.parametrize("joints,preset", [("O", "realistic"), ("OAB", "paper")])
def test_journal_stiff_rate_damped_and_friction(joints, preset):
    """Damping (c_r = 0.7) and friction with the journal's slip in the ramp, separating: the
    rate is max(root of m_eff s^2 + dF/d delta_dot s + dF/d delta, mu F_N / (v1 - v0) times
    the largest tangential inverse mass), with the reference's W_p; a steep ramp (v1 = 2v0)
    so that friction's rate is the larger (steel's mu is 0.01)."""
    for friction in (False, True):
        pk = o_case(joints, preset, friction={"enabled": friction, "v1": 2.0e-4})
        rng = np.random.default_rng(47)
        y = journal_state(base_state(pk, 1.0), pk, rng, 4e-6, -2e-3, 1.5e-4, **OUT_OF_CONTACT)
        rate, elastic, fric = rates_in_ramp(0.2, y, pk, O)
        assert (fric > elastic) == friction
        assert rate == pytest.approx(max(elastic, fric), rel=RTOL, abs=0.0)


@pytest.mark.parametrize("joints", ["O", "OAB"])
def test_journal_stiff_rate_predictive(joints):
    """The journal approaching at 0.05 m/s from 1e-7 m: the rate at the penetration its kinetic
    energy reaches, (1/2) m_eff delta_dot^2 = U(delta_pred) - U(delta), U = A c^(1-n)
    delta^(n+1) / (n + 1) the Hertz law's energy (n = 3/2), with the damping there."""
    pk = o_case(joints, "realistic", friction={"enabled": False})
    rng = np.random.default_rng(43)
    y = journal_state(base_state(pk, 0.4), pk, rng, 1e-7, 0.05, **OUT_OF_CONTACT)
    k = run_evaluate(0.1, y, pk.p, pk.jp)
    r = ref_mod.evaluate(0.1, y, pk.p, pk.jp)
    c = r.contacts[O]
    elastic, _, m_eff = ref_mod.stiff_rates(r, O, pk.p, pk.jp)
    jp = pk.jp[O]
    cc, ew, ri, rj = jp[L.J_C], jp[L.J_EW], jp[L.J_RI], jp[L.J_RJ]
    n = ref_mod.JOURNAL_EXPONENT
    a = 4.0 / 3.0 * ew * np.sqrt(ri * rj)      # F_el = A c^(1-n) delta^n (journal_force)
    dpred = (c.delta ** (n + 1.0) + 0.5 * (n + 1.0) * m_eff * c.ddot ** 2 * cc ** (n - 1.0) / a
             ) ** (1.0 / (n + 1.0))
    assert dpred > 10.0 * c.delta

    def fn(d, v):
        return ref_mod.journal_force(d, v, cc, ew, ri, rj, c.kappa)[0]

    kf = ref_mod.d1(lambda d: fn(d, c.ddot), dpred, 1e-3 * dpred)
    cf = ref_mod.d1(lambda v: fn(dpred, v), c.ddot, 1e-3 * c.ddot)
    pred = float(np.max(np.abs(np.roots([m_eff, cf, kf]))))
    assert pred > elastic
    assert k["dg"][L.D_RATE] == pytest.approx(pred, rel=1e-6, abs=0.0)


# ---------------------------------------------------------------------------
# 2. one journal impact against the contact law integrated by scipy
# ---------------------------------------------------------------------------

def run_case(overrides):
    """The kernel's run of configs/one_clearance.yaml with ``overrides``, every step a row:
    (config, packed case, raw run, results dataset)."""
    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      ["solver.save_every=1", *overrides])
    pk = pack(cfg, resolve_materials(cfg))
    prepare_kernel(cfg.solver.method)
    raw = run_kernel(pk)
    assert raw.status == "ok"
    return cfg, pk, raw, case_dataset(cfg, pk, raw)

#: Clearance at O and at A (so that A does not hold the crank: the journal's effective mass is
#: m2 in the bearing's plane while A is out of contact), B ideal, both joints centred: the
#: crank's centroid flies free (gravity) while the crank turns, and the journal meets the
#: bearing wall after 6.3 ms at 0.079 m/s. dt = 1e-6 s resolves the impact (0.26 ms) in
#: 255 steps.
IMPACT = ["joints.B.clearance=0", f"joints.O.clearance={CLEAR}", f"joints.A.clearance={CLEAR}",
          "initial.joints=centred", "solver.dt=1.0e-6", "solver.duration=0.007"]


@pytest.fixture(scope="module")
def impact_run():
    return run_case(IMPACT)


def test_journal_impact_against_scipy(impact_run):
    """Peak normal force, peak penetration and the exit/entry velocity ratio of O's first
    impact against scipy's integration of m2 delta'' = -F_N(delta, delta') + m2 a_ext, F_N the
    journal's law (tests/reference.journal_force: Hertz n = 3/2 with the conformal radius and
    Hertz's modulus E* = E / (2 (1 - nu^2)) of the steel pair,
    the damping factor 20 (1 - c_r) / (13 c_r delta_dot0), delta_dot0 the impact's fastest
    approach), from the kernel's entry velocity; a_ext the approach acceleration of the two
    rows before contact (12.6 m/s^2: gravity, the journal's centripetal and centrifugal parts).

    Tolerance 1e-4 (relative). The kernel's peaks are row samples, every dt = 1e-6 s: near the
    peak F ~ F_max (1 - 1.5 (pi (t - t_p) / T)^2 / 2) for an impact of duration T = 0.26 ms,
    so a sample within dt/2 of the peak reads up to 1.5 (pi dt / 2T)^2 / 2 = 2.8e-5 low (the
    penetration 1.9e-5); RK4's error at rate * dt = 0.02 and the parts of a_ext that the
    1-DOF model holds constant (the crank turns 1.4 mrad during the impact; friction, mu =
    0.01, changes the journal's tangential velocity and so its centrifugal part) stay near
    1e-5. Measured: peak force 1.9e-5, penetration 1.3e-5, velocity ratio 1.0e-5. A stiffness
    off by 0.1 % (0.4 of it in the peak force) or a damping factor off by 0.1 % (1.2e-4 in
    the peak penetration, about half of it in the ratio) fails.
    """
    _, pk, raw, ds = impact_run
    assert int(ds.substeps_used) == 1          # the rows are the steps
    p, jp = pk.p, pk.jp
    dt = p[L.P_DT]
    d = raw.d
    ddot = d[:, L.D_DDOT + O]
    k0, k1, v_in, kernel = kernel_impact(raw, ds, O)
    # A out of contact throughout, so that only O's force moves the crank in the plane
    assert np.all(d[k0 - 2:k1 + 2, L.D_DELTA + A] < 0.0)
    assert ds.first_impact_time.sel(joint="O") == pytest.approx(raw.t[k0])
    a_ext = (ddot[k0 - 1] - ddot[k0 - 2]) / dt
    m2, cr = p[L.P_M2], p[L.P_CR]
    # Hertz's E* of the uncoated steel pair in closed form, not the kernel's packed value
    # (which held the paper's layered modulus, 1.346 times stiffer, before issue 41)
    c, ew, ri, rj = jp[O, L.J_C], hertz_modulus_steel(), jp[O, L.J_RI], jp[O, L.J_RJ]

    def force(x, v, kappa):
        return ref_mod.journal_force(x, v, c, ew, ri, rj, kappa)[0]

    # the impact velocity is the episode's fastest approach: a little above the entry
    # velocity, as a_ext still speeds the approach up while F_N < m2 a_ext
    t_out, model = scipy_impact(force, m2, v_in, cr, a_ext)
    assert t_out == pytest.approx((k1 - k0 + 1) * dt, abs=2 * dt)
    assert 0.5 < model["ratio"] < 0.9
    for key, val in model.items():
        assert kernel[key] == pytest.approx(val, rel=1e-4, abs=0.0), (key, kernel[key], val)


# ---------------------------------------------------------------------------
# 3. the worn volume at O
# ---------------------------------------------------------------------------

#: O alone with clearance, seated (the journal leans on the bearing under the crank's load
#: and slides at omega R_j = 0.06 m/s from the start), its own wear coefficient.
SLIDING = ["joints.B.clearance=0", f"joints.O.clearance={CLEAR}",
           "joints.O.wear_coefficient=3.0e-13", "solver.duration=0.01"]


def archard_volume(pk, raw):
    """k * sum(F_N |v_t| dt) at O over the rows after the first (each the end of a step of
    length dt: the right-end rule of the kernel)."""
    d = raw.d[1:]
    return pk.jp[O, L.J_K] * np.sum(d[:, L.D_FN + O] * d[:, L.D_VT + O] * pk.p[L.P_DT])


def bearing_map_volume(pk, ds):
    """sum(depth * R_i L dphi) over O's bearing map (its row 0; the other rows stay 0)."""
    wmap = ds.wear_map.sel(joint="O").values
    assert not wmap[1:].any()
    return wmap[0].sum() * pk.jp[O, L.J_RI] * pk.jp[O, L.J_LENGTH] * 2.0 * np.pi / wmap.shape[1]


def test_worn_volume_sliding():
    """A seated journal sliding for 0.01 s (1000 steps, all in contact): wear_volume at O
    equals k * sum(F_N |v_t| dt) of the rows, k O's own coefficient, to 1e-12 relative, and
    the bearing map holds that volume to 1e-12. Both sides add the same float64 products in
    another order (1000 positive terms: at most ~1e3 eps = 2e-13 apart); the map's deposit
    spreads each volume over bins whose weights sum to one (a rounding of ~1e-15 per step).
    A wrong coefficient (A's or B's 8e-14), a slip other than |v_t| or a step other than dt
    is off by far more."""
    _, pk, raw, ds = run_case(SLIDING)
    assert int(ds.substeps_used) == 1
    assert pk.jp[O, L.J_K] == 3.0e-13
    assert np.all(raw.d[1:, L.D_DELTA + O] > 0.0)
    assert np.all(raw.d[1:, L.D_VT + O] > 0.05)
    volume = float(ds.wear_volume.sel(joint="O"))
    assert volume > 0.0 and not ds.wear_volume.sel(joint=["A", "B"]).any()
    assert volume == pytest.approx(archard_volume(pk, raw), rel=1e-12, abs=0.0)
    assert bearing_map_volume(pk, ds) == pytest.approx(volume, rel=1e-12, abs=0.0)


def test_worn_volume_impact(impact_run):
    """The impact run of item 2 (in contact 255 of 7000 steps, F_N from 0 to 1.4 kN): the same
    identities. The worn volume to 1e-8: a row where the episode's impact velocity is set or
    raised (the approach still speeding up in the first steps of the impact) is evaluated
    again after the step's wear is booked, with the new damping factor, so its F_N differs
    from the one the wear used in the last digits (measured 2.3e-9 relative in all); the map
    to 1e-12."""
    _, pk, raw, ds = impact_run
    assert int(ds.substeps_used) == 1
    volume = float(ds.wear_volume.sel(joint="O"))
    assert volume > 0.0
    assert volume == pytest.approx(archard_volume(pk, raw), rel=1e-8, abs=0.0)
    assert bearing_map_volume(pk, ds) == pytest.approx(volume, rel=1e-12, abs=0.0)
