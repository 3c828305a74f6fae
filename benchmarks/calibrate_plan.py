"""Measure what the plans charge (clearsweep/data/plan_costs.yaml) and write the file.

The plans that ``sweep``, ``run``, ``life``, ``validate`` and ``--dry-run`` print price a
case by the joints that have clearance (clearsweep/budget.py, :func:`step_seconds`): an
ideal step, plus each clearance joint's share (a spherical joint's ball and socket, O's
journal, P's block on the guide's faces), plus each saved row a ``store: full`` part keeps, plus a
fixed cost per case; a life block adds its jump (the wear rates, the map grown, the
block's summary). This script measures each of those on this machine, in this process, the
way a sweep's worker runs a case (simulate, summarise, write its part), and writes them.
It also fits a socket's wear pace to configs/life.yaml's run (:func:`fit_wear_pace`), with
which a life plan counts the blocks to ``life.cycles`` (clearsweep.budget.WearPace):

    .venv/bin/python benchmarks/calibrate_plan.py              # measure and write the file
    .venv/bin/python benchmarks/calibrate_plan.py --dry-run    # measure and print only
    .venv/bin/python benchmarks/calibrate_plan.py --compile    # also a cold compile (~40 s)
    .venv/bin/python benchmarks/calibrate_plan.py --wear-pace  # the wear pace alone (~15 s)
    .venv/bin/python benchmarks/calibrate_plan.py --slider-crank   # its costs alone (~30 s)

Re-run it when the kernel changes (a joint type, the step, the outputs, the contact or
wear laws, which move the wear pace): the file records
the date, the machine, the load average and the kernel's cache key it was measured under.
Run from the repository root with nothing else running, and check the plans against whole
runs afterwards (benchmarks/README.md, "Plans against measured times").
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from clearsweep.budget import PLAN_COSTS_FILE, clearance_joints
from clearsweep.config import load_config, resolve_materials
from clearsweep.core.numba_compat import cache_dir
from clearsweep.service_life import block_steps, life
from clearsweep.simulation import prepare_kernel
from clearsweep.sweeping.parts import part_identity, with_identity, write_part
from clearsweep.sweeping.worker import CaseTask, _run_case

#: The clearance of each joint where a set gives it one [m] (O's and P's as the shipped
#: configs give them, A's and B's the main job's middle value).
CLEARANCE = {"O": ["joints.O.clearance=1e-4"], "A": ["joints.A.clearance=2.5e-4"],
             "B": ["joints.B.clearance=2.5e-4"],
             "P": ["joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4"]}
#: The joint sets measured: the ideal mechanism, each joint alone, and two mixes that check
#: that the joints' shares add up.
SETS = ["", "O", "A", "B", "P", "AB", "OABP"]
#: The two lengths of a case [s of motion]: the slope between them is the cost per step,
#: the intercept the cost per case.
DURATIONS = (0.01, 0.4)


def case_config(joints: str, duration: float, extra=()):
    """The realistic mechanism at 60 r/min, seated, with clearance at ``joints`` only."""
    sets = [f"joints.{j}.clearance=0" for j in "AB"] + [s for j in joints for s in CLEARANCE[j]]
    return load_config({"mechanism": {"preset": "realistic", "speed_rpm": 60.0}},
                       [*sets, f"solver.duration={duration}", *extra])


def time_case(cfg, store: str, repeats: int, parts: Path) -> float:
    """Least CPU time [s] of one case as a pool worker runs it: simulate, summarise, write.
    CPU time, not wall time: on the shared machine other jobs stretch the wall time, and a
    plan is for a machine whose cores the sweep has to itself."""
    best = float("inf")
    for i in range(repeats):
        began = time.process_time()
        part = _run_case(CaseTask(cfg, store))
        write_part(parts, f"{i:016x}", with_identity(part, part_identity(cfg, store)))
        best = min(best, time.process_time() - began)
        status = str(part["status"].values)
        if status != "ok":
            raise SystemExit(f"calibration case stopped: {status}")
    return best


def fit(short: float, long: float, steps_short: int, steps_long: int) -> tuple[float, float]:
    """(seconds per step, seconds per case) through two timed lengths."""
    slope = (long - short) / (steps_long - steps_short)
    return slope, short - slope * steps_short


def measure_steps(repeats: int, parts: Path) -> dict:
    """Cost per step of each joint set (summary store) and per saved row of a full part."""
    slopes, intercepts, row_extra = {}, [], []
    for joints in SETS:
        per_store = {}
        for store in ("summary", "full"):
            cfgs = [case_config(joints, d) for d in DURATIONS]
            steps = [round(c.solver.duration / c.solver.dt) for c in cfgs]
            times = [time_case(c, store, repeats, parts) for c in cfgs]
            per_store[store] = fit(times[0], times[1], steps[0], steps[1])
            print(f"  {joints or 'ideal':5s} {store:8s}: {steps[1] / times[1]:>9,.0f} steps/s "
                  f"({DURATIONS[1]} s of motion in {times[1]:.3f} s of CPU; "
                  f"{per_store[store][0] * 1e6:.3f} us a "
                  f"step, {per_store[store][1]:.3f} s a case)", flush=True)
        slopes[joints] = per_store["summary"][0]
        intercepts.append(per_store["summary"][1])
        row_extra.append(per_store["full"][0] - per_store["summary"][0])
    ideal = slopes[""]
    shares = {j: max(0.0, slopes[j] - ideal) for j in "OABP"}
    for mix in ("AB", "OABP"):
        priced = ideal + sum(shares[j] for j in mix)
        print(f"  {mix}: priced {priced * 1e6:.3f} us a step, measured {slopes[mix] * 1e6:.3f} "
              f"({slopes[mix] / priced:.2f})")
    # a full part's wear maps: the tiny B case on the default map and on the main job's
    maps = {}
    for shape in ((144, 288), (288, 576)):
        cfg = case_config("B", DURATIONS[0], [f"wear.map=[{shape[0]}, {shape[1]}]"])
        maps[shape[0] * shape[1]] = time_case(cfg, "full", repeats, parts)
    (small, t_small), (big, t_big) = sorted(maps.items())
    map_bin_s = max(0.0, (t_big - t_small) / (4 * (big - small)))
    print(f"  wear maps of a full part: {map_bin_s * 1e9:.3f} ns a bin and joint")
    return {"step_s": ideal, "joint_step_s": shares, "map_bin_s": map_bin_s,
            "row_s": max(0.0, statistics.median(row_extra)),
            "case_s": max(0.0, statistics.median(intercepts)),
            "check": {mix: {"priced_us": round((ideal + sum(shares[j] for j in mix)) * 1e6, 3),
                            "measured_us": round(slopes[mix] * 1e6, 3)} for mix in ("AB", "OABP")}}


#: The block's joints: the reliability example's but the guide P, whose steps' cost moves
#: with its motion by more than a block's bookkeeping costs.
NO_GUIDE = ["joints.P.clearance_y=0", "joints.P.clearance_z=0"]


def measure_blocks(costs: dict, repeats: int) -> float:
    """A life block's cost beyond its priced steps [s]: the jump, the wear rates and maps,
    the block's rows and row; the reliability example's map (72 x 144) and joints O, A and B,
    the slope between 2 and 6 blocks, less the steps at the joints' price.

    Without P: a block's cost beyond its steps is the small difference of two large times,
    and P's steps cost what its motion asks (a later block's about 10 % less than the
    start-up that the joint set's slope above includes): with P in it the difference came
    out negative (1.163 s a block against 1.42 s of priced steps) and wrote a cost of 0."""
    times = {}
    cfg = None
    for blocks in (2, 6):
        cfg = load_config(_reliability_base(), [f"life.max_blocks={blocks}", "life.cycles=1e9",
                                                *NO_GUIDE])
        best = float("inf")
        for _ in range(repeats):
            began = time.process_time()
            ds = life(cfg, allow_large=True)
            best = min(best, time.process_time() - began)
        times[blocks] = (best, int(ds.sizes["cycle"]))
    (t2, n2), (t6, n6) = times[2], times[6]
    per_block = (t6 - t2) / (n6 - n2)
    steps = block_steps(cfg)
    step = costs["step_s"] + sum(costs["joint_step_s"][j] for j in clearance_joints(cfg))
    jump = per_block - steps * step
    print(f"  life block ({clearance_joints(cfg)}): {per_block:.3f} s ({steps:,} steps at "
          f"{step * 1e6:.3f} us, and {jump:.3f} s for the jump and the block's bookkeeping)")
    return max(0.0, jump)


#: The life run a socket's wear pace is fitted to (WearPace, clearsweep/budget.py), and its joint.
PACE_CONFIG, PACE_JOINT = "configs/life.yaml", "B"


def fit_wear_pace(ds, cfg, joint: str = PACE_JOINT) -> dict:
    """A socket's wear pace (clearsweep.budget.WearPace) from a life run ``ds`` of ``cfg``
    that reached its ``life.cycles``: r0 the deepest bin of ``joint`` after the first block
    per revolution; K such that the jumps at r(h) = K / (K / r0 + h), each the allowance
    a_k over the rate at the allowances H_k grown before it, sum to the revolutions the
    run's uncut jumps took: dN_k = a_k / r0 + a_k H_k / K, so
    K = sum(a_k H_k) / sum(dN_k - a_k / r0). The run's own jumps, not its depths: the bin
    that limits a jump is not always the deepest, and what a plan needs is when the
    jumps reach life.cycles."""
    j = [str(x) for x in ds["joint"].values].index(joint)
    lc = cfg.life
    jc = getattr(cfg.joints, joint)
    coating = jc.coating_thickness if jc.coating != "none" else math.inf
    revs = float(ds["block_revolutions"].values[0])
    r0 = float(ds["wear_depth_max"].values[0, j]) / revs
    jumps = ds["jump_revolutions"].values
    cycles = ds["cycle"].values
    grown = spent = weighted = 0.0
    used = 0
    for k, jump in enumerate(jumps):
        if not jump > 0.0 or cycles[k] + jump + revs >= lc.cycles * (1.0 - 1e-9):
            break           # the last jump is cut to end at life.cycles
        step = lc.jump_clearance_fraction * jc.clearance
        if grown < coating:
            step = min(step, lc.jump_coating_fraction * max(coating - grown,
                                                            lc.jump_coating_fraction * coating))
        weighted += step * grown
        spent += float(jump) - step / r0
        grown += step
        used += 1
    if used < 2 or not (weighted > 0.0 and spent > 0.0 and r0 > 0.0):
        raise SystemExit(f"the wear pace needs a run that jumps at least twice; got {used} jumps")
    material = jc.coating if jc.coating != "none" else "steel"
    k = jc.wear_coefficient
    k = resolve_materials(cfg)[material].wear_coefficient_m2_per_N if k is None else k
    return {"first_rate_m": r0, "growth_m2": weighted / spent, "clearance_m": jc.clearance,
            "wear_coefficient_m2_per_N": k * cfg.wear.amplification,
            "reference": f"{PACE_CONFIG}, joint {joint}: {ds.sizes['cycle']} blocks to "
                         f"{float(cycles[-1]):.4g} revolutions ({used} jumps fitted)"}


def measure_wear_pace() -> dict:
    """Run configs/life.yaml (about 12 s of CPU, kernel cached) and fit its wear pace."""
    cfg = load_config(PACE_CONFIG)
    began = time.process_time()
    ds = life(cfg)
    pace = fit_wear_pace(ds, cfg)
    print(f"  wear pace ({PACE_CONFIG}, {time.process_time() - began:.1f} s): "
          f"r0 {pace['first_rate_m']:.4g} m a revolution, K {pace['growth_m2']:.4g} m^2 "
          f"a revolution; {pace['reference']}")
    return pace


#: The slider-crank's cases: configs/slider_crank.yaml (5000 r/min, dt 2.5e-6 s, the
#: benchmark's contact law) with clearance at one joint alone: B's 0.5 mm as the config's,
#: A's the same pin and bearing, O's journal the RSSP's 0.1 mm.
SLIDER_CRANK = "configs/slider_crank.yaml"
SLIDER_CRANK_JOINTS = {"": ["joints.B.clearance=0"],
                       "O": ["joints.B.clearance=0", "joints.O.clearance=1e-4"],
                       "A": ["joints.B.clearance=0", "joints.A.clearance=5e-4",
                             "joints.A.socket_radius=0.01"],
                       "B": []}
#: The two lengths of a slider-crank case [crank revolutions], the first left out of the
#: statistics: the slope between them is the cost per revolution.
SLIDER_CRANK_REVOLUTIONS = (3, 9)


def measure_slider_crank(costs: dict, repeats: int, parts: Path) -> dict:
    """The slider-crank's costs (PlanCosts.slider_crank_step_s, joint_revolution_s): its ideal step
    [s], and what each clearance joint adds per crank revolution [s] beyond its per-step
    share (``joint_step_s``, the RSSP's): the impacts, whose sub-steps the kernel takes at
    the contact's own time scale, so that their cost goes with the impacts, about a fixed
    number a revolution, not with the steps (0.5 mm at B, 5 revolutions: 0.08-0.10 s over
    the ideal case's at 1000, 2500 and 5000 r/min, with 5, 2 and 1 times the steps)."""
    slopes = {}
    for joints, sets in SLIDER_CRANK_JOINTS.items():
        cfgs = [load_config(SLIDER_CRANK, [*sets, f"solver.revolutions={n}"])
                for n in SLIDER_CRANK_REVOLUTIONS]
        if clearance_joints(cfgs[0]) != joints:
            raise SystemExit(f"slider-crank case {joints or 'ideal'}: clearance at "
                             f"{clearance_joints(cfgs[0]) or 'no joint'}")
        steps = [round(c.solver.duration / c.solver.dt) for c in cfgs]
        times = [time_case(c, "summary", repeats, parts) for c in cfgs]
        slopes[joints] = fit(times[0], times[1], steps[0], steps[1])[0]
        print(f"  slider-crank {joints or 'ideal'}: {slopes[joints] * 1e6:.3f} us a step "
              f"({SLIDER_CRANK_REVOLUTIONS[1]} revolutions in {times[1]:.3f} s)", flush=True)
    per_rev = round(60.0 / cfgs[0].mechanism.speed_rpm / cfgs[0].solver.dt)
    ideal = slopes[""]
    revolution = {j: max(0.0, (slopes[j] - ideal - costs["joint_step_s"][j]) * per_rev)
                  for j in "OAB"}
    print("  slider-crank per revolution: " + ", ".join(f"{j} {revolution[j]:.4f} s"
                                                        for j in "OAB"))
    return {"step_s": ideal, "joint_revolution_s": revolution}


def measure_imports(repeats: int) -> dict:
    """What a process pays once for the summaries' spectrum (``spectrum_s``: scipy.signal,
    imported by a worker's first case whose settled window holds a spectrum,
    motion.order_spectrum) and a sweep's driver for an ensemble's statistics
    (``ensemble_s``: scipy.stats and the intervals, stores.add_ensemble_statistics, on a
    summary sweep of 2 designs of 8 members), CPU time in a fresh process."""
    code = ("import time, clearsweep.simulation, clearsweep.summary, xarray; "
            "t = time.process_time(); import scipy.signal; print(time.process_time() - t)")
    spectrum = min(float(subprocess.run([sys.executable, "-c", code], check=True,
                                        capture_output=True, text=True).stdout.split()[-1])
                   for _ in range(repeats))
    cli = [sys.executable, "-c", "from clearsweep.cli import main; main()"]
    drivers = {}
    with tempfile.TemporaryDirectory() as tmp:
        base = ("{mechanism: {preset: realistic}, joints: {B: {clearance: 0.0}}, "
                "solver: {duration: 0.01}%s}")
        for name, extra, grid in (
                ("plain", "", ", ".join(f"{60.0 + i * 0.5:g}" for i in range(16))),
                ("ensemble", ", ensemble: {members: 8, seed: 1, perturb: {crank_phase_deg: 5}}",
                 "60, 60.5")):
            path = Path(tmp) / f"{name}.yaml"
            path.write_text(f"name: {name}\nstore: summary\nbase: {base % extra}\n"
                            f"sweep: {{grid: {{mechanism.speed_rpm: [{grid}]}}}}\n")
            drivers[name] = min(tree_cpu([*cli, "sweep", str(path), "-o", str(Path(tmp) / "o.nc"),
                                          "--overwrite", "--workers", "2", "-q", "--yes"])[1]
                                for _ in range(repeats))
    ensemble = max(0.0, drivers["ensemble"] - drivers["plain"])
    print(f"  spectrum's import {spectrum:.3f} s; an ensemble's statistics {ensemble:.3f} s "
          f"(driver {drivers['ensemble']:.2f} s against {drivers['plain']:.2f} s, 16 cases each)")
    return {"spectrum_s": spectrum, "ensemble_s": ensemble}


def _reliability_base() -> dict:
    """configs/reliability_joints.yaml's base config (one member's joints and life)."""
    from clearsweep.schema import read_yaml

    return read_yaml("configs/reliability_joints.yaml")["base"]


def tree_cpu(args: list[str], capture_stderr: bool = False) -> tuple[float, float, float]:
    """(wall, the process's CPU, its descendants' CPU) [s] of ``args``, the process tree
    polled every 50 ms (benchmarks/plan_vs_measured.py measures whole runs with it);
    ``capture_stderr``: the command's standard error kept for a failure's message."""
    import psutil

    began = time.perf_counter()
    proc = psutil.Popen(args, stdout=subprocess.DEVNULL,
                        stderr=subprocess.PIPE if capture_stderr else None)
    seen: dict[int, float] = {}
    own = 0.0
    while proc.poll() is None:
        try:
            t = proc.cpu_times()
            own = t.user + t.system
            for child in proc.children(recursive=True):
                try:
                    c = child.cpu_times()
                    seen[child.pid] = c.user + c.system
                except psutil.Error:
                    pass
        except psutil.Error:
            pass
        time.sleep(0.05)
    if proc.returncode:
        tail = proc.stderr.read().decode()[-2000:] if capture_stderr else ""
        raise SystemExit(f"{' '.join(args)}: exit {proc.returncode}" + (f": {tail}" if tail else ""))
    return time.perf_counter() - began, own, sum(seen.values())


def measure_start(costs: dict, repeats: int) -> dict:
    """A run's and a sweep's fixed costs and a sweep driver's cost per case [s].

    ``run_start_s``: the CPU time of ``clearsweep run`` of an ideal 0.01 s case, less its
    priced work. ``sweep_start_s``: the driver's CPU time of ``clearsweep sweep`` of two such
    cases on two workers, plus its workers' CPU time shared by the two (they start side by
    side), less the cases' priced work. ``assemble_case_s``: what the driver spends on each
    case (its part checked and copied into the file, and the summaries' statistics), from
    sweeps of 2 and 18 cases; ``assemble_row_s``: each saved row it copies of a ``store:
    full`` case, from full sweeps of 0.01 s and 0.1 s cases. The driver does this after the
    cases, one core while the other waits."""
    cli = [sys.executable, "-c", "from clearsweep.cli import main; main()"]
    work = costs["case_s"] + 1000 * costs["step_s"]
    with tempfile.TemporaryDirectory() as tmp:
        case = Path(tmp) / "tiny_case.yaml"
        case.write_text("mechanism: {preset: realistic}\njoints: {B: {clearance: 0.0}}\n"
                        "solver: {duration: 0.01}\n")

        def sweep(cases: int, store: str, duration: float) -> tuple[float, float]:
            path = Path(tmp) / "tiny.yaml"
            speeds = ", ".join(f"{60.0 + i * 0.5:g}" for i in range(cases))
            path.write_text(textwrap.dedent(f"""\
                name: tiny
                store: {store}
                base: {{mechanism: {{preset: realistic}}, joints: {{B: {{clearance: 0.0}}}},
                       solver: {{duration: {duration}}}}}
                sweep: {{grid: {{mechanism.speed_rpm: [{speeds}]}}}}
                """))
            best = (float("inf"), float("inf"))
            for _ in range(repeats):
                wall, own, workers = tree_cpu([*cli, "sweep", str(path), "-o",
                                               str(Path(tmp) / "tiny.nc"), "--overwrite",
                                               "--workers", "2", "-q", "--yes"])
                print(f"  sweep of {cases} cases of {duration} s, {store}: {wall:.2f} s wall, "
                      f"{own:.2f} s CPU in the driver, {workers:.2f} s in its workers")
                best = min(best, (own, workers))
            return best

        runs = []
        for _ in range(repeats):
            wall, own, _ = tree_cpu([*cli, "run", str(case), "-o", str(Path(tmp) / "c.nc"),
                                     "--overwrite", "-q"])
            runs.append(own - work)
            print(f"  run of a tiny case: {wall:.2f} s wall, {own:.2f} s CPU")
        two, two_workers = sweep(2, "summary", 0.01)
        many, _ = sweep(18, "summary", 0.01)
        full_short, _ = sweep(18, "full", 0.01)
        full_long, _ = sweep(18, "full", 0.1)
    per_case = max(0.0, (many - two) / 16)
    rows = (1001 - 101) * 18
    return {"run_start_s": max(0.0, min(runs)),
            "sweep_start_s": max(0.0, two - 2 * per_case + two_workers / 2 - work),
            "assemble_case_s": per_case,
            "assemble_row_s": max(0.0, (full_long - full_short) / rows)}


def measure_compile() -> float:
    """A cold compile of the RK4 kernel [s] in a fresh process with an empty cache: its CPU
    time, imports included (the wall time a quiet machine gives; a busy one stretches it)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = subprocess.run(
            [sys.executable, "-c", "import time; from clearsweep.simulation import "
             "prepare_kernel; wall = prepare_kernel('rk4'); print(wall, time.process_time())"],
            check=True, capture_output=True, text=True, env={**os.environ, "NUMBA_CACHE_DIR": tmp})
    wall, cpu = (float(x) for x in out.stdout.split()[-2:])
    print(f"  cold compile: {wall:.1f} s wall, {cpu:.1f} s CPU in all")
    return cpu


def machine() -> str:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, Python {platform.python_version()}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--compile", action="store_true", help="measure a cold compile too")
    parser.add_argument("--dry-run", action="store_true", help="print, do not write the file")
    parser.add_argument("--wear-pace", action="store_true",
                        help="measure the wear pace alone; keep the file's other costs")
    parser.add_argument("--slider-crank", action="store_true",
                        help="measure the slider-crank's costs, the spectrum's import and an "
                        "ensemble's statistics alone; keep the file's other costs")
    parser.add_argument("-o", "--output", default=str(PLAN_COSTS_FILE))
    args = parser.parse_args()
    load_before = os.getloadavg()
    prepare_kernel("rk4")
    if args.wear_pace or args.slider_crank:
        costs = kept_costs()
        if args.wear_pace:
            costs["wear_pace"] = measure_wear_pace()
            costs["pace_when"] = None
        if args.slider_crank:
            with tempfile.TemporaryDirectory() as tmp:
                costs["slider_crank"] = measure_slider_crank(costs, args.repeats, Path(tmp))
            costs.update(measure_imports(max(1, args.repeats - 1)))
            costs["later_when"] = None
        write(args, costs, load_before, os.getloadavg())
        return
    with tempfile.TemporaryDirectory() as tmp:
        print("cost per step and case (a worker's case: simulate, summarise, write its part):")
        costs = measure_steps(args.repeats, Path(tmp))
    print("a life block and a sweep's start:")
    costs["block_s"] = measure_blocks(costs, max(1, args.repeats - 1))
    costs.update(measure_start(costs, max(1, args.repeats - 1)))
    if args.compile:
        costs["compile_s"] = measure_compile()
    costs["wear_pace"] = measure_wear_pace()
    with tempfile.TemporaryDirectory() as tmp:
        costs["slider_crank"] = measure_slider_crank(costs, args.repeats, Path(tmp))
    costs.update(measure_imports(max(1, args.repeats - 1)))
    load_after = os.getloadavg()
    write(args, costs, load_before, load_after)


def kept_costs() -> dict:
    """The current file's costs (``--wear-pace``, ``--slider-crank``: only those are
    measured again), with when and where they were measured."""
    from clearsweep.budget import read_plan_costs

    old = read_plan_costs()
    costs = {name: getattr(old, name) for name in
             ("step_s", "row_s", "case_s", "map_bin_s", "block_s", "run_start_s",
              "sweep_start_s", "assemble_case_s", "assemble_row_s")}
    costs["joint_step_s"] = dict(old.joint_step_s)
    text = PLAN_COSTS_FILE.read_text().splitlines()
    start = text.index("measured:") + 1
    end = next(i for i in range(start, len(text)) if not text[i].startswith("  "))
    costs["measured"] = "\n".join(text[start:end])
    mark = "# the joints' shares checked on mixes (us a step): "
    lines = [line for line in PLAN_COSTS_FILE.read_text().splitlines() if line.startswith(mark)]
    costs["check"] = lines[0][len(mark):] if lines else "not recorded"
    # the wear pace and the later costs as they are, with when they were measured
    costs["wear_pace"] = {"reference": old.wear_pace.reference,
                          "first_rate_m": old.wear_pace.first_rate_m,
                          "growth_m2": old.wear_pace.growth_m2,
                          "clearance_m": old.wear_pace.clearance_m,
                          "wear_coefficient_m2_per_N": old.wear_pace.wear_coefficient_m2_per_N
                          } if old.wear_pace is not None else None
    costs["pace_when"] = _when_line(text, "(fit_wear_pace), measured")
    if old.slider_crank_step_s is not None:
        costs["slider_crank"] = {"step_s": old.slider_crank_step_s,
                                 "joint_revolution_s": dict(old.joint_revolution_s)}
        costs["spectrum_s"], costs["ensemble_s"] = old.spectrum_s, old.ensemble_s
        costs["later_when"] = _when_line(text, "(measure_slider_crank, measure_imports), measured")
    return costs


def _when_line(text: list[str], mark: str) -> str:
    """The line after the comment line that ends with ``mark`` (when a part was measured)."""
    for i, line in enumerate(text[:-1]):
        if line.endswith(mark):
            return text[i + 1].lstrip("# ").rstrip(";")
    return "not recorded"


def write(args, costs: dict, load_before, load_after) -> None:
    from clearsweep.budget import read_plan_costs

    old = read_plan_costs()
    compile_s = costs.get("compile_s", old.compile_s)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    shares = costs["joint_step_s"]
    pace = costs["wear_pace"]
    now = (f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
           f"tree {commit}, load average {load_before[0]:.2f}-{load_after[0]:.2f}")
    if "measured" in costs:
        # --wear-pace, --slider-crank: the other costs keep their own measurement; the
        # part measured now says when
        measured = costs["measured"]
        pace_when = costs["pace_when"] or now
        later_when = costs.get("later_when") or now
    else:
        measured = f"""\
  date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC
  machine: {machine()}
  load_average: [{load_before[0]:.2f}, {load_after[0]:.2f}]   # 1-minute, before and after
  tree: {commit}
  kernel_cache: {Path(cache_dir()).name}
  repeats: {args.repeats}
  timing: CPU time, the least of the repeats (other work stretches the wall time, not it)"""
        pace_when = later_when = "with the costs above"
    sc = costs["slider_crank"]
    revolution = sc["joint_revolution_s"]
    text = f"""\
# What clearsweep's plans charge (clearsweep/budget.py, read by `sweep`, `run`, `life`,
# `validate` and `--dry-run`), measured by benchmarks/calibrate_plan.py: re-run it when the
# kernel changes (a joint type, the step, the outputs) and check the plans against whole
# runs (benchmarks/README.md, "Plans against measured times").
measured:
{measured}
# one RK4 step on the output grid of the ideal mechanism, as a worker runs it [s]
step_s: {costs['step_s']:.4g}
# what a joint with clearance adds to each step [s]: A and B a ball in its socket, O the
# crank's journal, P the block on the guide's faces (an elastic foundation over each face)
joint_step_s: {{O: {shares['O']:.4g}, A: {shares['A']:.4g}, B: {shares['B']:.4g}, P: {shares['P']:.4g}}}
# each saved row a `store: full` part keeps (a run's or a full sweep's time series) [s]
row_s: {costs['row_s']:.4g}
# each case beyond its steps: packing, the seated start, the summaries, the part [s]
case_s: {costs['case_s']:.4g}
# each bin of each joint's wear map a `store: full` case writes [s]
map_bin_s: {costs['map_bin_s']:.4g}
# each life block beyond its priced steps: the jump (wear rates, the grown map), its rows
# and row, measured on the reliability example's block without P (measure_blocks) [s]
block_s: {costs['block_s']:.4g}
# a run's or a life run's fixed cost: the interpreter, the imports, the kernel from the cache [s]
run_start_s: {costs['run_start_s']:.3g}
# a sweep's fixed cost: the driver's and the workers' start, the kernel from the cache [s]
sweep_start_s: {costs['sweep_start_s']:.3g}
# what a sweep's driver spends on each case (its checks before the run; its part checked
# and copied into the file, the statistics, after it), and on each saved row of a
# `store: full` case [s]
assemble_case_s: {costs['assemble_case_s']:.4g}
assemble_row_s: {costs['assemble_row_s']:.4g}
# a cold compile of the RK4 kernel on an empty cache, CPU time with the imports [s]{'' if 'compile_s' in costs else
                                                              ' (kept: run with --compile)'}
compile_s: {compile_s:.3g}
# the joints' shares checked on mixes (us a step): {costs['check']}
# a ball-and-socket joint's wear pace, which a life plan walks to life.cycles with
# (clearsweep.budget.WearPace: the deepest bin deepens by K / (K / r0 + h) a revolution at
# depth h), fitted to a life run that reached its life.cycles (fit_wear_pace), measured
# {pace_when};
# a config's r0 and K are these scaled by its Archard k times wear.amplification, and by
# its clearance
wear_pace:
  reference: "{pace['reference']}"
  first_rate_m: {pace['first_rate_m']:.4g}
  growth_m2: {pace['growth_m2']:.4g}
  clearance_m: {pace['clearance_m']:.4g}
  wear_coefficient_m2_per_N: {pace['wear_coefficient_m2_per_N']:.4g}
# the costs below (measure_slider_crank, measure_imports), measured
# {later_when};
# once per sweep process whose cases' settled windows hold a spectrum: scipy.signal's
# import [s]
spectrum_s: {costs['spectrum_s']:.3g}
# once per ensemble sweep, in its driver after the cases: the ensemble's statistics [s]
ensemble_s: {costs['ensemble_s']:.3g}
# the slider-crank (mechanism.kind: slider_crank, configs/slider_crank.yaml at 5000 r/min):
# its ideal step [s], and what each joint with clearance adds per crank revolution beyond
# its share of each step above [s] (the impacts' sub-steps)
slider_crank:
  step_s: {sc['step_s']:.4g}
  joint_revolution_s: {{O: {revolution['O']:.4g}, A: {revolution['A']:.4g}, B: {revolution['B']:.4g}}}
"""
    print(text)
    if not args.dry_run:
        Path(args.output).write_text(text)
        print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
