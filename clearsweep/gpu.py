"""Cases in batches on a CUDA device: pack, copy, one thread per case, summaries back.

The device runs ``core.device.run_cases``, which calls the CPU kernel's own
``core.rk4.advance`` (one source of the physics for both targets). What comes back per
case is what the summaries need: the running statistics (layout.M_*), the wear map, the
projections, the worn volume, the counters and the energy residual; no time series (a
sweep runs the cases whose series it keeps on the CPU: ``sweeping.backends``).

Memory per case (:func:`case_bytes`), structure-of-arrays: the wear maps of the batch's
clearance joints alone, in the rows each type uses (8 * nazim bytes per map row: npolar
rows for the RSSP's A and B, 4 * (npolar // 4) for P's walls, one for a bearing: O and the
slider-crank's pins, :func:`map_rows`), 8,640 bytes of projections per joint of A, B
and O with clearance, an undo buffer of 64 * 2**level bytes per such joint (the level a
launch holds it for, :func:`launch_level`: :data:`UNDO_LEVEL`, where the cases' cap is
deeper; a case that needs more runs again with its cap's, :func:`run_packed`), the
parameters that differ across the batch (the others are one shared row), and about 8 kB
of other work arrays and results: 0.71 MB for the two-clearance case (A and B) on the
default map [144, 288] at level cap 8, 1.46 MB case by case. Cases are grouped by
:func:`batch_key` (the wear-map shape and the kernel build, ``params.build_of`` their
joints with clearance: one compiled kernel per joint set; sweep cases and ensemble members
share launches) and run in batches that fit the device's free memory, stored
structure-of-arrays (element e of case i at e * capacity + i) and padded to a launch
capacity (:data:`CAPACITIES`, :func:`batch_plan`): a batch takes capacity x case_bytes.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .config import Config, resolve_materials
from .core import jointset
from .core import layout as L
from .core.joints import INDEX, row_types
from .core.joints import JOINTS as JOINT_TABLE
from .core.rk4 import INT_WORK, PAIR_FIRST, work_shapes
from .jointtypes import kind
from .params import Packed, build_of, pack
from .simulation import KernelRun, check_step, section_rows

#: What a sweep or the CLI reports when no device is there.
NO_DEVICE = "no CUDA device: use --backend processes"

#: Share of the device's free memory that one batch may take.
DEVICE_MEMORY_FRACTION = 0.5

#: Share of the host's available memory (:func:`available_memory`) that one window of a
#: sweep's cases may take, their batch arrays and their results together
#: (:func:`host_batch_bytes`, :func:`host_case_bytes`). A batch must hold thousands of cases
#: to fill the device: on an H200, one launch of 1,470 cases ran 7.4e6 RK4 steps/s, of
#: 10,000 cases 1.71e7 (benchmarks/README.md, "CUDA backend").
HOST_MEMORY_FRACTION = 0.5

#: Host memory [bytes] a window may take where the machine does not say what it has
#: available (no /proc/meminfo, no sysconf): 16 GiB, the fixed bound of before.
HOST_BATCH_BYTES = 16 << 30

#: The environment variable that sets a window's host memory [bytes] in place of
#: :data:`HOST_MEMORY_FRACTION` of the available memory: a whole number of bytes, or one with
#: a suffix K, M, G or T (powers of 1024): ``CLEARSWEEP_HOST_MEMORY=64G``.
HOST_MEMORY_ENV = "CLEARSWEEP_HOST_MEMORY"
_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}

#: Where Linux says what memory is available, and a memory cgroup (v2, v1) its limit and use.
MEMINFO = "/proc/meminfo"
CGROUP_MEMORY = (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                 ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                  "/sys/fs/cgroup/memory/memory.usage_in_bytes"))

#: Sub-step level whose undo buffer a structure-of-arrays launch holds first
#: (:func:`launch_level`): a case that needs a deeper level stops before its attempt there
#: and runs again in a launch of the level it allows (:func:`run_packed`). The shipped
#: cases stay at level 2 or shallower at their settings (``configs/*.yaml``, 30 ms each on
#: the CPU kernel); the paper's preset at h = 1e-5 s reaches 4 within 0.2 ms. Level 4 holds
#: 16 sub-steps' rows, 1 kB per undone joint against 16 kB at the default cap of 8.
UNDO_LEVEL = 4

#: Cases per batch in numba's CUDA simulator (every thread is a Python thread).
SIMULATOR_BATCH = 64

#: The device layouts and launch capacities (``core.device``, which imports numba.cuda:
#: stated here too, so that planning a batch needs no CUDA import; tests check they agree).
LAYOUTS = ("soa", "aos", "soa-local", "soa-one-evaluate")
#: The work arrays the "soa-local" layout keeps in each thread's local memory
#: (``core.device.LOCAL_WORK``): the launch holds a placeholder for each.
LOCAL_WORK = ("vec", "diag", "cstate", "msave", "mats", "vz", "caps")
DEFAULT_LAYOUT = "soa"
CAPACITIES = (64, 1024, 4096, 16384, 32768)
#: Parameters of a case (p, then jp's rows) and entries of the joint layout ``geom``
#: (``core.device.N_PJ``, ``N_GEOM``: stated here for the same reason).
N_PJ = L.N_P + L.N_JOINTS * L.N_JP
N_GEOM = 5


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


#: Joints in the kernel's order (``core.joints.INDEX``): A, B, O, P.
JOINT_NAMES = tuple(sorted(INDEX, key=INDEX.__getitem__))

#: Rows of its map that a joint type uses where fewer than its ``map_rows`` (the CPU kernel's
#: map gives it npolar rows): the guide's walls are four bands of npolar // 4 rows each
#: (``prismatic.wall_bin``, ``wall_read``, ``deposit``), so that 4 * (npolar // 4) rows hold
#: them and a remainder of npolar % 4 rows is never touched.
USED_ROWS = {"prismatic": lambda npolar: 4 * (npolar // 4)}


def type_map_rows(type_name: str, npolar: int) -> int:
    """Rows of the wear map that a clearance joint of the type ``type_name`` takes in a
    structure-of-arrays batch of npolar polar bins: the rows its map uses (:data:`USED_ROWS`,
    else its type's ``map_rows``): a spherical socket's npolar, a bearing's one row of nazim
    bins (``revolute``), the guide's four wall bands."""
    return int(USED_ROWS.get(type_name, kind(type_name).map_rows)(int(npolar)))


#: Rows of the wear map that a clearance joint's map takes in a structure-of-arrays batch of
#: the RSSP, by joint, as a function of the map's polar bins (:func:`type_map_rows`; the
#: slider-crank's pins are bearings: :func:`map_rows`). A joint without clearance takes none.
MAP_ROWS = {joint.name: functools.partial(type_map_rows, joint.type) for joint in JOINT_TABLE}

#: Rows of N_ANGLE_BINS projection bins a clearance joint's projections take: three (x, y,
#: z) for O, A and B; none for P, whose wear the projections do not hold (``rk4.accept_substep``).
PROJ_ROWS = {joint.name: kind(joint.type).proj_rows for joint in JOINT_TABLE}


def map_rows(joints: Sequence[bool], npolar: int, slider_crank: bool = False) -> list[int]:
    """Per joint (the kernel's order) the wear-map rows a case of the clearance joints
    ``joints`` takes in a structure-of-arrays batch, by the joint's type in its mechanism
    (``core.joints.row_types``: the slider-crank's pins A and B are bearings, one row each)."""
    return [type_map_rows(t, npolar) if c else 0
            for t, c in zip(row_types(bool(slider_crank)), joints)]


def proj_rows(joints: Sequence[bool], slider_crank: bool = False) -> list[int]:
    """Per joint (the kernel's order) the projection rows a case of the clearance joints
    ``joints`` takes, by the joint's type in its mechanism."""
    return [int(kind(t).proj_rows) if c else 0 for t, c in zip(row_types(bool(slider_crank)), joints)]

#: Joints whose wear the undo buffer holds, one row per accepted sub-step (P's is not undone
#: row by row: ``rk4.accept_substep``).
UNDO_JOINTS = tuple(joint.name for joint in JOINT_TABLE if kind(joint.type).undo_rows)


def joint_rows(rows: Sequence[int]) -> tuple[int, int, int]:
    """(r0, dj, total): where joint j's rows[j] rows start in a structure-of-arrays array of
    ``total`` rows: row r0 + j * dj (``core.device.soa_joint_rows``), the joints with rows
    disjoint and within the array, total as small as one stride between joints allows. A
    joint of no rows (no clearance) gets none: its rows alias others' or lie outside the
    array (r0 may be negative), and the kernel never touches them."""
    return _joint_rows(tuple(int(r) for r in rows))


@functools.lru_cache(maxsize=256)
def _joint_rows(rows: tuple[int, ...]) -> tuple[int, int, int]:
    """:func:`joint_rows`, once per joint set and map shape (a sweep asks per case)."""
    present = [j for j, r in enumerate(rows) if r > 0]
    if not present:
        return 0, 0, 1
    if len(present) == 1:
        return 0, 0, int(rows[present[0]])
    best: tuple[int, int, int] | None = None
    reach = max(rows) * len(rows)
    for dj in range(-reach, reach + 1):
        if dj == 0:
            continue
        spans = sorted((j * dj, j * dj + int(rows[j])) for j in present)
        if any(a[1] > b[0] for a, b in zip(spans, spans[1:])):
            continue
        r0 = -spans[0][0]
        total = max(end for _, end in spans) + r0
        if best is None or total < best[2]:
            best = (r0, dj, total)
    assert best is not None     # dj = the largest rows count always fits
    return best


def clearance_joints(jp: np.ndarray) -> tuple[bool, ...]:
    """Per joint (the kernel's order) whether a case's jp row gives it clearance."""
    mask = jointset.of(jp)
    return tuple(bool(mask >> j & 1) for j in range(L.N_JOINTS))


def map_layout(joints: Sequence[bool], npolar: int,
               slider_crank: bool = False) -> dict[str, tuple[int, int, int]]:
    """The structure-of-arrays batch's joint layout for the clearance joints ``joints`` (per
    joint, the kernel's order) of the RSSP or the slider-crank: (r0, dj, total rows) of the
    wear map ("wmap": :func:`map_rows`) and of the projections ("proj"), :func:`joint_rows`."""
    return {"wmap": joint_rows(map_rows(joints, npolar, slider_crank)),
            "proj": joint_rows(proj_rows(joints, slider_crank))}


def undo_rows(joints: Sequence[bool], max_level: int) -> int:
    """Rows of the undo buffer for a case of the clearance joints ``joints`` whose attempts
    go no deeper than sub-step level max_level (the level a launch holds the buffer for,
    :func:`launch_level`): one per undone joint with clearance and sub-step of that level
    (one row at least: no zero-size array for the device)."""
    undone = sum(1 for n, c in zip(JOINT_NAMES, joints) if c and n in UNDO_JOINTS)
    return max(1, undone) * (1 << int(max_level))


def launch_level(max_level: int, undo_level: int | None = UNDO_LEVEL) -> int:
    """The sub-step level whose undo buffer a structure-of-arrays launch holds for cases that
    allow max_level at most: ``undo_level`` where that is shallower (:data:`UNDO_LEVEL` by
    default), else max_level (None: max_level, the full buffer)."""
    return int(max_level) if undo_level is None else min(int(max_level), int(undo_level))


ALL_JOINTS = (True,) * L.N_JOINTS


def case_bytes(map_shape: Sequence[int], max_level: int, sections: int = 0,
               joints: Sequence[bool] | None = None, shared: int = 0,
               slider_crank: bool = False) -> int:
    """Device memory [bytes] that one case of a batch takes (inputs, results, work);
    ``sections``: the Poincare section rows its batch holds. ``joints`` (per joint, the
    kernel's order: whether it has clearance): the structure-of-arrays layout, which holds
    maps and projections for the clearance joints alone (:func:`map_layout`), the undo
    buffer for their rows (:func:`undo_rows`), and of the parameters only the ``N_PJ -
    shared`` that differ across the batch; None: the case-by-case layout, every joint's map
    and every parameter per case. ``slider_crank``: the joints' types are the slider-crank's
    (its pins A and B bearings of one map row, :func:`map_rows`)."""
    npolar, nazim = int(map_shape[0]), int(map_shape[1])
    nj = L.N_JOINTS
    work = work_shapes(max_level, npolar)
    if joints is None:
        params = L.N_P + nj * L.N_JP
        maps = nj * npolar * nazim + nj * 3 * L.N_ANGLE_BINS
        undo = 2 * 4 * work["buf_i"][0]
    else:
        params = max(1, N_PJ - int(shared))
        lay = map_layout(joints, npolar, slider_crank)
        maps = lay["wmap"][2] * nazim + lay["proj"][2] * L.N_ANGLE_BINS
        undo = 2 * 4 * undo_rows(joints, max_level)
    items = (params + L.N_Y + 2                    # parameters, y0, n_steps, save_every
             + maps + nj                           # wmap, proj, wvol
             + L.N_INFO + L.N_WINDOWS * L.N_M + L.N_TRACK     # info, stats, track
             + sections * L.N_SEC                                # sec
             + 1 + L.N_Y + L.N_D + nj)             # row placeholders
    items += undo + sum(math.prod(s) for name, s in work.items() if name not in ("buf_i", "buf_v"))
    return 8 * items


def config_bytes(cfg: Config) -> int:
    """:func:`case_bytes` of a resolved config in the structure-of-arrays layout (its
    revolutions, one section each, rounded up; its clearance joints; every parameter per
    case, as a batch of it may hold; the undo buffer of the level a launch holds first,
    :func:`launch_level`)."""
    from .params import joint_configs

    sections = math.ceil(cfg.solver.duration * cfg.mechanism.speed_rpm / 60.0) + 1
    joints = tuple(joint.clearance > 0.0 for _, joint in joint_configs(cfg))
    return case_bytes(cfg.wear.map, launch_level(cfg.solver.max_substep_level), sections, joints,
                      slider_crank=cfg.mechanism.kind == "slider_crank")


def host_case_bytes(cfg: Config) -> int:
    """Host memory [bytes] one case of a sweep's window takes: its share of the batch arrays
    (:func:`config_bytes`) and its results, held until the window's parts are written: the
    wear map and the projections in the CPU kernel's shape, every joint's (a case's dataset:
    ``simulation.case_dataset``). Measured in the simulator: 2.06 MB per two-clearance case
    of the default map in a batch of 64 (its capacity), 0.71 MB of them the batch's."""
    npolar, nazim = (int(n) for n in cfg.wear.map)
    results = L.N_JOINTS * npolar * nazim + L.N_JOINTS * 3 * L.N_ANGLE_BINS
    return config_bytes(cfg) + 8 * results


def _cgroup_available() -> int | None:
    """What the process's memory cgroup leaves it [bytes] (v2: memory.max - memory.current;
    v1: memory.limit_in_bytes - memory.usage_in_bytes), None where it sets no limit."""
    for limit, usage in CGROUP_MEMORY:
        try:
            with open(limit) as f:
                text = f.read().strip()
            if text == "max":
                return None
            with open(usage) as f:
                used = int(f.read().strip())
            cap = int(text)
        except (OSError, ValueError):
            continue
        if cap >= 1 << 60:          # v1's "no limit"
            return None
        return max(0, cap - used)
    return None


def available_memory() -> int | None:
    """The host memory [bytes] available to new allocations: Linux's MemAvailable (free
    memory and the caches it can drop), or free pages where there is no /proc/meminfo, the
    less where a memory cgroup leaves less; None where the machine says neither."""
    import os

    available: int | None = None
    try:
        with open(MEMINFO) as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        available = None
    if available is None:
        try:
            available = int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
        except (ValueError, OSError, AttributeError):
            available = None
    group = _cgroup_available()
    if group is not None:
        available = group if available is None else min(available, group)
    return available


def host_memory_setting(text: str) -> int:
    """Bytes of a :data:`HOST_MEMORY_ENV` value: a whole number, or one with a suffix K, M,
    G or T (powers of 1024, an optional "iB" or "B" after it); ConfigError naming the
    variable otherwise."""
    from .config import ConfigError

    raw = text.strip()
    body = raw.upper().removesuffix("IB").removesuffix("B") if raw[-1:].isalpha() else raw
    unit = body[-1:] if body[-1:].isalpha() else ""
    digits = body[:-1] if unit else body
    if unit in _UNITS and digits.isascii() and digits.isdigit() and int(digits) > 0:
        return int(digits) * _UNITS[unit]
    raise ConfigError(HOST_MEMORY_ENV, text, "a whole number of bytes > 0, or one with K, M, G "
                      "or T (powers of 1024): 64G", "environment")


def host_batch_bytes() -> int:
    """Host memory [bytes] one window of a sweep's cases may take: :data:`HOST_MEMORY_ENV`
    where it is set, else :data:`HOST_MEMORY_FRACTION` of the memory available now
    (:func:`available_memory`), else :data:`HOST_BATCH_BYTES`."""
    import os

    given = os.environ.get(HOST_MEMORY_ENV)
    if given is not None and given.strip():
        return host_memory_setting(given)
    available = available_memory()
    if available is None:
        return HOST_BATCH_BYTES
    return max(int(HOST_MEMORY_FRACTION * available), 1)


def batch_window(configs: Sequence[Config]) -> int:
    """Cases per window that a sweep hands to :func:`simulate_batch`: as many as
    :func:`host_batch_bytes` holds at :func:`host_case_bytes` each, and no more than one
    launch of the largest capacity (a larger window fills no launch further, and holds more
    results before any part of it is written)."""
    if not configs:
        return 1
    per_case = max(host_case_bytes(c) for c in configs)
    return max(1, min(len(configs), CAPACITIES[-1], host_batch_bytes() // per_case))


def _device_budget() -> int:
    from numba import cuda

    free, _ = cuda.current_context().get_memory_info()
    return int(DEVICE_MEMORY_FRACTION * free)


def batch_joints(group: Sequence[Packed]) -> tuple[bool, ...]:
    """The clearance joints of a batch: per joint (the kernel's order), whether any of its
    cases gives it clearance (the batch's maps hold rows for these)."""
    flags = [clearance_joints(pk.jp) for pk in group]
    return tuple(any(f[j] for f in flags) for j in range(L.N_JOINTS))


def is_slider_crank(group: Sequence[Packed]) -> bool:
    """Whether a batch's cases are the slider-crank's (``jointset.SLIDER_CRANK``: one
    :func:`batch_key` holds one mechanism's cases)."""
    return bool(jointset.of(group[0].jp, group[0].p) & jointset.SLIDER_CRANK)


def parameter_rows(group: Sequence[Packed]) -> np.ndarray:
    """Each case's parameters as one row (n, N_PJ): p, then jp's rows."""
    return np.stack([np.concatenate([pk.p, pk.jp.reshape(-1)]) for pk in group])


def shared_columns(rows: np.ndarray) -> np.ndarray:
    """Which parameters (columns of :func:`parameter_rows`) a batch shares: equal to the bit
    in every case (0.0 and -0.0, or two NaNs of other bits, stay per case)."""
    bits = np.ascontiguousarray(rows).view(np.int64)
    return np.all(bits == bits[:1], axis=0)


def _shapes(group: Sequence[Packed], layout: str = "aos",
            level: int | None = None) -> dict[str, tuple[tuple[int, ...], Any, float]]:
    """Per-case shape, dtype and initial value of run_cases' arguments but the inputs p, jp,
    y0, n_steps, save_every, pcols and geom, by name (``core.device.ARGS``' order), for one
    batch of cases of one map shape: in the structure-of-arrays layout ("soa") the maps, the
    projections and the undo buffer hold the rows of the batch's clearance joints alone, the
    undo buffer those of sub-step level ``level`` (None: the deepest the cases allow)."""
    npolar, nazim = group[0].map_shape
    max_level = max(int(pk.p[L.P_MAX_LEVEL]) for pk in group)
    undo_level = max_level if level is None else int(level)
    wmap_rows: tuple[int, ...] = (L.N_JOINTS, npolar)
    proj_n: tuple[int, ...] = (L.N_JOINTS, 3)
    if layout != "aos":
        joints = batch_joints(group)
        lay = map_layout(joints, npolar, is_slider_crank(group))
        wmap_rows, proj_n = (lay["wmap"][2],), (lay["proj"][2],)
    shapes: dict[str, tuple[tuple[int, ...], Any, float]] = {
        "wmap": (wmap_rows + (nazim,), np.float64, 0.0),
        "proj": (proj_n + (L.N_ANGLE_BINS,), np.float64, 0.0),
        "wvol": ((L.N_JOINTS,), np.float64, 0.0), "info": ((L.N_INFO,), np.int64, 0),
        "stats": ((L.N_WINDOWS, L.N_M), np.float64, 0.0), "track": ((L.N_TRACK,), np.float64, 0.0),
        # one row at least: no zero-size array for the device
        "sec": ((max(1, max(section_rows(pk) for pk in group)), L.N_SEC), np.float64, np.nan)}
    for name, shape in work_shapes(max_level, npolar).items():
        if layout != "aos" and name in ("buf_i", "buf_v"):
            shape = (undo_rows(joints, undo_level), 4)
        if layout == "soa-local" and name in LOCAL_WORK:
            shape = (1,) * len(shape)       # not read: the thread's local arrays
        shapes[name] = (shape, np.int64 if name in INT_WORK else np.float64, 0)
    shapes.update(rows_t=((1,), np.float64, 0.0), rows_y=((1, L.N_Y), np.float64, 0.0),
                  rows_d=((1, L.N_D), np.float64, 0.0), rows_wmax=((1, L.N_JOINTS), np.float64, 0.0))
    return shapes


def _geom(group: Sequence[Packed]) -> np.ndarray:
    """The structure-of-arrays kernel's ``geom`` for a batch (``core.device.GEOM_*``): the
    map's polar bins, (r0, dj) of the maps and of the projections (:func:`map_layout`)."""
    npolar = group[0].map_shape[0]
    lay = map_layout(batch_joints(group), npolar, is_slider_crank(group))
    return np.array([npolar, lay["wmap"][0], lay["wmap"][1], lay["proj"][0], lay["proj"][1]],
                    dtype=np.int64)


def _allocate(group: Sequence[Packed], layout: str = "aos",
              capacity: int | None = None, level: int | None = None) -> dict[str, np.ndarray]:
    """Host arrays of run_cases' arguments, by name (``core.device.ARGS``), for one batch of
    cases of one map shape: with the case first ("aos"), or stored structure-of-arrays with
    the case last, padded to ``capacity`` cases ("soa": ``core.device.soa_kernel``; the
    smallest launch capacity that holds the batch by default). n_steps and save_every hold
    the batch's cases alone in either layout. In "soa" the parameters every case shares
    (:func:`shared_columns`) are one row (``jp``), the others per case (``p``: their
    columns, ``pcols``: each parameter's column there or -1), and the maps hold the batch's
    clearance joints' rows alone (``geom``: :func:`map_layout`). ``level`` ("soa" alone): the
    sub-step level the undo buffer holds (:func:`launch_level`), each case's level cap
    p[P_MAX_LEVEL] lowered to it where deeper, so that a case that needs a deeper level
    stops with status unstable_step before its attempt there (None: the cases' own caps, the
    buffer of the deepest)."""
    n = len(group)
    arrays: dict[str, np.ndarray] = {}
    if layout == "aos":
        arrays.update(p=np.stack([pk.p for pk in group]), jp=np.stack([pk.jp for pk in group]),
                      pcols=np.zeros(N_PJ, dtype=np.int64), geom=np.zeros(N_GEOM, dtype=np.int64))
        arrays["y0"] = np.stack([pk.y0 for pk in group])
    else:
        cap = capacity if capacity is not None else capacity_for(n)
        rows = parameter_rows(group)
        if level is not None:
            rows[:, L.P_MAX_LEVEL] = np.minimum(rows[:, L.P_MAX_LEVEL], float(level))
        shared = shared_columns(rows)
        varying = np.flatnonzero(~shared)
        pcols = np.full(N_PJ, -1, dtype=np.int64)
        pcols[varying] = np.arange(varying.size)
        per_case = rows[:, varying] if varying.size else np.zeros((n, 1))
        arrays.update(p=to_soa(per_case, cap), jp=np.where(shared, rows[0], 0.0), pcols=pcols,
                      geom=_geom(group), y0=to_soa(np.stack([pk.y0 for pk in group]), cap))
    arrays["n_steps"] = np.array([pk.n_steps for pk in group], dtype=np.int64)
    arrays["save_every"] = np.array([pk.save_every for pk in group], dtype=np.int64)
    for name, (shape, dtype, fill) in _shapes(group, layout, level).items():
        full = (n,) + shape if layout == "aos" else shape + (cap,)
        if layout == "soa-local" and name in LOCAL_WORK:
            full = shape + (1,)
        arrays[name] = np.full(full, fill, dtype=dtype) if fill != 0 else np.zeros(full, dtype=dtype)
    from .core.device import ARGS

    return {name: arrays[name] for name in ARGS}


def expand_joints(compact: np.ndarray, geom_r0: int, geom_dj: int, rows: Sequence[int],
                  nrows: int) -> np.ndarray:
    """One case's (N_JOINTS, nrows, ncols) array from its structure-of-arrays rows (rows,
    ncols) of the clearance joints alone (:func:`joint_rows`: joint j's rows[j] rows from row
    r0 + j * dj); zero where a joint has no rows, as the kernel leaves it."""
    out = np.zeros((L.N_JOINTS, nrows, compact.shape[-1]), dtype=compact.dtype)
    for j, r in enumerate(rows):
        if r > 0:
            first = geom_r0 + j * geom_dj
            out[j, :r] = compact[first:first + r]
    return out


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


def _run_on_device(arrays: dict[str, np.ndarray], layout: str = "aos", build: int = jointset.ALL,
                   case_sets: Sequence[int] = ()) -> dict[str, np.ndarray]:
    """Launch one batch on the kernel built for the joint set ``build`` (``case_sets``: its
    cases' sets, checked against it); the arrays it gives back (``core.device.RESULTS``:
    wmap, proj, wvol, info, stats, track and the work array ``pairs``, which holds the first
    impact times) on the host, by name, case first."""
    from .core import device

    n = arrays["n_steps"].shape[0]
    if simulated():
        device.launch(arrays, layout, build, case_sets)
        res = {name: arrays[name] for name in device.RESULTS}
    else:
        from numba import cuda

        stream = cuda.stream()
        on_device = {name: cuda.to_device(a, stream=stream) for name, a in arrays.items()}
        stream.synchronize()
        device.launch(on_device, layout, build, case_sets)
        res = {name: on_device[name].copy_to_host() for name in device.RESULTS}
    if layout != "aos":
        res = {name: from_soa(a, n) for name, a in res.items()}
    return res


def batch_key(pk: Packed) -> tuple[tuple[int, ...], int]:
    """What the cases of one launch must have in common: the wear map's shape and the
    kernel build (``params.build_of`` the case's joints with clearance, for the device).
    Anything else may differ within a launch (sweep cases and ensemble members alike):
    parameters the batch does not share are per case, the maps hold the rows of every joint
    that any case gives clearance, the undo buffer the rows of :func:`launch_level` of the
    deepest level any case allows (a case that needs more runs again, :func:`run_packed`)."""
    return tuple(pk.map_shape), build_of(jointset.of(pk.jp, pk.p), device=True)


def run_packed(packed: Sequence[Packed], layout: str = DEFAULT_LAYOUT,
               capacity: int | None = None, undo_level: int | None = UNDO_LEVEL) -> list[KernelRun]:
    """Run cases on the device; per case what ``simulation.run_kernel`` returns, with one
    NaN row for the time series (none is kept) and the batch's wall time shared out.
    ``layout``: "soa" (structure of arrays, :func:`batch_plan`'s capacities), "soa-local"
    (the same, the fixed-size work arrays in each thread's local memory,
    ``core.device.LOCAL_WORK``), "soa-one-evaluate" (the same as "soa", each step's
    evaluations at one call site, ``core.onestep``) or "aos" (case by case); ``capacity``: the launch capacity
    of every structure-of-arrays batch, of at most that many cases (a benchmark compiles
    the kernel of the capacity it times).

    ``undo_level`` (the structure-of-arrays layouts): the sub-step level whose undo buffer a
    launch holds first (:func:`launch_level`; None: the deepest level the cases allow, the
    full buffer). A case that needs a deeper level stops before its attempt there (its
    level cap lowered to the buffer's: status unstable_step) and runs again, with the other
    such cases of its group, in a launch of the full buffer: its results are that launch's
    (the kernel is deterministic), its wall time the sum of both."""
    if layout not in LAYOUTS:
        raise ValueError(f"device layout {layout!r}: expected one of {LAYOUTS}")
    device_name()
    out: list[KernelRun | None] = [None] * len(packed)
    groups: dict[tuple, list[int]] = {}
    for i, pk in enumerate(packed):
        groups.setdefault(batch_key(pk), []).append(i)
    for (shape, build), members in groups.items():
        first = None if layout == "aos" else undo_level
        runs = _run_group(packed, members, shape, build, layout, capacity, first)
        deeper = [i for i in members if first is not None and _needs_deeper(packed[i], runs[i], first)]
        if deeper:
            again = _run_group(packed, deeper, shape, build, layout, capacity, None)
            for i in deeper:
                runs[i] = dataclasses.replace(again[i], wall_time=again[i].wall_time + runs[i].wall_time)
        for i in members:
            out[i] = runs[i]
    return [r for r in out if r is not None]


def _needs_deeper(pk: Packed, run: KernelRun, level: int) -> bool:
    """Whether a case run with an undo buffer of sub-step level ``level`` stopped for want of
    a deeper one: status unstable_step, where its own cap allows deeper than the buffer (the
    launch lowered its cap to the buffer's level, :func:`_allocate`)."""
    return run.status == L.STATUS_NAMES[L.ST_UNSTABLE_STEP] and int(pk.p[L.P_MAX_LEVEL]) > level


def _run_group(packed: Sequence[Packed], members: Sequence[int], shape: tuple[int, ...],
               build: int, layout: str, capacity: int | None,
               undo_level: int | None) -> dict[int, KernelRun]:
    """:func:`run_packed` for the cases ``members`` of one :func:`batch_key` (``shape``,
    ``build``), in as many launches as the device's memory needs, the structure-of-arrays
    ones with the undo buffer of :func:`launch_level` (``undo_level``); per case its run."""
    runs: dict[int, KernelRun] = {}
    rows = max(section_rows(packed[i]) for i in members)
    allowed = max(int(packed[i].p[L.P_MAX_LEVEL]) for i in members)
    level = None if layout == "aos" else launch_level(allowed, undo_level)
    joints = None if layout == "aos" else batch_joints([packed[i] for i in members])
    need = case_bytes(shape, allowed if level is None else level, rows, joints,
                      slider_crank=is_slider_crank([packed[i] for i in members]))
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
        group = [packed[i] for i in batch]
        began = time.perf_counter()
        res = _run_on_device(_allocate(group, layout, cap, level), layout, build,
                             [jointset.of(pk.jp, pk.p) for pk in group])
        wall = (time.perf_counter() - began) / len(batch)
        if layout != "aos":
            joints, npolar, planar = batch_joints(group), shape[0], is_slider_crank(group)
            lay = map_layout(joints, npolar, planar)
            rows_map, rows_proj = map_rows(joints, npolar, planar), proj_rows(joints, planar)
        for k, i in enumerate(batch):
            # each case's arrays contiguous, as the CPU kernel's (a structure-of-arrays
            # batch gives strided views), one case at a time
            one = {name: np.ascontiguousarray(a[k]) for name, a in res.items()}
            if layout != "aos":
                one["wmap"] = expand_joints(one["wmap"], *lay["wmap"][:2], rows_map, npolar)
                one["proj"] = expand_joints(one["proj"], *lay["proj"][:2], rows_proj, 3)
            runs[i] = _raw(packed[i], one["wmap"], one["proj"], one["wvol"], one["info"],
                           one["stats"], one["track"], one["pairs"][PAIR_FIRST],
                           one["sec"][:section_rows(packed[i])], wall)
    return runs


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
