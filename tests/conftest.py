"""Session fixtures shared by the test files: one warm process pool, one small Dask cluster,
and the reference runs that several files check, each computed once per session.

Tiers: ``python -m pytest -q -n auto`` runs everything, spread over the cores by
pytest-xdist (each of its worker processes has its own session fixtures);
``python -m pytest -q -n auto -m "not slow"`` leaves out the long physics runs and builds
marked ``slow`` (the fast tier, for development).
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


@pytest.fixture(scope="session")
def short_life_cli(tmp_path_factory):
    """``clearsweep life`` of tests/test_service_life.py's SHORT_LIFE run, once per session:
    ``(output file, click result)``. test_service_life and test_report_summary read it."""
    from click.testing import CliRunner

    from clearsweep.cli import main
    from tests.test_service_life import CASE, SHORT_LIFE

    out = tmp_path_factory.mktemp("life") / "life.nc"
    args = ["life", str(ROOT / CASE), "-o", str(out), *[a for o in SHORT_LIFE for a in ("--set", o)]]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    return out, result
