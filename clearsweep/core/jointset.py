"""The joint set a kernel build is compiled for: which joints of the table may have clearance.

A joint set is a bitmask over the rows of ``joints.JOINTS`` (bit j: joint j). The
integrators take it as their last argument and hand it down to every function that tests a
joint for clearance (``dynamics.evaluate``, ``rk4.advance``, ``rk4.accept_substep``,
``rk4.record_sample``, ``dopri5.advance_dopri5``, ...). The CPU entry points take it as a
compile-time constant (a :class:`Build` from ``simulation.run_kernel``, or an int made a
literal by ``numba.literally``): Numba compiles, and caches on disk, one build per set, the
set in the cached signature. The CUDA kernels close over it (``device.soa_kernel``,
``device.aos_kernel``). :func:`has_clearance` reads the bit before the case's packed flag
(``jp[j, J_CLEARANCE]``): where the bit is clear the test is a constant False, and LLVM
folds the joint's contact, its free coordinates and its wear away.

A joint set also says which joints may be elastic bushings (``core/bushing.py``): bit
``N_JOINTS + j`` (:data:`BUSHINGS`). A bushing frees the joint's coordinates as a clearance
does and takes the bushing's law in place of the type's contact; :func:`is_bushing` reads
that bit before the case's packed flag (``jp[j, J_BUSHING]``), so that a build without
bushings folds the test, and the bushing's code, away: the one place where the kernel
chooses a joint's law by its type. :func:`is_free` is either.

A build's set may hold joints that the case has not (an ideal joint in a build with its
bit set takes the ideal branch at run time, as every joint did before builds were
specialised), never fewer: :func:`check` refuses such a pair. A case's set is read from
its packed flags by :func:`of`; which build runs it is the host's choice
(``params.kernel_build``).
"""

from numba import types
from numba.extending import typeof_impl

from .compiled import compiled
from .joints import INDEX, JOINTS, N_JOINTS
from .layout import J_BUSHING, J_CLEARANCE, P_GUIDE

#: Every joint: the generic build, in which each joint's clearance is tested at run time.
ALL = (1 << N_JOINTS) - 1

#: Every joint as a bushing (bits N_JOINTS ...): a build's bushing bits.
BUSHINGS = ALL << N_JOINTS

#: Every joint with clearance or as a bushing: the largest build.
ANY = ALL | BUSHINGS

#: No joint with clearance: the ideal mechanism.
NONE = 0

#: The mechanism bit (bit 2 N_JOINTS): set for the planar slider-crank
#: (``mechanism.kind: slider_crank``, docs/mechanisms.md), whose slider's guide runs along
#: the global y axis, in the crank's plane; clear for the RSSP, whose guide runs along x.
#: The packed case says which (``p[P_GUIDE]``, :func:`of`); :func:`guide_axis` reads it from
#: a build's set, a constant of the build.
SLIDER_CRANK = 1 << (2 * N_JOINTS)

#: Every mechanism bit.
MECHANISMS = SLIDER_CRANK


class Build(int):
    """A joint set handed to an integrator from Python (``simulation.run_kernel``): Numba
    types it as the literal it holds, so that the dispatcher finds the set's build (compiled,
    or in the cache) at once. A plain int is typed int64 first and retried as a literal by
    ``numba.literally``, a type inference of the whole entry point at every call: about
    18 ms, a fifth of a 0.3 s case's run."""

    __slots__ = ()


@typeof_impl.register(Build)
def _typeof_build(val, c):
    return types.IntegerLiteral(int(val))


def of(jp, p=None) -> int:
    """The joint set of a packed case (its ``jp``, the flags that the kernel tests): bit j
    where ``jp[j, J_CLEARANCE]`` is not 0, bit N_JOINTS + j where ``jp[j, J_BUSHING]`` is
    not 0; and, from its ``p``, :data:`SLIDER_CRANK` where ``p[P_GUIDE]`` is 1 (the guide
    along y)."""
    mask = SLIDER_CRANK if p is not None and p[P_GUIDE] == 1.0 else 0
    for j in range(N_JOINTS):
        if jp[j, J_CLEARANCE] != 0.0:
            mask |= 1 << j
        if jp[j, J_BUSHING] != 0.0:
            mask |= 1 << (N_JOINTS + j)
    return mask


def named(*names: str) -> int:
    """The set of the joints named (``"A"``, ``"P"``: rows of the joint table; ``"O(bushing)"``:
    joint O as a bushing, as :func:`names` writes it)."""
    mask = 0
    for name in names:
        base, bushing = (name[:-len("(bushing)")], True) if name.endswith("(bushing)") else (name, False)
        if base not in INDEX:
            raise ValueError(f"no joint {name!r}: the joints are {', '.join(INDEX)}")
        mask |= 1 << (INDEX[base] + (N_JOINTS if bushing else 0))
    return mask


def names(mask: int) -> tuple[str, ...]:
    """The names of the joints in ``mask``, in the table's order; a bushing's followed by
    ``(bushing)``."""
    out = []
    for j, joint in enumerate(JOINTS):
        if mask >> j & 1:
            out.append(joint.name)
        if mask >> (N_JOINTS + j) & 1:
            out.append(f"{joint.name}(bushing)")
    return tuple(out)


def label(mask: int) -> str:
    """``mask`` in words: the joints' names joined by commas, or ``none``; followed by
    `` (slider-crank)`` for that mechanism's."""
    joints = ",".join(names(mask)) or "none"
    return f"{joints} (slider-crank)" if int(mask) & SLIDER_CRANK else joints


def check(case_set: int, build_set: int) -> None:
    """ValueError unless a build of ``build_set`` can run a case of ``case_set``: every
    joint with clearance in the case must be in the build (a build without it would treat
    the joint as ideal)."""
    if (int(case_set) ^ int(build_set)) & MECHANISMS:
        raise ValueError(f"a case of the {mechanism_name(case_set)} cannot run on the kernel "
                         f"built for the {mechanism_name(build_set)}")
    missing = int(case_set) & ~int(build_set)
    if missing or not 0 <= int(build_set) <= ANY | MECHANISMS:
        raise ValueError(f"a case with clearance at {label(case_set)} cannot run on the "
                         f"kernel built for {label(build_set)}")


def mechanism_name(mask: int) -> str:
    """The mechanism of a set in words: ``slider-crank`` or ``RSSP``."""
    return "slider-crank" if int(mask) & SLIDER_CRANK else "RSSP"


@compiled(inline="always")
def guide_axis(spec):
    """The global axis along which the slider's guide runs, a constant of the build: 0 (x,
    the RSSP) or 1 (y, the planar slider-crank: :data:`SLIDER_CRANK`)."""
    return (spec >> (2 * N_JOINTS)) & 1


@compiled(inline="always")
def has_clearance(spec, jp, j):
    """Whether joint j has clearance: in the build's joint set ``spec`` (a constant of the
    build: a clear bit folds the test, and what it guards, away) and in the case (``jp``)."""
    return (spec >> j) & 1 != 0 and jp[j, J_CLEARANCE] != 0.0


@compiled(inline="always")
def is_bushing(spec, jp, j):
    """Whether joint j is an elastic bushing: in the build's bushing bits (``spec``, a
    constant of the build: a clear bit folds the test away) and in the case (``jp``). The
    build's bushing bits are tested first as a whole, a constant whatever j is, so that a
    build without bushings folds the test away also where j is a loop's variable (the rate
    loop of ``dynamics.evaluate``: without it the device build of A and B kept the
    bushing's rate, 2.41 M characters of PTX against 2.19 M, ``python -m clearsweep.ptx``)."""
    return ((spec >> N_JOINTS) & ALL != 0 and (spec >> (N_JOINTS + j)) & 1 != 0
            and jp[j, J_BUSHING] != 0.0)


@compiled(inline="always")
def is_free(spec, jp, j):
    """Whether joint j's coordinates are free: a clearance joint or a bushing."""
    return has_clearance(spec, jp, j) or is_bushing(spec, jp, j)


def frees(jp, j: int) -> bool:
    """Host side: whether joint j of a packed case has free coordinates (clearance or a
    bushing)."""
    return bool(jp[j, J_CLEARANCE] != 0.0 or jp[j, J_BUSHING] != 0.0)
