"""Draw one figure of every plot kind from short runs: docs/figures/gallery/*.png.

Run from the repository root: ``.venv/bin/python docs/gallery.py`` (about 1 min on 2 cores
once the kernel is compiled; ``--work DIR`` keeps the result files there). It runs the
shipped configs shortened (a quarter revolution, fewer members, 10^5 revolutions of
life), prints every command it runs, and writes the figures that ``clearsweep plot`` and
``clearsweep sensitivity -o`` make from them. docs/figures/gallery/README.md lists
the figures with their commands and what was checked in each.
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
OUT = Path("docs/figures/gallery")


def commands(work: Path) -> list[tuple[str, list[str]]]:
    """(what it makes, command) in the order they run; ``{W}`` is the work folder."""
    w = str(work)
    cli = ["clearsweep"]
    return [
        ("single run", [*cli, "run", "configs/two_clearances.yaml", "-o", f"{w}/case.nc",
                        "--set", "solver.duration=0.25", "--set", "joints.B.coating=PTFE"]),
        # the figure is named after its kind
        *[(png, [*cli, "plot", f"{w}/case.nc", "--kind", png.removesuffix(".png"), "-o", str(OUT / png)])
          for png in ("slider.png", "forces.png", "wear-map.png", "wear-polar.png", "orbit.png")],
        ("sweep (the paper's cases)", [*cli, "sweep", "configs/paper.yaml", "-o", f"{w}/paper.nc",
                                       "--set", "solver.duration=0.1", "--workers", "2"]),
        ("sweep_heatmap.png", [*cli, "plot", f"{w}/paper.nc", "--kind", "sweep", "--metric",
                               "slider_acceleration_peak_settled", "-o",
                               str(OUT / "sweep_heatmap.png")]),
        ("sweep_select.png", [*cli, "plot", f"{w}/paper.nc", "--kind", "sweep", "--metric",
                              "slider_acceleration_rms_settled", "--select", "clearance_joints=AB",
                              "-o", str(OUT / "sweep_select.png")]),
        ("slider_sweep_select.png", [*cli, "plot", f"{w}/paper.nc", "--kind", "slider", "--select",
                                     "clearance_joints=AB", "-o", str(OUT / "slider_sweep_select.png")]),
        ("orbit_sweep_select.png", [*cli, "plot", f"{w}/paper.nc", "--kind", "orbit", "--select",
                                    "coating_joints=none", "-o", str(OUT / "orbit_sweep_select.png")]),
        ("ensemble", [*cli, "sweep", "configs/coating_ensemble.yaml", "-o", f"{w}/ensemble.nc",
                      "--set", "solver.duration=0.25", "--set", "ensemble.members=8",
                      "--workers", "2"]),
        ("ensemble_wear.png", [*cli, "plot", f"{w}/ensemble.nc", "--kind", "sweep", "--metric",
                               "wear_depth_max_final", "-o", str(OUT / "ensemble_wear.png")]),
        ("ensemble_rms.png", [*cli, "plot", f"{w}/ensemble.nc", "--kind", "sweep", "--metric",
                              "slider_acceleration_rms_settled", "-o",
                              str(OUT / "ensemble_rms.png")]),
        ("life run", [*cli, "life", "configs/life.yaml", "-o", f"{w}/life.nc", "--set",
                      "life.cycles=1e5", "--set", "wear.map=[36,72]"]),
        ("life.png", [*cli, "plot", f"{w}/life.nc", "--kind", "life", "-o", str(OUT / "life.png")]),
        ("reliability sweep", [*cli, "sweep", "configs/reliability.yaml", "-o", f"{w}/rel.nc",
                               "--set", "reliability.members=4", "--set", "life.cycles=3e4",
                               # 4 um of wear instead of 40 um: members reach it in 3e4 turns
                               "--set", "life.max_clearance_growth=4e-6", "--workers", "2"]),
        ("reliability.png", [*cli, "plot", f"{w}/rel.nc", "--kind", "reliability", "-o",
                             str(OUT / "reliability.png")]),
        ("reliability_b10.png", [*cli, "plot", f"{w}/rel.nc", "--kind", "reliability", "--b10",
                                 "-o", str(OUT / "reliability_b10.png")]),
        ("sensitivity sample (configs/sensitivity.yaml with n = 32)",
         [*cli, "sweep", f"{w}/sensitivity.yaml", "-o", f"{w}/sensitivity.nc", "--workers", "2"]),
        ("sensitivity.png", [*cli, "sensitivity", f"{w}/sensitivity.nc", "--metric",
                             "slider_acceleration_rms_settled", "-o",
                             str(OUT / "sensitivity.png")]),
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, help="keep the result files in this folder")
    args = parser.parse_args(argv)
    os.chdir(ROOT)
    (ROOT / OUT).mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        spec = yaml.safe_load((ROOT / "configs" / "sensitivity.yaml").read_text())
        spec["sweep"]["sample"]["n"] = 32
        (work / "sensitivity.yaml").write_text(yaml.safe_dump(spec, sort_keys=False))
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        for what, command in commands(work):
            if any(arg.startswith(str(OUT)) for arg in command):
                command = [*command, "--overwrite"]     # this gallery's own figures
            print(f"# {what}\n{shlex.join(command)}", flush=True)
            run = [sys.executable, "-m", "clearsweep.cli", *command[1:]]
            done = subprocess.run(run, env=env, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(f"failed ({done.returncode}): {shlex.join(command)}\n{done.stderr}")


if __name__ == "__main__":
    main()
