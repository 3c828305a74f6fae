"""The spherical clearance joint: a ball in a worn, possibly coated socket (docs/physics.md 3, 5).

A clearance-joint type is a module of this shape (docs/architecture.md, "Joint types"), its
:func:`gap` and :func:`contact` of the signatures ``joints.PROTOCOL`` fixes for every type:

- :func:`gap`: from the ball's and the socket's centres, the gap geometry in the socket:
  eccentricity, contact normal, penetration against the worn clearance, and whether the
  coating is worn through there;
- the wear-map geometry it wears: a map over the socket's inner sphere (``wear.map_bin``,
  ``wear.deposit``, ``wear.worn_surface``), and the contact's angle and area
  (:func:`contact_angle`, :func:`contact_area`) that the wear step reads;
- :func:`contact`: the gap composed with the coated contact law, damping and friction
  (``contact.respond``: where the force pair acts, the approach rate, the slip), returning
  the force and the moments that the equations of motion apply to the two bodies;
- the rest of ``joints.PROTOCOL``: the paper's slip angle (:func:`paper_angle`), the wear
  surface of a step (:func:`wear_surface`: the cap's area, its projection weights |n|,
  the socket's radius as the scale), when a step's cap joins the waiting one
  (:func:`cap_mergeable`) and its deposit on the sphere's map (:func:`deposit_cap`,
  ``wear.deposit``), the section offsets over the clearance (:func:`section_offsets`) and
  the seated start (:func:`seat`); a ball touches at one point (``CONTACTS = 1``), so that
  :func:`accept`, :func:`deposit_step` and :func:`penetration` have nothing to do.

The kernel composes these (through ``jointkinds``); nothing of a joint type's geometry is
written elsewhere.
"""

import math

from . import shared
from .compiled import compiled
from .contact import compose, seat_episode, store_contact
from .kinematics import body_moment, dot, mtv, mv, point_state, scale, sub
from .layout import (
    D_DELTA,
    D_ECC,
    D_HWEAR,
    J_C,
    J_COAT,
    J_RI,
    J_RJ,
    P_FEEDBACK,
    P_INTERP,
    S_BETA,
)
from .wear import deposit, worn_surface

#: The joint type this module implements (registered in ``joints.JOINT_TYPES``).
JOINT_TYPE = "spherical"
#: Contact points of the joint (``joints.PROVIDES``): the ball touches its socket at one.
CONTACTS = 1


@compiled
def gap(jp, j, wmap, p, k, pb, ps, Rs):
    """:func:`socket_gap` without a hint: the protocol's gap (``joints.PROTOCOL``)."""
    return socket_gap(jp, j, wmap, p, pb, ps, Rs, None)


@compiled
def socket_gap(jp, j, wmap, p, pb, ps, Rs, hint):
    """Gap geometry of joint j with ball centre pb and socket centre ps (global) in a socket
    of rotation Rs: (e, n, d_s, n_s, h, slope, worn, c_eff, delta) (``joints.PROTOCOL``;
    the ball touches its socket at one point: the contact index k is 0 and not read).

    e = |d| [m], d = pb - ps; n = d / e (global; e = 0: the x axis); d_s, n_s: d and n in the
    socket frame; h [m], worn: the worn socket in direction n_s (wear.worn_surface);
    c_eff = c + h; delta = e - c_eff, the penetration (negative: a gap). ``slope`` is the
    gradient of h with respect to the ball centre, grad_d h = R_s grad h / e (global,
    tangent to n, dimensionless), so that grad_d delta = n - slope: the worn gap's normal.
    ``hint``: None, or the contact state s, whose row j keeps the map bin last read
    (``wear.map_bin_near``: the same bin, found sooner).
    """
    d = sub(pb, ps)
    e = math.sqrt(dot(d, d))
    if e > 0.0:
        n = scale(1.0 / e, d)
    else:
        n = (1.0, 0.0, 0.0)
    d_s = mtv(Rs, d)
    n_s = mtv(Rs, n)
    h, grad, worn = worn_surface(wmap, j, n_s, jp[j, J_COAT], p[P_FEEDBACK] != 0.0,
                                 p[P_INTERP] != 0.0, hint)
    slope = (0.0, 0.0, 0.0)
    if e > 0.0 and (grad[0] != 0.0 or grad[1] != 0.0 or grad[2] != 0.0):
        slope = scale(1.0 / e, mv(Rs, grad))
    c_eff = jp[j, J_C] + h
    return e, n, d_s, n_s, h, slope, worn, c_eff, e - c_eff


@compiled
def cap_height(pen, e, ri, rj):
    """h_c = R_j (1 + cos beta) of Eq. 11-12 without cancellation [m].

    1 + cos beta = (e - R_i + R_j)(e + R_j + R_i) / (2 R_j e); the first factor is the
    penetration against the unworn radii, ``pen`` = delta + h, passed in rather than
    formed as a difference of radii (which would lose all digits for small delta).
    """
    return pen * (e + rj + ri) / (2.0 * e)


@compiled
def contact_area(pen, e, ri, rj):
    """Contact area A = pi(|cB|^2 + h_c^2) = 2 pi R_j h_c (Eq. 13) [m^2]."""
    return 2.0 * math.pi * rj * cap_height(pen, e, ri, rj)


@compiled
def contact_angle(pen, e, ri, rj):
    """Angle beta of Eq. 11 [rad]: pi - 2 asin(sqrt((1 + cos beta) / 2)), accurate near pi."""
    half = 0.5 * cap_height(pen, e, ri, rj) / rj
    return math.pi - 2.0 * math.asin(math.sqrt(min(1.0, max(0.0, half))))


@compiled
def contact(j, model, ball, socket, full, dg):
    """The socket's action on the ball of spherical clearance joint j (``joints.PROTOCOL``):
    (force on the ball's body [N, global], its moment about that body's centroid [N m, the
    body's frame], the moment of the opposite force about the socket's body's centroid
    [N m, that body's frame], power dissipated by damping and friction [W]). ``ball``: the
    ball's body (rb, vb, Rb, wb) and the centre's body offset ub; ``socket``: likewise. The
    gap (:func:`gap`) composed by ``contact.respond`` with the case's elastic law
    (docs/physics.md section 3); with ``full`` (a step's end) the joint's contact state
    into the diagnostics dg (``contact.store_contact``)."""
    rb, vb, Rb, wb, ub = ball
    rs, vs, Rs, ws_, us = socket
    pb, _ = point_state(rb, vb, Rb, wb, ub)
    ps, _ = point_state(rs, vs, Rs, ws_, us)
    geo = socket_gap(model.jp, j, model.wmap, model.p, pb, ps, Rs, model.s)
    c = compose(j, model, ball, socket, pb, ps, geo, elastic_law(model.p, j), full)
    if full:
        store_contact(dg, j, c)
    return (c.force, body_moment(Rb, rb, c.q_ball, c.force),
            body_moment(Rs, rs, c.q_socket, c.force), c.diss_power)


@compiled(inline="always")
def paper_angle(jp, j, pen, e):
    """(The contact angle beta of Eq. 11 [rad] at the penetration pen against the unworn
    radii and the eccentricity e (:func:`contact_angle`), True: the paper's slip rule
    applies) (``joints.PROTOCOL``)."""
    return contact_angle(pen, e, jp[j, J_RI], jp[j, J_RJ]), True


@compiled(inline="always")
def wear_surface(jp, j, pen, e, n):
    """The cap a step wears (``joints.PROTOCOL``): its area (:func:`contact_area`) [m^2],
    the projection weights |n_x|, |n_y|, |n_z| of the normal n, the socket's radius R_i as
    the scale [m]."""
    area = contact_area(pen, e, jp[j, J_RI], jp[j, J_RJ])
    return area, abs(n[0]), abs(n[1]), abs(n[2]), jp[j, J_RI]


@compiled(inline="always")
def cap_mergeable(j, d2, tol, area, scale):
    """Whether a direction d2 (squared) from the waiting cap's stays within tol of the cap's
    angular radius, whose square is A / (pi R^2) for a small cap of area A on a sphere of
    radius R = ``scale`` (``joints.PROTOCOL``)."""
    return d2 <= tol * tol * area / (math.pi * scale * scale)


@compiled(inline="always")
def deposit_cap(wmap, j, n, vol, area, scale, scratch):
    """The waiting cap on the sphere's map (``wear.deposit``, ``scale`` the radius R_i);
    the largest depth written [m] (``joints.PROTOCOL``)."""
    return deposit(wmap, j, n, vol, area, scale, scratch)


#: The case's elastic law (``contact.elastic``), the ball's contact's (``shared``).
elastic_law = shared.case_elastic_law
#: Nothing: the ball's step is the kernel's one-point rule (``rk4.accept_substep``); False
#: (``shared``).
accept = shared.neutral_accept
#: Nothing: the ball's wear waits as a cap (:func:`deposit_cap`); 0 (``shared``).
deposit_step = shared.neutral_deposit_step
#: -inf: the ball's one contact is the diagnostics' (``shared``).
penetration = shared.neutral_penetration
#: The ball's section offset and its rate over the clearance c (``shared``).
section_offsets = shared.one_point_section_offsets


@compiled(inline="always")
def seat(j, model, dg, body):
    """A seated ball (``joints.PROTOCOL``): its episode begins without an impact
    (``contact.seat_episode``) at the contact angle of its seat (:func:`contact_angle`);
    True."""
    seated = seat_episode(j, model, dg)
    model.s[j, S_BETA] = contact_angle(dg[D_DELTA + j] + dg[D_HWEAR + j], dg[D_ECC + j],
                                       model.jp[j, J_RI], model.jp[j, J_RJ])
    return seated


#: The ball's contact points, at R_j and R_i along the normal, rated in or near contact
#: (``shared``).
rate_point = shared.one_point_rate_point
#: The stiff rate of the ball's contact force on the mobility of its points (``shared``).
force_rate = shared.one_point_force_rate
