"""Every device measurement of the CUDA backend in one prepared call (issue 43 item 7).

Run: ``python benchmarks/device_suite.py OUT_DIR`` on a machine with a CUDA device (within
about 8 minutes on an H100 or H200, ``--budget`` seconds in all), or
``python benchmarks/device_suite.py OUT_DIR --simulator`` without one: the same steps in
numba's CUDA simulator on 8 cases of a few steps (tests/test_device_suite.py runs exactly
that), so that the call is known to work before device time is spent. Steps, in order:

1. **builds**: each kernel the later steps launch (layout aos; soa at the capacities they
   use), compiled in parallel processes into Numba's on-disk cache
   (``CLEARSWEEP_CUDA_CACHE=1``), with ``--ptxas`` each also built to PTX for ptxas'
   registers and spills (``python -m clearsweep.ptx``, the same figures as without a
   device); the later steps load the builds. Skipped in the simulator.
2. **kernel**: ``bench_gpu.py --kernel-only`` at 10,000 and 30,000 two-clearance cases
   (``--kernel-sizes``) for the case-by-case layout (aos) and the structure-of-arrays one
   (soa), each in its own process, with the CPU agreement on three cases.
3. **sweep, cuda**: ``clearsweep sweep --backend cuda`` of 10^4 cases x 1 s, end to end
   (process start, compile or cache load, transfers and the results file included).
4. **sweep, CPU**: the same sweep's first ``--cpu-cases`` cases (100 per core by default) on
   the host's CPU workers (``--backend processes``), side by side in the same call; its
   cases/s against the device's.
4b. **variants** (issue 43 item 6), where time is left: the kernel step again for the
   work arrays in each thread's local memory (layout soa-local), for the
   structure-of-arrays kernel built to prefer the most L1 (``CLEARSWEEP_CUDA_CARVEOUT=maxl1``)
   and for its step with one ``evaluate`` call site (layout soa-one-evaluate).
5. **ncu**, where ``ncu`` is on the PATH: achieved occupancy, L1/L2 hit rates, DRAM
   throughput, sectors per request and the warp stall reasons of one launch of 2,000 short
   cases per layout (the raw CSV kept).

It writes ``suite.json`` (everything measured, the commands, each step's output tail and
what was skipped and why), ``suite.md`` (one markdown table) and, with ncu, its CSV per
layout under OUT_DIR: four files at most. The steps' own files (logs, sweep files, results)
go to a temporary folder named in suite.json. A step that fails or runs out of time is
recorded as such and the next one runs.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks" / "bench_gpu.py"

#: The kernel benchmark's cases: the wear map made smaller than the default [144, 288] so
#: that 30,000 cases fit half an H100's memory in one launch (1.46 MB per case with the
#: default map: 44 GB); both layouts run the same cases.
KERNEL_SET = ("wear.map=[72,144]",)

#: ncu's sections for step 5: achieved occupancy, L1/L2 hit rates and DRAM throughput
#: (MemoryWorkloadAnalysis), sectors per request (MemoryWorkloadAnalysis_Tables), stall
#: reasons (WarpStateStats).
NCU_SECTIONS = ("SpeedOfLight", "Occupancy", "MemoryWorkloadAnalysis",
                "MemoryWorkloadAnalysis_Tables", "WarpStateStats")

#: The ncu metrics picked out for the table: (name in the CSV, label).
NCU_METRICS = (("Achieved Occupancy", "achieved occupancy [%]"),
               ("L1/TEX Hit Rate", "L1 hit rate [%]"),
               ("L2 Hit Rate", "L2 hit rate [%]"),
               ("DRAM Throughput", "DRAM throughput [%]"),
               ("Mem Busy", "memory busy [%]"))


class Suite:
    """The suite's record and clock: each step's result, and the time left."""

    def __init__(self, out: Path, work: Path, budget: float, simulator: bool):
        self.out = out
        self.work = work
        self.began = time.perf_counter()
        self.budget = budget
        self.simulator = simulator
        self.record: dict = {"simulator": simulator, "steps": {}, "skipped": {}}
        self.full = ""      # the last step's whole standard output

    def left(self) -> float:
        return self.budget - (time.perf_counter() - self.began)

    def env(self, extra: dict | None = None) -> dict:
        env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
        if self.simulator:
            env.update(NUMBA_ENABLE_CUDASIM="1", NUMBA_DISABLE_JIT="1")
        else:
            env["CLEARSWEEP_CUDA_CACHE"] = "1"
        env.update(extra or {})
        return env

    def run(self, name: str, argv: list[str], need: float, extra: dict | None = None) -> dict | None:
        """Run argv (a step's process) with the time left; its wall time, exit status and
        output tail, or None where it was skipped (recorded as such)."""
        if self.left() < need:
            self.record["skipped"][name] = f"out of time ({self.left():.0f} s left, needs {need:.0f})"
            return None
        began = time.perf_counter()
        try:
            proc = subprocess.run(argv, capture_output=True, text=True, env=self.env(extra), cwd=ROOT,
                                  timeout=max(1.0, self.left()))
            rc, tail = proc.returncode, (proc.stdout + proc.stderr)[-3000:]
            self.full = proc.stdout
        except subprocess.TimeoutExpired as exc:
            out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
            rc, tail = 124, out[-3000:]
            self.full = out
        res = {"argv": [str(a) for a in argv], "seconds": time.perf_counter() - began, "rc": rc,
               "tail": tail}
        (self.work / f"{name}.log").write_text(proc.stdout + proc.stderr if rc != 124 else tail)
        return res


def host() -> dict:
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "load_average": list(load), "python": platform.python_version()}


def versions() -> dict:
    from importlib import metadata

    out = {}
    for dist in ("numpy", "numba", "numba-cuda"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


BUILD = r"""
import json, sys, time
from clearsweep import ptx
layout, cap = sys.argv[1], int(sys.argv[2])
res = {"layout": layout, "capacity": cap if layout.startswith("soa") else None}
if layout == "cpu":
    from clearsweep.simulation import prepare_kernel
    began = time.perf_counter()
    prepare_kernel()
    res.update(build_s=time.perf_counter() - began, ptxas="the CPU kernel (Numba's cache)")
    print("BUILD " + json.dumps(res))
    sys.exit(0)
res["build_s"] = ptx.build_kernel(layout, cap)
if sys.argv[3] != "1":
    res["ptxas"] = "not asked for (--ptxas)"
    print("BUILD " + json.dumps(res))
    sys.exit(0)
try:
    from numba import cuda
    cc = cuda.get_current_device().compute_capability
    rep = ptx.ptxas_report(ptx.compile_run_cases_ptx(cc, layout, cap), f"sm_{cc[0]}{cc[1]}")
    res.update(ptxas=rep.line(), registers=rep.registers, spill_stores=rep.spill_store_bytes,
               spill_loads=rep.spill_load_bytes, stack=rep.stack_bytes)
except Exception as exc:
    res["ptxas"] = f"not built: {type(exc).__name__}: {str(exc).splitlines()[0][:200]}"
print("BUILD " + json.dumps(res))
"""


def builds(suite: Suite, kernels: list[tuple[str, int]], ptxas: bool = False) -> None:
    """Step 1: the kernels compiled in parallel processes (into the on-disk cache), the CPU
    kernel beside them (the agreement and the CPU sweep load it)."""
    if suite.simulator:
        suite.record["skipped"]["builds"] = "the simulator compiles nothing"
        return
    began = time.perf_counter()
    procs = [(layout, cap, subprocess.Popen([sys.executable, "-c", BUILD, layout, str(cap),
                                             "1" if ptxas else "0"],
                                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                            text=True, env=suite.env(), cwd=ROOT))
             for layout, cap in kernels]
    done = []
    for layout, cap, proc in procs:
        try:
            text, _ = proc.communicate(timeout=max(1.0, min(suite.left() - 120, 300)))
        except subprocess.TimeoutExpired:
            proc.kill()
            text, _ = proc.communicate()
        line = [ln for ln in text.splitlines() if ln.startswith("BUILD ")]
        done.append(json.loads(line[-1][6:]) if line else
                    {"layout": layout, "capacity": cap, "error": text[-1500:]})
    suite.record["steps"]["builds"] = {"seconds": time.perf_counter() - began, "kernels": done}


#: Step 2's kernels: (name, layout, environment), each timed in its own process.
KERNELS = (("aos", "aos", {}), ("soa", "soa", {}))

#: Step 4b, issue 43 item 6's arrangements, timed against step 2's "soa" where time is left:
#: the fixed-size work arrays in each thread's local memory ("soa-local", which the
#: hardware interleaves thread by thread), and the structure-of-arrays kernel preferring
#: the most L1 over shared memory (``core.device.CARVEOUT``; compiled in its own process,
#: outside the on-disk cache, so that no build of another carve-out is loaded for it), and
#: the step with one ``evaluate`` call site (``core.onestep``: a quarter less PTX, more spill
#: stores and fewer loads, ptxas says; its time decides).
VARIANTS = (("soa-local", "soa-local", {}),
            ("soa-maxl1", "soa", {"CLEARSWEEP_CUDA_CARVEOUT": "maxl1",
                                  "CLEARSWEEP_CUDA_CACHE": "0"}),
            ("soa-one-evaluate", "soa-one-evaluate", {}))


def kernel(suite: Suite, sizes: list[int], duration: float, kernels=KERNELS,
           step: str = "kernel") -> None:
    """Step 2 (and 4b, ``kernels=VARIANTS``): one launch per size and kernel, each kernel in
    its own process."""
    rows = []
    cap = None
    if not suite.simulator:
        from clearsweep.gpu import capacity_for

        cap = capacity_for(max(sizes))
    for name, layout, extra in kernels:
        path = suite.work / f"kernel_{name}.json"
        argv = [sys.executable, str(BENCH), "--kernel-only", "--layout", layout, "--sizes",
                *map(str, sizes), "--duration", str(duration), "--json", str(path)]
        argv += [a for s in KERNEL_SET for a in ("--set", s)]
        if suite.simulator:
            argv.append("--simulator")
        elif layout != "aos":
            argv += ["--capacity", str(cap)]
        res = suite.run(f"kernel_{name}", argv, need=30 if step == "kernel" else 90, extra=extra)
        if res is None:
            continue
        res["kernel"] = name
        if res["rc"] == 0 and path.exists():
            res.update(json.loads(path.read_text()))
        rows.append(res)
    suite.record["steps"][step] = rows


def sweep_file(suite: Suite, n: int, duration: float) -> tuple[Path, list[str]]:
    """A sweep file of n two-clearance cases of ``duration`` seconds (bench_gpu's) and the
    ``--set`` overrides it is run with."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_gpu import sweep_doc

    doc = sweep_doc(n, duration)
    overrides = doc.pop("overrides")
    path = suite.work / f"sweep_{n}.yaml"
    path.write_text(json.dumps(doc))
    return path, overrides


def sweeps(suite: Suite, n: int, duration: float, cpu_cases: int, workers: int) -> None:
    """Steps 3 and 4: the sweep through the CLI on the device, then its first cpu_cases
    cases on the CPU workers."""
    cli = [sys.executable, "-c", "from clearsweep.cli import main; main()"]     # the script
    for name, cases, backend in (("sweep_cuda", n, ["--backend", "cuda"]),
                                 ("sweep_cpu", cpu_cases, ["--backend", "processes",
                                                           "--workers", str(workers)])):
        path, overrides = sweep_file(suite, cases, duration)
        out = suite.work / f"{name}.nc"
        argv = [*cli, "sweep", str(path), "-o", str(out), "--yes", "--no-progress", "--overwrite",
                *[a for o in overrides for a in ("--set", o)], *backend]
        res = suite.run(name, argv, need=20)
        if res is None:
            continue
        res.update(cases=cases, duration_s=duration, cases_per_s=cases / res["seconds"])
        if name == "sweep_cpu":
            res["workers"] = workers
        if out.exists():
            res["file_bytes"] = out.stat().st_size
            try:
                import xarray as xr

                with xr.open_dataset(out) as ds:
                    res["failed"] = int(ds.attrs.get("sweep_failed", -1))
                    res["statuses"] = {str(k): int(v) for k, v in
                                       zip(*_unique(ds["status"].values))}
            except Exception as exc:       # the record says what could not be read
                res["read_error"] = f"{type(exc).__name__}: {exc}"
            out.unlink()        # the results are not kept: the figures are
        suite.record["steps"][name] = res


def _unique(values):
    import numpy as np

    keys, counts = np.unique(np.asarray(values).astype(str), return_counts=True)
    return keys, counts


def ncu(suite: Suite, cases: int) -> None:
    """Step 5: ncu's sections of one launch per layout, where ncu is present."""
    exe = shutil.which("ncu")
    if suite.simulator or exe is None:
        suite.record["skipped"]["ncu"] = "the simulator" if suite.simulator else "ncu not on the PATH"
        return
    rows = []
    for layout in ("aos", "soa"):
        argv = [exe, "--csv", "--kernel-name", "regex:run_cases", "--launch-skip", "1",
                "--launch-count", "1", *[a for s in NCU_SECTIONS for a in ("--section", s)],
                sys.executable, str(BENCH), "--kernel-only", "--layout", layout, "--sizes",
                str(cases), "--duration", "0.002", *[a for s in KERNEL_SET for a in ("--set", s)]]
        res = suite.run(f"ncu_{layout}", argv, need=40)
        if res is None:
            continue
        full = suite.full
        (suite.out / f"ncu_{layout}.csv").write_text(full)
        res["metrics"] = {label: _ncu_value(full, metric) for metric, label in NCU_METRICS}
        res["stalls"] = {k: v for k, v in _ncu_rows(full).items() if "stall" in k.lower()}
        rows.append(res)
    suite.record["steps"]["ncu"] = rows


def _ncu_rows(text: str) -> dict[str, str]:
    """Metric name -> value of ncu's --csv output (the last occurrence of each)."""
    import csv
    import io

    out = {}
    lines = [ln for ln in text.splitlines() if ln.startswith('"')]
    for row in csv.reader(io.StringIO("\n".join(lines))):
        if len(row) >= 3 and row[-3] != "Metric Name":
            out[row[-3]] = row[-1]
    return out


def _ncu_value(text: str, metric: str) -> str | None:
    return _ncu_rows(text).get(metric)


def table(record: dict) -> str:
    """The markdown table of the record."""
    steps = record["steps"]
    lines = [f"device: {record['device']}; host: {record['host']['cores']} cores, load "
             f"{record['host']['load_average'][0]:.2f}; numpy {record['versions']['numpy']}, "
             f"numba-cuda {record['versions']['numba-cuda']}", "",
             "| step | layout | cases | duration [s] | wall [s] | figure | note |",
             "|---|---|---|---|---|---|---|"]
    for b in steps.get("builds", {}).get("kernels", []):
        lines.append(f"| build | {b.get('layout')} {b.get('capacity') or ''} | | | "
                     f"{b.get('build_s', float('nan')):.1f} | {b.get('ptxas', b.get('error', ''))[:120]} | |")
    for k in steps.get("kernel", []) + steps.get("variants", []):
        for launch in k.get("launches", []):
            name = k.get("kernel", k.get("layout"))
            lines.append(f"| kernel | {name} | {launch['cases']:,} | {k.get('duration_s')} | "
                         f"{launch['seconds']:.2f} | {launch['steps_per_s']:.3g} RK4 steps/s | "
                         f"{launch['statuses']} |")
        for a in k.get("agreement", []):
            lines.append(f"| CPU agreement | {k.get('kernel', k.get('layout'))} | case {a['case']} | | | statistics "
                         f"{a['stats_max_rel']:.1e}, worn volume {a['wvol_max_rel']:.1e} relative | "
                         f"{a['status']} |")
        if k.get("rc"):
            lines.append(f"| kernel | {k.get('kernel')} | | | "
                         f"{k['seconds']:.1f} | failed (exit {k['rc']}) | see its log |")
    for name in ("sweep_cuda", "sweep_cpu"):
        s = steps.get(name)
        if s is None:
            continue
        note = f"exit {s['rc']}" + (f", {s['workers']} workers" if "workers" in s else "")
        if "statuses" in s:
            note += f", {s['statuses']}"
        lines.append(f"| {name.replace('_', ', ')} | | {s['cases']:,} | {s['duration_s']} | "
                     f"{s['seconds']:.1f} | {s['cases_per_s']:.3g} cases/s | {note} |")
    if "sweep_cuda" in steps and "sweep_cpu" in steps:
        ratio = steps["sweep_cuda"]["cases_per_s"] / steps["sweep_cpu"]["cases_per_s"]
        lines.append(f"| device / CPU workers | | | | | {ratio:.2f}x cases/s | |")
    for n in steps.get("ncu", []):
        layout = n["argv"][n["argv"].index("--layout") + 1]
        figures = ", ".join(f"{k} {v}" for k, v in n["metrics"].items() if v is not None)
        lines.append(f"| ncu | {layout} | | | {n['seconds']:.1f} | {figures or 'no metrics read'} | "
                     f"exit {n['rc']} |")
    for name, why in record["skipped"].items():
        lines.append(f"| {name} | | | | | skipped | {why} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="folder for suite.json, suite.md and the logs")
    ap.add_argument("--simulator", action="store_true",
                    help="numba's CUDA simulator, 8 cases of a few steps (no device)")
    ap.add_argument("--budget", type=float, default=450.0, help="seconds for the whole call")
    ap.add_argument("--kernel-sizes", type=int, nargs="+", default=None)
    ap.add_argument("--kernel-duration", type=float, default=None)
    ap.add_argument("--sweep-cases", type=int, default=None)
    ap.add_argument("--sweep-duration", type=float, default=None)
    ap.add_argument("--cpu-cases", type=int, default=None,
                    help="cases of the CPU sweep (default: 100 per core; 8 in the simulator)")
    ap.add_argument("--ncu-cases", type=int, default=2000)
    ap.add_argument("--ptxas", action="store_true",
                    help="each build also compiled to PTX for ptxas' figures (about a minute "
                         "more per build; the figures do not depend on the device)")
    args = ap.parse_args(argv)
    sim = args.simulator
    sizes = args.kernel_sizes or ([8] if sim else [10_000, 30_000])
    kdur = args.kernel_duration or (2.0e-4 if sim else 0.05)
    n = args.sweep_cases or (8 if sim else 10_000)
    sdur = args.sweep_duration or (2.0e-4 if sim else 1.0)
    cores = os.cpu_count() or 1
    workers = 1 if sim else cores
    cpu_cases = args.cpu_cases or (8 if sim else 100 * cores)
    args.out.mkdir(parents=True, exist_ok=True)
    import tempfile

    work = Path(tempfile.mkdtemp(prefix="device_suite_"))
    suite = Suite(args.out, work, args.budget, sim)
    suite.record["work_folder"] = str(work)
    if sim:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
    sys.path.insert(0, str(ROOT))
    from clearsweep.gpu import NoCudaDevice, capacity_for, device_name

    suite.record.update(host=host(), versions=versions())
    try:
        suite.record["device"] = device_name()      # a numpy / numba-cuda mismatch: here
    except NoCudaDevice as exc:
        suite.record["device"] = None
        suite.record["error"] = str(exc)
        print(f"device_suite: {exc}", file=sys.stderr)
        (args.out / "suite.json").write_text(json.dumps(suite.record, indent=1))
        return 2
    kernels = [("cpu", 0), ("aos", capacity_for(max(sizes))), ("soa", capacity_for(max(sizes))),
               ("soa", capacity_for(n)), ("soa-local", capacity_for(max(sizes))),
               ("soa-one-evaluate", capacity_for(max(sizes)))]
    builds(suite, list(dict.fromkeys(kernels)), args.ptxas)
    kernel(suite, sizes, kdur)
    sweeps(suite, n, sdur, cpu_cases, workers)
    kernel(suite, sizes, kdur, VARIANTS, "variants")
    ncu(suite, args.ncu_cases)
    suite.record["seconds"] = time.perf_counter() - suite.began
    (args.out / "suite.json").write_text(json.dumps(suite.record, indent=1))
    (args.out / "suite.md").write_text(table(suite.record))
    print(table(suite.record))
    return 0


if __name__ == "__main__":
    sys.exit(main())
