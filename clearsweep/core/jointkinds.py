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
``rk4`` and ``dopri5`` call these and name no joint and no type. A bushing stands
in for a table joint per case (``jointset.is_bushing``, ``dynamics.evaluate``), never as a
row's type: its mask is 0 and its branches fold away; it never has clearance, so that the
loops below (which test ``jointset.has_clearance``) pass it by.

A type touches its socket at one point (``CONTACTS`` 1: the kernel's one-point rules of
``rk4.accept_substep``, ``rk4.merge_wear``, ...) or at several (:data:`MULTI`: the type's own
``accept`` and ``deposit_step``, :func:`multi_free`; one such joint, :data:`MULTI_ROW`, as the
step's wear rows of ``layout`` hold one). A type that needs the ball's body
state (``accept``, ``seat``, ``penetration``) gets it from :func:`ball_body`, read from the
state vector at the ball's body's slots in ``joints.BODIES``.
"""

from . import bushing, prismatic, revolute, spherical
from .compiled import compiled
from .joints import BODIES, JOINT_TYPES, JOINTS, row_types
from .jointset import guide_axis, has_clearance
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
def is_revolute_on(g, j):
    """Whether row j is of the revolute type in a build whose slider's guide runs along
    global axis ``g`` (``jointset.guide_axis``: 1 the slider-crank's, :data:`SC_REVOLUTE`)."""
    return of_kind(SC_REVOLUTE if g == 1 else REVOLUTE, j)


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
def is_revolute(spec, j):
    """Whether row j is of the revolute type in a build of joint set ``spec``
    (``dynamics.evaluate`` chooses A's and B's contact by it)."""
    return is_revolute_on(guide_axis(spec), j)


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
def type_body(spec, j, y):
    """:func:`ball_body` in the frame joint j's type is written in: the ball's body as is,
    but for the planar slider-crank's guide (``jointset.guide_axis`` of the build's set
    ``spec`` 1, a constant of the build), whose block the prismatic type sees in its
    guide's frame (``prismatic.in_guide``). What ``rk4`` and ``dopri5`` hand to a type's
    ``accept``, ``seat`` and ``penetration``."""
    body = ball_body(j, y)
    if guide_axis(spec) == 1 and of_kind(PRISMATIC, j):
        return prismatic.in_guide(body)
    return body


@compiled(inline="always")
def type_vector(spec, j, v):
    """A socket-frame vector of joint j (an offset, a rate) in the frame its type is
    written in: as is, but for the planar slider-crank's guide (``prismatic.to_guide``),
    as :func:`type_body`."""
    if guide_axis(spec) == 1 and of_kind(PRISMATIC, j):
        return prismatic.to_guide(v)
    return v


# --------------------------------------------------------------- the protocol, by row type


@compiled(inline="always")
def paper_angle(spec, jp, j, pen, e):
    """``joints.PROTOCOL``'s ``paper_angle`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.paper_angle(jp, j, pen, e)
    if of_kind(revolute_rows(spec), j):
        return revolute.paper_angle(jp, j, pen, e)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.paper_angle(jp, j, pen, e)
    return bushing.paper_angle(jp, j, pen, e)


@compiled(inline="always")
def wear_surface(spec, jp, j, pen, e, n):
    """``joints.PROTOCOL``'s ``wear_surface`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.wear_surface(jp, j, pen, e, n)
    if of_kind(revolute_rows(spec), j):
        return revolute.wear_surface(jp, j, pen, e, n)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.wear_surface(jp, j, pen, e, n)
    return bushing.wear_surface(jp, j, pen, e, n)


@compiled(inline="always")
def cap_mergeable(spec, j, d2, tol, area, scale):
    """``joints.PROTOCOL``'s ``cap_mergeable`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.cap_mergeable(j, d2, tol, area, scale)
    if of_kind(revolute_rows(spec), j):
        return revolute.cap_mergeable(j, d2, tol, area, scale)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.cap_mergeable(j, d2, tol, area, scale)
    return bushing.cap_mergeable(j, d2, tol, area, scale)


@compiled(inline="always")
def deposit_cap(spec, wmap, j, n, vol, area, scale, scratch):
    """``joints.PROTOCOL``'s ``deposit_cap`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.deposit_cap(wmap, j, n, vol, area, scale, scratch)
    if of_kind(revolute_rows(spec), j):
        return revolute.deposit_cap(wmap, j, n, vol, area, scale, scratch)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.deposit_cap(wmap, j, n, vol, area, scale, scratch)
    return bushing.deposit_cap(wmap, j, n, vol, area, scale, scratch)


@compiled(inline="always")
def accept(spec, j, model, body, hs, in_settled, stats, cur):
    """``joints.PROTOCOL``'s ``accept`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.accept(j, model, body, hs, in_settled, stats, cur)
    if of_kind(revolute_rows(spec), j):
        return revolute.accept(j, model, body, hs, in_settled, stats, cur)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.accept(j, model, body, hs, in_settled, stats, cur)
    return bushing.accept(j, model, body, hs, in_settled, stats, cur)


@compiled(inline="always")
def deposit_step(spec, wmap, j, jp, cur, wvol):
    """``joints.PROTOCOL``'s ``deposit_step`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.deposit_step(wmap, j, jp, cur, wvol)
    if of_kind(revolute_rows(spec), j):
        return revolute.deposit_step(wmap, j, jp, cur, wvol)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.deposit_step(wmap, j, jp, cur, wvol)
    return bushing.deposit_step(wmap, j, jp, cur, wvol)


@compiled(inline="always")
def penetration(spec, j, model, k, body):
    """``joints.PROTOCOL``'s ``penetration`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.penetration(j, model, k, body)
    if of_kind(revolute_rows(spec), j):
        return revolute.penetration(j, model, k, body)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.penetration(j, model, k, body)
    return bushing.penetration(j, model, k, body)


@compiled(inline="always")
def section_offsets(spec, jp, j, d, rate):
    """``joints.PROTOCOL``'s ``section_offsets`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.section_offsets(jp, j, d, rate)
    if of_kind(revolute_rows(spec), j):
        return revolute.section_offsets(jp, j, d, rate)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.section_offsets(jp, j, d, rate)
    return bushing.section_offsets(jp, j, d, rate)


@compiled(inline="always")
def seat(spec, j, model, dg, body):
    """``joints.PROTOCOL``'s ``seat`` of joint j's type."""
    if of_kind(spherical_rows(spec), j):
        return spherical.seat(j, model, dg, body)
    if of_kind(revolute_rows(spec), j):
        return revolute.seat(j, model, dg, body)
    if of_kind(prismatic_rows(spec), j):
        return prismatic.seat(j, model, dg, body)
    return bushing.seat(j, model, dg, body)

