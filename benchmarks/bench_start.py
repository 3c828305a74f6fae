"""Cached start of ``clearsweep run``: wall time of a short run against a bare interpreter's imports.

    .venv/bin/python benchmarks/bench_start.py [--repeats 5] [TREE ...]

Times, in fresh processes and alternating between the trees given (source trees, put
first on ``PYTHONPATH``; default: this one), the wall time of

- ``python -c "import numpy, xarray, numba, netCDF4, yaml, click"`` (the bare imports), and
- ``clearsweep run configs/one_clearance.yaml --set solver.duration=0.1 -q`` with each
  tree's Numba cache warm (one run first, untimed), its output file there from the run
  before, as when the command is typed again,

and prints the best of ``--repeats`` of each and the difference (issue 32's goal: the run
at most 0.5 s beyond the bare imports). For scale it also times the bare imports and one
call of a one-line ``@njit(cache=True)`` function loaded from its cache: what loading any
cached kernel adds (numba's target context, which imports ``numba.np.arraymath`` and
through it ``scipy.linalg``), clearsweep or not.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BARE = "import numpy, xarray, numba, netCDF4, yaml, click"
#: One cached @njit function, called once.
NJIT = "from numba import njit\n\n@njit(cache=True)\ndef one(x):\n    return x + 1\n"
NJIT_CALL = BARE + "; from njit_one import one; one(1)"
#: The ``clearsweep`` console script (its arguments follow the code; ``-c`` is its argv[0]).
ENTRY = "import sys; from clearsweep.cli import main; sys.exit(main())"
ARGS = ("run", "configs/one_clearance.yaml", "--set", "solver.duration=0.1", "-q", "-o")


def _wall(code: str, tree: Path, path: str | None = None, args: tuple[str, ...] = ()) -> float:
    env = {**os.environ, "PYTHONPATH": path or str(tree)}
    began = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, *args], cwd=tree, env=env, check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trees", nargs="*", type=Path, default=[ROOT])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        run = {tree: (*ARGS, str(Path(folder) / f"run{i}.nc")) for i, tree in enumerate(args.trees)}
        (Path(folder) / "njit_one.py").write_text(NJIT)
        _wall(NJIT_CALL, ROOT, folder)      # warm its cache
        for tree in args.trees:     # warm each tree's Numba cache
            _wall(ENTRY, tree.resolve(), args=run[tree])
        times: dict[Path, dict[str, list[float]]] = {t: {"bare": [], "run": []} for t in args.trees}
        njit: list[float] = []
        for _ in range(args.repeats):
            for tree in args.trees:
                times[tree]["bare"].append(_wall(BARE, tree.resolve()))
                times[tree]["run"].append(_wall(ENTRY, tree.resolve(), args=run[tree]))
            njit.append(_wall(NJIT_CALL, ROOT, folder))
    print(f"best of {args.repeats}, {sys.version.split()[0]}, load {os.getloadavg()[0]:.2f}\n")
    # the bare imports do not depend on the tree: one figure, the best of all rounds
    bare = min(min(t["bare"]) for t in times.values())
    print("| tree | bare imports [s] | `clearsweep run` [s] | beyond the imports [s] |")
    print("|---|---|---|---|")
    for tree, t in times.items():
        run_s = min(t["run"])
        print(f"| {tree} | {bare:.2f} | {run_s:.2f} | {run_s - bare:.2f} |")
    print(f"| (bare imports + one cached `@njit` call) | {bare:.2f} | {min(njit):.2f} | "
          f"{min(njit) - bare:.2f} |")


if __name__ == "__main__":
    main()
