"""The spherical clearance joint: a ball in a worn, possibly coated socket (docs/physics.md 3, 5).

A clearance-joint type is a module of this shape (docs/architecture.md, "Joint types"):

- :func:`gap`: from the two bodies' states, the gap geometry in the socket: eccentricity,
  contact normal, penetration against the worn clearance, and whether the coating is worn
  through there;
- :func:`contact_points`, :func:`point_velocity` and :func:`relative_velocity`: where the
  force pair acts and how fast those points move, hence the normal approach rate and the
  tangential slip (:func:`tangential`);
- the wear-map geometry it wears: a map over the socket's inner sphere (``wear.map_bin``,
  ``wear.deposit``, ``wear.worn_surface``);
- :func:`contact`: the composition with the coated contact law, damping and friction of
  ``contact.py``, returning a :data:`ContactState` that the equations of motion apply to
  the two bodies.

The kernel composes these; nothing of a joint type's geometry is written elsewhere.
"""

import math
from collections import namedtuple

from .compiled import compiled
from .contact import (
    contact_damping,
    elastic_energy,
    friction_magnitude,
    normal_force,
    surface,
)
from .kinematics import add, cross, dot, mtv, mv, point_state, scale, sub
from .layout import (
    J_C,
    J_COAT,
    J_RI,
    J_RJ,
    P_EXPONENT,
    P_FEEDBACK,
    P_FRICTION,
    P_INTERP,
    P_V0,
    P_V1,
    S_DV0,
)
from .wear import worn_surface

#: The joint type this module implements (registered in ``joints.JOINT_TYPES``).
JOINT_TYPE = "spherical"

#: What :func:`contact` returns for one clearance joint (Numba compiles a namedtuple as a
#: tuple: fields are read by name at no cost). Vectors are 3-tuples, global frame unless
#: named ``_socket``.
ContactState = namedtuple("ContactState", (
    "force",            # force on the ball [N]
    "force_normal",     # its normal part (the force without friction) [N]
    "q_ball",           # contact point Q_j on the ball
    "q_socket",         # contact point Q_i on the socket
    "fn",               # normal force F_N [N]
    "dfn_ddelta",       # dF_N / d delta [N/m]
    "dfn_dddot",        # dF_N / d delta_dot [N s/m]
    "delta",            # penetration delta = e - c_eff [m] (negative: a gap)
    "ddot",             # normal approach rate delta_dot [m/s]
    "ecc",              # eccentricity e [m]
    "normal",           # line of the normal force (n on a flat surface)
    "offset_socket",    # ball-centre offset d in the socket frame [m]
    "normal_socket",    # n in the socket frame
    "slip_speed",       # tangential slip speed |v_t| [m/s]
    "c_eff",            # local clearance c + h [m]
    "wear_depth",       # wear depth h under the contact point [m]
    "elastic_energy",   # elastic energy U_el [J] (0 unless asked for)
    "diss_power",       # power dissipated by damping and friction [W]
    "worn_through",     # 1.0: coating worn through under the contact, base values used
))


@compiled
def gap(jp, j, wmap, p, pb, ps, Rs):
    """Gap geometry of joint j with ball centre pb and socket centre ps (global) in a socket
    of rotation Rs: (e, n, d_s, n_s, h, slope, worn, c_eff, delta).

    e = |d| [m], d = pb - ps; n = d / e (global; e = 0: the x axis); d_s, n_s: d and n in the
    socket frame; h [m], worn: the worn socket in direction n_s (wear.worn_surface);
    c_eff = c + h; delta = e - c_eff, the penetration (negative: a gap). ``slope`` is the
    gradient of h with respect to the ball centre, grad_d h = R_s grad h / e (global,
    tangent to n, dimensionless), so that grad_d delta = n - slope: the worn gap's normal.
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
                                 p[P_INTERP] != 0.0)
    slope = (0.0, 0.0, 0.0)
    if e > 0.0 and (grad[0] != 0.0 or grad[1] != 0.0 or grad[2] != 0.0):
        slope = scale(1.0 / e, mv(Rs, grad))
    c_eff = jp[j, J_C] + h
    return e, n, d_s, n_s, h, slope, worn, c_eff, e - c_eff


@compiled
def contact_points(pb, ps, n, ri, rj):
    """(Q_j on the ball, Q_i on the socket): the surface points along the normal n."""
    return add(pb, scale(rj, n)), add(ps, scale(ri, n))


@compiled
def point_velocity(r, v, R, w, q):
    """Velocity of the material point at global position q of a body (centroid r, velocity
    v, rotation R, body-frame angular velocity w)."""
    return add(v, mv(R, cross(w, mtv(R, sub(q, r)))))


@compiled
def tangential(v, u):
    """The part v_t of v tangent to the unit vector u, and |v_t|."""
    vt = sub(v, scale(dot(u, v), u))
    return vt, math.sqrt(dot(vt, vt))


@compiled
def relative_velocity(rb, vb, Rb, wb, rs, vs, Rs, ws_, qj, qi):
    """v(Q_j) - v(Q_i): the velocity of the ball's point Q_j relative to the socket's Q_i."""
    return sub(point_velocity(rb, vb, Rb, wb, qj), point_velocity(rs, vs, Rs, ws_, qi))


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
def contact(j, model, ball, socket, energy):
    """Contact state and force of clearance joint j (docs/physics.md section 3).

    ``ball``: the ball's body (centroid rb, velocity vb, rotation Rb, body-frame angular
    velocity wb) and the ball centre's body offset ub, as the tuple (rb, vb, Rb, wb, ub);
    ``socket``: (rs, vs, Rs, ws_, us) likewise. ``model`` (a :data:`work.Model`) holds p, jp,
    s and wmap. ``energy``: also compute the elastic energy (else 0 where not needed).
    Returns a :data:`ContactState`. The whole arrays jp, s, wmap are passed with the joint
    index, never a row of them: a row is a new array view, formed at every call.

    On a sloped worn surface (bilinear map read, :func:`gap`'s ``slope`` s != 0) the
    penetration delta = e - c - h(n) has the gradient m = n - s, and the contact force
    derives from the elastic potential U(delta, c_eff) (docs/physics.md 3.5):
    F = -F_N m - X s on the ball, X = dU/dc_eff at fixed delta while F_N > 0 (0 otherwise),
    acting along its own line through the ball centre, so that its power is exactly
    -F_N delta_dot - X h_dot with delta_dot = m . w, h_dot = s . w, w the ball centre's
    velocity as the socket sees it; damping and friction are booked as dissipated.
    A flat surface (s = 0) gives the radial force F = -F_N n of section 3.4.
    """
    p = model.p
    jp = model.jp
    s = model.s
    wmap = model.wmap
    rb, vb, Rb, wb, ub = ball
    rs, vs, Rs, ws_, us = socket
    pb, _ = point_state(rb, vb, Rb, wb, ub)
    ps, _ = point_state(rs, vs, Rs, ws_, us)
    e, n, d_s, n_s, h, slope, worn, c_eff, delta = gap(jp, j, wmap, p, pb, ps, Rs)
    ew, mu, _ = surface(jp, j, worn)
    worn_flag = 1.0 if worn else 0.0
    ri = jp[j, J_RI]
    rj = jp[j, J_RJ]
    zero = (0.0, 0.0, 0.0)
    sloped = slope[0] != 0.0 or slope[1] != 0.0 or slope[2] != 0.0
    hdot = 0.0
    if sloped:
        # the ball centre's velocity relative to the socket, in the socket's rotating frame
        # (the centres' velocities formed here, not kept live across the flat path)
        w = sub(sub(point_velocity(rb, vb, Rb, wb, pb), point_velocity(rs, vs, Rs, ws_, ps)),
                cross(mv(Rs, ws_), sub(pb, ps)))
        hdot = dot(slope, w)
        ddot = dot(n, w) - hdot
        qj, qi = contact_points(pb, pb, n, rj - delta, rj)
        v = zero
    else:
        qj, qi = contact_points(pb, ps, n, ri, rj)
        v = relative_velocity(rb, vb, Rb, wb, rs, vs, Rs, ws_, qj, qi)
        ddot = dot(n, v)
    if delta <= 0.0:
        return ContactState(zero, zero, qj, qi, 0.0, 0.0, 0.0, delta, ddot, e, n, d_s, n_s, 0.0,
                            c_eff, h, 0.0, 0.0, worn_flag)
    kappa = contact_damping(s[j, S_DV0], ddot, p)
    law = p[P_EXPONENT]
    fn, fel, dfd, dfdd = normal_force(delta, ddot, c_eff, ew, ri, rj, law, kappa)
    uel = elastic_energy(delta, c_eff, ew, ri, rj, law) if (energy or sloped) else 0.0
    line = n
    if sloped:
        uc = (2.0 * uel - delta * fel) / c_eff       # dU/dc_eff at fixed delta
        x = uc if fn > 0.0 else 0.0
        force = add(scale(-fn, n), scale(fn - x, slope))
        pdiss = (fn - fel) * ddot + (x - uc) * hdot
        size = math.sqrt(dot(force, force))
        if size > 0.0:
            line = scale(-1.0 / size, force)
        qj, qi = contact_points(pb, pb, line, rj - delta, rj)
        v = relative_velocity(rb, vb, Rb, wb, rs, vs, Rs, ws_, qj, qi)
    else:
        force = scale(-fn, n)
        pdiss = (fn - fel) * ddot
    force_normal = force
    vt, vtn = tangential(v, line)
    if p[P_FRICTION] != 0.0 and vtn > 0.0:
        ft = friction_magnitude(mu, fn, vtn, p[P_V0], p[P_V1])
        force = add(force, scale(-ft / vtn, vt))
        pdiss += ft * vtn
    return ContactState(force, force_normal, qj, qi, fn, dfd, dfdd, delta, ddot, e, line, d_s, n_s, vtn, c_eff,
                        h, uel if energy else 0.0, pdiss, worn_flag)
