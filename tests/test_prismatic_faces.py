"""The guide P's contact along the block's edges and faces (docs/physics.md 3.7, 5.7; issue
41 item 5): each wall meets the block's face along the face's two long edges, each a line
whose penetration is linear between its end corners and whose pressure per unit length is
k_l max(delta, 0), k_l = E* sqrt(W / (pi L)) (the face an elastic foundation of modulus
2 E* / sqrt(pi L W), half of it to each edge).

1. The line's loads on its two corners against scipy's quadrature of the pressure, and
   their energy: f_a = dU/d delta_a.
2. The kernel's guide force on a block posed flat on a wall (the face: 2 k_l L delta), and
   rolled so that one edge leads (the edge: k_l L delta): the closed forms, and no jump as
   the roll brings the second edge in.
3. The energy: the joint's elastic energy is the lines', dU/dt balances the guide's power
   along a motion that rolls the block from edge to face, and a run with impacts on the
   walls keeps its residual.
4. The walls' depth converges with the map's resolution and holds the worn volume.
5. An impact is one contact episode of the joint: it begins when the block goes from
   touching no wall to touching one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import reference as ref_mod
from test_prismatic import P_JOINTS, P, band_volumes, guide, line_stiffness, run_case
from test_reference import packed_case

from clearsweep.core import layout as L
from clearsweep.core import prismatic
from clearsweep.core.dynamics import GROUND
from clearsweep.core.work import Model


def guide_contact(model, slider, dg):
    """The guide's (force, moment, dissipated power) on the block in body state ``slider``
    (``prismatic.contact`` with the block as its ball and the ground as its socket)."""
    force, moment, _, pdiss = prismatic.contact(P, model, (*slider, (0.0, 0.0, 0.0)),
                                                (*GROUND, (0.0, 0.0, 0.0)), True, dg)
    return force, moment, pdiss

# ---------------------------------------------------------------------------
# 1. the line's law
# ---------------------------------------------------------------------------

def test_line_loads_against_quadrature_and_their_energy():
    """prismatic.line_load for both ends in contact, one end in (either), and none: the
    ends' loads against scipy's quadrature of k_l max(delta(s), 0) times the linear shape
    functions (tests/reference.py ``edge_loads``) to 1e-12, their sum the line's force
    k_l int max(delta, 0) ds, and each the derivative of the line's energy U by central
    differences (1e-7): the loads derive from one potential, so a line conserves energy."""
    kl, length = 5.5e10, 0.08
    rng = np.random.default_rng(41)
    cases = [(2e-6, 1e-6), (1e-6, -3e-6), (-2e-6, 5e-7), (1e-9, 1e-9), (-1e-6, -1e-6),
             *[tuple(v) for v in rng.uniform(-2e-6, 2e-6, (40, 2))]]
    for da, db in cases:
        fa, fb, u = prismatic.line_load(da, db, kl, length)
        qa, qb = ref_mod.edge_loads(da, db, kl, length)
        assert fa == pytest.approx(qa, rel=1e-12, abs=1e-30)
        assert fb == pytest.approx(qb, rel=1e-12, abs=1e-30)
        if da <= 0.0 and db <= 0.0:
            assert fa == fb == u == 0.0
            continue
        h = 1e-4 * max(abs(da), abs(db))
        dua = (prismatic.line_load(da + h, db, kl, length)[2]
               - prismatic.line_load(da - h, db, kl, length)[2]) / (2 * h)
        dub = (prismatic.line_load(da, db + h, kl, length)[2]
               - prismatic.line_load(da, db - h, kl, length)[2]) / (2 * h)
        if min(abs(da), abs(db)) > 2 * h:         # away from the kink at 0
            assert dua == pytest.approx(fa, rel=1e-6)
            assert dub == pytest.approx(fb, rel=1e-6)
    # continuity where an end reaches the wall
    for eps in (1e-12, 1e-15):
        lo = np.array(prismatic.line_load(2e-6, -eps, kl, length))
        hi = np.array(prismatic.line_load(2e-6, eps, kl, length))
        assert np.all(np.abs(hi - lo) <= 1e-6 * np.abs(hi) + kl * length * eps)


# ---------------------------------------------------------------------------
# 2. edge and face: closed forms, continuity
# ---------------------------------------------------------------------------

def elastic_model():
    """P with clearance alone, no damping (c_r = 1), no friction, unworn walls."""
    pk = packed_case(P_JOINTS["P"], "realistic", contact={"restitution": 1.0},
                     friction={"enabled": False})
    model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)), np.zeros((L.N_JOINTS, 36, 72)))
    return pk, model


def rolled(pk, roll, depth, v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0)):
    """The block's body state rolled by ``roll`` [rad] about its length (x), its +y face's
    middle ``depth`` [m] into the +y wall, halfway along the guide."""
    jp, p = pk.jp, pk.p
    c, s = math.cos(roll), math.sin(roll)
    R = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    b = 0.5 * jp[P, L.J_WIDTH]
    r = np.array([jp[P, L.J_X0] + 0.5 * jp[P, L.J_XSPAN], jp[P, L.J_CY] + depth + b - b * c,
                  p[L.P_ZS]])
    return tuple(r), tuple(v), tuple(R.ravel()), tuple(w)


def edge_depths(pk, model, state):
    """The +y wall's two edge lines' penetrations [m] (its -z edge, its +z edge), each the
    same at both ends (no yaw), from the kernel's geometry."""
    out = []
    for e in (0, 1):
        ka, kb = prismatic.line_slots(e)
        da = prismatic.slot_geometry(P, model, ka, state).delta
        db = prismatic.slot_geometry(P, model, kb, state).delta
        assert da == pytest.approx(db, rel=1e-9, abs=1e-18)
        out.append(da)
    return out


def test_face_and_edge_closed_forms_and_no_jump_as_the_block_rolls():
    """A block pressed 2 nm into the +y wall and rolled through the angle at which its
    second edge reaches the wall: the guide's force on it is k_l L (delta_1+ + delta_2+),
    delta_i+ its two edges' penetrations where positive: the edge alone k_l L delta_1, the
    face lying flat 2 k_l L delta (to 1e-12), and across the angle where the second edge
    comes in no jump: the force moves by its slope times the step (the corners' Hertz law
    before issue 41 item 5 gives (4/3) E* sqrt(r_c) delta^(3/2) per corner, 50 times
    less at the face's 2 nm)."""
    pk, model = elastic_model()
    jp = pk.jp
    kl = line_stiffness(jp, 1)
    length = jp[P, L.J_BLOCK_LENGTH]
    h = 0.5 * jp[P, L.J_HEIGHT]
    depth = 2e-9
    dg = np.zeros(L.N_D)
    # the second edge reaches the wall where the roll lifts it by the depth: h sin(roll) ~ depth
    critical = depth / h
    forces = []
    rolls = critical * np.linspace(0.0, 2.0, 401)
    for roll in rolls:
        state = rolled(pk, roll, depth)
        d1, d2 = edge_depths(pk, model, state)
        force, _, _ = guide_contact(model, state, dg)
        want = kl * length * (max(d1, 0.0) + max(d2, 0.0))
        assert -force[1] == pytest.approx(want, rel=1e-12)
        assert force[0] == 0.0 and force[2] == 0.0
        forces.append(-force[1])
    forces = np.array(forces)
    assert forces[0] == pytest.approx(2.0 * kl * length * depth, rel=1e-9)   # the face
    # rolled twice as far: one edge 3 x as deep, the other lifted
    assert forces[-1] == pytest.approx(kl * length * 3.0 * depth, rel=1e-3)
    # no jump: the largest step between neighbouring rolls is the slope's, k_l L h d(roll)
    steps = np.abs(np.diff(forces))
    assert steps.max() <= 1.001 * kl * length * h * (rolls[1] - rolls[0])
    # Hertz corners: four of them at the face's depth
    hertz = 4 * 4.0 / 3.0 * jp[P, L.J_EW] * math.sqrt(jp[P, L.J_CORNER_RADIUS]) * depth ** 1.5
    assert forces[0] > 20.0 * hertz


# ---------------------------------------------------------------------------
# 3. energy
# ---------------------------------------------------------------------------

def test_energy_of_the_lines_and_its_balance_from_edge_to_face():
    """The joint's elastic energy (dg[D_UEL]) is the lines' closed form k_l L delta^2 / 2 per
    edge in contact along its length (to 1e-12), and along a motion that rolls the block
    from one edge onto its face while it moves into the wall and slides along the guide
    (the line's contact ends crossing its corners), dU/dt = -(F . v + M . w) - P_diss to
    1e-6 (central differences), with and without damping and friction. The corners' Hertz
    energy (2/5) K delta^(5/2) per corner fails the first check."""
    for lossy in (False, True):
        pk = packed_case(P_JOINTS["P"], "realistic",
                         **({} if lossy else {"contact": {"restitution": 1.0},
                                              "friction": {"enabled": False}}))
        model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)),
                      np.zeros((L.N_JOINTS, 36, 72)))
        jp = pk.jp
        kl = line_stiffness(jp, 1)
        length = jp[P, L.J_BLOCK_LENGTH]
        h = 0.5 * jp[P, L.J_HEIGHT]
        dg = np.zeros(L.N_D)
        if not lossy:
            state = rolled(pk, 0.0, 3e-9)
            guide_contact(model, state, dg)
            assert dg[L.D_UEL + P] == pytest.approx(2 * kl * length * (3e-9) ** 2 / 2,
                                                    rel=1e-12)
        # the roll decreases at rate w_x while the block moves into the wall and along it
        v = np.array([0.05, 1e-6, 0.0])
        w = np.array([-2e-4, 0.0, 0.0])
        worst = 0.0
        for t in np.linspace(0.0, 0.02, 21):
            roll = 3e-6 / h + w[0] * t
            dt = 1e-5
            r0 = np.array(rolled(pk, roll, 1e-9)[0])

            def at(tt, roll=roll, t=t, r0=r0):
                st = rolled(pk, roll + w[0] * (tt - t), 0.0, v=v, w=w)
                st = (tuple(r0 + v * (tt - t)), st[1], st[2], st[3])
                dgs = np.zeros(L.N_D)
                f, m, pd = guide_contact(model, st, dgs)
                return np.array(f), np.array(m), pd, dgs[L.D_UEL + P]

            f, m, pdiss, _ = at(t)
            du = (at(t + dt)[3] - at(t - dt)[3]) / (2 * dt)
            power = float(f @ v + m @ w)
            scale = abs(power) + abs(pdiss)
            assert scale > 0.0
            if not lossy:
                assert pdiss == 0.0
            worst = max(worst, abs(du + power + pdiss) / scale)
        assert worst < 1e-6, (lossy, worst)


def test_a_run_with_impacts_on_the_walls_keeps_its_energy():
    """P alone with clearance, the block starting centred in its guide (it falls onto its
    bottom face and bounces, its edges and faces meeting the walls some 35 times), B with
    2.5e-4 m, 0.1 s: status ok, and the energy residual is RK4's error on the faces' stiff
    impacts, falling with the step: measured 8.3e-5 at dt = 1e-5 s (4 sub-step levels),
    9.6e-6 at 5e-6 s, 3.9e-6 at 2.5e-6 s (load average ~15)."""
    res = {}
    for dt in (1e-5, 5e-6):
        _, _, _, ds = run_case([*guide(1e-4), "joints.B.clearance=2.5e-4",
                                "initial.joints=centred", "solver.duration=0.1",
                                f"solver.dt={dt}"])
        assert str(ds.status.values) == "ok"
        assert int(ds.impact_count.sel(joint="P")) >= 10
        res[dt] = float(ds.energy_residual_relative)
    assert res[1e-5] < 2e-4
    assert res[5e-6] < res[1e-5] / 4.0


def test_the_corners_stiff_rate_against_a_flat_faces_modes():
    """A block lying flat, 2 nm into the +y wall, at rest: the stiff rate the joint reports
    (D_PRATE: each corner's bound k_l L / 2 at the block's mobility there, docs/physics.md
    3.7) against the face's own modes, its two edge lines (each k_l L, at z = +-h) on the
    block of mass m4 and inertia J4: translation onto the wall sqrt(2 k_l L / m4), roll about
    the guide's axis sqrt(2 k_l L h^2 / J4x), yaw sqrt(k_l L^3 / (6 J4z)). The corner's
    bound covers the translation (the realistic block's corner mobility is 6.5 / m4: 1.27
    times its rate, not the half a corner's k_l L / 2 at 1 / m4 would give) and the yaw, and
    stays within 10 % of the roll (0.906 of it). A bound four times stiffer (the face's
    2 k_l L at the corner) lowers a centred start's energy residual exactly as
    solver.stability_limit 0.5 does, at the same cost (below)."""
    pk, model = elastic_model()
    jp, p = pk.jp, pk.p
    kll = line_stiffness(jp, 1) * jp[P, L.J_BLOCK_LENGTH]          # k_l L of one edge line
    h = 0.5 * jp[P, L.J_HEIGHT]
    length = jp[P, L.J_BLOCK_LENGTH]
    dg = np.zeros(L.N_D)
    guide_contact(model, rolled(pk, 0.0, 2e-9), dg)
    rate = dg[L.D_PRATE]
    translation = math.sqrt(2.0 * kll / p[L.P_M4])
    roll = math.sqrt(2.0 * kll * h * h / p[L.P_J4])
    yaw = math.sqrt(kll * length * length / (6.0 * p[L.P_J4 + 2]))
    assert rate >= translation * 1.2
    assert rate >= yaw
    assert rate >= 0.9 * roll


def test_a_halved_stability_limit_brings_a_centred_starts_residual_to_1e_5():
    """The centred start of test_a_run_with_impacts_on_the_walls_keeps_its_energy at
    dt = 1e-5 s: its residual (8.3e-5) is RK4's error on the faces' stiff rate at
    rate x h <= 1, and solver.stability_limit 0.5 (one more sub-step level wherever a wall
    is touched) brings it below 1e-5 (measured 5.2e-6 with 1.84 times the RK4 steps;
    a corner bound of the face's 2 k_l L gave 5.2e-6 with 1.88 times, and on a seated
    block in the reliability example's design 2.0 times the steps for a residual already
    at 2e-8: docs/physics.md 3.7)."""
    out = {}
    for limit in (1.0, 0.5):
        _, _, _, ds = run_case([*guide(1e-4), "joints.B.clearance=2.5e-4",
                                "initial.joints=centred", "solver.duration=0.1",
                                "solver.dt=1e-5", f"solver.stability_limit={limit}"])
        assert str(ds.status.values) == "ok"
        out[limit] = (float(ds.energy_residual_relative), int(ds.rk4_steps))
    assert out[1.0][0] > 2e-5
    assert out[0.5][0] < 1e-5
    assert out[0.5][1] < 2.0 * out[1.0][1]


# ---------------------------------------------------------------------------
# 4. the walls' depth and the map's resolution
# ---------------------------------------------------------------------------

def wall_depth(rows, cols):
    _, pk, _, ds = run_case([*guide(1e-4, 8e-5), "mechanism.theta0=1.0", "wear.feedback=false",
                             "solver.duration=0.2", f"wear.map=[{rows}, {cols}]"])
    wmap = ds.wear_map.sel(joint="P").values
    return wmap, float(ds.wear_volume.sel(joint="P")), band_volumes(pk.jp, wmap)


def test_the_walls_depth_converges_with_the_map():
    """A seated block sliding 0.2 s: on maps of 36 x 72, 72 x 144 and 144 x 288 bins the
    walls hold the worn volume (the bands' depth times area sum to wear_volume, 1e-9), and
    the deepest bin's depth converges: 72 x 144 within 5 % of 144 x 288 and closer to it
    than 36 x 72 is (the depth is the volume over the area the faces cover, Archard's k p s,
    not a corner's point track; measured 0.9998 and 0.9987 of 144 x 288's 2.76e-11 m). Before issue 41 item 5
    the bins held a corner's track depth V / (w x length), w its Hertz width (~70 um),
    whatever the map: the bands held tens of times the worn volume."""
    depth = {}
    for rows, cols in ((36, 72), (72, 144), (144, 288)):
        wmap, volume, bands = wall_depth(rows, cols)
        assert bands.sum() == pytest.approx(volume, rel=1e-9)
        depth[rows] = wmap.max()
    assert abs(depth[72] / depth[144] - 1.0) < 0.05
    assert abs(depth[72] / depth[144] - 1.0) < abs(depth[36] / depth[144] - 1.0) + 1e-12


# ---------------------------------------------------------------------------
# 5. impacts: contact episodes of the joint
# ---------------------------------------------------------------------------

def test_an_impact_is_the_joint_going_from_no_contact_to_contact():
    """The block starting centred (no friction, no wear feedback) falls onto its bottom
    face, bounces and rattles between its walls; every step a row (dt = 2e-6 s, no
    sub-steps): P's impact count is the number of rows at which the block goes from
    touching no wall (every corner's penetration <= 0, the deepest one's
    dg[D_DELTA] <= 0) to touching one, and its contact fraction the share of steps that
    end touching one. Several corners meeting the walls at once, or one after another
    while the block still touches, are one episode: the corners' own episodes (before
    issue 41 item 5 each counted an impact) outnumber the joint's."""
    _, pk, raw, ds = run_case([*guide(1e-4), "friction.enabled=false", "initial.joints=centred",
                               "wear.feedback=false", "solver.dt=2.0e-6", "solver.save_every=1",
                               "solver.duration=0.03"])
    assert int(ds.substeps_used) == 1
    delta = raw.d[:, L.D_DELTA + P]
    touching = delta > 0.0
    onsets = int(np.sum(~touching[:-1] & touching[1:]))
    assert onsets >= 2
    assert int(ds.impact_count.sel(joint="P")) == onsets
    # the corners' own onsets, counted in the rows' slot penetrations
    from test_prismatic import slot_penetrations

    pens = np.array([slot_penetrations(y, pk.p, pk.jp) for y in raw.y])
    corner_onsets = int(np.sum((pens[:-1] <= 0.0) & (pens[1:] > 0.0)))
    assert corner_onsets > onsets
