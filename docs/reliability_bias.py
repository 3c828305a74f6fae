"""The bias check of docs/reliability.md: revolutions to each limit of the shipped example's
nominal design against the cycle-jump limit, extrapolated to jumps of zero, and compared
with the width of the B10 interval the example reports.

    python docs/reliability_bias.py [REL.nc] [--set KEY=VALUE ...]

Runs the base of configs/reliability.yaml (MoS2 at B, no scatter; ``--set`` changes it, e.g.
``--set joints.B.coating=PTFE`` for another design of the example) as a life run at
life.jump_clearance_fraction 0.04, 0.02, 0.01 and 0.005, until both limits are reached.
The revolutions to a depth limit are first order in the jump limit f
(docs/service_life.md), so N(0) ~ 2 N(f / 2) - N(f) (Richardson) from the two smallest.
With REL.nc (the example's `clearsweep sweep` output), prints each design's B10 interval
width relative to its B10 beside the bias at the example's jump limit.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from clearsweep.config import load_config
from clearsweep.reliability import _all_reached
from clearsweep.schema import ConfigError, read_yaml
from clearsweep.service_life import life

ROOT = Path(__file__).resolve().parents[1]
FRACTIONS = (0.04, 0.02, 0.01, 0.005)
LIMITS = ("clearance_growth", "motion_error")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rel", nargs="?", help="the example's sweep output (rel.nc)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="override of the base design")
    args = parser.parse_args(argv)
    sweep = read_yaml(ROOT / "configs" / "reliability.yaml")
    try:
        base = load_config(sweep["base"]).replace(*args.overrides)
    except ConfigError as exc:
        parser.error(str(exc))
    shipped = base.life.jump_clearance_fraction
    cycles = {}
    for f in FRACTIONS:
        start = time.perf_counter()
        ds = life(base.replace(f"life.jump_clearance_fraction={f}"), stop_rule=_all_reached)
        cycles[f] = [float(ds[f"cycles_to_{name}"]) for name in LIMITS]
        print(f"jump limit {f:<6} blocks {ds.sizes['cycle']:3d}  " + "  ".join(
            f"{name} {value:.5g}" for name, value in zip(LIMITS, cycles[f]))
            + f"  ({time.perf_counter() - start:.0f} s)")
    extrapolated = 2.0 * np.array(cycles[FRACTIONS[-1]]) - np.array(cycles[FRACTIONS[-2]])
    bias = np.array(cycles[shipped]) / extrapolated - 1.0
    for name, value, b in zip(LIMITS, extrapolated, bias):
        print(f"{name}: extrapolated to jumps of zero {value:.5g} revolutions; bias at the "
              f"example's jump limit {shipped}: {100 * b:+.1f} %")
    if args.rel:
        import xarray as xr

        with xr.open_dataset(args.rel) as rel:
            for name in LIMITS:
                for coating in rel["B_coating"].values:
                    case = rel.sel(B_coating=coating, limit=name)
                    b10, low, high = (float(case[v]) for v in ("b10", "b10_ci_low", "b10_ci_high"))
                    print(f"{name}, B coating {coating}: B10 {b10:.4g} [{low:.4g}, {high:.4g}], "
                          f"interval width {100 * (high - low) / b10:.0f} % of B10")


if __name__ == "__main__":
    main()
