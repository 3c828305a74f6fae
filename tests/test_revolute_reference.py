"""Joint O (the crank's journal in its bearing, core/revolute.py) against independent models.

1. The kernel's right-hand side with O's clearance (alone, with A, with B, with both) against
   the dense reference of tests/reference.py, which keeps the revolute's axial row and applies
   the journal's contact force (Hertz's law of internal cylinders, n = 3/2, with damping and
   friction written from their formulas) at its contact point on the crank: accelerations,
   joint forces, the bearing's force on the crank, the drive torque, the contact diagnostics
   (tests/test_reference.py's ``compare``, its tolerances), and the contact mobility W_p.
   Measured worst differences, scaled as ``compare`` scales them: accelerations 3.9e-11,
   torque 7.5e-12, the bearing's force and the joint forces 1.1e-11, O's F_N and friction
   force 1.1e-11 relative (the reference's finite-difference approach rate), W_p 6.4e-13;
   RTOL = 1e-7.
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
    packed_case,
    perturb,
    run_evaluate,
)

from clearsweep.core import layout as L
from clearsweep.core.joints import INDEX

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

def seat_journal(y, p, jp, rng, delta, ddot):
    """Shift the crank in the bearing's plane so that the journal centre sits at
    (c + delta) n, n a random in-plane direction, and its centroid velocity along n so that
    the journal approaches the bearing wall at ddot (the crank's rotation as it is)."""
    mech = ref_mod.Mechanism(p, jp)
    y = np.array(y, float)
    phi = rng.uniform(-np.pi, np.pi)
    n = np.array([0.0, np.cos(phi), np.sin(phi)])
    p_o = ref_mod.point(y[:L.N_Q], ref_mod.CRANK, mech.u_O)
    y[L.Y_R2 + 1:L.Y_R2 + 3] += (jp[O, L.J_C] + delta) * n[1:] - p_o[1:]
    c = ref_mod.journal_contact(mech, y[:L.N_Q], y[L.Y_QD:L.Y_QD + L.N_Q])
    assert np.allclose(c.n, n, atol=1e-12)
    y[L.Y_QD + L.Y_R2 + 1:L.Y_QD + L.Y_R2 + 3] += (ddot - c.ddot) * n[1:]
    return y


def journal_state(y0, pk, rng, delta_o=2e-6, ddot_o=3e-3, **spherical):
    """A drifted state (tests/test_reference.perturb) with the journal pressed into the bearing
    wall (seat_journal) and A, B where they have clearance pressed into their sockets
    (tests/test_reference.contact_state; the rod and slider follow the crank)."""
    y = perturb(y0, rng)
    y = seat_journal(y, pk.p, pk.jp, rng, delta_o, ddot_o)
    return contact_state(y, pk.p, pk.jp, rng, drift=False, **spherical)


@pytest.mark.parametrize("joints,preset", CASES)
def test_journal_in_contact(joints, preset):
    """Journal pressed 2e-6 m (or 5e-6 m) into the bearing, approaching or receding, several
    crank angles, A and B pressed where they have clearance, with and without stored impact
    velocities: every quantity of ``compare`` within RTOL of the reference."""
    pk = o_case(joints, preset)
    rng = np.random.default_rng(100 + CASES.index((joints, preset)))
    results = []
    for t, delta_o, ddot_o in ((0.0, 2e-6, 3e-3), (0.13, 5e-6, -2e-3), (0.41, 2e-6, 1e-3),
                               (0.77, 5e-6, 4e-3)):
        y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
        y = journal_state(y0, pk, rng, delta_o, ddot_o)
        res = compare(t, y, pk)
        r = res["reference"]
        c = r.contacts[O]
        assert c.delta > 0.0 and c.fn > 0.0 and c.ft > 0.0
        assert c.ddot == pytest.approx(ddot_o, rel=1e-9)
        # the bearing's force carries the journal's contact force (in its plane) and the axial
        # row's reaction; the friction's moment about the crank axis reaches the drive torque
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

