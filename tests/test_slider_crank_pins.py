"""The slider-crank's crank pin A and wrist pin B are revolute clearance joints (issue 44,
docs/mechanisms.md "Joints"): a pin in a bearing, its wear a strip around the bearing
(one row of the map, 2 psi R_i L of area), its map turning with the body that carries the
bearing (A's with the rod), and its results saying so. The RSSP's A and B stay spherical.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clearsweep.config import load_config
from clearsweep.core import layout as L
from clearsweep.core import revolute
from clearsweep.core.joints import INDEX
from clearsweep.core.kinematics import mtv, rotation, trig
from clearsweep.simulation import simulate

JA = INDEX["A"]
JB = INDEX["B"]

#: Both pins with 0.5 mm in a 10 mm bearing (the benchmark's B), A's bearing 15 mm long and
#: B's the preset's (params.Preset.pin_length_m, 20 mm); wear amplified so that two
#: revolutions wear measurably, not fed back (the amplified wear would stop the run on
#: energy_residual); friction on (the slip is the wear's sliding distance).
PINS = {
    "name": "pins",
    "mechanism": {"kind": "slider_crank", "preset": "flores_benchmark", "speed_rpm": 2000.0},
    "joints": {"A": {"clearance": 5.0e-4, "socket_radius": 0.01, "length": 0.015},
               "B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
    "contact": {"elastic": "hertz", "hertz_exponent": 1.5, "damping": "lankarani_nikravesh",
                "restitution": 0.9, "impact_velocity": "onset"},
    "solver": {"dt": 5.0e-6, "revolutions": 2, "baumgarte": [50.0, 50.0]},
    "wear": {"map": [18, 36], "amplification": 1.0e6, "feedback": False},
}


@pytest.fixture(scope="module")
def pins():
    ds = simulate(PINS)
    assert str(ds["status"].values) == "ok"
    return ds


def test_the_dataset_says_the_pins_are_revolute(pins):
    """(was: joint_A_type and joint_B_type 'spherical' in the slider-crank); the RSSP's stay
    spherical, O revolute in both."""
    assert pins.attrs["joint_A_type"] == "revolute"
    assert pins.attrs["joint_B_type"] == "revolute"
    assert pins.attrs["joint_O_type"] == "revolute"
    rssp = simulate({"solver": {"duration": 1e-3}})
    assert rssp.attrs["joint_A_type"] == "spherical" and rssp.attrs["joint_B_type"] == "spherical"


def test_the_resolved_config_says_what_the_pins_run_as():
    """``joints.A.type`` and ``joints.B.type`` not given resolve to the mechanism's type, so
    that a results file's config says what ran (was: 'spherical' in the slider-crank, whose
    pins run as the revolute type); a bushing stays a bushing."""
    sc = load_config({"mechanism": {"kind": "slider_crank", "preset": "flores_benchmark"},
                      "joints": {"A": {"type": "bushing"}}})
    assert (sc.joints.A.type, sc.joints.B.type) == ("bushing", "revolute")
    rssp = load_config({})
    assert (rssp.joints.A.type, rssp.joints.B.type) == ("spherical", "spherical")
    stated = load_config({"mechanism": {"kind": "slider_crank", "preset": "flores_benchmark"},
                          "joints": {"B": {"type": "revolute"}}})
    assert stated == sc.replace(joints__A__type="revolute")


@pytest.mark.parametrize("joint, length", [("A", 0.015), ("B", 0.02)])
def test_a_pins_wear_is_one_strip_row_of_the_bearings_area(pins, joint, length):
    """A pin's worn volume lies in row 0 of its map, each bin's depth over its strip of the
    bearing, R_i L dphi (the bearing's length: A's config key, B's the preset's), so that
    sum(depth) R_i L dphi is the worn volume; the other rows stay unworn (was: a sphere's
    caps spread over the polar rows, the map's volume its spherical bins' areas)."""
    wmap = pins["wear_map"].sel(joint=joint).values
    volume = float(pins["wear_volume"].sel(joint=joint))
    assert volume > 0.0
    assert np.count_nonzero(wmap[0]) > 1
    assert not np.any(wmap[1:])
    dphi = 2.0 * math.pi / wmap.shape[1]
    assert float(wmap[0].sum()) * 0.01 * length * dphi == pytest.approx(volume, rel=1e-9)


def test_a_pins_length_is_packed_from_its_key_or_the_preset():
    """joints.A.length [m] packs as A's bearing length (J_LENGTH); null: the preset's (was:
    no length, J_LENGTH 0 at A and B); the pins take Hertz's modulus and law under the
    paper's elastic law, as O does."""
    from clearsweep.config import load_config, resolve_materials
    from clearsweep.params import PRESETS, hertz_modulus, pack

    cfg = load_config(PINS)
    packed = pack(cfg, resolve_materials(cfg), seat=False)
    assert packed.jp[JA, L.J_LENGTH] == 0.015
    assert packed.jp[JB, L.J_LENGTH] == PRESETS["flores_benchmark"].pin_length_m == 0.02
    paper = load_config({**PINS, "contact": {"elastic": "paper"}})
    jp = pack(paper, resolve_materials(paper), seat=False).jp
    for j, name in ((JA, "A"), (JB, "B")):
        assert jp[j, L.J_EW] == hertz_modulus(getattr(paper.joints, name), resolve_materials(paper))


def rod_rotation(beta: float):
    """The slider-crank's rod frame at angle beta3 (alpha3 = pi/2 held, gamma3 = 0): its
    rotation about global x is -beta."""
    return rotation(trig(0.5 * math.pi, beta, 0.0))


def gap_at(wmap, j, phi_global, Rs, e=4.0e-4, interp=False):
    """revolute.gap of joint j with the journal at eccentricity e along the global in-plane
    angle phi_global, feedback on (bilinear with ``interp``)."""
    jp = np.zeros((L.N_JOINTS, L.N_JP))
    jp[:, L.J_C] = 5.0e-4
    jp[:, L.J_COAT] = math.inf
    p = np.zeros(L.N_P)
    p[L.P_FEEDBACK] = 1.0
    p[L.P_INTERP] = 1.0 if interp else 0.0
    ps = (0.0, 0.03, -0.02)
    pb = (0.0, ps[1] + e * math.cos(phi_global), ps[2] + e * math.sin(phi_global))
    return revolute.gap(jp, j, wmap, p, 0, pb, ps, Rs)


@settings(max_examples=40, deadline=None)
@given(beta=st.floats(-math.pi, math.pi), phi=st.floats(-math.pi, math.pi))
def test_as_map_turns_with_the_rod(beta, phi):
    """A's bearing is the rod's eye: its map's angle is n's angle about x less the rod's
    rotation about x (-beta3), so a worn bin at a rod-frame angle is under a journal at
    that angle plus the rod's rotation, whatever the rod's angle; the bearing-frame normal
    and offset are n and d in that frame (was: A read a sphere's map in the rod's frame)."""
    nazim = 36
    wmap = np.zeros((L.N_JOINTS, 4, nazim))
    k = int((phi + math.pi) / (2.0 * math.pi) * nazim) % nazim
    wmap[JA, 0, k] = 1.0e-6
    centre = -math.pi + (k + 0.5) * 2.0 * math.pi / nazim    # the bin's rod-frame angle
    Rs = rod_rotation(beta)
    e, n, d_s, n_s, h, slope, worn, c_eff, delta = gap_at(wmap, JA, centre - beta, Rs)
    assert h == 1.0e-6 and c_eff == pytest.approx(5.0e-4 + 1.0e-6, rel=1e-15)
    assert n_s[0] == 0.0
    assert math.atan2(n_s[2], n_s[1]) == pytest.approx(centre, abs=1e-12)
    assert d_s[1:] == pytest.approx((e * n_s[1], e * n_s[2]), abs=1e-18)
    # the same global direction with the rod turned a bin further reads the next bin
    assert gap_at(wmap, JA, centre - beta, rod_rotation(beta + 2.0 * math.pi / nazim))[4] == 0.0
    # B's bearing rides the slider, unrotated: its map's angle is the global one
    wmap[JB, 0, k] = 2.0e-6
    assert gap_at(wmap, JB, centre, rotation(trig(0.0, 0.0, 0.0)))[4] == 2.0e-6


@settings(max_examples=20, deadline=None)
@given(beta=st.floats(-math.pi, math.pi), phi=st.floats(-math.pi, math.pi))
def test_as_slope_is_the_gradient_of_the_rod_frame_map(beta, phi):
    """With the bilinear read, A's slope is the gradient of h with respect to the journal
    centre (global), its angle measured in the rod's frame: central differences of h."""
    nazim = 36
    rng = np.random.default_rng(7)
    wmap = np.zeros((L.N_JOINTS, 4, nazim))
    wmap[JA, 0, :] = rng.uniform(0.0, 2.0e-6, nazim)
    Rs = rod_rotation(beta)
    e = 4.0e-4
    geo = gap_at(wmap, JA, phi, Rs, e=e, interp=True)
    dphi = 1e-6
    hp = gap_at(wmap, JA, phi + dphi, Rs, e=e, interp=True)[4]
    hm = gap_at(wmap, JA, phi - dphi, Rs, e=e, interp=True)[4]
    slope = geo[5]
    tangent = (0.0, -math.sin(phi), math.cos(phi))
    # a bin centre (or the map's seam) inside the difference's span breaks the linear read
    ends = [math.atan2(math.sin(a + beta), math.cos(a + beta)) for a in (phi - dphi, phi + dphi)]
    spans = [math.floor((a + math.pi) / (2.0 * math.pi) * nazim - 0.5) for a in ends]
    if spans[0] != spans[1]:
        return
    expected = (hp - hm) / (2.0 * dphi) / e
    assert slope[0] == 0.0
    assert np.dot(slope, tangent) == pytest.approx(expected, rel=1e-6, abs=1e-12)
    radial = np.dot(slope, (0.0, math.cos(phi), math.sin(phi)))
    assert radial == pytest.approx(0.0, abs=1e-14 * float(np.linalg.norm(slope)))


def test_as_section_offsets_are_the_gaps_bearing_frame():
    """The Poincare section's offset of A (revolute.section_offsets of the rod-frame offset)
    is the gap's d_s over c: the bearing's frame, x its axis (-y of the rod), y along the
    rod, z across it in the plane."""
    Rs = rod_rotation(0.7)
    wmap = np.zeros((L.N_JOINTS, 4, 36))
    geo = gap_at(wmap, JA, 2.1, Rs, e=3.0e-4)
    d_global = (2.0e-6, 3.0e-4 * math.cos(2.1), 3.0e-4 * math.sin(2.1))
    jp = np.zeros((L.N_JOINTS, L.N_JP))
    jp[:, L.J_C] = 5.0e-4
    off, rate = revolute.section_offsets(jp, JA, mtv(Rs, d_global), (0.0, 0.0, 0.0))
    assert off[0] == pytest.approx(2.0e-6 / 5.0e-4, rel=1e-9)     # along global x
    assert off[1:] == pytest.approx((geo[2][1] / 5.0e-4, geo[2][2] / 5.0e-4), rel=1e-12)


def test_the_configs_pins_are_the_kernels():
    """config.SLIDER_CRANK_PINS (whose ``length`` the RSSP refuses) names the joints whose
    type the slider-crank changes (core.joints.SLIDER_CRANK_TYPES)."""
    from clearsweep.config import SLIDER_CRANK_PINS
    from clearsweep.core.joints import SLIDER_CRANK_TYPES

    assert SLIDER_CRANK_PINS == tuple(SLIDER_CRANK_TYPES)
