"""The commands of README.md and of the docs pages run as written (simulated time shortened
with --set)."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
DOCS = ROOT / "docs"
CLI = [sys.executable, "-m", "clearsweep.cli"]


def commands_under(heading: str, text: str = README) -> list[list[str]]:
    """The clearsweep command lines of the first bash block after ``heading`` in ``text``."""
    section = text.split(heading, 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    out = []
    for line in block.splitlines():
        for part in line.split("&&"):
            words = shlex.split(part)
            if words and words[0].endswith("bin/clearsweep"):
                out.append(words[1:])
    return out


def run(args: list[str], cwd: Path, in_process: bool = False) -> subprocess.CompletedProcess:
    """The command line ``args`` run in ``cwd``, shortened (0.02 s of motion, settled from
    0.01 s, so that the settled statistics the figures draw exist); as a process of its
    own, or with ``in_process`` through the same entry point in this process (the commands
    of a page share one interpreter start: the reproduction page has 18)."""
    args = [str(ROOT / a) if a.startswith("configs/") else a for a in args]
    short = ["--set", "solver.duration=0.02", "--set", "metrics.settle_time=0.01"]
    if args[0] in ("sweep", "run"):
        args += short + ["--workers", "1"] if args[0] == "sweep" else short
    if not in_process:
        return subprocess.run(CLI + args, cwd=cwd, capture_output=True, text=True, timeout=600)
    from click.testing import CliRunner

    from clearsweep.cli import main

    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(cwd)
        res = CliRunner().invoke(main, args, prog_name="clearsweep")
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        raise res.exception
    return subprocess.CompletedProcess(args, res.exit_code, res.stdout, res.stderr)


@pytest.mark.slow
def test_quick_start_main_job_runs(tmp_path):
    (cmd,) = commands_under("## Quick start")
    assert cmd[:2] == ["sweep", "configs/coating_clearance.yaml"]
    res = run(cmd, tmp_path)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "coating_clearance.nc") as ds:
        assert (ds["status"] == "ok").all()


@pytest.mark.slow
def test_reproduction_commands_run_as_written(tmp_path):
    (tmp_path / "docs" / "figures").mkdir(parents=True)
    text = (DOCS / "reproduction.md").read_text()
    # the runs, then the block that replaces the tracked figures (tests/test_docs_commands.py)
    cmds = commands_under("## Commands", text) + commands_under("### Regenerate the docs figures", text)
    assert cmds[0][:2] == ["sweep", "configs/paper.yaml"] and len(cmds) > 5
    for cmd in cmds:
        res = run(cmd, tmp_path, in_process=True)
        assert res.returncode == 0, (cmd, res.stderr)
    figures = sorted(p.name for p in (tmp_path / "docs" / "figures").iterdir())
    committed = sorted(p.name for p in (ROOT / "docs" / "figures").glob("*.png"))
    assert figures == committed


def test_run_writes_a_labelled_file_with_units(tmp_path):
    """`clearsweep run configs/two_clearances.yaml -o out.nc` (shortened), then xr.open_dataset."""
    res = run(["run", "configs/two_clearances.yaml", "-o", "out.nc"], tmp_path)
    assert res.returncode == 0, res.stderr
    assert "status: ok" in res.stdout and "steps/s" in res.stdout
    with xr.open_dataset(tmp_path / "out.nc") as ds:
        assert str(ds["status"].values) == "ok"
        for name, var in ds.variables.items():
            assert "long_name" in var.attrs, name
            if var.dtype.kind in "fi" and name not in ("joint", "axis"):
                assert "units" in var.attrs, name
        assert ds["normal_force"].attrs["units"] == "N"
        assert ds["joint_force"].dims == ("time", "joint", "axis")
        assert "joints:" in ds.attrs["config"] and ds.attrs["numba_version"]


def test_run_command_of_the_guide_is_the_one_tested():
    """docs/runs.md opens with the command test_run_writes_a_labelled_file_with_units runs."""
    (cmd, *_) = commands_under("# Runs: one case", (DOCS / "runs.md").read_text())
    assert cmd == ["run", "configs/two_clearances.yaml", "-o", "out.nc"]


def test_every_status_code_is_documented():
    from clearsweep.core.layout import STATUS_NAMES

    for page in ("runs.md", "physics.md"):
        text = (DOCS / page).read_text()
        missing = [name for name in STATUS_NAMES.values() if f"`{name}`" not in text]
        assert not missing, f"docs/{page} does not list the status(es) {missing}"


def test_readme_stays_short_and_ci_runs_its_test_command():
    assert len(README.splitlines()) <= 150
    (block,) = [b for b in re.findall(r"```bash\n(.*?)```", README, re.S) if "pytest" in b]
    ci = (ROOT / ".ci" / "run").read_text()
    assert block.strip() in ci


def test_benchmarks_are_run_with_the_project_interpreter():
    text = (ROOT / "benchmarks" / "README.md").read_text()
    commands = re.findall(r"`(\S*python benchmarks/[^` ]*\.py)", text)
    assert commands and all(c.startswith(".venv/bin/python benchmarks/") for c in commands), commands
    for command in commands:
        assert (ROOT / command.split()[-1]).is_file()


def test_the_commands_of_the_readme_and_docs_leave_nothing_untracked():
    """Every file the README's and the docs' command lines write with -o, run from the
    repository's root as shown, is ignored by git (with its parts folder and checkpoint)."""
    import shutil

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    texts = [README, *(p.read_text() for p in DOCS.glob("*.md"))]
    outs = sorted({o for text in texts
                   for o in re.findall(r"clearsweep [^`\n]*?-o ([\w.-]+\.[a-z]+)\b", text)})
    assert "cc.png" in outs and "coating_clearance.nc" in outs
    paths = [p for o in outs for p in ((o, o + ".parts/x.nc", o + ".life-checkpoint")
                                       if o.endswith(".nc") else (o,))]
    res = subprocess.run(["git", "check-ignore", "--no-index", *paths], cwd=ROOT,
                         capture_output=True, text=True)
    assert sorted(res.stdout.split()) == sorted(paths)
