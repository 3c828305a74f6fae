"""Runs one case in a worker (pool process, Dask worker or this process) and writes its part."""

from __future__ import annotations

import faulthandler
import functools
import os
import pickle
import signal
import threading
import time
import warnings
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import xarray as xr

from .. import variables
from ..config import Config
from ..summary import case_summary
from .parts import MESSAGE_ATTRS, STATUS_ATTRS, part_identity, with_identity, write_part
from .stores import STORES

#: The receipt's key of the warnings a case raised in a pool worker process.
WARNINGS_KEY = "warnings"
#: How often a pool worker checks that the driver process still exists [s].
WATCHDOG_PERIOD_S = 1.0


def _text(value) -> str:
    value = np.asarray(value)
    return str(value[()] if value.ndim == 0 else value.ravel()[0])


def _failed_part(status: str, message: str, wall_time: float) -> xr.Dataset:
    return xr.Dataset({
        "status": ((), status, STATUS_ATTRS),
        "message": ((), message, MESSAGE_ATTRS),
        "wall_time": ((), float(wall_time), variables.attrs_for("wall_time")),
    })


class CaseTask(NamedTuple):
    """One case as a worker runs it (pickled to pool and Dask workers)."""

    #: The resolved configuration, run as it is.
    config: Config
    #: The sweep's ``store``: ``"full"`` keeps the time series in the part.
    store: str
    #: Config -> dataset; ``None``: :func:`clearsweep.simulation.simulate`.
    simulate: Callable[[Config], xr.Dataset] | None = None
    #: Dataset -> its summaries; ``None``: :func:`clearsweep.summary.case_summary`.
    summarize: Callable[[xr.Dataset], xr.Dataset] | None = None


def _run_case(task: CaseTask) -> xr.Dataset:
    """Simulate one case and build its part (runs in a worker).

    Returns
    -------
    xr.Dataset
        Summaries, ``status`` and ``message``, and the time series unless
        ``task.store`` is ``"summary"`` or ``"life"``. A case that raises, or stops with a
        status other than ``ok``, gives only ``status``, ``message`` and
        ``wall_time``.
    """
    simulate, summarize = task.simulate, task.summarize
    if simulate is None:
        from ..simulation import simulate as simulate_case

        # expand() checked every case's budget, with the sweep's --allow-large
        simulate = functools.partial(simulate_case, allow_large=True)
    if summarize is None:
        summarize = case_summary
    start = time.perf_counter()
    try:
        return _part(simulate(task.config), task.store, summarize, start)
    except Exception as exc:    # a failed case, not a failed sweep
        return _error_part(exc, time.perf_counter() - start)


def _part(ds: xr.Dataset, store_mode: str, summarize=case_summary, start: float | None = None) -> xr.Dataset:
    """The part of a simulated case (see :func:`_run_case`); ``start`` is when it began
    (perf_counter), for the wall time of a failed case without one."""
    status = _text(ds["status"].values)
    if status == "ok":
        summary = summarize(ds)
        no_message = xr.Variable((), "", MESSAGE_ATTRS)
        if not STORES[store_mode].keeps_series:
            return summary.assign(message=no_message)
        if set(summary.coords) - set(ds.coords):
            return ds.assign({**summary.data_vars, "message": no_message})
        # one assign of bare variables: DataArrays would be aligned on every coordinate
        # (the most of a small case's time outside the kernel, before)
        return ds.assign({name: var.variable for name, var in summary.data_vars.items()}
                         | {"message": no_message})
    if "message" in ds:
        message = _text(ds["message"].values)
    else:
        when = ds.attrs.get("status_time_s")
        message = f"the simulation stopped with status {status!r}" + (
            f" at t = {float(when):g} s" if when is not None else "")
    if ds.attrs.get("status_hint"):
        message += f"; {ds.attrs['status_hint']}"
    wall = (float(ds["wall_time"].values) if "wall_time" in ds
            else 0.0 if start is None else time.perf_counter() - start)
    return _failed_part(status, message, wall)


def _error_part(exc: BaseException, wall_time: float = 0.0) -> xr.Dataset:
    """The part of a case that raised ``exc``."""
    return _failed_part("error", f"{type(exc).__name__}: {exc}", wall_time)


def _receipt(part: xr.Dataset) -> dict[str, Any]:
    """What the driver logs of a finished case."""
    wall = float(part["wall_time"].values) if "wall_time" in part else None
    return {"status": _text(part["status"].values), "wall_time": wall}


def _run_and_store(task: CaseTask, parts_dir: str, h: str) -> dict[str, Any]:
    """Run one case and write its part here, in the worker; return its receipt.

    Writing in the worker keeps the driver (which shares the cores) idle
    while the cases run. A pool worker process sends back the warnings the case raised
    (:data:`WARNINGS_KEY`), for :func:`reissue`.
    """
    if threading.current_thread() is not threading.main_thread():
        # a thread of the caller's executor or of a Dask worker: warnings are the process's,
        # and catching them here would change them for every thread at once
        part = _run_case(task)
        write_part(parts_dir, h, with_identity(part, part_identity(task.config, task.store)))
        return _receipt(part)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")     # the driver's filters decide (:func:`reissue`)
        part = _run_case(task)
        write_part(parts_dir, h, with_identity(part, part_identity(task.config, task.store)))
    receipt = _receipt(part)
    if caught:
        receipt[WARNINGS_KEY] = [(str(w.message), _portable(w.category), w.filename, w.lineno)
                                 for w in caught]
    return receipt


def _portable(category: type[Warning]) -> type[Warning]:
    """``category``, or ``UserWarning`` where the class cannot travel to the driver (one
    defined in a function): a warning must not fail the case's receipt."""
    try:
        return category if pickle.loads(pickle.dumps(category)) is category else UserWarning
    except Exception:
        return UserWarning


def reissue(receipt: dict[str, Any], seen: set) -> dict[str, Any]:
    """``receipt`` without the warnings its worker process caught, which are raised again
    here, in the driver, each distinct one once per sweep (``seen``): they reach the caller's
    filters and the ``clearsweep`` command's one-line printer instead of the worker's stderr."""
    receipt = dict(receipt)
    for message, category, filename, lineno in receipt.pop(WARNINGS_KEY, ()):
        if (category, message) not in seen:
            seen.add((category, message))
            warnings.warn_explicit(message, category, filename, lineno)
    return receipt


def _driver_gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    try:        # killed but not yet reaped by its parent
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rpartition(")")[2].split()[0] in ("Z", "X")
    except (OSError, IndexError):
        return False


def _worker_init(driver_pid: int, crash_dir: str | None = None) -> None:
    """Pool worker set-up: leave Ctrl-C to the driver, end when the driver is gone, and, with
    ``crash_dir``, write a fatal error's report (a crash in compiled code: the signal and the
    Python frames) to ``crash_dir/<pid>.log``, read by :func:`crash_report`."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if crash_dir is not None:
        # kept open for the process's life: faulthandler writes to its descriptor when it dies
        faulthandler.enable(open(os.path.join(crash_dir, f"{os.getpid()}.log"), "w"))  # noqa: SIM115

    def watch() -> None:
        # A killed driver cannot stop its pool; without this its workers would wait forever.
        while not _driver_gone(driver_pid):
            time.sleep(WATCHDOG_PERIOD_S)
        os._exit(1)

    threading.Thread(target=watch, name="clearsweep-driver-watch", daemon=True).start()


def crash_report(crash_dir: str | None, pid: int | None) -> str:
    """What the worker ``pid`` wrote when it crashed (:func:`_worker_init`): the fatal
    error and the innermost Python frame, as one line; ``""`` where it wrote nothing."""
    if crash_dir is None or pid is None:
        return ""
    try:
        with open(os.path.join(crash_dir, f"{pid}.log"), encoding="utf-8", errors="replace") as f:
            lines = [line.strip() for line in f if line.strip()]
    except OSError:
        return ""
    error = next((line for line in lines if line.startswith("Fatal Python error")), "")
    # the crashing thread's frames follow "Current thread ...", innermost first
    current = next((i for i, line in enumerate(lines) if line.startswith("Current thread")), 0)
    frame = next((line for line in lines[current:] if line.startswith("File ")), "")
    return "; ".join(x for x in (error, frame and f"in {frame}") if x)


#: What a signal alone says of a worker's end, where the worker could write nothing.
SIGNAL_CAUSES = {"SIGKILL": "the system's out-of-memory killer or a user stopped it; "
                            "--dry-run shows the case's memory"}


def _worker_died(h: str, how: str) -> xr.Dataset:
    """The part of a case that killed its worker twice; ``how``: how the worker ended, with
    what it wrote when it crashed (:meth:`backends._Futures.restart`)."""
    return _failed_part("error", f"the worker process running this case died twice, the second "
                        f"time running it alone on a fresh worker: {how}", 0.0)
