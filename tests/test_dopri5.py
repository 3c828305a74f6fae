"""Adaptive Dormand-Prince 5(4) (solver.method: dopri5, docs/physics.md section 4.4):
convergence with the tolerance, contact-onset location, agreement with RK4, statuses."""

from pathlib import Path

import numpy as np
import pytest

from clearsweep.params import PRESETS, ideal_slider_x
from clearsweep.simulation import simulate

P = PRESETS["realistic"]
SMALL_MAP = {"map": [6, 12]}


def slider_error(rtol):
    """Largest slider-position error against the closed form (ideal joints, no Baumgarte)."""
    ds = simulate({"solver": {"duration": 0.5, "dt": 1e-3, "save_every": 10, "method": "dopri5",
                              "rtol": rtol, "atol_position": 1e-14, "atol_velocity": 1e-14,
                              "atol_energy": 1e-14, "max_step": 0.05, "baumgarte": [0.0, 0.0]},
                   "wear": SMALL_MAP})
    assert str(ds.status.values) == "ok"
    theta = ds.crank_angle.values
    exact = ideal_slider_x(theta, P.crank_length_m, P.rod_length_m, P.slider_height_m)
    return np.abs(ds.slider_position.values - exact).max(), int(ds.rk4_steps)


def test_error_falls_with_the_tolerance_at_the_expected_rate():
    # Error-per-step control of a 5th-order solution: global error ~ rtol^1. Output rows
    # fall between steps (max_step 0.05 s, rows every 0.01 s): the continuous extension
    # is in the measured error too.
    rtols = [1e-6, 1e-7, 1e-8, 1e-9]
    errors, steps = zip(*(slider_error(r) for r in rtols))
    slopes = np.diff(np.log10(errors)) / np.diff(np.log10(rtols))
    assert np.all(slopes > 0.8) and np.all(slopes < 1.5), (errors, slopes)
    assert errors[-1] < 1e-9
    assert list(steps) == sorted(steps)          # tighter tolerance, more steps


def first_impact_at_B(**solver):
    ds = simulate({"joints": {"B": {"clearance": 2.5e-4}}, "initial": {"joints": "centred"},
                   "wear": SMALL_MAP,
                   "solver": dict({"duration": 0.008, "save_every": 10}, **solver)})
    assert str(ds.status.values) == "ok"
    return float(ds.first_impact_time.sel(joint="B"))


@pytest.fixture(scope="module")
def reference_onset():
    """RK4 at dt = 1e-7 s: the ball (centred start) first meets the socket wall within 1e-7 s
    before this time (~5.34 ms)."""
    return first_impact_at_B(dt=1e-7, save_every=1000)


@pytest.mark.parametrize("tolerance", [1e-5, 1e-6, 1e-7])
def test_contact_onset_is_located_within_the_tolerance(reference_onset, tolerance):
    t = first_impact_at_B(method="dopri5", onset_tolerance=tolerance)
    # the step that closes the gap ends after the onset and is at most `tolerance` long
    assert reference_onset - 1e-7 <= t <= reference_onset + tolerance + 1e-7


def test_without_onset_location_the_impact_time_is_off(reference_onset):
    # the same run with steps up to 1e-4 s allowed over an onset: the check above has teeth
    t = first_impact_at_B(method="dopri5", onset_tolerance=1e-4, max_step=1e-4)
    assert abs(t - reference_onset) > 1e-6


@pytest.fixture(scope="module")
def two_clearances():
    base = {"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}},
            "wear": SMALL_MAP}

    def run(**solver):
        return simulate(dict(base, solver=dict({"duration": 0.2}, **solver)))
    return run


def test_agrees_with_rk4_on_two_clearances(two_clearances):
    reference = two_clearances(dt=1e-6, save_every=100)
    ds = two_clearances(method="dopri5")
    for d in (reference, ds):
        assert str(d.status.values) == "ok"
    rms, rms_ref = (float(d.slider_acceleration_rms_settled) for d in (ds, reference))
    assert abs(rms - rms_ref) <= 0.01 * rms_ref
    fn, fn_ref = (d.normal_force_peak_settled.values for d in (ds, reference))
    np.testing.assert_allclose(fn, fn_ref, rtol=0.02)
    np.testing.assert_allclose(ds.wear_volume.values, reference.wear_volume.values, rtol=0.02)
    assert int(ds.rk4_steps) < int(reference.rk4_steps) / 10
    assert float(ds.energy_residual_relative) < 1e-5


def test_statistics_do_not_depend_on_save_every(two_clearances):
    a = two_clearances(method="dopri5", save_every=1)
    b = two_clearances(method="dopri5", save_every=20)
    for name in ("slider_acceleration_peak_settled", "slider_acceleration_rms_settled",
                 "normal_force_peak", "impact_count", "wear_volume", "rk4_steps"):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    # rows both runs have agree: every 20th row of the first is the second's
    np.testing.assert_array_equal(a.slider_position.values[::20], b.slider_position.values)


def test_a_step_the_error_control_cannot_make_is_an_unstable_step_status():
    # paper preset, centred start, PTFE at B: the first impact needs steps far below
    # dt / 2^max_substep_level = 2.25e-7 s
    ds = simulate(Path(__file__).parents[1] / "configs" / "paper_case.yaml",
                  ["initial.joints=centred", "solver.method=dopri5", "solver.dt=9e-7",
                   "solver.max_substep_level=2", "solver.duration=0.02", "solver.save_every=100",
                   "wear.map=[6, 12]"])
    assert str(ds.status.values) == "unstable_step"
    stop = float(ds.attrs["status_time_s"])
    assert 0.0 < stop < 0.02
    after = ds.time.values > stop + 1e-4
    assert after.any() and np.isnan(ds.slider_position.values[after]).all()
