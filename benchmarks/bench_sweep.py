"""Sweep benchmarks: worker scaling, memory of a 500-case summary sweep, the shipped sweeps.

Run: ``python benchmarks/bench_sweep.py [--repeats 2] [--shipped] [--overhead] [--host]
[--main-job] [--ensemble]``; prints markdown. ``--overhead``: CPU per case outside the kernel.
``--host``: host time per case of the main job's 48 cases run in this process (everything
but the kernel: packing, the dataset, the part write, the assembly share), per store, at the
main job's duration and at 0.01 s.
``--main-job``: the 48-case main job on 1 worker, 2 pool workers and a 2-worker local Dask
cluster, wall and CPU time.

- **Scaling.** One list of cases (16 cases, 1 s of motion each, full store)
  run serially in this process and on two warm worker processes, alternately,
  ``--repeats`` times; the ratio is serial time / two-worker time, best of
  each. Warm means that the Numba kernel is loaded in every process before the
  clock starts (a warm-up sweep on the same pool); the cold two-worker time
  (pool start and kernel load included) is reported beside it.
- **Memory.** A 500-case ``store: summary`` sweep of short cases (5 ms of
  motion) with two workers, in a fresh interpreter; the peak of the summed
  resident memory of the driver and all its descendants (sampled every 20
  ms with psutil; RSS counts shared library pages once per process, so this
  is an upper bound), and each process's own peak.
- **Ensemble** (``--ensemble``): 48 designs (4 coatings x 6 clearances x clearance at
  B / at A and B) x 16 members = 768 cases of 5 ms of motion, ``store: summary``, 2
  workers, in a fresh interpreter; beside it a plain 768-case summary sweep of the same
  cases without perturbations (48 designs x 16 speeds) to show that members run at the
  speed of ordinary cases; wall, cases/s, peak memory and file size per case.
- **Shipped sweeps** (``--shipped``): ``configs/coating_clearance.yaml`` and
  ``configs/paper.yaml`` through the CLI with two workers: wall time, peak
  memory, cases and file size.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]

#: 4 coatings x 2 clearances x {B, AB}: 16 cases of 1 s of motion, as in the main sweep.
SCALING_SWEEP = {
    "name": "scaling",
    "base": {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 1.0}},
    "sweep": {"grid": {"joints.B.coating": ["none", "MoS2", "lead", "PTFE"],
                       "joints.B.clearance": [1.0e-4, 5.0e-4]},
              "zip": [{"name": "clearance_joints", "labels": ["B", "AB"],
                       "joints.A.clearance": [0.0, 2.5e-4]}]},
}
WARMUP_SWEEP = {"name": "warmup", "base": {"solver": {"duration": 0.002}},
                "sweep": {"grid": {"mechanism.speed_rpm": [30, 40, 50, 60]}}}

#: 4 coatings x 25 clearances x 5 speeds = 500 cases of 5 ms of motion, summaries only.
MEMORY_SWEEP = {
    "name": "memory",
    "store": "summary",
    "base": {"joints": {"A": {"clearance": 2.5e-4}}, "solver": {"duration": 0.005}},
    "sweep": {"grid": {"joints.B.coating": ["none", "MoS2", "lead", "PTFE"],
                       "joints.B.clearance": [round(5e-5 + 4e-5 * i, 10) for i in range(25)],
                       "mechanism.speed_rpm": [30, 45, 60, 75, 90]}},
}

_CASE_GRID = {"joints.B.coating": ["none", "MoS2", "lead", "PTFE"],
            "joints.B.clearance": [5.0e-5, 1.0e-4, 2.5e-4, 5.0e-4, 7.5e-4, 1.0e-3]}
_JOINT_SETS = [{"name": "clearance_joints", "labels": ["B", "AB"], "joints.A.clearance": [0.0, 2.5e-4]}]
#: 48 designs x 16 members = 768 cases of 5 ms, summaries only.
ENSEMBLE_SWEEP = {
    "name": "ensemble",
    "store": "summary",
    "base": {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.005},
             "ensemble": {"members": 16, "seed": 1,
                          "perturb": {"ball_offset": 0.5, "crank_phase_deg": 5.0,
                                      "wear_coefficient_cv": 0.3}}},
    "sweep": {"grid": _CASE_GRID, "zip": _JOINT_SETS},
}
#: The same 768 cases without an ensemble: 48 designs x 16 speeds.
PLAIN_SWEEP = {
    "name": "plain",
    "store": "summary",
    "base": {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.005}},
    "sweep": {"grid": {**_CASE_GRID, "mechanism.speed_rpm": [52.0 + i for i in range(16)]},
              "zip": _JOINT_SETS},
}

RUN_SNIPPET = """
import json, sys, time
from clearsweep.sweeping import run_sweep
t0 = time.perf_counter()
with run_sweep(json.loads(sys.argv[1]), sys.argv[2], workers=2, progress=False) as ds:
    cases, failed = int(ds.attrs["sweep_cases"]), int(ds.attrs["sweep_failed"])
print(json.dumps({"wall_s": time.perf_counter() - t0, "cases": cases, "failed": failed}))
"""


def timed_sweep(doc: dict, **kwargs) -> float:
    """Seconds to run ``doc`` to a temporary file (assembly included)."""
    return timed_sweep_kernel(doc, **kwargs)[0]


def timed_sweep_kernel(doc: dict, **kwargs) -> tuple[float, float]:
    """Seconds to run ``doc`` to a temporary file (assembly included), and the sum of its
    cases' ``wall_time`` (the kernel's seconds)."""
    from clearsweep.sweeping import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with run_sweep(doc, Path(tmp) / "s.nc", progress=False, **kwargs) as ds:
            wall = time.perf_counter() - t0
            return wall, float(ds["wall_time"].sum())


def scaling(repeats: int) -> dict:
    """Serial vs two warm workers on the same cases, alternately; cold two-worker run beside."""
    from clearsweep.sweeping import expand, process_pool

    n = len(expand(SCALING_SWEEP).runnable())
    cold = timed_sweep(SCALING_SWEEP, workers=2)
    timed_sweep(WARMUP_SWEEP, workers=1)                   # kernel loaded in this process
    serial, pooled = [], []
    with process_pool(2) as pool:
        timed_sweep(WARMUP_SWEEP, client=pool)             # ... and in both workers
        for _ in range(repeats):
            serial.append(timed_sweep(SCALING_SWEEP, workers=1))
            pooled.append(timed_sweep(SCALING_SWEEP, client=pool))
    return {"cases": n, "serial": serial, "pooled": pooled, "cold": cold,
            "ratio": min(serial) / min(pooled)}


def _cpu_seconds() -> float:
    """CPU time of this process and its live descendants (pool or cluster workers)."""
    total = 0.0
    me = psutil.Process()
    for proc in [me, *me.children(recursive=True)]:
        try:
            t = proc.cpu_times()
            total += t.user + t.system
        except psutil.Error:
            pass
    return total


def main_job(repeats: int) -> dict:
    """The shipped main job (configs/coating_clearance.yaml, 48 cases): one worker (this
    process), two pool workers and a two-worker local Dask cluster, each warmed up (kernel
    loaded) before its clock starts and alone on the machine while it runs (pool and
    cluster are started and shut down around their own runs); rounds alternate. Wall time,
    and CPU time of this process and its children (workers, nannies)."""
    from distributed import Client, LocalCluster

    from clearsweep.sweeping import expand, process_pool

    plan_doc = str(ROOT / "configs" / "coating_clearance.yaml")
    n = len(expand(plan_doc).runnable())
    timed_sweep(WARMUP_SWEEP, workers=1)
    rows: dict[str, list[tuple[float, float, float]]] = {
        "1 worker": [], "2 workers (pool)": [], "2 workers (Dask, local)": []}

    def measure(label: str, **kwargs) -> None:
        cpu0 = _cpu_seconds()
        wall, kernel = timed_sweep_kernel(plan_doc, **kwargs)
        rows[label].append((wall, _cpu_seconds() - cpu0, kernel))

    for _ in range(repeats):
        measure("1 worker", workers=1)
        with process_pool(2) as pool:
            timed_sweep(WARMUP_SWEEP, client=pool)
            measure("2 workers (pool)", client=pool)
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            timed_sweep(WARMUP_SWEEP, client=client)
            measure("2 workers (Dask, local)", client=client)
    return {"cases": n, "rows": rows}


def host_per_case(store: str, duration: float | None = None, repeats: int = 2) -> dict:
    """The main job's cases run in this process (``workers=1``, warm kernel) with ``store``
    (and ``duration``, default the job's own), best of ``repeats``: seconds per case of the
    sweep's wall time (assembly included) beyond the kernel's (the cases' ``wall_time``), and
    of its CPU time beyond the kernel's CPU time (the thread's CPU time inside
    ``simulation.run_kernel``), which a machine busy with other work does not inflate."""
    import yaml

    from clearsweep import simulation
    from clearsweep.sweeping import run_sweep

    doc = yaml.safe_load((ROOT / "configs" / "coating_clearance.yaml").read_text())
    doc["store"] = store
    if duration is not None:        # in seconds, instead of the job's revolutions
        doc["base"]["solver"] = {"duration": duration}
        doc["base"].pop("metrics", None)
    timed_sweep(WARMUP_SWEEP, workers=1)
    kernel_cpu = [0.0]
    real = simulation.run_kernel

    def counted(*args, **kwargs):
        t0 = time.thread_time()
        try:
            return real(*args, **kwargs)
        finally:
            kernel_cpu[0] += time.thread_time() - t0

    best: dict | None = None
    simulation.run_kernel = counted
    try:
        for _ in range(repeats):
            kernel_cpu[0] = 0.0
            with tempfile.TemporaryDirectory() as tmp:
                t0, c0 = time.perf_counter(), time.process_time()
                with run_sweep(doc, Path(tmp) / "s.nc", workers=1, progress=False) as ds:
                    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                    kernel, n = float(ds["wall_time"].sum()), int(ds.attrs["sweep_cases"])
            run = {"host_s": (wall - kernel) / n, "host_cpu_s": (cpu - kernel_cpu[0]) / n,
                   "kernel_s": kernel / n, "kernel_cpu_s": kernel_cpu[0] / n, "wall_s": wall,
                   "cases": n}
            if best is None or run["host_cpu_s"] < best["host_cpu_s"]:
                best = run
    finally:
        simulation.run_kernel = real
    assert best is not None
    return best


def case_overhead(n: int = 50) -> dict:
    """CPU per case outside the kernel: a worker's whole job for a 1 ms two-clearance case
    (simulate, summarize, build the part; no file), summary and full store, minus the
    kernel's own time; ``n`` cases each, warm."""
    from clearsweep.config import load_config
    from clearsweep.simulation import prepare_kernel
    from clearsweep.sweeping.worker import CaseTask, _run_case

    prepare_kernel()
    cfg = load_config(ROOT / "configs" / "two_clearances.yaml", ["solver.duration=0.001"])
    out = {}
    for store in ("summary", "full"):
        _run_case(CaseTask(cfg, store))
        kernel = 0.0
        t0 = time.process_time()
        for _ in range(n):
            kernel += float(_run_case(CaseTask(cfg, store))["wall_time"])
        out[store] = ((time.process_time() - t0) / n, kernel / n)
    return out


class TreeMemory:
    """Peak of the summed RSS of a process and its descendants, sampled in a thread."""

    def __init__(self, pid: int, period: float = 0.02):
        self.root, self.period = psutil.Process(pid), period
        self.peak_total = 0
        self.peak_each: dict[int, tuple[str, int]] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                procs = [self.root, *self.root.children(recursive=True)]
            except psutil.Error:
                return
            total = 0
            for p in procs:
                try:
                    rss = p.memory_info().rss
                    role = "driver" if p.pid == self.root.pid else _role(p)
                except psutil.Error:
                    continue
                total += rss
                if rss > self.peak_each.get(p.pid, ("", 0))[1]:
                    self.peak_each[p.pid] = (role, rss)
            self.peak_total = max(self.peak_total, total)
            self._stop.wait(self.period)

    def stop(self) -> dict:
        self._stop.set()
        self._thread.join()
        by_role: dict[str, int] = {}
        for role, rss in self.peak_each.values():
            by_role[role] = max(by_role.get(role, 0), rss)
        return {"total_mb": self.peak_total / 2**20,
                "largest_mb": {r: v / 2**20 for r, v in sorted(by_role.items())}}


def _role(p: psutil.Process) -> str:
    cmd = " ".join(p.cmdline())
    if "forkserver" in cmd:
        return "pool worker" if p.parent() and "forkserver" in " ".join(p.parent().cmdline()) \
            else "forkserver"
    if "resource_tracker" in cmd:
        return "resource tracker"
    return "other child"


def measured_run(command: list[str]) -> dict:
    """Run ``command``; its wall time, output and the peak memory of its process tree."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT)
    memory = TreeMemory(proc.pid)
    out, err = proc.communicate()
    wall = time.perf_counter() - t0
    result = {"wall_s": wall, "returncode": proc.returncode, "stdout": out, "stderr": err,
              **memory.stop()}
    return result


def memory_sweep(doc: dict = MEMORY_SWEEP) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "memory.nc"
        run = measured_run([sys.executable, "-c", RUN_SNIPPET, json.dumps(doc), str(out)])
        if run["returncode"]:
            raise RuntimeError(run["stderr"])
        run.update(json.loads(run["stdout"].strip().splitlines()[-1]))
        run["file_mb"] = out.stat().st_size / 2**20
    return run


def shipped(name: str) -> dict:
    from clearsweep.dataset import open_results

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / f"{name}.nc"
        run = measured_run([sys.executable, "-m", "clearsweep.cli", "sweep", f"configs/{name}.yaml",
                            "-o", str(out), "--workers", "2", "--no-progress"])
        if run["returncode"] not in (0, 1):
            raise RuntimeError(run["stderr"])
        with open_results(out) as ds:
            run.update(cases=int(ds.attrs["sweep_cases"]), failed=int(ds.attrs["sweep_failed"]),
                       skipped=int(ds.attrs["sweep_skipped"]),
                       case_wall_s=float(ds["wall_time"].sum()),
                       statuses=sorted(set(ds["status"].values.ravel().tolist())))
        run["file_mb"] = out.stat().st_size / 2**20
    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2, help="alternating timing rounds")
    parser.add_argument("--shipped", action="store_true", help="also run the shipped sweeps")
    parser.add_argument("--overhead", action="store_true",
                        help="only the CPU per case outside the kernel (1 ms cases)")
    parser.add_argument("--host", action="store_true",
                        help="only the host time per case of the main job's cases, in this process")
    parser.add_argument("--main-job", action="store_true",
                        help="only the 48-case main job: 1 worker, 2 pool workers, 2 Dask workers")
    parser.add_argument("--ensemble", action="store_true",
                        help="only the 768-case ensemble and its plain twin")
    args = parser.parse_args()

    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    if args.overhead:
        print("\n## CPU per case outside the kernel (1 ms two-clearance case, warm)\n")
        print("| store | CPU per case [ms] | kernel [ms] | outside the kernel [ms] |")
        print("|---|---|---|---|")
        for store, (cpu, kernel) in case_overhead().items():
            print(f"| {store} | {1e3 * cpu:.1f} | {1e3 * kernel:.2f} | {1e3 * (cpu - kernel):.1f} |")
        return
    if args.host:
        print("\n## Host time per case: main job's 48 cases in this process\n")
        print("| store | duration [s] | kernel per case: wall / CPU [ms] | host per case: wall "
              "- kernel wall [ms] | host per case: CPU - kernel CPU [ms] | sweep wall [s] |")
        print("|---|---|---|---|---|---|")
        for store in ("summary", "full"):
            for duration in (None, 0.01):
                h = host_per_case(store, duration, args.repeats)
                print(f"| {store} | {duration or 'job (1.0)'} | {1e3 * h['kernel_s']:.1f} / "
                      f"{1e3 * h['kernel_cpu_s']:.1f} | {1e3 * h['host_s']:.1f} | "
                      f"{1e3 * h['host_cpu_s']:.1f} | {h['wall_s']:.1f} |", flush=True)
        return
    if args.main_job:
        r = main_job(args.repeats)
        print(f"\n## Main job (configs/coating_clearance.yaml, {r['cases']} cases), warm\n")
        print("| backend | wall [s] per round | CPU [s] per round (all processes) | "
              "kernel per worker [s] (sum of wall_time / workers) | wall / kernel per worker | "
              "speed-up vs 1 worker (best/best) | CPU vs pool (best/best) |")
        print("|---|---|---|---|---|---|---|")
        best = {k: (min(w for w, _, _ in v), min(c for _, c, _ in v)) for k, v in r["rows"].items()}
        for label, runs in r["rows"].items():
            workers = 1 if label == "1 worker" else 2
            kernel = [k / workers for _, _, k in runs]
            print(f"| {label} | {', '.join(f'{w:.1f}' for w, _, _ in runs)} | "
                  f"{', '.join(f'{c:.1f}' for _, c, _ in runs)} | "
                  f"{', '.join(f'{k:.1f}' for k in kernel)} | "
                  f"{', '.join(f'{w / k:.2f}' for (w, _, _), k in zip(runs, kernel))} | "
                  f"{best['1 worker'][0] / best[label][0]:.2f}x | "
                  f"{best[label][1] / best['2 workers (pool)'][1]:.2f} |", flush=True)
        return
    if args.ensemble:
        print("\n## 48 designs x 16 members, summary store, 2 workers\n")
        print("| sweep | cases | wall [s] | cases/s | peak RSS, driver + descendants [MB] | "
              "file [MB] | file per case [bytes] |")
        print("|---|---|---|---|---|---|---|")
        for doc in (ENSEMBLE_SWEEP, PLAIN_SWEEP):
            m = memory_sweep(doc)
            print(f"| {doc['name']} | {m['cases']} | {m['wall_s']:.1f} | {m['cases'] / m['wall_s']:.1f} | "
                  f"{m['total_mb']:.0f} | {m['file_mb']:.2f} | {m['file_mb'] * 2**20 / m['cases']:.0f} |",
                  flush=True)
        return
    s = scaling(args.repeats)
    print("\n## Scaling: serial vs 2 workers, same cases\n")
    print("| cases | serial [s] | 2 workers, warm [s] | speed-up (best/best) | 2 workers, cold [s] |")
    print("|---|---|---|---|---|")
    print(f"| {s['cases']} | {', '.join(f'{t:.2f}' for t in s['serial'])} | "
          f"{', '.join(f'{t:.2f}' for t in s['pooled'])} | {s['ratio']:.2f}x | {s['cold']:.2f} |")

    m = memory_sweep()
    print("\n## 500-case summary sweep, 2 workers\n")
    print("| cases | wall [s] | cases/s | peak RSS, driver + descendants [MB] | largest per process [MB] | file [MB] |")
    print("|---|---|---|---|---|---|")
    each = ", ".join(f"{r} {v:.0f}" for r, v in m["largest_mb"].items())
    print(f"| {m['cases']} | {m['wall_s']:.1f} | {m['cases'] / m['wall_s']:.1f} | {m['total_mb']:.0f} | "
          f"{each} | {m['file_mb']:.2f} |")

    if args.shipped:
        print("\n## Shipped sweeps, 2 workers (CLI)\n")
        print("| config | cases (run / skipped) | failed | wall [s] | sum of case wall times [s] | "
              "peak RSS, all processes [MB] | file [MB] |")
        print("|---|---|---|---|---|---|---|")
        for name in ("coating_clearance", "paper"):
            r = shipped(name)
            print(f"| {name} | {r['cases'] - r['skipped']} / {r['skipped']} | {r['failed']} | "
                  f"{r['wall_s']:.1f} | {r['case_wall_s']:.1f} | {r['total_mb']:.0f} | "
                  f"{r['file_mb']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
