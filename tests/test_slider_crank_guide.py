"""The planar slider-crank's guide P with clearance (issue 44, item 1: "the slider's guide is
ideal or has clearance, the translational type, in the plane"; docs/mechanisms.md).

The prismatic type (core/prismatic.py, written for the RSSP's guide along x) evaluated in the
slider-crank's guide frame (``prismatic.PLANAR_GUIDE``: x' = y, y' = -x, z' = z), the block
free across its guide in the plane (z4) and tilting in it (gamma4, about x), its x4, alpha4
and beta4 held by Baumgarte rows (``dynamics.planar_slider``):

1. the kernel's right-hand side against the dense reference (tests/reference.py, its block
   contact written in the guide's frame and the plane's rows on the free block) with the
   block pressed into its upper or lower wall, tilted, with P alone and with B's clearance;
2. clearances of 1e-9 m at P: the slider on the closed form within the offset that the
   block's face sinking into its wall under the guide's load gives;
3. a 0.1 mm guide over three revolutions at 5000 r/min: impacts, the block in the plane to
   the bit, tilting in it, the upper and lower walls worn and the side walls not, the energy
   balance, the Poincare sections' offsets;
4. the seated start, the ensemble's offsets, the sink warning in the guide's frame;
5. ``clearsweep run`` + ``report`` + ``plot --kind wear-map`` of P on a shipped-like config.

The refusals that remain are rows of tests/test_hostile.py (ISSUE44_GUIDE).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import reference as ref_mod
from click.testing import CliRunner
from test_reference import RTOL, compare, contact_state, perturb
from test_slider_crank import OMEGA, PERIOD, PRESET, SLIDER_CRANK, closed_form, run

from clearsweep.cli import main
from clearsweep.config import load_config, resolve_materials
from clearsweep.core import jointset
from clearsweep.core import layout as L
from clearsweep.core.joints import INDEX
from clearsweep.params import (
    build_of,
    hertz_sink_warnings,
    initial_state,
    joint_set,
    pack,
    seated_offsets,
)

ROOT = Path(__file__).resolve().parents[1]
B, P = INDEX["B"], INDEX["P"]
#: The guide's clearances: 0.1 mm in the plane (above and below the block), 0.2 mm to the
#: side walls across it (which the block held in the plane never reaches).
CZ, CY = 1.0e-4, 2.0e-4
GUIDE = {"clearance_y": CY, "clearance_z": CZ}
#: The benchmark's solver settings (configs/slider_crank.yaml).
SOLVER = {"dt": 2.5e-6, "save_every": 4, "baumgarte": [50.0, 50.0]}


def sc_packed(joints, **sections):
    """The packed slider-crank case (5000 r/min) with ``joints``."""
    cfg = {"mechanism": SLIDER_CRANK, "joints": joints,
           "contact": {"min_impact_velocity": 1.0e-2}, **sections}
    cfg = load_config(cfg)
    return pack(cfg, resolve_materials(cfg))


# ---------------------------------------------------------------------------
# 1. the right-hand side against the dense reference
# ---------------------------------------------------------------------------

def test_the_guide_frame_is_a_rotation_taking_y_to_x():
    """``prismatic.PLANAR_GUIDE`` is Q = Rz(-90 deg) (a proper rotation taking the
    slider-crank's guide, global y, to the type's x; x to -y'); ``in_guide`` gives the block
    state (Q r, Q v, Q R Q^T, Q w) for any rotation R (against numpy), and ``from_guide``
    undoes ``to_guide``."""
    from clearsweep.core import prismatic
    from clearsweep.core.kinematics import rotation, trig

    q = np.array(prismatic.PLANAR_GUIDE).reshape(3, 3)
    np.testing.assert_array_equal(q @ q.T, np.eye(3))
    assert np.linalg.det(q) == 1.0
    np.testing.assert_array_equal(q @ [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(q @ [1.0, 0.0, 0.0], [0.0, -1.0, 0.0])
    rng = np.random.default_rng(44)
    for _ in range(5):
        r, v, w = rng.standard_normal((3, 3))
        R = rotation(trig(*rng.uniform(-3.0, 3.0, 3)))
        rq, vq, Rq, wq = prismatic.in_guide((tuple(r), tuple(v), R, tuple(w)))
        np.testing.assert_array_equal(rq, q @ r)
        np.testing.assert_array_equal(vq, q @ v)
        np.testing.assert_array_equal(wq, q @ w)
        np.testing.assert_allclose(np.array(Rq).reshape(3, 3),
                                   q @ np.array(R).reshape(3, 3) @ q.T, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(prismatic.from_guide(prismatic.to_guide(tuple(r))), r)


def corner_heights(y, p, jp):
    """z - z_s [m] of the block's eight corners (its length along y, its height along z at
    zero rotation: the guide's frame), from the reference's rotation."""
    q = np.asarray(y[:L.N_Q], float)
    half = 0.5 * np.array([jp[P, L.J_BLOCK_LENGTH], jp[P, L.J_WIDTH], jp[P, L.J_HEIGHT]])
    basis = ref_mod.Mechanism(p, jp).guide_basis
    out = []
    for c in range(8):
        signs = np.array([1.0 if c & bit else -1.0 for bit in (1, 2, 4)])
        out.append(ref_mod.point(q, ref_mod.SLIDER, basis @ (signs * half))[2] - p[L.P_ZS])
    return np.array(out)


def pose_block(y, p, jp, gamma, wall, depth):
    """The block tilted by gamma [rad] about x and moved across its guide so that its deepest
    corner on wall ``wall`` (+1 the upper, -1 the lower) is ``depth`` [m] beyond it."""
    y = np.array(y, float)
    y[L.Y_PHI4 + 2] = gamma
    y[L.Y_R4 + 2] = p[L.P_ZS]
    z = corner_heights(y, p, jp)
    reach = (z.max() if wall > 0 else -z.min()) - 0.5 * jp[P, L.J_HEIGHT]
    y[L.Y_R4 + 2] += wall * (jp[P, L.J_CZ] + depth - reach)
    return y


#: (tilt gamma4 [rad], wall, the deepest corner's depth [m]): a corner's edge end, the face
#: flat on its wall (both edge lines along their length), and the other wall.
POSES = [(3e-4, -1, 2e-6), (0.0, -1, 1e-6), (-2e-4, 1, 3e-6)]


@pytest.mark.parametrize("joints", ["P", "PB"])
def test_block_in_contact_against_reference(joints):
    """The block pressed into its lower or upper wall, tilted or flat, at three crank
    angles, its corners approaching and sliding (the slider's velocity along the guide, a
    rate across it and a tilting rate), the state drifted off the plane by ~1e-7 (which the
    Baumgarte rows of both hold): every quantity of ``tests/test_reference.compare`` within
    RTOL of the dense KKT solve, P's force and contact normal in global axes."""
    spec = {"P": GUIDE} if joints == "P" else {"P": GUIDE, "B": {"clearance": 2.5e-4}}
    pk = sc_packed(spec)
    p, jp = pk.p, pk.jp
    rng = np.random.default_rng(440 + len(joints))
    worst = 0.0
    for t in (0.0, 0.0031, 0.0077):
        for gamma, wall, depth in POSES:
            y = perturb(initial_state(PRESET, p[L.P_THETA0] + OMEGA * t, OMEGA), rng)
            y = pose_block(y, p, jp, gamma, wall, depth)
            y = contact_state(y, p, jp, rng, drift=False)
            y[L.Y_QD + L.Y_R4 + 2] = -wall * 2e-3            # approaching its wall
            y[L.Y_QD + L.Y_PHI4 + 2] = 3e-2
            res = compare(t, y, pk, speed=30.0)
            c = res["reference"].contacts[P]
            assert c.fn > 0.0 and c.delta > 0.0
            # the upper or lower wall's normal, in the plane
            n = res["kernel"]["dg"][L.D_NGLOBAL + 3 * P:L.D_NGLOBAL + 3 * P + 3]
            np.testing.assert_array_equal(n, [0.0, 0.0, wall])
            worst = max(worst, res["qdd"], res["joint_force"])
    assert worst < RTOL


# ---------------------------------------------------------------------------
# 2. 1e-9 m at P: the closed form within the face's sink
# ---------------------------------------------------------------------------

def test_near_ideal_guide_follows_the_closed_form():
    """P at 1e-9 m (the penetration stop lifted), seated, one revolution at 5000 r/min: the
    block rides on its wall, its face sunk delta_z = F / (2 k_l L) (``params.face_sink``)
    under the guide's largest force across it, and the slider's position along its guide
    leaves the closed form by its slope ds/dz = |z_s + l2 cos theta| / w times that offset:
    |s - s_ideal| < 1.5 max(slope) (c + delta_z). The block stays in the plane (x4, alpha4,
    beta4 exactly 0). Measured: 4.0e-8 m against the bound 8.6e-8 m; the face sinks 1.24e-7 m
    under 1.10 kN, the block's offset across the guide 1.25e-7 m."""
    from clearsweep.params import face_sink

    cfg, pk, raw, ds = run({"joints": {"P": {"clearance_y": 1e-9, "clearance_z": 1e-9}},
                            "contact": {"max_penetration_fraction": 1.0e6},
                            "solver": {**SOLVER, "duration": PERIOD}})
    assert str(ds.status.values) == "ok"
    theta = ds.crank_angle.values
    s_ideal = closed_form(theta)[0]
    err = np.abs(ds.slider_position.values - s_ideal)
    w = s_ideal - PRESET.crank_length_m * np.sin(theta)
    slope = np.abs(PRESET.slider_height_m + PRESET.crank_length_m * np.cos(theta)) / w
    force = float(np.abs(ds.joint_force.sel(joint="P", axis="z")).max())
    delta = face_sink(force, pk.jp[P], 2)
    assert 1e-10 < delta < 1e-6
    assert err.max() < 1.5 * slope.max() * (1e-9 + delta), (err.max(), delta)
    held = raw.y[:, [L.Y_R4, L.Y_PHI4, L.Y_PHI4 + 1]]
    assert np.abs(held).max() == 0.0
    # the offset across the guide: its sink, no more
    assert np.abs(raw.y[:, L.Y_R4 + 2] - PRESET.slider_height_m).max() < 1.5 * (1e-9 + delta)


# ---------------------------------------------------------------------------
# 3. a 0.1 mm guide over three revolutions
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def guide_run():
    """P at 0.1 mm (0.2 mm to the side walls), the rest ideal, seated, three revolutions at
    5000 r/min with the benchmark's step, wear fed back."""
    return run({"joints": {"P": GUIDE}, "solver": {**SOLVER, "revolutions": 3}})


def test_guide_clearance_runs_in_the_plane(guide_run):
    """The run ends ok with impacts at P; the block's out-of-plane coordinates (x4, alpha4,
    beta4) and their rates stay exactly 0 (nothing pushes them: the Baumgarte rows hold
    round-off at 0), while it moves across its guide within c plus its corners' sink and
    tilts about x. Its force and offset across the plane are 0; the offset's side
    component (the guide frame's y' = -x) too. Measured: 104 impacts, in contact 46 % of
    the time, tilt up to 5.6e-4 rad, |z4 - z_s| up to 1.04e-4 m, the constraint violation
    9.8e-10 m."""
    cfg, pk, raw, ds = guide_run
    assert str(ds.status.values) == "ok"
    assert int(ds.impact_count.sel(joint="P")) > 0
    y = raw.y
    for k in (L.Y_R4, L.Y_PHI4, L.Y_PHI4 + 1):
        assert np.abs(y[:, k]).max() == 0.0 and np.abs(y[:, L.Y_QD + k]).max() == 0.0
    tilt = np.abs(y[:, L.Y_PHI4 + 2]).max()
    assert 1e-5 < tilt < 2.0 * CZ / (0.5 * pk.jp[P, L.J_BLOCK_LENGTH])
    across = np.abs(y[:, L.Y_R4 + 2] - PRESET.slider_height_m).max()
    assert 0.5 * CZ < across < CZ + 1e-5
    assert np.abs(ds.joint_force.sel(joint="P", axis="x")).max() == 0.0
    assert np.abs(ds.ball_offset.sel(joint="P", axis="y")).max() == 0.0
    np.testing.assert_array_equal(ds.ball_offset.sel(joint="P", axis="z"),
                                  y[:, L.Y_R4 + 2] - PRESET.slider_height_m)
    assert float(ds.constraint_violation.max()) < 1e-8


def test_the_upper_and_lower_walls_wear(guide_run):
    """The walls' maps (prismatic: four bands of the map's rows, +y', -y', +z, -z): the
    block wears the upper and lower walls (bands 3 and 4), never the side walls across the
    plane; the bands' volume is the joint's worn volume."""
    cfg, pk, raw, ds = guide_run
    wmap = ds.wear_map.sel(joint="P").values
    band = wmap.shape[0] // 4
    assert np.abs(wmap[:2 * band]).max() == 0.0
    assert wmap[2 * band:].max() > 0.0
    area = (pk.jp[P, L.J_XSPAN] / wmap.shape[1]) * np.array(
        [2 * (0.5 * pk.jp[P, L.J_WIDTH] + pk.jp[P, L.J_CY]) / band])
    assert float(wmap[2 * band:].sum() * area[0]) == pytest.approx(
        float(ds.wear_volume.sel(joint="P")), rel=1e-9)


def test_energy_balance(guide_run):
    """The drive's work less the dissipated energy is the change of the kinetic, potential
    and the lines' elastic energy: the residual within 1e-4 of the peak kinetic energy at the
    benchmark's step and at half of it, and the energy that the guide's impacts and friction
    dissipate over the three revolutions the same at both within 1 % (the books close on
    the same physics, whatever the step's error on each impact). Measured: residual 3.4e-5
    at 2.5e-6 s, 4.7e-6 at 1.25e-6 s (1.3e-5 at 5e-6 s: RK4's error on the edge lines'
    stiff impacts, as the RSSP's guide, tests/test_prismatic_faces.py); dissipated 4.375 and
    4.371 J."""
    _, _, _, ds = guide_run
    _, _, _, fine = run({"joints": {"P": GUIDE},
                         "solver": {**SOLVER, "dt": 1.25e-6, "save_every": 8, "revolutions": 3}})
    for case in (ds, fine):
        assert str(case.status.values) == "ok"
        assert float(case.energy_residual_relative) < 1e-4
    dissipated = float(ds.energy_dissipated[-1]), float(fine.energy_dissipated[-1])
    assert dissipated[0] > 1.0
    assert dissipated[1] == pytest.approx(dissipated[0], rel=1e-2)


def test_poincare_offsets_in_the_guide_frame(guide_run):
    """Each revolution's section holds P's offset over its clearances in the guide's frame:
    along the guide 0, to the side (across the plane) 0, up (z) within the clearance and its
    sink. Measured: 1.0001-1.0002 at the three sections (the block on its upper wall)."""
    _, _, _, ds = guide_run
    off = ds.poincare_offset.sel(joint="P")
    assert off.sizes["revolution"] >= 2
    np.testing.assert_array_equal(off.sel(axis="x"), 0.0)
    np.testing.assert_array_equal(off.sel(axis="y"), 0.0)
    up = off.sel(axis="z").values
    assert np.all(np.isfinite(up)) and np.abs(up).max() < 1.2 and np.abs(up).max() > 0.1


def test_dopri5_runs_the_guide_in_the_plane(guide_run):
    """``solver.method: dopri5`` (its onset location reads the corners' penetrations through
    ``jointkinds.type_body``, in the guide's frame): one revolution ends ok with impacts at
    P, the block in the plane exactly, its offset across the guide within the clearance and
    its corners' sink, and its slider acceleration's peak within 2 % of RK4's over the same
    revolution (the two place the impacts' instants differently; the motion is sensitive to
    them). Measured: 29 impacts, the peaks 6.039e4 and 6.036e4 m/s^2 (ratio 1.0004)."""
    _, _, raw, ds = run({"joints": {"P": GUIDE},
                         "solver": {**SOLVER, "method": "dopri5", "revolutions": 1}})
    assert str(ds.status.values) == "ok"
    assert int(ds.impact_count.sel(joint="P")) > 0
    for k in (L.Y_R4, L.Y_PHI4, L.Y_PHI4 + 1):
        assert np.abs(raw.y[:, k]).max() == 0.0
    assert np.abs(raw.y[:, L.Y_R4 + 2] - PRESET.slider_height_m).max() < CZ + 1e-5
    rk4 = guide_run[3].slider_acceleration.sel(time=slice(0.0, PERIOD))
    assert float(np.abs(ds.slider_acceleration).max()) == pytest.approx(
        float(np.abs(rk4).max()), rel=0.02)


# ---------------------------------------------------------------------------
# 4. the start, the ensemble, the sink warning, the build
# ---------------------------------------------------------------------------

def test_seated_block_rests_on_the_wall_the_load_presses():
    """The seated start (``params.seated_offsets``): the block's offset in the guide's frame
    (0, side, up), against the wall opposite the ideal guide's force across the guide (its z
    part, the side part 0), at c plus its face's sink; the start state puts it at z_s plus
    that, x4 = 0."""
    from clearsweep.core.dynamics import ideal_joint_forces
    from clearsweep.params import face_sink

    pk = sc_packed({"P": GUIDE})
    off = seated_offsets(PRESET, pk.p, pk.jp, pk.p[L.P_THETA0], OMEGA)[P]
    force = ideal_joint_forces(0.0, initial_state(PRESET, pk.p[L.P_THETA0], OMEGA),
                               pk.p, pk.jp)[P]
    assert force[0] == 0.0 and force[1] == 0.0 and force[2] != 0.0
    assert off[0] == 0.0 and off[1] == 0.0
    assert off[2] == pytest.approx(-math.copysign(CZ + face_sink(abs(force[2]), pk.jp[P], 2),
                                                  force[2]), rel=1e-12)
    assert pk.y0[L.Y_R4] == 0.0
    assert pk.y0[L.Y_R4 + 2] == pytest.approx(PRESET.slider_height_m + off[2], abs=1e-18)


def test_ensemble_offsets_stay_in_the_plane():
    """An ensemble member's perturbed start (``ensemble.perturb.ball_offset``) moves the
    block up or down in its guide, never across the plane (x4 = 0)."""
    moved = []
    for member in range(4):
        cfg = load_config({"mechanism": SLIDER_CRANK, "joints": {"P": GUIDE},
                           "ensemble": {"members": 4, "member": member,
                                        "perturb": {"ball_offset": 0.5}}})
        y0 = pack(cfg, resolve_materials(cfg)).y0
        assert y0[L.Y_R4] == 0.0
        moved.append(y0[L.Y_R4 + 2])
    assert len(set(moved)) == 4
    assert max(abs(z - PRESET.slider_height_m) for z in moved) <= CZ + 1e-6


def test_sink_warning_reads_the_load_across_the_plane():
    """The guide's sink warning (``params.guide_sink``) reads the ideal guide's force in the
    guide's frame: at 1e-9 m the upper or lower wall's face sink is named (the z walls),
    never the side walls."""
    cfg = load_config({"mechanism": SLIDER_CRANK,
                       "joints": {"P": {"clearance_y": 1e-9, "clearance_z": 1e-9}}})
    texts = [t for t in hertz_sink_warnings(cfg, resolve_materials(cfg)) if "joint P" in t]
    assert len(texts) == 1 and "its z walls" in texts[0]


def test_build_keeps_p_only_where_the_case_has_it():
    """The slider-crank's kernel builds keep P where the case has P's clearance, and fold it
    away otherwise (the builds of every slider-crank case before P's clearance in it)."""
    with_p = joint_set(load_config({"mechanism": SLIDER_CRANK, "joints": {"P": GUIDE}}))
    without = joint_set(load_config({"mechanism": SLIDER_CRANK,
                                     "joints": {"B": {"clearance": 5e-4,
                                                      "socket_radius": 0.01}}}))
    assert build_of(with_p) & jointset.named("P")
    assert not build_of(without) & jointset.named("P")
    jointset.check(with_p, build_of(with_p))


# ---------------------------------------------------------------------------
# 5. the command line
# ---------------------------------------------------------------------------

#: The shipped benchmark (configs/slider_crank.yaml: 0.5 mm at B, centred start) with a
#: 0.1 mm guide, 2 revolutions (docs/mechanisms.md, "The guide P with clearance").
SHIPPED_LIKE = ["configs/slider_crank.yaml", "--set", "joints.P.clearance_y=2e-4", "--set",
                "joints.P.clearance_z=1e-4", "--set", "solver.revolutions=2"]


def test_run_report_and_wear_map_plot(tmp_path):
    """``clearsweep run`` of the shipped benchmark with a guide's clearance too (B and P),
    ``report`` and ``plot --kind wear-map``: each exits 0, the report's guide-walls table
    notes the slider-crank's walls and gives the upper and lower walls' tracks, the side
    walls' 0; the figure is written. Measured: tracks 3.3 nm on each of the upper and lower
    walls."""
    out = tmp_path / "sc.nc"
    runner = CliRunner()
    shipped = [str(ROOT / SHIPPED_LIKE[0]), *SHIPPED_LIKE[1:]]
    res = runner.invoke(main, ["run", *shipped, "-o", str(out)])
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["report", str(out)])
    assert res.exit_code == 0, res.output
    # the guide's walls: the upper and lower worn, the side walls across the plane not
    lines = res.output.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("Guide walls"))
    assert "side walls across the plane" in lines[k]
    depths = [float(v) for v in next(line for line in lines[k:] if line.startswith("P ")).split()[1:]]
    assert depths[:2] == [0.0, 0.0] and min(depths[2:]) > 0.0
    png = tmp_path / "wear_P.png"
    res = runner.invoke(main, ["plot", str(out), "--kind", "wear-map", "-o", str(png)])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 0
