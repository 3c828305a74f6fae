"""The measured verification of docs/service_life.md, printed as that page quotes it.

Run from the repository root: ``python docs/service_life_verification.py`` (a few minutes
on one core). Cases: ``configs/one_clearance.yaml`` with the map read bilinearly (the
worn-surface normal, docs/physics.md 3.5) and the default energy tolerance.

1. Convergence with the jump limit: revolutions to 40 um of wear at B (36 x 72 map, wear
   amplified 300 times) at jump limits 0.04, 0.02, 0.01, 0.005, the change per halving and
   the Richardson extrapolation to a zero limit (first order).
2. Direct simulation: MoS2 at B, wear amplified 2000 times, 12 revolutions simulated one by
   one against life runs at jump limits 0.08 to 0.01: worn volume, largest and mean depth,
   settled peak normal force.
"""

from __future__ import annotations

import numpy as np

from clearsweep.service_life import WORN_FRACTION, bin_areas, life
from clearsweep.simulation import simulate

CASE = "configs/one_clearance.yaml"
MAP = ["wear.map=[36,72]", "wear.interpolate=true"]


def convergence() -> None:
    common = [*MAP, "wear.amplification=300", "life.cycles=1e4", "life.max_clearance_growth=4e-5"]
    limits = (0.04, 0.02, 0.01, 0.005)
    cycles = []
    for f in limits:
        ds = life(CASE, [*common, f"life.jump_clearance_fraction={f}"])
        cycles.append(float(ds.cycles_to_clearance_growth))
        print(f"  limit {f}: {cycles[-1]:.0f} revolutions to 40 um "
              f"(largest block energy residual {float(ds.energy_residual_relative.max()):.2g})")
    changes = [abs(b - a) / b for a, b in zip(cycles, cycles[1:])]
    print("  change per halving: " + ", ".join(f"{100 * c:.1f} %" for c in changes))
    print(f"  extrapolated to a zero limit: {2 * cycles[-1] - cycles[-2]:.0f}")


def mean_depth(wmap: np.ndarray, radius: float) -> float:
    worn = wmap > WORN_FRACTION * wmap.max()
    areas = bin_areas(wmap.shape, radius)
    return float((wmap * areas)[worn].sum() / areas[worn].sum())


def direct() -> None:
    common = [*MAP, "wear.amplification=2000", "joints.B.coating=MoS2"]
    ds = simulate(CASE, [*common, "solver.duration=12", "solver.save_every=1000"])
    v_direct = float(ds.wear_volume.sel(joint="B"))
    wmap = ds.wear_map.sel(joint="B").values
    h_direct = float(wmap.max())
    m_direct = mean_depth(wmap, 0.015)
    print(f"  direct: volume {v_direct:.4g} m3, largest depth {h_direct:.4g} m, mean depth "
          f"{m_direct:.4g} m, settled peak F_N {float(ds.normal_force_peak_settled.sel(joint='B')):.3g} N, "
          f"energy residual {float(ds.energy_residual_relative):.2g}")
    for f in (0.08, 0.04, 0.02, 0.01):
        lf = life(CASE, [*common, "life.cycles=12", f"life.jump_clearance_fraction={f}"])
        last = lf.isel(cycle=-1)
        print(f"  limit {f}: volume {float(last.wear_volume.sel(joint='B')) / v_direct - 1:+.2g}, "
              f"largest depth {float(last.wear_depth_max.sel(joint='B')) / h_direct - 1:+.1%}, "
              f"mean depth {float(last.wear_depth_mean.sel(joint='B')) / m_direct - 1:+.1%}, "
              f"settled peak F_N {float(last.normal_force_peak_settled.sel(joint='B')):.3g} N, "
              f"{int(lf.sizes['cycle'])} blocks")


if __name__ == "__main__":
    print("convergence with the jump limit:")
    convergence()
    print("direct simulation against life runs:")
    direct()
