"""Joint P (the slider's block in its guide with clearance, core/prismatic.py) against
independent models.

1. The kernel's right-hand side with P's clearance (alone, with B, with A, B and O; both
   presets) against the dense reference of tests/reference.py (``block_contact``: the
   prismatic rows dropped, each corner's Hertz point-on-flat force F = (4/3) E* sqrt(r_c)
   delta^(3/2) with damping and friction written from their formulas, applied at the corner
   through finite-difference point Jacobians), with the block posed so that one corner,
   several corners (on a y and a z wall) and diagonally opposite corners (on opposite walls)
   penetrate, counted in numpy (``slot_penetrations``). Measured worst differences, scaled
   as tests/test_reference.py's ``compare`` scales them: accelerations 3.5e-11, torque
   6.7e-12, the guide's and the joints' forces 1.3e-11, P's F_N 1.1e-14 and friction force
   9.0e-15 relative (the deepest slot's); RTOL = 1e-7. A worn wall (a depth in the map bin
   under a corner) acts as the wider gap c + h there and nowhere else; the corners' stiff
   rate is the free block's at the corner (equal to 1e-12), above the constrained one.
2. The ideal mechanism's closed form (params.ideal_slider_x) with clearances of 1e-9 m: the
   realistic corners sink ~1.4 um into the walls under the load, which moves x by the
   closed form's slope times that (measured 1.32e-6 m, 4.7e-6 relative, near theta = 2.8 +
   0.3 rad where the slope is 0.94); walls 1e4 times stiffer: 1.4e-8 relative.
3. A symmetric load and start stay symmetric to round-off (the angles exactly 0 but roll,
   3e-22 rad); a yaw of 1e-12 rad at the start grows a yaw rate of 6.8e-9 rad/s.
4. One corner impact of the full kernel against scipy's integration of the 1-DOF model
   m_eff delta'' = -F_N(delta, delta'): peak force -3.2e-5, penetration -3.4e-5, velocity
   ratio +3.4e-4 relative (the block turns during the impact; tolerance 1e-3).
5. The worn volume of each wall's band of P's map, and each bin's depth, against
   k * sum(F_N |v_t| dt) written out from the saved states: 3e-13 relative (bins 6e-13).
6. The energy residual of a 0.1 s run (3.9e-8 of the peak kinetic energy) and the settled
   statistics' change with dt halved (< 5e-5).
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
    half = 0.5 * np.array([jp[P, L.J_LENGTH], jp[P, L.J_WIDTH], jp[P, L.J_HEIGHT]])
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


def corner_stiffness(jp):
    """K [N m^-1.5] of a corner's Hertz law F_el = K delta^(3/2), K = (4/3) E* sqrt(r_c)
    (jp[J_EW]: Hertz's modulus at the corners, tests/test_contact.py)."""
    return 4.0 / 3.0 * jp[P, L.J_EW] * np.sqrt(jp[P, L.J_RI])


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
    """The realistic corners: the block sinks delta_s = (F / 4K)^(2/3) ~ 1.4 um into the -z
    wall under the guide's largest vertical force F (the slider's weight and the rod's
    push; four corners share it), and ~0.1 um into a y wall, which moves the rod's end and
    so x by the closed form's slope times that: |x - x_ideal| stays within 1.5 x (slope_z
    (c + delta_z) + slope_y (c + delta_y)), the largest slopes of the window, and reaches
    half of slope_z delta_z (the compliance is there). Measured: 1.32e-6 m (4.7e-6
    relative) against slope_z delta_z = 1.32e-6 m (1.08e-6 m, 3.9e-6, with the layered
    modulus E_w that the corners took before issue 41)."""
    _, pk, raw, ds = run_case(NEAR_IDEAL)
    err, slope_z, slope_y = closed_form_error(pk, raw)
    force = np.abs(ds.joint_force.sel(joint="P").values).max(axis=0)
    k = corner_stiffness(pk.jp)
    delta_y, delta_z = (force[1:] / (4.0 * k)) ** (2.0 / 3.0)
    c = pk.jp[P, L.J_CY]
    bound = slope_z.max() * (c + delta_z) + slope_y.max() * (c + delta_y)
    assert 0.5 * slope_z.max() * delta_z < err.max() < 1.5 * bound


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
# 4. one corner impact against the contact law integrated by scipy
# ---------------------------------------------------------------------------

#: No gravity, no friction, B with a 1 mm clearance (the slider flies free of the rod for the
#: test window), P with 1e-4 m, everything centred; dt = 1e-6 s, every step a row.
CORNER_IMPACT = [*guide(1e-4), "joints.B.clearance=1.0e-3", "mechanism.gravity=[0, 0, 0]",
                 "friction.enabled=false", "initial.joints=centred", "solver.dt=1.0e-6",
                 "solver.save_every=1", "solver.duration=0.003"]
#: The block's yaw and roll [rad] and its velocity toward the +y wall [m/s]: the corner
#: (+x, +y, -z) (slot 6) leads by 2 h gamma = 18 um and meets the wall after 1.4 ms.
IMPACT_YAW, IMPACT_ROLL, IMPACT_SPEED = 5e-4, 3e-4, 0.05
IMPACT_SLOT = 6


def launched(cfg, pk):
    pk.y0[L.Y_PHI4] = IMPACT_YAW
    pk.y0[L.Y_PHI4 + 2] = IMPACT_ROLL
    pk.y0[L.Y_QD + L.Y_R4 + 1] = IMPACT_SPEED


@pytest.fixture(scope="module")
def impact_run():
    return run_case(CORNER_IMPACT, launched)


def test_corner_impact_against_scipy(impact_run):
    """Peak normal force, peak penetration and the exit/entry velocity ratio of the first
    corner impact against scipy's integration of m_eff delta'' = -F_N(delta, delta'),
    F_N = K delta^(3/2) (1 + kappa delta'), K = (4/3) E* sqrt(r_c) with Hertz's modulus
    E* = E / (2 (1 - nu^2)) of the steel pair, kappa = 20 (1 - c_r) /
    (13 c_r delta'_0), delta'_0 the impact's fastest approach, and m_eff = 1 / (1/m4 +
    (u x n)^T J4^-1 (u x n)) the free block's mass at the corner u along the wall's normal n
    (body frame), from the kernel's entry velocity. No force acts on the block before the
    impact (no gravity, B open), so the 1-DOF model has no other term.

    Tolerance 1e-3 (relative). The 1-DOF model holds the block's orientation fixed and
    leaves out its angular velocity's square terms: the impact (impulse m_eff v (1 + e) =
    0.029 N s on the lever |u x n| = 0.05 m, J4 = 1e-3 kg m^2) spins the block up to
    1.4 rad/s and turns it by ~0.35 mrad while the corner is in contact (0.54 ms), which
    changes the lever u x n, and so m_eff, by that order; the centripetal part
    |w|^2 |u| = 0.12 m/s^2 against a peak deceleration of 330 m/s^2 is 4e-4 of it. RK4 at
    rate x dt ~ 0.01 and the row-sampled peaks (dt / T = 2e-3: < 1e-5 low) stay well below
    that. Measured (kernel / model - 1): peak force -3.2e-5, peak penetration -3.4e-5,
    velocity ratio +3.4e-4 (0.6920 against 0.6918). A stiffness off by 1 % (0.4 % in the
    peak force) or the mass at the corner taken as the centroid's (m4 = 2.2 kg, not m_eff
    = 0.339 kg) fails.
    """
    _, pk, raw, ds = impact_run
    assert int(ds.substeps_used) == 1          # the rows are the steps
    p, jp = pk.p, pk.jp
    dt = p[L.P_DT]
    d = raw.d
    k0, k1, v_in, kernel = kernel_impact(raw, ds, P)
    # one slot, the corner (+x, +y, -z) on the +y wall, and nothing else in contact
    for k in range(k0 - 2, k1 + 3):
        pen = slot_penetrations(raw.y[k], p, jp)
        assert set(np.flatnonzero(pen > 0.0)) == ({IMPACT_SLOT} if k0 <= k <= k1 else set())
    assert np.all(d[:k1 + 3, L.D_DELTA + B] < 0.0)          # B open: the block flies free
    assert float(ds.first_impact_time.sel(joint="P")) == pytest.approx(raw.t[k0])
    # the block's mass at the corner along the wall's normal, at the impact's start
    u = corners(jp)[0][IMPACT_SLOT // 2]
    n_body = ref_mod.rotation(raw.y[k0 - 1, L.Y_PHI4:L.Y_PHI4 + 3]).T @ np.array([0.0, 1.0, 0.0])
    lever = np.cross(u, n_body)
    m_eff = 1.0 / (1.0 / p[L.P_M4] + lever @ (lever / p[L.P_J4:L.P_J4 + 3]))
    # Hertz's E* of the uncoated steel pair in closed form, not the kernel's packed value
    # (which held the paper's layered modulus, 1.346 times stiffer, before issue 41)
    k_hertz = 4.0 / 3.0 * hertz_modulus_steel() * np.sqrt(jp[P, L.J_RI])

    def force(x, v, kappa):
        return max(0.0, k_hertz * max(x, 0.0) ** 1.5 * (1.0 + kappa * v))

    # nothing else acting, the impact's fastest approach is its entry velocity
    t_out, model = scipy_impact(force, m_eff, v_in, p[L.P_CR])
    assert t_out == pytest.approx((k1 - k0 + 1) * dt, rel=5e-3)
    assert 0.5 < model["ratio"] < 0.9
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
    approach rate against its wall, F_N = K delta^(3/2) (1 + kappa delta_dot) (clamped at
    0), kappa = 20 (1 - c_r) / (13 c_r delta_dot0) with delta_dot0 the slot's episode's
    onset value: max(delta_dot, contact.min_impact_velocity) at the first row in contact
    (the seated start's slots too, at the initial row), the row's own approach before the
    episode's value is booked. Returns (rows x 16 volumes [m^3], the wall of each slot,
    rows x 16 x 3: the corner's x, its position across its wall (z - z_s on a y wall,
    y on a z wall) and its penetration [m])."""
    p, jp = pk.p, pk.jp
    u, signs = corners(jp)
    half = np.abs(u[-1])
    clear = (0.0, jp[P, L.J_CY], jp[P, L.J_CZ])
    centre = np.array([0.0, 0.0, p[L.P_ZS]])
    k_hertz = corner_stiffness(jp)
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
            out.append((n @ q - half[axis] - clear[axis], ddot,
                        np.linalg.norm(v - ddot * n), q[0], q[3 - axis]))
        return out

    dv0 = np.array([max(ddot, floor) if delta > 0.0 else 0.0
                    for delta, ddot, *_ in slots(raw.y[0])])
    vol = np.zeros((len(raw.y) - 1, 16))
    where = np.zeros((len(raw.y) - 1, 16, 3))
    for row, y in enumerate(raw.y[1:]):
        for s, (delta, ddot, slip, x, across) in enumerate(slots(y)):
            where[row, s] = x, across, delta
            if delta <= 0.0:
                dv0[s] = 0.0
                continue
            kappa = 20.0 * (1.0 - cr) / (13.0 * cr * (dv0[s] if dv0[s] > 0.0 else max(ddot, floor)))
            fn = max(0.0, k_hertz * delta ** 1.5 * (1.0 + kappa * ddot))
            vol[row, s] = p[L.P_AMPL] * jp[P, L.J_K] * fn * slip * p[L.P_DT]
            if dv0[s] == 0.0:
                dv0[s] = max(ddot, floor)
    return vol, walls, where


def test_worn_volume_and_track_depth_per_wall():
    """A seated block (crank from 1 rad, so that the rod pushes it on a y wall as well as
    its weight on the -z wall) sliding for 0.01 s (1000 steps): P's wear_volume is k x the
    sum over rows and slots of F_N |v_t| dt (slot_wear), and each bin of a wall's band
    holds the depth of the corners' track over it: the volume of the steps whose corner lay
    over it (the bin found in numpy from the corner's x and its position across the wall),
    each over its track's width w = 2 sqrt(r_c delta) (the Hertz patch; narrower here than
    a bin across the wall, so the bin's height plays no part) and the bin's length along
    the guide; per wall, sum(depth) x length = the sum of V / w over the wall's slots. All
    to 1e-9 relative (bins: of the deepest). Both sides add the same float64 products in
    other orders and from corner positions rounded differently (~1e-17 m against
    penetrations of ~1 um: ~1e-11 in F_N). A depth of volume over bin area (the map before
    its depth was the track's) fails the bins by a factor of the bin's height over w."""
    _, pk, raw, ds = run_case(WEARING)
    assert int(ds.substeps_used) == 1          # the rows are the steps
    jp = pk.jp
    vol, walls, where = slot_wear(pk, raw)
    wmap = ds.wear_map.sel(joint="P").values
    nrow, ncol = wmap.shape
    band = nrow // 4
    length = jp[P, L.J_XSPAN] / ncol
    expected = np.zeros_like(wmap)
    total = float(ds.wear_volume.sel(joint="P"))
    assert total > 0.0 and not ds.wear_volume.sel(joint=["A", "B", "O"]).any()
    worst = 0.0
    for wall in range(4):
        half = (0.5 * jp[P, L.J_HEIGHT] + jp[P, L.J_CZ] if wall < 2
                else 0.5 * jp[P, L.J_WIDTH] + jp[P, L.J_CY])
        on_map = wmap[wall * band:(wall + 1) * band].sum() * length
        line = 0.0
        # each step's volume deepens the bin under its corner by volume / (w x length)
        for step, s in zip(*np.nonzero(vol * (walls == wall))):
            x, across, delta = where[step, s]
            width = 2.0 * np.sqrt(jp[P, L.J_RI] * delta)
            assert width < 2.0 * half / band
            line += vol[step, s] / width
            col = int(np.floor((x - jp[P, L.J_X0]) / jp[P, L.J_XSPAN] * ncol))
            # a corner sunk into the other wall lies just beyond this one's edge: its end bin
            row = min(max(int(np.floor((across + half) / (2.0 * half) * band)), 0), band - 1)
            assert 0 < col < ncol - 1
            expected[wall * band + row, col] += vol[step, s] / width / length
        if line == 0.0:
            assert on_map == 0.0
        else:
            worst = max(worst, abs(on_map / line - 1.0))
    bins = np.abs(wmap - expected).max() / wmap.max()
    assert bins < 1e-9
    assert worst < 1e-9
    worn = {wall for wall in range(4) if vol[:, walls == wall].any()}
    assert worn & {0, 1} and worn & {2, 3}       # a y wall and a z wall
    assert vol.sum() == pytest.approx(total, rel=1e-9, abs=0.0)


def test_a_track_wider_than_a_bin_spreads_over_the_bin():
    """The track's width is the Hertz patch 2 sqrt(r_c delta) while it fits in a bin across
    the wall, and the bin's extent once the patch would cover more (a 4-row map: one bin
    across each wall, 70.4 mm on this block's y walls; a patch 126 mm wide), so a step's depth is never more than its
    volume over the bin's area; a y wall and a z wall have their own extents."""
    from clearsweep.core.prismatic import track_width

    cfg = load_config(str(ROOT / "configs" / "one_clearance.yaml"),
                      [*guide(1e-4, 2e-4), "joints.P.block=[0.08, 0.05, 0.07]"])
    jp = pack(cfg, resolve_materials(cfg)).jp
    rc = jp[P, L.J_RI]
    height = jp[P, L.J_HEIGHT] + 2 * jp[P, L.J_CZ]      # a y wall's extent across
    width = jp[P, L.J_WIDTH] + 2 * jp[P, L.J_CY]        # a z wall's
    assert track_width(jp, P, 0, 1e-6, 144) == pytest.approx(2 * np.sqrt(rc * 1e-6), rel=1e-15)
    assert track_width(jp, P, 3, 1e-6, 144) == pytest.approx(2 * np.sqrt(rc * 1e-6), rel=1e-15)
    assert track_width(jp, P, 1, 4.0, 4) == pytest.approx(height, rel=1e-15)
    assert track_width(jp, P, 2, 4.0, 4) == pytest.approx(width, rel=1e-15)
    assert track_width(jp, P, 2, 4.0, 36) == pytest.approx(width / 9, rel=1e-15)


# ---------------------------------------------------------------------------
# 6. the energy balance, and the step
# ---------------------------------------------------------------------------

def test_energy_and_step():
    """P and B with clearance, seated, 0.1 s: the energy residual stays within the default
    tolerance (the run's status; measured 3.9e-8 of the peak kinetic energy, against 1e-3
    of the throughput), and halving dt (1e-5 s to 5e-6 s) moves the settled slider RMS
    acceleration, P's settled contact fraction and P's worn volume by < 0.5 %. Measured:
    +4.9e-6, 0 (the block always touches a wall), -4.7e-5; 48 corner impacts in both, the
    residual 3.7e-8 at dt / 2."""
    out = {}
    for dt in (1e-5, 5e-6):
        _, _, _, ds = run_case([*guide(1e-4), "joints.B.clearance=2.5e-4", "solver.duration=0.1",
                                f"solver.dt={dt}"])
        assert str(ds.status.values) == "ok"
        assert float(ds.energy_residual_relative) < 1e-6
        out[dt] = np.array([float(ds.slider_acceleration_rms_settled),
                            float(ds.contact_fraction_settled.sel(joint="P")),
                            float(ds.wear_volume.sel(joint="P"))])
        assert int(ds.impact_count.sel(joint="P")) > 10 and np.all(out[dt] > 0.0)
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
    """Wear feedback: a depth h in the +y wall's map bin under the one corner in contact (the
    "one" pose; bin found in numpy: the band of rows 0..8 of 36 across the wall, z - z_s,
    and the column along the guide, x) acts on that corner as the clearance c_y + h: the
    accelerations, the guide's force and the contact values as those of the unworn map with
    c_y + h, and as the dense reference's there (``compare``); the same depth in the next
    bin along the guide, or in the -y wall's band, changes nothing."""
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
    (the "one" pose), no damping (c_r = 1), no friction: separating slowly, sqrt(dF/d delta
    W) with dF/d delta = (3/2) K delta^(1/2) and W = 1/m4 + (u x n_b)^T J4^-1 (u x n_b) the
    free block's inverse mass at the corner (prismatic.corner_mobility), which bounds the
    mechanism's (the reference's n^T W_p n, the block tied to the rod at B) from above;
    approaching at 0.05 m/s, the rate at the penetration the approach reaches by energy,
    K delta_p^(5/2) / (5/2) = K delta^(5/2) / (5/2) + m_eff delta_dot^2 / 2."""
    pk = packed_case(P_JOINTS["P"], "realistic", contact={"restitution": 1.0},
                     friction={"enabled": False})
    rng = np.random.default_rng(67)
    t = 0.2
    y0 = base_state(pk, pk.p[L.P_THETA0] + pk.p[L.P_OMEGA] * t)
    jp, p = pk.jp, pk.p
    k_hertz = corner_stiffness(jp)
    u = corners(jp)[0][IMPACT_SLOT // 2]
    for ddot in (-1e-4, 0.05):
        y = block_state(y0, pk, rng, "one", velocity=(ddot, 0.0), rates=(0.0, 0.0, 0.0))
        k = kernel_evaluate(t, y, pk)
        r = ref_mod.evaluate(t, y, p, jp)
        c = r.contacts[P]
        assert c.ddot == pytest.approx(ddot, rel=1e-12)
        n_body = ref_mod.rotation(y[L.Y_PHI4:L.Y_PHI4 + 3]).T @ c.n
        lever = np.cross(u, n_body)
        inv_m = 1.0 / p[L.P_M4] + lever @ (lever / p[L.P_J4:L.P_J4 + 3])
        bound = ref_mod.stiff_rates(r, P, p, jp)[0]          # the constrained m_eff
        delta = c.delta
        if ddot > 0.0:
            delta = (delta ** 2.5 + 1.25 * ddot ** 2 / (inv_m * k_hertz)) ** 0.4
            assert delta > 3.0 * c.delta
        rate = np.sqrt(1.5 * k_hertz * np.sqrt(delta) * inv_m)
        assert k["dg"][L.D_RATE] == pytest.approx(rate, rel=1e-12)
        assert k["dg"][L.D_PRATE] == k["dg"][L.D_RATE]
        if ddot < 0.0:
            assert bound < rate


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
