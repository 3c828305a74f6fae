"""One compile of a kernel build per machine (``core.compiled.compile_lock``, held by
``simulation.prepare_kernel`` and the host's evaluations in ``core.dynamics``): a process
that compiles a build holds a lock beside the function's Numba cache, so that another
process needing the same build on a cold cache waits and loads it from the cache instead
of compiling it again (a test run's workers, Dask workers); other builds do not wait."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from clearsweep.core import dynamics, jointset
from clearsweep.core.compiled import compile_lock, lock_path
from clearsweep.simulation import _kernel

#: Tries the lock file argv[1] without waiting; exit 3 where another process holds it.
TRY_LOCK = """
import fcntl, os, sys
fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT, 0o666)
try:
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
except BlockingIOError:
    sys.exit(3)
"""


def try_lock(path: str) -> int:
    return subprocess.run([sys.executable, "-c", TRY_LOCK, path], timeout=60).returncode


def test_a_build_being_compiled_is_locked_for_other_processes_and_other_builds_are_not():
    kernel = _kernel("rk4")
    b_alone = jointset.named("B", "O", "P")
    a_and_b = jointset.named("A", "B", "O", "P")
    held, other = lock_path(kernel, b_alone), lock_path(kernel, a_and_b)
    assert held and other and held != other
    with compile_lock(kernel, b_alone):
        assert try_lock(held) == 3          # the same build: another process waits
        assert try_lock(other) == 0         # another build: no wait
    assert try_lock(held) == 0              # released once compiled


def test_each_method_locks_its_own_kernel():
    assert lock_path(_kernel("rk4"), 15) != lock_path(_kernel("dopri5"), 15)


def test_the_hosts_first_evaluation_takes_the_lock_and_later_ones_do_not(monkeypatch):
    """``dynamics._diagnostics_at``'s first call of a build in a process goes through the
    lock (it may compile), and marks the build ready; the next call does not lock."""
    from clearsweep.config import DEFAULTS, resolve_materials
    from clearsweep.params import pack

    packed = pack(DEFAULTS, resolve_materials(DEFAULTS), seat=False)
    taken = []
    real = dynamics.compile_lock

    def spy(fn, tag):
        taken.append(tag)
        return real(fn, tag)

    monkeypatch.setattr(dynamics, "compile_lock", spy)
    monkeypatch.setattr(dynamics, "_HOST_READY", set())
    wmap = np.zeros((len(packed.jp),) + tuple(packed.map_shape))
    first = dynamics._diagnostics_at(0.0, packed.y0, packed.p, packed.jp, wmap, ideal=True)
    second = dynamics._diagnostics_at(0.0, packed.y0, packed.p, packed.jp, wmap, ideal=True)
    assert taken == [f"host{jointset.NONE}"]
    assert first is not None and np.array_equal(first, second)
