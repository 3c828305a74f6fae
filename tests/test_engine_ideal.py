"""Ideal joints: closed-form kinematics (docs/physics.md section 1), energy/torque balance, RK4 order."""

import numpy as np
import pytest

from clearsweep.params import PRESETS, ideal_slider_x
from clearsweep.simulation import simulate

P = PRESETS["realistic"]
L2, L3, ZS = P.crank_length_m, P.rod_length_m, P.slider_height_m


def closed_form_acceleration(theta, omega):
    """Second time derivative of x_B(theta(t)) at constant omega (docs/physics.md section 1)."""
    x = ideal_slider_x(theta, L2, L3, ZS)
    s, c = np.sin(theta), np.cos(theta)
    d2x = ZS * L2 * c / x - (ZS * L2 * s) ** 2 / x ** 3
    return omega ** 2 * d2x


@pytest.fixture(scope="module")
def ideal_1s():
    return simulate({"solver": {"duration": 1.0, "save_every": 1}})


def test_ideal_runs_ok(ideal_1s):
    assert str(ideal_1s.status.values) == "ok"
    assert int(ideal_1s.substeps_used) == 1


def test_closed_form_endpoints():
    # docs/physics.md section 1: x_B(0) = 0.37947 m, x_B(pi) = 0.27713 m
    assert ideal_slider_x(0.0, L2, L3, ZS) == pytest.approx(0.37947, abs=1e-5)
    assert ideal_slider_x(np.pi, L2, L3, ZS) == pytest.approx(0.27713, abs=1e-5)


def test_slider_position_matches_closed_form(ideal_1s):
    ds = ideal_1s
    theta = 2 * np.pi * ds.time.values  # 60 r/min from theta0 = 0
    np.testing.assert_allclose(ds.crank_angle.values, theta, atol=1e-12)
    err = np.abs(ds.slider_position.values - ideal_slider_x(theta, L2, L3, ZS))
    assert err.max() < 1e-9


def test_slider_acceleration_matches_closed_form(ideal_1s):
    ds = ideal_1s
    theta = ds.crank_angle.values
    expected = closed_form_acceleration(theta, 2 * np.pi)
    err = np.abs(ds.slider_acceleration.values - expected)
    assert err.max() < 1e-7 * np.abs(expected).max()


def test_torque_power_equals_energy_rate(ideal_1s):
    """tau * omega = d/dt (E_kin + E_pot), the rate by 4th-order central differences."""
    ds = ideal_1s
    e = ds.energy_kinetic.values + ds.energy_potential.values
    dt = float(ds.time[1] - ds.time[0])
    rate = (e[:-4] - 8 * e[1:-3] + 8 * e[3:-1] - e[4:]) / (12 * dt)
    power = ds.crank_torque.values[2:-2] * 2 * np.pi
    assert np.abs(power - rate).max() < 1e-6 * np.abs(power).max()
    # the integrated drive work closes the balance too
    assert float(ds.energy_residual_relative) < 1e-9


def test_gravity_free_mechanism_needs_inertial_torque_only():
    """With g = 0 the drive work equals the kinetic energy change."""
    ds = simulate({"mechanism": {"gravity": [0, 0, 0]}, "solver": {"duration": 0.25}})
    ke = ds.energy_kinetic.values
    np.testing.assert_allclose(ds.work_drive.values, ke - ke[0], atol=1e-10)


def test_rk4_fourth_order_convergence():
    """Halving h cuts the slider error 16x (RK4), measured against the closed form."""
    errs = []
    for dt in (4e-3, 2e-3, 1e-3):
        ds = simulate({"mechanism": {"speed_rpm": 60.0},
                       "solver": {"duration": 0.4, "dt": dt, "save_every": int(round(4e-3 / dt)),
                                  "baumgarte": [0.0, 0.0]}})
        exact = ideal_slider_x(2 * np.pi * ds.time.values, L2, L3, ZS)
        errs.append(np.abs(ds.slider_position.values - exact).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 3.7), (errs, orders)
