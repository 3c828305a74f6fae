"""The README's Python example saved as a script and run as written (short runs through a
prelude that adds overrides); without its ``__main__`` guard it fails at once, naming it."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import pytest

from clearsweep.sweeping import CasesFailedWarning, SweepFailed, UnguardedScript, run_sweep
from clearsweep.sweeping.guard import _guarded

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.search(r"## From Python\n\n```python\n(.*?)```", (ROOT / "README.md").read_text(),
                  re.S).group(1)

#: Runs before the README's block: every call made short, nothing else changed (it runs in
#: every worker too, as a script's top level does).
PRELUDE = '''\
import functools
import clearsweep

def _short(name, extra):
    real = getattr(clearsweep, name)

    @functools.wraps(real)
    def short(config, *args, overrides=(), **kwargs):
        return real(config, *args, overrides=[*overrides, *extra], **kwargs, **(
            {"progress": False} if name == "sweep" else {}))
    return short

clearsweep.simulate = _short("simulate", ["solver.duration=0.002"])
clearsweep.sweep = _short("sweep", ["solver.duration=0.002", "ensemble.members=2"])
clearsweep.life = _short("life", ["life.max_blocks=1", "mechanism.speed_rpm=3000", "wear.map=[12, 24]"])
'''


def run_script(tmp_path: Path, body: str) -> subprocess.CompletedProcess:
    script = tmp_path / "example.py"
    script.write_text(PRELUDE + body)
    return subprocess.run([sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)


def test_readme_python_block_runs_as_a_script(tmp_path):
    res = run_script(tmp_path, BLOCK)
    assert res.returncode == 0, res.stderr[-3000:]
    assert re.match(r"[-+.\deE]+ N\n", res.stdout), res.stdout


def test_readme_python_block_without_its_guard_fails_at_once_naming_it(tmp_path):
    body, guard = BLOCK.split('if __name__ == "__main__":', 1)
    unguarded = body + textwrap.dedent(guard.split("\n", 1)[1])
    assert "__main__" not in unguarded
    res = run_script(tmp_path, unguarded)
    assert res.returncode == 1
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("clearsweep.sweeping.guard.UnguardedScript: a sweep with 2 worker processes")
    assert 'if __name__ == "__main__":' in last and "example.py" in last
    assert "Process" not in res.stderr     # no worker started


@pytest.mark.parametrize("source, line, expected", [
    ('import x\nif __name__ == "__main__":\n    x.sweep()\n', 3, True),
    ('import x\nif "__main__" == __name__:\n    x.sweep()\n', 3, True),
    ('import x\nx.sweep()\n', 2, False),
    ('import x\nif __name__ == "__main__":\n    pass\nelse:\n    x.sweep()\n', 5, False),
    ('import x\ndef main():\n    x.sweep()\nmain()\n', 4, False),
])
def test_the_guard_is_read_from_the_script(source, line, expected):
    assert _guarded(source, line) is expected


def test_worker_processes_from_a_worker_reimporting_the_script_are_refused(monkeypatch):
    """A process still importing its parent's script (multiprocessing's ``_inheriting``, set
    while spawn or forkserver runs it as ``__mp_main__``); a spawned child past its import
    runs its sweep (tests/test_workers_hazards.py)."""
    import multiprocessing

    monkeypatch.setattr(multiprocessing.current_process(), "_inheriting", True, raising=False)
    with pytest.raises(UnguardedScript, match="while a worker process was importing"):
        run_sweep({"base": str(ROOT / "configs/two_clearances.yaml"),
                   "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]}}}, workers=2)


def _failing(config):
    if config.joints.B.coating == "PTFE":
        raise ValueError("no PTFE today")
    from clearsweep.simulation import simulate

    return simulate(config)


SWEEP = {"base": str(ROOT / "configs/two_clearances.yaml"),
         "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]}}}


def test_a_sweep_whose_cases_all_failed_raises(tmp_path):
    spec = {**SWEEP, "sweep": {"grid": {"joints.B.coating": ["PTFE"]}}}
    with pytest.raises(SweepFailed, match=r"all 1 cases failed \(the first: error: ValueError: "
                                          r"no PTFE today\); see .*all\.nc"):
        run_sweep(spec, tmp_path / "all.nc", workers=1, progress=False, _simulate=_failing,
                  overrides=["solver.duration=0.002"])
    assert (tmp_path / "all.nc").exists()


def test_a_sweep_with_some_failed_cases_warns_with_the_count(tmp_path):
    with pytest.warns(CasesFailedWarning, match=r"1 of 2 cases failed \(the first: error: ValueError"):
        ds = run_sweep(SWEEP, workers=1, progress=False, _simulate=_failing,
                       overrides=["solver.duration=0.002"])
    assert int(ds.attrs["sweep_failed"]) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run_sweep(SWEEP, workers=1, progress=False, _simulate=_failing, report_failures=False,
                  overrides=["solver.duration=0.002"])


def _crash_on_ptfe(config):
    """A case whose worker crashes in compiled code (a null pointer read)."""
    import ctypes

    if config.joints.B.coating == "PTFE":
        ctypes.string_at(0)
    from clearsweep.simulation import simulate

    return simulate(config)


@pytest.mark.slow
def test_a_worker_that_crashes_reports_its_fatal_error_and_frame(tmp_path):
    with run_sweep(SWEEP, tmp_path / "c.nc", workers=2, progress=False, _simulate=_crash_on_ptfe,
                   overrides=["solver.duration=0.002"], report_failures=False) as ds:
        message = ds["message"].sel(B_coating="PTFE").item()
    assert "killed by SIGSEGV (Fatal Python error: Segmentation fault; in File " in message
    assert "string_at" in message


def test_the_crash_report_names_the_crashing_threads_innermost_frame(tmp_path):
    from clearsweep.sweeping.worker import crash_report

    (tmp_path / "7.log").write_text(
        "Fatal Python error: Segmentation fault\n\nThread 0x1 (most recent call first):\n"
        '  File "w.py", line 3 in watch\n\nCurrent thread 0x2 (most recent call first):\n'
        '  File "k.py", line 9 in step\n  File "k.py", line 1 in run\n')
    assert crash_report(str(tmp_path), 7) == ('Fatal Python error: Segmentation fault; '
                                              'in File "k.py", line 9 in step')
    assert crash_report(str(tmp_path), 8) == ""
