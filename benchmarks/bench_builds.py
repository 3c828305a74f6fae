"""Steps/s of one case on kernel builds of different joint sets, side by side in one process:
the case's own build (its joints with clearance), coarser builds that hold more joints, and
the generic build (every joint tested at run time). The results are the same bit for bit
(tests/test_jointset.py); what differs is what the compiler could fold away.

Run: ``python benchmarks/bench_builds.py [--duration 0.2] [--repeats 5]``. Each build is
compiled (or loaded from the cache) before the timed runs, which alternate between builds;
the rate is per CPU second of this process (``time.process_time`` around each run: on a
loaded machine the wall time also counts the waits for a core). Writes markdown to stdout.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

#: case -> (overrides, the builds to time it on, as joint names; "all": the generic build)
CASES = {
    "ideal": ((), ("none", "O,P", "A,B", "all")),
    "one clearance (B)": (("joints.B.clearance=2.5e-4",), ("B", "B,O,P", "A,B", "all")),
    "two clearances (A, B)": (("joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4"),
                              ("A,B", "all")),
    "A, B and O": (("joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4",
                    "joints.O.clearance=5e-5"), ("A,B,O", "all")),
}


def spec_of(label: str) -> int:
    from clearsweep.core import jointset

    if label == "all":
        return jointset.ALL
    if label == "none":
        return jointset.NONE
    return jointset.named(*label.split(","))


def main(argv=None) -> str:
    from clearsweep.config import DEFAULTS, resolve_materials
    from clearsweep.params import pack
    from clearsweep.simulation import run_kernel

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--duration", type=float, default=0.2, help="simulated time per run [s]")
    ap.add_argument("--repeats", type=int, default=5, help="alternating runs per build")
    args = ap.parse_args(argv)
    lines = [f"RK4 steps per CPU second, {args.duration:g} s simulated, median of {args.repeats} alternating "
             f"runs in one process; load average (1 min) at the start {os.getloadavg()[0]:.1f}",
             "", "| case | build | steps/s | ratio to the generic build |", "|---|---|---|---|"]
    for name, (overrides, builds) in CASES.items():
        cfg = DEFAULTS.replace(*overrides, f"solver.duration={args.duration}")
        packed = pack(cfg, resolve_materials(cfg))
        rates: dict[str, list[float]] = {b: [] for b in builds}
        for b in builds:
            run_kernel(packed, build=spec_of(b))      # compile or load
        for _ in range(args.repeats):
            for b in builds:
                cpu = time.process_time()
                run_kernel(packed, build=spec_of(b))
                rates[b].append(packed.n_steps / (time.process_time() - cpu))
        med = {b: statistics.median(v) for b, v in rates.items()}
        for b in builds:
            lines.append(f"| {name} | {b} | {med[b]:,.0f} | {med[b] / med['all']:.3f} |")
    lines.append(f"\nload average (1 min) at the end {os.getloadavg()[0]:.1f}")
    text = "\n".join(lines)
    print(text)
    return text


if __name__ == "__main__":
    main()
