"""CUDA batch kernel: one thread per case, running the CPU kernel's own :func:`rk4.advance`.

No physics is written here. Numba's CUDA target compiles a CPU ``@njit`` function that a
kernel calls as a device function (``CUDATypingContext.resolve_value_type`` turns the CPU
dispatcher into a device dispatcher of the same Python source), so :func:`run_cases`
reaches ``advance``, ``evaluate``, the contact law and the wear map through the very
functions that ``rk4.integrate`` runs on the CPU.

Every array argument carries the case as its first axis; thread i integrates case i on
its own slices: inputs (p, jp, y0, n_steps, save_every), results (wmap, proj, wvol,
info, stats, track) and the work arrays of ``rk4.work_shapes``. No rows are saved on
the device (``keep_rows`` False): the summaries are the kernel's running statistics, the
wear map and projections.

Importing this module imports ``numba.cuda``; with ``NUMBA_ENABLE_CUDASIM=1`` (read when
numba is first imported) the kernel runs in numba's CUDA simulator, where each thread is a
Python thread: the simulator hands kernels wrapped arrays, which :func:`_advance` unwraps
there. ``advance`` then runs compiled for the CPU, unless ``NUMBA_DISABLE_JIT=1`` is set
too, when it runs as the Python source that the CUDA compiler sees (tests/test_gpu.py).
The build for a device is checked without one by ``python -m clearsweep.ptx``.
"""

import numba
from numba import cuda

from .rk4 import PAIR_FIRST, advance

SIMULATED = bool(numba.config.ENABLE_CUDASIM)

#: Threads per block. The kernel is register- and local-memory-heavy (the right-hand side
#: keeps its 3-vectors and 3x3 matrices in registers): small blocks keep occupancy even.
THREADS_PER_BLOCK = 64

if SIMULATED:
    def _plain(a):
        """The numpy array behind a simulator kernel argument (or its slice)."""
        inner = getattr(a, "_item", None)
        return a if inner is None else inner._ary

    def _advance(*args):
        return advance(*(_plain(a) for a in args))
else:
    _advance = advance


@cuda.jit
def run_cases(p, jp, y0, n_steps, save_every, wmap, proj, wvol, info, stats, track, vec, diag,
              cstate, msave, pairs, mats, vz, buf_i, buf_v, caps, scratch, rows_t, rows_y, rows_d,
              rows_wmax):
    """Integrate case i = thread index from t = 0 (see :func:`rk4.advance`); the grouped work
    arrays of ``rk4.work_shapes`` are handed to advance row by row; ``rows_*`` are
    placeholders (one row per case) that ``keep_rows = False`` leaves untouched."""
    i = cuda.grid(1)
    if i < p.shape[0]:
        v = vec[i]
        pr = pairs[i]
        _advance(p[i], jp[i], y0[i], 0.0, n_steps[i], save_every[i], wmap[i], proj[i], wvol[i],
                 False, rows_t[i], rows_y[i], rows_d[i], rows_wmax[i], info[i], stats[i], track[i],
                 pr[PAIR_FIRST], v[0], v[1], v[2], v[3], v[4], v[5], v[6], diag[i, 0],
                 diag[i, 1], cstate[i, 0], cstate[i, 1], msave[i], pr[0], pr[1], pr[2],
                 pr[PAIR_FIRST + 1], mats[i, 0], mats[i, 1], mats[i, 2], vz[i], buf_i[i],
                 buf_v[i], caps[i, 0], caps[i, 1], scratch[i])


def launch(arrays: tuple) -> None:
    """Run :func:`run_cases` over every case of ``arrays`` (its arguments, device or host
    arrays) and wait for it to finish."""
    n = arrays[0].shape[0]
    blocks = (n + THREADS_PER_BLOCK - 1) // THREADS_PER_BLOCK
    run_cases[blocks, THREADS_PER_BLOCK](*arrays)
    cuda.synchronize()
