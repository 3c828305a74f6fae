"""Results with the structure of the shipped examples, cheap enough for a test module.

The real results take hours on two cores; these keep what the figures read from them: the
same dimensions, coordinates and value ranges, with short durations and few cases.

* :func:`main_job`: ``configs/paper.yaml`` (the zip groups clearance_joints x coating_joints,
  four cases skipped, full store) run for 0.02 s at dt 1e-5 s instead of 1 s at 1e-6 s.
* :func:`reliability_example`: ``configs/reliability.yaml`` (B_coating x 16 members, limits
  clearance_growth and motion_error, and "any"); the members' revolutions to each limit are
  drawn (log-normal, 1.5e5 to 6e5 revolutions, as the example's members reach) instead of
  simulated, and the estimate is :func:`clearsweep.reliability.reliability_estimate`'s.
* :func:`life_sweep`: ``configs/life_sweep.yaml`` (B_coating x B_clearance, life store) with
  the short life of ``TINY_LIFE`` per case (300 r/min, a coarse map, wear x300).
* :func:`sensitivity_example`: ``configs/sensitivity.yaml`` (a Saltelli sample over the
  same four inputs and ranges, summary store) with n = 8 (48 points, not 3,072) of 10 ms each.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from clearsweep.reliability import reliability_estimate
from clearsweep.sweeping import run_sweep

ROOT = Path(__file__).resolve().parents[1]

#: A short life run: 300 r/min (0.2 s blocks), a coarse map, wear x300, to 70 um of wear.
TINY_LIFE = ["mechanism.speed_rpm=300", "metrics.settle_time=0.02", "wear.map=[8,16]",
             "wear.interpolate=true", "solver.energy_tolerance=0.5", "wear.amplification=300",
             "life.cycles=1e5", "life.jump_clearance_fraction=0.1",
             "life.max_clearance_growth=7e-5"]


def _run(doc, path: Path, overrides: list[str]) -> xr.Dataset:
    run_sweep(doc, path, workers=1, progress=False, overrides=overrides).close()
    with xr.open_dataset(path) as ds:
        return ds.load()


def main_job(folder: Path) -> xr.Dataset:
    return _run(str(ROOT / "configs/paper.yaml"), folder / "paper.nc",
                ["solver.duration=0.02", "solver.dt=1e-5", "solver.save_every=1",
                 "metrics.settle_time=0.005"])


def life_sweep(folder: Path) -> xr.Dataset:
    return _run(str(ROOT / "configs/life_sweep.yaml"), folder / "life_sweep.nc", TINY_LIFE)


def sensitivity_example(folder: Path) -> xr.Dataset:
    doc = yaml.safe_load((ROOT / "configs/sensitivity.yaml").read_text())
    doc["sweep"]["sample"]["n"] = 8
    return _run(doc, folder / "sensitivity.nc", ["solver.duration=0.01", "metrics.settle_time=0.002"])


def reliability_example() -> xr.Dataset:
    doc = yaml.safe_load((ROOT / "configs/reliability.yaml").read_text())
    coatings = doc["sweep"]["grid"]["joints.B.coating"]
    members, limits = doc["base"]["reliability"]["members"], ["clearance_growth", "motion_error"]
    rng = np.random.default_rng(1)
    # the example's members reach 40 um of wear after 1.5e5 to 6e5 revolutions
    median = np.array([2.2e5, 3.0e5, 3.4e5, 4.1e5])[:, None, None]
    times = median * rng.lognormal(0.0, 0.3, (len(coatings), members, len(limits)))
    times[:, :, 1] *= 1.3
    times = np.concatenate([times, times.min(axis=2, keepdims=True)], axis=2)
    censored = times > 6e5
    times = np.minimum(times, 6e5)
    dims = ("B_coating", "member", "limit")
    ds = xr.Dataset(
        {"revolutions_to_limit": (dims, times), "censored": (dims, censored),
         "status": (("B_coating", "member"), np.full((len(coatings), members), "ok"))},
        coords={"B_coating": ("B_coating", coatings, {"long_name": "coating of joint B"}),
                "limit": ("limit", [*limits, "any"])},
        attrs={"sweep_config": yaml.safe_dump(doc)})
    return ds.merge(reliability_estimate(ds))
