"""The elastic bushing: a linear spring-damper between the ball point and the socket point
(docs/physics.md section 3.8).

A joint type of the shape docs/architecture.md ("Joint types") describes, selectable at A,
B (in place of the spherical joint) and O (in place of the revolute): ``joints.X.type:
bushing``. A rubber bushing holds the two bodies together elastically, with no gap, no
impact, no friction and no wear; it is modelled, as in vehicle and mechanism dynamics, by
springs and dampers that penalise the relative motion of the two attachment points,
linear and diagonal in the bushing's own frame (Ambrósio, "Sensitivity of a vehicle ride
to the suspension bushing characteristics", J. Mech. Sci. Technol. 23(4), 1075-1082,
2009; the linear bushing force element of MotionSolve's ``Force_Bushing``, a diagonal
stiffness and damping in the bushing's marker frame). Translational only: the joint
transmits no moment, as the spherical joint it replaces.

With e = p_ball - p_socket (global) and a the bushing's axis (the socket body's local x
axis: the rod's long axis at A, the slider's guide direction at B, the bearing's axis,
global x, at O), e_a = (e . a) a its axial part and e_r = e - e_a its radial part, the
force on the ball is

    F = -(k_r e_r + c_r w_r) - (k_a e_a + c_a w_a),

w the velocity of the ball's point relative to the socket's material point where it sits,
split likewise. The pair acts at the ball point on both bodies (the socket's share at its
material point there), so that its power on the bodies is F . w, and the stored energy
U = k_r |e_r|^2 / 2 + k_a e_a^2 / 2 (booked with the contacts' elastic energies) and the
dissipated power c_r |w_r|^2 + c_a w_a^2 balance it exactly, the axis turning with the
socket included. At O the axial stiffness and damping are packed 0: O's axial motion stays
ideal, as with its clearance (revolute.py).

- :func:`gap`: the offset's geometry in the ``spherical.gap`` shape (no clearance: c_eff
  and the penetration are 0, so that no contact, impact or wear is ever counted);
- :func:`contact`: the law above as a ``contact.ContactState``;
- :func:`rate`: its largest stiff rate on the mobility of the joint's point, for the
  sub-step (docs/physics.md section 4): the protocol's :func:`force_rate`, at the point
  :func:`rate_point` names (the joint's centres, always due).

The rest of ``joints.PROTOCOL`` is the shared neutral functions (``shared.neutral_*``,
and the case's elastic law, never read: ``shared.case_elastic_law``; taken by name): a bushing does not wear (no
wear surface, caps or deposit), has no contact episodes (no seat, no accept, no
penetration: ``CONTACTS = 0``) and no clearance to scale a section's offsets by (NaN).
"""

import math

from . import shared
from .compiled import compiled
from .contact import ContactState, relative_velocity, stiff_rate, store_contact
from .joints import BODIES, JOINTS
from .kinematics import add, body_moment, dot, mtv, point_state, rotation, scale, sub, trig
from .layout import D_JOINT_FORCE, J_C_AXIAL, J_C_RADIAL, J_K_AXIAL, J_K_RADIAL
from .multibody import tangent_basis

#: The joint type this module implements (registered in ``joints.JOINT_TYPES``).
JOINT_TYPE = "bushing"
#: Contact points of the joint (``joints.PROVIDES``): none, it never touches.
CONTACTS = 0


@compiled
def axis_of(Rs):
    """The bushing's axis (global, unit): the socket body's local x axis, the first column
    of its rotation Rs (row-major)."""
    return (Rs[0], Rs[3], Rs[6])


@compiled
def split(v, a):
    """(the part of v along the unit axis a, the rest): v_a a and v - v_a a."""
    along = scale(dot(v, a), a)
    return along, sub(v, along)


@compiled
def gap(jp, j, wmap, p, k, pb, ps, Rs):
    """Offset geometry of bushing j with ball point pb and socket point ps (global) on a
    socket of rotation Rs, in ``spherical.gap``'s shape: (e, n, d_s, n_s, h, slope, worn,
    c_eff, delta) with e = |pb - ps|, n its direction (e = 0: the x axis), d_s, n_s in the
    socket frame; no wear (h 0, flat), no clearance (c_eff 0) and no penetration (delta 0:
    a bushing is never "in contact")."""
    d = sub(pb, ps)
    e = math.sqrt(dot(d, d))
    if e > 0.0:
        n = scale(1.0 / e, d)
    else:
        n = (1.0, 0.0, 0.0)
    return e, n, mtv(Rs, d), mtv(Rs, n), 0.0, (0.0, 0.0, 0.0), False, 0.0, 0.0


@compiled
def contact(j, model, ball, socket, full, dg):
    """The socket's action on the ball of bushing j, as ``spherical.contact``
    (``joints.PROTOCOL``): (force on the ball's body [N, global], its moment about that
    body's centroid, the moment of the opposite force about the socket's body's centroid,
    power dissipated by the damper [W]). The ball point (``ball``: its body's (rb, vb, Rb,
    wb) and the point's body offset ub) is held to the socket point (``socket``: likewise)
    by the linear spring-damper of the module's docstring. With ``full``, its state into
    dg (``contact.store_contact``: the stored energy U among it; ``fn`` the force's size,
    ``ddot`` the offset's rate along n, ``dfn_ddelta`` and ``dfn_dddot`` the radial
    stiffness and damping) and its force as the joint's force."""
    jp = model.jp
    rb, vb, Rb, wb, ub = ball
    rs, vs, Rs, ws_, us = socket
    pb, _ = point_state(rb, vb, Rb, wb, ub)
    ps, _ = point_state(rs, vs, Rs, ws_, us)
    e, n, d_s, n_s, h, _, _, c_eff, delta = gap(jp, j, model.wmap, model.p, 0, pb, ps, Rs)
    a = axis_of(Rs)
    d = sub(pb, ps)
    # the ball's point against the socket's material point at pb
    w = relative_velocity(rb, vb, Rb, wb, rs, vs, Rs, ws_, pb, pb)
    kr = jp[j, J_K_RADIAL]
    ka = jp[j, J_K_AXIAL]
    cr = jp[j, J_C_RADIAL]
    ca = jp[j, J_C_AXIAL]
    da, dr = split(d, a)
    wa, wr = split(w, a)
    force = scale(-1.0, add(add(scale(kr, dr), scale(cr, wr)), add(scale(ka, da), scale(ca, wa))))
    uel = 0.5 * (kr * dot(dr, dr) + ka * dot(da, da)) if full else 0.0
    pdiss = cr * dot(wr, wr) + ca * dot(wa, wa)
    fn = math.sqrt(dot(force, force))
    if full:
        store_contact(dg, j, ContactState(force, force, pb, pb, fn, kr, cr, delta, dot(n, w), e,
                                          n, d_s, n_s, 0.0, c_eff, h, uel, pdiss, 0.0))
        # the joint's force on the ball (at O the kernel completes it with the axial
        # reaction; at A and B it is written again from the solve's forces)
        for i in range(3):
            dg[D_JOINT_FORCE + 3 * j + i] = force[i]
    return (force, body_moment(Rb, rb, pb, force), body_moment(Rs, rs, pb, force), pdiss)


@compiled
def sym3_top(a11, a12, a13, a22, a23, a33):
    """Largest eigenvalue of the symmetric 3x3 matrix [[a11, a12, a13], [., a22, a23],
    [., ., a33]] (the trigonometric closed form; Smith, Commun. ACM 4(4), 168, 1961)."""
    p1 = a12 * a12 + a13 * a13 + a23 * a23
    q = (a11 + a22 + a33) / 3.0
    b11 = a11 - q
    b22 = a22 - q
    b33 = a33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    if not p2 > 0.0:
        return q
    pp = math.sqrt(p2 / 6.0)
    det = (b11 * (b22 * b33 - a23 * a23) - a12 * (a12 * b33 - a23 * a13)
           + a13 * (a12 * a23 - b22 * a13))
    r = 0.5 * det / (pp * pp * pp)
    r = min(1.0, max(-1.0, r))
    return q + 2.0 * pp * math.cos(math.acos(r) / 3.0)


@compiled
def quad(w, x, y):
    """x^T W y for the packed symmetric W (xx, xy, xz, yy, yz, zz)."""
    return (x[0] * (w[0] * y[0] + w[1] * y[1] + w[2] * y[2])
            + x[1] * (w[1] * y[0] + w[3] * y[1] + w[4] * y[2])
            + x[2] * (w[2] * y[0] + w[4] * y[1] + w[5] * y[2]))


@compiled
def scaled_top(w, u, g):
    """Largest eigenvalue of G^1/2 W' G^1/2, W' the packed symmetric mobility ``w`` in the
    orthonormal basis ``u`` (3 vectors) and G = diag(g) [per basis vector]."""
    s0 = math.sqrt(g[0])
    s1 = math.sqrt(g[1])
    s2 = math.sqrt(g[2])
    return sym3_top(g[0] * quad(w, u[0], u[0]), s0 * s1 * quad(w, u[0], u[1]),
                    s0 * s2 * quad(w, u[0], u[2]), g[1] * quad(w, u[1], u[1]),
                    s1 * s2 * quad(w, u[1], u[2]), g[2] * quad(w, u[2], u[2]))


@compiled
def rate(jp, j, wp, a, t1, t2):
    """Largest stiff rate [1/s] of bushing j on the mobility ``wp`` of its point (packed
    symmetric 3x3 [1/kg], ``dynamics.point_mobility``), axis a and the two unit vectors t1, t2
    across it: the root of s^2 + lambda_c s + lambda_k = 0 (``contact.stiff_rate``), lambda_k
    the top eigenvalue of K^1/2 W K^1/2 (K the stiffnesses in the basis a, t1, t2: the
    undamped rate's square) and lambda_c that of C^1/2 W C^1/2. Exact for one direction, or
    for damping proportional to stiffness (docs/physics.md section 4)."""
    basis = (a, t1, t2)
    kr = jp[j, J_K_RADIAL]
    cr = jp[j, J_C_RADIAL]
    lk = scaled_top(wp, basis, (jp[j, J_K_AXIAL], kr, kr))
    lc = scaled_top(wp, basis, (jp[j, J_C_AXIAL], cr, cr))
    return stiff_rate(1.0, lk, lc)


@compiled(inline="always")
def rate_point(j, model, dg):
    """(True, True, zero, zero): the bushing's stiff rate is always due, on the mobility
    of its centres themselves (its small deflection left out; ``joints.PROTOCOL``)."""
    zero = (0.0, 0.0, 0.0)
    return True, True, zero, zero


#: Each joint's socket body's Euler angles in the state (``layout.Y_*``, the body's slots
#: of ``joints.BODIES``), -1 for the ground: the bushing's axis is that body's local x axis.
SOCKET_PHI = tuple(-1 if body.y_phi is None else body.y_phi
                   for joint in JOINTS for body in BODIES if body.name == joint.socket.body)


@compiled
def force_rate(j, model, dg, wp, y, law):
    """The bushing's largest stiff rate [1/s] (:func:`rate`) on the mobility wp of its
    centres, its axis the socket body's local x axis at the state y (:func:`axis_of` of
    that body's rotation; the ground's: global x) and the two unit vectors across it
    (``multibody.tangent_basis``; ``joints.PROTOCOL``: dg and law not read)."""
    a = (1.0, 0.0, 0.0)
    phi = SOCKET_PHI[j]
    if phi >= 0:
        a = axis_of(rotation(trig(y[phi], y[phi + 1], y[phi + 2])))
    t1, t2 = tangent_basis(a)
    return rate(model.jp, j, wp, a, t1, t2)


# The rest of ``joints.PROTOCOL``: the neutral functions (``shared``), written once.
#: The case's elastic law, never read: the bushing's force is its spring's.
elastic_law = shared.case_elastic_law
#: (pi, False): no contact.
paper_angle = shared.neutral_paper_angle
#: Zeros: a bushing does not wear.
wear_surface = shared.neutral_wear_surface
#: False: no wear caps.
cap_mergeable = shared.neutral_cap_mergeable
#: 0: no wear.
deposit_cap = shared.neutral_deposit_cap
#: False: no contact episodes.
accept = shared.neutral_accept
#: 0: no wear.
deposit_step = shared.neutral_deposit_step
#: -inf: never in contact.
penetration = shared.neutral_penetration
#: NaN: no clearance to scale by (a bushing's deflection is its diagnostics' offset).
section_offsets = shared.neutral_section_offsets
#: False: never in contact, nothing to seat.
seat = shared.neutral_seat
