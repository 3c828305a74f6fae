"""Joint P (the slider's block in its guide with clearance, core/prismatic.py) against
independent models.

1. The kernel's right-hand side with P's clearance (alone, with B, with A, B and O; both
   presets) against the dense reference of tests/reference.py (``block_contact``: the
   prismatic rows dropped, each wall meeting the block's face along its two long edges,
   each edge's load on its end corners integrated by scipy's quadrature of the pressure
   k_l max(delta, 0) per unit length, with damping and friction written from their
   formulas, applied at the corners through finite-difference point Jacobians), with the
   block posed so that one corner, several corners (on a y and a z wall) and diagonally
   opposite corners (on opposite walls) penetrate, counted in numpy
   (``slot_penetrations``); RTOL = 1e-7 as tests/test_reference.py's ``compare`` scales
   it. A worn wall (a depth in the map bins under an edge's corners) acts as the wider gap
   c + h there and nowhere else; the corners' stiff rate is the free block's at the corner
   with the line's stiffness bound k_l L / 2, above the constrained one.
2. The ideal mechanism's closed form (params.ideal_slider_x) with clearances of 1e-9 m: the
   faces sink ~10 nm into the walls under the load (face_sink), which moves x by the closed
   form's slope times that; walls 1e4 times stiffer: < 1e-6 relative.
3. A symmetric load and start stay symmetric to round-off; a yaw of 1e-12 rad at the start
   grows a yaw rate.
4. One edge impact and one face impact of the full kernel against scipy's integration of
   the 1-DOF model m_eff delta'' = -F_N(delta, delta'), F_N = K delta (1 + kappa delta'),
   K = k_l L for an edge, 2 k_l L for a face (tolerance 1e-3).
5. The worn volume of P, and of each wall's band of its map (its bins' depths times their
   areas), against k * sum(F_N |v_t| dt) written out from the saved states (1e-9), and the
   track's width across a wall.
6. The energy residual of a 0.1 s run and the settled statistics' change with dt halved
   (< 5e-3).
7. Bad ``joints.P`` values: one ``clearsweep: error:`` line naming the key, clearances
   beyond the rod's reach included (params.check_guide_reach).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import reference as ref_mod
from click.testing import CliRunner
from impacts import hertz_modulus_steel, kernel_impact, scipy_impact
from test_cli_errors import assert_error
from test_reference import RTOL, base_state, compare, contact_state, packed_case, perturb
from test_revolute_reference import seat_journal

from clearsweep.cli import main
from clearsweep.config import load_config, resolve_materials
from clearsweep.core import layout as L
from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
from clearsweep.core.joints import INDEX
from clearsweep.core.work import Model, Solve
from clearsweep.params import (
    PRESETS,
    Packed,
    ideal_slider_x,
    initial_state,
    pack,
    seated_offsets,
)
from clearsweep.simulation import case_dataset, prepare_kernel, run_kernel

ROOT = Path(__file__).resolve().parents[1]
A, B, O, P = INDEX["A"], INDEX["B"], INDEX["O"], INDEX["P"]
SLIDER = ref_mod.SLIDER
#: The guide's clearances of the dense checks: small enough that tilts of 1e-4..1e-3 rad
#: bring opposite corners to their walls (the block's half length is 0.04 m).
CY, CZ = 2.0e-5, 3.0e-5
CLEAR = 2.5e-4
GUIDE = {"clearance_y": CY, "clearance_z": CZ}
#: P with clearance alone, with B, and with A, B and O.
P_JOINTS = {
    "P": {"P": GUIDE},
    "PB": {"P": GUIDE, "B": {"clearance": CLEAR}},
    "PABO": {"P": GUIDE, "A": {"clearance": CLEAR}, "B": {"clearance": CLEAR},
             "O": {"clearance": CLEAR}},
}
CASES = [(j, preset) for j in P_JOINTS for preset in ("realistic", "paper")]


# ---------------------------------------------------------------------------
# 1. the right-hand side against the dense reference
# ---------------------------------------------------------------------------

def corners(jp):
    """The block's eight corners in its frame, in the kernel's order (corner index bits:
    x, y, z), and their signs."""
    half = 0.5 * np.array([jp[P, L.J_BLOCK_LENGTH], jp[P, L.J_WIDTH], jp[P, L.J_HEIGHT]])
    signs = np.array([[1.0 if c & 1 else -1.0, 1.0 if c & 2 else -1.0, 1.0 if c & 4 else -1.0]
                      for c in range(8)])
    return signs * half, signs


def slot_penetrations(y, p, jp):
    """The 16 slots' penetrations [m] (slot 2 corner + 0: its y wall, + 1: its z wall) of the
    block in state y, from the reference's rotation (R = Rz Ry Rx of the slider's angles)."""
    q = np.asarray(y[:L.N_Q], float)
    u, signs = corners(jp)
    half = np.abs(u[-1])
    centre = np.array([0.0, 0.0, p[L.P_ZS]])
    clear = (0.0, jp[P, L.J_CY], jp[P, L.J_CZ])
    out = np.empty(16)
    for c in range(8):
        pos = ref_mod.point(q, SLIDER, u[c]) - centre
        for axis in (1, 2):
            out[2 * c + axis - 1] = signs[c, axis] * pos[axis] - half[axis] - clear[axis]
    return out


#: Block poses (slider angles alpha, beta, gamma [rad]; its y and z - z_s [m]) and the slots
#: each brings into contact (slot = 2 corner + wall, corner bits x, y, z; corner 3 is
#: (+x, +y, -z)). Every penetration differs from every other by > 1e-7 m, so that the
#: deepest slot (the diagnostics') is the same one in the kernel and the reference.
POSES = {
    # yaw and roll: the corner (+x, +y, -z) alone on the +y wall, 2 um deep
    "one": ((2e-4, 0.0, 1e-4), (CY + 2e-6 - 2e-4 * 0.04 - 1e-4 * 0.03, 0.0), {6}),
    # the +y face's front edge on the +y wall (corners (+x, +y, -+z), 5 and 2 um) and the
    # corners (+x, -+y, -z) on the -z wall (4 and 1 um)
    "several": ((5e-4, 4e-4, 5e-5), (CY + 5e-6 - 5e-4 * 0.04 - 5e-5 * 0.03,
                                      -(CZ + 4e-6 - 4e-4 * 0.04 - 5e-5 * 0.03)),
                {6, 14, 3, 7}),
    # yaw past the clearance: diagonally opposite corners on opposite walls, (+x, +y, -z) on
    # the +y wall 11 um and (-x, -y, +z) on the -y wall 9 um deep
    "opposite": ((6e-4, 0.0, 2e-4), (1e-6, 0.0), {6, 8}),
    # the same, and pitch: the corner (+x, -y, -z) on the -z wall, 3 um
    "opposite_z": ((6e-4, 4e-4, 2e-4), (1e-6, -(CZ + 3e-6 - 4e-4 * 0.04 - 2e-4 * 0.03)),
                   {6, 8, 3}),
}


def pose_block(y, p, angles, offset):
    """The slider's angles and its y, z (about the guide's axis) set; the rest as it is."""
    y = np.array(y, float)
    y[L.Y_PHI4:L.Y_PHI4 + 3] = angles
    y[L.Y_R4 + 1] = offset[0]
    y[L.Y_R4 + 2] = p[L.P_ZS] + offset[1]
    return y


def block_state(y0, pk, rng, pose, velocity=(2e-3, -1e-3), rates=(2e-2, -1e-2, 3e-2),
                stand=False):
    """A drifted state (tests/test_reference.perturb) with the block posed (``POSES``), the
    journal (O with clearance) pressed into its bearing, A and B (with clearance) pressed
    into their sockets (tests/test_reference.contact_state: the rod and the slider's x
    follow), and then the slider's velocity across the guide and its angular rates [rad/s]
    set: corners approaching and receding at ~1e-3 m/s; with ``stand``, its velocity along
    the guide 0 (the corners' slip ~4e-4 m/s, in the friction ramp)."""
    p, jp = pk.p, pk.jp
    y = perturb(y0, rng)
    if jp[O, L.J_CLEARANCE] != 0.0:
        y = seat_journal(y, p, jp, rng, 2e-6, 1e-3)
    angles, offset, _ = POSES[pose]
    y = pose_block(y, p, angles, offset)
    y = contact_state(y, p, jp, rng, drift=False)
    y[L.Y_QD + L.Y_R4 + 1:L.Y_QD + L.Y_R4 + 3] = velocity
    y[L.Y_QD + L.Y_PHI4:L.Y_QD + L.Y_PHI4 + 3] = rates
    if stand:
        y[L.Y_QD + L.Y_R4] = 0.0
    return y


@pytest.mark.parametrize("joints,preset", CASES)
def test_block_in_contact(joints, preset):
    """The block pressed into its walls at one corner, several corners, and opposite corners
    (on opposite walls), with tilts of 1e-4..6e-4 rad, at four crank angles, the corners
    approaching and receding, the other clearance joints pressed into contact: every
    quantity of ``compare`` within RTOL of the reference, and the slots in contact those
    intended (counted in numpy from the reference's rotation). At t = 0 the slider
    stands (``block_state``'s ``stand``), so the deepest corner's slip lies in the friction
    ramp (4e-4 m/s); at the other angles beyond it."""
    pk = packed_case(P_JOINTS[joints], preset)
    rng = np.random.default_rng(300 + CASES.index((joints, preset)))
    results = []
    for t in (0.0, 0.13, 0.41, 0.77):
        for pose, (_, _, slots) in POSES.items():
            y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
            y = block_state(y0, pk, rng, pose, stand=t == 0.0)
            pen = slot_penetrations(y, pk.p, pk.jp)
            assert set(np.flatnonzero(pen > 0.0)) == slots, (pose, pen)
            live = np.sort(pen[pen > -1e-5])
            assert np.all(np.diff(live) > 1e-7)
            res = compare(t, y, pk)
            c = res["reference"].contacts[P]
            assert c.delta == pytest.approx(pen.max(), rel=1e-9)
            assert c.fn > 0.0 and c.ft > 0.0
            slip = np.linalg.norm(c.vt)
            assert (pk.p[L.P_V0] < slip < pk.p[L.P_V1]) == (t == 0.0), slip
            dg = res["kernel"]["dg"]
            res["fn"] = abs(dg[L.D_FN + P] - c.fn) / c.fn
            res["ft"] = abs(dg[L.D_FT + P] - c.ft) / c.fn
            results.append(res)
    worst = {key: max(res[key] for res in results)
             for key in ("qdd", "torque", "reaction_O", "joint_force", "fn", "ft")}
    for val in worst.values():
        assert val < RTOL


# ---------------------------------------------------------------------------
# runs of the kernel
# ---------------------------------------------------------------------------

def run_case(overrides, edit=None, wmap0=None):
    """The kernel's run of configs/one_clearance.yaml with B ideal unless ``overrides`` say
    otherwise, and ``overrides``; ``edit(cfg, pk)`` may change the packed case before the
    run, ``wmap0(cfg, pk)`` gives the wear map it starts from (default unworn).
    (config, packed case, raw run, results dataset)."""
    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      ["joints.B.clearance=0", *overrides])
    pk = pack(cfg, resolve_materials(cfg))
    if edit is not None:
        edit(cfg, pk)
    prepare_kernel(cfg.solver.method)
    raw = run_kernel(pk, wmap0=None if wmap0 is None else wmap0(cfg, pk))
    assert raw.status == "ok"
    return cfg, pk, raw, case_dataset(cfg, pk, raw)


def guide(c_y, c_z=None):
    return [f"joints.P.clearance_y={c_y}", f"joints.P.clearance_z={c_y if c_z is None else c_z}"]


def line_stiffness(jp, axis):
    """k_l [N/m^2] per unit length of an edge line on a wall across ``axis`` (1: a y wall,
    2: a z wall): the face (length L, width W: the block's height on a y wall, its width on
    a z wall) an elastic foundation of modulus k_f = 2 E* / sqrt(pi L W), a rigid flat punch
    of the face's area on a half-space (docs/physics.md 3.7), each edge carrying half of it:
    k_l = k_f W / 2 (jp[J_EW]: Hertz's modulus E*, tests/test_contact.py)."""
    length = jp[P, L.J_BLOCK_LENGTH]
    width = jp[P, L.J_HEIGHT] if axis == 1 else jp[P, L.J_WIDTH]
    return 2.0 * jp[P, L.J_EW] / np.sqrt(np.pi * length * width) * width / 2.0


def face_sink(jp, axis, force):
    """Penetration [m] of a face lying flat on a wall across ``axis`` under ``force`` [N]:
    both edge lines in contact along the block's length L, 2 k_l L delta = force."""
    return force / (2.0 * line_stiffness(jp, axis) * jp[P, L.J_BLOCK_LENGTH])


# ---------------------------------------------------------------------------
# 2. the ideal mechanism's closed form with clearances of 1e-9 m
# ---------------------------------------------------------------------------

#: Clearances of 1e-9 m at P (the rest ideal), the penetration stop lifted (the corners
#: sink ~1 um into the walls under the load, 1e3 clearances), the crank from 2.8 rad, where
#: the closed form's slope dx/dz_s = -(z_s + l2 cos theta) / x is near its largest (0.94).
NEAR_IDEAL = [*guide(1e-9), "contact.max_penetration_fraction=1.0e6", "mechanism.theta0=2.8",
              "solver.duration=0.05"]


def closed_form_error(pk, raw):
    """|x - x_ideal(theta)| of the rows [m], and the closed form's slopes |dx/dz_s|,
    |dx/dy| [-] there (x = sqrt(l3^2 - (y - l2 sin theta)^2 - (z_s + z + l2 cos theta)^2)
    with the block's offset (y, z) from the guide's axis)."""
    p = pk.p
    theta = p[L.P_THETA0] + p[L.P_OMEGA] * raw.t
    x_ideal = ideal_slider_x(theta, p[L.P_L2], p[L.P_L3], p[L.P_ZS])
    slope_z = np.abs(p[L.P_ZS] + p[L.P_L2] * np.cos(theta)) / x_ideal
    slope_y = np.abs(p[L.P_L2] * np.sin(theta)) / x_ideal
    return np.abs(raw.y[:, L.Y_SLIDER_X] - x_ideal), slope_z, slope_y


def test_closed_form_realistic_modulus():
    """The realistic guide: the block's bottom face sinks delta_z = F / (2 k_l L) into the -z
    wall under the guide's largest vertical force F (the slider's weight and the rod's
    push, the face lying flat: face_sink), and a side face delta_y into a y wall, which
    moves the rod's end and so x by the closed form's slope times that: |x - x_ideal| stays
    within 1.5 x (slope_z (c + delta_z) + slope_y (c + delta_y)), the largest slopes of the
    window. Measured: 1.1e-8 m (3.9e-8 relative) against the bound 4.3e-8 m; the faces sink
    ~10 nm, a hundredth of the corners' Hertz sink (1.3 um: |x - x_ideal| 1.32e-6 m before
    issue 41 item 5)."""
    _, pk, raw, ds = run_case(NEAR_IDEAL)
    err, slope_z, slope_y = closed_form_error(pk, raw)
    force = np.abs(ds.joint_force.sel(joint="P").values).max(axis=0)
    delta_y, delta_z = face_sink(pk.jp, 1, force[1]), face_sink(pk.jp, 2, force[2])
    assert 1e-9 < delta_z < 1e-7
    c = pk.jp[P, L.J_CY]
    bound = slope_z.max() * (c + delta_z) + slope_y.max() * (c + delta_y)
    assert err.max() < 1.5 * bound
    assert err.max() < 1e-7                 # the corners' law: 1.32e-6 m


def stiff_walls(cfg, pk):
    """The guide's walls 1e4 times stiffer (E*), and the seated start for them."""
    pk.jp[P, L.J_EW] *= 1e4
    pk.jp[P, L.J_EW_BASE] *= 1e4
    preset = PRESETS[cfg.mechanism.preset]
    off = seated_offsets(preset, pk.p, pk.jp, pk.p[L.P_THETA0], pk.p[L.P_OMEGA])
    pk.y0[:] = initial_state(preset, pk.p[L.P_THETA0], pk.p[L.P_OMEGA], *off)


def test_closed_form_stiff_walls():
    """E* x 1e4 (the corners sink 1e4^(-2/3) as far, ~3 nm): |x - x_ideal| / max|x| <
    1e-6 over 0.05 s. Measured: 1.4e-8. Without wear feedback: under these walls' pressure
    the corners' tracks deepen by about a micron in 0.05 s (Archard's k p s, the track's
    depth: docs/physics.md 5.7), hundreds of times the corners' sinking, which the walls'
    map would put into the step's energy (status energy_residual). The seated corners stay
    on their walls (more than half the time in contact; without feedback they need no
    impact to get there)."""
    _, pk, raw, ds = run_case([*NEAR_IDEAL, "wear.feedback=false"], stiff_walls)
    err, _, _ = closed_form_error(pk, raw)
    rel = err.max() / np.abs(raw.y[:, L.Y_SLIDER_X]).max()
    assert float(ds.contact_fraction.sel(joint="P")) > 0.5
    assert rel < 1e-6


# ---------------------------------------------------------------------------
# 3. a symmetric load and start stay symmetric
# ---------------------------------------------------------------------------

#: P with clearance, the rest ideal, the block centred at the start, no friction, no wear
#: feedback (the walls' wear under the front and rear corners differs, which tilts the block
#: by ~5e-9 rad in 0.05 s: a real asymmetry, not round-off).
SYMMETRIC = [*guide(1e-4), "friction.enabled=false", "initial.joints=centred",
             "wear.feedback=false", "solver.duration=0.05"]


def slider_angles(raw):
    """The slider's angles and angular rates of the rows (each n x 3)."""
    return (raw.y[:, L.Y_PHI4:L.Y_PHI4 + 3],
            raw.y[:, L.Y_QD + L.Y_PHI4:L.Y_QD + L.Y_PHI4 + 3])


def test_symmetric_start_stays_symmetric():
    """The block falls from the guide's centre onto its walls (corner impacts at P) and is
    pushed across by the rod at its centroid: its corners on each wall carry equal forces,
    so the three angles and their rates stay at round-off. Measured: alpha, beta and their
    rates exactly 0, gamma 3e-22 rad (the moment's sum over slots of the y and the z walls
    interleaved)."""
    _, _, raw, ds = run_case(SYMMETRIC)
    assert int(ds.impact_count.sel(joint="P")) > 5
    angles, rates = slider_angles(raw)
    assert np.abs(angles).max() < 1e-15 and np.abs(rates).max() < 1e-15


def test_asymmetric_start_tilts():
    """The same with an initial yaw of 1e-12 rad: the corners' impacts turn it into a yaw
    rate of ~7e-9 rad/s (measured 6.8e-9), so the check above can fail."""
    def yawed(cfg, pk):
        pk.y0[L.Y_PHI4] = 1e-12

    _, _, raw, _ = run_case(SYMMETRIC, yawed)
    _, rates = slider_angles(raw)
    assert np.abs(rates[:, 0]).max() > 1e-9


# ---------------------------------------------------------------------------
# 4. one edge impact and one face impact against the contact law integrated by scipy
# ---------------------------------------------------------------------------

#: No gravity, no friction, B with a 1 mm clearance (the slider flies free of the rod for the
#: test window), P with 1e-4 m, everything centred; dt = 1e-7 s (the faces' contact lasts
#: ~50 us), every step a row.
EDGE_IMPACT = [*guide(1e-4), "joints.B.clearance=1.0e-3", "mechanism.gravity=[0, 0, 0]",
               "friction.enabled=false", "initial.joints=centred", "solver.dt=1.0e-7",
               "solver.save_every=1", "solver.duration=0.0025"]
#: The block's roll [rad] and its velocity toward the +y wall [m/s]: with the roll the +y
#: face's -z edge (corners (-+x, +y, -z), slots 4 and 6) leads by 2 h gamma = 18 um and
#: meets the wall along its whole length after 1.6 ms; without it the face meets it flat.
IMPACT_ROLL, IMPACT_SPEED = 3e-4, 0.05
IMPACT_SLOT = 6


def launcher(roll):
    def launched(cfg, pk):
        pk.y0[L.Y_PHI4 + 2] = roll
        pk.y0[L.Y_QD + L.Y_R4 + 1] = IMPACT_SPEED
    return launched


@pytest.fixture(scope="module", params=["edge", "face"])
def impact_run(request):
    return request.param, run_case(EDGE_IMPACT, launcher(IMPACT_ROLL if request.param == "edge"
                                                         else 0.0))


def test_edge_and_face_impact_against_scipy(impact_run):
    """Peak normal force, peak penetration and the exit/entry velocity ratio of the first
    impact against scipy's integration of m_eff delta'' = -F_N(delta, delta'),
    F_N = K delta (1 + kappa delta'), kappa = 20 (1 - c_r) / (13 c_r delta'_0), delta'_0 the
    impact's fastest approach, from the kernel's entry velocity:

    - an edge (the block rolled: the +y face's -z edge meets the +y wall along its length):
      the line law K = k_l L, k_l = E* sqrt(W / (pi L)) with Hertz's E* = E / (2 (1 - nu^2))
      of the steel pair in closed form, the block's mass at the edge's middle along the
      wall's normal, m_eff = 1 / (1/m4 + (u x n)^T J4^-1 (u x n)) (the impact turns the
      block about x only, so the edge stays parallel to its wall);
    - a face (no roll): both edge lines of the +y face, K = 2 k_l L, and m_eff = m4.

    The kernel's F_N is its deepest corner's, a line's load on one end: the total is 2 of
    them for the edge, 4 for the face. No force acts on the block before the impact (no
    gravity, B open), so the 1-DOF model has no other term. Tolerance 1e-3 (relative): the
    edge impact turns the block by a fraction of its roll. Measured (kernel / model - 1):
    edge (m_eff 0.739 kg, peak 2,727 N) force -2.1e-6, penetration -3.0e-6, ratio +4.4e-5;
    face (2.2 kg, 6,657 N) +6.0e-7, -4.8e-6, -1.2e-5. The corners' Hertz law before issue
    41 item 5 (K delta^(3/2) at one corner) fails both by orders of magnitude.
    """
    kind, (_, pk, raw, ds) = impact_run
    assert int(ds.substeps_used) == 1          # the rows are the steps
    p, jp = pk.p, pk.jp
    dt = p[L.P_DT]
    d = raw.d
    k0, k1, v_in, kernel = kernel_impact(raw, ds, P)
    ends = 2 if kind == "edge" else 4
    # the edge's two corners (the face's four) beyond the wall, and nothing else
    for k in range(k0 - 2, k1 + 3):
        pen = slot_penetrations(raw.y[k], p, jp)
        inside = set(np.flatnonzero(pen > 0.0))
        want = {IMPACT_SLOT - 2, IMPACT_SLOT} if kind == "edge" else {4, 6, 12, 14}
        assert inside == (want if k0 <= k <= k1 else set()), (k, inside)
    assert np.all(d[:k1 + 3, L.D_DELTA + B] < 0.0)          # B open: the block flies free
    assert float(ds.first_impact_time.sel(joint="P")) == pytest.approx(raw.t[k0])
    # the block's mass at the edge's middle along the wall's normal, at the impact's start
    half = corners(jp)[0][IMPACT_SLOT // 2]
    u = np.array([0.0, half[1], half[2]])
    n_body = ref_mod.rotation(raw.y[k0 - 1, L.Y_PHI4:L.Y_PHI4 + 3]).T @ np.array([0.0, 1.0, 0.0])
    lever = np.cross(u, n_body) if kind == "edge" else np.zeros(3)
    m_eff = 1.0 / (1.0 / p[L.P_M4] + lever @ (lever / p[L.P_J4:L.P_J4 + 3]))
    # Hertz's E* of the uncoated steel pair in closed form, not the kernel's packed value
    length, width = jp[P, L.J_BLOCK_LENGTH], jp[P, L.J_HEIGHT]
    k_line = hertz_modulus_steel() * np.sqrt(width / (np.pi * length)) * length
    stiffness = k_line * (1 if kind == "edge" else 2)

    def force(x, v, kappa):
        return max(0.0, stiffness * max(x, 0.0) * (1.0 + kappa * v))

    t_out, model = scipy_impact(force, m_eff, v_in, p[L.P_CR])
    assert t_out == pytest.approx((k1 - k0 + 1) * dt, rel=5e-3)
    assert 0.5 < model["ratio"] < 0.9
    kernel["force"] *= ends
    for key, val in model.items():
        assert kernel[key] == pytest.approx(val, rel=1e-3, abs=0.0), (key, kernel[key], val)


# ---------------------------------------------------------------------------
# 5. the worn volume per wall
# ---------------------------------------------------------------------------

#: P with clearance, seated (the block rests on its -z wall and leans on a y wall, sliding
#: along the guide from the start), no wear feedback (the walls stay where they were: the
#: penetrations below need no map), the onset impact velocity, every step a row.
WEARING = [*guide(1e-4, 8e-5), "mechanism.theta0=1.0", "wear.feedback=false", "contact.impact_velocity=onset",
           "solver.save_every=1", "solver.duration=0.01"]


def slot_wear(pk, raw):
    """Archard's k F_N |v_t| dt of each slot in each row after the first (each row the end of
    one step of length dt; the wear of a step is its end's), written out in numpy from the
    saved states: each corner's position and velocity from the block's (v + R (w x u),
    w = G(phi) phi_dot the body rates of the reference's rotation), its penetration and
    approach rate against its wall, its edge line's load on it (tests/reference.py's
    ``edge_loads``: scipy's quadrature of the line's pressure k_l max(delta, 0)), F_N =
    F_el (1 + kappa delta_dot) (clamped at 0), kappa = 20 (1 - c_r) / (13 c_r delta_dot0)
    with delta_dot0 the corner's episode's onset value: max(delta_dot,
    contact.min_impact_velocity) at the first row its line loads it (the seated start's
    slots too, at the initial row), the row's own approach before the episode's value is
    booked. Returns (rows x 16 volumes [m^3], the wall of each slot)."""
    p, jp = pk.p, pk.jp
    u, signs = corners(jp)
    half = np.abs(u[-1])
    clear = (0.0, jp[P, L.J_CY], jp[P, L.J_CZ])
    centre = np.array([0.0, 0.0, p[L.P_ZS]])
    cr, floor = p[L.P_CR], p[L.P_DV0_MIN]
    walls = np.array([(0 if signs[s // 2, 1] > 0 else 1) if s % 2 == 0 else
                      (2 if signs[s // 2, 2] > 0 else 3) for s in range(16)])

    def slots(y):
        r4, phi = y[L.Y_R4:L.Y_R4 + 3], y[L.Y_PHI4:L.Y_PHI4 + 3]
        v4 = y[L.Y_QD + L.Y_R4:L.Y_QD + L.Y_R4 + 3]
        w = ref_mod.body_rate_matrix(phi) @ y[L.Y_QD + L.Y_PHI4:L.Y_QD + L.Y_PHI4 + 3]
        rot = ref_mod.rotation(phi)
        out = []
        for s in range(16):
            c, axis = s // 2, 1 + s % 2
            n = np.zeros(3)
            n[axis] = signs[c, axis]
            q = r4 + rot @ u[c] - centre
            v = v4 + rot @ np.cross(w, u[c])
            ddot = n @ v
            out.append([n @ q - half[axis] - clear[axis], ddot, np.linalg.norm(v - ddot * n)])
        # each slot's line load: its partner is the corner across the block's length (s ^ 2)
        for s in range(16):
            if s & 2:
                continue
            axis = 1 + s % 2
            fa, fb = ref_mod.edge_loads(out[s][0], out[s ^ 2][0],
                                        line_stiffness(jp, axis), 2.0 * half[0])
            out[s].append(fa)
            out[s ^ 2].append(fb)
        return out

    dv0 = np.array([max(ddot, floor) if fel > 0.0 else 0.0
                    for _, ddot, _, fel in slots(raw.y[0])])
    vol = np.zeros((len(raw.y) - 1, 16))
    for row, y in enumerate(raw.y[1:]):
        for s, (_, ddot, slip, fel) in enumerate(slots(y)):
            if fel <= 0.0:
                dv0[s] = 0.0
                continue
            kappa = 20.0 * (1.0 - cr) / (13.0 * cr * (dv0[s] if dv0[s] > 0.0 else max(ddot, floor)))
            fn = max(0.0, fel * (1.0 + kappa * ddot))
            vol[row, s] = p[L.P_AMPL] * jp[P, L.J_K] * fn * slip * p[L.P_DT]
            if dv0[s] == 0.0:
                dv0[s] = max(ddot, floor)
    return vol, walls


def band_volumes(jp, wmap):
    """Each wall's band of P's map (+y, -y, +z, -z) as a volume [m^3]: its bins' depths
    times their areas (the band's extent across the wall over its rows, the map's span along
    the guide over its columns)."""
    nrow, ncol = wmap.shape
    band = nrow // 4
    length = jp[P, L.J_XSPAN] / ncol
    out = []
    for wall in range(4):
        half = (0.5 * jp[P, L.J_HEIGHT] + jp[P, L.J_CZ] if wall < 2
                else 0.5 * jp[P, L.J_WIDTH] + jp[P, L.J_CY])
        out.append(wmap[wall * band:(wall + 1) * band].sum() * length * 2.0 * half / band)
    return np.array(out)


def test_worn_volume_and_wall_volumes():
    """A seated block (crank from 1 rad, so that the rod pushes it on a y wall as well as
    its weight on the -z wall) sliding for 0.01 s (1000 steps): P's wear_volume is k x the
    sum over rows and slots of F_N |v_t| dt (slot_wear: the edge lines' loads by scipy's
    quadrature), and each wall's band of the map holds the volume its slots wore (its bins'
    depths times their areas: the track is spread over the bins it covers, not deepened as
    a corner's point track). All to 1e-9 relative. Before issue 41 item 5 (a corner's track
    of its Hertz width, some 70 um, deepening one bin by V / (w x length)) the bands held
    the worn volume times a bin's height over that width, tens of times too much."""
    _, pk, raw, ds = run_case(WEARING)
    assert int(ds.substeps_used) == 1          # the rows are the steps
    jp = pk.jp
    vol, walls = slot_wear(pk, raw)
    total = float(ds.wear_volume.sel(joint="P"))
    assert total > 0.0 and not ds.wear_volume.sel(joint=["A", "B", "O"]).any()
    assert vol.sum() == pytest.approx(total, rel=1e-9, abs=0.0)
    bands = band_volumes(jp, ds.wear_map.sel(joint="P").values)
    per_wall = np.array([vol[:, walls == wall].sum() for wall in range(4)])
    assert bands == pytest.approx(per_wall, rel=1e-9, abs=1e-9 * total)
    assert (per_wall[:2] > 0).any() and (per_wall[2:] > 0).any()   # a y wall and a z wall


def test_track_width():
    """The track's width across a wall (prismatic.track_width): half the face's width while
    the face's other edge line touches too (the face lies on the wall); with the other line
    lifted, the strip of the face its tilt brings in, W mean / (mean - other), continuous
    with W / 2 as the other line reaches the wall; at least the rounded edge's line contact,
    2 sqrt(4 P' r_c / (pi E*)) (Johnson 4.2), P' the load per unit length; y and z walls
    take their faces' widths (block [0.08, 0.05, 0.07]: a y wall's face 70 mm, a z wall's
    50 mm)."""
    from clearsweep.core.prismatic import track_width

    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      [*guide(1e-4, 2e-4), "joints.P.block=[0.08, 0.05, 0.07]"])
    jp = pack(cfg, resolve_materials(cfg)).jp
    rc, ew = jp[P, L.J_CORNER_RADIUS], jp[P, L.J_EW]
    assert track_width(jp, P, 0, 10.0, 0.08, 1e-9, 1e-9, ew) == pytest.approx(0.035, rel=1e-15)
    assert track_width(jp, P, 3, 10.0, 0.08, 1e-9, 0.0, ew) == pytest.approx(0.025, rel=1e-15)
    # a lifted face: the tilted strip, continuous with W / 2
    assert track_width(jp, P, 2, 10.0, 0.08, 1e-8, -1e-8, ew) == pytest.approx(0.025, rel=1e-12)
    assert track_width(jp, P, 2, 10.0, 0.08, 1e-8, -1e-14, ew) == pytest.approx(0.025, rel=1e-12)
    assert track_width(jp, P, 2, 10.0, 0.08, 1e-8, -4e-8, ew) == pytest.approx(0.01, rel=1e-12)
    # steeply tilted: the line contact of the rounded edge
    line = 2.0 * np.sqrt(4.0 * 10.0 / 0.08 * rc / (np.pi * ew))
    assert track_width(jp, P, 2, 10.0, 0.08, 1e-9, -1e-3, ew) == pytest.approx(line, rel=1e-12)


# ---------------------------------------------------------------------------
# 6. the energy balance, and the step
# ---------------------------------------------------------------------------

def test_energy_and_step():
    """P and B with clearance, seated, 0.1 s: the energy residual stays within the default
    tolerance (the run's status; measured 1.1e-8 of the peak kinetic energy, against 1e-3
    of the throughput), and halving dt (1e-5 s to 5e-6 s) moves the settled slider RMS
    acceleration, P's settled contact fraction and P's worn volume by < 0.5 %. Measured:
    +1.1e-5, 0 (the block always touches a wall), +4.2e-5; the residual 6.0e-9 at dt / 2.
    The seated block never leaves its walls: no impact (a contact episode of the joint
    begins when it goes from touching no wall to touching one, docs/physics.md 3.7)."""
    out = {}
    for dt in (1e-5, 5e-6):
        _, _, _, ds = run_case([*guide(1e-4), "joints.B.clearance=2.5e-4", "solver.duration=0.1",
                                f"solver.dt={dt}"])
        assert str(ds.status.values) == "ok"
        assert float(ds.energy_residual_relative) < 1e-6
        out[dt] = np.array([float(ds.slider_acceleration_rms_settled),
                            float(ds.contact_fraction_settled.sel(joint="P")),
                            float(ds.wear_volume.sel(joint="P"))])
        assert int(ds.impact_count.sel(joint="P")) == 0 and np.all(out[dt] > 0.0)
    change = out[5e-6] / out[1e-5] - 1.0
    assert np.all(np.abs(change) < 5e-3)


# ---------------------------------------------------------------------------
# 7. bad joints.P values
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("command", ["validate", "run"])
@pytest.mark.parametrize("sets,key", [
    (["joints.P.clearance_y=-1e-4", "joints.P.clearance_z=1e-4"], "joints.P.clearance_y"),
    (["joints.P.clearance_y=1e-4"], "joints.P.clearance_z"),
    (["joints.P.clearance_z=1e-4", "joints.P.clearance_y=0"], "joints.P.clearance_y"),
    ([*guide(1e-4), "joints.P.block=[0, 0.06, 0.06]"], "joints.P.block"),
    ([*guide(1e-4), "joints.P.corner_radius=0.031"], "joints.P.corner_radius"),
    (["joints.P.corner_radius=0.031"], "joints.P.corner_radius"),
])
def test_bad_guide(tmp_path, command, sets, key):
    """Each bad value of joints.P: exit 2, one ``clearsweep: error:`` line naming the key,
    no traceback, no result file."""
    out = tmp_path / "p.nc"
    args = [command, str(ROOT / "configs" / "one_clearance.yaml")]
    for item in sets:
        args += ["--set", item]
    if command == "run":
        args += ["-o", str(out)]
    assert_error(CliRunner().invoke(main, args), 2, key)
    assert not out.exists()


# ---------------------------------------------------------------------------
# 1b. a worn wall, and the corners' stiff rate
# ---------------------------------------------------------------------------

def kernel_evaluate(t, y, pk, wmap=None):
    """One kernel right-hand side (tests/test_reference.run_evaluate) on the wear map
    ``wmap`` (N_JOINTS x 36 x 72 [m]; default unworn)."""
    s = np.zeros((L.N_JOINTS, L.N_S))
    wmap = np.zeros((L.N_JOINTS, 36, 72)) if wmap is None else wmap
    work = dict(dy=np.zeros(L.N_Y), dg=np.zeros(L.N_D), C=np.zeros((NZ, NZ)),
                S=np.zeros((NZ, NZ)), L=np.zeros((NZ, NZ)), vz=np.zeros((VZ_ROWS, NZ)))
    st = evaluate(t, np.array(y, float), Model(pk.p, pk.jp, s, wmap), work["dy"], work["dg"],
                  True, Solve(work["C"], work["S"], work["L"], work["vz"]))
    assert st == L.ST_OK
    return work


def test_worn_wall_is_a_wider_gap():
    """Wear feedback: a depth h in the +y wall's map bins under the one corner in contact (the
    "one" pose; bin found in numpy: the band of rows 0..8 of 36 across the wall, z - z_s,
    and the column along the guide, x) and under the other end of its edge line acts on
    that line as the clearance c_y + h: the accelerations, the guide's force and the
    contact values as those of the unworn map with c_y + h, and as the dense reference's
    there (``compare``); the same depth in the next bin along the guide, or in the -y
    wall's band, changes nothing."""
    pk = packed_case(P_JOINTS["P"], "realistic")
    rng = np.random.default_rng(61)
    t = 0.41
    y = block_state(base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t), pk, rng, "one")
    jp = pk.jp
    u = corners(jp)[0][IMPACT_SLOT // 2]
    q = ref_mod.point(y[:L.N_Q], SLIDER, u)
    half = 0.5 * jp[P, L.J_HEIGHT] + jp[P, L.J_CZ]
    col = int((q[0] - jp[P, L.J_X0]) / jp[P, L.J_XSPAN] * 72)
    row = int((q[2] - pk.p[L.P_ZS] + half) / (2.0 * half) * 9)
    assert 0 < col < 71 and 0 <= row < 9
    h = 1e-6
    worn = np.zeros((L.N_JOINTS, 36, 72))
    worn[P, row, col] = h
    # the line's other end, the corner (-x, +y, -z)
    q_back = ref_mod.point(y[:L.N_Q], SLIDER, corners(jp)[0][(IMPACT_SLOT - 2) // 2])
    col_back = int((q_back[0] - jp[P, L.J_X0]) / jp[P, L.J_XSPAN] * 72)
    row_back = int((q_back[2] - pk.p[L.P_ZS] + half) / (2.0 * half) * 9)
    assert col_back < col - 1
    worn[P, row_back, col_back] = h
    k = kernel_evaluate(t, y, pk, worn)
    wider = Packed(p=pk.p, jp=pk.jp.copy(), y0=pk.y0, n_steps=pk.n_steps,
                   save_every=pk.save_every, map_shape=pk.map_shape)
    wider.jp[P, L.J_CY] += h
    res = compare(t, y, wider)
    kw = res["kernel"]
    assert res["reference"].contacts[P].delta == pytest.approx(2e-6 - h, rel=1e-3)
    assert k["dg"][L.D_HWEAR + P] == h
    assert k["dg"][L.D_CEFF + P] == pytest.approx(kw["dg"][L.D_CEFF + P], rel=1e-15)
    for key in (L.D_DELTA, L.D_FN, L.D_FT, L.D_DDOT, L.D_VT):
        assert k["dg"][key + P] == pytest.approx(kw["dg"][key + P], rel=1e-9), key
    assert np.allclose(k["dy"], kw["dy"], rtol=1e-9, atol=1e-12)
    unworn = kernel_evaluate(t, y, pk)
    for other in ((P, row, col + 1), (P, 9 + row, col), (P, row, col - 1)):
        elsewhere = np.zeros((L.N_JOINTS, 36, 72))
        elsewhere[other] = h
        assert np.array_equal(kernel_evaluate(t, y, pk, elsewhere)["dy"], unworn["dy"]), other
    assert not np.allclose(unworn["dy"], k["dy"], rtol=1e-6)


def test_corner_stiff_rate():
    """The corners' stiff rate (docs/physics.md section 4), the one corner in contact
    (the "one" pose), no damping (c_r = 1), no friction, separating slowly and approaching
    at 0.05 m/s: the largest over the two corners of the loaded edge line of
    sqrt(k_l L / 2 W), k_l L / 2 the bound on dF / d delta at a corner (its row of the
    line's stiffness, k_l L / 3 + k_l L / 6) and W = 1/m4 + (u x n_b)^T J4^-1 (u x n_b) the
    free block's inverse mass at the corner (prismatic.corner_mobility), which bounds the
    mechanism's (the reference's n^T W_p n, the block tied to the rod at B) from above. The
    line's law is linear: the rate does not grow with the depth an approach reaches."""
    pk = packed_case(P_JOINTS["P"], "realistic", contact={"restitution": 1.0},
                     friction={"enabled": False})
    rng = np.random.default_rng(67)
    t = 0.2
    y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
    jp, p = pk.jp, pk.p
    stiff = 0.5 * line_stiffness(jp, 1) * jp[P, L.J_BLOCK_LENGTH]
    for ddot in (-1e-4, 0.05):
        y = block_state(y0, pk, rng, "one", velocity=(ddot, 0.0), rates=(0.0, 0.0, 0.0))
        k = kernel_evaluate(t, y, pk)
        r = ref_mod.evaluate(t, y, p, jp)
        c = r.contacts[P]
        assert c.ddot == pytest.approx(ddot, rel=1e-12)
        n_body = ref_mod.rotation(y[L.Y_PHI4:L.Y_PHI4 + 3]).T @ c.n
        rates = []
        for slot in (IMPACT_SLOT, IMPACT_SLOT - 2):        # the corners (+-x, +y, -z)
            lever = np.cross(corners(jp)[0][slot // 2], n_body)
            inv_m = 1.0 / p[L.P_M4] + lever @ (lever / p[L.P_J4:L.P_J4 + 3])
            rates.append(np.sqrt(stiff * inv_m))
        assert k["dg"][L.D_RATE] == pytest.approx(max(rates), rel=1e-12)
        assert k["dg"][L.D_PRATE] == k["dg"][L.D_RATE]
        bound = ref_mod.stiff_rates(r, P, p, jp)[0]          # the constrained m_eff
        assert bound < max(rates)


@pytest.mark.parametrize("command", ["validate", "run"])
@pytest.mark.parametrize("clearance", [0.3, 1.0])
def test_guide_beyond_the_rods_reach(tmp_path, clearance, command):
    """Clearances that let the block sit where the rod cannot reach it (here, the crank at
    theta = pi: z_s - l2 - c below the crank pin's level, 0.26 m + c against l3 = 0.38 m):
    `run` and `validate` refuse them in one line naming the key (before the check, the seated
    start took a square root of a negative number: a traceback); 0.05 m, within reach, packs."""
    out = tmp_path / "p.nc"
    args = [command, str(ROOT / "configs" / "one_clearance.yaml"), "--set", "mechanism.theta0=3.14159"]
    args += ["-o", str(out)] if command == "run" else []
    for item in guide(clearance):
        args += ["--set", item]
    assert_error(CliRunner().invoke(main, args), 2, "joints.P.clearance_y", "reach")
    assert not out.exists()
    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      [*guide(0.05), "mechanism.theta0=3.14159"])
    pk = pack(cfg, resolve_materials(cfg))         # the seated start
    assert np.all(np.isfinite(pk.y0)) and pk.y0[L.Y_R4 + 2] < pk.p[L.P_ZS] - 0.05


# ---------------------------------------------------------------------------
# review fixes: the perturbed start, dopri5's onsets, the walls' bin areas
# ---------------------------------------------------------------------------

def test_a_perturbed_start_keeps_each_corner_out_of_the_walls():
    """An ensemble member's start moves the seated block by its draw times each direction's
    clearance and keeps it, direction by direction, within max(|seated|, c): before, a limit
    on the offset's length let one direction grow while the other shrank (corners up to
    37 um into a wall, 598 N at the first step)."""
    from clearsweep.params import perturbed_block

    cy, cz = 1e-4, 2e-4
    row = np.zeros(L.N_JP)
    row[L.J_CY], row[L.J_CZ] = cy, cz
    seated = np.array([0.0, -(cy + 1e-6), -(cz + 1e-6)])
    rng = np.random.default_rng(5)
    for shift in rng.uniform(-1.0, 1.0, (200, 3)):
        d = perturbed_block(seated, shift, row)
        assert d[0] == 0.0
        assert abs(d[1]) <= cy + 1e-6 and abs(d[2]) <= cz + 1e-6
    # members of an ensemble with large offsets: no corner deeper than the seated start's
    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      [*guide(1e-4), "ensemble.members=8", "ensemble.perturb.ball_offset=1",
                       "ensemble.perturb.crank_phase_deg=60"])
    seated_pk = pack(cfg.replace(ensemble__members=1, ensemble__perturb__ball_offset=0.0,
                                 ensemble__perturb__crank_phase_deg=0.0), resolve_materials(cfg))
    sink = max(abs(seated_pk.y0[L.Y_R4 + 1]), abs(seated_pk.y0[L.Y_R4 + 2] - seated_pk.p[L.P_ZS]))
    for member in range(8):
        pk = pack(cfg.replace(ensemble__member=member), resolve_materials(cfg))
        assert abs(pk.y0[L.Y_R4 + 1]) <= max(sink, 1e-4) + 1e-15
        assert abs(pk.y0[L.Y_R4 + 2] - pk.p[L.P_ZS]) <= max(sink, 1e-4) + 1e-15


def test_dopri5_shortens_its_step_to_a_corner_that_closes_while_another_touches():
    """dopri5's onset rule reads P's 16 corner-wall gaps: the block seated on its bottom
    wall (four corners in contact, the deepest pair's penetration > 0 at both ends) moving
    across the guide into a side wall gets a shorter step; before, the joint's one
    penetration never went from <= 0 to > 0, and no onset was bracketed."""
    from clearsweep.core.dopri5 import onset_step

    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      [*guide(1e-4), "mechanism.gravity=[0, 0, -9.81]"])
    pk = pack(cfg, resolve_materials(cfg))
    y0 = np.array(pk.y0)
    y0[L.Y_R4 + 1] = 0.0                          # centred across, resting on the bottom wall
    y0[L.Y_R4 + 2] = pk.p[L.P_ZS] - (1e-4 + 1e-6)
    y1 = y0.copy()
    y1[L.Y_R4 + 1] = 1e-4 + 2e-6                  # its side corners 2 um into the +y wall
    model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)), np.zeros((L.N_JOINTS, 36, 72)))
    dg = np.zeros(L.N_D)
    h = 1e-4
    pp = pk.p.copy()
    pp[L.P_ONSET_TOL] = 1e-7
    shorter = onset_step(pp, pk.jp, dg, dg, h, model, y0, y1)
    assert 0.0 < shorter < h
    # the onset's linear estimate: 1e-4 / (1e-4 + 2e-6) of the step, half the tolerance after
    assert shorter == pytest.approx(h * 1e-4 / (1e-4 + 2e-6) + 0.5e-7, rel=1e-9)



@pytest.mark.parametrize("command", ["validate", "run"])
def test_a_map_too_small_for_the_guides_walls(tmp_path, command):
    """The guide's four walls are bands of the map's polar rows: with fewer than 4, the run
    divided by a band of 0 rows (ZeroDivisionError traceback after validate accepted it);
    now one line naming wear.map, before anything runs."""
    out = tmp_path / "p.nc"
    args = [command, str(ROOT / "configs" / "one_clearance.yaml"), "--set", "wear.map=[3,8]"]
    args += ["-o", str(out)] if command == "run" else []
    for item in guide(1e-4):
        args += ["--set", item]
    assert_error(CliRunner().invoke(main, args), 2, "wear.map", "4 polar rows")
    assert not out.exists()
