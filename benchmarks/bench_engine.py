"""Engine benchmark, measured side by side in one run: this tree's kernel against a previous
revision's (steps/s, median of alternating runs in separate processes, and the ratio; cold
compile of both), each shipped case config's throughput, ns per right-hand side, and the
same right-hand side driven by scipy.integrate.solve_ivp; and, in this tree alone, the
slider-crank's one-clearance case against the RSSP's (``MECHANISM_CASES``, steps per CPU
second, the ratio).

Run: ``python benchmarks/bench_engine.py [--baseline REV] [--repeats 5] [--duration 1.0]
[--out FILE] [--rates-only [--bearings]] [--mechanisms]`` (``--rates-only``: the side-by-side
steps/s alone, no cold compile, shipped configs or solve_ivp, with ``--bearings`` of the
cases whose clearance joints are bearings, ``BEARING_CASES``; ``--mechanisms``: the
mechanisms' table alone). The baseline defaults to the merge-base of HEAD with ``main``; it is
exported with ``git archive`` into a temporary folder. Writes markdown to stdout (and to
``--out`` if given).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CASES = {
    "ideal": [],
    "one clearance (B)": ["joints.B.clearance=2.5e-4"],
    "two clearances (A, B)": ["joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4"],
}

#: Cases whose clearance joints are journals in bearings (the revolute type: the RSSP's O,
#: the slider-crank's pins), for ``--bearings``: the bearing map's read side by side.
BEARING_CASES = {
    "RSSP, O": ["joints.O.clearance=2.5e-4"],
    "RSSP, O, A and B": ["joints.O.clearance=2.5e-4", "joints.A.clearance=2.5e-4",
                         "joints.B.clearance=2.5e-4"],
    "slider-crank, B, 60 r/min": ["mechanism.kind=slider_crank", "mechanism.preset=flores_benchmark",
                                  "joints.B.clearance=2.5e-4"],
}

#: The mechanisms side by side, this tree alone (the baseline may predate mechanism.kind):
#: case -> (overrides, simulated seconds or None for --duration). The RSSP's row is
#: CASES' one clearance; the slider-crank's first row the same joint, clearance, speed, step
#: and length; its second the published benchmark's speed and clearance, with the shipped
#: config's Baumgarte constants (50 1/s: at 5 1/s the crank pin's constraint drifts to its
#: stop in about 0.2 s at 5000 r/min, configs/slider_crank.yaml) and the wear not fed back
#: (fed back, 1 s of it stops on energy_residual at 0.53 s, as the Poincare runs of
#: docs/mechanisms.md do).
SLIDER_CRANK = ["mechanism.kind=slider_crank", "mechanism.preset=flores_benchmark"]
BENCHMARK = [*SLIDER_CRANK, "mechanism.speed_rpm=5000", "joints.B.clearance=5.0e-4",
             "joints.B.socket_radius=0.01", "solver.baumgarte=[50.0, 50.0]",
             "wear.feedback=false"]
MECHANISM_CASES = {
    "RSSP, one clearance (B), 60 r/min": (CASES["one clearance (B)"], None),
    "slider-crank, one clearance (B), 60 r/min": (
        [*SLIDER_CRANK, "joints.B.clearance=2.5e-4"], None),
    "slider-crank, B 0.5 mm, 5000 r/min": (BENCHMARK, None),
    # the same without wear: what the wear map's deposits cost at its contact loads
    "slider-crank, B 0.5 mm, 5000 r/min, wear off": ([*BENCHMARK, "wear.enabled=false"], None),
}

#: Times each case of MECHANISM_CASES (argv[1]: their JSON, each case's duration filled in)
#: once, warm; prints {case: [grid steps run, RK4 sub-steps, CPU seconds, status]}: the
#: steps the run took (a run that stops early counts the steps up to its stop).
MECHANISM_SNIPPET = """
import json, sys, time
from clearsweep.config import load_config
from clearsweep.simulation import preflight, run_kernel
from clearsweep.core import layout as L
out = {}
for name, (overrides, duration) in json.loads(sys.argv[1]).items():
    packed = preflight(load_config({"solver": {"duration": duration}}, overrides))
    run_kernel(packed)
    cpu = time.process_time()
    res = run_kernel(packed)
    cpu = time.process_time() - cpu
    steps = min(packed.n_steps, round(res.t_end / packed.p[L.P_DT]))
    out[name] = [steps, int(res.rk4_steps), cpu, res.status]
print(json.dumps(out))
"""

COMPILE_SNIPPET = """
import time
t0 = time.perf_counter()
from clearsweep.simulation import simulate
simulate({"solver": {"duration": 1e-4, "save_every": 1}, "joints": {"A": {"clearance": 2.5e-4},
          "B": {"clearance": 2.5e-4}}})
print(time.perf_counter() - t0)
"""


ROOT = Path(__file__).resolve().parent.parent

#: Times every case of CASES once with the kernel of the tree it runs in (argv[1]: the
#: simulated duration); prints {case: [RK4 grid steps, wall seconds, CPU seconds]} as JSON
#: (the process's CPU time around the run: on a loaded machine, where the wall time counts
#: the waits for a core, the steadier measure).
RATE_SNIPPET = """
import json, sys, time
from clearsweep.config import load_config
from clearsweep.simulation import preflight, prepare_kernel, run_kernel
cases = json.loads(sys.argv[2])
prepare_kernel()
out = {}
for name, overrides in cases.items():
    packed = preflight(load_config({"solver": {"duration": float(sys.argv[1])}}, overrides))
    run_kernel(packed)
    cpu = time.process_time()
    res = run_kernel(packed)
    cpu = time.process_time() - cpu
    # a KernelRun (a dict in revisions before it): this snippet also times older trees
    out[name] = [packed.n_steps, res["wall_time"] if isinstance(res, dict) else res.wall_time, cpu]
print(json.dumps(out))
"""


def in_tree(tree: Path, code: str, *args: str, cache: str | None = None) -> str:
    """Run ``code`` in a fresh interpreter on the clearsweep of ``tree``; its stdout."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    if cache:
        env["NUMBA_CACHE_DIR"] = cache
    res = subprocess.run([sys.executable, "-c", code, *args], env=env, cwd=tree, check=True,
                         capture_output=True, text=True)
    return res.stdout


def compile_times(tree: Path = ROOT) -> tuple[float, float]:
    """(cold, cached) seconds to import and run a 10-step case in a fresh interpreter."""
    with tempfile.TemporaryDirectory() as cache:
        out = [float(in_tree(tree, COMPILE_SNIPPET, cache=cache).strip().splitlines()[-1])
               for _ in range(2)]
    return out[0], out[1]


def export_revision(rev: str, dest: Path) -> str:
    """Write the tree of git revision ``rev`` into ``dest``; its short commit id."""
    commit = subprocess.run(["git", "rev-parse", "--short", rev], cwd=ROOT, check=True,
                            capture_output=True, text=True).stdout.strip()
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return commit


def default_baseline() -> str:
    """The merge-base of HEAD with main: the release this branch started from."""
    res = subprocess.run(["git", "merge-base", "HEAD", "main"], cwd=ROOT, capture_output=True,
                         text=True)
    return res.stdout.strip() if res.returncode == 0 else "HEAD"


def side_by_side(trees: dict[str, Path], duration: float, repeats: int,
                 cpu: bool = False, cases: dict = CASES) -> dict:
    """{tree label: {case: median steps/s}}: the trees' kernels timed alternately, each
    repeat in a fresh process per tree; per CPU second of the process with ``cpu``, else
    per wall second."""
    rates: dict[str, dict[str, list[float]]] = {label: {c: [] for c in cases} for label in trees}
    for label, tree in trees.items():  # warm the on-disk caches
        in_tree(tree, RATE_SNIPPET, "1e-3", json.dumps(cases))
    for _ in range(repeats):
        for label, tree in trees.items():
            res = json.loads(in_tree(tree, RATE_SNIPPET, str(duration), json.dumps(cases)))
            for case, (steps, wall, seconds) in res.items():
                rates[label][case].append(steps / (seconds if cpu else wall))
    return {label: {c: statistics.median(v) for c, v in r.items()} for label, r in rates.items()}


def mechanisms_side_by_side(duration: float, repeats: int) -> dict[str, dict]:
    """{case: {"steps": grid steps per CPU second, "rk4": RK4 (sub-)steps per CPU second,
    "status": the runs' statuses}} of MECHANISM_CASES in this tree: every case in each of
    ``repeats`` fresh processes, one after the other (the same load for all), the medians."""
    cases = {name: (ov, duration if d is None else d) for name, (ov, d) in MECHANISM_CASES.items()}
    in_tree(ROOT, MECHANISM_SNIPPET, json.dumps({n: (ov, 1e-3) for n, (ov, _) in cases.items()}))
    runs: dict[str, list] = {name: [] for name in cases}
    for _ in range(repeats):
        res = json.loads(in_tree(ROOT, MECHANISM_SNIPPET, json.dumps(cases)))
        for name, row in res.items():
            runs[name].append(row)
    return {name: {"steps": statistics.median(r[0] / r[2] for r in rows),
                   "rk4": statistics.median(r[1] / r[2] for r in rows),
                   "duration": cases[name][1], "ran": rows[0][0],
                   "status": sorted({r[3] for r in rows})}
            for name, rows in runs.items()}


def mechanism_lines(duration: float, repeats: int) -> list[str]:
    """The mechanisms' table (markdown lines), with the load average around it."""
    load = os.getloadavg()[0]
    rates = mechanisms_side_by_side(duration, repeats)
    reference = rates[next(iter(MECHANISM_CASES))]["steps"]
    return [
        f"Mechanisms, this tree: steps per CPU second, median of {repeats} runs (a fresh "
        "process per run, every case in each), h = 1e-5 s, uncoated steel; the ratio to the "
        "RSSP's one-clearance case:",
        "",
        "| case | simulated [s] | grid steps run | grid steps / CPU s | RK4 (sub-)steps / CPU s "
        "| status | ratio |",
        "|---|---|---|---|---|---|---|",
        *(f"| {name} | {r['duration']:g} | {r['ran']:,} | {r['steps']:,.0f} | {r['rk4']:,.0f} | "
          f"{', '.join(r['status'])} | {r['steps'] / reference:.2f} |" for name, r in rates.items()),
        "",
        f"load average (1 min) before the timed runs: {load:.1f}, after: {os.getloadavg()[0]:.1f}",
    ]


def shipped_case_configs() -> list[Path]:
    """configs/*.yaml that are single cases (not sweep files, as ``load_config`` tells them:
    ``config.file_kind``; a one-design reliability file has no ``sweep:`` section)."""
    import yaml

    from clearsweep.config import file_kind

    return [path for path in sorted((ROOT / "configs").glob("*.yaml"))
            if file_kind(yaml.safe_load(path.read_text()) or {}) != "sweep"]


def config_rate(path: Path, duration: float) -> tuple[float, float, float]:
    """(grid steps/s, RK4 sub-steps/s, simulated s per wall s) of a shipped config, warm."""
    from clearsweep.config import load_config
    from clearsweep.simulation import preflight, prepare_kernel, run_kernel

    prepare_kernel()
    packed = preflight(load_config(str(path), [f"solver.duration={duration}"]))
    run_kernel(packed)
    raw = run_kernel(packed)
    wall = raw.wall_time
    return packed.n_steps / wall, raw.rk4_steps / wall, raw.t_end / wall


def packed_case(overrides, duration):
    from clearsweep.config import load_config, resolve_materials
    from clearsweep.params import pack

    cfg = load_config({"solver": {"duration": duration}}, overrides)
    return pack(cfg, resolve_materials(cfg))


def rk4_rate(packed, repeats=3) -> float:
    """Warm RK4 steps per second (best of ``repeats``)."""
    from clearsweep.simulation import run_kernel

    run_kernel(packed)
    best = min(run_kernel(packed).wall_time for _ in range(repeats))
    return packed.n_steps / best


def rhs_ns(packed, n=200_000) -> float:
    """Nanoseconds per right-hand-side evaluation (Numba loop, no Python in between)."""
    from numba import njit

    from clearsweep.core import layout as L
    from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
    from clearsweep.core.work import Model, Solve

    @njit
    def loop(y, p, jp, n):
        s = np.zeros((L.N_JOINTS, L.N_S))
        wmap = np.zeros((L.N_JOINTS, 36, 72))
        dy = np.zeros(L.N_Y)
        dg = np.zeros(L.N_D)
        C = np.zeros((NZ, NZ))
        S = np.zeros((NZ, NZ))
        Lm = np.zeros((NZ, NZ))
        vz = np.zeros((VZ_ROWS, NZ))
        acc = 0.0
        for i in range(n):
            evaluate(1e-3 * (i % 7), y, Model(p, jp, s, wmap), dy, dg, False, Solve(C, S, Lm, vz))
            acc += dy[30]
        return acc

    y = packed.y0.copy()
    loop(y, packed.p, packed.jp, 10)
    t0 = time.perf_counter()
    loop(y, packed.p, packed.jp, n)
    return (time.perf_counter() - t0) / n * 1e9


def step_breakdown(overrides, repeats=3, n=200_000) -> dict[str, float]:
    """Nanoseconds of a stage evaluation, a step-end evaluation (diagnostics, energies, the
    stiff rate) and a whole RK4 step, at a settled state of the case; and a stage evaluation
    without the wear-map read (wear.feedback off)."""
    from numba import njit

    from clearsweep.core import layout as L
    from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
    from clearsweep.core.work import Model, Solve
    from clearsweep.simulation import run_kernel

    @njit
    def loop(y, p, jp, n, full, wmap):
        s = np.zeros((L.N_JOINTS, L.N_S))
        s[:, 0] = 0.01
        dy = np.zeros(L.N_Y)
        dg = np.zeros(L.N_D)
        C = np.zeros((NZ, NZ))
        S = np.zeros((NZ, NZ))
        Lm = np.zeros((NZ, NZ))
        vz = np.zeros((VZ_ROWS, NZ))
        acc = 0.0
        for i in range(n):
            evaluate(1e-3 * (i % 7), y, Model(p, jp, s, wmap), dy, dg, full, Solve(C, S, Lm, vz))
            acc += dy[30]
        return acc

    def per_call(packed, full):
        raw = run_kernel(packed)
        y = raw.y[raw.n_saved - 1].copy()
        wmap = np.zeros((L.N_JOINTS,) + tuple(packed.map_shape))
        loop(y, packed.p, packed.jp, 10, full, wmap)
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            loop(y, packed.p, packed.jp, n, full, wmap)
            best = min(best, time.perf_counter() - t0)
        return best / n * 1e9

    packed = packed_case(overrides, 0.05)
    out = {"stage": per_call(packed, False), "step end": per_call(packed, True)}
    out["stage, no map read"] = per_call(packed_case([*overrides, "wear.feedback=false"], 0.05), False)
    packed.n_steps = 20_000
    run_kernel(packed)
    out["RK4 step"] = min(run_kernel(packed).wall_time for _ in range(repeats)) / packed.n_steps * 1e9
    return out


def solve_ivp_rate(packed, duration) -> tuple[float, int, float]:
    """The same right-hand side under solve_ivp (RK45, rtol 1e-8, atol 1e-10), no wear/status.

    Returns (right-hand-side evaluations per second, evaluations, wall seconds).
    """
    from scipy.integrate import solve_ivp

    from clearsweep.core import layout as L
    from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
    from clearsweep.core.work import Model, Solve

    s = np.zeros((L.N_JOINTS, L.N_S))
    wmap = np.zeros((L.N_JOINTS, 36, 72))
    dg = np.zeros(L.N_D)
    C = np.zeros((NZ, NZ))
    S = np.zeros((NZ, NZ))
    Lm = np.zeros((NZ, NZ))
    vz = np.zeros((VZ_ROWS, NZ))

    model = Model(packed.p, packed.jp, s, wmap)
    solve = Solve(C, S, Lm, vz)

    def f(t, y):
        dy = np.empty(L.N_Y)
        evaluate(t, y, model, dy, dg, False, solve)
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
    ap.add_argument("--baseline", default=None,
                    help="git revision to compare with (default: merge-base of HEAD and main)")
    ap.add_argument("--repeats", type=int, default=5, help="alternating runs per tree")
    ap.add_argument("--config-duration", type=float, default=0.1,
                    help="simulated time per shipped config [s]")
    ap.add_argument("--rates-only", action="store_true",
                    help="the side-by-side steps/s alone (no compile times, configs, solve_ivp)")
    ap.add_argument("--baseline-tree", default=None,
                    help="a copy of the baseline tree to time in place of exporting --baseline "
                         "(then its label; the copy's kernel cache stays warm between runs)")
    ap.add_argument("--cpu-time", action="store_true",
                    help="steps per CPU second of each run's process (a loaded machine) rather "
                         "than per wall second")
    ap.add_argument("--bearings", action="store_true",
                    help="with --rates-only: time the cases with bearings in clearance "
                         "(BEARING_CASES: O, O with A and B, the slider-crank's B) in place of "
                         "the goal cases")
    ap.add_argument("--mechanisms", action="store_true",
                    help="the mechanisms' table alone (this tree: the slider-crank against the "
                         "RSSP, steps per CPU second)")
    args = ap.parse_args(argv)

    lines = [
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}",
        "",
    ]
    if args.mechanisms:
        text = "\n".join(lines + mechanism_lines(args.duration, args.repeats))
        print(text)
        if args.out:
            with open(args.out, "w") as fh:
                fh.write(text + "\n")
        return text
    with tempfile.TemporaryDirectory() as tmp:
        if args.baseline_tree:
            base = Path(args.baseline_tree)
            commit = args.baseline or base.name       # the label: the revision it holds
        else:
            base = Path(tmp)
            commit = export_revision(args.baseline or default_baseline(), base)
        print(f"baseline: {commit}", file=sys.stderr)
        trees = {commit: base, "this tree": ROOT}
        colds = {} if args.rates_only else {label: compile_times(tree) for label, tree in trees.items()}
        load = os.getloadavg()[0]
        cases = BEARING_CASES if args.bearings else CASES
        rates = side_by_side(trees, args.duration, args.repeats, args.cpu_time, cases)
    if colds:
        lines += [
            "JIT compile (import + 10-step two-clearance case, fresh interpreter, empty cache):",
            "",
            "| tree | cold [s] | cached [s] |",
            "|---|---|---|",
            *(f"| {label} | {cold:.1f} | {cached:.2f} |" for label, (cold, cached) in colds.items()),
            "",
        ]
    lines += [
        f"RK4 steps per {'CPU' if args.cpu_time else 'wall'} second, {args.duration:g} s simulated "
        f"per case, median of {args.repeats} alternating runs (a fresh process per tree and run):",
        "",
        f"| case | {commit} | this tree | ratio |",
        "|---|---|---|---|",
        *(f"| {case} | {rates[commit][case]:,.0f} | {rates['this tree'][case]:,.0f} | "
          f"{rates['this tree'][case] / rates[commit][case]:.2f} |" for case in cases),
        "",
        f"load average (1 min) before the timed runs: {load:.1f}, after: {os.getloadavg()[0]:.1f}",
    ]
    if args.rates_only:
        text = "\n".join(lines)
        print(text)
        if args.out:
            with open(args.out, "w") as fh:
                fh.write(text + "\n")
        return text
    lines += ["", *mechanism_lines(args.duration, args.repeats)]
    lines += [
        "",
        f"Shipped case configs, {args.config_duration:g} s simulated each (warm, this tree):",
        "",
        "| config | grid steps/s | RK4 (sub-)steps/s | simulated s / wall s |",
        "|---|---|---|---|",
    ]
    for path in shipped_case_configs():
        grid, sub, sim = config_rate(path, args.config_duration)
        lines.append(f"| {path.name} | {grid:,.0f} | {sub:,.0f} | {sim:.3f} |")
    lines += [
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
    lines += [
        "",
        "Where a step's time goes (ns, warm, a settled state; the wear map zero for the "
        "evaluation loops):",
        "",
        "| case | stage evaluation | step-end evaluation | stage without the map read | RK4 step |",
        "|---|---|---|---|---|",
    ]
    for name, ov in CASES.items():
        b = step_breakdown(ov)
        lines.append(f"| {name} | {b['stage']:,.0f} | {b['step end']:,.0f} | "
                     f"{b['stage, no map read']:,.0f} | {b['RK4 step']:,.0f} |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text + "\n")
    return text


if __name__ == "__main__":
    main()
