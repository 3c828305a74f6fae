"""Where a sweep's workers run and how they start, each in a process of its own (a crash
there must not end the test run): every executor kind a caller may pass as ``client``,
a sweep in a process that ``multiprocessing`` started, every way a script reaches a sweep
(a file, standard input, ``python -c``, an interactive session, a notebook cell), and the
warnings of a case run in a worker process.

Before (issue 40, items 4, 6 and 10; issue 45, item 3): a ``ThreadPoolExecutor`` client
crashed the process (SIGSEGV or SIGBUS, two threads writing parts with netCDF4 at once); a
guarded sweep in a ``spawn`` child was refused as an unguarded script; a script on standard
input failed every case with "worker died twice"; a worker's warnings reached stderr raw.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Two cases at 2 ms of simulated time; every script below sweeps them.
PRELUDE = f'''\
import sys, warnings
import clearsweep
from clearsweep.sweeping import drop_timing, run_sweep
SWEEP = {{"base": {str(ROOT / "configs/two_clearances.yaml")!r},
         "sweep": {{"grid": {{"joints.B.coating": ["none", "PTFE"],
                             "joints.B.clearance": [1e-4, 2e-4, 3e-4]}}}}}}
SHORT = ["solver.duration=0.002"]
'''


def run_python(tmp_path: Path, body: str, *how: str, stdin: str | None = None,
               timeout: float = 300) -> subprocess.CompletedProcess:
    """``python [how...]`` in the repository root; ``how`` ``"file"``: the script saved as
    ``script.py`` and run from it."""
    text = PRELUDE + textwrap.dedent(body)
    argv = [sys.executable, *how]
    if how == ("file",):
        (tmp_path / "script.py").write_text(text)
        argv = [sys.executable, str(tmp_path / "script.py")]
    elif how == ("-c",):
        argv.append(text)
    return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          input=text if stdin == "script" else stdin)


# --- 40.4: each executor kind the docs admit as `client`
EXECUTORS = {
    "threads": "from concurrent.futures import ThreadPoolExecutor as make; args = (2,)",
    "processes": "from concurrent.futures import ProcessPoolExecutor as make; args = (2,)",
    "process_pool": "from clearsweep.sweeping import process_pool as make; args = (2,)",
}


@pytest.mark.parametrize("kind", [*EXECUTORS, "dask threads"])
def test_every_executor_kind_a_caller_may_pass_runs_the_sweep_bit_for_bit(tmp_path, kind):
    """Before: threads ended the process with SIGSEGV/SIGBUS (exit -11/-7, no Python error)."""
    if kind == "dask threads":
        make = ("from distributed import Client, LocalCluster; cluster = LocalCluster("
                "n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None); "
                "executor = Client(cluster); close = lambda: (executor.close(), cluster.close())")
    else:
        make = f"{EXECUTORS[kind]}; executor = make(*args); close = executor.shutdown"
    body = f'''\
        import xarray as xr

        if __name__ == "__main__":
            one = run_sweep(SWEEP, workers=1, progress=False, overrides=SHORT)
            {make}
            two = run_sweep(SWEEP, {str(tmp_path / "x.nc")!r}, client=executor, progress=False,
                            overrides=SHORT)
            close()
            xr.testing.assert_identical(drop_timing(one), drop_timing(two.load()))
            print("identical", int(two.attrs["sweep_cases"]), int(two.attrs["sweep_failed"]))
        '''
    res = run_python(tmp_path, body, "file")
    assert res.returncode == 0, (res.returncode, res.stderr[-3000:])
    assert res.stdout.split() == ["identical", "6", "0"]


# --- 40.6: a sweep in a process that multiprocessing started
SPAWNED = '''\
import multiprocessing as mp

def target(workers):
    ds = run_sweep(SWEEP, workers=workers, progress=False, overrides=SHORT)
    print("swept", int(ds.attrs["sweep_cases"]), int(ds.attrs["sweep_failed"]), flush=True)

if __name__ == "__main__":
    ctx = mp.get_context("spawn")
    if sys.argv[1] == "process":
        child = ctx.Process(target=target, args=(2,))
        child.start()
        child.join()
        print("exit", child.exitcode)
    else:
        with ctx.Pool(1) as pool:
            try:
                pool.apply(target, (int(sys.argv[1]),))
            except Exception as exc:
                print(f"{type(exc).__name__}: {exc}")
'''


def run_spawned(tmp_path: Path, how: str) -> subprocess.CompletedProcess:
    (tmp_path / "spawned.py").write_text(PRELUDE + SPAWNED)
    return subprocess.run([sys.executable, str(tmp_path / "spawned.py"), how], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def test_a_guarded_sweep_in_a_spawned_process_runs_on_two_workers(tmp_path):
    """Before: UnguardedScript ("while a worker process was importing the script"), exit 1."""
    res = run_spawned(tmp_path, "process")
    assert res.stdout.split() == ["swept", "6", "0", "exit", "0"], res.stderr[-3000:]


def test_a_pool_worker_asking_for_workers_is_told_to_pass_workers_1(tmp_path):
    """Before: UnguardedScript, naming the script's import, which was not the cause."""
    res = run_spawned(tmp_path, "2")
    line = res.stdout.strip()
    assert line.startswith("UnguardedScript: a sweep with 2 worker processes was started in the "
                           "daemonic process 'SpawnPoolWorker-1'"), (line, res.stderr[-2000:])
    assert "pass workers=1" in line and "__main__" not in line
    assert run_spawned(tmp_path, "1").stdout.split() == ["swept", "6", "0"]


def test_a_sweep_started_while_a_spawned_child_imports_the_script_is_refused(tmp_path):
    """The guard's other half: a script that starts a sweep when it is imported (here only
    when imported, in the spawned child) is refused there, before any worker starts."""
    body = '''\
        import multiprocessing as mp

        def nothing():
            pass

        if __name__ == "__main__":
            child = mp.get_context("spawn").Process(target=nothing)
            child.start()
            child.join()
            print("exit", child.exitcode)
        else:
            run_sweep(SWEEP, workers=2, progress=False, overrides=SHORT)
        '''
    res = run_python(tmp_path, body, "file")
    assert res.stdout.split() == ["exit", "1"], res.stderr[-2000:]
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("clearsweep.sweeping.guard.UnguardedScript: a sweep with 2 worker "
                           "processes was started while a worker process was importing the "
                           "script"), last
    assert "workers=1" in last


# --- 45.3: every way a script reaches a sweep with workers
SWEEP_TWO = '''\
ds = run_sweep(SWEEP, workers=2, progress=False, overrides=SHORT)
print("swept", int(ds.attrs["sweep_cases"]), int(ds.attrs["sweep_failed"]))
'''


@pytest.mark.parametrize("how", [("-",), ()], ids=["python -", "python < script"])
def test_a_script_on_standard_input_is_refused_before_any_worker_starts(tmp_path, how):
    """Before: every case failed with "worker died twice" (exit code 1 of each worker,
    which could not re-import a script named '<stdin>'), the cause only in their tracebacks."""
    res = run_python(tmp_path, SWEEP_TWO, *how, stdin="script")
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 1 and "swept" not in res.stdout
    assert lines[-1] == (
        "clearsweep.sweeping.guard.UnguardedScript: a sweep with 2 worker processes was started "
        "from a script read from standard input: each worker process starts by re-importing the "
        "script from its file; save the script to a file and run that (its work under "
        '`if __name__ == "__main__":`), or pass workers=1'), res.stderr[-2000:]
    assert "died" not in res.stderr and "Process" not in res.stderr      # no worker started


def test_a_script_on_standard_input_runs_with_one_worker(tmp_path):
    res = run_python(tmp_path, SWEEP_TWO.replace("workers=2", "workers=1"), "-", stdin="script")
    assert res.stdout.split() == ["swept", "6", "0"], res.stderr[-2000:]


NOTEBOOK = '''\
import sys, types
# a notebook kernel (IPython) runs each cell in a main module of its own, without __file__,
# compiled under a cell name that is no file
cell = types.ModuleType("__main__")
cell.__dict__["__builtins__"] = __builtins__
sys.modules["__main__"] = cell
exec(compile({source!r}, "/tmp/ipykernel_1/2650276547.py", "exec"), cell.__dict__)
'''


@pytest.mark.parametrize("how", ["-c", "interactive", "notebook cell"])
def test_a_sweep_from_code_without_a_script_file_runs_on_two_workers(tmp_path, how):
    """``python -c``, an interactive session and a notebook cell have no script for a
    worker to re-import: the workers import only clearsweep, and the sweep runs."""
    if how == "-c":
        res = run_python(tmp_path, SWEEP_TWO, "-c")
    elif how == "interactive":
        res = run_python(tmp_path, SWEEP_TWO, "-q", "-i", stdin="script")
    else:
        res = run_python(tmp_path, NOTEBOOK.format(source=PRELUDE + SWEEP_TWO), "-c")
    assert "swept 6 0" in res.stdout, (res.returncode, res.stderr[-3000:])
    assert "Error" not in res.stderr, res.stderr[-3000:]


# --- 40.10: a warning raised in a worker process
def test_a_warning_raised_in_a_worker_reaches_the_driver_once(tmp_path):
    """Before: each worker printed Python's two raw lines (file, line, category, source) on
    stderr, once per case, and the driver's filters and the command's printer never saw it."""
    body = '''\
        def warning_case(config):
            from clearsweep.simulation import simulate

            warnings.warn("the friction law is extrapolated", RuntimeWarning, stacklevel=1)
            return simulate(config)

        if __name__ == "__main__":
            from clearsweep.cli import _show_warning

            warnings.showwarning = _show_warning
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                run_sweep(SWEEP, workers=2, progress=False, overrides=SHORT,
                          _simulate=warning_case)
            print(len(caught), caught[0].category.__name__, caught[0].message)
            warnings.warn_explicit(caught[0].message, caught[0].category, caught[0].filename,
                                   caught[0].lineno)
        '''
    res = run_python(tmp_path, body, "file")
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.strip() == "1 RuntimeWarning the friction law is extrapolated"
    assert res.stderr.strip().splitlines() == [
        "clearsweep: warning: the friction law is extrapolated (RuntimeWarning from script)"]


def test_a_warning_class_that_cannot_travel_comes_back_as_a_user_warning():
    """A category defined in a function cannot be pickled to the driver: the receipt must
    still travel (the warning's text is kept, its class becomes UserWarning)."""
    import pickle

    from clearsweep.sweeping.worker import WARNINGS_KEY, _portable, reissue

    class Local(UserWarning):
        pass

    assert _portable(RuntimeWarning) is RuntimeWarning and _portable(Local) is UserWarning
    receipt = {"status": "ok", WARNINGS_KEY: [("text", _portable(Local), "f.py", 3)] * 2}
    pickle.dumps(receipt)
    with pytest.warns(UserWarning, match="^text$") as caught:
        assert reissue(receipt, set()) == {"status": "ok"}
    assert len(caught) == 1
