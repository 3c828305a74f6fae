"""CUDA batch kernel: one thread per case, running the CPU kernel's own :func:`rk4.advance`.

No physics is written here. Numba's CUDA target compiles a CPU ``@njit`` function that a
kernel calls as a device function (``CUDATypingContext.resolve_value_type`` turns the CPU
dispatcher into a device dispatcher of the same Python source), so :func:`run_cases`
reaches ``advance``, ``evaluate``, the contact law and the wear map through the very
functions that ``rk4.integrate`` runs on the CPU. Where a function holds one rule in a
CPU arrangement and a register-lean one, ``target.on_device`` picks the latter here
(registered for the CUDA target below).

Every array argument carries the case as its first axis; thread i integrates case i on
its own slices: inputs (p, jp, y0, n_steps, save_every), results (wmap, proj, wvol,
info, stats, track) and the work arrays of ``rk4.work_shapes``. No rows are saved on
the device (``keep_rows`` False): the summaries are the kernel's running statistics, the
wear map and projections.

Slices whose shape is fixed by the kernel's layout (every work row but the undo buffer and
the wear scratch, and jp, proj, stats) are handed to advance by :func:`block`, as arrays
of a compile-time shape at a constant offset from their case's start: their addresses are
then one base per argument plus constants, rather than a pointer and row lengths per row
that stay live in registers across every inlined ``evaluate``. :func:`launch` checks the
shapes.

The structure-of-arrays kernel (:func:`soa_kernel`) takes what its batch shares once: the
parameters equal in every case as one row, the others per case, gathered by each thread
into its local memory at its start; and the wear maps and projections of the batch's
clearance joints alone, each joint's rows at r0 + j * dj of one array
(:func:`soa_joint_rows`, the layout ``gpu.joint_rows`` chooses and ``geom`` carries).

Importing this module imports ``numba.cuda``; with ``NUMBA_ENABLE_CUDASIM=1`` (read when
numba is first imported) the kernel runs in numba's CUDA simulator, where each thread is a
Python thread: the simulator hands kernels wrapped arrays, which :func:`_advance` unwraps
there. ``advance`` then runs compiled for the CPU, unless ``NUMBA_DISABLE_JIT=1`` is set
too, when it runs as the Python source that the CUDA compiler sees (tests/test_gpu.py).
The build for a device is checked without one by ``python -m clearsweep.ptx``.
"""

import inspect
import math
import os

import numba
from numba import cuda, types

from .dynamics import NZ, VZ_ROWS
from .jointset import ALL, check
from .layout import (
    N_ANGLE_BINS,
    N_CAP,
    N_CAP_ROWS,
    N_D,
    N_INFO,
    N_JOINTS,
    N_JP,
    N_M,
    N_P,
    N_S,
    N_SEC,
    N_TRACK,
    N_WINDOWS,
    N_Y,
)
from .numba_compat import simulator_array
from .onestep import advance_one_call as _cpu_advance_one
from .rk4 import (
    CAP_ROWS,
    CSTATE_ROWS,
    DIAG_ROWS,
    MAT_ROWS,
    PAIR_FIRST,
    VEC_ROWS,
    work_shapes,
    zero_rows,
)
from .rk4 import advance as _cpu_advance
from .target import on_device
from .work import Case, Out, Rk4Work

SIMULATED = bool(numba.config.ENABLE_CUDASIM)

#: ``CLEARSWEEP_CUDA_CACHE=1``: the kernels are kept in Numba's on-disk cache (the folder of
#: ``numba_compat.cache_dir``), so that processes after the first load the build of each
#: layout and capacity instead of compiling it (benchmarks/device_suite.py builds them in
#: parallel processes first). Off by default: tried on a device by that script alone.
CACHE_KERNELS = os.environ.get("CLEARSWEEP_CUDA_CACHE") == "1" and not SIMULATED

#: ``CLEARSWEEP_CUDA_CARVEOUT``: the kernels' preferred split of each multiprocessor's L1
#: and shared memory (numba-cuda's ``shared_memory_carveout``: ``maxl1``, ``maxshared``,
#: ``default`` or a percentage of shared memory). The kernel uses no shared memory, so
#: ``maxl1`` gives the threads' spills and local arrays the most L1 (issue 43 item 6: to time
#: against the driver's default, benchmarks/device_suite.py). Unset: the driver's choice.
CARVEOUT = None if SIMULATED else os.environ.get("CLEARSWEEP_CUDA_CARVEOUT") or None
_options: dict = {}
if CACHE_KERNELS:
    _options["cache"] = True
if CARVEOUT is not None:
    _options["shared_memory_carveout"] = int(CARVEOUT) if CARVEOUT.isdigit() else CARVEOUT
_jit = cuda.jit(**_options) if _options else cuda.jit

#: Threads per block. The kernel is register- and local-memory-heavy (the right-hand side
#: keeps its 3-vectors and 3x3 matrices in registers): small blocks keep occupancy even.
THREADS_PER_BLOCK = 64

#: row of the work array ``pairs`` holding the copy of the first impact times
PAIR_FIRST_COPY = PAIR_FIRST + 1

#: Parameters of a case in the structure-of-arrays kernel: p's N_P values, then jp's rows.
N_PJ = N_P + N_JOINTS * N_JP

#: Entries of the structure-of-arrays kernel's ``geom`` (``gpu.joint_rows``): the wear map's
#: polar bins, then (first row, rows from one joint to the next) of the maps and of the
#: projections.
GEOM_NPOLAR, GEOM_MAP_R0, GEOM_MAP_DJ, GEOM_PROJ_R0, GEOM_PROJ_DJ = range(5)
N_GEOM = 5


def block_typer(typingctx, arr, i, k, shape):
    """Typing and code generation of :func:`block` for ``numba.extending.intrinsic`` (any
    target: the CUDA one here; tests/test_ptx.py registers it for the CPU to check the
    addressing against numpy): k and the entries of shape must be literal integers, arr a
    C-contiguous array."""
    if not (isinstance(arr, types.Array) and arr.layout == "C"
            and isinstance(k, types.IntegerLiteral) and isinstance(shape, types.BaseTuple)
            and len(shape) > 0 and all(isinstance(n, types.IntegerLiteral) for n in shape)):
        return None     # numba retries with literal arguments
    dims = tuple(n.literal_value for n in shape)
    start = k.literal_value * math.prod(dims)
    out = types.Array(arr.dtype, len(dims), "C")

    def codegen(context, builder, sig, args):
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        intp = context.get_value_type(types.intp)
        itemsize = context.get_abi_sizeof(context.get_data_type(arr.dtype))
        case = args[1]
        if case.type != intp:
            case = builder.sext(case, intp)
        offset = builder.add(builder.mul(case, builder.extract_value(ary.strides, 0)),
                             intp(start * itemsize))
        byte_ptr = context.get_value_type(types.voidptr)
        data = builder.bitcast(builder.gep(builder.bitcast(ary.data, byte_ptr), [offset]),
                               ary.data.type)
        strides = []
        step = itemsize
        for n in reversed(dims):
            strides.insert(0, intp(step))
            step *= n
        res = context.make_array(out)(context, builder)
        context.populate_array(res, data=data, shape=[intp(n) for n in dims], strides=strides,
                               itemsize=intp(itemsize), meminfo=None, parent=None)
        return res._getvalue()

    return out(arr, i, k, shape), codegen


def soa_block_typer(typingctx, arr, i, k, shape, cap):
    """Typing and code generation of :func:`soa_block` for ``numba.extending.intrinsic`` (the
    CUDA target; tests/test_ptx.py registers it for the CPU too): arr a C-contiguous array
    whose last axis is the case, of length ``cap`` (a literal integer: the launch capacity);
    k a literal integer; the entries of shape integers, literal where the kernel's layout
    fixes them (then every address is one base per argument plus constants), or read at run
    time (the wear map's bins, the undo buffer's rows). The view is an 'A'-layout array:
    strides of cap elements and its multiples."""
    if not (isinstance(arr, types.Array) and arr.layout == "C"
            and isinstance(k, types.IntegerLiteral) and isinstance(cap, types.IntegerLiteral)
            and isinstance(shape, types.BaseTuple) and len(shape) > 0
            and all(isinstance(n, types.Integer) for n in shape)):
        return None     # numba retries with literal arguments
    ndim = len(shape)
    literal = [n.literal_value if isinstance(n, types.IntegerLiteral) else None for n in shape]
    capacity = cap.literal_value
    out = types.Array(arr.dtype, ndim, "A")

    def codegen(context, builder, sig, args):
        from numba.core import cgutils

        ary = context.make_array(sig.args[0])(context, builder, args[0])
        intp = context.get_value_type(types.intp)
        itemsize = context.get_abi_sizeof(context.get_data_type(arr.dtype))
        values = cgutils.unpack_tuple(builder, args[3], ndim)
        dims = []
        for lit, val, ty in zip(literal, values, sig.args[3]):
            if lit is not None:
                dims.append(intp(lit))
            else:
                dims.append(context.cast(builder, val, ty, types.intp))
        case = context.cast(builder, args[1], sig.args[1], types.intp)
        size = intp(1)
        for d in dims:
            size = builder.mul(size, d)
        # element (k block, e, case) at (k * size + e) * cap + case
        first = builder.add(builder.mul(builder.mul(intp(k.literal_value), size),
                                        intp(capacity)), case)
        offset = builder.mul(first, intp(itemsize))
        byte_ptr = context.get_value_type(types.voidptr)
        data = builder.bitcast(builder.gep(builder.bitcast(ary.data, byte_ptr), [offset]),
                               ary.data.type)
        strides = []
        step = intp(capacity * itemsize)
        for d in reversed(dims):
            strides.insert(0, step)
            step = builder.mul(step, d)
        res = context.make_array(out)(context, builder)
        context.populate_array(res, data=data, shape=dims, strides=strides,
                               itemsize=intp(itemsize), meminfo=None, parent=None)
        return res._getvalue()

    return out(arr, i, k, shape, cap), codegen


def soa_joint_rows_typer(typingctx, arr, i, r0, dj, nrows, cap):
    """Typing and code generation of :func:`soa_joint_rows` for ``numba.extending.intrinsic``:
    arr a C-contiguous (rows, ncols, cap) array stored structure-of-arrays (the case last, of
    the literal length cap); the view (N_JOINTS, nrows, ncols) whose joint j, row r is arr's
    row r0 + j * dj + r (r0, dj and nrows integers read at run time: the batch's joint
    layout, ``gpu.joint_rows``). Joints without clearance get no rows of their own: their
    rows alias others' and are never touched."""
    if not (isinstance(arr, types.Array) and arr.layout == "C" and arr.ndim == 3
            and isinstance(cap, types.IntegerLiteral)
            and all(isinstance(x, types.Integer) for x in (r0, dj, nrows))):
        return None
    capacity = cap.literal_value
    out = types.Array(arr.dtype, 3, "A")

    def codegen(context, builder, sig, args):
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        intp = context.get_value_type(types.intp)
        itemsize = context.get_abi_sizeof(context.get_data_type(arr.dtype))
        case = context.cast(builder, args[1], sig.args[1], types.intp)
        row0 = context.cast(builder, args[2], sig.args[2], types.intp)
        jstep = context.cast(builder, args[3], sig.args[3], types.intp)
        rows = context.cast(builder, args[4], sig.args[4], types.intp)
        ncols = builder.extract_value(ary.shape, 1)
        row_stride = builder.mul(ncols, intp(capacity * itemsize))
        # element (row R, column c, case) at (R * ncols + c) * cap + case
        offset = builder.add(builder.mul(row0, row_stride), builder.mul(case, intp(itemsize)))
        byte_ptr = context.get_value_type(types.voidptr)
        data = builder.bitcast(builder.gep(builder.bitcast(ary.data, byte_ptr), [offset]),
                               ary.data.type)
        strides = [builder.mul(jstep, row_stride), row_stride, intp(capacity * itemsize)]
        res = context.make_array(out)(context, builder)
        context.populate_array(res, data=data, shape=[intp(N_JOINTS), rows, ncols],
                               strides=strides, itemsize=intp(itemsize), meminfo=None,
                               parent=None)
        return res._getvalue()

    return out(arr, i, r0, dj, nrows, cap), codegen


if SIMULATED:
    _plain = simulator_array

    def _unwrap(a):
        """The plain arrays of a simulator array or of a named tuple of them."""
        if isinstance(a, tuple):
            return type(a)(*(_plain(x) for x in a))
        return _plain(a)

    def _advance(*args):
        return _cpu_advance(*(_unwrap(a) for a in args))

    def _advance_one(*args):
        return _cpu_advance_one(*(_unwrap(a) for a in args))

    def block(arr, i, k, shape):
        """Block k, of shape ``shape``, of case i's part of arr, as a view: case i's
        elements k * prod(shape) to (k + 1) * prod(shape), in C order."""
        size = math.prod(shape)
        return _plain(arr[i]).reshape(-1)[k * size:(k + 1) * size].reshape(shape)

    def soa_block(arr, i, k, shape, cap):
        """Block k, of shape ``shape``, of case i's part of arr stored structure-of-arrays
        (the case last, ``cap`` of them), as a strided view: its elements e at
        (k * prod(shape) + e) * cap + i."""
        size = math.prod(shape)
        column = _plain(arr).reshape(-1, cap)[k * size:(k + 1) * size, i]
        view = column.view()
        view.shape = tuple(shape)       # a view or an error, never a copy
        return view

    def soa_joint_rows(arr, i, r0, dj, nrows, cap):
        """Case i's (N_JOINTS, nrows, ncols) view of the structure-of-arrays arr (rows,
        ncols, cap): joint j, row r at arr's row r0 + j * dj + r (the batch's joint layout)."""
        import numpy as np

        a = _plain(arr)
        ncols = a.shape[1]
        item = a.itemsize
        # the view's first element may lie outside a (r0 < 0: a joint without clearance),
        # as on the device: numpy's own views cannot start there
        return np.asarray(_Strided(a, a.ctypes.data + (int(r0) * ncols * cap + i) * item,
                                   (N_JOINTS, int(nrows), ncols),
                                   (int(dj) * ncols * cap * item, ncols * cap * item,
                                    cap * item)))

    class _Strided:
        """A strided view of ``owner``'s memory from the address ``data`` (kept alive by the
        array numpy makes of it)."""

        def __init__(self, owner, data, shape, strides):
            self.owner = owner
            self.__array_interface__ = {"shape": shape, "typestr": owner.dtype.str,
                                        "data": (data, False), "strides": strides,
                                        "version": 3}
else:
    from numba.cuda.extending import intrinsic, overload

    @overload(on_device, inline="always")
    def _on_device_cuda():
        """The device build: True, a constant (core/target.py)."""
        return lambda: True

    #: Block k, of the literal shape ``shape``, of case i's part of the C-contiguous arr:
    #: case i's elements k * prod(shape) to (k + 1) * prod(shape), in C order, as an array
    #: of that shape known to the compiler.
    block = intrinsic(block_typer)
    #: Block k, of the shape ``shape``, of case i's part of the C-contiguous arr stored
    #: structure-of-arrays, its last axis the case (of the literal length cap): element e of
    #: the block at (k * prod(shape) + e) * cap + i, as a strided ('A' layout) array.
    soa_block = intrinsic(soa_block_typer)
    #: Case i's (N_JOINTS, nrows, ncols) view of a (rows, ncols, cap) array stored
    #: structure-of-arrays: joint j, row r at the array's row r0 + j * dj + r.
    soa_joint_rows = intrinsic(soa_joint_rows_typer)
    _advance = _cpu_advance
    _advance_one = _cpu_advance_one


#: The case-by-case ("aos") kernels built so far, by joint set (:func:`aos_kernel`).
_AOS_KERNELS: dict = {}


def aos_kernel(spec: int = ALL):
    """:func:`run_cases` built for the joint set ``spec`` (``core.jointset``; ``params.build_of``
    its cases' sets), once per set and process: ``spec`` is a constant of its closure, which
    Numba compiles as a literal, so that advance and everything it calls are built for that
    set (the joints outside it folded away)."""
    spec = int(spec)
    if spec in _AOS_KERNELS:
        return _AOS_KERNELS[spec]

    def run_cases(p, jp, y0, n_steps, save_every, wmap, proj, wvol, info, stats, track, sec, vec,
                  diag, cstate, msave, pairs, mats, vz, buf_i, buf_v, caps, scratch, rows_t, rows_y,
                  rows_d, rows_wmax, pcols, geom):
        """Integrate case i = thread index from t = 0 (see :func:`rk4.advance`); the grouped work
        arrays of ``rk4.work_shapes`` are handed to advance row by row; ``rows_*`` are
        placeholders (one row per case) that ``keep_rows = False`` leaves untouched; ``pcols``
        and ``geom`` are the structure-of-arrays kernel's (:func:`soa_kernel`): unused here.
        Built for the joint set ``spec`` of :func:`aos_kernel`."""
        i = cuda.grid(1)
        if i < p.shape[0]:
            case = Case(p[i], block(jp, i, 0, (N_JOINTS, N_JP)), y0[i], wmap[i],
                        block(proj, i, 0, (N_JOINTS, 3, N_ANGLE_BINS)), wvol[i])
            out = Out(rows_t[i], rows_y[i], rows_d[i], rows_wmax[i], info[i],
                      block(stats, i, 0, (N_WINDOWS, N_M)), track[i], block(pairs, i, PAIR_FIRST, (N_JOINTS,)),
                      sec[i])
            work = Rk4Work(block(vec, i, 0, (N_Y,)), block(vec, i, 1, (N_Y,)),
                           block(vec, i, 2, (N_Y,)), block(vec, i, 3, (N_Y,)),
                           block(vec, i, 4, (N_Y,)), block(vec, i, 5, (N_Y,)),
                           block(vec, i, 6, (N_Y,)),
                           block(diag, i, 0, (N_D,)), block(diag, i, 1, (N_D,)),
                           block(cstate, i, 0, (N_JOINTS, N_S)),
                           block(cstate, i, 1, (N_JOINTS, N_S)),
                           block(msave, i, 0, (N_WINDOWS, N_M)),
                           block(pairs, i, 0, (N_JOINTS,)), block(pairs, i, 1, (N_JOINTS,)),
                           block(pairs, i, 2, (N_JOINTS,)),
                           block(pairs, i, PAIR_FIRST_COPY, (N_JOINTS,)),
                           block(mats, i, 0, (NZ, NZ)), block(mats, i, 1, (NZ, NZ)),
                           block(mats, i, 2, (NZ, NZ)), block(vz, i, 0, (VZ_ROWS, NZ)),
                           buf_i[i], buf_v[i], block(caps, i, 0, (N_CAP_ROWS, N_CAP)),
                           block(caps, i, 1, (N_CAP_ROWS, N_CAP)), scratch[i],
                           block(vec, i, 7, (N_Y,)), block(diag, i, 2, (N_D,)),
                           block(vec, i, 8, (N_Y,)), block(vec, i, 9, (N_Y,)))
            _advance(case, 0.0, n_steps[i], save_every[i], False, out, work, spec)

    _AOS_KERNELS[spec] = _jit(run_cases)
    return _AOS_KERNELS[spec]


#: The generic case-by-case kernel, every joint's clearance tested at run time.
run_cases = aos_kernel(ALL)


#: The launch capacities of the structure-of-arrays kernel (:func:`soa_kernel`): a batch of
#: n cases is stored for the smallest capacity that holds it (its arrays padded to that many
#: cases), so that a sweep compiles the kernel for one or two capacities, each once per
#: process. The capacity is a compile-time constant of the kernel: with a run-time batch
#: size the strides of every per-case view stay live in registers, and sm_90's spill stores
#: grew from 3,100 to 15,984 bytes (issue 43); as a constant they are folded into the
#: addresses (benchmarks/README.md, "CUDA backend": the figures of each layout).
CAPACITIES = (64, 1024, 4096, 16384, 32768)

#: The device layouts: "soa" (structure of arrays, the default: element e of case i at
#: e * capacity + i, so that a warp's 32 threads read 32 consecutive words) and "aos" (array
#: of structures, case by case: :func:`run_cases`, kept to measure one against the other);
#: two arrangements of "soa" to time against it: "soa-local" (:data:`LOCAL_WORK`) and
#: "soa-one-evaluate" (``onestep.advance_one_call``: one ``evaluate`` call site per step).
LAYOUTS = ("soa", "aos", "soa-local", "soa-one-evaluate")
DEFAULT_LAYOUT = "soa"


def capacity_for(n: int) -> int:
    """The smallest launch capacity (:data:`CAPACITIES`) that holds n cases; ValueError past
    the largest."""
    for cap in CAPACITIES:
        if n <= cap:
            return cap
    raise ValueError(f"{n} cases exceed the largest launch capacity {CAPACITIES[-1]}")


_SOA_KERNELS: dict = {}

#: The work arrays that the "soa-local" layout keeps in each thread's local memory rather
#: than in the batch's global arrays (``rk4.work_shapes``' groups of a fixed size: every one
#: but the undo buffer and the wear scratch, whose sizes the batch decides, and ``pairs``,
#: whose row PAIR_FIRST is a result). The hardware interleaves local memory thread by
#: thread, so a warp's accesses to it coalesce as the structure-of-arrays layout's do; the
#: launch's global arrays of these names are then placeholders of one element per axis.
LOCAL_WORK = ("vec", "diag", "cstate", "msave", "mats", "vz", "caps")


def soa_kernel(capacity: int, spec: int = ALL, local: bool = False, one_evaluate: bool = False):
    """:func:`run_cases` over arrays stored structure-of-arrays for ``capacity`` cases (one
    of :data:`CAPACITIES`), built for the joint set ``spec`` (as :func:`aos_kernel`) once per
    capacity, set, arrangement and process: the same arguments, each per-case array of shape
    (per-case shape..., capacity) with the case as its last axis; n_steps and save_every
    hold the batch's n cases (threads past n do nothing). ``local`` (the "soa-local"
    layout): the work arrays of :data:`LOCAL_WORK` are each thread's local arrays, and the
    launch's arrays of those names are not read. ``one_evaluate`` (the "soa-one-evaluate"
    layout): each step evaluates the right-hand side from one call site
    (``onestep.advance_one_call``), where ``rk4.advance`` has three."""
    if capacity not in CAPACITIES:
        raise ValueError(f"launch capacity {capacity}: expected one of {CAPACITIES}")
    spec = int(spec)
    local = bool(local)
    one = bool(one_evaluate)
    key = (capacity, spec, local, one)
    if key in _SOA_KERNELS:
        return _SOA_KERNELS[key]
    cap = capacity      # a constant of the kernel (a closure variable), as the joint set

    @_jit
    def run_cases_soa(p, jp, y0, n_steps, save_every, wmap, proj, wvol, info, stats, track,
                      sec, vec, diag, cstate, msave, pairs, mats, vz, buf_i, buf_v, caps,
                      scratch, rows_t, rows_y, rows_d, rows_wmax, pcols, geom):
        """run_cases, structure of arrays (:func:`soa_block`). The parameters: ``jp`` the
        batch's shared row (p then jp's rows, N_PJ values), ``p`` the per-case columns
        (columns x capacity) and ``pcols`` the column of each parameter in p, -1 where the
        shared row holds it; each thread gathers its p and jp into its local memory once.
        The maps: ``wmap`` (rows, nazim, capacity) and ``proj`` (rows, N_ANGLE_BINS,
        capacity) hold rows for the batch's clearance joints alone, placed by ``geom``
        (:data:`GEOM`: ``gpu.joint_rows``)."""
        i = cuda.grid(1)
        if i < n_steps.shape[0]:
            pl = cuda.local.array(N_P, numba.float64)
            jl = cuda.local.array((N_JOINTS, N_JP), numba.float64)
            for k in range(N_P):
                c = pcols[k]
                pl[k] = p[c, i] if c >= 0 else jp[k]
            for j in range(N_JOINTS):
                for m in range(N_JP):
                    k = N_P + j * N_JP + m
                    c = pcols[k]
                    jl[j, m] = p[c, i] if c >= 0 else jp[k]
            npolar = geom[GEOM_NPOLAR]
            nbuf = buf_i.shape[0]
            case = Case(pl, jl, soa_block(y0, i, 0, (N_Y,), cap),
                        soa_joint_rows(wmap, i, geom[GEOM_MAP_R0], geom[GEOM_MAP_DJ], npolar, cap),
                        soa_joint_rows(proj, i, geom[GEOM_PROJ_R0], geom[GEOM_PROJ_DJ], 3, cap),
                        soa_block(wvol, i, 0, (N_JOINTS,), cap))
            out = Out(soa_block(rows_t, i, 0, (1,), cap), soa_block(rows_y, i, 0, (1, N_Y), cap),
                      soa_block(rows_d, i, 0, (1, N_D), cap),
                      soa_block(rows_wmax, i, 0, (1, N_JOINTS), cap),
                      soa_block(info, i, 0, (N_INFO,), cap),
                      soa_block(stats, i, 0, (N_WINDOWS, N_M), cap),
                      soa_block(track, i, 0, (N_TRACK,), cap),
                      soa_block(pairs, i, PAIR_FIRST, (N_JOINTS,), cap),
                      soa_block(sec, i, 0, (sec.shape[0], N_SEC), cap))
            if local:
                # LOCAL_WORK in the thread's local memory (a constant of the build: the
                # branch not taken is pruned before typing)
                lv = cuda.local.array((VEC_ROWS, N_Y), numba.float64)
                ld = cuda.local.array((DIAG_ROWS, N_D), numba.float64)
                ls = cuda.local.array((CSTATE_ROWS, N_JOINTS, N_S), numba.float64)
                lm = cuda.local.array((N_WINDOWS, N_M), numba.float64)
                lc = cuda.local.array((MAT_ROWS, NZ, NZ), numba.float64)
                lz = cuda.local.array((VZ_ROWS, NZ), numba.float64)
                lk = cuda.local.array((CAP_ROWS, N_CAP_ROWS, N_CAP), numba.float64)
                # zeroed, as the host's arrays are (the CPU kernel's rk4.zero_rows)
                for a in (lv, ld, lm, lz):
                    zero_rows(a)
                for a in (ls, lc, lk):
                    for r in range(a.shape[0]):
                        zero_rows(a[r])
                work = Rk4Work(lv[0], lv[1], lv[2], lv[3], lv[4], lv[5], lv[6], ld[0], ld[1],
                               ls[0], ls[1], lm, soa_block(pairs, i, 0, (N_JOINTS,), cap),
                               soa_block(pairs, i, 1, (N_JOINTS,), cap),
                               soa_block(pairs, i, 2, (N_JOINTS,), cap),
                               soa_block(pairs, i, PAIR_FIRST_COPY, (N_JOINTS,), cap),
                               lc[0], lc[1], lc[2], lz,
                               soa_block(buf_i, i, 0, (nbuf, 4), cap),
                               soa_block(buf_v, i, 0, (nbuf, 4), cap), lk[0], lk[1],
                               soa_block(scratch, i, 0, (scratch.shape[0], 3), cap),
                               lv[7], ld[2], lv[8], lv[9])
                if one:
                    _advance_one(case, 0.0, n_steps[i], save_every[i], False, out, work, spec)
                    return
                _advance(case, 0.0, n_steps[i], save_every[i], False, out, work, spec)
                return
            work = Rk4Work(soa_block(vec, i, 0, (N_Y,), cap), soa_block(vec, i, 1, (N_Y,), cap),
                           soa_block(vec, i, 2, (N_Y,), cap), soa_block(vec, i, 3, (N_Y,), cap),
                           soa_block(vec, i, 4, (N_Y,), cap), soa_block(vec, i, 5, (N_Y,), cap),
                           soa_block(vec, i, 6, (N_Y,), cap),
                           soa_block(diag, i, 0, (N_D,), cap), soa_block(diag, i, 1, (N_D,), cap),
                           soa_block(cstate, i, 0, (N_JOINTS, N_S), cap),
                           soa_block(cstate, i, 1, (N_JOINTS, N_S), cap),
                           soa_block(msave, i, 0, (N_WINDOWS, N_M), cap),
                           soa_block(pairs, i, 0, (N_JOINTS,), cap),
                           soa_block(pairs, i, 1, (N_JOINTS,), cap),
                           soa_block(pairs, i, 2, (N_JOINTS,), cap),
                           soa_block(pairs, i, PAIR_FIRST_COPY, (N_JOINTS,), cap),
                           soa_block(mats, i, 0, (NZ, NZ), cap), soa_block(mats, i, 1, (NZ, NZ), cap),
                           soa_block(mats, i, 2, (NZ, NZ), cap),
                           soa_block(vz, i, 0, (VZ_ROWS, NZ), cap),
                           soa_block(buf_i, i, 0, (nbuf, 4), cap),
                           soa_block(buf_v, i, 0, (nbuf, 4), cap),
                           soa_block(caps, i, 0, (N_CAP_ROWS, N_CAP), cap),
                           soa_block(caps, i, 1, (N_CAP_ROWS, N_CAP), cap),
                           soa_block(scratch, i, 0, (scratch.shape[0], 3), cap),
                           soa_block(vec, i, 7, (N_Y,), cap), soa_block(diag, i, 2, (N_D,), cap),
                           soa_block(vec, i, 8, (N_Y,), cap), soa_block(vec, i, 9, (N_Y,), cap))
            if one:
                # the step with one evaluate call site (a constant of the build, as local)
                _advance_one(case, 0.0, n_steps[i], save_every[i], False, out, work, spec)
                return
            _advance(case, 0.0, n_steps[i], save_every[i], False, out, work, spec)

    _SOA_KERNELS[key] = run_cases_soa
    return run_cases_soa


#: run_cases' arguments by name, in launch order (inputs, results, the work arrays of
#: ``rk4.work_shapes``, the row placeholders): :func:`launch` takes them by name.
ARGS = tuple(inspect.signature(run_cases.py_func).parameters)

#: The arguments that hold what a batch gives back: the results (``sec``: the Poincare
#: sections, revolutions x layout.N_SEC per case, as many rows as the batch's longest run
#: needs), and the work array
#: ``pairs`` (its row PAIR_FIRST holds the first impact times).
RESULTS = ("wmap", "proj", "wvol", "info", "stats", "track", "sec", "pairs")

#: Per-case shapes that run_cases' :func:`block` calls take for granted, by argument name:
#: jp, proj, stats and the work arrays but buf_i, buf_v and scratch.
FIXED_SHAPES = {"jp": (N_JOINTS, N_JP), "proj": (N_JOINTS, 3, N_ANGLE_BINS),
                "stats": (N_WINDOWS, N_M)}
FIXED_SHAPES.update({name: shape for name, shape in work_shapes(0, 1).items()
                     if name not in ("buf_i", "buf_v", "scratch")})

#: The arguments that hold one value per case, n of them in either layout (no capacity).
PER_CASE_SCALARS = ("n_steps", "save_every")

#: The structure-of-arrays kernel's arguments that hold one row for the whole batch, and
#: their shapes: the shared parameter row (``jp``), each parameter's per-case column
#: (``pcols``) and the joint layout of the maps (``geom``).
BATCH_ROWS = {"jp": (N_PJ,), "pcols": (N_PJ,), "geom": (N_GEOM,)}

#: The structure-of-arrays kernel's arguments whose per-case shape the batch decides: the
#: per-case parameter columns and the maps' rows of the batch's clearance joints.
SOA_FREE = ("p", "wmap", "proj")


def launch(arrays: dict, layout: str = "aos", spec: int = ALL, case_sets=()) -> None:
    """Run the kernel of ``layout`` built for the joint set ``spec`` over every case of
    ``arrays`` (its arguments by name, device or host arrays) and wait for it to finish:
    "aos", :func:`aos_kernel` over arrays with the case first; "soa", :func:`soa_kernel`
    over arrays with the case last (every argument's last axis the launch capacity, n_steps
    and save_every the n cases run). ValueError if one of ``case_sets`` (the cases' joint
    sets, ``jointset.of``) has a joint with clearance outside ``spec``, if an argument is
    missing or unknown, or if its per-case shape is not the one the kernel addresses it by
    (FIXED_SHAPES), or a capacity not one of CAPACITIES."""
    for case_set in case_sets:
        check(case_set, spec)
    if layout not in LAYOUTS:
        raise ValueError(f"device layout {layout!r}: expected one of {LAYOUTS}")
    if set(arrays) != set(ARGS):
        raise ValueError(f"run_cases arguments: missing {sorted(set(ARGS) - set(arrays))}, "
                         f"unknown {sorted(set(arrays) - set(ARGS))}")
    n = arrays["n_steps"].shape[0]
    if layout == "aos":
        for name, shape in FIXED_SHAPES.items():
            if tuple(arrays[name].shape[1:]) != shape:
                raise ValueError(f"run_cases argument {name}: per-case shape "
                                 f"{arrays[name].shape[1:]}, expected {shape}")
        kernel = aos_kernel(spec)
    else:
        cap = arrays["p"].shape[-1]
        for name in ARGS:
            if name in PER_CASE_SCALARS or (layout == "soa-local" and name in LOCAL_WORK):
                continue
            if name in BATCH_ROWS:
                if tuple(arrays[name].shape) != BATCH_ROWS[name]:
                    raise ValueError(f"run_cases argument {name}: shape {arrays[name].shape}, "
                                     f"expected {BATCH_ROWS[name]}")
                continue
            if arrays[name].shape[-1] != cap:
                raise ValueError(f"run_cases argument {name}: capacity {arrays[name].shape[-1]}, "
                                 f"expected {cap} (p's)")
            shape = None if name in SOA_FREE else FIXED_SHAPES.get(name)
            if shape is not None and tuple(arrays[name].shape[:-1]) != shape:
                raise ValueError(f"run_cases argument {name}: per-case shape "
                                 f"{arrays[name].shape[:-1]}, expected {shape}")
        if n > cap:
            raise ValueError(f"{n} cases exceed the arrays' capacity {cap}")
        kernel = soa_kernel(cap, spec, local=layout == "soa-local",
                            one_evaluate=layout == "soa-one-evaluate")
    blocks = (n + THREADS_PER_BLOCK - 1) // THREADS_PER_BLOCK
    kernel[blocks, THREADS_PER_BLOCK](*(arrays[name] for name in ARGS))
    cuda.synchronize()
