"""Each shipped config's plan against its measured time (benchmarks/README.md, "Plans
against measured times").

For every config in configs/ this runs the command a user runs (some cut short with
``--set``, where the plan scales linearly: the table says so), first with ``--dry-run``
to read the plan's time, then for real, and measures the whole process tree: wall time, and
the CPU time of the driver and of its workers. On a shared machine the wall time stretches
with the other jobs; the CPU times do not, so the table also gives the wall time the run
would take with its cores to itself: the driver's CPU time plus the workers' CPU time shared
by the workers (the driver waits while the cases run).

    .venv/bin/python benchmarks/plan_vs_measured.py                 # every config
    .venv/bin/python benchmarks/plan_vs_measured.py life ideal      # the rows named so
    .venv/bin/python benchmarks/plan_vs_measured.py --plan-only     # the plans alone

Run from the repository root with a warm kernel cache; results go to a temporary folder.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

CS = [sys.executable, "-c", "from clearsweep.cli import main; main()"]
#: name -> (command and config, the --set cuts, the note on the cut)
ROWS = {
    "bifurcation": (["sweep", "configs/bifurcation.yaml"], ["solver.revolutions=5",
                    "metrics.settle_revolutions=1"], "5 of 110 revolutions"),
    "coating_clearance": (["sweep", "configs/coating_clearance.yaml"], [], "whole"),
    "coating_ensemble": (["sweep", "configs/coating_ensemble.yaml"], ["solver.duration=0.25"],
                         "0.25 of 1 s"),
    "contact_laws": (["sweep", "configs/contact_laws.yaml"], [], "whole"),
    "dynamics_map": (["sweep", "configs/dynamics_map.yaml"], ["solver.revolutions=5",
                     "metrics.settle_revolutions=1"], "5 of 110 revolutions"),
    "ideal": (["run", "configs/ideal.yaml"], [], "whole"),
    "life": (["life", "configs/life.yaml"], [], "whole"),
    "life_sweep": (["sweep", "configs/life_sweep.yaml"], ["life.max_clearance_growth=2.5e-5"],
                   "to 25 um of growth"),
    "measured_friction": (["sweep", "configs/measured_friction.yaml"], [], "whole"),
    "mixed_clearances": (["sweep", "configs/mixed_clearances.yaml"], ["solver.revolutions=2",
                         "metrics.settle_revolutions=1"], "2 of 10 revolutions"),
    "one_clearance": (["run", "configs/one_clearance.yaml"], [], "whole"),
    "paper": (["sweep", "configs/paper.yaml"], ["solver.duration=0.25"], "0.25 of 1 s"),
    "paper_case": (["run", "configs/paper_case.yaml"], [], "whole"),
    "reliability": (["sweep", "configs/reliability.yaml"], ["reliability.members=4"],
                    "4 of 16 members"),
    "reliability_joints": (["sweep", "configs/reliability_joints.yaml"],
                           ["reliability.members=4"], "4 of 16 members"),
    "revolute_clearance": (["sweep", "configs/revolute_clearance.yaml"],
                           ["solver.duration=0.25"], "0.25 of 1 s"),
    "sensitivity": (["sweep", "configs/sensitivity.yaml"], ["solver.duration=0.025"],
                    "0.025 of 0.25 s (3,072 cases)"),
    "two_clearances": (["run", "configs/two_clearances.yaml"], [], "whole"),
    "slider_crank": (["run", "configs/slider_crank.yaml"], [], "whole"),
    "slider_crank_clearance_sweep": (["sweep", "configs/slider_crank_clearance_sweep.yaml"], [],
                                     "whole"),
    "slider_crank_ensemble": (["sweep", "configs/slider_crank_ensemble.yaml"], [], "whole"),
    "slider_crank_life": (["life", "configs/slider_crank_life.yaml"], [], "whole"),
}
_ABOUT = re.compile(r"(expected )?about ([0-9.e+]+) (s|min|h|d)\b")
_UNIT = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}
WORKERS = 2


def planned(text: str) -> float | None:
    """The plan's time [s]: its expected time where it gives one, else its 'about'."""
    found = _ABOUT.findall(text)
    if not found:
        return None
    expected = [f for f in found if f[0]]
    _, value, unit = (expected or found)[0]
    return float(value) * _UNIT[unit]


def measure(args: list[str]) -> tuple[float, float, float]:
    """(wall, driver CPU, workers' CPU) [s] of ``args`` run to its end
    (``calibrate_plan.tree_cpu``: the process tree polled every 50 ms)."""
    from calibrate_plan import tree_cpu

    return tree_cpu(args, capture_stderr=True)


def plan_of(name: str, tmp: str) -> float | None:
    """The plan's time [s] of row ``name`` (its ``--dry-run``)."""
    (command, config), cuts = ROWS[name][0], ROWS[name][1]
    sets = [x for cut in cuts for x in ("--set", cut)]
    extra = ["--workers", str(WORKERS), "--yes"] if command == "sweep" else []
    plan_out = subprocess.run([*CS, command, config, *sets, "-o", str(Path(tmp) / "plan.nc"),
                               *extra, "--dry-run"], capture_output=True, text=True)
    return planned(plan_out.stdout + plan_out.stderr)


def row(name: str, tmp: str) -> str:
    (command, config), cuts, note = ROWS[name][0], ROWS[name][1], ROWS[name][2]
    sets = [x for cut in cuts for x in ("--set", cut)]
    out = ["-o", str(Path(tmp) / f"{name}.nc"), "--overwrite"]
    extra = ["--workers", str(WORKERS)] if command == "sweep" else []
    yes = ["--yes"] if command == "sweep" else []
    plan = plan_of(name, tmp)
    load0 = os.getloadavg()[0]
    wall, driver, workers = measure([*CS, command, config, *sets, *out, *extra, *yes, "-q"])
    load1 = os.getloadavg()[0]
    share = WORKERS if extra else 1
    own = driver + workers / share
    plan_text = f"{plan:.3g}" if plan is not None else "none"
    ratio = f"{own / plan:.2f}" if plan else "-"
    return (f"| {name} | {' '.join(['clearsweep', command, config] + sets)} | {note} | "
            f"{plan_text} | {wall:.3g} | {driver:.3g} + {workers:.3g} | {own:.3g} | {ratio} | "
            f"{load0:.1f}-{load1:.1f} |")


def main() -> None:
    """Every row, or the rows named; ``--plan-only``: each row's plan alone, nothing run."""
    names = [a for a in sys.argv[1:] if not a.startswith("--")] or list(ROWS)
    if "--plan-only" in sys.argv:
        with tempfile.TemporaryDirectory() as tmp:
            for name in names:
                print(f"{name}: {plan_of(name, tmp):.3g} s", flush=True)
        return
    print("| config | command | cut | plan [s] | wall [s] | CPU driver + workers [s] | "
          "own cores [s] | own / plan | load average |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            print(row(name, tmp), flush=True)


if __name__ == "__main__":
    main()
