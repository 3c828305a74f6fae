"""Engine benchmark: RK4 steps/s, ns per right-hand side, JIT compile time, and the same
right-hand side driven by scipy.integrate.solve_ivp, measured side by side in one run.

Run: ``python benchmarks/bench_engine.py [--duration 1.0] [--out FILE]``.
Writes a markdown table to stdout (and to ``--out`` if given).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

CASES = {
    "ideal": [],
    "one clearance (B)": ["joints.B.clearance=2.5e-4"],
    "two clearances (A, B)": ["joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4"],
}

COMPILE_SNIPPET = """
import time
t0 = time.perf_counter()
from clearsweep.simulation import simulate
simulate({"solver": {"duration": 1e-4, "save_every": 1}, "joints": {"A": {"clearance": 2.5e-4},
          "B": {"clearance": 2.5e-4}}})
print(time.perf_counter() - t0)
"""


def compile_times() -> tuple[float, float]:
    """(cold, cached) seconds to import and run a 10-step case in a fresh interpreter."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = []
        for _ in range(2):
            res = subprocess.run([sys.executable, "-c", COMPILE_SNIPPET], env=env, check=True,
                                 capture_output=True, text=True)
            out.append(float(res.stdout.strip().splitlines()[-1]))
    return out[0], out[1]


def packed_case(overrides, duration):
    from clearsweep.config import load_config, resolve_materials
    from clearsweep.params import pack

    cfg = load_config({"solver": {"duration": duration}}, overrides)
    return pack(cfg, resolve_materials(cfg))


def rk4_rate(packed, repeats=3) -> float:
    """Warm RK4 steps per second (best of ``repeats``)."""
    from clearsweep.simulation import run_kernel

    run_kernel(packed)
    best = min(run_kernel(packed)["wall_time"] for _ in range(repeats))
    return packed.n_steps / best


def rhs_ns(packed, n=200_000) -> float:
    """Nanoseconds per right-hand-side evaluation (Numba loop, no Python in between)."""
    from numba import njit

    from clearsweep.core import layout as L
    from clearsweep.core.dynamics import evaluate

    @njit
    def loop(y, p, jp, n):
        s = np.zeros((2, L.N_S))
        wmap = np.zeros((2, 36, 72))
        dy = np.zeros(L.N_Y)
        dg = np.zeros(L.N_D)
        C = np.zeros((6, 6))
        S = np.zeros((6, 6))
        Lm = np.zeros((6, 6))
        vz = np.zeros((8, 6))
        acc = 0.0
        for i in range(n):
            evaluate(1e-3 * (i % 7), y, p, jp, s, wmap, dy, dg, False, C, S, Lm, vz)
            acc += dy[30]
        return acc

    y = packed.y0.copy()
    loop(y, packed.p, packed.jp, 10)
    t0 = time.perf_counter()
    loop(y, packed.p, packed.jp, n)
    return (time.perf_counter() - t0) / n * 1e9


def solve_ivp_rate(packed, duration) -> tuple[float, int, float]:
    """The same right-hand side under solve_ivp (RK45, rtol 1e-8, atol 1e-10), no wear/status.

    Returns (right-hand-side evaluations per second, evaluations, wall seconds).
    """
    from scipy.integrate import solve_ivp

    from clearsweep.core import layout as L
    from clearsweep.core.dynamics import evaluate

    s = np.zeros((2, L.N_S))
    wmap = np.zeros((2, 36, 72))
    dg = np.zeros(L.N_D)
    C = np.zeros((6, 6))
    S = np.zeros((6, 6))
    Lm = np.zeros((6, 6))
    vz = np.zeros((8, 6))

    def f(t, y):
        dy = np.empty(L.N_Y)
        evaluate(t, y, packed.p, packed.jp, s, wmap, dy, dg, False, C, S, Lm, vz)
        return dy

    f(0.0, packed.y0)
    t0 = time.perf_counter()
    sol = solve_ivp(f, (0.0, duration), packed.y0, method="RK45", rtol=1e-8, atol=1e-10)
    wall = time.perf_counter() - t0
    return sol.nfev / wall, sol.nfev, wall


def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated time per case [s]")
    ap.add_argument("--out", help="also write the markdown here")
    args = ap.parse_args(argv)

    cold, cached = compile_times()
    lines = [
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}",
        "",
        f"JIT compile (import + 10-step two-clearance case, fresh interpreter): "
        f"cold {cold:.1f} s, cached {cached:.2f} s",
        "",
        f"Each case: {args.duration:g} s simulated at 60 r/min, realistic preset, uncoated steel.",
        "",
        "| case | RK4 steps/s (h = 1e-5 s, warm) | ns / RHS (Numba loop) | RK4 wall [s] "
        "| solve_ivp RK45 wall [s] | solve_ivp RHS evaluations | solve_ivp us / RHS "
        "| wall ratio solve_ivp / RK4 |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, ov in CASES.items():
        packed = packed_case(ov, args.duration)
        rate = rk4_rate(packed)
        ns = rhs_ns(packed)
        ivp_rate, nfev, ivp_wall = solve_ivp_rate(packed, args.duration)
        rk4_wall = packed.n_steps / rate
        lines.append(f"| {name} | {rate:,.0f} | {ns:,.0f} | {rk4_wall:.2f} | {ivp_wall:.2f} | "
                     f"{nfev:,} | {1e6 / ivp_rate:.1f} | {ivp_wall / rk4_wall:.2f} |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text + "\n")
    return text


if __name__ == "__main__":
    main()
