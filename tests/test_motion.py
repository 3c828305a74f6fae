"""Spectra, period detection and the 0-1 test for chaos (clearsweep.motion), on systems
whose answers are known: the ideal mechanism's closed form, the logistic map and a forced
Duffing oscillator (docs/physics.md section 11)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import synthetic as syn

from clearsweep.analysis import case_summary
from clearsweep.motion import (
    HIGH_ORDER,
    PERIOD_NONE,
    PERIOD_RTOL,
    PERIOD_UNKNOWN,
    ZERO_ONE_MIN_SAMPLES,
    detect_period,
    order_spectrum,
    segment_revolutions,
    spectrum_summary,
    zero_one_test,
)
from clearsweep.params import PRESETS, ideal_slider_x


def closed_form_order_amplitudes(omega: float, orders: np.ndarray, n: int = 1024) -> np.ndarray:
    """Amplitude of each crank order of the ideal slider acceleration [m s-2]: the Fourier
    coefficients of x_B(theta) over one revolution (FFT of n points: exact to rounding for
    orders far below n / 2), times (k omega)^2 (d^2/dt^2 at constant omega)."""
    preset = PRESETS["realistic"]
    theta = 2.0 * np.pi * np.arange(n) / n
    c = np.fft.rfft(ideal_slider_x(theta, preset.crank_length_m, preset.rod_length_m,
                                   preset.slider_height_m))
    return 2.0 * np.abs(c[orders]) / n * (orders * omega) ** 2


@pytest.mark.parametrize("samples_per_revolution, rtol", [(1000, 2e-5), (997.3, 5e-3)])
def test_the_spectrum_of_the_ideal_slider_acceleration_gives_the_closed_forms_fourier_amplitudes(
        samples_per_revolution, rtol):
    """Welch segments of whole revolutions under a periodic Hann window put order k on a bin
    and leak the other harmonics of a periodic signal nothing into it (the window's
    transform is zero 2 bins and more from its centre), so that with a whole number of
    samples a revolution the amplitude sqrt(2 P) of orders 1-7 (down to 2e-5 of order 1)
    matches the closed form to the synthetic series' own error, the central difference's
    (k omega h)^2 / 12 = 4e-6 at order 7. With 997.3 samples a revolution a segment is a
    fraction of a sample off whole revolutions: order k sits delta = 2e-4 k bins off its
    bin and the 6 times larger order k - 1 leaks about delta / 3 of itself into it
    (measured: 2.4e-3 at order 6)."""
    ds = syn.ideal_acceleration_case(samples_per_revolution=samples_per_revolution)
    t = ds["time"].values
    orders, power = order_spectrum(t, ds["slider_acceleration"].values, syn.OMEGA_RAD_S)
    k = np.arange(1, 8)
    expected = closed_form_order_amplitudes(syn.OMEGA_RAD_S, k)
    bins = [int(np.argmin(np.abs(orders - order))) for order in k]
    assert np.abs(orders[bins] / k - 1.0).max() < 5e-4     # half a sample of ~2000
    np.testing.assert_allclose(np.sqrt(2.0 * power[bins]), expected, rtol=rtol)
    dominant, share = spectrum_summary(orders, power)
    assert dominant == pytest.approx(1.0, rel=5e-4)
    assert share < 1e-8        # HIGH_ORDER's reason: the ideal motion has nothing up there


def test_a_window_of_fewer_than_two_revolutions_gives_no_spectrum():
    ds = syn.ideal_acceleration_case(revolutions=1.9)
    orders, power = order_spectrum(ds["time"].values, ds["slider_acceleration"].values,
                                   syn.OMEGA_RAD_S)
    assert orders.size == power.size == 0
    assert np.isnan(spectrum_summary(orders, power)).all()
    assert segment_revolutions(1.999) == 0 and segment_revolutions(2.0) == 2
    assert segment_revolutions(20.0) == 5


def test_the_spectrum_reads_only_the_settled_window():
    """A burst of order-25 content before the settled window is not read."""
    ds = syn.ideal_acceleration_case(revolutions=8.0, settle_s=2.0)
    t = ds["time"].values
    burst = np.where(t < 2.0, 50.0 * np.sin(25.0 * syn.OMEGA_RAD_S * t), 0.0)
    a = ds["slider_acceleration"].values + burst
    settled = spectrum_summary(*order_spectrum(t, a, syn.OMEGA_RAD_S, start=2.0))
    whole = spectrum_summary(*order_spectrum(t, a, syn.OMEGA_RAD_S))
    assert settled[1] < 1e-8
    assert whole[0] == pytest.approx(25.0) and whole[1] > 0.5


def test_the_summary_adds_the_spectrum_with_its_units_where_the_time_series_exists():
    summary = case_summary(syn.ideal_acceleration_case(revolutions=8.0))
    dominant = summary["slider_acceleration_dominant_order"]
    share = summary["slider_acceleration_high_order_share"]
    assert float(dominant) == pytest.approx(1.0)
    assert float(share) < 1e-8
    assert dominant.attrs["units"] == share.attrs["units"] == "1"
    assert share.attrs["high_order"] == HIGH_ORDER
    # the synthetic run of 0.2 s at one revolution a second: too short, NaN
    assert np.isnan(case_summary(syn.one_case())["slider_acceleration_dominant_order"])


@pytest.mark.parametrize("r, period", [(3.2, 2), (3.5, 4), (3.83, 3), (2.9, 1)])
def test_the_logistic_map_in_a_periodic_window_has_its_period(r, period):
    assert detect_period(syn.logistic_orbit(r, 40)) == period


@pytest.mark.parametrize("r", [3.9, 4.0])
def test_the_chaotic_logistic_map_has_no_period_and_k_near_one(r):
    orbit = syn.logistic_orbit(r, 1000)
    assert detect_period(orbit[-40:]) == PERIOD_NONE
    assert zero_one_test(orbit) > 0.95


@pytest.mark.parametrize("r", [3.2, 3.5, 3.83])
def test_the_periodic_logistic_map_has_k_near_zero(r):
    assert zero_one_test(syn.logistic_orbit(r, 1000)) < 0.05


def test_the_zero_one_test_is_deterministic_and_needs_enough_samples():
    orbit = syn.logistic_orbit(4.0, 500)
    assert zero_one_test(orbit) == zero_one_test(orbit)
    assert np.isnan(zero_one_test(orbit[:ZERO_ONE_MIN_SAMPLES - 1]))
    assert zero_one_test(np.full(500, 0.3)) == 0.0      # a fixed point


def test_too_few_or_nan_samples_have_no_period():
    assert detect_period(np.array([1.0])) == PERIOD_UNKNOWN
    assert detect_period(np.array([1.0, np.nan, 1.0, 1.0])) == PERIOD_UNKNOWN
    # period 5 needs 10 samples to show each point twice
    five = np.tile([1.0, 2.0, 3.0, 4.0, 5.0], 2)
    assert detect_period(five) == 5 and detect_period(five[:9]) == PERIOD_NONE


def test_points_within_the_tolerance_are_one_point():
    noisy = 1.0 + 1e-3 * np.sin(np.arange(20.0))       # 0.1 % wobble: PERIOD_RTOL is 1 %
    assert detect_period(noisy) == 1
    assert detect_period(noisy, rtol=1e-4) == PERIOD_NONE
    # a feature scaled by the clearance: 0.8 % of it apart is the same point
    offsets = np.stack([np.full(20, 0.3), 0.3 + 0.004 * (-1.0) ** np.arange(20)], axis=1)
    assert detect_period(offsets, scale=1.0) == 1
    assert detect_period(offsets, scale=0.1) == 2


def duffing_section(gamma: float, n: int, skip: int = 200, y0=(1.0, 0.0)) -> np.ndarray:
    """x'' + 0.3 x' - x + x^3 = gamma cos(1.2 t) (Ueda / Holmes), sampled once a forcing
    period after ``skip`` periods: (n, 2) of (x, x')."""
    from scipy.integrate import solve_ivp

    period = 2.0 * np.pi / 1.2
    times = np.arange(skip, skip + n) * period
    solution = solve_ivp(lambda t, y: (y[1], -0.3 * y[1] + y[0] - y[0] ** 3 + gamma * np.cos(1.2 * t)),
                         (0.0, times[-1]), y0, t_eval=times, rtol=1e-9, atol=1e-11, method="DOP853")
    return solution.y.T


@pytest.mark.parametrize("y0", [(1.0, 0.0), (-0.5, 0.2)])
def test_a_weakly_forced_duffing_oscillator_is_period_one_and_regular(y0):
    """gamma = 0.1: a period-1 orbit in one well (measured: K = 0 from three starts)."""
    section = duffing_section(0.1, 300, y0=y0)
    assert detect_period(section[-40:]) == 1
    assert zero_one_test(section[:, 0]) < 0.05


def test_a_duffing_oscillator_at_gamma_065_is_period_two():
    section = duffing_section(0.65, 60)
    assert detect_period(section[-40:]) == 2


@pytest.mark.parametrize("y0", [(1.0, 0.0), (0.1, 0.1)])
def test_the_chaotic_duffing_oscillator_has_no_period_and_k_near_one(y0):
    """gamma = 0.5: the Ueda / Holmes strange attractor (measured: K = 0.99 from three
    starts over 1000 periods, 0.88-0.94 over 300)."""
    section = duffing_section(0.5, 600, y0=y0)
    assert detect_period(section[-40:]) == PERIOD_NONE
    assert zero_one_test(section[:, 0]) > 0.8


def test_the_spectrum_of_a_real_ideal_run_gives_the_closed_forms_fourier_amplitudes():
    """The ideal mechanism run by the kernel at 12000 r/min (one revolution every 500 steps
    of 1e-5 s, every step saved), 5 revolutions, the first cut: 4 settled revolutions, two
    segments of 2 under Hann windows, so every integer order on a bin and no leakage between
    them. What remains is the run's own error against the closed form (RK4, constraint
    stabilisation): measured 1.5e-8 at order 1 and 1.1e-6 at order 7 (1e-4 of order 1)."""
    from clearsweep.config import load_config
    from clearsweep.simulation import simulate

    cfg = load_config(Path(__file__).resolve().parents[1] / "configs" / "ideal.yaml", overrides=[
        "mechanism.speed_rpm=12000", "solver.duration=0.025", "solver.save_every=1",
        "metrics.settle_time=0.005"])
    ds = simulate(cfg)
    t = ds["time"].values
    omega = cfg.mechanism.omega_rad_s
    orders, power = order_spectrum(t, ds["slider_acceleration"].values, omega, start=0.005)
    k = np.arange(1, 8)
    bins = [int(np.argmin(np.abs(orders - order))) for order in k]
    np.testing.assert_allclose(orders[bins], k, rtol=1e-9)
    np.testing.assert_allclose(np.sqrt(2.0 * power[bins]),
                               closed_form_order_amplitudes(omega, k), rtol=1e-5)
    summary = case_summary(ds)
    assert float(summary["slider_acceleration_dominant_order"]) == pytest.approx(1.0)
    assert float(summary["slider_acceleration_high_order_share"]) < 1e-8


def test_the_settled_window_of_a_sweep_case_comes_from_its_swept_key_or_the_base_config():
    import xarray as xr

    from clearsweep.analysis import settle_time

    assert settle_time(xr.Dataset(attrs={"settle_time_s": 0.2})) == 0.2
    # configs/bifurcation.yaml zips metrics.settle_time with the speed: a coordinate per case
    assert settle_time(xr.Dataset(coords={"metrics_settle_time": 0.4})) == 0.4
    assert settle_time(xr.Dataset(attrs={"sweep_config": "base: {metrics: {settle_time: 0.3}}"})) == 0.3
    assert settle_time(xr.Dataset(attrs={"sweep_config": "base: {name: x}"})) == 0.05   # default
    assert settle_time(xr.Dataset()) == 0.0


def test_a_sweep_cases_settled_window_in_revolutions_is_resolved_at_its_speed():
    """configs/bifurcation.yaml gives metrics.settle_revolutions in its base and sweeps the
    speed: the window of each case starts 10 revolutions in, at that case's speed."""
    import xarray as xr

    from clearsweep.analysis import settle_time, settled_revolutions

    base = "base: {solver: {revolutions: 110}, metrics: {settle_revolutions: 10}}"
    case = xr.Dataset(coords={"speed_rpm": 120.0}, attrs={"sweep_config": base})
    assert settle_time(case) == 5.0 and settled_revolutions(case) == 100.0
    # a swept key replaces the base's length, in either unit
    assert settle_time(case.assign_coords(metrics_settle_time=0.5)) == 0.5
    swept = case.assign_coords(metrics_settle_revolutions=4.0, revolutions=5.0)
    assert settle_time(swept) == 2.0 and settled_revolutions(swept) == 1.0
    # a run's own config text: the speed in it, no sweep
    run = xr.Dataset(attrs={"config": "mechanism: {speed_rpm: 30}\nmetrics: {settle_time: null, "
                                      "settle_revolutions: 1}\nsolver: {duration: 5}"})
    assert settle_time(run) == 2.0 and settled_revolutions(run) == 1.5


def test_the_poincare_samples_of_the_ideal_mechanism_are_one_point_period_one():
    """Issue 31's check, end to end once the kernel stores the Poincaré samples: the ideal
    mechanism's motion repeats every revolution, so its samples are one point (period 1;
    the offsets of its ideal joints NaN)."""
    from clearsweep.config import load_config
    from clearsweep.simulation import simulate

    cfg = load_config(Path(__file__).resolve().parents[1] / "configs" / "ideal.yaml", overrides=[
        "mechanism.speed_rpm=12000", "solver.duration=0.03", "metrics.settle_time=0.005"])
    ds = simulate(cfg)
    if "poincare_slider_acc" not in ds:
        pytest.skip("this kernel stores no Poincaré samples")
    summary = case_summary(ds)
    assert int(summary["period"]) == 1
    assert np.isnan(ds["poincare_offset"].values).all()
    a = ds["poincare_slider_acc"].values
    a = a[np.isfinite(a)]
    assert np.ptp(a[1:]) <= 1e-6 * np.abs(a).max()


def decaying_spiral(n: int, skip: int = 0, rate: float = 0.995, amplitude: float = 0.1) -> np.ndarray:
    """Poincaré samples (n, 2) of a slowly decaying spiral around the fixed point (1.0, 0.5):
    each revolution turns a third of a turn (plus a little) and keeps ``rate`` of the
    distance, from ``amplitude`` at revolution 0; the samples from revolution ``skip`` on."""
    k = np.arange(skip, skip + n)
    turn = 2.0 * np.pi / 3.0 + 0.01
    radius = amplitude * rate ** k
    return np.stack([1.0 + radius * np.cos(turn * k), 0.5 + radius * np.sin(turn * k)], axis=1)


def test_a_slowly_decaying_spiral_is_not_period_three_until_it_has_settled():
    """Issue 45 item 8: at 93 r/min a slowly decaying spiral read as period 3 (every point
    within 1 % of the one 3 revolutions before), and as period 1 after 1,000 revolutions.
    Over the window each of its three points drifts by 40 % of its amplitude: no period;
    once it has decayed below the tolerance, period 1."""
    early = decaying_spiral(101, skip=10)
    # what the old rule read: each point within the tolerance of the one 3 revolutions before
    assert (np.abs(early[3:] - early[:-3]) <= PERIOD_RTOL).all()
    assert detect_period(early, scale=1.0) == PERIOD_NONE
    late = decaying_spiral(101, skip=1000)
    assert detect_period(late, scale=1.0) == 1


def test_a_spiral_that_converges_within_the_tolerance_is_not_period_three():
    """The 93 r/min case (B at 0.25 mm): a spiral turning about a third of a turn a revolution
    and keeping 0.87 of its distance (the exponent measured there, -0.14 a revolution),
    from 0.8 % of the scale. Each of its three phases stays within the 1 % tolerance over
    the window, but they converge on one point: not three distinct points. Period 1 once
    it has settled."""
    spiral = decaying_spiral(101, rate=0.87, amplitude=0.008)
    # each phase within the tolerance over the whole window, the samples together not
    assert all((np.ptp(spiral[r::3], axis=0) <= PERIOD_RTOL).all() for r in range(3))
    assert np.ptp(spiral, axis=0).max() > PERIOD_RTOL
    assert detect_period(spiral, scale=1.0) == PERIOD_NONE
    assert detect_period(decaying_spiral(101, skip=100, rate=0.87, amplitude=0.008),
                         scale=1.0) == 1


def test_a_period_is_its_points_spread_over_the_whole_window():
    """A period-2 orbit whose two points creep by 0.3 % of the scale a revolution: within the
    tolerance of the point 2 revolutions before, but 30 % apart over 100 revolutions."""
    k = np.arange(100)
    creeping = (-1.0) ** k + 3e-3 * k
    assert detect_period(creeping, scale=1.0) == PERIOD_NONE
    assert detect_period(creeping[:4], scale=1.0) == 2
