"""Contact law (docs/physics.md section 3.2, paper Table 1) and the double-elastic-layer modulus."""

import ast
import math
import pathlib

import pytest
from impacts import RI, RJ, C, impact_restitution

from clearsweep.config import JointConfig
from clearsweep.core.contact import (
    damping_factor,
    elastic_energy,
    elastic_force,
    episode_impact_velocity,
    friction_factor,
    hysteresis_fraction,
    normal_force,
)
from clearsweep.core.spherical import contact_area
from clearsweep.materials import load_materials
from clearsweep.params import equivalent_modulus, hertz_modulus, oedometric_modulus

MATERIALS = load_materials()


def joint(coating="none", coating_thickness=1e-4):
    return JointConfig(coating=coating, coating_thickness=coating_thickness, base_thickness=4.9e-3)


def test_uncoated_modulus_is_steels():
    steel = MATERIALS["steel"]
    es = oedometric_modulus(steel.youngs_modulus_Pa, steel.poisson_ratio)
    expected = es / (2.0 * (1.0 - steel.poisson_ratio ** 2))
    assert equivalent_modulus(joint(), MATERIALS, "series") == pytest.approx(expected, rel=1e-14)


def test_paper_mm_rule_makes_uncoated_five_times_softer():
    series = equivalent_modulus(joint(), MATERIALS, "series")
    literal = equivalent_modulus(joint(), MATERIALS, "paper_mm")
    assert series / literal == pytest.approx(4.9, rel=1e-12)


@pytest.mark.parametrize("coating", ["MoS2", "lead", "PTFE"])
def test_softer_coating_lowers_modulus(coating):
    soft = equivalent_modulus(joint(coating), MATERIALS, "series")
    assert soft < equivalent_modulus(joint(), MATERIALS, "series")
    # a vanishing coating thickness recovers the uncoated value
    thin = joint(coating, coating_thickness=1e-15)
    m = MATERIALS[coating]
    steel = MATERIALS["steel"]
    # (only the surface Poisson ratio differs then)
    ei = oedometric_modulus(steel.youngs_modulus_Pa, steel.poisson_ratio)
    expected = 1.0 / ((1 - m.poisson_ratio ** 2) / ei + (1 - steel.poisson_ratio ** 2) / ei)
    assert equivalent_modulus(thin, MATERIALS, "series") == pytest.approx(expected, rel=1e-9)


def test_hertz_modulus_of_steel_on_steel_is_the_closed_form():
    """Hertz's E* = [(1 - nu^2)/E + (1 - nu^2)/E]^-1 = E / (2 (1 - nu^2)) of the uncoated
    steel pair, and the paper's layered E_w over it is the oedometric factor
    (1 - nu) / ((1 + nu)(1 - 2 nu)), 1.346 for nu = 0.3: what O's journal and P's corners
    took before issue 41."""
    steel = MATERIALS["steel"]
    e, nu = steel.youngs_modulus_Pa, steel.poisson_ratio
    assert hertz_modulus(joint(), MATERIALS) == pytest.approx(e / (2.0 * (1.0 - nu ** 2)), rel=1e-14)
    ratio = equivalent_modulus(joint(), MATERIALS, "series") / hertz_modulus(joint(), MATERIALS)
    assert ratio == pytest.approx((1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)), rel=1e-14)
    assert ratio == pytest.approx(1.346, abs=1e-3)


@pytest.mark.parametrize("coating", ["MoS2", "lead", "PTFE"])
def test_coated_hertz_modulus_between_its_limits(coating):
    """The coated side's compliance is the thickness average of its coating's and its base's
    (docs/physics.md 3.2): a vanishing coating gives the uncoated E*, a coating much thicker
    than its base Hertz's E* of the coating material against the steel ball, and the default
    0.1 mm over 4.9 mm the thickness-weighted value between them."""
    steel, m = MATERIALS["steel"], MATERIALS[coating]
    ws = (1.0 - steel.poisson_ratio ** 2) / steel.youngs_modulus_Pa
    wc = (1.0 - m.poisson_ratio ** 2) / m.youngs_modulus_Pa
    uncoated = 1.0 / (2.0 * ws)
    thin = JointConfig(coating=coating, coating_thickness=1e-15, base_thickness=4.9e-3)
    assert hertz_modulus(thin, MATERIALS) == pytest.approx(uncoated, rel=1e-11)
    thick = JointConfig(coating=coating, coating_thickness=1.0, base_thickness=1e-15)
    assert hertz_modulus(thick, MATERIALS) == pytest.approx(1.0 / (wc + ws), rel=1e-11)
    fc = 1e-4 / 5e-3
    expected = 1.0 / (fc * wc + (1.0 - fc) * ws + ws)
    assert hertz_modulus(joint(coating), MATERIALS) == pytest.approx(expected, rel=1e-14)
    assert hertz_modulus(joint(coating), MATERIALS) < uncoated        # every coating is softer


def test_small_penetration_limit_of_stiffness():
    """F_el -> (8 pi E_w R_i / (5 c)) delta^2 as delta/c -> 0."""
    ew = 1.1e11
    for delta in (1e-12, 1e-10, 1e-9):
        f, _ = elastic_force(delta, C, ew, RI, RJ, 0.0)
        limit = 8 * math.pi * ew * RI / (5 * C) * delta ** 2
        assert f == pytest.approx(limit, rel=3 * delta / C)


def test_elastic_slope_and_energy_are_consistent():
    ew = 1.1e11
    for delta in (1e-8, 1e-6, 2e-5):
        f, df = elastic_force(delta, C, ew, RI, RJ, 0.0)
        h = delta * 1e-5
        assert df == pytest.approx((elastic_force(delta + h, C, ew, RI, RJ, 0.0)[0]
                                    - elastic_force(delta - h, C, ew, RI, RJ, 0.0)[0]) / (2 * h), rel=1e-6)
        assert f == pytest.approx((elastic_energy(delta + h, C, ew, RI, RJ, 0.0)
                                   - elastic_energy(delta - h, C, ew, RI, RJ, 0.0)) / (2 * h), rel=1e-6)


@pytest.mark.parametrize("ddot", [-10.0, -1.0, -1e-3, 0.0, 1e-3, 1.0])
def test_normal_force_never_pulls(ddot):
    kappa = damping_factor(*hysteresis_fraction(0, 0.7), 0.01)
    for delta in (1e-9, 1e-6, 1e-5):
        fn, *_ = normal_force(delta, ddot, C, 1.1e11, RI, RJ, 0.0, kappa)
        assert fn >= 0.0


def test_contact_area_is_two_pi_rj_hc():
    rj = RI - C
    e = C + 1e-6
    hc = rj * (1 + (e ** 2 + rj ** 2 - RI ** 2) / (2 * rj * e))
    assert contact_area(1e-6, e, RI, rj) == pytest.approx(2 * math.pi * rj * hc, rel=1e-6)


@pytest.mark.parametrize("cr", [0.5, 0.7, 0.9])
def test_delivered_restitution_is_close_to_requested(cr):
    """The damping law of Table 1 (hysteresis factor 20 (1 - c_r) / (13 c_r)) delivers a
    restitution slightly below c_r; measured with this harness: 0.5 -> 0.481,
    0.7 -> 0.692, 0.9 -> 0.898."""
    delivered = impact_restitution(cr, 0.1)
    assert cr - 0.025 < delivered < cr


def test_delivered_restitution_does_not_depend_on_impact_speed():
    """With delta_dot0 = the impact speed the law is self-similar in v."""
    values = [impact_restitution(0.7, v) for v in (0.01, 0.1, 1.0)]
    assert max(values) - min(values) < 1e-6


def test_core_imports_no_io_or_framework_layer():
    """clearsweep.core is numbers only: numpy, numba and the standard library; no xarray,
    YAML, Dask, SciPy, plotting or I/O libraries, and nothing from the rest of the package."""
    import sys

    allowed = {"numpy", "numba"} | set(sys.stdlib_module_names)
    core = pathlib.Path(__file__).resolve().parents[1] / "clearsweep" / "core"
    for path in core.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:  # relative import inside core
                    continue
                names = [node.module.split(".")[0]]
            else:
                continue
            assert set(names) <= allowed, (path.name, names)


@pytest.mark.parametrize("cr, measured", [(0.5, 0.481), (0.7, 0.692), (0.9, 0.898)])
def test_episode_latch_keeps_delivered_restitution(cr, measured):
    """The kernel's latch (fastest approach of the episode) delivers the restitution of the
    law with delta_dot0 = the impact speed: 0.481 / 0.692 / 0.898 for c_r = 0.5 / 0.7 / 0.9,
    from the floor up to 100x the floor."""
    for v_in in (0.01, 0.1):
        assert impact_restitution(cr, v_in, latch_floor=1e-3) == pytest.approx(measured, abs=3e-3)
        assert impact_restitution(cr, v_in, latch_floor=1e-3) == pytest.approx(impact_restitution(cr, v_in),
                                                              abs=2e-3)


def test_episode_latch_rule():
    assert episode_impact_velocity(0.0, 0.5, 1e-3, False) == 0.5        # onset: the approach rate
    assert episode_impact_velocity(0.0, -0.2, 1e-3, False) == 1e-3      # grazing onset: the floor
    assert episode_impact_velocity(0.3, 0.1, 1e-3, False) == 0.3        # slowing: kept
    assert episode_impact_velocity(0.3, 0.4, 1e-3, False) == 0.4        # faster approach: raised


@pytest.mark.parametrize("vt, factor", [(0.0, 0.0), (0.5e-4, 0.0), (1e-4, 0.0), (3.25e-4, 0.25),
                                        (5.5e-4, 0.5), (1e-3, 1.0), (2e-3, 1.0), (1.0, 1.0)])
def test_friction_factor_is_the_ramp_of_physics_3_3(vt, factor):
    """c_d by hand at the default v0 = 1e-4 m/s, v1 = 1e-3 m/s: 0 below v0, linear between,
    1 above v1 (the reference in tests/reference.py is a separate formulation)."""
    assert friction_factor(vt, 1e-4, 1e-3) == pytest.approx(factor, abs=1e-15)


@pytest.mark.parametrize("elastic", ["paper", "hertz"])
def test_each_joint_packs_the_modulus_of_its_law(elastic):
    """jp[J_EW] is the modulus of the joint's elastic law: Hertz's E* at O's journal and P's
    corners (always a Hertz power law) and at A and B under ``contact.elastic: hertz``, the
    paper's layered E_w at A and B under the paper's law; where the coating is worn through
    (J_EW_BASE) the uncoated pair's value of the same law."""
    from clearsweep.config import load_config
    from clearsweep.core import layout as L
    from clearsweep.core.joints import INDEX
    from clearsweep.params import pack

    root = pathlib.Path(__file__).resolve().parents[1]
    cfg = load_config(str(root / "configs" / "two_clearances.yaml"),
                      [f"contact.elastic={elastic}", "joints.O.clearance=1e-4",
                       "joints.O.coating=PTFE", "joints.P.clearance_y=1e-4",
                       "joints.P.clearance_z=1e-4", "joints.A.coating=MoS2"])
    jp = pack(cfg, MATERIALS, seat=False).jp
    steel = MATERIALS["steel"]
    e_star = steel.youngs_modulus_Pa / (2.0 * (1.0 - steel.poisson_ratio ** 2))
    o, p_, a, b = INDEX["O"], INDEX["P"], INDEX["A"], INDEX["B"]
    assert jp[p_, L.J_EW] == pytest.approx(e_star, rel=1e-14)
    assert jp[o, L.J_EW_BASE] == pytest.approx(e_star, rel=1e-14)
    assert jp[o, L.J_EW] == pytest.approx(hertz_modulus(cfg.joints.O, MATERIALS), rel=1e-14)
    if elastic == "hertz":
        assert jp[b, L.J_EW] == pytest.approx(e_star, rel=1e-14)
        assert jp[a, L.J_EW] == pytest.approx(hertz_modulus(cfg.joints.A, MATERIALS), rel=1e-14)
        assert jp[a, L.J_EW_BASE] == pytest.approx(e_star, rel=1e-14)
    else:
        assert jp[b, L.J_EW] == equivalent_modulus(joint(), MATERIALS, "series")
        assert jp[a, L.J_EW] == equivalent_modulus(cfg.joints.A, MATERIALS, "series")
        assert jp[a, L.J_EW_BASE] == equivalent_modulus(joint(), MATERIALS, "series")
