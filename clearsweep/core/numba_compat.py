"""The Numba internals that clearsweep relies on, in one module, each with a probe.

clearsweep uses four things of Numba and numba-cuda that are not public API. Each is named
here once, used from here alone, and checked by :func:`probes` (tests/test_numba_compat.py
runs them on every CI run, so a Numba release that moves one fails there, with the name
of what moved, rather than deep inside a compile):

- ``_nrt``: the compile option that turns Numba's runtime (reference counting) off for a
  function; :data:`NO_RUNTIME` (core/compiled.py).
- the cache folder: ``numba.config.CACHE_DIR``, read by Numba's cache locator when a
  function with ``cache=True`` is decorated; :func:`use_cache_dir`.
- the CUDA simulator's wrapped kernel arguments, whose numpy array is ``arg._item._ary``;
  :func:`simulator_array` (core/device.py).
- numba-cuda's ``dispatcher.get_current_device``, which its compiler asks for the compute
  capability; :func:`stand_in_device` replaces it while ``python -m clearsweep.ptx``
  compiles for a capability without a device.

:data:`TESTED_NUMBA` is the range of Numba versions the test suite has passed on; the
``numba`` requirement in pyproject.toml states the same range.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numba

#: Numba versions (inclusive lower, exclusive upper) the test suite passed on: 0.68.1 on
#: the project's machines, 0.68.0 with numba-cuda 0.30.4 on a CUDA device.
TESTED_NUMBA = ("0.68", "0.69")

#: The compile option that turns Numba's runtime off for a function (no reference counts).
NO_RUNTIME = {"_nrt": False}


def _version(text: str) -> tuple[int, ...]:
    return tuple(int(p) for p in text.split(".")[:2] if p.isdigit())


def numba_tested() -> bool:
    """Whether the installed Numba lies in :data:`TESTED_NUMBA`."""
    low, high = (_version(v) for v in TESTED_NUMBA)
    return low <= _version(numba.__version__) < high


def cache_dir() -> str:
    """The folder of clearsweep's compiled kernel: under ``NUMBA_CACHE_DIR`` (or the user's
    cache folder), named by a hash of every source file of the kernel package and the Numba
    version. Numba keys a cached function on its own source file only, so a change in a
    helper it calls from another file would leave a stale binary: any change to the kernel
    gets a fresh folder instead."""
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    digest.update(numba.__version__.encode())
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "clearsweep", "numba")
    return os.path.join(root, digest.hexdigest()[:16])


def use_cache_dir() -> str:
    """Point Numba's cache at :func:`cache_dir`; the folder. It must run before the kernel's
    functions are decorated: Numba's cache locator reads the folder at decoration, not at
    compile (core/__init__.py calls it first thing)."""
    numba.config.CACHE_DIR = cache_dir()
    return numba.config.CACHE_DIR


def simulator_array(arg: Any) -> Any:
    """The numpy array behind a CUDA-simulator kernel argument (or its slice); any other
    object unchanged."""
    inner = getattr(arg, "_item", None)
    return arg if inner is None else inner._ary


@contextlib.contextmanager
def stand_in_device(device: Any) -> Iterator[None]:
    """numba-cuda's compiler sees ``device`` as the current device (restored on exit)."""
    from numba.cuda import dispatcher

    real = dispatcher.get_current_device
    dispatcher.get_current_device = lambda: device
    try:
        yield
    finally:
        dispatcher.get_current_device = real


def _probe_no_runtime() -> str | None:
    f = numba.njit(lambda a: a[0] + 1.0, **NO_RUNTIME)
    import numpy as np

    if f(np.ones(1)) != 2.0 or f.targetoptions.get("_nrt", True) is not False:
        return "the '_nrt' compile option no longer turns Numba's runtime off"
    return None


def _cached_probe_target(x: float) -> float:
    return x + 1.0


def _probe_cache_dir() -> str | None:
    import tempfile

    saved = numba.config.CACHE_DIR
    with tempfile.TemporaryDirectory() as folder:
        try:
            numba.config.CACHE_DIR = folder
            numba.njit(cache=True)(_cached_probe_target)(1.0)
        finally:
            numba.config.CACHE_DIR = saved
        if not any(Path(folder).rglob("*.nbi")):
            return "numba.config.CACHE_DIR no longer chooses the folder of cached functions"
    return None


def _probe_simulator() -> str | None:
    import importlib.util

    import numpy as np

    if importlib.util.find_spec("numba.cuda") is None:
        return None     # no CUDA target installed: nothing to check
    try:
        from numba.cuda.simulator.cudadrv.devicearray import (
            FakeCUDAArray,
            FakeWithinKernelCUDAArray,
        )
    except ImportError:
        return "the CUDA simulator's FakeCUDAArray and FakeWithinKernelCUDAArray moved"
    a = np.arange(3.0)
    if simulator_array(FakeWithinKernelCUDAArray(FakeCUDAArray(a))) is not a:
        return "the CUDA simulator's kernel arguments no longer hold their array in _item._ary"
    return None


def _probe_stand_in() -> str | None:
    import importlib.util

    if importlib.util.find_spec("numba.cuda.dispatcher") is None:
        return None
    from numba.cuda import dispatcher

    if not callable(getattr(dispatcher, "get_current_device", None)):
        return "numba-cuda's dispatcher.get_current_device is gone"
    return None


#: name -> probe: None when the internal still works as clearsweep uses it, else what moved.
PROBES: dict[str, Callable[[], str | None]] = {
    "_nrt": _probe_no_runtime, "cache folder": _probe_cache_dir,
    "simulator arrays": _probe_simulator, "compile-only device": _probe_stand_in}


def probes() -> dict[str, str | None]:
    """Run every probe: name -> None (works) or what moved."""
    return {name: probe() for name, probe in PROBES.items()}
