"""Session fixtures shared by the test files: one warm process pool, one small Dask cluster,
and the reference runs that several files check, each computed once per session (once per
test run where :func:`made_once` keeps it).

Tiers: ``python -m pytest -q -n auto`` (the default run) leaves out the long physics runs
and builds marked ``slow`` (``pyproject.toml``'s ``addopts``) and spreads the rest over the
cores by pytest-xdist (each of its worker processes has its own session fixtures);
``python -m pytest -q -n auto -m slow`` runs the slow ones alone. CI (``.ci/run``) runs
both.
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def process_pool():
    """Two warm worker processes (each loads the Numba kernel once), passed to
    ``run_sweep(..., client=process_pool)`` by the tests that compare one worker with two."""
    from clearsweep.sweeping import process_pool as make_pool

    pool = make_pool(2)
    yield pool
    pool.shutdown(cancel_futures=True)


@pytest.fixture(scope="session")
def dask_cluster():
    """A local Dask cluster of two single-thread worker processes."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        yield cluster


@pytest.fixture(scope="session")
def two_clearances_1s():
    """One crank turn (the default 1 s) with 0.25 mm clearance at A and B, everything else
    the defaults: test_engine_clearance and test_statistics both check it."""
    from clearsweep.simulation import simulate

    return simulate({"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}}})


def made_once(tmp_path_factory, name: str, make) -> Path:
    """A folder that ``make(folder)`` fills once per test run, even when pytest-xdist runs
    the tests in several worker processes, each with its own session fixtures: the first
    worker to ask makes it, under a lock, in the folder the workers share (the parent of
    each one's base temporary folder); the others wait and read it."""
    import fcntl
    import os

    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    folder = shared / name
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder / ".made").exists():
            folder.mkdir(exist_ok=True)
            make(folder)
            (folder / ".made").touch()
    return folder


@pytest.fixture(scope="session")
def short_life_cli(tmp_path_factory):
    """``clearsweep life`` of tests/test_service_life.py's SHORT_LIFE run, once per test run
    (:func:`made_once`): ``(output file, result)``, the result with the command's
    ``exit_code``, ``stdout`` and ``stderr``. test_service_life and test_report_summary read
    it."""
    import json
    from types import SimpleNamespace

    def make(folder: Path) -> None:
        from click.testing import CliRunner

        from clearsweep.cli import main
        from tests.test_service_life import CASE, SHORT_LIFE

        args = ["life", str(ROOT / CASE), "-o", str(folder / "life.nc"),
                *[a for o in SHORT_LIFE for a in ("--set", o)]]
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 0, result.output
        (folder / "result.json").write_text(json.dumps(
            {"exit_code": result.exit_code, "stdout": result.stdout, "stderr": result.stderr}))

    folder = made_once(tmp_path_factory, "short_life", make)
    result = SimpleNamespace(**json.loads((folder / "result.json").read_text()))
    return folder / "life.nc", result
