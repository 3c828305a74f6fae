"""Joint O, the revolute clearance joint at the crank bearing (docs/physics.md 3.6): limiting
cases, convergence, the bearing map's bookkeeping, the config and the CLI.

The dense reference, the single journal impact against scipy and the worn volume against
k * sum(F_N |v_t| dt) are in tests/test_revolute_reference.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import ConfigError, load_config
from clearsweep.core import layout as L
from clearsweep.core import revolute
from clearsweep.core.joints import INDEX
from clearsweep.params import PRESETS, ideal_slider_x
from clearsweep.simulation import simulate

O = INDEX["O"]

#: Joint O alone with clearance (A and B ideal).
O_ONLY = {"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}, "O": {"clearance": 2.5e-4}}}


def test_a_tight_bearing_moves_the_slider_as_the_ideal_mechanism():
    """With a radial clearance of 1 nm at O the journal sits in its bearing to a few nm
    (clearance plus the Hertz penetration under the crank's load), and the slider follows
    the closed-form kinematics of the ideal mechanism to 1e-6 relative."""
    # the Hertz penetration under the crank's load (about 7 nm) is several clearances deep:
    # the penetration stop (a fraction of c) is lifted
    ds = simulate({**O_ONLY, "joints": {**O_ONLY["joints"], "O": {"clearance": 1e-9}},
                   "contact": {"max_penetration_fraction": 100.0},
                   "solver": {"duration": 0.05, "save_every": 10}})
    assert str(ds.status.values) == "ok"
    preset = PRESETS["realistic"]
    x = ideal_slider_x(ds.crank_angle.values, preset.crank_length_m, preset.rod_length_m,
                       preset.slider_height_m)
    np.testing.assert_allclose(ds.slider_position.values, x, rtol=1e-6, atol=0.0)
    # and the journal is in contact, carrying the crank: a few nm off the bearing centre
    ecc = ds.eccentricity.sel(joint="O").values
    assert 1e-9 < ecc.max() < 2e-8
    assert float(ds.normal_force_peak.sel(joint="O")) > 0.0


def closed_form_acceleration(theta, omega):
    """The ideal mechanism's slider acceleration [m/s^2] at crank angles ``theta`` turning
    at ``omega``: x''(theta) omega^2 of the closed form x(theta) (``ideal_slider_x``), by
    central differences (step 1e-4 rad: truncation and rounding below 1e-6 m/s^2)."""
    preset = PRESETS["realistic"]

    def x(t):
        return ideal_slider_x(t, preset.crank_length_m, preset.rod_length_m, preset.slider_height_m)

    h = 1e-4
    return (x(theta + h) - 2.0 * x(theta) + x(theta - h)) / (h * h) * omega * omega


def deviation_from_closed_form(ds):
    """max |a - a_ideal| of the slider's acceleration over the run's rows, as a fraction of
    the closed form's peak |a_ideal| over a revolution (the settled peak a seated start
    runs at)."""
    theta = ds.crank_angle.values
    time = ds.time.values
    omega = (theta[-1] - theta[0]) / (time[-1] - time[0])        # driven: constant
    peak = np.abs(closed_form_acceleration(np.linspace(0.0, 2.0 * math.pi, 20001), omega)).max()
    error = ds.slider_acceleration.values - closed_form_acceleration(theta, omega)
    return float(np.abs(error).max() / peak)


def test_a_tight_bearing_with_friction_follows_the_closed_form_acceleration():
    """O's clearance at 1 nm, the penetration stop lifted, friction on: the journal seated at
    the friction angle (docs/physics.md 3.6) starts in equilibrium, and the slider's
    acceleration follows the closed form to 1e-3 of its peak over the first 0.05 s.
    Measured: 1.4e-4 (friction off: 1.4e-4). Seated along the reaction alone (before issue
    41), the journal's friction, mu F_N across the normal, was unbalanced at the start and
    drove its tangential mode at 7 kHz, growing to 5.2e-3 of the peak within 0.05 s."""
    ds = simulate({**O_ONLY, "joints": {**O_ONLY["joints"], "O": {"clearance": 1e-9}},
                   "contact": {"max_penetration_fraction": 100.0},
                   "friction": {"enabled": True},
                   "solver": {"duration": 0.05, "save_every": 1}})
    assert str(ds.status.values) == "ok"
    assert float(ds.friction_force.sel(joint="O")[0]) > 0.0
    assert deviation_from_closed_form(ds) < 1e-3


def test_a_seated_start_with_friction_has_no_start_up_transient():
    """A PTFE-lined bearing (mu = 0.167, a friction angle of 9.5 degrees) with 0.25 mm of
    clearance, seated, friction on: over the first 0.05 s the slider's acceleration stays
    within 1 % of the settled peak (the closed form's over a revolution) of the closed form,
    and the bearing's force on the crank at the start, normal and friction together, is the
    ideal reaction. Measured: 0.39 % (friction off: 0.38 %: the journal's offset c + delta
    moves the crank's geometry), the force to 1.6e-11 of its size (tolerance 1e-9). Seated along the reaction
    alone, the unbalanced friction rang the journal's tangential mode: 10.1 %."""
    coated = {**O_ONLY, "joints": {**O_ONLY["joints"], "O": {"clearance": 2.5e-4, "coating": "PTFE"}},
              "friction": {"enabled": True}, "solver": {"duration": 0.05, "save_every": 1}}
    ds = simulate(coated)
    assert int(ds.impact_count.sel(joint="O")) == 0
    assert deviation_from_closed_form(ds) < 0.01
    ideal = simulate({"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}},
                      "solver": {"duration": 0.01, "save_every": 10}}).reaction_O.values[0]
    force = ds.joint_force.sel(joint="O").values[0]
    np.testing.assert_allclose(force[1:], ideal[1:], rtol=0, atol=1e-9 * np.abs(ideal[1:]).max())


@pytest.fixture(scope="module")
def seated_o():
    return simulate({**O_ONLY, "solver": {"duration": 0.05, "save_every": 10}})


def test_a_seated_journal_starts_on_the_wall_without_an_impact(seated_o):
    """The seated start leans the journal on the bearing wall along the ideal reaction at
    t = 0 (in the bearing's plane): in contact from the first row, no impact counted, the
    bearing's force on the crank the ideal one at the start, but for the friction of the
    journal spinning in its bearing (|F_t| = mu F_N, tangential)."""
    ds = seated_o
    assert float(ds.penetration.sel(joint="O")[0]) > 0.0
    assert int(ds.impact_count.sel(joint="O")) == 0
    # the reaction at O: the contact force in the plane, the axial reaction along x
    force = ds.joint_force.sel(joint="O").values
    np.testing.assert_array_equal(force, ds.reaction_O.values)
    ideal = simulate({"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}},
                      "solver": {"duration": 0.01, "save_every": 10}}).reaction_O.values[0]
    friction = float(ds.friction_force.sel(joint="O")[0])
    assert 0.0 < friction < 0.5 * float(ds.normal_force.sel(joint="O")[0])
    np.testing.assert_allclose(force[0], ideal, rtol=0, atol=1.01 * friction)
    frictionless = simulate({**O_ONLY, "friction": {"enabled": False},
                             "solver": {"duration": 0.01, "save_every": 10}})
    # in the plane: the ideal reaction; along the axis: the rod's pull, whose line the
    # journal's offset (c + delta = 2.5e-4 m on a 0.14 m crank) turns by about 0.2 %
    got = frictionless.reaction_O.values[0]
    np.testing.assert_allclose(got[1:], ideal[1:], rtol=0, atol=1e-6 * np.abs(ideal).max())
    assert got[0] == pytest.approx(ideal[0], rel=5e-3)


def test_the_ideal_bearing_reports_its_reaction_and_no_contact(seated_o):
    ideal = simulate({"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}},
                      "solver": {"duration": 0.01, "save_every": 10}})
    np.testing.assert_array_equal(ideal.joint_force.sel(joint="O").values, ideal.reaction_O.values)
    assert np.isnan(float(ideal.normal_force_peak.sel(joint="O")))
    assert not ideal.wear_map.sel(joint="O").values.any()
    assert float(ideal.wear_volume.sel(joint="O")) == 0.0


def test_the_journal_wears_its_bearing_and_the_map_keeps_the_volume(seated_o):
    """The journal slides at about R_j omega against the bearing: wear at O, spread over the
    bearing map's row 0 (uniform along its length), whose depth times bin area R_i L dphi
    adds up to the worn volume."""
    ds = seated_o
    wmap = ds.wear_map.sel(joint="O").values
    assert wmap[1:].sum() == 0.0 and wmap[0].max() > 0.0
    cfg = load_config(O_ONLY)
    r_i, length = cfg.joints.O.bearing_radius, cfg.joints.O.length
    area = r_i * length * 2.0 * math.pi / wmap.shape[1]
    assert wmap[0].sum() * area == pytest.approx(float(ds.wear_volume.sel(joint="O")), rel=1e-12)


def test_bearing_deposit_keeps_volume_and_wraps_around():
    """revolute.deposit: a strip straddling phi = +-180 degree, a strip narrower than a bin,
    the whole volume kept to rounding and the depth inside the strip V / A."""
    nazim = 72
    wmap = np.zeros((L.N_JOINTS, 4, nazim))
    r_l = 0.01 * 0.02
    bin_area = r_l * 2.0 * math.pi / nazim
    vol, psi = 3e-15, 0.3                          # a strip of half-angle 0.3 rad
    area = 2.0 * psi * r_l
    n = (0.0, -1.0, 1e-3)                          # phi ~ 180 degree: the seam
    top = revolute.deposit(wmap, O, n, vol, area, r_l)
    assert wmap[O, 0].sum() * bin_area == pytest.approx(vol, rel=1e-12)
    assert top == pytest.approx(vol / area, rel=1e-12)
    assert wmap[O, 0, 0] > 0.0 and wmap[O, 0, -1] > 0.0    # both sides of the seam
    assert not wmap[O, 1:].any() and not wmap[:O].any()
    narrow = np.zeros_like(wmap)
    revolute.deposit(narrow, O, (0.0, 1.0, 0.0), vol, 1e-12 * r_l, r_l)
    assert narrow[O, 0].sum() * bin_area == pytest.approx(vol, rel=1e-12)
    assert np.count_nonzero(narrow[O, 0]) <= 2


def test_contact_angle_of_the_journal_is_the_circles_overlap():
    """psi: where the journal's circle (R_j, centre at e) leaves the bearing's (R_i), from
    the law of cosines, for a small and a large penetration."""
    ri, rj = 0.01, 0.01 - 2.5e-4
    for pen in (1e-7, 2e-5):
        e = ri - rj + pen
        cos_psi = (ri * ri + e * e - rj * rj) / (2.0 * ri * e)
        # the circles cross where |x| = R_i and |x - e| = R_j: the bearing's angle seen from
        # its centre is psi with cos psi = (R_i^2 + e^2 - R_j^2) / (2 R_i e)... for the
        # journal outside the bearing's circle, on the side of the normal
        assert revolute.contact_angle(pen, e, ri, rj) == pytest.approx(math.acos(cos_psi), rel=1e-6)


def test_halving_the_step_moves_settled_statistics_by_less_than_half_a_percent():
    """A centred journal (impacts at O) over 0.3 s: the energy residual within the default
    tolerance, and the settled RMS acceleration, O's contact fraction and worn volume within
    0.5 % at dt = 1e-5 s and 5e-6 s."""
    base = {**O_ONLY, "initial": {"joints": "centred"}, "metrics": {"settle_time": 0.1}}
    runs = [simulate({**base, "solver": {"duration": 0.3, "dt": dt, "save_every": 100}})
            for dt in (1e-5, 5e-6)]
    tolerance = load_config(base).solver.energy_tolerance
    for ds in runs:
        assert str(ds.status.values) == "ok"
        assert float(ds.energy_residual_relative) < tolerance
        assert int(ds.impact_count.sel(joint="O")) > 0
    for name in ("slider_acceleration_rms_settled", "contact_fraction_settled", "wear_volume"):
        a, b = (float(ds[name].sel(joint="O")) if "joint" in ds[name].dims else float(ds[name])
                for ds in runs)
        assert abs(a - b) <= 5e-3 * abs(b), (name, a, b)


@pytest.mark.parametrize("override, key", [
    ("joints.O.clearance=-1e-4", "joints.O.clearance"),
    ("joints.O.clearance=0.009", "joints.O.clearance"),
    ("joints.O.length=0", "joints.O.length"),
    ("joints.O.bearing_radius=abc", "joints.O.bearing_radius"),
    ("joints.O.coating=teflon", "joints.O.coating"),
    ("joints.O.socket_radius=0.01", "joints.O.socket_radius"),
])
def test_a_bad_joint_o_value_is_one_error_line_naming_the_key(tmp_path, override, key):
    out = tmp_path / "o.nc"
    result = CliRunner().invoke(main, ["run", "configs/one_clearance.yaml", "--set", override,
                                       "-o", str(out)])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: ") and key in lines[0]
    assert not out.exists()


def test_joint_o_is_sweepable_and_validated_per_case():
    cfg = load_config(O_ONLY, ["joints.O.coating=PTFE", "joints.O.length=0.03"])
    assert cfg.joints.O.coating == "PTFE" and cfg.joints.O.length == 0.03
    with pytest.raises(ConfigError, match="joints.O.clearance"):
        load_config(O_ONLY, ["joints.O.bearing_radius=2e-3", "joints.O.clearance=1.5e-3"])


@pytest.mark.parametrize("kind", ["wear-map", "orbit", "wear-polar", "forces"])
def test_figures_of_a_run_with_clearance_at_o_read_and_keep_their_text_apart(seated_o, kind):
    """The bearing is drawn as a bearing: its wear around the bearing (a curve and the
    bearing's cross-section) rather than a sphere, the journal's orbit in the bearing's
    plane only; the layout check of tests/test_figure_layout.py passes."""
    from test_figure_layout import layout_problems

    from clearsweep.plotting import figure

    fig = figure(seated_o, kind)
    assert not layout_problems(fig), layout_problems(fig)
    titles = [ax.get_title() for ax in fig.axes]
    if kind == "wear-map":
        assert any(t.startswith("bearing O: wear around the bearing") for t in titles)
        assert any(ax.name == "polar" and "bearing O" in ax.get_title() for ax in fig.axes)
        assert not any(ax.name == "3d" and "O" in ax.get_title() for ax in fig.axes)
        # the bearing alone has clearance: no socket (it said "Socket and bearing")
        assert fig.get_suptitle().startswith("Bearing wear depth")
    if kind == "forces":
        # the journal's force is the reaction at O: one row, not two
        assert not any(t.startswith("joint O") for t in titles)
        assert len([t for t in titles if t.startswith("bearing O")]) == 4     # |F|, x, y, z
    if kind == "orbit":
        assert [t for t in titles if "O" in t.split(":")[0]] == ["bearing O: journal in the bearing's plane, yz"]


def test_a_life_run_wears_the_bearing_by_cycle_jumps():
    """Cycle jumps extrapolate the bearing map as they do a socket's: O's depth grows with
    the revolutions, its effective clearance is c plus the deepest bin, and the coating's
    remaining thickness is reported for O."""
    from clearsweep import life

    cfg = load_config("configs/life.yaml", ["joints.B.clearance=0", "joints.O.clearance=2.5e-4",
                                            "joints.O.coating=PTFE", "life.cycles=2000"])
    ds = life(cfg)
    depth = ds.wear_depth_max.sel(joint="O").values
    assert depth.size >= 2 and np.all(np.diff(depth) > 0) and depth[-1] > 100 * depth[0]
    np.testing.assert_allclose(ds.clearance_effective.sel(joint="O").values, 2.5e-4 + depth,
                               rtol=1e-12)
    assert np.all(ds.coating_remaining.sel(joint="O").values < cfg.joints.O.coating_thickness)
    assert np.isnan(ds.wear_depth_max.sel(joint="B").values).all()
