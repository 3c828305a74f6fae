"""The revolute clearance joint: a journal in a worn, possibly coated bearing: the crank's
in the ground (O), and in the planar slider-crank the crank pin in the rod's eye (A) and
the wrist pin in the slider (B) (docs/physics.md section 3.6, docs/modelling.md,
docs/mechanisms.md).

A joint type of the shape docs/architecture.md ("Joint types") describes, as
``spherical.py`` is. Every bearing's axis lies along the global x axis (the crank's axis
of rotation). O's sits in the ground at the origin: its frame is the global frame. A's
and B's sit in a body that moves in the plane (the rod turns in it): their frame turns
with that body about x (:data:`BEARING_U`, :func:`to_bearing`), and their maps with it.
The journal centre moves in the bearing's plane (y, z): radial clearance. Axial play and
tilt stay ideal (the crank's axial position and its two tilt angles are constrained, the
slider-crank's rod is held in its plane), so the gap, the normal and the contact points
lie in that plane:

- :func:`gap`: eccentricity e of the journal centre in the plane, the normal n (in the
  plane), the penetration against the worn clearance c_eff = c + h(phi) read from the
  bearing map at the normal's angle in the bearing's frame phi = atan2(n_z, n_y);
- the bearing map: one row (``wmap[j, 0, :]``) of ``nazim`` bins around the bearing, the
  depth uniform along its length (the model does not resolve the length): :func:`map_read`,
  :func:`deposit`;
- :func:`contact_angle` and :func:`contact_area`: the half-angle psi of the arc where the
  journal's circle overlaps the bearing's, and the strip A = 2 psi R_i L;
- :func:`contact`: the gap composed by ``contact.respond`` with the journal's elastic law,
  the power law F_el = K delta^n with K = 4 E* sqrt(R_i R_j / c) / 3 (Hertz's modulus E*,
  ``params.hertz_modulus``) and n = 3/2 unless ``contact.elastic: hertz`` gives another
  exponent (Flores et al. 2008; docs/physics.md
  section 3.6);
- the rest of ``joints.PROTOCOL``: the wear surface of a step (:func:`wear_surface`: the
  strip, its depth projected about the bearing's axis, R_i L as the scale), when a step's
  strip joins the waiting one (:func:`cap_mergeable`: within a fraction of its half-angle)
  and its deposit (:func:`deposit_cap`, :func:`deposit`), the section offsets over the
  clearance and the seated start; the paper's slip rule is a sphere's, not a bearing's
  (:func:`paper_angle`), and a journal touches at one point (``CONTACTS = 1``).
"""

import math

from . import shared
from .compiled import compiled
from .contact import compose, store_contact
from .joints import JOINTS, PLANE_AXES
from .kinematics import body_moment, mtv, point_state
from .layout import (
    D_JOINT_FORCE,
    J_C,
    J_COAT,
    J_LENGTH,
    J_RI,
    J_RJ,
    P_EXPONENT,
    P_FEEDBACK,
    P_INTERP,
)
from .wear import angle_bin, angle_bin_near, arc_to_bins, coating_worn

#: The joint type this module implements (registered in ``joints.JOINT_TYPES``).
JOINT_TYPE = "revolute"
#: Contact points of the joint (``joints.PROVIDES``): the journal touches its bearing at one.
CONTACTS = 1

#: The journal's elastic exponent where the case keeps the paper's (spherical) law.
JOURNAL_EXPONENT = 1.5


def _bearing_axes(joint):
    """(u, v, sign) of a joint's bearing in its socket body's frame: the body's two axes
    spanning the mechanism's plane (``joints.PLANE_AXES``) and the sign that makes the
    bearing's axis (u x v) the body's third axis or its opposite; (-1, -1, 1) for a
    bearing in the ground, whose frame is the global frame."""
    body = joint.socket.body
    if body == "ground":
        return -1, -1, 1.0
    u, v = PLANE_AXES[body]
    return u, v, 1.0 if (u + 1) % 3 == v else -1.0


#: Each row's bearing axes in its socket body's frame where that body moves (the
#: slider-crank's A, in the rod, and B, in the slider): the axes u, v that span the
#: mechanism's plane; -1 where the bearing sits in the ground (O) and its frame is the
#: global frame. Rows of other types never read them.
BEARING_U = tuple(_bearing_axes(joint)[0] for joint in JOINTS)
BEARING_V = tuple(_bearing_axes(joint)[1] for joint in JOINTS)
#: The sign of the socket body's third axis along the bearing's axis, u x v.
BEARING_SIGN = tuple(_bearing_axes(joint)[2] for joint in JOINTS)


@compiled(inline="always")
def to_bearing(j, a):
    """A vector ``a`` in joint j's socket body's frame in its bearing's frame (x the
    bearing's axis, u x v; y, z the body's axes u, v in the plane): (sign a_w, a_u, a_v);
    ``a`` itself where the bearing sits in the ground."""
    u = BEARING_U[j]
    if u < 0:
        return a
    v = BEARING_V[j]
    return (BEARING_SIGN[j] * a[3 - u - v], a[u], a[v])


@compiled
def journal_law(p):
    """The exponent n of the journal's power law F_el = A c (delta / c)^n: the case's Hertz
    exponent under ``contact.elastic: hertz``, else :data:`JOURNAL_EXPONENT`."""
    law = p[P_EXPONENT]
    return law if law != 0.0 else JOURNAL_EXPONENT


@compiled
def bearing_angle(n):
    """Angle phi = atan2(n_z, n_y) [rad] of an in-plane direction around the bearing."""
    return math.atan2(n[2], n[1])


@compiled
def bearing_bin(n, nazim, hint, j):
    """The bearing map's bin holding the in-plane direction n's angle phi (``wear.angle_bin``
    of (n_y, n_z)); ``hint``: None, or the contact state s whose row j keeps the bin read
    last (``wear.angle_bin_near``: the same bin, found sooner)."""
    if hint is None:
        return angle_bin(n[2], n[1], nazim)
    return angle_bin_near(n[2], n[1], nazim, hint, j)


@compiled
def map_read(wmap, j, n, interp, hint=None):
    """Depth h [m] of joint j's bearing map at the in-plane direction n and its rate
    dh/dphi [m per rad]: the bin holding phi (:func:`bearing_bin`), or (``interp``) linear
    between the bin centres, periodic around the bearing."""
    nazim = wmap.shape[2]
    if not interp:
        return wmap[j, 0, bearing_bin(n, nazim, hint, j)], 0.0
    v = (bearing_angle(n) + math.pi) / (2.0 * math.pi) * nazim - 0.5
    k = int(math.floor(v))
    fv = v - k
    k0 = k % nazim
    k1 = (k + 1) % nazim
    w0 = wmap[j, 0, k0]
    w1 = wmap[j, 0, k1]
    return (1.0 - fv) * w0 + fv * w1, (w1 - w0) * nazim / (2.0 * math.pi)


@compiled
def worn_through(wmap, j, n, coat, hint=None):
    """Whether the coating of thickness ``coat`` [m] (inf: none) is worn through in the bin
    of the bearing map holding the in-plane direction n (:func:`bearing_bin`)."""
    if not coat < math.inf:
        return False
    return coating_worn(wmap[j, 0, bearing_bin(n, wmap.shape[2], hint, j)], coat)


@compiled
def gap(jp, j, wmap, p, k, pb, ps, Rs):
    """:func:`bearing_gap` without a hint: the protocol's gap (``joints.PROTOCOL``)."""
    return bearing_gap(jp, j, wmap, p, pb, ps, Rs, None)


@compiled
def bearing_gap(jp, j, wmap, p, pb, ps, Rs, hint):
    """Gap geometry of revolute joint j with journal centre pb and bearing centre ps
    (global) in a bearing body of rotation Rs: (e, n, d_s, n_s, h, slope, worn, c_eff,
    delta), as ``spherical.gap`` (``joints.PROTOCOL``; one contact point, k = 0, not read).

    d = pb - ps in the mechanism's plane (global y, z; its axial part dropped: axial play
    is ideal); e = |d|; n = d / e (e = 0: the y axis). In the ground's bearing (O) the
    bearing's frame is the global frame: d_s = d, n_s = n, and Rs is not read. In a moving
    body's (the slider-crank's A in the rod, B in the slider: :data:`BEARING_U`) d_s and
    n_s are d and n in the bearing's frame (:func:`to_bearing` of R_s^T d), axial part 0:
    the map's angle phi = atan2(n_s,z, n_s,y) is the angle of n about x less the body's
    rotation about x. h [m] is the bearing map's depth at n_s (0 without feedback);
    ``slope`` = (dh/dphi / e) e_phi, e_phi = (0, -n_z, n_y) (global: the body's rotation
    shifts phi, not its rate), the gradient of h with respect to the journal centre, so
    that grad_d delta = n - slope. ``hint``: None, or the contact state s, whose row j keeps
    the map bin last read (:func:`bearing_bin`).
    """
    d = (0.0, pb[1] - ps[1], pb[2] - ps[2])
    e = math.sqrt(d[1] * d[1] + d[2] * d[2])
    if e > 0.0:
        n = (0.0, d[1] / e, d[2] / e)
    else:
        n = (0.0, 1.0, 0.0)
    d_s = d
    n_s = n
    if BEARING_U[j] >= 0:
        # a bearing in a moving body: d and n in its frame (the map turns with the body)
        d_b = to_bearing(j, mtv(Rs, d))
        n_b = to_bearing(j, mtv(Rs, n))
        d_s = (0.0, d_b[1], d_b[2])
        n_s = (0.0, n_b[1], n_b[2])
    h = 0.0
    slope = (0.0, 0.0, 0.0)
    if p[P_FEEDBACK] != 0.0:
        h, dh = map_read(wmap, j, n_s, p[P_INTERP] != 0.0, hint)
        if e > 0.0 and dh != 0.0:
            slope = (0.0, -dh / e * n[2], dh / e * n[1])
    worn = worn_through(wmap, j, n_s, jp[j, J_COAT], hint)
    c_eff = jp[j, J_C] + h
    return e, n, d_s, n_s, h, slope, worn, c_eff, e - c_eff


@compiled
def contact_angle(pen, e, ri, rj):
    """Half-angle psi [rad] of the arc over which the journal's circle (radius R_j, centre at
    eccentricity e) lies outside the bearing's (radius R_i): 1 - cos psi =
    pen (R_i + R_j - e) / (2 R_i e), pen = e - (R_i - R_j) the penetration against the unworn
    radii, passed in rather than formed as a difference of radii."""
    half = 0.25 * pen * (ri + rj - e) / (ri * e)
    return 2.0 * math.asin(math.sqrt(min(1.0, max(0.0, half))))


@compiled
def contact_area(pen, e, ri, rj, length):
    """Contact strip A = 2 psi R_i L [m^2] on the bearing (:func:`contact_angle`'s psi,
    bearing length L)."""
    return 2.0 * contact_angle(pen, e, ri, rj) * ri * length


@compiled
def deposit(wmap, j, n, vol, area, radius_length):
    """Spread the worn volume ``vol`` [m^3] over the bearing map's bins that the strip of
    area ``area`` [m^2] centred on the in-plane direction n overlaps (half-angle
    psi = area / (2 R_i L), ``radius_length`` = R_i L [m^2]); each bin deepens by its share of
    the volume over its area R_i L dphi, so sum(depth * bin area) = vol to rounding.
    Returns the largest depth of a bin written [m]."""
    nazim = wmap.shape[2]
    dphi = 2.0 * math.pi / nazim
    phi_c = bearing_angle(n)
    half = 0.5 * area / radius_length
    if not half * 2.0 > 1e-9 * dphi:
        ia = angle_bin(n[2], n[1], nazim)
        wmap[j, 0, ia] += vol / (radius_length * dphi)
        return wmap[j, 0, ia]
    # a bin inside the arc deepens by vol / (2 psi R_i L); one partly inside, by that times
    # its overlap in bin widths (the sphere's row rule, wear.arc_to_bins, on row 0)
    return arc_to_bins(wmap, j, 0, phi_c, half, vol / (2.0 * half * radius_length), nazim, 0.0)


@compiled
def contact(j, model, ball, socket, full, dg):
    """The bearing's action on the journal of revolute clearance joint j, as
    ``spherical.contact`` (``joints.PROTOCOL``): the journal centre (``ball``: its body's
    (rb, vb, Rb, wb) and the centre's body offset) in the bearing (``socket``: the
    ground's, all zero and unrotated, at O; the rod's at A, the slider's at B), composed
    by ``contact.respond`` with the journal's elastic law (:func:`journal_law`); with
    ``full`` the joint's contact state into dg, its joint force the contact force (the
    kernel completes it with the axial reaction)."""
    rb, vb, Rb, wb, ub = ball
    rs, vs, Rs, ws_, us = socket
    pb, _ = point_state(rb, vb, Rb, wb, ub)
    ps, _ = point_state(rs, vs, Rs, ws_, us)
    geo = bearing_gap(model.jp, j, model.wmap, model.p, pb, ps, Rs, model.s)
    c = compose(j, model, ball, socket, pb, ps, geo, elastic_law(model.p, j), full)
    if full:
        store_contact(dg, j, c)
        for i in range(3):
            dg[D_JOINT_FORCE + 3 * j + i] = c.force[i]
    return (c.force, body_moment(Rb, rb, c.q_ball, c.force),
            body_moment(Rs, rs, c.q_socket, c.force), c.diss_power)


#: (pi, False): the paper's slip rule is a sphere's; a bearing's sliding distance is the
#: slip times the step (``shared``).
paper_angle = shared.neutral_paper_angle


@compiled(inline="always")
def elastic_law(p, j):
    """The journal's elastic law (``joints.PROTOCOL``): :func:`journal_law`."""
    return journal_law(p)


@compiled(inline="always")
def wear_surface(jp, j, pen, e, n):
    """The strip a step wears (``joints.PROTOCOL``): its area 2 psi R_i L
    (:func:`contact_area`) [m^2], its depth projected about the bearing's axis (weights
    1, 0, 0), the scale R_i L [m^2]."""
    ri = jp[j, J_RI]
    area = contact_area(pen, e, ri, jp[j, J_RJ], jp[j, J_LENGTH])
    return area, 1.0, 0.0, 0.0, ri * jp[j, J_LENGTH]


@compiled(inline="always")
def cap_mergeable(j, d2, tol, area, scale):
    """Whether a direction d2 (squared) from the waiting strip's stays within tol of the
    strip's half-angle psi = A / (2 R_i L), ``scale`` = R_i L (``joints.PROTOCOL``)."""
    half = 0.5 * area / scale
    return d2 <= tol * tol * half * half


@compiled(inline="always")
def deposit_cap(wmap, j, n, vol, area, scale, scratch):
    """The waiting strip on the bearing's map (:func:`deposit`, ``scale`` = R_i L;
    ``scratch`` not read); the largest depth written [m] (``joints.PROTOCOL``)."""
    return deposit(wmap, j, n, vol, area, scale)


#: Nothing: the journal's step is the kernel's one-point rule (``rk4.accept_substep``);
#: False (``shared``).
accept = shared.neutral_accept
#: Nothing: the journal's wear waits as a strip (:func:`deposit_cap`); 0 (``shared``).
deposit_step = shared.neutral_deposit_step
#: -inf: the journal's one contact is the diagnostics' (``shared``).
penetration = shared.neutral_penetration


@compiled(inline="always")
def section_offsets(jp, j, d, rate):
    """The journal's section offset and its rate over the clearance c (``joints.PROTOCOL``;
    the axial part as the table's attachments give it), in the bearing's frame
    (:func:`to_bearing` of the socket body's ``d`` and ``rate``, as the gap's d_s): the
    one-point offsets (``shared.one_point_section_offsets``) there."""
    return shared.one_point_section_offsets(jp, j, to_bearing(j, d), to_bearing(j, rate))


#: A seated journal: its episode begins without an impact (``shared.one_point_seat``);
#: its slip angle stays pi; True.
seat = shared.one_point_seat


#: The journal's contact points, at R_j and R_i along the normal, rated in or near contact
#: (``shared``).
rate_point = shared.one_point_rate_point
#: The stiff rate of the journal's contact force on the mobility of its points, under its
#: own elastic law (``law``, :func:`elastic_law`; ``shared``).
force_rate = shared.one_point_force_rate
