"""docs/sweeps.md's reading of configs/bifurcation.yaml (B's clearance, speeds 50 to 640
r/min): the motion repeats every revolution at 80 r/min and not at 110 r/min. Short runs of
the config's base: 14 revolutions, 4 of them start-up (as the bifurcation example runs
them), where the shipped sweep runs 110 with 10."""

from __future__ import annotations

from pathlib import Path

import yaml

import clearsweep

ROOT = Path(__file__).resolve().parents[1]


def test_the_motion_stops_repeating_between_80_and_110_rpm():
    """Measured on the shipped settings (docs/sweeps.md): period 1 at 50 to 90 r/min (K 0.00
    at 80), none from 100 r/min (K 0.99 at 110). Short runs give the same split at 80 and
    110 r/min."""
    spec = yaml.safe_load((ROOT / "configs" / "bifurcation.yaml").read_text())
    spec["sweep"]["grid"]["mechanism.speed_rpm"] = [80.0, 110.0]
    spec["base"]["solver"]["revolutions"] = 14
    spec["base"]["metrics"]["settle_revolutions"] = 4
    ds = clearsweep.sweep(spec, workers=1, progress=False)
    assert [str(s) for s in ds.status.values] == ["ok", "ok"]
    assert int(ds.period.sel(speed_rpm=80.0)) == 1
    assert int(ds.period.sel(speed_rpm=110.0)) != 1
