"""The journal's tangential ("pendulum") mode at O and the bearing film's viscous damping
(docs/physics.md 3.6, ``joints.O.lubricant_viscosity``).

A journal pressed on its bearing wall by a load F_N swings along the wall like a pendulum of
length e = c + delta: f = sqrt(F_N / (m_eff e)) / (2 pi), m_eff about the crank's mass and
half the rod's (1.9 kg). At full slip Coulomb friction is constant and does not damp it;
Petroff's viscous shear of an oil film, eta 2 pi R L / c times the slip, does.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import butter, sosfiltfilt
from test_revolute import closed_form_acceleration

from clearsweep.params import PRESETS, film_coefficient
from clearsweep.simulation import simulate

#: O alone with 10 um of clearance, started 0.2 c off its seat (ensemble member 1 of seed 0):
#: the journal rings from the start.
RINGING = {"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}, "O": {"clearance": 1e-5}},
           "ensemble": {"members": 2, "member": 1, "perturb": {"ball_offset": 0.2}},
           "solver": {"duration": 0.12, "save_every": 1}}


def ring(viscosity_Pa_s):
    """(time, the slider acceleration's departure from the closed form above 20 Hz, dataset)."""
    ds = simulate({**RINGING, "joints": {**RINGING["joints"],
                                         "O": {"clearance": 1e-5,
                                               "lubricant_viscosity": viscosity_Pa_s}}})
    assert str(ds.status.values) == "ok"
    t = ds.time.values
    err = ds.slider_acceleration.values - closed_form_acceleration(ds.crank_angle.values,
                                                                  2.0 * math.pi)
    return t, sosfiltfilt(butter(4, 20.0, "highpass", fs=1.0 / (t[1] - t[0]), output="sos"), err), ds


def amplitudes(t, x):
    """The largest |x| in each of six equal windows of the run."""
    edges = np.linspace(0.0, t[-1] + 1e-9, 7)
    return [float(np.abs(x[(t >= a) & (t < b)]).max()) for a, b in zip(edges[:-1], edges[1:])]


@pytest.fixture(scope="module")
def dry():
    return ring(0.0)


def test_the_dry_journal_rings_at_the_pendulum_frequency(dry):
    """Without a film the ring does not decay (the last 0.02 s at 0.93 of the second window's
    amplitude), and its frequency is the pendulum's to 10 % (measured 183.9 Hz against 177.6
    from the closed form with F_N's mean)."""
    t, x, ds = dry
    amps = amplitudes(t, x)
    assert amps[-1] > 0.8 * amps[1]
    keep = t > 0.01
    n = 2 ** 18
    freq = np.fft.rfftfreq(n, t[1] - t[0])
    dominant = freq[np.argmax(np.abs(np.fft.rfft(x[keep] * np.hanning(keep.sum()), n)))]
    preset = PRESETS["realistic"]
    m_eff = preset.crank_mass_kg + 0.5 * preset.rod_mass_kg
    load = float(ds.normal_force.sel(joint="O").values[keep].mean())
    e = float(ds.eccentricity.sel(joint="O").values[keep].mean())
    assert dominant == pytest.approx(math.sqrt(load / (m_eff * e)) / (2.0 * math.pi), rel=0.1)


def test_the_bearing_film_damps_the_ring(dry):
    """With an ISO VG 680 oil (0.6 Pa s) the same ring decays: the last 0.02 s hold 0.34 of the
    second window's amplitude (measured), where the dry journal keeps 0.93. The decay rate,
    ln(0.107 / 0.036) / 0.08 s = 13.5 1/s, is 0.63 of the closed form's c_t / (2 m_eff) =
    21.5 1/s (c_t = 75.4 N s/m, m_eff from the measured frequency): the film shears the
    contact's slip, not the mode's own coordinate."""
    t, x, _ = ring(0.6)
    amps = amplitudes(t, x)
    assert amps[-1] < 0.5 * amps[1]
    assert amps[-1] < 0.8 * amplitudes(*dry[:2])[-1]


def test_the_film_is_petroffs_shear():
    """eta 2 pi R L / c: 0.06 Pa s in the shipped bearing (R 10 mm, L 20 mm) at 0.25 mm gives
    0.30 N s/m."""
    assert film_coefficient(0.06, 0.01, 0.02, 2.5e-4) == pytest.approx(
        0.06 * 2.0 * math.pi * 0.01 * 0.02 / 2.5e-4, rel=1e-15)
    assert film_coefficient(0.06, 0.01, 0.02, 2.5e-4) == pytest.approx(0.3016, rel=1e-3)


def test_the_seated_journal_balances_the_film_too():
    """Seated with a film (0.6 Pa s at 0.25 mm: 3.0 N s/m, a drag of 0.19 N at the journal's
    slip), the bearing's force on the crank at the start, normal, Coulomb and film together,
    is the ideal reaction to 1e-9 of its size (seated at the friction angle alone it would
    miss by the drag, 0.8 % of the 24 N load)."""
    ds = simulate({"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0},
                              "O": {"clearance": 2.5e-4, "lubricant_viscosity": 0.6}},
                   "solver": {"duration": 0.001, "save_every": 10}})
    ideal = simulate({"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}},
                      "solver": {"duration": 0.001, "save_every": 10}}).reaction_O.values[0]
    force = ds.joint_force.sel(joint="O").values[0]
    np.testing.assert_allclose(force[1:], ideal[1:], rtol=0, atol=1e-9 * np.abs(ideal[1:]).max())
