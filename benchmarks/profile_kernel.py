"""Where the kernel's time goes, per compiled function: `run_kernel` of one case of
benchmarks/bench_kernel_calls.py under ``perf record``, with a perf map of the compiled
functions written at start, so that ``perf report`` names them (Numba's machine code lies in
memory that perf cannot read symbols from). Run from the repository root:

    perf record -e cpu-clock -F 10000 -o perf.data \\
        .venv/bin/python benchmarks/profile_kernel.py ideal
    perf report -i perf.data --no-children --sort sym -n | grep clearsweep

CASE: ideal, B or AB (the cases of bench_kernel_calls.py); then optionally the number of runs
of 0.5 s of motion (default 20). ``cpu-clock`` needs no hardware counters (a virtual
machine has none). The map's names come from Numba's loaded code (a private attribute of its
JIT engine, Numba 0.6x); each function is taken to run up to the next one's address.
Samples count the time of the function's own instructions, not of its callees: a
function that LLVM inlined counts in its caller.
"""

from __future__ import annotations

import os
import re
import sys
import time

from clearsweep.config import load_config, resolve_materials
from clearsweep.core import rk4
from clearsweep.params import pack
from clearsweep.simulation import run_kernel

CASES = {"ideal": ["joints.B.clearance=0"], "B": [], "AB": ["joints.A.clearance=2.5e-4"]}


def write_perf_map() -> int:
    """/tmp/perf-PID.map for the compiled kernel functions loaded in this process; returns
    how many it names."""
    engine = rk4.integrate.overloads[rk4.integrate.signatures[0]].library.codegen._engine
    addrs = []
    for name in engine._defined_symbols:
        if "clearsweep" in name:
            address = engine.get_function_address(name)
            if address:
                addrs.append((address, name))
    addrs.sort()
    ends = [a for a, _ in addrs[1:]] + [addrs[-1][0] + 65536]
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as f:
        for (address, name), end in zip(addrs, ends):
            f.write(f"{address:x} {end - address:x} {short_name(name)}\n")
    return len(addrs)


def short_name(mangled: str) -> str:
    """_ZN10clearsweep4core3rk47advanceB4v184B40... -> clearsweep.core.rk4.advance (the
    length-prefixed names before the first non-name part); a cpython wrapper keeps its
    prefix."""
    rest = mangled.split("_ZN", 1)[-1]
    parts = []
    while (m := re.match(r"(\d+)", rest)):
        n = int(m.group(1))
        parts.append(rest[m.end():m.end() + n])
        rest = rest[m.end() + n:]
    return ".".join(parts) or mangled


def main() -> None:
    case = sys.argv[1] if len(sys.argv) > 1 else "ideal"
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 20
    cfg = load_config("configs/one_clearance.yaml", ["solver.duration=0.5", *CASES[case]])
    packed = pack(cfg, resolve_materials(cfg))
    run_kernel(packed)
    named = write_perf_map()
    began = time.perf_counter()
    for _ in range(runs):
        run_kernel(packed)
    rate = runs * packed.n_steps / (time.perf_counter() - began)
    print(f"{case}: {rate:,.0f} RK4 steps/s over {runs} runs; {named} functions in the perf map")


if __name__ == "__main__":
    main()
