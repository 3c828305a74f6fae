"""Drives a plan through a backend: progress, interrupts, resume, and the final file.

:func:`run_sweep` is the public ``clearsweep.sweep``.
"""

from __future__ import annotations

import collections
import contextlib
import errno
import itertools
import os
import shutil
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

import xarray as xr

from ..budget import duration_text, estimate
from ..config import ConfigError
from ..dataset import (
    file_size_limit_text,
    history_line,
    open_results,
    remove_stale_temporaries,
    versions,
    with_command_line,
)
from .assemble import write_sweep_netcdf
from .backends import _backend, _InterruptGuard, _Serial
from .guard import require_main_guard
from .parts import NOT_FAILED, PartStore, file_sha256, part_identity, parts_dir_for, with_identity
from .plan import MAX_CASES, SweepPlan, expand
from .stores import STORES
from .worker import CaseTask, _receipt, _worker_died, reissue

#: Variables (and dataset attributes) that change from run to run of the same sweep.
TIMING_VARIABLES = ("wall_time",)
TIMING_ATTRS = ("history",)


class SweepInterrupted(KeyboardInterrupt):
    """The sweep was stopped (Ctrl-C) before it finished; its finished cases are kept.

    Attributes
    ----------
    finished, total : int
        Cases with a part, and cases to run, in the sweep.
    parts_dir : pathlib.Path
        Where the finished cases are.
    """

    def __init__(self, finished: int, total: int, parts_dir: Path):
        super().__init__(f"sweep interrupted: {finished} of {total} cases finished (kept in {parts_dir})")
        self.finished, self.total, self.parts_dir = finished, total, parts_dir


class SweepFailed(RuntimeError):
    """The backend failed (a worker died, the scheduler went away); finished cases are kept.

    Also raised by :func:`run_sweep` when every case that ran failed (the file, when one
    was asked for, is written: the ``status`` and ``message`` variables say why).
    """


class CasesFailedWarning(UserWarning):
    """Some cases of a sweep failed (their ``status`` and ``message`` say why); the others are fine."""


def _report_failures(ds: xr.Dataset, out: Path | None) -> None:
    """Raise :class:`SweepFailed` when every case of ``ds`` that ran failed; warn with the
    count when some did. Names the first failure's message, and ``out`` where written."""
    failed, cases = int(ds.attrs["sweep_failed"]), int(ds.attrs["sweep_cases"])
    ran = cases - int(ds.attrs["sweep_skipped"])
    if not failed:
        return
    statuses, messages = ds["status"].values.ravel(), ds["message"].values.ravel()
    first = next(f"{s}: {m}" for s, m in zip(statuses, messages) if str(s) not in NOT_FAILED)
    where = f"; see the status and message variables in {out}" if out is not None else ""
    if failed == ran:
        ds.close()
        raise SweepFailed(f"all {ran} cases failed (the first: {first}){where}")
    warnings.warn(f"{failed} of {ran} cases failed (the first: {first}){where}",
                  CasesFailedWarning, stacklevel=3)


def _drive(backend, tasks: Iterable[tuple[str, CaseTask]], on_result: Callable[[str, Any], None],
           guard: _InterruptGuard) -> None:
    """Keep ``backend.window`` cases in flight; hand each result to ``on_result``.

    A result is the case's part (a dataset) or, where the worker wrote the
    part itself, its receipt. Only the result being handled is held, so
    memory does not grow with the sweep.

    A worker process that dies breaks a process pool of our own and every
    case in flight with it: the pool is replaced and those cases are run
    again one at a time, so that the one that kills its worker alone is
    found; it is recorded as failed (status ``error``, with the reason)
    and the sweep goes on.
    """
    tasks = iter(tasks)
    pending: dict[Any, tuple[str, Any]] = {}
    suspects: collections.deque = collections.deque()   # (hash, task) to run again, alone
    solo: tuple[str, Any] | None = None                  # the suspect running alone

    def refill() -> None:
        nonlocal solo
        if solo is not None:
            return
        if suspects:
            solo = suspects.popleft()
            pending[backend.submit(*solo)] = solo
            return
        for h, task in itertools.islice(tasks, backend.window - len(pending)):
            pending[backend.submit(h, task)] = (h, task)

    def finished_well(future) -> bool:
        return future.done() and not future.cancelled() and future.exception() is None

    try:
        refill()
        while pending:
            broken = False
            for future in backend.wait(list(pending)):
                if not finished_well(future) and isinstance(future.exception(), BrokenProcessPool):
                    broken = True
                    continue
                h, _ = pending.pop(future)
                on_result(h, future.result())
                if solo is not None and solo[0] == h:
                    solo = None
            if broken:
                done = [f for f in pending if finished_well(f)]
                for future in done:
                    h, _ = pending.pop(future)
                    on_result(h, future.result())
                lost = list(pending.values())
                how = backend.restart()
                if how is None:
                    raise BrokenProcessPool("a worker process died")
                pending.clear()
                if solo is not None:        # it killed its worker again, alone: a failed case
                    on_result(solo[0], _worker_died(solo[0], how))
                    solo = None
                else:
                    suspects.extend(lost)
            guard.check()
            refill()
    except BaseException:
        backend.cancel(list(pending))
        raise


def drop_timing(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` without what changes from run to run (``wall_time``, ``history``).

    Two runs of one sweep, on any backend and any number of workers, are
    identical after this (``xr.testing.assert_identical``).
    """
    out = ds.drop_vars([v for v in TIMING_VARIABLES if v in ds.variables])
    out.attrs = {k: v for k, v in ds.attrs.items() if k not in TIMING_ATTRS}
    return out


def _attrs(plan: SweepPlan) -> dict[str, Any]:
    from ..variables import mechanism_title

    # the mechanism of its cases (a sweep of mechanism.kind names each)
    kinds = sorted({plan.base.mechanism.kind}
                   | {case.config.mechanism.kind for case in plan.cases if case.config is not None})
    return {
        "title": f"clearsweep {' and '.join(map(mechanism_title, kinds))} parameter sweep",
        "mechanism": " ".join(kinds),
        "Conventions": "CF-1.8",
        "source": "clearsweep",
        "history": with_command_line(
            history_line(f"clearsweep sweep {plan.name!r} from {plan.source}")),
        "sweep_name": plan.name,
        "sweep_store": plan.store,
        "sweep_dims": " ".join(plan.dims),
        "sweep_config": plan.text,
        **versions(),
    }


def run_sweep(config_or_path: str | os.PathLike | Mapping | SweepPlan, out: str | os.PathLike | None = None,
              workers: int | None = None, client=None, resume: bool = False,
              overrides: Iterable[str] = (), progress: bool = True, *, overwrite: bool = False,
              keep_parts: bool = False, discard_parts: bool = False, allow_large: bool = False,
              max_cases: int | None = MAX_CASES, backend: str | None = None,
              keep_series: str | Iterable[int] = (), report_failures: bool = True,
              _simulate: Callable | None = None, _summarize: Callable | None = None) -> xr.Dataset:
    """Run a parameter sweep and return its results as one labelled dataset.

    Parameters
    ----------
    config_or_path
        Sweep YAML file or mapping (module docstring), or a :class:`SweepPlan`
        from :func:`expand` (then ``overrides``, ``allow_large`` and
        ``max_cases`` were applied by it and are ignored here).
    out
        netCDF file to write. ``None``: work in a temporary folder and
        return the dataset loaded into memory (small sweeps only).
    workers
        Worker processes (default: ``os.cpu_count()``); 1 runs the cases in
        this process. Ignored when ``client`` is given.
    client
        A ``distributed.Client``, a scheduler address (connected to here and
        disconnected after), or a ``concurrent.futures.Executor`` owned by
        the caller (e.g. :func:`process_pool`, to reuse warm workers across
        sweeps; a ``ThreadPoolExecutor`` works, its threads writing one part at a time,
        but runs the cases no faster than one worker: the kernel holds the GIL). The
        library never starts a cluster.
    resume
        Keep the finished cases of an interrupted run (``OUT.parts``) and run
        only the others; no case runs twice.
    overrides
        ``"dotted.key=VALUE"`` applied to the base configuration.
    progress
        Show a progress bar (tqdm, on stderr) with the number of failed cases.
    overwrite
        Delete the parts of an earlier run instead of refusing to start.
    keep_parts
        Keep ``OUT.parts`` after the final file is written.
    discard_parts
        Delete the parts in ``OUT.parts`` that are not cases of this sweep
        (left by another sweep file or other overrides); without it such
        parts make the sweep refuse to start, resumed or not.
    allow_large
        Admit cases beyond the work and memory bounds of
        :func:`clearsweep.budget.check_budget`.
    max_cases
        Refuse a sweep of more points (:func:`expand`); ``None``: no limit.
    backend
        ``None`` or ``"processes"``: this process, a process pool or Dask, as
        ``workers`` and ``client`` say; ``"cuda"``: batches on a CUDA device
        (``clearsweep.gpu``; ``workers`` and ``client`` ignored), summaries only.
        Without a device it raises :class:`clearsweep.gpu.NoCudaDevice` before
        anything runs.
    keep_series
        With ``backend="cuda"``: the cases (positions in sweep order, as in
        ``plan.cases``; ``"all"`` for every one) whose time series are kept; they
        run on the CPU kernel in this process and are stored in full.
    report_failures
        Raise :class:`SweepFailed` when every case that ran failed, and warn
        (:class:`CasesFailedWarning`, with the count and the first message) when
        some did; ``False``: return the dataset either way (the ``clearsweep``
        command reports them itself, exit status 1).

    Returns
    -------
    xr.Dataset
        Sweep dimensions first, then the case dimensions; ``status`` and
        ``message`` per case; attributes ``sweep_config``, ``sweep_dims``,
        ``sweep_failed``, versions and ``history``. Opened lazily from
        ``out`` when given (close it when done).

    Raises
    ------
    ConfigError
        Invalid sweep or case (before anything runs; no file is written).
    StoreError
        ``OUT.parts`` holds earlier parts and neither ``resume`` nor
        ``overwrite`` was given, holds parts of another sweep (without
        ``discard_parts`` or ``overwrite``), or another sweep is using it.
    SweepInterrupted
        Ctrl-C: pending cases cancelled, finished ones kept for ``resume``.
    SweepFailed
        The backend failed; finished cases are kept for ``resume``. Or every case that
        ran failed (with ``report_failures``; the file is written).
    UnguardedScript
        ``workers`` > 1 asked for from the top level of a script, outside
        ``if __name__ == "__main__":`` (every worker would re-run the script), from a
        script read from standard input (no worker can re-import it), or in a daemonic
        ``multiprocessing.Pool`` worker (pass ``workers=1`` there), before anything runs.
    """
    plan = (config_or_path if isinstance(config_or_path, SweepPlan)
            else expand(config_or_path, overrides, allow_large=allow_large, max_cases=max_cases))
    cuda = _cuda_options(plan, backend, keep_series)
    if cuda is None and client is None:
        pool = min((os.cpu_count() or 1) if workers is None else int(workers), len(plan.runnable()))
        if pool > 1:
            require_main_guard(pool)
    tmpdir = None
    if out is None:
        tmpdir = tempfile.mkdtemp(prefix="clearsweep-")
        out = Path(tmpdir) / f"{plan.name}.nc"
    out = Path(out)
    store = PartStore(parts_dir_for(out))
    try:
        with _InterruptGuard() as guard:
            runnable = plan.runnable()
            finished = store.open(resume=resume, overwrite=overwrite, expected=set(runnable),
                                  discard_foreign=discard_parts, configs=runnable,
                                  sweep={"name": plan.name, "source": plan.source, "store": plan.store,
                                         "cases": len(plan.cases)})
            # OUT is ours while we hold the lock: drop what a killed assembly left beside it
            remove_stale_temporaries(out)
            try:
                functions = STORES[plan.store].functions()
                simulate_case = _simulate or functions.simulate
                summarize_case = _summarize or functions.summarize
                finish = STORES[plan.store].finish(functions, plan.dims)
                todo = [(h, CaseTask(cfg, plan.store, simulate_case, summarize_case))
                        for h, cfg in runnable.items() if h not in finished]
                _execute(plan, store, todo, len(runnable), workers, client, progress, guard, cuda)
                try:
                    counts = write_sweep_netcdf(out, sweep_dims=plan.dims, sweep_coords=plan.coords,
                                                slots=plan.slots(), store=store, attrs=_attrs(plan),
                                                check=guard.check, finish=finish,
                                                holds=plan.store)
                except KeyboardInterrupt:
                    store.log("interrupted", finished=len(runnable), total=len(runnable))
                    raise SweepInterrupted(len(runnable), len(runnable), store.directory) from None
                store.log("assembled", path=str(out), **counts)
            finally:
                store.close()
        if not keep_parts:
            store.remove()
        if tmpdir is None:
            ds = open_results(out)
        else:
            with open_results(out) as opened:
                ds = opened.load()
        if report_failures:
            _report_failures(ds, out if tmpdir is None else None)
        return ds
    finally:
        if tmpdir is not None:
            shutil.rmtree(tmpdir, ignore_errors=True)


def _cuda_options(plan: SweepPlan, backend: str | None, keep_series: str | Iterable[int]) -> dict | None:
    """``_backend``'s ``cuda`` argument for ``backend`` (None: not the CUDA backend)."""
    if backend in (None, "processes"):
        return None
    if backend != "cuda":
        raise ValueError(f"backend must be 'processes' or 'cuda', got {backend!r}")
    if not STORES[plan.store].on_cuda:
        on_cuda = " or ".join(name for name, store in STORES.items() if store.on_cuda)
        raise ConfigError("store", plan.store, f"{on_cuda} with --backend cuda (life runs "
                          "alternate simulation and jumps on the CPU: use --backend processes)",
                          plan.source)
    methods = {cfg.solver.method for cfg in plan.runnable().values()}
    if methods - {"rk4"}:
        raise ConfigError("solver.method", sorted(methods - {"rk4"})[0],
                          "rk4 with --backend cuda (the device runs the fixed-step RK4 only: "
                          "use --backend processes for dopri5)", plan.source)
    from ..gpu import batch_window, device_name

    device_name()       # NoCudaDevice before anything runs
    if isinstance(keep_series, str):
        if keep_series != "all":
            raise ConfigError("--keep-series", keep_series, "'all' or case positions",
                              plan.source)
        positions: Iterable[int] = range(len(plan.cases))
    else:
        positions = keep_series
    series = set()
    for i in positions:
        if not 0 <= int(i) < len(plan.cases):
            raise ConfigError("--keep-series", i, f"case positions 0 to {len(plan.cases) - 1} "
                              "(in sweep order, 0-based)", plan.source)
        if plan.cases[int(i)].hash is not None:
            series.add(plan.cases[int(i)].hash)
    return {"window": batch_window(list(plan.runnable().values())), "series": frozenset(series)}


def _failed(exc: Exception, label: str, directory: Path, kept: int, total: int) -> SweepFailed:
    """The :class:`SweepFailed` of a sweep that ``exc`` stopped, with ``kept`` of its ``total``
    cases kept in ``directory``: a full disk and a file-size limit named as such."""
    if isinstance(exc, OSError) and exc.errno == errno.ENOSPC:
        return SweepFailed(f"the disk is full: cannot write in {directory} ({exc.strerror}); "
                           f"{kept} of the {total} cases are finished and kept there: make room "
                           "and run again with --resume")
    if isinstance(exc, OSError) and exc.errno == errno.EFBIG:
        reason = (exc.strerror if exc.strerror and "ulimit -f" in exc.strerror
                  else file_size_limit_text())
        return SweepFailed(f"cannot write in {directory}: {reason}; {kept} of the {total} cases "
                           "are finished and kept there: raise the limit (ulimit -f unlimited) "
                           "and run again with --resume")
    return SweepFailed(f"the {label} backend failed ({type(exc).__name__}: {exc}); {kept} of "
                       f"{total} cases are kept in {directory}; run again with --resume to finish "
                       "the sweep")


class StepEta:
    """Time left of a sweep: the wall time since this run's start, over the RK4 steps of the
    cases it finished, times the steps still to run (each case weighted by its steps).

    The clock starts once and never restarts, so the fixed costs before the first finished
    case (the pool's start, each worker loading the kernel) stay in the rate instead of being
    dropped or shown as hours; ``clock`` is injectable for tests."""

    def __init__(self, steps: Mapping[str, float], clock: Callable[[], float]):
        self.steps = dict(steps)
        self.clock = clock
        self.start = clock()
        self.done = 0.0
        self.left = float(sum(self.steps.values()))

    def finished(self, h: str) -> None:
        weight = self.steps.pop(h, 0.0)
        self.done += weight
        self.left -= weight

    def seconds_left(self) -> float | None:
        """``None`` until some work is finished (no rate to go by)."""
        if self.done <= 0.0:
            return None
        return (self.clock() - self.start) * max(self.left, 0.0) / self.done

    def text(self) -> str:
        left = self.seconds_left()
        return "?" if left is None else duration_text(left)


def _execute(plan: SweepPlan, store: PartStore, todo: list, total: int, workers, client,
             progress: bool, guard: _InterruptGuard, cuda: dict | None = None) -> None:
    """Run ``todo`` on the chosen backend, writing each finished case at once."""
    from tqdm.auto import tqdm

    kept = total - len(todo)
    runnable = plan.runnable()
    failed = sum(1 for r in store.events("done") if r.get("status") not in NOT_FAILED
                 and r.get("hash") in runnable) if kept else 0
    try:
        backend = (_backend(workers, client, len(todo), guard, store.directory, cuda) if todo
                   else _Serial(guard))
    except (OSError, TimeoutError) as exc:
        raise SweepFailed(f"cannot start the backend for {client or workers!r}: "
                          f"{type(exc).__name__}: {exc}") from exc
    store.log("run", name=plan.name, source=plan.source, cases=len(plan.cases), to_run=len(todo), kept=kept,
              backend=backend.label, command=plan.command)
    # tqdm's own time left counts cases, all alike; a sweep's cases differ in steps, so the
    # time left is StepEta's (steps-weighted, one clock from the start) in the postfix
    eta = StepEta({h: float(estimate(runnable[h]).steps) for h, _ in todo if h in runnable},
                  time.monotonic)
    bar = tqdm(total=total, initial=kept, desc=plan.name, unit="case", disable=not progress,
               file=sys.stderr, dynamic_ncols=True, smoothing=0,
               bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]")
    bar.set_postfix(failed=failed, left=eta.text())
    done = kept

    warned: set = set()

    def on_result(h: str, result) -> None:
        nonlocal failed, done
        if isinstance(result, xr.Dataset):
            store.write(h, with_identity(result, part_identity(runnable[h], plan.store)))
            result = _receipt(result)
        result = reissue(result, warned)
        # the part's content hash: a ledger line proves a file clearsweep's only with it
        store.log("done", hash=h, sha256=file_sha256(store.path(h)), **result)
        failed += result["status"] not in NOT_FAILED
        done += 1
        eta.finished(h)
        bar.set_postfix(failed=failed, left=eta.text(), refresh=False)
        bar.update()

    interrupted = stopped = False
    failure: Exception | None = None
    try:
        _drive(backend, todo, on_result, guard)
    except KeyboardInterrupt:
        interrupted = stopped = True
    except Exception as exc:
        interrupted, failure = True, exc
        with contextlib.suppress(OSError):      # the log is on the same (maybe full) disk
            store.log("failed", error=f"{type(exc).__name__}: {exc}")
    finally:
        bar.close()
        backend.close(interrupted=interrupted)
    if failure is not None:
        # what --resume keeps: the parts on disk (a pool worker writes its part before the
        # driver hears of it), counted once the workers are stopped
        kept_now = len(store.finished() & set(runnable))
        raise _failed(failure, backend.label, store.directory, kept_now, total) from failure
    if stopped:
        # what is kept is what --resume keeps: the parts on disk, counted once the workers
        # are stopped (a worker writes its part before the driver hears of it)
        kept_now = len(store.finished() & set(runnable))
        store.log("interrupted", finished=kept_now, total=total)
        raise SweepInterrupted(kept_now, total, store.directory)
