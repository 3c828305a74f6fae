"""The largest Lyapunov exponent by twin runs renormalised once a block (Benettin et al. 1980;
docs/physics.md section 11.5), on systems whose exponent is known: the logistic map, the
forced Duffing oscillator and the ideal mechanism."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from clearsweep.motion import LYAPUNOV_PERTURBATION, largest_lyapunov

ROOT = Path(__file__).resolve().parents[1]


def logistic_exponent(r: float, blocks: int, skip: int = 1000, x0: float = 0.3) -> float:
    x = x0
    for _ in range(skip):
        x = r * x * (1.0 - x)

    def advance(k, reference, twin):
        return r * reference * (1.0 - reference), r * twin * (1.0 - twin)

    return largest_lyapunov(advance, np.array([x]), blocks)


def test_the_chaotic_logistic_map_at_r_4_has_the_exponent_ln_2():
    """At r = 4 the map is conjugate to the tent map: lambda = ln 2 per iterate."""
    assert logistic_exponent(4.0, 20000) == pytest.approx(math.log(2.0), abs=0.02)


def test_the_period_two_logistic_map_has_its_closed_form_negative_exponent():
    """At r = 3.2 the orbit is period 2 and lambda = ln|r^2 (1 - 2 x+)(1 - 2 x-)| / 2 =
    ln(4 + 2 r - r^2) / 2 = ln(0.16) / 2 = -0.916 per iterate."""
    r = 3.2
    exact = 0.5 * math.log(4.0 + 2.0 * r - r * r)
    assert logistic_exponent(r, 400) == pytest.approx(exact, abs=1e-3)


DAMPING, OMEGA_F = 0.3, 1.2
FORCING_PERIOD = 2.0 * math.pi / OMEGA_F


def duffing_exponent(gamma: float, blocks: int, skip: int = 100, y0=(1.0, 0.0)) -> float:
    """lambda per forcing period of x'' + 0.3 x' - x + x^3 = gamma cos(1.2 t) (Ueda / Holmes,
    tests/test_motion.py), reference and twin integrated as one system (one step sequence
    for both, so that the integrator's error does not enter their difference)."""
    from scipy.integrate import solve_ivp

    def pair(t, z):
        x, v, xt, vt = z
        force = gamma * math.cos(OMEGA_F * t)
        return (v, -DAMPING * v + x - x ** 3 + force, vt, -DAMPING * vt + xt - xt ** 3 + force)

    def advance(k, reference, twin):
        t0 = (skip + k) * FORCING_PERIOD
        z = solve_ivp(pair, (t0, t0 + FORCING_PERIOD), np.concatenate([reference, twin]),
                      rtol=1e-11, atol=1e-13, method="DOP853").y[:, -1]
        return z[:2], z[2:]

    start = solve_ivp(lambda t, y: pair(t, np.concatenate([y, y]))[:2], (0.0, skip * FORCING_PERIOD),
                      y0, rtol=1e-10, atol=1e-12, method="DOP853").y[:, -1]
    return largest_lyapunov(advance, start, blocks)


def test_a_weakly_forced_duffing_oscillator_contracts_at_half_its_damping():
    """gamma = 0.1: a period-1 orbit in one well, a focus: both exponents equal half the
    phase-space contraction, -0.3 / 2 per unit time, -0.785 per forcing period."""
    assert duffing_exponent(0.1, 60) == pytest.approx(-0.5 * DAMPING * FORCING_PERIOD, rel=0.03)


def test_the_chaotic_duffing_oscillator_has_a_positive_exponent():
    """gamma = 0.5: the Ueda / Holmes strange attractor (K = 0.99, tests/test_motion.py): a
    positive exponent, smaller than the contraction so that the two sum to -0.3 T."""
    value = duffing_exponent(0.5, 200)
    assert 0.2 < value < DAMPING * FORCING_PERIOD


def test_the_twin_starts_its_size_away_and_the_estimate_is_deterministic():
    seen = []

    def advance(k, reference, twin):
        seen.append(float(np.linalg.norm((twin - reference) / np.array([1.0, 10.0]))))
        return reference, twin

    # a flow that does nothing: the offset neither grows nor shrinks (but for the rounding
    # of x + d - x: 1e-9 against 2.0 keeps 7 digits)
    assert largest_lyapunov(advance, np.array([0.5, 2.0]), 3, scale=[1.0, 10.0]) == \
        pytest.approx(0.0, abs=1e-6)
    assert seen == pytest.approx([LYAPUNOV_PERTURBATION] * 3, rel=1e-6)
    assert logistic_exponent(4.0, 500) == logistic_exponent(4.0, 500)


def test_a_component_of_infinite_scale_is_neither_perturbed_nor_measured():
    def advance(k, reference, twin):
        assert twin[1] == reference[1]
        return reference * np.array([2.0, 1.0]), twin * np.array([2.0, 1.0]) + np.array([0.0, 5.0])

    assert largest_lyapunov(advance, np.array([1.0, 1.0]), 4, scale=[1.0, math.inf]) == \
        pytest.approx(math.log(2.0))


def test_a_non_finite_state_gives_nan():
    def advance(k, reference, twin):
        return reference, np.full_like(twin, np.nan)

    assert np.isnan(largest_lyapunov(advance, np.array([1.0]), 2))


def ideal_run(speed_rpm: float, revolutions: int):
    from clearsweep.simulation import simulate

    return simulate({"mechanism": {"preset": "realistic", "speed_rpm": speed_rpm},
                     "solver": {"revolutions": revolutions + 1},
                     "metrics": {"settle_revolutions": 1, "lyapunov_revolutions": revolutions}})


def test_the_ideal_mechanism_has_a_negative_exponent_no_faster_than_baumgartes():
    """The ideal mechanism has no degree of freedom of its own (the crank is driven): every
    offset of the twin breaks a constraint, and Baumgarte's terms (alpha = beta = 5 s-1, a
    double root at -5 s-1) take it back. The exponent is negative, and above -5 s-1 times
    the revolution's 0.5 s at 120 r/min (the double root's t e^{-5 t} decays more slowly
    than e^{-5 t} over a few revolutions)."""
    ds = ideal_run(120.0, 4)
    value = float(ds["lyapunov_exponent"])
    assert -5.0 * 0.5 < value < 0.0
    assert ds["lyapunov_exponent"].attrs["lyapunov_revolutions"] == 4
    assert ds["lyapunov_exponent"].attrs["units"] == "1"


def test_the_twin_runs_are_planned_and_their_time_is_counted():
    """The plan counts two runs of a block of whole saved rows per revolution after the
    settled window's start (budget.lyapunov_steps), and a run without the key has none."""
    from clearsweep.budget import estimate
    from clearsweep.config import load_config

    doc = {"mechanism": {"speed_rpm": 120.0}, "solver": {"revolutions": 5, "save_every": 10},
           "metrics": {"settle_revolutions": 1, "lyapunov_revolutions": 4}}
    with_twins = estimate(load_config(doc))
    doc["metrics"]["lyapunov_revolutions"] = 0
    without = estimate(load_config(doc))
    # a revolution at 120 r/min is 0.5 s: 50,000 steps of 1e-5 s, 5,000 rows of 10
    assert with_twins.steps - without.steps == 2 * 4 * 50_000
    assert with_twins.rows == without.rows
    doc["metrics"]["lyapunov_revolutions"] = 40          # more than the run holds: 4
    assert estimate(load_config(doc)).steps == with_twins.steps


def test_a_run_too_short_for_one_block_has_no_exponent():
    from clearsweep.simulation import simulate

    ds = simulate({"mechanism": {"preset": "realistic", "speed_rpm": 600.0},
                   "solver": {"revolutions": 1.5},
                   "metrics": {"settle_revolutions": 1, "lyapunov_revolutions": 3}})
    assert np.isnan(float(ds["lyapunov_exponent"]))


@pytest.mark.parametrize("period, k, exponent, expected", [
    (1, 0.10, -0.44, "periodic"),             # 92 r/min
    (0, 0.22, -0.14, "transient"),            # 93 r/min: the spiral onto period 1
    (0, 0.81, 0.026, "quasi-periodic"),       # 94 r/min: K high at 100 samples, lambda ~ 0
    (0, 0.66, -0.026, "transient"),           # 95 r/min: converging onto period 7
    (0, 0.995, 0.55, "chaotic"),              # 96 r/min
    (0, 0.30, 0.55, "undetermined"),          # the indicators disagree
    (-1, np.nan, np.nan, "undetermined"),     # fewer than 2 settled revolutions
    (0, 0.9, np.nan, "chaotic"),              # no exponent: the 0-1 test alone
    (0, 0.1, np.nan, "non-periodic"),
    (3, 0.9, 0.5, "periodic"),                # the period test speaks first
])
def test_the_two_indicators_classify_the_motion(period, k, exponent, expected):
    """The values measured at B 0.25 mm (docs/physics.md section 11.6) and the edge cases."""
    from clearsweep.motion import classify_motion

    assert classify_motion(period, k, exponent) == expected


@pytest.mark.slow
def test_the_onset_between_92_and_96_rpm():
    """Issue 45 item 8: configs/dynamics_map.yaml's case (B at 0.25 mm, uncoated, 110
    revolutions, 10 of start-up), the exponent over 25 settled revolutions. At 92 r/min the
    motion is period 1 and contracts (measured: -0.44 a revolution over 99, -0.43 over 25);
    at 96 r/min it has no period, K near 1 and a positive exponent (measured: K = 0.995,
    +0.55 over 75, +0.64 over 25): the onset of chaos lies between. 103 s on the 2-core
    machine under other work (load average about 20)."""
    import yaml

    from clearsweep.simulation import simulate
    from clearsweep.summary import case_summary

    doc = yaml.safe_load((ROOT / "configs" / "dynamics_map.yaml").read_text())["base"]
    doc["metrics"]["lyapunov_revolutions"] = 25
    found = {}
    for speed in (92.0, 96.0):
        doc["mechanism"]["speed_rpm"] = speed
        summary = case_summary(simulate(doc))
        found[speed] = (int(summary["period"]), float(summary["chaos_k"]),
                        float(summary["lyapunov_exponent"]), str(summary["motion_class"].values))
    period, k, exponent, name = found[92.0]
    assert (period, name) == (1, "periodic") and exponent < -0.2
    period, k, exponent, name = found[96.0]
    assert (period, name) == (0, "chaotic") and k > 0.9 and exponent > 0.3
