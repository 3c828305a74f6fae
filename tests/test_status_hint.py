"""An energy_residual stop says what dominated the balance (post-processing, outside the kernel)."""

import numpy as np

from clearsweep.config import load_config
from clearsweep.simulation import energy_residual_hint, simulate
from clearsweep.sweeping import run_sweep

#: A clearance case whose energy tolerance is so tight that it stops within a few ms.
TIGHT = {"joints": {"B": {"clearance": 2.5e-4}},
         "solver": {"duration": 0.02, "energy_tolerance": 1e-9}}


def test_hint_names_the_largest_term_and_the_wear_against_the_clearance():
    n = 5
    arrays = {"energy_kinetic": np.full(n, 1.0), "energy_potential": np.full(n, 0.5),
              "work_drive": np.linspace(0.0, 2.0, n), "energy_dissipated": np.linspace(0.0, 3.0, n),
              "energy_residual": np.array([0.0, 0.1, 0.2, 0.3, np.nan]),
              "wear_depth_max": np.array([[0.0, 0.0, 0.0, 0.0]] * 3 + [[0.0, 5e-5, 0.0, 0.0],
                                                                        [np.nan] * 4])}
    cfg = load_config({"joints": {"B": {"clearance": 2.5e-4}}})
    hint = energy_residual_hint(arrays, np.arange(n) * 0.1, cfg)
    assert hint.startswith("hint (saved rows up to t = 0.3 s): the largest change since t = 0 is "
                           "the dissipated energy, +2.25 J")
    assert "drive work +1.5 J" in hint and "B 5e-05 m = 20 % of its clearance" in hint
    cfg = cfg.replace(wear__feedback=False)
    assert "clearance" not in energy_residual_hint(arrays, np.arange(n) * 0.1, cfg)


def test_energy_residual_stop_carries_the_hint_into_the_sweep_message(tmp_path):
    ds = simulate(TIGHT)
    assert ds["status"].item() == "energy_residual"
    assert ds.attrs["status_hint"].startswith("hint (saved rows up to t = ")
    with run_sweep({"base": TIGHT, "sweep": {"grid": {"joints.B.coating": ["none"]}}},
                   tmp_path / "s.nc", workers=1, progress=False, report_failures=False) as sweep:
        message = sweep["message"].item()
    assert "energy_residual" in message and "the largest change since t = 0 is the " in message
