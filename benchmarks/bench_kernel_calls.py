"""The kernel's steps/s and one right-hand side's time, in this process, for the tree on
the path: `run_kernel` of the ideal, one-clearance (B) and two-clearance (A, B) cases of
configs/one_clearance.yaml, 0.5 s each, best of 5; `dynamics.evaluate` at their initial
state, a stage (no diagnostics) and a step's end, best of 7 loops of 200,000 calls.

    .venv/bin/python benchmarks/bench_kernel_calls.py                  # this tree
    PYTHONPATH=/path/to/other/tree .venv/bin/python benchmarks/bench_kernel_calls.py

Run from the repository root (the configs are read from there). A quick probe for
comparing variants of the kernel side by side (benchmarks/README.md, "Joint P"); about
+-3 % from run to run on the 2-core machine, so compare several runs.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from clearsweep.config import load_config, resolve_materials
from clearsweep.core import layout as L
from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
from clearsweep.core.work import Model, Solve
from clearsweep.params import pack
from clearsweep.simulation import prepare_kernel, run_kernel

CASES = {"ideal": ["joints.B.clearance=0"], "one clearance (B)": [],
         "two clearances (A, B)": ["joints.A.clearance=2.5e-4"]}


@njit
def _loop(n, y, model, dy, dg, full, solve):
    acc = 0.0
    for i in range(n):
        evaluate(i * 1e-9, y, model, dy, dg, full, solve)
        acc += dy[L.Y_QD + L.Y_SLIDER_X]
    return acc


def main() -> None:
    prepare_kernel("rk4")
    for name, sets in CASES.items():
        cfg = load_config("configs/one_clearance.yaml", ["solver.duration=0.5", *sets])
        pk = pack(cfg, resolve_materials(cfg))
        run_kernel(pk)
        best = min(_timed(lambda: run_kernel(pk)) for _ in range(5))
        model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)), np.zeros((L.N_JOINTS, 144, 288)))
        solve = Solve(np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((NZ, NZ)),
                      np.zeros((VZ_ROWS, NZ)))
        dy, dg = np.zeros(L.N_Y), np.zeros(L.N_D)
        per_call = []
        for full in (False, True):
            _loop(10, pk.y0, model, dy, dg, full, solve)
            per_call.append(min(_timed(lambda: _loop(200_000, pk.y0, model, dy, dg, full, solve))
                                for _ in range(7)) / 200_000 * 1e9)
        print(f"{name}: {pk.n_steps / best:,.0f} RK4 steps/s; evaluate {per_call[0]:.0f} ns a "
              f"stage, {per_call[1]:.0f} ns a step's end")


def _timed(call) -> float:
    began = time.perf_counter()
    call()
    return time.perf_counter() - began


if __name__ == "__main__":
    main()
