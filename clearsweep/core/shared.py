"""The joint-type protocol's functions that several types share, written once (docs/
architecture.md, "Joint types").

A type module provides every function of ``joints.PROTOCOL``; where its function is one
that another type has too, it takes this module's by name (``accept =
shared.neutral_accept``) rather than compiling a copy of its own. tests/test_joints.py
checks that every provided function is compiled in the type's module or here, with the
protocol's parameters and the length of what it returns, and that no function body is
written twice.

- ``neutral_<name>``: the neutral value of a protocol function that a type has nothing
  to do in (``joints.PROTOCOL`` names it): the slip angle of a type that does not follow
  the paper's slip rule, the wear caps of a type that does not wear by caps, the
  multi-contact steps of a one-point type, and the contact episodes and section offsets
  of a type that never touches (the bushing);
- ``case_elastic_law``: the case's elastic law (``p[P_EXPONENT]``), a ball's and the
  law of a type that has no one-point force (never read there);
- ``one_point_<name>``: what the one-point types (a ball, a journal: ``CONTACTS`` 1)
  share: the seated start's episode (``contact.seat_episode``) and the section offsets
  over the radial clearance (``contact.offsets_over``).

A function here is compiled once whatever the types that take it (one Numba dispatcher),
and ``jointkinds`` dispatches a protocol function to each distinct one once.
"""

import math

from .compiled import compiled
from .contact import offsets_over, seat_episode
from .layout import J_C, P_EXPONENT

# ------------------------------------------------------------------------ neutral values


@compiled(inline="always")
def case_elastic_law(p, j):
    """The case's elastic law (``contact.elastic``: ``p[P_EXPONENT]``, 0 the paper's): a
    ball's; a type without a one-point force law (the guide's lines, a bushing) names it and
    never reads it."""
    return p[P_EXPONENT]


@compiled(inline="always")
def neutral_paper_angle(jp, j, pen, e):
    """(pi, False): the type does not follow the paper's slip rule (a bearing, whose
    sliding distance is the slip times the step; a multi-contact type, whose wear is its
    ``accept``'s; a type that never touches)."""
    return math.pi, False


@compiled(inline="always")
def neutral_wear_surface(jp, j, pen, e, n):
    """Zeros: no one-point wear surface (a multi-contact type's wear is its ``accept``'s; a
    bushing does not wear)."""
    return 0.0, 0.0, 0.0, 0.0, 0.0


@compiled(inline="always")
def neutral_cap_mergeable(j, d2, tol, area, scale):
    """False: no wear caps (the guide's wear waits per edge line; a bushing does not
    wear)."""
    return False


@compiled(inline="always")
def neutral_deposit_cap(wmap, j, n, vol, area, scale, scratch):
    """0: no wear caps to deposit."""
    return 0.0


@compiled(inline="always")
def neutral_accept(j, model, body, hs, in_settled, stats, cur):
    """False: nothing of the type's own in an accepted step (a one-point type's step is
    the kernel's one-point rule, ``rk4.accept_substep``; a bushing has no contact
    episodes)."""
    return False


@compiled(inline="always")
def neutral_deposit_step(wmap, j, jp, cur, wvol):
    """0: no step wear of the type's own (a one-point type's waits as a cap,
    ``deposit_cap``; a bushing does not wear)."""
    return 0.0


@compiled(inline="always")
def neutral_penetration(j, model, k, body):
    """-inf: no contact of the type's own to locate (a one-point type's one contact is the
    diagnostics'; a bushing is never in contact)."""
    return -math.inf


@compiled(inline="always")
def neutral_section_offsets(jp, j, d, rate):
    """NaN: no clearance to scale a section's offsets by (a bushing: its deflection is its
    diagnostics' offset)."""
    return (math.nan, math.nan, math.nan), (math.nan, math.nan, math.nan)


@compiled(inline="always")
def neutral_seat(j, model, dg, body):
    """False: never in contact, nothing to seat."""
    return False


# ------------------------------------------------------------------ the one-point types'


@compiled(inline="always")
def one_point_section_offsets(jp, j, d, rate):
    """A one-point joint's section offset d [m] and its rate [m/s] in its socket's frame,
    each over its radial clearance c (``contact.offsets_over``)."""
    return offsets_over(d, rate, jp[j, J_C])


@compiled(inline="always")
def one_point_seat(j, model, dg, body):
    """A seated one-point joint: its episode begins without an impact
    (``contact.seat_episode``); True (``body`` not read)."""
    return seat_episode(j, model, dg)
