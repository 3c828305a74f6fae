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


#: Runs every case of CASES, each in its own folder, in one process under the address-space
#: limit (one interpreter start instead of one per case): the entry point as the console
#: script calls it, its exit status, stderr and seconds per case, as JSON on stdout.
DRIVER = """
import contextlib, io, json, os, sys, time
from clearsweep.cli import main
results = {}
for name, folder, argv in json.loads(sys.argv[1]):
    os.chdir(folder)
    err = io.StringIO()
    began = time.perf_counter()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            main(argv, prog_name="clearsweep")
            code = 0
        except SystemExit as exc:
            code = exc.code
        except BaseException as exc:        # a traceback would have been printed
            code, err = None, io.StringIO(f"Traceback: {exc!r}")
    results[name] = (code, err.getvalue(), time.perf_counter() - began)
print(json.dumps(results))
"""


@pytest.fixture(scope="module")
def refusals(tmp_path_factory):
    """name -> (exit status, stderr, seconds, folder) of every case of CASES."""
    import json

    jobs = []
    for name, (argv, _) in CASES.items():
        folder = tmp_path_factory.mktemp("absurd")
        jobs.append((name, str(folder), argv(folder)))
    cmd = f"ulimit -v {LIMIT_KB}; exec {sys.executable} -c \"$0\" \"$1\""
    proc = subprocess.run(["bash", "-c", cmd, DRIVER, json.dumps(jobs)], capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    results = json.loads(proc.stdout)
    return {name: (*results[name], Path(folder)) for name, folder, _ in jobs}


@pytest.mark.parametrize("name", list(CASES))
def test_an_absurd_size_is_refused_before_memory_is_taken(refusals, name):
    code, stderr, seconds, folder = refusals[name]
    expected = CASES[name][1]
    assert code == 2, stderr[-2000:]
    lines = stderr.strip().splitlines()
    assert lines[-1].startswith("clearsweep: error: ") and expected in lines[-1], stderr[-2000:]
    assert "Traceback" not in stderr
    assert not (folder / "o.nc").exists() and not (folder / "o.nc.parts").exists()
    assert seconds < 15      # seconds in practice (5 s asked); the margin is for a loaded machine


def test_workers_beyond_the_cores_are_capped_with_a_note(tmp_path):
    """The plan (--dry-run) says how many workers the sweep would use: the cores, at most
    one per case."""
    proc, _ = clearsweep(tmp_path, "sweep", sweep_file(tmp_path, "sweep:\n  grid: {joints.B.coating: [none, PTFE]}\n"),
                         "--set", "solver.duration=0.002", "--workers", "100000", "-o", "o.nc",
                         "--dry-run")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert f"--workers 100000 is more than this machine's {os.cpu_count()} cores" in proc.stderr
    used = min(os.cpu_count() or 1, 2)
    assert "2 cases, 2 to simulate, 400 RK4 steps: about " in proc.stdout
    assert f" s on {used} worker{'s' if used > 1 else ''} (at " in proc.stdout
