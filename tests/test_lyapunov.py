"""The largest Lyapunov exponent by twin runs renormalised once a block (Benettin et al. 1980;
docs/physics.md section 11.4), on systems whose exponent is known: the logistic map, the
forced Duffing oscillator and the ideal mechanism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clearsweep.motion import LYAPUNOV_PERTURBATION, largest_lyapunov


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
