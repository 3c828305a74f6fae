"""Clearance joints: energy bookkeeping, status codes, wear (docs/physics.md sections 3-5, 8)."""

import math

import mpmath
import numpy as np
import pytest

from clearsweep.config import ConfigError
from clearsweep.core.spherical import contact_angle, contact_area
from clearsweep.core.wear import bin_area, map_bin, projection_bins
from clearsweep.simulation import simulate

CLEAR = 2.5e-4
ONE = {"joints": {"B": {"clearance": CLEAR}}}
TWO = {"joints": {"A": {"clearance": CLEAR}, "B": {"clearance": CLEAR}}}


def with_solver(cfg, **solver):
    out = {k: v for k, v in cfg.items()}
    out["solver"] = dict(cfg.get("solver", {}), **solver)
    return out


@pytest.fixture(scope="module")
def one_clearance():
    return simulate(with_solver(ONE, duration=1.0))


@pytest.fixture(scope="module")
def two_clearances(two_clearances_1s):
    """One crank turn with clearance at A and B (tests/conftest.py, shared with
    test_statistics)."""
    return two_clearances_1s


@pytest.mark.parametrize("name", ["one_clearance", "two_clearances"])
def test_default_step_is_stable_and_closes_energy(name, request):
    ds = request.getfixturevalue(name)
    assert str(ds.status.values) == "ok"
    assert float(ds.energy_residual_relative) < 1e-5
    assert np.isfinite(ds.slider_acceleration.values).all()
    assert float(ds.normal_force.sel(joint="B").max()) > 0.0


def test_ideal_joint_of_one_clearance_case_has_no_contact_or_wear(one_clearance):
    a = one_clearance.sel(joint="A")
    assert float(abs(a.normal_force).max()) == 0.0
    assert float(abs(a.wear_map).max()) == 0.0
    assert float(abs(a.wear_projection).max()) == 0.0


@pytest.mark.parametrize("name", ["one_clearance", "two_clearances"])
def test_wear_is_positive_finite_and_non_decreasing(name, request):
    ds = request.getfixturevalue(name)
    for j in ("A", "B"):
        if j == "A" and name == "one_clearance":
            continue
        w = ds.wear_depth_max.sel(joint=j).values
        assert np.isfinite(w).all() and w[-1] > 0.0
        assert np.all(np.diff(w) >= 0.0)


@pytest.mark.parametrize("name", ["one_clearance", "two_clearances"])
def test_wear_map_sum_rule(name, request):
    """sum(depth * bin area) equals the worn volume sum(k F_N dS), to round-off."""
    ds = request.getfixturevalue(name)
    npol, naz = ds.sizes["polar"], ds.sizes["azimuth"]
    areas = np.array([bin_area(i, npol, naz, 0.015) for i in range(npol)])
    for j in ("A", "B"):
        volume = float((ds.wear_map.sel(joint=j).values * areas[:, None]).sum())
        assert volume == pytest.approx(float(ds.wear_volume.sel(joint=j)), rel=1e-12, abs=1e-30)


def test_paper_preset_two_clearances_never_returns_diverged_ok():
    """Paper inertia (docs/physics.md section 1.1): stable through sub-stepping, or stopped with unstable_step."""
    ds = simulate(dict(TWO, mechanism={"preset": "paper"}, solver={"duration": 0.05}))
    status = str(ds.status.values)
    assert status in ("ok", "unstable_step")
    n = int(np.isfinite(ds.slider_position.values).sum())
    if status == "ok":
        assert float(ds.energy_residual_relative) < 1e-5
    else:
        assert n < ds.sizes["time"]  # rows after the stop are NaN, not plausible numbers
        assert np.isnan(ds.slider_position.values[-1])
    assert int(ds.substeps_used) > 1


def test_level_cap_reports_unstable_step():
    """Measured: from the centred start, the paper preset's free rod outgrows 2^8 sub-steps
    of h = 1e-5 s at its first impacts (~17.5 ms)."""
    ds = simulate(dict(TWO, mechanism={"preset": "paper"}, solver={"duration": 0.03},
                       initial={"joints": "centred"}))
    assert str(ds.status.values) == "unstable_step"
    assert 0.0 < ds.attrs["status_time_s"] < 0.03


def test_too_large_step_is_a_config_error():
    from clearsweep.config import ConfigError

    with pytest.raises(ConfigError, match="solver.dt"):
        simulate(with_solver(TWO, dt=0.01, duration=0.1))


def test_penetration_limit_stops_the_case():
    ds = simulate(dict(ONE, contact={"max_penetration_fraction": 1e-3}, solver={"duration": 0.3}))
    assert str(ds.status.values) == "penetration_exceeded"


def test_results_are_bit_identical_between_runs():
    a = simulate(with_solver(TWO, duration=0.05))
    b = simulate(with_solver(TWO, duration=0.05))
    for name in a.data_vars:
        if name != "wall_time":
            np.testing.assert_array_equal(a[name].values, b[name].values)


# --- wear law (docs/physics.md section 5, paper Eq. 11-15) ----------------------------------------------

@pytest.mark.parametrize("delta", [1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5])
def test_contact_area_without_cancellation(delta):
    """Eq. 11-13 in 60-digit arithmetic vs the cancellation-free double evaluation."""
    mpmath.mp.dps = 60
    ri = mpmath.mpf("0.015")
    rj = ri - mpmath.mpf("2.5e-4")
    e = mpmath.mpf("2.5e-4") + mpmath.mpf(delta)
    cosb = (e ** 2 + rj ** 2 - ri ** 2) / (2 * rj * e)      # Eq. 11
    hc = rj * (1 + cosb)                                     # Eq. 12
    cb2 = (rj * mpmath.sin(mpmath.acos(cosb))) ** 2
    a_eq13 = mpmath.pi * (cb2 + hc ** 2)                     # Eq. 13
    got = contact_area(delta, CLEAR + delta, 0.015, 0.015 - CLEAR)
    assert float(abs(got - a_eq13) / a_eq13) < 1e-12
    # and Eq. 13 is exactly 2 pi R_j h_c
    assert float(abs(a_eq13 - 2 * mpmath.pi * rj * hc) / a_eq13) < 1e-40
    beta = contact_angle(delta, CLEAR + delta, 0.015, 0.015 - CLEAR)
    assert float(abs(beta - mpmath.acos(cosb)) / (mpmath.pi - mpmath.acos(cosb))) < 1e-9


def test_no_contact_no_wear():
    # balls start centred and are still in flight: no contact yet
    ds = simulate(dict(with_solver(TWO, duration=0.002), initial={"joints": "centred"}))
    assert float(ds.normal_force.max()) == 0.0
    assert float(ds.wear_map.max()) == 0.0 and float(ds.wear_projection.max()) == 0.0


def test_wear_scales_linearly_with_coefficient_and_amplification():
    """k and the amplification enter as one product: doubling either gives the same run,
    bit for bit, and about twice the wear (not exactly: the worn map feeds back into the
    contact, docs/physics.md section 5)."""
    base = simulate(with_solver(ONE, duration=0.2))
    k2 = simulate(dict(with_solver(ONE, duration=0.2),
                       joints={"B": {"clearance": CLEAR, "wear_coefficient": 1.6e-13}}))
    amp = simulate(dict(with_solver(ONE, duration=0.2), wear={"amplification": 2.0}))
    np.testing.assert_array_equal(k2.wear_map.values, amp.wear_map.values)
    np.testing.assert_array_equal(k2.wear_projection.values, amp.wear_projection.values)
    ratio = float(amp.wear_volume.sel(joint="B") / base.wear_volume.sel(joint="B"))
    assert ratio == pytest.approx(2.0, rel=1e-3)
    no_feedback = simulate(dict(with_solver(ONE, duration=0.05), wear={"amplification": 2.0}))
    short = simulate(with_solver(ONE, duration=0.05))
    # early on the feedback is negligible: the worn volume doubles to 1e-6
    assert float(no_feedback.wear_volume.sel(joint="B")) == pytest.approx(
        2.0 * float(short.wear_volume.sel(joint="B")), rel=1e-6)


def test_steady_press_wears_only_bins_under_the_load():
    """Gravity along -Y presses the rod's ball sideways into B's socket at a crawling crank."""
    ds = simulate({"mechanism": {"speed_rpm": 0.01, "gravity": [0.0, -9.81, 0.0]},
                   "joints": {"B": {"clearance": CLEAR}},
                   "contact": {"restitution": 0.3},
                   "solver": {"duration": 0.3}})
    assert str(ds.status.values) == "ok"
    wm = ds.wear_map.sel(joint="B")
    assert float(wm.max()) > 0
    worn = wm.where(wm > 0, drop=True)
    # -Y in the slider (socket) frame: polar 90 deg, azimuth -90 deg
    assert float(abs(worn.polar - 90.0).max()) <= 5.0
    assert float(abs(worn.azimuth + 90.0).max()) <= 5.0


@pytest.mark.parametrize("n, bins", [
    ((0.0, 1.0, 0.0), (180, None, 270)),   # about x: atan2(0, 1) = 0 deg -> bin 180
    ((1.0, 0.0, 0.0), (None, 270, 180)),   # about y: atan2(1, 0) = 90 deg -> bin 270
    ((0.0, 0.0, -1.0), (90, 0, None)),     # about x: -90 deg -> bin 90; about y: 180 -> wraps
])
def test_known_direction_lands_in_projection_bins(n, bins):
    got = projection_bins(n, 360)
    for axis, expected in enumerate(bins):
        if expected is not None:
            assert got[axis] in (expected, (expected - 1) % 360), (axis, got)


def test_map_bin_of_known_directions():
    assert map_bin((0.0, 0.0, 1.0), 36, 72)[0] == 0
    assert map_bin((0.0, 0.0, -1.0), 36, 72)[0] == 35
    ip, ia = map_bin((0.0, -1.0, 0.0), 36, 72)
    assert ip in (17, 18) and ia in (17, 18)
    total = sum(bin_area(i, 36, 72, 1.0) for i in range(36)) * 72
    assert total == pytest.approx(4 * math.pi, rel=1e-12)


def test_stop_time_is_the_failing_step_not_the_last_saved_row():
    ds = simulate(dict(ONE, contact={"max_penetration_fraction": 1e-3}, solver={"duration": 0.3}))
    assert str(ds.status.values) == "penetration_exceeded"
    finite = ds.time.values[np.isfinite(ds.slider_position.values)]
    stop = ds.attrs["status_time_s"]
    assert finite[-1] < stop <= finite[-1] + 10 * 1e-5 + 1e-12
    assert np.isnan(ds.slider_position.values[-1])


@pytest.mark.parametrize("duration, simulated", [(1.5e-4, 2e-4), (1e-3, 1e-3)])
def test_duration_rounds_up_to_whole_output_samples(duration, simulated):
    ds = simulate({"solver": {"duration": duration}})
    assert ds.attrs["simulated_duration_s"] == pytest.approx(simulated, rel=1e-12)
    assert float(ds.time[-1]) == pytest.approx(simulated, rel=1e-12)


def test_a_run_shorter_than_one_output_sample_is_refused_not_stretched():
    # 2 steps with save_every 10 would run 10 steps, 5x the duration asked
    with pytest.raises(ConfigError, match=r"solver\.save_every: got 10; expected an integer <= 2 "):
        simulate({"solver": {"duration": 2e-5}})
    ds = simulate({"solver": {"duration": 2e-5, "save_every": 2}})
    assert ds.attrs["simulated_duration_s"] == pytest.approx(2e-5, rel=1e-12)
