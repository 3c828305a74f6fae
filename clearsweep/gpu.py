"""Cases in batches on a CUDA device: pack, copy, one thread per case, summaries back.

The device runs ``core.device.run_cases``, which calls the CPU kernel's own
``core.rk4.advance`` (one source of the physics for both targets). What comes back per
case is what the summaries need: the running statistics (layout.M_*), the wear map, the
projections, the worn volume, the counters and the energy residual; no time series (a
sweep runs the cases whose series it keeps on the CPU: ``sweeping.backends``).

Memory per case (:func:`case_bytes`): the wear map 16 * npolar * nazim bytes, the
projections 17,280, the undo buffer 128 * 2**max_substep_level, and about 6.6 kB of
other work arrays and results; 0.73 MB for the default map [144, 288] and level 8.
Cases are grouped by wear-map shape and run in batches that fit the device's free memory,
stored structure-of-arrays (element e of case i at e * capacity + i) and padded to a launch
capacity (:data:`CAPACITIES`, :func:`batch_plan`): a batch takes capacity x case_bytes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .config import Config, resolve_materials
from .core import layout as L
from .core.rk4 import INT_WORK, PAIR_FIRST, work_shapes
from .params import Packed, pack
from .simulation import KernelRun, check_step, section_rows

#: What a sweep or the CLI reports when no device is there.
NO_DEVICE = "no CUDA device: use --backend processes"

#: Share of the device's free memory that one batch may take.
DEVICE_MEMORY_FRACTION = 0.5

#: Host memory [bytes] that one batch's arrays and results may take at most: 16 GiB (10,000
#: cases of the default map at 1.46 MB each, four joints' maps), or a quarter of the
#: machine's memory where that is less (:func:`host_batch_bytes`). A batch must hold
#: thousands of cases to fill the device: on an H200, one launch of 1,470 cases ran
#: 7.4e6 RK4 steps/s, of 10,000 cases 1.71e7 (benchmarks/README.md, "CUDA backend").
HOST_BATCH_BYTES = 16 << 30

#: Cases per batch in numba's CUDA simulator (every thread is a Python thread).
SIMULATOR_BATCH = 64

#: The device layouts and launch capacities (``core.device``, which imports numba.cuda:
#: stated here too, so that planning a batch needs no CUDA import; tests check they agree).
LAYOUTS = ("soa", "aos")
DEFAULT_LAYOUT = "soa"
CAPACITIES = (64, 1024, 4096, 16384, 32768)


class NoCudaDevice(RuntimeError):
    """``--backend cuda`` without a CUDA device (and without the simulator)."""

    def __init__(self, detail: str = ""):
        super().__init__(NO_DEVICE + (f" ({detail})" if detail else ""))


class CudaPairing(NoCudaDevice):
    """numba-cuda and numpy releases that do not compile the kernel together: no usable
    device, said in one line before any case runs."""

    def __init__(self, message: str):
        RuntimeError.__init__(self, message)


#: numba-cuda releases (major, minor) and the numpy (major, minor) below which each
#: compiles the kernel: numba-cuda 0.30 (0.30.4 on the device image) fails with numpy 2.5,
#: whose removal of np.row_stack breaks its compiler, and every case of a sweep came back
#: ``failed`` with numpy's message (benchmarks/README.md, "CUDA backend"). pyproject.toml's
#: ``cuda`` and ``test`` extras pin the same pairing (tests/test_gpu.py checks they agree).
NUMPY_BELOW = {(0, 30): (2, 5)}


def _minor(version: str) -> tuple[int, int]:
    parts = [int("".join(c for c in p if c.isdigit()) or 0) for p in version.split(".")[:2]]
    return (parts + [0, 0])[0], (parts + [0, 0])[1]


def installed_versions() -> tuple[str, str | None]:
    """(numpy's version, numba-cuda's; None where numba-cuda is not installed)."""
    from importlib import metadata

    try:
        numba_cuda: str | None = metadata.version("numba-cuda")
    except metadata.PackageNotFoundError:
        numba_cuda = None
    return np.__version__, numba_cuda


def pairing_problem(numpy_version: str, numba_cuda_version: str | None) -> str | None:
    """The one-line message for a numpy and numba-cuda pairing that does not compile the
    kernel (:data:`NUMPY_BELOW`), None for one that does or is not known not to."""
    if numba_cuda_version is None:
        return None
    below = NUMPY_BELOW.get(_minor(numba_cuda_version))
    if below is None or _minor(numpy_version) < below:
        return None
    return (f"numba-cuda {numba_cuda_version} does not compile the kernel with numpy "
            f"{numpy_version}: install numpy below {below[0]}.{below[1]} "
            "(pip install 'clearsweep[cuda]'), or use --backend processes")


def simulated() -> bool:
    """Whether numba's CUDA simulator stands in for the device (``NUMBA_ENABLE_CUDASIM=1``)."""
    import numba

    return bool(getattr(numba.config, "ENABLE_CUDASIM", 0))


def device_name() -> str:
    """The CUDA device's name; raises :class:`NoCudaDevice` when there is none, and
    :class:`CudaPairing` (one of them) when the installed numpy and numba-cuda do not compile
    the kernel together (:data:`NUMPY_BELOW`), before anything is compiled or run."""
    if simulated():
        return "numba CUDA simulator"
    problem = pairing_problem(*installed_versions())
    if problem is not None:
        raise CudaPairing(problem)
    try:
        from numba import cuda

        if not cuda.is_available():
            raise NoCudaDevice()
        name = cuda.get_current_device().name
    except NoCudaDevice:
        raise
    except Exception as exc:    # no driver, no toolkit, a broken install: all "no device"
        raise NoCudaDevice(f"{type(exc).__name__}: {exc}") from exc
    return name.decode() if isinstance(name, bytes) else str(name)


def case_bytes(map_shape: Sequence[int], max_level: int, sections: int = 0) -> int:
    """Device memory [bytes] that one case of a batch takes (inputs, results, work);
    ``sections``: the Poincare section rows its batch holds."""
    npolar, nazim = int(map_shape[0]), int(map_shape[1])
    nj = L.N_JOINTS
    items = (L.N_P + nj * L.N_JP + L.N_Y + 2       # p, jp, y0, n_steps, save_every
             + nj * npolar * nazim + nj * 3 * L.N_ANGLE_BINS + nj   # wmap, proj, wvol
             + L.N_INFO + L.N_WINDOWS * L.N_M + L.N_TRACK     # info, stats, track
             + sections * L.N_SEC                                # sec
             + 1 + L.N_Y + L.N_D + nj)             # row placeholders
    items += sum(math.prod(s) for s in work_shapes(max_level, npolar).values())
    return 8 * items


def config_bytes(cfg: Config) -> int:
    """:func:`case_bytes` of a resolved config (its revolutions, one section each, rounded
    up)."""
    sections = math.ceil(cfg.solver.duration * cfg.mechanism.speed_rpm / 60.0) + 1
    return case_bytes(cfg.wear.map, cfg.solver.max_substep_level, sections)


def host_batch_bytes() -> int:
    """Host memory [bytes] one batch may take: :data:`HOST_BATCH_BYTES`, or a quarter of
    the machine's physical memory where that is less."""
    import os

    try:
        physical = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):    # no sysconf: the fixed bound alone
        return HOST_BATCH_BYTES
    return min(HOST_BATCH_BYTES, max(int(physical) // 4, 1))


def batch_window(configs: Sequence[Config]) -> int:
    """Cases per batch that a sweep hands to :func:`simulate_batch` (host memory bound)."""
    if not configs:
        return 1
    return max(1, min(len(configs), host_batch_bytes() // max(config_bytes(c) for c in configs)))


def _device_budget() -> int:
    from numba import cuda

    free, _ = cuda.current_context().get_memory_info()
    return int(DEVICE_MEMORY_FRACTION * free)


def _shapes(group: Sequence[Packed]) -> dict[str, tuple[tuple[int, ...], Any, float]]:
    """Per-case shape, dtype and initial value of run_cases' arguments but the inputs p, jp,
    y0, n_steps and save_every, by name (``core.device.ARGS``' order), for one batch of cases
    of one map shape."""
    npolar, nazim = group[0].map_shape
    max_level = max(int(pk.p[L.P_MAX_LEVEL]) for pk in group)
    shapes: dict[str, tuple[tuple[int, ...], Any, float]] = {
        "wmap": ((L.N_JOINTS, npolar, nazim), np.float64, 0.0),
        "proj": ((L.N_JOINTS, 3, L.N_ANGLE_BINS), np.float64, 0.0),
        "wvol": ((L.N_JOINTS,), np.float64, 0.0), "info": ((L.N_INFO,), np.int64, 0),
        "stats": ((L.N_WINDOWS, L.N_M), np.float64, 0.0), "track": ((L.N_TRACK,), np.float64, 0.0),
        # one row at least: no zero-size array for the device
        "sec": ((max(1, max(section_rows(pk) for pk in group)), L.N_SEC), np.float64, np.nan)}
    for name, shape in work_shapes(max_level, npolar).items():
        shapes[name] = (shape, np.int64 if name in INT_WORK else np.float64, 0)
    shapes.update(rows_t=((1,), np.float64, 0.0), rows_y=((1, L.N_Y), np.float64, 0.0),
                  rows_d=((1, L.N_D), np.float64, 0.0), rows_wmax=((1, L.N_JOINTS), np.float64, 0.0))
    return shapes


def _allocate(group: Sequence[Packed], layout: str = "aos",
              capacity: int | None = None) -> dict[str, np.ndarray]:
    """Host arrays of run_cases' arguments, by name (``core.device.ARGS``), for one batch of
    cases of one map shape: with the case first ("aos"), or stored structure-of-arrays with
    the case last, padded to ``capacity`` cases ("soa": ``core.device.soa_kernel``; the
    smallest launch capacity that holds the batch by default). n_steps and save_every hold
    the batch's cases alone in either layout."""
    n = len(group)
    inputs = {"p": np.stack([pk.p for pk in group]), "jp": np.stack([pk.jp for pk in group]),
              "y0": np.stack([pk.y0 for pk in group])}
    arrays: dict[str, np.ndarray] = {}
    if layout == "aos":
        arrays.update(inputs)
    else:
        cap = capacity if capacity is not None else capacity_for(n)
        for name, a in inputs.items():
            arrays[name] = to_soa(a, cap)
    arrays["n_steps"] = np.array([pk.n_steps for pk in group], dtype=np.int64)
    arrays["save_every"] = np.array([pk.save_every for pk in group], dtype=np.int64)
    for name, (shape, dtype, fill) in _shapes(group).items():
        full = (n,) + shape if layout == "aos" else shape + (cap,)
        arrays[name] = np.full(full, fill, dtype=dtype) if fill != 0 else np.zeros(full, dtype=dtype)
    from .core.device import ARGS

    return {name: arrays[name] for name in ARGS}


def capacity_for(n: int) -> int:
    """The launch capacity a batch of n cases is stored for (``core.device.capacity_for``,
    without importing numba.cuda)."""
    for cap in CAPACITIES:
        if n <= cap:
            return cap
    raise ValueError(f"{n} cases exceed the largest launch capacity {CAPACITIES[-1]}")


def to_soa(a: np.ndarray, capacity: int) -> np.ndarray:
    """Case-first a (n, ...) stored structure-of-arrays: shape (..., capacity), case i of a
    in column i, the padding zero."""
    n = a.shape[0]
    out = np.zeros(a.shape[1:] + (capacity,), dtype=a.dtype)
    out[..., :n] = np.moveaxis(a, 0, -1)
    return out


def from_soa(a: np.ndarray, n: int) -> np.ndarray:
    """The first n cases of a structure-of-arrays a (..., capacity), case first (a view)."""
    return np.moveaxis(a[..., :n], -1, 0)


def batch_plan(n: int, fit: int) -> tuple[int, int]:
    """(cases per batch, launch capacity) of the structure-of-arrays layout for n cases of
    which ``fit`` fit the device's memory at once: as many as fit, in the smallest capacity
    that holds them, where that capacity fits too; else in the largest capacity that fits
    (the smallest, at worst)."""
    size = max(1, min(n, fit, CAPACITIES[-1]))
    cap = capacity_for(size)
    if cap > fit:
        fitting = [c for c in CAPACITIES if c <= fit]
        cap = fitting[-1] if fitting else CAPACITIES[0]
        size = min(size, cap)
    return size, cap


def _run_on_device(arrays: dict[str, np.ndarray], layout: str = "aos") -> dict[str, np.ndarray]:
    """Launch one batch; the arrays it gives back (``core.device.RESULTS``: wmap, proj,
    wvol, info, stats, track and the work array ``pairs``, which holds the first impact
    times) on the host, by name, case first."""
    from .core import device

    n = arrays["n_steps"].shape[0]
    if simulated():
        device.launch(arrays, layout)
        res = {name: arrays[name] for name in device.RESULTS}
    else:
        from numba import cuda

        stream = cuda.stream()
        on_device = {name: cuda.to_device(a, stream=stream) for name, a in arrays.items()}
        stream.synchronize()
        device.launch(on_device, layout)
        res = {name: on_device[name].copy_to_host() for name in device.RESULTS}
    if layout == "soa":
        res = {name: from_soa(a, n) for name, a in res.items()}
    return res


def run_packed(packed: Sequence[Packed], layout: str = DEFAULT_LAYOUT,
               capacity: int | None = None) -> list[KernelRun]:
    """Run cases on the device; per case what ``simulation.run_kernel`` returns, with one
    NaN row for the time series (none is kept) and the batch's wall time shared out.
    ``layout``: "soa" (structure of arrays, :func:`batch_plan`'s capacities) or "aos" (case
    by case); ``capacity``: the launch capacity of every "soa" batch, of at most that many
    cases (a benchmark compiles the kernel of the capacity it times)."""
    if layout not in LAYOUTS:
        raise ValueError(f"device layout {layout!r}: expected one of {LAYOUTS}")
    device_name()
    out: list[KernelRun | None] = [None] * len(packed)
    by_shape: dict[tuple[int, ...], list[int]] = {}
    for i, pk in enumerate(packed):
        by_shape.setdefault(tuple(pk.map_shape), []).append(i)
    for shape, members in by_shape.items():
        rows = max(section_rows(packed[i]) for i in members)
        need = max(case_bytes(shape, int(packed[i].p[L.P_MAX_LEVEL]), rows) for i in members)
        fit = SIMULATOR_BATCH if simulated() else max(1, _device_budget() // need)
        cap = None
        if layout == "aos":
            size = fit
        elif capacity is not None:
            size, cap = min(fit, capacity), capacity
        else:
            size, cap = batch_plan(len(members), fit)
        for start in range(0, len(members), size):
            batch = members[start:start + size]
            began = time.perf_counter()
            res = _run_on_device(_allocate([packed[i] for i in batch], layout, cap), layout)
            wall = (time.perf_counter() - began) / len(batch)
            for k, i in enumerate(batch):
                # each case's arrays contiguous, as the CPU kernel's (a structure-of-arrays
                # batch gives strided views), one case at a time
                one = {name: np.ascontiguousarray(a[k]) for name, a in res.items()}
                out[i] = _raw(packed[i], one["wmap"], one["proj"], one["wvol"], one["info"],
                              one["stats"], one["track"], one["pairs"][PAIR_FIRST],
                              one["sec"][:section_rows(packed[i])], wall)
    return [r for r in out if r is not None]


def _raw(pk: Packed, wmap, proj, wvol, info, stats, track, first, sec, wall: float) -> KernelRun:
    """One case of a batch as a :class:`~clearsweep.simulation.KernelRun`: one NaN row for
    the series the device does not keep."""
    return KernelRun.from_counters(pk, info, track[L.T_RESIDUAL_MAX], track[L.T_KE_PEAK], first,
                                   wall, t=np.zeros(1), y=np.full((1, L.N_Y), np.nan), d=np.full((1, L.N_D), np.nan),
                                   wmax=np.full((1, L.N_JOINTS), np.nan), wmap=wmap, proj=proj, wvol=wvol,
                                   stats=stats, sec=sec)


def simulate_batch(configs: Sequence[Config]) -> list[Any]:
    """Simulate resolved configs on the device (budgets checked by the sweep plan); per
    config its dataset (``simulation.case_dataset``, no time series) or the exception that
    its packing raised."""
    from .simulation import case_dataset

    results: list[Any] = [None] * len(configs)
    ready: list[tuple[int, Packed]] = []
    for i, cfg in enumerate(configs):
        try:
            pk = pack(cfg, resolve_materials(cfg))
            check_step(cfg, pk)
        except Exception as exc:    # a failed case, not a failed batch
            results[i] = exc
            continue
        ready.append((i, pk))
    raws = run_packed([pk for _, pk in ready])
    for (i, pk), raw in zip(ready, raws):
        results[i] = case_dataset(configs[i], pk, raw)
    return results
