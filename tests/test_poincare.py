"""Poincare sections (docs/physics.md 8.4): one per crank revolution, read by the kernel at
the section time within the (sub-)step that holds it.

Runs are short: at 600 r/min a revolution takes 0.1 s; the interpolation checks put one
section at about 0.05 s of a 60 r/min run with the phase.
"""

from pathlib import Path

import numpy as np
import pytest

from clearsweep.config import load_config
from clearsweep.core import layout as L
from clearsweep.params import kernel_build
from clearsweep.simulation import preflight, prepare_kernel, simulate
from clearsweep.variables import POINCARE, STATISTICS

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
FAST = ["mechanism.speed_rpm=600", "solver.duration=0.3"]


def phase_at(t: float, rpm: float = 60.0) -> float:
    """The section angle [degree] whose first section (theta0 = 0) falls at time t."""
    return float(np.degrees(rpm * 2.0 * np.pi / 60.0 * t))


def test_ideal_sections_are_period_one():
    """The ideal mechanism is periodic with the crank: every revolution's section is the
    same point (slider acceleration to 1e-9 relative), at t_k = k T; an ideal joint has no
    offset (NaN)."""
    ds = simulate(str(CONFIGS / "ideal.yaml"), FAST)
    np.testing.assert_array_equal(ds.revolution.values, [1, 2, 3])
    np.testing.assert_allclose(ds.poincare_time.values, [0.1, 0.2, 0.3], rtol=1e-12)
    acc = ds.poincare_slider_acc.values
    np.testing.assert_allclose(acc[1:], acc[0], rtol=1e-9)
    assert np.isnan(ds.poincare_offset.values).all()
    assert np.isnan(ds.poincare_velocity.values).all()
    for name, spec in POINCARE.items():
        assert ds[name].dims == spec.dims and ds[name].attrs["units"] == spec.units


def test_section_between_step_ends_matches_a_run_whose_grid_hits_it():
    """A section a third of a step past a step end, interpolated, against the same section
    of a run whose step is chosen so that it is a step end (its end state, no interpolation).

    Ideal mechanism: the slider acceleration agrees to 1e-8 relative. The cubic Hermite of
    the state has a local error ~ h^4 |y''''| / 384, about 1e-17 m here (omega^4 l2 h^4 /
    384), and the acceleration, the derivative of the slider velocity's Hermite, one of
    O(h^3 |a'''|), about 1e-13 m s-2: nothing at 1e-8; what is left is the two runs'
    rounding and O(h^4) differences.
    The nearest saved rows, one step apart, differ by 1e-5 relative. One clearance joint
    (B, seated): the offset / c agrees to 1e-7; its rate to 2e-4 s-1 (of 0.27 s-1),
    the two step sizes' difference in the seated contact's fast normal mode, not the
    interpolation."""
    h = 1e-5
    tk = 0.05 + 0.37 * h
    n = round(tk / h)
    hb = float(tk / n)
    for name in ("ideal.yaml", "one_clearance.yaml"):
        common = [f"outputs.poincare_phase_deg={phase_at(tk)!r}", "solver.save_every=1"]
        a = simulate(str(CONFIGS / name), common + ["solver.duration=0.06"])
        b = simulate(str(CONFIGS / name), common + [f"solver.dt={hb!r}",
                                                    f"solver.duration={n * hb!r}"])
        assert float(a.poincare_time[0]) == pytest.approx(tk, rel=1e-12)
        assert float(b.poincare_time[0]) == pytest.approx(tk, rel=1e-12)
        # b's section is its last step's end: its saved row (to 1e-9: the section is
        # evaluated with the contact state after the step, whose damping may have moved)
        assert float(b.poincare_slider_acc[0]) == pytest.approx(float(b.slider_acceleration[-1]),
                                                                rel=1e-9)
        acc_a, acc_b = float(a.poincare_slider_acc[0]), float(b.poincare_slider_acc[0])
        if name == "ideal.yaml":
            assert acc_a == pytest.approx(acc_b, rel=1e-8)
            i = int(np.searchsorted(a.time.values, tk))
            rows = a.slider_acceleration.values[i - 1:i + 1]
            assert abs(rows[1] - rows[0]) > 100 * 1e-8 * abs(acc_b)
        else:
            np.testing.assert_allclose(a.poincare_offset.sel(joint="B").values,
                                       b.poincare_offset.sel(joint="B").values, rtol=0, atol=1e-7)
            np.testing.assert_allclose(b.poincare_offset.sel(joint="B").values[0],
                                       b.ball_offset.sel(joint="B").values[-1] / 2.5e-4,
                                       rtol=1e-9)
            np.testing.assert_allclose(a.poincare_velocity.sel(joint="B").values,
                                       b.poincare_velocity.sel(joint="B").values, rtol=0, atol=2e-4)
            assert np.isnan(a.poincare_offset.sel(joint="A").values).all()


def test_sections_and_statistics_do_not_depend_on_save_every():
    # 30,100 steps: whole samples of 7 steps (a duration is rounded up to whole samples)
    runs = [simulate(str(CONFIGS / "one_clearance.yaml"),
                     ["mechanism.speed_rpm=600", "solver.duration=0.301", f"solver.save_every={n}"])
            for n in (1, 7)]
    assert runs[0].sizes["revolution"] == 3
    for name in (*POINCARE, *STATISTICS):
        np.testing.assert_array_equal(runs[0][name].values, runs[1][name].values, err_msg=name)
    assert np.isfinite(runs[0].poincare_offset.sel(joint="B").values).all()


def test_taking_sections_changes_nothing_else():
    """The same run with its section rows and with none (Out.sec of no rows): every other
    output is equal bit for bit (a section reads the run's arrays, writes only its row)."""
    from clearsweep.core.rk4 import integrate
    from clearsweep.core.work import Case, Out

    cfg = load_config(str(CONFIGS / "two_clearances.yaml"),
                      ["initial.joints=centred", "solver.duration=0.02", "mechanism.speed_rpm=3000"])
    packed = preflight(cfg)
    build = kernel_build(cfg)
    prepare_kernel("rk4", build)
    results = []
    for rows in (0, 1):
        n_save = packed.n_steps // packed.save_every + 1
        arrays = [np.full(n_save, np.nan), np.full((n_save, L.N_Y), np.nan),
                  np.full((n_save, L.N_D), np.nan), np.zeros((n_save, L.N_JOINTS)),
                  np.zeros(L.N_INFO, dtype=np.int64), np.zeros((L.N_WINDOWS, L.N_M)),
                  np.zeros(L.N_TRACK), np.zeros(L.N_JOINTS), np.full((rows, L.N_SEC), np.nan)]
        wear = [np.zeros((L.N_JOINTS,) + packed.map_shape), np.zeros((L.N_JOINTS, 3, L.N_ANGLE_BINS)),
                np.zeros(L.N_JOINTS)]
        res = integrate(Case(packed.p, packed.jp, packed.y0, *wear), 0.0, packed.n_steps,
                        packed.save_every, Out(*arrays), build)
        results.append((arrays, wear, res))
    (a0, w0, r0), (a1, w1, r1) = results
    assert np.isfinite(a1[-1][0, L.SEC_OFFSET:L.SEC_OFFSET + 6]).all()   # a section taken
    assert (a0[4][L.I_SECTIONS], a1[4][L.I_SECTIONS]) == (0, 1)            # and counted
    a0[4][L.I_SECTIONS] = a1[4][L.I_SECTIONS] = 0
    for x, y in zip(a0[:-1] + w0 + [r0], a1[:-1] + w1 + [r1]):
        np.testing.assert_array_equal(x, y)


def test_dopri5_takes_the_same_sections():
    """The adaptive integrator reads its sections from its continuous extension: the same
    time, the offset to 1e-5 of c, the slider acceleration to 1e-3 (the seated contact's
    fast normal mode, resolved differently by the two integrators' steps)."""
    runs = [simulate(str(CONFIGS / "one_clearance.yaml"),
                     ["solver.duration=0.06", f"outputs.poincare_phase_deg={phase_at(0.05)!r}",
                      f"solver.method={m}"]) for m in ("rk4", "dopri5")]
    assert float(runs[1].poincare_time[0]) == float(runs[0].poincare_time[0])
    np.testing.assert_allclose(runs[1].poincare_offset.sel(joint="B").values,
                               runs[0].poincare_offset.sel(joint="B").values, atol=1e-5)
    assert float(runs[1].poincare_slider_acc[0]) == pytest.approx(
        float(runs[0].poincare_slider_acc[0]), rel=1e-3)


def test_a_run_shorter_than_its_first_section_has_none():
    ds = simulate(str(CONFIGS / "one_clearance.yaml"), ["solver.duration=0.01"])
    assert not any(name in ds for name in POINCARE) and "revolution" not in ds.dims


@pytest.mark.parametrize("value", ["360", "-1", "nan", "'x'"])
def test_bad_phase_is_one_line_naming_the_key(value):
    from clearsweep.config import ConfigError

    with pytest.raises(ConfigError, match="outputs.poincare_phase_deg") as info:
        load_config(str(CONFIGS / "ideal.yaml"), [f"outputs.poincare_phase_deg={value}"])
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("store", ["summary", "full"])
def test_a_sweep_keeps_the_sections_padded_to_its_longest_case(tmp_path, store):
    """A sweep over crank speed at a fixed duration: 2 and 4 revolutions; both stores keep
    the sections, the shorter case padded with NaN."""
    from clearsweep.sweeping import run_sweep

    doc = {"name": "speeds", "store": store,
           "base": {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.2},
                    "wear": {"map": [6, 12]}},
           "sweep": {"grid": {"mechanism.speed_rpm": [600.0, 1200.0]}}}
    ds = run_sweep(doc, tmp_path / "s.nc", workers=1, progress=False)
    np.testing.assert_array_equal(ds.revolution.values, [1, 2, 3, 4])
    times = ds.poincare_time.transpose("speed_rpm", "revolution").values
    np.testing.assert_allclose(times[0, :2], [0.1, 0.2], rtol=1e-12)
    assert np.isnan(times[0, 2:]).all()
    np.testing.assert_allclose(times[1], [0.05, 0.1, 0.15, 0.2], rtol=1e-12)
    offset = ds.poincare_offset.sel(joint="B").transpose("speed_rpm", "revolution", "axis").values
    assert np.isfinite(offset[1]).all() and np.isfinite(offset[0, :2]).all()
    assert np.isnan(offset[0, 2:]).all()
    assert ds.poincare_offset.attrs["units"] == "1" and ds.poincare_velocity.attrs["units"] == "s-1"
