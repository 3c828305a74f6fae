"""The kernel's one switch on a joint's type: each function of the joint-type protocol
(``joints.PROTOCOL``) dispatched on the type of joint row j in the joint table
(docs/architecture.md, "Joint types").

Each registered type's rows of ``joints.JOINTS`` are a bitmask (:data:`SPHERICAL`,
:data:`REVOLUTE`, :data:`PRISMATIC`, :data:`BUSHING`: bit j, joint j), read when the kernel
is imported and frozen into it as compile-time constants; the planar slider-crank's rows
(``joints.SLIDER_CRANK_TYPES``: its pins A and B revolute) are masks of their own
(:data:`SC_SPHERICAL`, :data:`SC_REVOLUTE`, ...). :func:`spherical_rows`,
:func:`revolute_rows` and :func:`prismatic_rows` pick a build's from its joint set ``spec``
(``jointset.guide_axis``, a constant of the build), and :func:`of_kind` tests row j against
one (a shift and a mask, which LLVM folds where j is known): an RSSP build's dispatch is the
table's, its code as before. Every dispatcher here takes the build's joint set and then the
protocol function's own parameters, and calls the type module's function of the same name;
one factory makes them all (:func:`dispatcher`, from ``joints.PROTOCOL`` and
:data:`MODULES`: one test per distinct function, the types that take the same function of
``shared`` tested together); ``rk4`` and ``dopri5`` call these and name no joint and no
type. ``dynamics`` applies the joints' contacts through them, calling no type's contact by
name: a one-point row's through :func:`contact`, the multi-contact row's through
:data:`multi_contact`, turned into the frame its type is written in and back
(:func:`in_type_frame`, :func:`from_type_frame`). A bushing stands in for a table joint
per case (``jointset.is_bushing``), never as a row's type: its mask is 0 and its branches
fold away; :func:`contact` tests for it before the row's type (``dynamics.applied_loads``
applies A's, B's and O's contact through it); it never has clearance, so that the loops
below (which test ``jointset.has_clearance``) pass it by.

A type touches its socket at one point (``CONTACTS`` 1: the kernel's one-point rules of
``rk4.accept_substep``, ``rk4.merge_wear``, ...) or at several (:data:`MULTI`: the type's own
``accept`` and ``deposit_step``, :func:`multi_free`; one such joint, :data:`MULTI_ROW`, as the
step's wear rows of ``layout`` hold one). A type that needs the ball's body
state (``accept``, ``seat``, ``penetration``) gets it from :func:`ball_body`, read from the
state vector at the ball's body's slots in ``joints.BODIES``.
"""

from . import bushing, prismatic, revolute, spherical
from .compiled import compiled
from .joints import BODIES, JOINT_TYPES, JOINTS, PROTOCOL, row_types
from .jointset import guide_axis, has_clearance, is_bushing
from .kinematics import gmat, mv, rotation, trig
from .layout import Y_QD

#: The type modules by type name (``joints.JOINT_TYPES``' modules).
MODULES = {"spherical": spherical, "revolute": revolute, "prismatic": prismatic,
           "bushing": bushing}
if set(MODULES) != set(JOINT_TYPES):
    raise ImportError(f"jointkinds dispatches {sorted(MODULES)}, the registered joint types "
                      f"are {sorted(JOINT_TYPES)}")


def rows_of(type_name: str, slider_crank: bool = False) -> int:
    """The rows of one type, a bitmask (bit j: joint j): the joint table's (the RSSP's), or
    with ``slider_crank`` the planar slider-crank's (``joints.row_types``)."""
    return sum(1 << j for j, kind in enumerate(row_types(slider_crank)) if kind == type_name)


SPHERICAL = rows_of("spherical")
REVOLUTE = rows_of("revolute")
PRISMATIC = rows_of("prismatic")
#: 0: a bushing is never a row's type (it stands in per case)
BUSHING = rows_of("bushing")

#: The slider-crank's rows of each type (``joints.SLIDER_CRANK_TYPES``: its pins A and B
#: revolute), which a build of that mechanism (``jointset.guide_axis`` 1) dispatches on.
SC_SPHERICAL = rows_of("spherical", True)
SC_REVOLUTE = rows_of("revolute", True)
SC_PRISMATIC = rows_of("prismatic", True)
if any(MODULES[kind].CONTACTS > 1 for kind in set(row_types(True)) - set(row_types(False))):
    raise ImportError("the slider-crank's own types must touch at one point: MULTI and "
                      "MULTI_ROW are the joint table's")

#: The rows whose type touches at several points (its module's ``CONTACTS`` > 1), a bitmask.
MULTI = sum(1 << j for j, joint in enumerate(JOINTS) if MODULES[joint.type].CONTACTS > 1)
if MULTI & (MULTI - 1):
    raise ImportError("the step's wear rows (layout.CAP_SLOT_ROW ...) hold one multi-contact "
                      "joint's edge lines; the joint table has several such joints")
#: The multi-contact row (-1: none), a compile-time constant: the kernel hands it to its
#: type's functions as a constant, so that their indices into jp, s and the maps fold (a
#: device build inlines them whole).
MULTI_ROW = MULTI.bit_length() - 1


def _ball_slots(joint):
    """State slots (centroid, Euler angles) of the body that carries the joint's ball; -1
    for the ground (no state)."""
    body = {b.name: b for b in BODIES}[joint.ball.body]
    return (-1, -1) if body.y_r is None else (body.y_r, body.y_phi)


#: Each row's ball body: where its centroid and its Euler angles start in the state vector.
BALL_R = tuple(_ball_slots(joint)[0] for joint in JOINTS)
BALL_PHI = tuple(_ball_slots(joint)[1] for joint in JOINTS)

_EYE = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


@compiled(inline="always")
def of_kind(rows, j):
    """Whether row j is one of ``rows`` (a type's bitmask: :data:`SPHERICAL`, ...)."""
    return (rows >> j) & 1 != 0


@compiled(inline="always")
def spherical_rows(spec):
    """The rows of the spherical type in a build of joint set ``spec`` (a constant of the
    build: the slider-crank's, :data:`SC_SPHERICAL`, where ``jointset.guide_axis`` is 1)."""
    return SC_SPHERICAL if guide_axis(spec) == 1 else SPHERICAL


@compiled(inline="always")
def revolute_rows(spec):
    """The rows of the revolute type in a build of joint set ``spec`` (the slider-crank's
    O, A and B: :data:`SC_REVOLUTE`)."""
    return SC_REVOLUTE if guide_axis(spec) == 1 else REVOLUTE


@compiled(inline="always")
def prismatic_rows(spec):
    """The rows of the prismatic type in a build of joint set ``spec``."""
    return SC_PRISMATIC if guide_axis(spec) == 1 else PRISMATIC


@compiled(inline="always")
def is_multi(j):
    """Whether joint j's type touches at several points (:data:`MULTI`)."""
    return of_kind(MULTI, j)


@compiled(inline="always")
def multi_free(spec, jp):
    """Whether the multi-contact joint (:data:`MULTI_ROW`) has clearance in this case
    (``spec``: the build's joint set): its ``accept`` and ``deposit_step`` have work to
    do."""
    return MULTI_ROW >= 0 and has_clearance(spec, jp, MULTI_ROW)


@compiled(inline="always")
def contacts(spec, j):
    """Contact points of joint j's type (its module's ``CONTACTS``)."""
    if of_kind(spherical_rows(spec), j):
        return spherical.CONTACTS
    if of_kind(revolute_rows(spec), j):
        return revolute.CONTACTS
    if of_kind(prismatic_rows(spec), j):
        return prismatic.CONTACTS
    return bushing.CONTACTS


@compiled(inline="always")
def ball_body(j, y):
    """(r, v, R, w) of the body that carries joint j's ball at state y: its centroid's
    position and velocity, its rotation and its body angular velocity (the ground's: at
    rest at the origin, unrotated)."""
    r_at = BALL_R[j]
    phi_at = BALL_PHI[j]
    if r_at < 0:
        zero = (0.0, 0.0, 0.0)
        return zero, zero, _EYE, zero
    tr = trig(y[phi_at], y[phi_at + 1], y[phi_at + 2])
    pd = (y[Y_QD + phi_at], y[Y_QD + phi_at + 1], y[Y_QD + phi_at + 2])
    return ((y[r_at], y[r_at + 1], y[r_at + 2]),
            (y[Y_QD + r_at], y[Y_QD + r_at + 1], y[Y_QD + r_at + 2]),
            rotation(tr), mv(gmat(tr), pd))


@compiled(inline="always")
def turns_frame(spec, j):
    """Whether joint j's type is written in another frame than the mechanism's: only the
    planar slider-crank's guide (``jointset.guide_axis`` of the build's set ``spec`` 1, a
    constant of the build), along global y, which the prismatic type sees in its guide's
    frame (``prismatic.PLANAR_GUIDE``, along x)."""
    return guide_axis(spec) == 1 and of_kind(PRISMATIC, j)


@compiled(inline="always")
def in_type_frame(spec, j, body):
    """A body state (r, v, R, w) (global; R its rotation, w its body angular velocity) in
    the frame joint j's type is written in: as is, but where :func:`turns_frame`
    (``prismatic.in_guide``)."""
    if turns_frame(spec, j):
        return prismatic.in_guide(body)
    return body


@compiled(inline="always")
def type_vector(spec, j, v):
    """A socket-frame vector of joint j (an offset, a rate) in the frame its type is
    written in: as is, but where :func:`turns_frame` (``prismatic.to_guide``)."""
    if turns_frame(spec, j):
        return prismatic.to_guide(v)
    return v


@compiled(inline="always")
def from_type_frame(spec, j, v):
    """A vector of the frame joint j's type is written in (a force, a contact normal; a
    moment about the block's centroid in its body frame) back in global axes (in the
    body's frame): the inverse of :func:`type_vector`, as is but where :func:`turns_frame`
    (``prismatic.from_guide``)."""
    if turns_frame(spec, j):
        return prismatic.from_guide(v)
    return v


@compiled(inline="always")
def type_body(spec, j, y):
    """:func:`ball_body` in the frame joint j's type is written in (:func:`in_type_frame`):
    what ``rk4`` and ``dopri5`` hand to a type's ``accept``, ``seat`` and
    ``penetration``."""
    return in_type_frame(spec, j, ball_body(j, y))


# --------------------------------------------------------------- the protocol, by row type


#: The rows of each type in a build of joint set ``spec``, by type name: the functions
#: above (the bushing's rows: :data:`BUSHING`, none).
ROWS_OF = {"spherical": "spherical_rows", "revolute": "revolute_rows",
           "prismatic": "prismatic_rows", "bushing": "bushing_rows"}
if set(ROWS_OF) != set(MODULES):
    raise ImportError(f"jointkinds reads the rows of {sorted(ROWS_OF)}, the registered joint "
                      f"types are {sorted(MODULES)}")


@compiled(inline="always")
def bushing_rows(spec):
    """The rows of the bushing type: none (:data:`BUSHING`, 0; a bushing stands in per case,
    ``jointset.is_bushing``)."""
    return BUSHING


def parameter_list(name: str) -> str:
    """Protocol function ``name``'s parameters (``joints.PROTOCOL``) as a call's argument
    list: ``"jp, j, pen, e"``."""
    return ", ".join(next(fn for fn in PROTOCOL if fn.name == name).params)


def compiled_from_source(source: str, name: str, scope: dict, doc: str, label: str | None = None):
    """Function ``name`` of the Python ``source`` (a dispatcher written here), run in this
    module's globals and ``scope`` (the functions it calls), given the docstring ``doc``
    (and the name ``label``, by which Numba names its cache file) and compiled like every
    kernel function (``@compiled``, inlined); its code object is named for this file, so
    that Numba caches its callers as it does any function of this module."""
    namespace = dict(globals(), **scope)
    exec(compile(source, __file__, "exec"), namespace)
    func = namespace[name]
    if label is not None:
        func.__name__ = func.__qualname__ = label
    func.__doc__ = doc
    return compiled(inline="always")(func)


def dispatch_source(name: str, kinds_of: tuple[str, ...] = tuple(MODULES)) -> tuple[str, dict]:
    """The source of the dispatcher of protocol function ``name`` (``joints.PROTOCOL``) and
    the names it calls: ``name(spec, <the protocol's parameters>)`` tests row j against the
    rows of each distinct function the types ``kinds_of`` (every registered type) provide
    for it (the types that take the same function, ``shared``'s, tested together as one
    mask: ``of_kind`` of the masks' union), and calls it with the protocol's parameters;
    the bushing's function (no row's type) is the fall-through, a row of no type's as
    before, or without the bushing among ``kinds_of`` the last type's."""
    params = parameter_list(name)
    groups: list[tuple[object, list[str]]] = []
    for kind in kinds_of:
        func = getattr(MODULES[kind], name)
        for known, kinds in groups:
            if known is func:
                kinds.append(kind)
                break
        else:
            groups.append((func, [kind]))
    last = next((i for i, (_, kinds) in enumerate(groups) if "bushing" in kinds),
                len(groups) - 1)
    scope = {}
    lines = [f"def {name}(spec, {params}):"]
    for i, (func, kinds) in enumerate(groups):
        scope[f"{name}_{i}"] = func
        if i != last:
            rows = " | ".join(f"{ROWS_OF[kind]}(spec)" for kind in kinds)
            lines += [f"    if of_kind({rows}, j):", f"        return {name}_{i}({params})"]
    lines.append(f"    return {name}_{last}({params})")
    return "\n".join(lines) + "\n", scope


def dispatcher(name: str, label: str | None = None, kinds_of: tuple[str, ...] = tuple(MODULES)):
    """The compiled dispatcher of protocol function ``name`` (:func:`dispatch_source`):
    ``joints.PROTOCOL``'s ``name`` of joint j's type, given the build's joint set first.
    Compiled from its source like every kernel function (``@compiled``, inlined: the masks
    are constants of the build, so that LLVM folds each test where j is known, as it does
    the hand-written chains it replaces; :func:`compiled_from_source`). ``label``: its
    name (Numba names its cache file by it), ``name`` by default."""
    source, scope = dispatch_source(name, kinds_of)
    return compiled_from_source(
        source, name, scope,
        f"``joints.PROTOCOL``'s ``{name}`` of joint j's type (:func:`dispatcher`).",
        label or name)


elastic_law = dispatcher("elastic_law")
paper_angle = dispatcher("paper_angle")
wear_surface = dispatcher("wear_surface")
cap_mergeable = dispatcher("cap_mergeable")
deposit_cap = dispatcher("deposit_cap")
accept = dispatcher("accept")
deposit_step = dispatcher("deposit_step")
penetration = dispatcher("penetration")
section_offsets = dispatcher("section_offsets")
seat = dispatcher("seat")

#: The types that touch at one point (their module's ``CONTACTS`` 1), whose joints'
#: contact :func:`contact` applies.
ONE_POINT = tuple(kind for kind, module in MODULES.items() if module.CONTACTS == 1)


def per_case(name: str, kinds_of: tuple[str, ...] = tuple(MODULES)):
    """The compiled dispatcher of protocol function ``name`` for joint j as the case has it:
    the bushing's where the case makes j a bushing (``jointset.is_bushing``: a constant
    False in a build without bushings), else its row's type's (:func:`dispatcher` of the
    types ``kinds_of``, named ``row_<name>``). Every function it serves takes ``model``
    (the bushing's test reads ``model.jp``)."""
    row = dispatcher(name, f"row_{name}", kinds_of)
    params = parameter_list(name)
    source = (f"def {name}(spec, {params}):\n"
              f"    if is_bushing(spec, model.jp, j):\n"
              f"        return bushing_{name}({params})\n"
              f"    return row_{name}(spec, {params})\n")
    scope = {"is_bushing": is_bushing, f"row_{name}": row, f"bushing_{name}": getattr(bushing, name)}
    return compiled_from_source(
        source, name, scope,
        f"``joints.PROTOCOL``'s ``{name}`` of joint j as the case has it: the bushing's or "
        f"its row's type's (:func:`per_case`).")


#: The types that touch at several points (their module's ``CONTACTS`` > 1: the prismatic
#: type's block), whose joint's (:data:`MULTI_ROW`) contact :func:`multi_contact` applies.
MULTI_TYPES = tuple(kind for kind, module in MODULES.items() if module.CONTACTS > 1)

#: ``joints.PROTOCOL``'s ``contact`` of a row of a multi-contact type (:data:`MULTI_TYPES`):
#: ``dynamics.free_slider`` applies the guide's block through it, in the frame its type is
#: written in (:func:`in_type_frame`, :func:`from_type_frame`), naming no type.
multi_contact = dispatcher("contact", "multi_contact", MULTI_TYPES)


#: ``joints.PROTOCOL``'s ``contact`` of joint j, a row of a one-point type (:data:`ONE_POINT`)
#: or a bushing (:func:`per_case`): a multi-contact type's contact is not among its
#: branches, so that a call site typed with a one-point joint's bodies compiles none of it
#: (the guide's block's is :data:`multi_contact`, which ``dynamics.free_slider`` calls).
#: ``dynamics.applied_loads`` applies A's, B's and O's contact through it, naming no type.
contact = per_case("contact", ONE_POINT)
#: ``joints.PROTOCOL``'s ``rate_point`` and ``force_rate`` of joint j (:func:`per_case`):
#: the step's stiff rate of each joint with clearance or a bushing
#: (``dynamics.end_diagnostics``), naming no type.
rate_point = per_case("rate_point")
force_rate = per_case("force_rate")
