"""CUDA backend benchmark: cases/s of a two_clearances sweep on the device against the
2-worker CPU backend on the same sweep, with the device's name printed beside the numbers.

Run: ``python benchmarks/bench_gpu.py [--sizes 100 1000 10000] [--duration 1.0]
[--cpu-max 1000]``. Each size is a ``store: summary`` sweep of ``configs/two_clearances.yaml``
over that many distinct joint-B clearances (1.0e-4 to 3.0e-4 m), ``--duration`` seconds of
motion per case. The CPU backend runs at most ``--cpu-max`` cases per size (its cases/s
does not depend on the sweep's size; a larger size is reported as not run). Wall time
covers the whole sweep (planning excluded): device batches, parts and the final file.

For every size run on both backends, a second table gives the agreement of the device's
summaries with the CPU's: per summary variable, the largest relative difference over the
cases, and how many cases differ at all (the device contracts multiply-adds into fused
ones, so last-bit differences are expected, and contact dynamics amplify them over a run).

``--kernel-only`` times the device kernel alone instead: each size is one launch of
``gpu.run_packed`` over that many packed cases (no sweep, no parts, no file), the first
launch (2 cases) compiling outside the clock; it prints RK4 steps/s and the cases' statuses,
then the three smallest cases' statistics against the CPU kernel's (``simulation.run_kernel``).
``--kernel-only --sizes 1470 10000 --duration 0.1`` gives the figures in benchmarks/README;
``--set KEY=VALUE`` (repeatable) overrides every case's config (``--set joints.O.clearance=2.5e-4``:
clearance at the crank's bearing too). ``--layout aos`` times the case-by-case layout
instead of the structure-of-arrays one, ``--capacity N`` launches every soa batch at that
capacity (one compile for several sizes), ``--json FILE`` keeps the figures
(benchmarks/device_suite.py runs it so).

Without a CUDA device it prints ``no CUDA device`` and exits 0. ``--simulator`` runs the
CUDA path in numba's CUDA simulator instead (sizes and duration should then be tiny, e.g.
``--simulator --sizes 2 --duration 0.002``): a check that the script works, not a figure.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


#: ``--set KEY=VALUE`` overrides of the base config (e.g. ``joints.O.clearance=2.5e-4``: the
#: revolute joint at the crank too), applied to every case.
EXTRA: list[str] = []


def sweep_doc(n: int, duration: float) -> dict:
    step = 2.0e-4 / max(n - 1, 1)
    clearances = [1.0e-4 + i * step for i in range(n)]
    return {"name": f"bench_gpu_{n}", "store": "summary",
            "base": str(ROOT / "configs" / "two_clearances.yaml"),
            "sweep": {"grid": {"joints.B.clearance": clearances}},
            "overrides": [f"solver.duration={duration}", *EXTRA]}


def timed_sweep(n: int, duration: float, **backend):
    """Seconds, failed cases and the summaries (loaded, timing dropped) of one sweep of n
    cases."""
    from clearsweep.sweeping import drop_timing, expand, run_sweep

    doc = sweep_doc(n, duration)
    plan = expand({k: v for k, v in doc.items() if k != "overrides"}, doc["overrides"],
                  max_cases=None)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        with run_sweep(plan, Path(tmp) / "bench.nc", progress=False, **backend) as ds:
            seconds = time.perf_counter() - start
            return seconds, int(ds.attrs["sweep_failed"]), drop_timing(ds.load())


def packed_cases(n: int, duration: float) -> list:
    """The packed inputs of the n cases of :func:`sweep_doc`."""
    from clearsweep.config import resolve_materials
    from clearsweep.params import pack
    from clearsweep.sweeping import expand

    doc = sweep_doc(n, duration)
    plan = expand({k: v for k, v in doc.items() if k != "overrides"}, doc["overrides"],
                  max_cases=None)
    return [pack(c.config, resolve_materials(c.config)) for c in plan.cases]


def kernel_only(sizes: list[int], duration: float, layout: str = "soa",
                capacity: int | None = None) -> dict:
    """RK4 steps/s of one device launch per size, then the device's statistics against the
    CPU kernel's on three cases; what it printed, as a dict (``--json``). ``layout``: the
    device layout; ``capacity``: the launch capacity of every soa launch (default: the
    smallest that holds each size; one capacity for every size compiles the kernel once)."""
    from collections import Counter

    import numpy as np

    from clearsweep import gpu
    from clearsweep.simulation import run_kernel

    caps = sorted({capacity or gpu.capacity_for(n) for n in sizes}) if layout != "aos" else [None]
    began = time.perf_counter()
    for cap in caps:
        gpu.run_packed(packed_cases(2, 1.0e-4), layout, cap)           # compiles
    result: dict = {"layout": layout, "capacity": capacity, "duration_s": duration,
                    "compile_s": time.perf_counter() - began, "launches": [], "agreement": []}
    print("| layout | cases | one launch [s] | RK4 steps/s | statuses |")
    print("|---|---|---|---|---|")
    for n in sizes:
        packed = packed_cases(n, duration)
        start = time.perf_counter()
        runs = gpu.run_packed(packed, layout, capacity)
        seconds = time.perf_counter() - start
        steps = sum(pk.n_steps for pk in packed)
        statuses = dict(Counter(r.status for r in runs))
        result["launches"].append({"cases": n, "seconds": seconds, "steps_per_s": steps / seconds,
                                   "statuses": statuses})
        print(f"| {layout} | {n:,} | {seconds:.2f} | {steps / seconds:.3g} | {statuses} |",
              flush=True)
    print()
    print("| case | statistic's largest relative difference | worn volume per joint: device / CPU "
          "[m^3] | energy residual: device / CPU |")
    print("|---|---|---|---|")
    packed = packed_cases(3, duration)
    for k, (pk, dev) in enumerate(zip(packed, gpu.run_packed(packed, layout, capacity))):
        cpu = run_kernel(pk)
        rel = np.abs(dev.stats - cpu.stats) / np.maximum(np.abs(cpu.stats), 1e-300)
        wrel = np.abs(dev.wvol - cpu.wvol) / np.maximum(np.abs(cpu.wvol), 1e-300)
        result["agreement"].append({"case": k, "stats_max_rel": float(rel.max()),
                                    "wvol_max_rel": float(wrel.max()),
                                    "status": [dev.status, cpu.status]})
        print(f"| {k} | {float(rel.max()):.2e} | {dev.wvol} / {cpu.wvol} | "
              f"{dev.residual_max:.9e} / {cpu.residual_max:.9e} |")
    return result


def agreement(gpu, cpu) -> list[tuple[str, float, int]]:
    """Per numeric summary variable: the largest relative difference of the device's values
    from the CPU's (NaN where both are NaN counts as equal) and the number of cases that
    differ at all."""
    import numpy as np

    rows = []
    for name in cpu.data_vars:
        a = np.asarray(cpu[name].values)
        if name not in gpu or a.dtype.kind not in "fiu":
            continue
        a = a.astype(float).ravel()
        b = np.asarray(gpu[name].values, dtype=float).ravel()
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        scale = np.maximum(np.abs(a), np.abs(b))
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(same, 0.0, np.abs(a - b) / np.where(scale > 0, scale, 1.0))
        rel = np.where(np.isnan(rel), np.inf, rel)
        rows.append((str(name), float(rel.max(initial=0.0)), int((~same).sum())))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--duration", type=float, default=1.0, help="simulated time per case [s]")
    ap.add_argument("--cpu-max", type=int, default=1000,
                    help="largest sweep run on the CPU backend")
    ap.add_argument("--kernel-only", action="store_true",
                    help="time one device launch per size (no sweep, no files)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override of every case's config, e.g. joints.O.clearance=2.5e-4")
    ap.add_argument("--simulator", action="store_true",
                    help="run the CUDA path in numba's CUDA simulator (tiny sizes only)")
    ap.add_argument("--layout", choices=("soa", "aos", "soa-local", "soa-one-evaluate"),
                    default="soa",
                    help="the device layout (--kernel-only): structure of arrays, case by case, "
                         "or structure of arrays with the work arrays in each thread's local "
                         "memory")
    ap.add_argument("--capacity", type=int, default=None,
                    help="launch capacity of every soa launch (--kernel-only; default: the "
                         "smallest that holds each size)")
    ap.add_argument("--json", type=Path, default=None,
                    help="write the --kernel-only figures to this JSON file too")
    args = ap.parse_args(argv)
    EXTRA[:] = args.set
    if args.simulator:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"     # read when numba is first imported
    sys.path.insert(0, str(ROOT))
    from clearsweep.gpu import NoCudaDevice, device_name
    from clearsweep.simulation import prepare_kernel

    try:
        name = device_name()
    except NoCudaDevice as exc:
        print(str(exc).split(":")[0])
        return 0
    prepare_kernel()
    if args.kernel_only:
        print(f"device: {name}; two_clearances{''.join(' --set ' + o for o in EXTRA)}, "
              f"{args.duration:g} s of motion per case")
        print()
        result = kernel_only(args.sizes, args.duration, args.layout, args.capacity)
        if args.json is not None:
            import json

            result.update(device=name, overrides=list(EXTRA))
            args.json.write_text(json.dumps(result, indent=1))
        return 0
    # compile the device kernel outside the clock: one tiny batch
    timed_sweep(1, 1.0e-4, backend="cuda")
    print(f"device: {name}; CPU: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores; two_clearances, {args.duration:g} s of motion per case")
    print()
    print("| cases | cuda [s] | cuda cases/s | 2-worker CPU [s] | CPU cases/s | ratio |")
    print("|---|---|---|---|---|---|")
    compared = []
    for n in args.sizes:
        gpu_s, gpu_failed, gpu_ds = timed_sweep(n, args.duration, backend="cuda")
        if n <= args.cpu_max:
            cpu_s, cpu_failed, cpu_ds = timed_sweep(n, args.duration, workers=2)
            cpu = f"{cpu_s:.1f} | {n / cpu_s:,.1f} | {cpu_s / gpu_s:.1f}"
            compared.append((n, agreement(gpu_ds, cpu_ds)))
        else:
            cpu_failed, cpu = 0, "not run | | "
        note = f" ({gpu_failed} / {cpu_failed} failed)" if gpu_failed or cpu_failed else ""
        print(f"| {n:,}{note} | {gpu_s:.1f} | {n / gpu_s:,.1f} | {cpu} |", flush=True)
    for n, rows in compared:
        print()
        print(f"agreement with the CPU, {n:,} cases: largest relative difference, cases that "
              "differ")
        print()
        print("| summary | largest relative difference | cases differing |")
        print("|---|---|---|")
        for name, rel, differ in rows:
            print(f"| {name} | {rel:.2e} | {differ} of {n:,} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
