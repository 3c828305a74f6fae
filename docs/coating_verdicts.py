"""Why the coating ensemble and the single-run wear study disagree about B's wear.

Run from the repository root: ``.venv/bin/python docs/coating_verdicts.py`` (about 1.5 min on
2 cores once the kernel is compiled; ``--members 8`` halves it, ``--only NAME`` runs one
experiment). ``configs/coating_ensemble.yaml`` at its old settings (0.25 s per member,
balls started up to half the clearance away from seated) found every coating *deepening*
B's largest wear spot; ``docs/wear_study.py`` (1 s, seated, one run) finds PTFE *lowering*
it to 0.60x. Each experiment below runs the ensemble's grid (4 coatings x 3
clearances of B, ``--members`` members each) with one setting changed, and prints per
design B's ensemble-mean largest map depth (``wear_depth_max_final``) and its ratio to the
uncoated socket at the same clearance, with the Welch verdict of ``clearsweep report``
(95 % interval of the difference), the worn volume's ratio, and B's mean impact count over
the run and after the settled window starts (t >= 0.05 s). docs/wear_study.md explains
the outcome.

The nominal member (no perturbation) is ``configs/one_clearance.yaml`` at B's 0.25 mm; its
single-run depths at several times are printed first (``--only nominal``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]

#: The ensemble of ``configs/coating_ensemble.yaml`` before this study (sweep-base overrides).
OLD = ["solver.duration=0.25", "ensemble.perturb.ball_offset=0.5", "wear.map=[144,288]"]

#: name -> (what changes, overrides of the base on top of OLD)
EXPERIMENTS = {
    "old": ("the old shipped ensemble: 0.25 s, ball offsets up to 0.5 c", []),
    "map 36x72": ("the old ensemble on the 36 x 72 map it once used", ["wear.map=[36,72]"]),
    "map x2": ("the old ensemble on a 288 x 576 map", ["wear.map=[288,576]"]),
    "seated": ("the old ensemble, balls started seated (no ball offset)",
               ["ensemble.perturb.ball_offset=0"]),
    "1 s": ("the old ensemble, 1 s (one crank revolution)", ["solver.duration=1.0"]),
    "1 s seated": ("1 s, balls started seated: the shipped configs/coating_ensemble.yaml",
                   ["solver.duration=1.0", "ensemble.perturb.ball_offset=0"]),
}

#: Times [s] at which the nominal single run's largest depth is printed.
NOMINAL_TIMES = (0.05, 0.1, 0.25, 0.5, 1.0)


def nominal() -> None:
    """B's largest map depth of the nominal member, uncoated and PTFE, at NOMINAL_TIMES."""
    from clearsweep.simulation import simulate

    depth = {}
    for coating in ("none", "PTFE"):
        ds = simulate(ROOT / "configs" / "one_clearance.yaml", [f"joints.B.coating={coating}"])
        depth[coating] = ds.wear_depth_max.sel(joint="B")
    print("| t [s] | B max depth, uncoated [m] | PTFE [m] | ratio |")
    print("|---|---|---|---|")
    for t in NOMINAL_TIMES:
        none, ptfe = (float(depth[c].sel(time=t, method="nearest")) for c in ("none", "PTFE"))
        print(f"| {t:g} | {none:.3e} | {ptfe:.3e} | {ptfe / none:.2f} |")
    print()


def run(name: str, members: int, workers: int) -> None:
    from clearsweep.ensemble import distinguishable, welch_interval
    from clearsweep.sweeping import run_sweep

    what, overrides = EXPERIMENTS[name]
    doc = yaml.safe_load((ROOT / "configs" / "coating_ensemble.yaml").read_text())
    doc["base"]["ensemble"]["members"] = members
    start = time.perf_counter()
    ds = run_sweep(doc, workers=workers, progress=False,
                   overrides=[*OLD, *overrides]).sel(joint="B")
    wall = time.perf_counter() - start
    print(f"### {name}: {what}\n\n{members} members per design, {wall:.0f} s on {workers} "
          f"worker(s); overrides: {' '.join([*OLD, *overrides])}\n")
    print("| B clearance [m] | coating | B max depth [m] | ratio to uncoated | verdict "
          "| worn volume ratio | impacts at B, run / settled |")
    print("|---|---|---|---|---|---|---|")
    depth = "wear_depth_max_final"
    for c in ds["B_clearance"].values:
        ref = ds.sel(B_clearance=c, B_coating="none")
        for coating in ds["B_coating"].values:
            one = ds.sel(B_clearance=c, B_coating=coating)
            mean, half = float(one[depth + "_mean"]), 0.5 * float(
                one[depth + "_ci_high"] - one[depth + "_ci_low"])
            n, n_ref = int(one["members_ok"]), int(ref["members_ok"])
            _, low, high = welch_interval(float(ref[depth + "_mean"]), float(ref[depth + "_std"]),
                                          n_ref, mean, float(one[depth + "_std"]), n)
            verdict = "-" if coating == "none" else {
                True: "higher" if low > 0 else "lower", False: "not distinguishable",
                None: "n/a"}[distinguishable(low, high)]
            ratio = mean / float(ref[depth + "_mean"])
            volume = float(one["wear_volume_mean"]) / float(ref["wear_volume_mean"])
            impacts = (float(one["impact_count_mean"]), float(one["impact_count_settled_mean"]))
            print(f"| {c:g} | {coating} | {mean:.2e} +- {half:.1e} | {ratio:.2f} | {verdict} "
                  f"| {volume:.2f} | {impacts[0]:.1f} / {impacts[1]:.1f} |")
    print()
    sys.stdout.flush()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=16, help="members per design")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument("--only", action="append", choices=["nominal", *EXPERIMENTS],
                        help="one experiment (repeatable)")
    args = parser.parse_args(argv)
    names = args.only or ["nominal", *EXPERIMENTS]
    for name in names:
        if name == "nominal":
            nominal()
        else:
            run(name, args.members, args.workers)


if __name__ == "__main__":
    main()
