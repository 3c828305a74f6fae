"""How the kernel's functions are compiled for the CPU: one set of options, written once.

Every kernel function is decorated ``@compiled`` (or ``@compiled(inline="always",
locals=...)``): ``numba.njit`` with

- ``cache=True``: the machine code is kept on disk, so a new process starts without
  compiling;
- Numba's runtime off (its ``_nrt`` option False: ``numba_compat.NO_RUNTIME``), that is, no reference counting. The
  kernel's functions never allocate: they work on arrays that their caller owns for the
  whole call. With the runtime on, every call of a compiled function that LLVM does not
  inline increments and decrements the reference count of each array it is handed, an
  atomic read-modify-write each: on the two-clearance case that was about half of the run
  time (``perf``: NRT_incref and NRT_decref), and taking it away gives 1.5-1.9x the steps
  per second (benchmarks/README.md). No arithmetic changes: results are the same to the
  bit.
- numpy's error model (``error_model="numpy"``): a float division is the machine's, with no
  test of the divisor for zero and no path to raise ZeroDivisionError behind it (the kernel
  raises nothing: a status code comes back). A division by zero gives inf or NaN, which the
  step's checks stop as a non-finite state; every other division gives the same bits. The
  tests and their branches cost the one-clearance case about 2.5 % of its steps per CPU
  second (benchmarks/README.md, "Issue 42's CPU goals, measured again").

The entry points that allocate their work arrays (``rk4.integrate``, ``rk4.kernel_result``,
``dopri5.integrate_dopri5``) keep the runtime: they are plain ``njit(cache=True)``, listed
in :data:`ALLOCATING` (tests/test_kernel_rules.py checks every other kernel function).

The CUDA build compiles the same Python functions with the options copied (numba-cuda's
device dispatcher), where the runtime is off by default as well.

A build compiles once per machine, not once per process: :func:`compile_lock` is held
around a first call that may compile (``simulation.prepare_kernel``, the host's
evaluations in ``dynamics``), so that processes needing the same build at once with a cold
cache (a test run's workers, Dask workers) wait for the first and load its machine code
from the cache.
"""

import os
from contextlib import contextmanager

from numba import njit

from .numba_compat import NO_RUNTIME

#: Options of every kernel function that does not allocate.
OPTIONS = {"cache": True, "error_model": "numpy", **NO_RUNTIME}

#: Kernel functions that allocate, compiled with Numba's runtime: "module.function".
ALLOCATING = frozenset({"rk4.integrate", "rk4.kernel_result", "dopri5.integrate_dopri5"})


def compiled(func=None, **options):
    """``@compiled`` or ``@compiled(**options)``: ``numba.njit`` with :data:`OPTIONS` and
    the given ones (inline, locals, ...)."""
    if func is None:
        return njit(**OPTIONS, **options)
    return njit(func, **OPTIONS, **options)


def lock_path(dispatcher, tag) -> str | None:
    """The file :func:`compile_lock` locks for ``dispatcher``'s build ``tag``: beside the
    function's Numba cache index (``<index>.build<tag>.lock``); None where it has no
    on-disk cache (plain Python under NUMBA_DISABLE_JIT)."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    index = getattr(cache_file, "_index_path", None)
    return f"{os.path.splitext(index)[0]}.build{tag}.lock" if index else None


@contextmanager
def compile_lock(dispatcher, tag):
    """Hold an exclusive ``flock`` on :func:`lock_path` of ``dispatcher`` and ``tag`` (a
    build's joint set) while this process compiles that build or loads it: another process
    asking for the same build waits, then loads it from the cache; builds of other tags do
    not wait on each other. Without a cache folder that can be written (or ``fcntl``), no
    lock: each process compiles, as Numba does."""
    path = lock_path(dispatcher, tag)
    fd = None
    if path:
        try:
            import fcntl

            os.makedirs(os.path.dirname(path), exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
            fcntl.flock(fd, fcntl.LOCK_EX)
        except (ImportError, OSError):
            if fd is not None:
                os.close(fd)
            fd = None
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)        # releases the flock
