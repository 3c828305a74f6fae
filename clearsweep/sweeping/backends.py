"""Where cases run: in this process, on a process pool, or on a Dask client."""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import shutil
import signal
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from ..summary import case_summary
from .guard import require_main_guard
from .stores import CUDA_BATCH
from .worker import SIGNAL_CAUSES, CaseTask, _error_part, _part, _run_and_store, _run_case, _worker_init, crash_report

#: Futures kept in flight per worker, so that no worker waits for the driver.
IN_FLIGHT_PER_WORKER = 2


class _InterruptGuard:
    """Ctrl-C that never lands inside a file write.

    While active (main thread only), SIGINT raises ``KeyboardInterrupt``
    only inside :meth:`interruptible` blocks (waiting for workers, running a
    case in this process); anywhere else it is noted and raised by the next
    :meth:`check`. An interrupt inside netCDF/HDF5 or xarray's file locks can
    leave a lock held and hang the cleanup; this keeps it out of them.
    """

    def __init__(self):
        self.requested = False
        self._depth = 0
        self._previous = None

    def __enter__(self) -> _InterruptGuard:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None

    def _handler(self, signum, frame) -> None:
        first = not self.requested
        self.requested = True
        if first and self._depth:
            self._depth = 0
            raise KeyboardInterrupt

    @contextmanager
    def interruptible(self):
        """A block that Ctrl-C may interrupt at once."""
        self.check()
        self._depth += 1
        try:
            yield
        finally:
            self._depth = max(self._depth - 1, 0)

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed since the guard started."""
        if self.requested:
            raise KeyboardInterrupt


class _Serial:
    """Runs each case in this process when it is submitted."""

    label = "serial"
    window = 1

    def __init__(self, guard: _InterruptGuard):
        self.guard = guard

    def submit(self, h: str, task: CaseTask) -> cf.Future:
        future: cf.Future = cf.Future()
        with self.guard.interruptible():
            part = _run_case(task)
        future.set_result(part)
        return future

    def wait(self, futures):
        return futures

    def restart(self) -> str | None:
        return None

    def cancel(self, futures) -> None:
        pass

    def close(self, interrupted: bool = False) -> None:
        pass


class _Cuda:
    """Runs the cases in batches on a CUDA device (``clearsweep.gpu``), one thread per case.

    ``submit`` only queues a case; ``wait`` runs every queued case as one batch (split
    further to fit the device) and hands back their parts: summaries only, whatever the
    sweep's store. The cases named in ``series`` (hashes) keep their time series: they
    run on the CPU kernel in this process, with the sweep's store set to ``full``.
    """

    def __init__(self, guard: _InterruptGuard, window: int, series: frozenset[str] = frozenset()):
        from ..gpu import device_name

        self.guard, self.window, self.series = guard, max(1, int(window)), series
        self.label = f"cuda({device_name()}, {self.window} cases per batch)"
        self._queued: list[tuple[cf.Future, str, CaseTask]] = []

    def submit(self, h: str, task: CaseTask) -> cf.Future:
        future: cf.Future = cf.Future()
        self._queued.append((future, h, task))
        return future

    def wait(self, futures):
        from ..gpu import simulate_batch

        queued, self._queued = self._queued, []
        on_device = [(f, p) for f, h, p in queued if h not in self.series]
        with self.guard.interruptible():
            for future, h, task in queued:
                if h in self.series:
                    future.set_result(_run_case(task._replace(store=CUDA_BATCH.with_series,
                                                                  simulate=None)))
            started = time.perf_counter()
            try:
                results = simulate_batch([task.config for _, task in on_device])
            except Exception as exc:     # the device failed: every case of the batch did
                results = [exc] * len(on_device)
            wall = (time.perf_counter() - started) / max(len(on_device), 1)
        for (future, task), result in zip(on_device, results):
            try:
                part = (_error_part(result, wall) if isinstance(result, BaseException)
                        else _part(result, CUDA_BATCH.on_device, task.summarize or case_summary))
            except Exception as exc:
                part = _error_part(exc, wall)
            future.set_result(part)
        return futures

    def restart(self) -> str | None:
        return None

    def cancel(self, futures) -> None:
        self._queued.clear()

    def close(self, interrupted: bool = False) -> None:
        pass


def _mp_context():
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def process_pool(workers: int | None = None, crash_dir: str | None = None) -> cf.ProcessPoolExecutor:
    """A process pool set up as :func:`run_sweep` sets up its own.

    Pass it as ``client=`` to run several sweeps on the same warm workers
    (each worker loads the Numba kernel once); shut it down when done.

    Parameters
    ----------
    workers
        Worker processes (default: ``os.cpu_count()``).
    crash_dir
        A folder where each worker writes what it says when it crashes
        (``<pid>.log``: the fatal error and its Python frames).

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        ``forkserver`` (or ``spawn``) workers that ignore Ctrl-C (the driver
        handles it) and exit by themselves when the driver process is gone.

    Raises
    ------
    clearsweep.sweeping.UnguardedScript
        Called from a script's top level, outside ``if __name__ == "__main__":``
        (each worker would re-run the script).
    """
    require_main_guard(workers or os.cpu_count() or 1)
    return cf.ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1,
                                  mp_context=_mp_context(), initializer=_worker_init,
                                  initargs=(os.getpid(), crash_dir))


class _Futures:
    """A ``concurrent.futures`` executor: our own process pool, or one the caller passes."""

    def __init__(self, executor: cf.Executor, own: bool, guard: _InterruptGuard, parts_dir: Path):
        self.executor, self.own, self.guard = executor, own, guard
        self.parts_dir = str(parts_dir)
        workers = getattr(executor, "_max_workers", None) or os.cpu_count() or 1
        self.window = IN_FLIGHT_PER_WORKER * workers
        self.label = f"{type(executor).__name__}({workers})"
        self.crash_dir: str | None = None

    @classmethod
    def processes(cls, workers: int, guard: _InterruptGuard, parts_dir: Path) -> _Futures:
        crash_dir = tempfile.mkdtemp(prefix="clearsweep-workers-")
        futures = cls(process_pool(workers, crash_dir), own=True, guard=guard, parts_dir=parts_dir)
        futures.crash_dir = crash_dir
        return futures

    def submit(self, h: str, task: CaseTask) -> cf.Future:
        return self.executor.submit(_run_and_store, task, self.parts_dir, h)

    def restart(self) -> str | None:
        """Replace a broken pool of our own by a fresh one; how its workers ended.

        ``None`` where the pool is the caller's: it cannot be replaced here.
        """
        if not self.own:
            return None
        processes = list((getattr(self.executor, "_processes", None) or {}).values())
        ends = sorted({_exit_text(p.exitcode, crash_report(self.crash_dir, p.pid))
                       for p in processes if p.exitcode is not None and p.exitcode != 0})
        self.executor.shutdown(wait=False, cancel_futures=True)
        workers = getattr(self.executor, "_max_workers", None)
        self.executor = process_pool(workers, self.crash_dir)
        return ", ".join(ends) or "ended abruptly"

    def wait(self, futures):
        with self.guard.interruptible():
            return cf.wait(futures, return_when=cf.FIRST_COMPLETED).done

    def cancel(self, futures) -> None:
        for future in futures:
            future.cancel()

    def close(self, interrupted: bool = False) -> None:
        if not self.own:
            return
        try:
            self._close(interrupted)
        finally:
            if self.crash_dir is not None:
                shutil.rmtree(self.crash_dir, ignore_errors=True)

    def _close(self, interrupted: bool) -> None:
        if not interrupted:
            self.executor.shutdown(wait=True)
            return
        # Cases still running are lost anyway: stop their processes instead of waiting for them.
        processes = list((getattr(self.executor, "_processes", None) or {}).values())
        self.executor.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join(timeout=5)


class _Dask:
    """A ``distributed.Client`` (given, or connected here to a scheduler address).

    Workers of a local cluster (``LocalCluster``: this machine, this file system) write
    their cases' parts themselves, as pool workers do, and send back a receipt; workers
    that may run on other machines send each finished case back and the driver writes its
    part (compressing it: the driver's time, not the workers').
    """

    def __init__(self, client, own: bool, guard: _InterruptGuard, parts_dir: Path | None = None):
        self.client, self.own, self.guard = client, own, guard
        threads = sum(client.nthreads().values()) or 1
        self.window = IN_FLIGHT_PER_WORKER * threads
        # absolute: a worker's working folder is the one the cluster started in
        self.parts_dir = (os.path.abspath(parts_dir) if parts_dir is not None
                          and _local_cluster(client) else None)
        self.label = f"dask({client.scheduler.address}, {threads} threads)"

    def submit(self, h: str, task: CaseTask):
        if self.parts_dir is not None:
            return self.client.submit(_run_and_store, task, self.parts_dir, h, pure=False)
        return self.client.submit(_run_case, task, pure=False)

    def wait(self, futures):
        from distributed import wait

        with self.guard.interruptible():
            return wait(futures, return_when="FIRST_COMPLETED").done

    def cancel(self, futures) -> None:
        if futures:
            self.client.cancel(list(futures))

    def restart(self) -> str | None:
        return None     # the scheduler retries on other workers itself

    def close(self, interrupted: bool = False) -> None:
        if self.own:
            self.client.close()


def _backend(workers: int | None, client, n_cases: int, guard: _InterruptGuard, parts_dir: Path,
             cuda: dict | None = None):
    if cuda is not None:
        return _Cuda(guard, **cuda)
    if client is not None:
        if isinstance(client, cf.Executor):
            return _Futures(client, own=False, guard=guard, parts_dir=parts_dir)
        if isinstance(client, str):
            from distributed import Client

            return _Dask(Client(client), own=True, guard=guard, parts_dir=parts_dir)
        return _Dask(client, own=False, guard=guard, parts_dir=parts_dir)
    workers = (os.cpu_count() or 1) if workers is None else int(workers)
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    workers = min(workers, n_cases)
    return _Serial(guard) if workers <= 1 else _Futures.processes(workers, guard, parts_dir)


def _local_cluster(client) -> bool:
    """Whether ``client``'s workers are those of a ``distributed.LocalCluster`` (this machine)."""
    from distributed import LocalCluster

    return isinstance(getattr(client, "cluster", None), LocalCluster)


def _exit_text(exitcode: int, said: str = "") -> str:
    """How a worker ended: its exit status, and what it wrote when it crashed (``said``), or
    what the status alone tells."""
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        said = said or SIGNAL_CAUSES.get(name, "")
        return f"killed by {name}" + (f" ({said})" if said else "")
    return f"exit code {exitcode}" + (f" ({said})" if said else "")
