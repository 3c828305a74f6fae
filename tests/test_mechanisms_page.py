"""docs/mechanisms.md's claims: the slider-crank's closed-form numbers, the shipped benchmark
config's run (ok, in the plane, the impacts' tenfold peak acceleration), its Baumgarte
constants holding the constraints at a longer step, and the pins staying in the plane without
friction; the page's figures and the script that draws them."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from clearsweep import simulate
from clearsweep.config import load_config
from clearsweep.params import PRESETS, slider_crank_kinematics

ROOT = Path(__file__).resolve().parents[1]
PAGE = (ROOT / "docs" / "mechanisms.md").read_text()
CONFIG = ROOT / "configs" / "slider_crank.yaml"
PRESET = PRESETS["flores_benchmark"]
OMEGA = 5000.0 * 2.0 * math.pi / 60.0


def kinematics(theta):
    return slider_crank_kinematics(theta, OMEGA, PRESET.crank_length_m, PRESET.rod_length_m,
                                   PRESET.slider_height_m)


def test_the_closed_form_numbers_of_the_page():
    """TDC and BDC accelerations as the textbook's r w^2 (1 +- l2/l3), the positive maximum
    away from BDC (l2/l3 > 1/4), the largest speed and the acceleration's sign changes."""
    r, l = PRESET.crank_length_m, PRESET.rod_length_m
    theta = np.radians(np.arange(0.0, 360.0, 0.01))
    s, v, a = kinematics(theta)
    assert kinematics(math.pi / 2)[2] == pytest.approx(-r * OMEGA ** 2 * (1 + r / l), rel=1e-12)
    assert kinematics(3 * math.pi / 2)[2] == pytest.approx(r * OMEGA ** 2 * (1 - r / l), rel=1e-12)
    assert (s.min(), s.max()) == pytest.approx((l - r, l + r), abs=1e-12)
    for text in ("-19,419 m/s^2", "+7,996 m/s^2", "+9,696 m/s^2", "28.41 m/s"):
        assert text in PAGE
    assert round(float(a.max())) == 9696 and round(float(np.degrees(theta[a.argmax()]))) == 212
    assert round(float(np.abs(v).max()), 2) == 28.41
    zeros = np.degrees(theta[np.nonzero(np.diff(np.sign(a)))[0]])
    assert np.round(zeros, 1).tolist() == [19.8, 160.2]
    assert "theta = 19.8 and 160.2 degree" in PAGE


def test_the_page_names_each_preset_value_and_its_figures():
    cfg = load_config(CONFIG)
    assert cfg.mechanism.kind == "slider_crank" and cfg.mechanism.preset == "flores_benchmark"
    table = PAGE.split("## The preset and its sources", 1)[1].split("## The benchmark's", 1)[0]
    for value in ("0.05 m", "0.12 m", "0.30, 0.21, 0.14 kg", "1e-4, 2.5e-4, 1e-4 kg m^2",
                  "10.0 and 9.5 mm", "0.5 mm", "5000 r/min", "| 0.9 |"):
        assert value in table, value
    # every row says where its value comes from
    rows = [r for r in table.splitlines() if r.startswith("| ") and not r.startswith("| quantity")]
    assert rows and all(re.search(r"recalled|verified|computed|project", r) for r in rows)
    assert "None of the numerical values below was checked against the papers' tables" in PAGE
    for name in ("slider_acceleration", "orbit", "contact_force", "poincare"):
        assert f"figures/mechanisms/{name}.png" in PAGE
        assert (ROOT / "docs" / "figures" / "mechanisms" / f"{name}.png").is_file()
    assert "docs/mechanisms_figures.py" in PAGE and (ROOT / "docs" / "mechanisms_figures.py").is_file()


@pytest.fixture(scope="module")
def benchmark():
    return simulate(CONFIG)


def test_the_shipped_benchmark_runs_in_the_plane_with_the_impacts_peaks(benchmark):
    ds = benchmark
    assert str(ds.status.values) == "ok"
    # in the mechanism's plane: B's offset across it (x) stays at rounding's level (the rod
    # held in the plane; measured 3.7e-18 m)
    assert float(np.abs(ds.ball_offset.sel(joint="B", axis="x")).max()) < 1e-12
    assert float(ds.constraint_violation.max()) < 1e-7
    ideal = abs(kinematics(math.pi / 2)[2])
    # the literature's picture: impacts at B, peak slider acceleration several times the ideal
    # mechanism's (measured 10.5x), the velocity close to the ideal one (measured +8.7 %)
    assert int(ds.impact_count.sel(joint="B")) > 10
    assert float(ds.slider_acceleration_peak) > 5.0 * ideal
    vmax = float(np.abs(kinematics(np.linspace(0, 2 * math.pi, 3601))[1]).max())
    assert float(np.abs(ds.slider_velocity).max()) < 1.15 * vmax


def test_without_friction_the_pins_stay_in_the_plane():
    """docs/mechanisms.md, "In the plane": the rod is held in the plane, so without friction
    too the pin at B stays in the plane over the benchmark's 5 revolutions (measured 3.7e-18
    m; a ball free across the plane reached 4.4e-4 m in the 5th revolution of this run). The
    pin's offset across the plane is read at the Poincare sections, from the bodies'
    attachments: a pin's ``ball_offset`` has no axial part (its bearing's gap drops it; was:
    the ball's x, read from ``ball_offset``)."""
    ds = simulate(CONFIG, ["friction.enabled=false", "solver.save_every=40"])
    assert str(ds.status.values) == "ok"
    assert int(ds.impact_count.sel(joint="B")) > 10        # the impacts are there
    assert not ds.ball_offset.sel(joint="B", axis="x").values.any()
    sections = ds.poincare_offset.sel(joint="B")
    assert int(sections.sel(axis="y").notnull().sum()) >= 4
    x = np.abs(sections.sel(axis="x").values) * float(ds.attrs["joint_B_clearance_m"])
    assert np.nanmax(x) < 1e-12


def test_the_configs_baumgarte_holds_the_constraints_at_a_longer_step():
    """The config's Baumgarte constants, 50 and 50 1/s: at dt 1e-5 s the benchmark runs 10
    revolutions with its joints' constraints below the 1e-6 m stop (measured 7.4e-8 m over
    5, 1.1e-7 m over 20; 9.5e-8 and 1.2e-7 m when B was a ball), where the default 5 and 5
    reach the stop after 7.5 revolutions."""
    longer = ["solver.dt=1e-5", "solver.save_every=1", "solver.revolutions=10"]
    assert tuple(load_config(CONFIG).solver.baumgarte) == (50.0, 50.0)
    ds = simulate(CONFIG, longer)
    assert str(ds.status.values) == "ok"
    assert float(ds.constraint_violation.max()) < 0.5e-6
    weak = simulate(CONFIG, longer + ["solver.baumgarte=[5.0, 5.0]"])
    assert str(weak.status.values) == "constraint_violation"
