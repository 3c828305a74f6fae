"""Every size a config or option sets is bounded before memory is taken (hardening round 3):
each absurd value below ends, under a 1 GB address-space limit, within seconds, in one
``clearsweep: error:`` line with exit 2, no traceback and no output file. Before, members =
1e9 built a billion-element tuple (killed for memory), life.snapshots = 1e9 drew a billion
log-spaced marks every block, and sample sizes of 1e7 to 2^31 points were drawn before the
case count was checked (numpy _ArrayMemoryError tracebacks, 1.4 to 32 GiB asked)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LIMIT_KB = 1_000_000    # ulimit -v: far below what any of these asked for, above an import


def clearsweep(tmp_path, *args):
    cmd = f"ulimit -v {LIMIT_KB}; exec {sys.executable} -m clearsweep.cli " + " ".join(args)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    began = time.perf_counter()
    proc = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, cwd=tmp_path,
                          env=env, timeout=120)
    return proc, time.perf_counter() - began


def sweep_file(tmp_path, body: str) -> str:
    path = tmp_path / "s.yaml"
    path.write_text(f"name: s\nstore: summary\nbase: {ROOT / 'configs' / 'one_clearance.yaml'}\n"
                    + body)
    return str(path)


def grid_file(tmp_path, n: int, keys=("joints.B.clearance", "mechanism.speed_rpm")) -> str:
    """A grid of n values on each of ``keys``: n^len(keys) cases."""
    start = {"joints.B.clearance": 1e-4, "mechanism.speed_rpm": 30.0, "wear.amplification": 1.0}
    lines = [f"    {k}: [{', '.join(f'{start[k] * (1 + i * 1e-6):.9g}' for i in range(n))}]" for k in keys]
    return sweep_file(tmp_path, "sweep:\n  grid:\n" + "\n".join(lines) + "\n")


CASES = {
    "members 1e9 (run)": (lambda t: ["run", str(ROOT / "configs/one_clearance.yaml"),
                                     "--set", "ensemble.members=1000000000", "-o", "o.nc"],
                          "ensemble.members: got 1000000000"),
    "members 5e4 (run)": (lambda t: ["run", str(ROOT / "configs/one_clearance.yaml"),
                                     "--set", "ensemble.members=50000", "-o", "o.nc"],
                          "clearsweep sweep FILE --yes"),
    "members 1e9 (sweep)": (lambda t: ["sweep", sweep_file(t, "sweep: {}\n"),
                                       "--set", "ensemble.members=1000000000", "-o", "o.nc"],
                            "ensemble.members: got 1000000000"),
    "reliability members 1e9": (lambda t: ["sweep", str(ROOT / "configs/reliability.yaml"),
                                           "--set", "reliability.members=1000000000", "-o", "o.nc"],
                                "reliability.members: got 1000000000"),
    # two lists of 1e5 values pass the 1 MiB bound on a YAML file: refused as they are read
    "grid 1e5 x 1e5": (lambda t: ["sweep", grid_file(t, 100_000), "-o", "o.nc"],
                       "at most 1048576 bytes"),
    "grid 2e3 x 2e3 x 2e3": (lambda t: ["sweep", grid_file(t, 2000, ("joints.B.clearance", "mechanism.speed_rpm",
                                                                   "wear.amplification")), "--yes", "-o", "o.nc"],
                             "at most 1,000,000 cases, --yes or not"),
    "life snapshots 1e9": (lambda t: ["life", str(ROOT / "configs/life.yaml"),
                                      "--set", "life.snapshots=1000000000", "-o", "o.nc"],
                           "life.snapshots: got 1000000000"),
    "sobol n 2^31": (lambda t: ["sweep", sweep_file(t, "sweep:\n  sample: {method: sobol, n: 2147483648, "
                                                      "ranges: {joints.B.clearance: [1.0e-4, 3.0e-4]}}\n"),
                                "-o", "o.nc"], "sweep.sample.n: got 2147483648"),
    "lhs n 1e9 with --yes": (lambda t: ["sweep", sweep_file(t, "sweep:\n  sample: {method: lhs, n: 1000000000, "
                                                              "ranges: {joints.B.clearance: [1.0e-4, 3.0e-4]}}\n"),
                                        "--yes", "-o", "o.nc"], "at most 1,000,000 points"),
    "lhs n 1e5": (lambda t: ["sweep", sweep_file(t, "sweep:\n  sample: {method: lhs, n: 100000, "
                                                   "ranges: {joints.B.clearance: [1.0e-4, 3.0e-4]}}\n"),
                             "-o", "o.nc"], "100,000 cases"),
    "saltelli n 1e8": (lambda t: ["sweep", sweep_file(t, "sweep:\n  sample: {method: saltelli, n: 100000000, "
                                                        "ranges: {joints.B.clearance: [1.0e-4, 3.0e-4], "
                                                        "mechanism.speed_rpm: [30.0, 90.0]}}\n"),
                                  "-o", "o.nc"], "400,000,000 points"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_an_absurd_size_is_refused_before_memory_is_taken(tmp_path, name):
    argv, expected = CASES[name]
    proc, seconds = clearsweep(tmp_path, *argv(tmp_path))
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert lines[-1].startswith("clearsweep: error: ") and expected in lines[-1], proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "o.nc").exists() and not (tmp_path / "o.nc.parts").exists()
    assert seconds < 15      # seconds in practice (5 s asked); the margin is for a loaded machine


def test_workers_beyond_the_cores_are_capped_with_a_note(tmp_path):
    proc, _ = clearsweep(tmp_path, "sweep", sweep_file(tmp_path, "sweep:\n  grid: {joints.B.coating: [none, PTFE]}\n"),
                         "--set", "solver.duration=0.002", "--workers", "100000", "-o", "o.nc",
                         "--no-progress")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert f"--workers 100000 is more than this machine's {os.cpu_count()} cores" in proc.stderr
