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
  share: the seated start's episode (``contact.seat_episode``), the section offsets
  over the radial clearance (``contact.offsets_over``), and the stiff rate of a contact
  force (docs/physics.md section 4): where it acts and when it is due
  (:func:`one_point_rate_point`), and its rate on the mobility there
  (:func:`one_point_force_rate`).

A function here is compiled once whatever the types that take it (one Numba dispatcher),
and ``jointkinds`` dispatches a protocol function to each distinct one once.
"""

import math

from .compiled import compiled
from .contact import (
    contact_damping,
    normal_force,
    offsets_over,
    reachable_penetration,
    seat_episode,
    stiff_rate,
    surface,
)
from .kinematics import scale
from .layout import (
    D_CEFF,
    D_DDOT,
    D_DELTA,
    D_DFD,
    D_DFDD,
    D_FN,
    D_NGLOBAL,
    D_VT,
    D_WORN,
    J_C,
    J_FILM,
    J_RI,
    J_RJ,
    P_DT,
    P_EXPONENT,
    P_FRICTION,
    P_V0,
    P_V1,
    S_DV0,
)
from .multibody import quad_form, tangent_basis

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


@compiled(inline="always")
def one_point_rate_point(j, model, dg):
    """Where a one-point joint's contact force acts, for its stiff rate at a step's end
    (``joints.PROTOCOL``'s ``rate_point``): due in contact (delta > 0) or when the gap
    closes within one output step at its approach rate; the pair of contact points, each
    on the mobility of its body (True), at the ball's radius R_j and the socket's R_i along
    the contact normal n (dg, global) from the joint's centres [m]."""
    jp = model.jp
    delta = dg[D_DELTA + j]
    n = (dg[D_NGLOBAL + 3 * j], dg[D_NGLOBAL + 3 * j + 1], dg[D_NGLOBAL + 3 * j + 2])
    due = delta > 0.0 or delta + dg[D_DDOT + j] * model.p[P_DT] > 0.0
    return due, True, scale(jp[j, J_RJ], n), scale(jp[j, J_RI], n)


@compiled
def one_point_force_rate(j, model, dg, wp, y, law):
    """Largest stiff rate [1/s] of a one-point joint's contact: elastic/damping and
    friction (docs/physics.md section 4), on the mobility wp of its contact points
    (packed symmetric 3x3 [1/kg], every constraint in place: the crank is driven, hence
    of infinite mass), under the joint's elastic law ``law`` (its type's ``elastic_law``;
    the state y not read).

    Besides the rates at the current state, an approaching joint (delta_dot > 0) whose gap
    closes within one output step is also rated at the penetration its kinetic energy can
    reach, delta_pred^3 = delta^3 + 3 m_eff delta_dot^2 c / (4 K) (from
    U ~ 2 K delta^3 / (3 c)), so that an impact that begins and ends inside one step still
    sets the sub-step.
    """
    p = model.p
    jp = model.jp
    n = (dg[D_NGLOBAL + 3 * j], dg[D_NGLOBAL + 3 * j + 1], dg[D_NGLOBAL + 3 * j + 2])
    inv_m = quad_form(wp, n, n)
    if not inv_m > 0.0:
        return 0.0
    m_eff = 1.0 / inv_m
    rate = stiff_rate(m_eff, dg[D_DFD + j], dg[D_DFDD + j])
    ddot = dg[D_DDOT + j]
    ew, mu, _ = surface(jp, j, dg[D_WORN + j] != 0.0)
    if ddot > 0.0:
        c_eff = dg[D_CEFF + j]
        ri = jp[j, J_RI]
        rj = jp[j, J_RJ]
        dpred = reachable_penetration(max(dg[D_DELTA + j], 0.0), m_eff, ddot, c_eff, ew, ri,
                                      rj, law)
        kappa = contact_damping(model.s[j, S_DV0], ddot, p)
        _, _, dfd, dfdd = normal_force(dpred, ddot, c_eff, ew, ri, rj, law, kappa)
        rate = max(rate, stiff_rate(m_eff, dfd, dfdd))
    fn = dg[D_FN + j]
    film = jp[j, J_FILM]
    if p[P_FRICTION] != 0.0 and (mu > 0.0 or film > 0.0) and fn > 0.0:
        # largest tangential inverse mass: top eigenvalue of the 2x2 projection of W_p
        t1, t2 = tangent_basis(n)
        a = quad_form(wp, t1, t1)
        b = quad_form(wp, t1, t2)
        d = quad_form(wp, t2, t2)
        inv_t = 0.5 * (a + d) + math.sqrt(0.25 * (a - d) ** 2 + b * b)
        vt = dg[D_VT + j]
        slope = 1.0 / (p[P_V1] - p[P_V0]) if vt < p[P_V1] else 1.0 / vt
        # Coulomb's ramp and the film's viscous shear (its rate: the coefficient over the mass)
        rate = max(rate, (mu * fn * slope + film) * inv_t)
    return rate
