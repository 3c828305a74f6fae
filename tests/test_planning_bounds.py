"""Planning is bounded before it is taken (hardening round 4, issue 33 item 3; issue 32):
``validate`` and every ``--dry-run`` compile and run nothing, huge plans are counted rather
than enumerated, a life run's checkpoint lock is exclusive under any interleaving.

Before: ``sweep --dry-run`` on an empty Numba cache compiled 47 kernel functions (the seated
start of every case was worked out while planning)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs"


def compiled_files(cache: Path) -> list[Path]:
    return [p for p in cache.rglob("*") if p.suffix in (".nbi", ".nbc")]


@pytest.mark.parametrize("argv", [
    ["sweep", "paper.yaml", "--dry-run"],
    ["validate", "paper.yaml"],
    ["run", "two_clearances.yaml", "--dry-run"],
    ["validate", "reliability.yaml"],
    ["life", "life.yaml", "--dry-run"],
], ids=lambda a: " ".join(a))
def test_planning_compiles_nothing(tmp_path, argv):
    """Was: 47 kernel functions compiled into the empty cache by `sweep paper.yaml --dry-run`."""
    cache = tmp_path / "numba"
    cache.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": str(cache)}
    proc = subprocess.run([sys.executable, "-m", "clearsweep.cli", *argv], capture_output=True,
                          text=True, cwd=CONFIGS, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert compiled_files(cache) == []


def test_the_checkpoint_lock_is_held_by_one_run_at_a_time(tmp_path, monkeypatch):
    """40 life runs start at once, again and again, on one checkpoint: at most one may hold its
    lock at any moment. Was: the lock file is removed on release, so a run that opened it
    just before locked the removed file while a third locked a new one (two holders)."""
    import fcntl
    import random
    import threading
    import time
    import types

    import clearsweep.dataset as dataset
    from clearsweep.service_life import CheckpointError, checkpoint_lock

    def slow_flock(fd, operation):     # widen the moment between opening and locking
        time.sleep(random.uniform(0.0, 0.002))
        return fcntl.flock(fd, operation)

    monkeypatch.setattr(dataset, "fcntl", types.SimpleNamespace(
        flock=slow_flock, LOCK_EX=fcntl.LOCK_EX, LOCK_NB=fcntl.LOCK_NB))
    checkpoint = tmp_path / "out.nc.life-checkpoint"
    guard, holders, most, held = threading.Lock(), [0], [0], [0]
    stop = time.monotonic() + 1.5

    def start() -> None:
        while time.monotonic() < stop:
            try:
                with checkpoint_lock(checkpoint):
                    with guard:
                        holders[0] += 1
                        held[0] += 1
                        most[0] = max(most[0], holders[0])
                    time.sleep(random.uniform(0.0, 0.002))
                    with guard:
                        holders[0] -= 1
            except CheckpointError:
                pass

    threads = [threading.Thread(target=start) for _ in range(40)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert held[0] > 10         # the lock was taken, and released, many times
    assert most[0] == 1
    assert not (tmp_path / "out.nc.life-checkpoint.lock").exists()


def test_a_life_runs_snapshots_and_checkpoint_are_counted():
    """Was: the dry run counted one block's arrays (41 MiB) and no snapshot; the run kept 201
    maps of 30.5 MiB and rewrote them all after every block."""
    from click.testing import CliRunner

    from clearsweep.cli import main
    from clearsweep.config import load_config
    from clearsweep.service_life import life_cost

    cfg = load_config(CONFIGS / "life.yaml", ["life.snapshots=10000", "wear.map=[1000, 2000]"])
    cost = life_cost(cfg)
    # a map per joint (A, B, the bearing O and the guide P)
    assert cost.snapshots == 201 and cost.map_bytes == 4 * 1000 * 2000 * 8
    assert cost.memory_bytes > 3 * 201 * cost.map_bytes and cost.checkpoint_bytes > 201 * cost.map_bytes
    result = CliRunner().invoke(main, ["life", str(CONFIGS / "life.yaml"), "--dry-run"])
    assert result.exit_code == 0, result.output
    assert ("up to 13 wear-map snapshots of 324 KiB" in result.stdout
            and "a checkpoint of up to 4.48 MiB rewritten after every block (up to 896 MiB "
                "written)" in result.stdout)


@pytest.fixture
def few_cases_made(monkeypatch):
    """Fail at once where a plan makes more than 200 cases: a huge plan must be counted."""
    import clearsweep.sweeping.plan as plan

    real, made = plan.load_config, [0]

    def counting(*args, **kwargs):
        made[0] += 1
        if made[0] > 200:
            raise RuntimeError("the plan was enumerated")
        return real(*args, **kwargs)

    monkeypatch.setattr(plan, "load_config", counting)
    return made


@pytest.mark.parametrize("argv, words", [
    (["validate", "reliability.yaml", "--set", "reliability.members=5000", "--yes"],
     "20,000 life runs (counted from its dimensions; "),
    (["sweep", "SAMPLE", "--yes", "--dry-run"],
     "65,536 cases (counted from its dimensions; "),
    (["sweep", "SKIPS", "--yes", "--dry-run"],
     "12,000 cases (6,000 skipped) (counted from its dimensions; "),
], ids=["reliability members", "saltelli", "skips"])
def test_a_huge_plan_is_counted_not_enumerated(tmp_path, monkeypatch, few_cases_made, argv, words):
    """Was: 2e5 reliability members hung in validate, and a 1e6-case Saltelli sample ran past
    300 s at 1.5 GB with --yes --dry-run: every case was made and checked."""
    from click.testing import CliRunner

    from clearsweep.cli import main

    monkeypatch.chdir(CONFIGS)
    base = CONFIGS / "one_clearance.yaml"
    sample = tmp_path / "sample.yaml"
    sample.write_text(f"name: s\nstore: summary\nbase: {base}\nsweep:\n  sample:\n"
                      "    method: saltelli\n    n: 16384\n    ranges: {joints.B.clearance: "
                      "[1.0e-4, 4.0e-4], mechanism.speed_rpm: [500, 1500]}\n")
    skips = tmp_path / "skips.yaml"
    speeds = ", ".join(str(500 + k) for k in range(6000))
    skips.write_text(f"name: k\nstore: summary\nbase: {base}\nsweep:\n  grid:\n"
                     f"    joints.B.coating: [none, PTFE]\n    mechanism.speed_rpm: [{speeds}]\n"
                     "  skip: [{joints.B.coating: PTFE}]\n")
    argv = [{"SAMPLE": str(sample), "SKIPS": str(skips)}.get(a, a) for a in argv]
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 0, result.output
    assert words in result.stdout
    assert 0 < few_cases_made[0] <= 200


def test_the_step_bound_evaluated_as_python_is_the_kernels_to_the_bit():
    """The planning checks run the contact law as plain Python (nothing compiled): the same
    values as the compiled kernel function, so a plan and its run draw the same bound."""
    import inspect

    import numpy as np

    from clearsweep.core.contact import elastic_force
    from clearsweep.params import as_python

    rng = np.random.default_rng(0)
    names = list(inspect.signature(elastic_force.py_func).parameters)
    for _ in range(500):
        c, ri = rng.uniform(1e-6, 1e-3), rng.uniform(1e-3, 5e-2)
        given = {"delta": rng.uniform(1e-9, 1e-4), "c": c, "ew": rng.uniform(1e9, 3e11),
                 "ri": ri, "rj": ri - c, "n": rng.choice([0.0, 1.0, 1.5])}
        args = [float(given[name]) for name in names]
        assert as_python(elastic_force)(*args) == elastic_force(*args)
