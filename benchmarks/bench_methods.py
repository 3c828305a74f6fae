"""Speed and accuracy together: each shipped case config run with RK4 (its own dt) and with
dopri5 (default tolerances), against an RK4 reference at dt = 1e-7 s, in one run.

For every case: wall time of the stepping (compiled, warm), simulated seconds per wall
second, integrator steps per second, the errors of the settled RMS slider acceleration
and of the settled peak normal force (largest over the clearance joints) against the
reference, and the dopri5 / RK4 speed ratio. The issue's goal: at equal accuracy (RMS
within 1 %, peak force within 2 %), dopri5 >= 3x RK4 on two_clearances and >= 5x on
paper_case.

Run: ``.venv/bin/python benchmarks/bench_methods.py [--duration 0.3] [--repeats 3]
[--out FILE]``. paper_case runs a third of the duration (its reference is 10^6 steps per
0.1 s). Writes markdown to stdout (and to ``--out``).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from clearsweep.config import load_config
from clearsweep.simulation import prepare_kernel, simulate

ROOT = Path(__file__).resolve().parent.parent
CASES = ("ideal", "one_clearance", "two_clearances", "paper_case")
REFERENCE_DT = 1e-7


def run(name: str, duration: float, *overrides: str):
    cfg = load_config(ROOT / "configs" / f"{name}.yaml",
                      [f"solver.duration={duration}", "wear.map=[36, 72]", *overrides])
    return simulate(cfg, allow_large=True)


def settled(ds) -> tuple[float, float]:
    rms = float(ds["slider_acceleration_rms_settled"])
    force = float(np.nanmax(ds["normal_force_peak_settled"].values))
    return rms, force


def relative(a: float, b: float) -> float:
    return abs(a - b) / abs(b) if b else abs(a - b)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out")
    args = ap.parse_args()
    for method in ("rk4", "dopri5"):
        prepare_kernel(method)
    lines = [f"Machine: {platform.machine()}, {platform.python_version()}; one core; "
             f"reference RK4 dt = {REFERENCE_DT:g} s; wear map 36 x 72; settled window from "
             "0.05 s.", "",
             "| case | duration [s] | method | steps | wall [s] | steps/s | simulated s / wall s "
             "| RMS acc. error | peak F_N error | speed vs RK4 |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name in CASES:
        duration = args.duration / 3 if name == "paper_case" else args.duration
        cfg = load_config(ROOT / "configs" / f"{name}.yaml")
        ref = run(name, duration, f"solver.dt={REFERENCE_DT}",
                  f"solver.save_every={max(1, round(cfg.solver.dt * cfg.solver.save_every / REFERENCE_DT))}",
                  f"solver.max_substep_level={min(16, cfg.solver.max_substep_level + 4)}")
        ref_rms, ref_force = settled(ref)
        walls = {}
        for method in ("rk4", "dopri5"):
            times, ds = [], None
            for _ in range(args.repeats):
                ds = run(name, duration, f"solver.method={method}")
                times.append(float(ds["wall_time"]))
            wall = statistics.median(times)
            walls[method] = wall
            rms, force = settled(ds)
            steps = int(ds["rk4_steps"])
            ratio = "1" if method == "rk4" else f"{walls['rk4'] / wall:.2f}x"
            force_err = f"{relative(force, ref_force):.2e}" if ref_force > 0 else "- (no contact)"
            lines.append(f"| {name} | {duration:g} | {method} | {steps:,} | {wall:.3f} | "
                         f"{steps / wall:,.0f} | {duration / wall:.2f} | "
                         f"{relative(rms, ref_rms):.2e} | {force_err} | {ratio} |")
            print(lines[-1], flush=True)
    text = "\n".join(lines)
    print()
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"\n(benchmark took {time.perf_counter() - t0:.0f} s)")
