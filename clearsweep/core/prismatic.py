"""The prismatic clearance joint: the slider's block in a guide with clearance
(docs/physics.md section 3.7, docs/modelling.md).

A joint type of the shape docs/architecture.md ("Joint types") describes, with one
difference: a block touches its guide along up to eight edge lines at once, not at one point
(its :func:`gap` is a slot's, k the slot).
The guide is fixed in the ground along the global x axis at the height z_s; its four walls
lie at y = +-(b + c_y) and z - z_s = +-(h + c_z), where the block (length 2a along the
guide, width 2b, height 2h) sits centred with the gaps c_y and c_z. The block slides along
x, moves across the guide (y, z) and tilts (its three angles) within its clearances.

Each of the block's eight corners faces one y wall and one z wall: 16 corner-wall pairs
("slots", k = 2 corner + 0 for the y wall, + 1 for the z wall). The block meets a wall with
the face that faces it, along the face's two long edges (docs/physics.md 3.7): each edge is
a line of the block's length between two corners (an "edge line", e = 2 wall + side), its
penetration linear between its corners' and its pressure per unit length
k_l max(delta, 0), the face an elastic foundation (k_l = E* sqrt(W / (pi L)),
:func:`line_stiffness`). Each corner takes its line's consistent nodal load
(:func:`line_load`) as its elastic force, with the case's damping law on the corner's own
impact velocity, and the improved Coulomb friction on the corner's slip over the wall
(along and across the guide). Every slot's force acts at its corner.

- :func:`gap`: a slot's wall, outward normal and penetration against the wall's worn
  position c + h, h read from the wall's wear map at the corner (its bin, or with
  ``wear.interpolate`` bilinearly, :func:`wall_read`, whose gradient tilts the corner's
  force onto the worn wall's normal: :func:`slot_force`);
- the wall maps: the joint's map rows split in four bands, one per wall (+y, -y, +z, -z),
  each ``npolar // 4`` rows across the wall by ``nazim`` columns along the guide
  (x from jp[J_X0] over jp[J_XSPAN]), each bin holding the depth worn over it:
  :func:`wall_bin`, :func:`wall_read`, :func:`track_width`, :func:`deposit`;
- :func:`contact`: the sum over the lines' corners (force, moment, dissipated power: the
  shape ``joints.PROTOCOL`` fixes, the guide's moment zero) and, at
  a step's end, the joint's diagnostics: those of the most deeply penetrating slot, the
  lines' total elastic energy, the guide's total force and the largest stiff rate of a slot;
- :func:`accept`: an accepted step's impacts (the joint's contact episodes) and the wear each
  line leaves on its wall's map (``rk4.accept_multi``), :func:`deposit_step` (:func:`deposit`)
  its spread once the step is accepted, :func:`seat` the slots of a seated start,
  :func:`penetration` each slot's penetration (the adaptive step's onset location), and
  :func:`section_offsets` the block's offset across its guide: the functions of
  ``joints.PROTOCOL`` that a multi-contact type (``CONTACTS`` = 16 slots) takes for
  itself; the one-point wear caps (:func:`wear_surface`, :func:`cap_mergeable`,
  :func:`deposit_cap`) and the paper's slip angle have nothing to do here.
"""

import math
from collections import namedtuple

from . import shared
from .compiled import compiled
from .contact import (
    contact_damping,
    episode_impact_velocity,
    friction_magnitude,
    stiff_rate,
    surface,
)
from .kinematics import add, cross, dot, mtv, mv, scale, sub
from .layout import (
    CAP_SLOT_ROW,
    D_CEFF,
    D_DDOT,
    D_DELTA,
    D_DFD,
    D_DFDD,
    D_ECC,
    D_FN,
    D_FT,
    D_HWEAR,
    D_JOINT_FORCE,
    D_NGLOBAL,
    D_NORMAL,
    D_OFFSET,
    D_PRATE,
    D_UEL,
    D_VT,
    D_WORN,
    J_BLOCK_LENGTH,
    J_C,
    J_COAT,
    J_CORNER_RADIUS,
    J_CY,
    J_CZ,
    J_HEIGHT,
    J_WIDTH,
    J_X0,
    J_XSPAN,
    M_IMPACTS,
    M_VIMP_MAX,
    N_CAP,
    P_AMPL,
    P_DT,
    P_DV0_MIN,
    P_FEEDBACK,
    P_FRICTION,
    P_INTERP,
    P_J4,
    P_M4,
    P_ONSET,
    P_SLOTS,
    P_V0,
    P_V1,
    P_WEAR,
    P_ZS,
    S_DV0,
    S_SLOT,
    W_SETTLED,
    W_WHOLE,
)
from .wear import coating_worn

#: The joint type this module implements (registered in ``joints.JOINT_TYPES``).
JOINT_TYPE = "prismatic"
#: Contact points of the joint (``joints.PROVIDES``): the 16 corner-wall slots.
CONTACTS = P_SLOTS

#: The guide's rotation: the global frame (``gap``'s Rs, not read).
IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

#: The guide's frame of the planar slider-crank (``jointset.guide_axis`` 1, its guide along
#: global y): the fixed rotation Q = Rz(-90 deg) that takes its guide to this module's
#: (along x), x' = y, y' = -x, z' = z, as a row-major 9-tuple. Its block's body frame is
#: turned likewise (its length along the guide): this module sees the block at
#: (Q r, Q v, Q R Q^T, Q w) (:func:`in_guide`) and its forces and moments come back by Q^T
#: (:func:`from_guide`). Its y walls (+y', -y': global -x, +x) face across the mechanism's
#: plane, its z walls (the upper and lower) within it.
PLANAR_GUIDE = (0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0)

#: Walls of the guide, in the order of their bands of the wear map.
WALLS = ("+y", "-y", "+z", "-z")

#: One corner-wall pair's contact (:func:`slot_state`; Numba compiles a namedtuple as a
#: tuple: fields are read by name at no cost). Vectors are 3-tuples, global frame unless
#: named ``_body``.
Slot = namedtuple("Slot", (
    "delta",        # penetration [m] (negative: a gap)
    "ddot",         # approach rate d delta / dt [m/s]
    "fn",           # normal force F_N [N]
    "fel",          # its elastic part [N]
    "dfd",          # dF_N / d delta [N/m]
    "dfdd",         # dF_N / d delta_dot [N s/m]
    "force",        # force on the block at the corner, normal and friction [N]
    "fnormal",      # its normal part (the force without friction) [N]
    "pdiss",        # power dissipated by the slot's damping and friction [W]
    "q",            # the corner [m]
    "n",            # the wall's outward normal
    "vt",           # the corner's slip velocity over the wall [m/s]
    "slip",         # its speed [m/s]
    "across",       # the corner's position across the wall [m]
    "worn",         # the wall's coating worn through under the corner
    "c_eff",        # local clearance c + h [m]
    "h",            # the wall's wear depth at the corner [m]
    "u_body",       # the corner in the block's frame [m]
))


@compiled(inline="always")
def to_guide(v):
    """Q v: a global vector (or the slider's body-frame one) in the slider-crank's guide
    frame (:data:`PLANAR_GUIDE`)."""
    return (v[1], -v[0], v[2])


@compiled(inline="always")
def from_guide(v):
    """Q^T v: a vector of the slider-crank's guide frame (:data:`PLANAR_GUIDE`) in global
    axes (or in the slider's body frame, for a moment)."""
    return (-v[1], v[0], v[2])


@compiled(inline="always")
def in_guide(body):
    """The slider-crank's block state (r, v, R, w) (global; R its rotation, w its body
    angular velocity) as this module's guide frame sees it (:data:`PLANAR_GUIDE`):
    (Q r, Q v, Q R Q^T, Q w)."""
    r, v, R, w = body
    return (to_guide(r), to_guide(v),
            (R[4], -R[3], R[5], -R[1], R[0], -R[2], R[7], -R[6], R[8]), to_guide(w))


@compiled(inline="always")
def face_width(jp, j, wall):
    """Width W [m] across the guide of the block's face that meets wall ``wall`` (0..3: +y,
    -y, +z, -z): the block's height for a y wall, its width for a z wall."""
    return jp[j, J_HEIGHT] if wall < 2 else jp[j, J_WIDTH]


@compiled
def line_stiffness(jp, j, wall, ew):
    """Stiffness k_l [N/m^2] per unit length of one of the two edge lines that carry the
    block's face on wall ``wall`` (docs/physics.md 3.7): the face is an elastic foundation
    of modulus k_f = 2 E* / sqrt(pi A) (A = L W, the face's area: a rigid flat punch of that
    area pressed into an elastic half-space, F = 2 a E* delta with pi a^2 = A), and each edge
    carries half the face's width, k_l = k_f W / 2 = E* sqrt(W / (pi L)); ``ew`` is E*."""
    return ew * math.sqrt(face_width(jp, j, wall) / (math.pi * jp[j, J_BLOCK_LENGTH]))


@compiled
def line_load(da, db, kl, length):
    """The elastic load of one edge line of length ``length`` [m] whose ends (corners) a and b
    penetrate their wall by da and db [m], the penetration linear along the edge and the
    pressure per unit length k_l max(delta, 0) (a linear foundation): (f_a, f_b, U), the
    forces [N] the line puts on its two ends (its consistent nodal loads: the same force and
    moment as the distributed load, and f_a = dU/d da, f_b = dU/d db) and its elastic energy
    U = k_l int max(delta, 0)^2 / 2 ds [J]. With both ends in contact,
    f_a = k_l L (2 da + db) / 6; with one, the part of the edge in contact is the fraction
    lam = da / (da - db) of its length at a's end and the load is a triangle on it."""
    kll = kl * length
    if da > 0.0 and db > 0.0:
        return (kll * (2.0 * da + db) / 6.0, kll * (da + 2.0 * db) / 6.0,
                kll * (da * da + da * db + db * db) / 6.0)
    if da > 0.0:
        lam = da / (da - db)
        f = 0.5 * kll * lam * da
        return f * (1.0 - lam / 3.0), f * lam / 3.0, kll * lam * da * da / 6.0
    if db > 0.0:
        lam = db / (db - da)
        f = 0.5 * kll * lam * db
        return f * lam / 3.0, f * (1.0 - lam / 3.0), kll * lam * db * db / 6.0
    return 0.0, 0.0, 0.0


@compiled(inline="always")
def line_slots(e):
    """The two slots (its back corner's, at -x, and its front corner's) of edge line e
    (0..7): wall e // 2 (+y, -y, +z, -z), the face's edge on the negative (e % 2 = 0) or
    positive side across the wall (z for a y wall, y for a z wall)."""
    wall = e // 2
    side = e % 2
    if wall < 2:
        corner = (2 if wall == 0 else 0) + (4 if side == 1 else 0)
        return 2 * corner, 2 * (corner + 1)
    corner = (4 if wall == 2 else 0) + (2 if side == 1 else 0)
    return 2 * corner + 1, 2 * (corner + 1) + 1


@compiled(inline="always")
def corner_sign(corner, bit):
    """+1 where the corner (0..7) lies on the positive side along the axis of ``bit`` (1: x,
    2: y, 4: z), else -1."""
    return 1.0 if corner & bit else -1.0


@compiled
def slot_corner(jp, j, k):
    """Slot k's corner u in the block's frame [m] (its centroid the origin)."""
    corner = k // 2
    return (0.5 * corner_sign(corner, 1) * jp[j, J_BLOCK_LENGTH],
            0.5 * corner_sign(corner, 2) * jp[j, J_WIDTH],
            0.5 * corner_sign(corner, 4) * jp[j, J_HEIGHT])


@compiled(inline="always")
def slot_wall(k):
    """Slot k's wall (0..3: +y, -y, +z, -z) and the side s = +-1 it faces: the corner's y
    wall for even k, its z wall for odd k."""
    if k % 2 == 0:
        s = corner_sign(k // 2, 2)
        return (0 if s > 0.0 else 1), s
    s = corner_sign(k // 2, 4)
    return (2 if s > 0.0 else 3), s


@compiled(inline="always")
def line_cell(e):
    """Where edge line e's step wear waits in ``cur`` (layout.CAP_SLOT_ROW): its row."""
    return CAP_SLOT_ROW + e


@compiled(inline="always")
def wall_half(jp, j, wall):
    """Half the extent [m] of wall ``wall`` across the guide: h + c_z for a y wall (its
    height), b + c_y for a z wall (its width)."""
    if wall < 2:
        return 0.5 * jp[j, J_HEIGHT] + jp[j, J_CZ]
    return 0.5 * jp[j, J_WIDTH] + jp[j, J_CY]


@compiled
def wall_bin(jp, j, wall, x, across, nrow, ncol):
    """(row, column) of the wear-map bin of wall ``wall`` (0..3: +y, -y, +z, -z) holding the
    point x [m] along the guide and ``across`` [m] across the wall (z - z_s on a y wall, y on
    a z wall); points beyond the map's ends fall in its end bins."""
    band = nrow // 4
    half = wall_half(jp, j, wall)
    col = int(math.floor((x - jp[j, J_X0]) / jp[j, J_XSPAN] * ncol))
    row = int(math.floor((across + half) / (2.0 * half) * band))
    return wall * band + min(max(row, 0), band - 1), min(max(col, 0), ncol - 1)


@compiled
def track_width(jp, j, wall, load, span, mean, other, ew):
    """Width w [m] across wall ``wall`` of the track an edge line wears: half the face's
    width W / 2 while the face's other edge line is in contact too (the face lies on the
    wall: each line carries a strip of half the face); with the other line lifted, the
    strip of the face that its tilt brings into the wall, W mean / (mean - other) (``mean``,
    ``other``: the two lines' mean penetrations [m]), at least the line contact's width
    2 b = 2 sqrt(4 P' r_c / (pi E*)) of the rounded edge (Johnson, Contact Mechanics, ch. 4:
    the load per unit length P' = ``load`` / ``span`` [N/m]) and at most W / 2. Continuous:
    the tilted strip is W / 2 when the other line touches."""
    half = 0.5 * face_width(jp, j, wall)
    if other >= 0.0:
        return half
    tilt = 2.0 * half * mean / (mean - other) if mean > 0.0 else 0.0
    line = 2.0 * math.sqrt(4.0 * load / max(span, 1e-300) * jp[j, J_CORNER_RADIUS] / (math.pi * ew))
    return min(max(tilt, line), half)


@compiled(inline="always")
def clamped_cell(u, n):
    """(i, f, clamped) of the coordinate u [bins, 0 at the first bin's centre] among n bin
    centres: u lies between centres i and i + 1 at the fraction f; beyond the first or the
    last centre it is held there (f = 0, ``clamped``)."""
    i = int(math.floor(u))
    if i < 0:
        return 0, 0.0, True
    if i >= n - 1:
        return n - 1, 0.0, True
    return i, u - i, False


@compiled
def wall_read(wmap, j, jp, wall, x, across):
    """Depth h [m] of wall ``wall``'s map (0..3: +y, -y, +z, -z) at x [m] along the guide and
    ``across`` [m] across the wall, bilinear between the bin centres of the wall's band (held
    at the band's first and last centres across the wall and at the map's ends along it:
    never read from the neighbouring wall's band); and its gradient (dh/dx, dh/d across)
    [-], zero along a direction where the read is held."""
    band = wmap.shape[1] // 4
    ncol = wmap.shape[2]
    half = wall_half(jp, j, wall)
    c0, fx, held_x = clamped_cell((x - jp[j, J_X0]) / jp[j, J_XSPAN] * ncol - 0.5, ncol)
    r0, fa, held_a = clamped_cell((across + half) / (2.0 * half) * band - 0.5, band)
    c1 = min(c0 + 1, ncol - 1)
    r1 = wall * band + min(r0 + 1, band - 1)
    r0 += wall * band
    w00 = wmap[j, r0, c0]
    w01 = wmap[j, r0, c1]
    w10 = wmap[j, r1, c0]
    w11 = wmap[j, r1, c1]
    h = (1.0 - fa) * ((1.0 - fx) * w00 + fx * w01) + fa * ((1.0 - fx) * w10 + fx * w11)
    dh_dx = 0.0
    dh_da = 0.0
    if not held_x:
        dh_dx = ((1.0 - fa) * (w01 - w00) + fa * (w11 - w10)) * ncol / jp[j, J_XSPAN]
    if not held_a:
        dh_da = ((1.0 - fx) * (w10 - w00) + fx * (w11 - w01)) * band / (2.0 * half)
    return h, dh_dx, dh_da


@compiled
def gap(jp, j, wmap, p, k, pb, ps, Rs):
    """Gap geometry of slot k of prismatic joint j with its corner at the global point pb,
    ps the point of the guide's axis abreast of it, (x, 0, z_s): (e, n, d_s, n_s, h, slope,
    worn, c_eff, delta) as ``spherical.gap`` (``joints.PROTOCOL``; the guide's frame is the
    global frame, Rs is not read): e [m] the corner's distance beyond the block's nominal
    face along the wall's outward unit normal n, d_s = (0, y, z - z_s) the corner's offset
    from the guide's axis [m] (its position across the wall: z - z_s on a y wall, y on a z
    wall, :func:`across_wall`), n_s = n, the wall's wear depth there h [m] (0 without
    feedback; the bin's, or with ``wear.interpolate`` the bilinear read of
    :func:`wall_read`), h's gradient with respect to the corner (global, tangent to the
    wall; zero for the bin read), whether the wall's coating is worn through in the bin
    under the corner, the local clearance c_eff = c + h and the penetration
    delta = e - c - h [m] (negative: a gap), whose gradient with respect to the corner is
    n - slope: the worn wall's normal."""
    wall, s = slot_wall(k)
    d = (0.0, pb[1] - ps[1], pb[2] - ps[2])
    if wall < 2:
        n = (0.0, s, 0.0)
        out = s * d[1] - 0.5 * jp[j, J_WIDTH]
        c = jp[j, J_CY]
        across = d[2]
    else:
        n = (0.0, 0.0, s)
        out = s * d[2] - 0.5 * jp[j, J_HEIGHT]
        c = jp[j, J_CZ]
        across = d[1]
    feedback = p[P_FEEDBACK] != 0.0
    binned = feedback and p[P_INTERP] == 0.0
    coat = jp[j, J_COAT]
    h = 0.0
    slope = (0.0, 0.0, 0.0)
    worn = False
    if feedback and not binned:
        h, dh_dx, dh_da = wall_read(wmap, j, jp, wall, pb[0], across)
        slope = (dh_dx, 0.0, dh_da) if wall < 2 else (dh_dx, dh_da, 0.0)
    if binned or coat < math.inf:
        row, col = wall_bin(jp, j, wall, pb[0], across, wmap.shape[1], wmap.shape[2])
        depth = wmap[j, row, col]
        if binned:
            h = depth
        worn = coat < math.inf and coating_worn(depth, coat)
    return out, n, d, n, h, slope, worn, c + h, out - c - h


@compiled(inline="always")
def across_wall(k, d_s):
    """Slot k's corner's position across its wall [m] from its offset d_s = (0, y, z - z_s)
    from the guide's axis (:func:`gap`): z - z_s on a y wall, y on a z wall."""
    wall, _ = slot_wall(k)
    return d_s[2] if wall < 2 else d_s[1]


@compiled(inline="always")
def guide_point(p, q):
    """The point (x, 0, z_s) of the guide's axis abreast of the global point q: the
    socket's point that :func:`gap` measures a corner from."""
    return (q[0], 0.0, p[P_ZS])


@compiled
def corner_mobility(p, u, nb):
    """Inverse mass [1/kg] of the block's motion at body point u along the body-frame unit
    vector nb, the block alone (its centroid free, its rotation free): 1/m4 +
    (u x nb)^T J4^-1 (u x nb). The rod that joint B ties to the block only adds mass, so this
    bounds the mechanism's value from above (a stiff rate at least as fast)."""
    a = cross(u, nb)
    return (1.0 / p[P_M4] + a[0] * a[0] / p[P_J4] + a[1] * a[1] / p[P_J4 + 1]
            + a[2] * a[2] / p[P_J4 + 2])


#: One slot's geometry and kinematics (:func:`slot_geometry`), before any force.
Geo = namedtuple("Geo", (
    "delta", "ddot", "q", "n", "vt", "slip", "across", "worn", "c_eff", "h", "u", "slope",
    "hdot", "sloped",
))


@compiled
def slot_geometry(j, model, k, slider):
    """Slot k's :data:`Geo`: its corner q, the wall's normal, the penetration delta and its
    rate delta_dot (on a sloped worn wall, m . v_q with m = n - slope the worn wall's normal:
    the slope's rate s . v_q is ``hdot``), the corner's slip over the wall."""
    p = model.p
    jp = model.jp
    r4, v4, R4, w4 = slider
    u = slot_corner(jp, j, k)
    q = add(r4, mv(R4, u))
    _, n, d_s, _, h, slope, worn, c_eff, delta = gap(jp, j, model.wmap, p, k, q,
                                                     guide_point(p, q), IDENTITY)
    across = across_wall(k, d_s)
    vq = add(v4, mv(R4, cross(w4, u)))
    sloped = slope[0] != 0.0 or slope[1] != 0.0 or slope[2] != 0.0
    hdot = 0.0
    if sloped:
        hdot = dot(slope, vq)
        vn = dot(n, vq)
        ddot = vn - hdot
        vt = sub(vq, scale(vn, n))
    else:
        ddot = dot(n, vq)
        vt = sub(vq, scale(ddot, n))
    slip = math.sqrt(dot(vt, vt))
    return Geo(delta, ddot, q, n, vt, slip, across, worn, c_eff, h, u, slope, hdot, sloped)


@compiled
def slot_force(j, model, k, g, fel, stiff):
    """Slot k's contact, a :data:`Slot`, from its geometry g (:func:`slot_geometry`) and the
    elastic load ``fel`` [N] its edge line puts on its corner (:func:`line_load`; 0: the line
    is not in contact); ``stiff`` [N/m] the line's k_l L / 2, which bounds dF_el / d delta
    at the corner (its row of the line's stiffness, k_l L / 3 + k_l L / 6 with both ends in).

    The normal force F_N = F_el (1 + kappa delta_dot) (clamped at 0) carries the case's
    damping law on the corner's own approach rate and episode impact velocity. The line's
    potential depends on the penetrations alone, so on a sloped worn wall the corner's
    normal force is -F_N m, m = n - slope (docs/physics.md 3.5, 3.7): the guide does not
    move, so its power is exactly -F_N delta_dot with delta_dot = m . v_q, of which
    (F_N - F_el) delta_dot is booked as dissipated. Friction stays tangent to the wall,
    against the corner's slip over it (the improved Coulomb law on F_N): its power is its
    dot product with that slip whatever the normal force's direction."""
    p = model.p
    jp = model.jp
    zero = (0.0, 0.0, 0.0)
    if not fel > 0.0:
        return Slot(g.delta, g.ddot, 0.0, 0.0, 0.0, 0.0, zero, zero, 0.0, g.q, g.n, g.vt,
                    g.slip, g.across, g.worn, g.c_eff, g.h, g.u)
    ew, mu, _ = surface(jp, j, g.worn)
    kappa = contact_damping(model.s[j, S_SLOT + k], g.ddot, p)
    fac = 1.0 + kappa * g.ddot
    fn = fel * fac
    dfd = stiff * fac
    dfdd = kappa * fel
    if fn < 0.0:
        fn = 0.0
        dfd = 0.0
        dfdd = 0.0
    if g.sloped:
        fnormal = add(scale(-fn, g.n), scale(fn, g.slope))
    else:
        fnormal = scale(-fn, g.n)
    pdiss = (fn - fel) * g.ddot
    force = fnormal
    if p[P_FRICTION] != 0.0 and g.slip > 0.0:
        ft = friction_magnitude(mu, fn, g.slip, p[P_V0], p[P_V1])
        force = add(force, scale(-ft / g.slip, g.vt))
    # friction: its work on the corner's slip
    pdiss -= dot(sub(force, fnormal), g.vt)
    return Slot(g.delta, g.ddot, fn, fel, dfd, dfdd, force, fnormal, pdiss, g.q, g.n, g.vt,
                g.slip, g.across, g.worn, g.c_eff, g.h, g.u)


@compiled
def line_state(j, model, e, slider):
    """Edge line e's two corners (:func:`line_slots`): (their geometries, their elastic
    loads f_a, f_b and the line's elastic energy U, :func:`line_loads`)."""
    ka, kb = line_slots(e)
    ga = slot_geometry(j, model, ka, slider)
    gb = slot_geometry(j, model, kb, slider)
    fa, fb, uel = line_loads(model.jp, j, e, ga.delta, gb.delta, ga.worn, gb.worn)
    return ga, gb, fa, fb, uel


@compiled
def line_loads(jp, j, e, da, db, worn_a, worn_b):
    """Edge line e's elastic loads on its corners and its energy (f_a, f_b, U,
    :func:`line_load`) from its corners' penetrations da, db [m] and whether the wall's
    coating is worn through under each: the line's modulus is its deeper corner's surface
    (coated, or the base where the coating is worn through)."""
    if not (da > 0.0 or db > 0.0):
        return 0.0, 0.0, 0.0
    ew, _, _ = surface(jp, j, worn_a if da >= db else worn_b)
    return line_load(da, db, line_stiffness(jp, j, e // 2, ew), jp[j, J_BLOCK_LENGTH])


@compiled
def edge_loads(j, model, e, slider):
    """Edge line e's loads and energy (f_a, f_b, U), as :func:`line_state` gives them,
    keeping of its corners' geometries only their penetrations and worn flags.
    :func:`contact` then forms each loaded corner's geometry again, one corner at a time:
    with both corners' geometries held through the corners' forces, the device build's
    spill stores doubled (issue 43, benchmarks/README.md)."""
    ka, kb = line_slots(e)
    ga = slot_geometry(j, model, ka, slider)
    da = ga.delta
    worn_a = ga.worn
    gb = slot_geometry(j, model, kb, slider)
    return line_loads(model.jp, j, e, da, gb.delta, worn_a, gb.worn)


@compiled
def line_deltas(j, model, e, slider):
    """The penetrations [m] of edge line e's two corners (:func:`line_slots`), as
    :func:`slot_geometry` gives them: what :func:`accept` reads of a face's other line,
    formed where a line wears instead of holding both lines' geometries through the wall's
    corners (the device build's spill stores, issue 43)."""
    ka, kb = line_slots(e)
    return (slot_geometry(j, model, ka, slider).delta,
            slot_geometry(j, model, kb, slider).delta)


@compiled
def line_stiff(jp, j, e, worn):
    """k_l L / 2 [N/m] of edge line e (:func:`slot_force`'s ``stiff``)."""
    ew, _, _ = surface(jp, j, worn)
    return 0.5 * line_stiffness(jp, j, e // 2, ew) * jp[j, J_BLOCK_LENGTH]


@compiled
def slot_state(j, model, k, slider):
    """Slot k's contact, a :data:`Slot` (its edge line evaluated whole, :func:`line_state`).
    ``slider``: the block's body state (r, v, R, w)."""
    e = slot_line(k)
    ga, gb, fa, fb, _ = line_state(j, model, e, slider)
    ka, _ = line_slots(e)
    if k == ka:
        return slot_force(j, model, k, ga, fa, line_stiff(model.jp, j, e, ga.worn))
    return slot_force(j, model, k, gb, fb, line_stiff(model.jp, j, e, gb.worn))


@compiled(inline="always")
def slot_line(k):
    """The edge line (0..7, :func:`line_slots`) that slot k ends: its wall and the side of
    the face its corner lies on across the wall."""
    wall, _ = slot_wall(k)
    corner = k // 2
    bit = 4 if k % 2 == 0 else 2
    return 2 * wall + (1 if corner & bit else 0)


@compiled
def slot_rate(j, model, k, st, R4):
    """Largest stiff rate [1/s] of slot k in contact or closing within one output step
    (docs/physics.md section 4), from the block's mobility at the corner
    (:func:`corner_mobility`) and the line's stiffness bound k_l L / 2 at the corner; a
    closing corner's damping from the penetration it can reach by energy; 0 for a slot that
    stays open. ``st``: :func:`slot_state`."""
    p = model.p
    jp = model.jp
    delta = st.delta
    ddot = st.ddot
    u = st.u_body
    if not (st.fel > 0.0 or delta > 0.0 or delta + ddot * p[P_DT] > 0.0):
        return 0.0
    m_eff = 1.0 / corner_mobility(p, u, mtv(R4, st.n))
    stiff = line_stiff(jp, j, slot_line(k), st.worn)
    rate = stiff_rate(m_eff, max(st.dfd, stiff), st.dfdd)
    ew, mu, _ = surface(jp, j, st.worn)
    if ddot > 0.0:
        # the depth an approach at ddot reaches on the line's stiffness at the corner
        dpred = math.sqrt(max(delta, 0.0) ** 2 + m_eff * ddot * ddot / stiff)
        kappa = contact_damping(model.s[j, S_SLOT + k], ddot, p)
        rate = max(rate, stiff_rate(m_eff, stiff * (1.0 + kappa * ddot), kappa * stiff * dpred))
    if p[P_FRICTION] != 0.0 and mu > 0.0 and st.fn > 0.0:
        # the tangential inverse mass, bounded by the largest over directions
        jmin = min(p[P_J4], min(p[P_J4 + 1], p[P_J4 + 2]))
        inv_t = 1.0 / p[P_M4] + dot(u, u) / jmin
        slope = 1.0 / (p[P_V1] - p[P_V0]) if st.slip < p[P_V1] else 1.0 / st.slip
        rate = max(rate, mu * st.fn * slope * inv_t)
    return rate


@compiled
def contact(j, model, ball, socket, full, dg):
    """The guide's action on the block of prismatic joint j (``joints.PROTOCOL``): (force
    [N], moment about the block's centroid in the block's frame [N m], the moment of the
    opposite force on the guide (the ground: zero), power dissipated by damping and
    friction [W]), summed over the eight edge lines' corners. ``ball``: the block's body
    state (r, v, R, w) and its centroid's offset (zero, not read); ``socket``: the ground's
    (not read: the guide is fixed along the global x axis at z_s).

    With ``full`` (a step's end), joint j's diagnostics into dg: the contact values of the
    slot that penetrates deepest (or, with none in contact, of the one nearest to contact),
    the block's offset (0, y, z - z_s) from the guide's axis, the elastic energy of all
    lines, the guide's total force on the block and the largest stiff rate of a slot
    (D_PRATE)."""
    p = model.p
    jp = model.jp
    r4, v4, R4, w4, _ = ball
    slider = (r4, v4, R4, w4)
    force = (0.0, 0.0, 0.0)
    moment = (0.0, 0.0, 0.0)
    pdiss = 0.0
    uel = 0.0
    rate = 0.0
    best = -math.inf
    for e in range(P_SLOTS // 2):
        fa, fb, ue = edge_loads(j, model, e, slider)
        ka, kb = line_slots(e)
        if not (fa > 0.0 or fb > 0.0 or full):
            continue
        uel += ue
        for end in range(2):
            fel = fa if end == 0 else fb
            if not (fel > 0.0 or full):
                continue
            k = ka if end == 0 else kb
            g = slot_geometry(j, model, k, slider)
            st = slot_force(j, model, k, g, fel, line_stiff(jp, j, e, g.worn))
            if full:
                rate = max(rate, slot_rate(j, model, k, st, R4))
                if st.delta > best:
                    best = st.delta
                    store_slot(dg, j, st)
            if not st.fel > 0.0:
                continue
            f = st.force
            force = add(force, f)
            moment = add(moment, cross(st.u_body, mtv(R4, f)))
            pdiss += st.pdiss
    if full:
        dg[D_UEL + j] = uel
        dg[D_PRATE] = rate
        dg[D_ECC + j] = math.sqrt(r4[1] * r4[1] + (r4[2] - p[P_ZS]) * (r4[2] - p[P_ZS]))
        dg[D_OFFSET + 3 * j] = 0.0
        dg[D_OFFSET + 3 * j + 1] = r4[1]
        dg[D_OFFSET + 3 * j + 2] = r4[2] - p[P_ZS]
        for i in range(3):
            dg[D_JOINT_FORCE + 3 * j + i] = force[i]
    return force, moment, (0.0, 0.0, 0.0), pdiss


@compiled
def store_slot(dg, j, st):
    """Joint j's per-joint contact diagnostics from one slot's :func:`slot_state`."""
    dg[D_FN + j] = st.fn
    ft = sub(st.force, st.fnormal)     # the friction force
    dg[D_FT + j] = math.sqrt(dot(ft, ft))
    dg[D_DELTA + j] = st.delta
    dg[D_DDOT + j] = st.ddot
    dg[D_VT + j] = st.slip
    dg[D_CEFF + j] = st.c_eff
    dg[D_HWEAR + j] = st.h
    dg[D_DFD + j] = st.dfd
    dg[D_DFDD + j] = st.dfdd
    dg[D_WORN + j] = 1.0 if st.worn else 0.0
    for i in range(3):
        dg[D_NORMAL + 3 * j + i] = st.n[i]
        dg[D_NGLOBAL + 3 * j + i] = st.n[i]


@compiled
def seat(j, model, dg, body):
    """A seated start's slots (``joints.PROTOCOL``; ``body``: the block's state (r, v, R,
    w), dg not read): each corner that an edge line in contact loads begins its episode
    without an impact (impact velocity at the floor), and so does the joint's. True."""
    slider = body
    p = model.p
    s = model.s
    touching = False
    for e in range(P_SLOTS // 2):
        ga, gb, fa, fb, _ = line_state(j, model, e, slider)
        ka, kb = line_slots(e)
        s[j, S_SLOT + ka] = (episode_impact_velocity(0.0, ga.ddot, p[P_DV0_MIN], False)
                             if fa > 0.0 else 0.0)
        s[j, S_SLOT + kb] = (episode_impact_velocity(0.0, gb.ddot, p[P_DV0_MIN], False)
                             if fb > 0.0 else 0.0)
        touching = touching or fa > 0.0 or fb > 0.0
    s[j, S_DV0] = 1.0 if touching else 0.0
    return True


@compiled
def accept(j, model, body, hs, in_settled, stats, cur):
    """An accepted (sub-)step of length hs ends with the block in state ``body`` (r, v, R,
    w) (``joints.PROTOCOL``).

    Impacts (docs/physics.md 3.7): the joint's contact episode starts when the block goes
    from touching no wall to touching one (a corner beyond its wall): that onset is one
    impact of the joint, counted with the fastest approach rate among the corners its
    lines then load. Each corner keeps its own episode impact velocity for its damping
    (``contact.episode_impact_velocity``) while its line loads it.

    Wear: Archard's V = k F_N |v_t| hs at each loaded corner, summed per edge line into
    ``cur``'s line row (:func:`line_cell`): V, and V times the load's centroid along the
    guide, the ends of the part of the edge in contact, the edge's position across the wall
    and the track's width (:func:`track_width`); spread on the wall's map once the step is
    accepted (:func:`deposit`). V also into ``cur[j, 0]`` (the joint's own row).

    Returns whether a slot's episode state changed (the step-end evaluation must be redone).
    """
    slider = body
    p = model.p
    jp = model.jp
    s = model.s
    changed = False
    wear_on = p[P_WEAR] != 0.0
    any_contact = False
    vimp = 0.0
    length = jp[j, J_BLOCK_LENGTH]
    for e in range(P_SLOTS // 2):
        wall = e // 2
        ga, gb, fa, fb, _ = line_state(j, model, e, slider)
        ka, kb = line_slots(e)
        vol_line = 0.0
        for end in range(2):
            k = ka if end == 0 else kb
            g = ga if end == 0 else gb
            fel = fa if end == 0 else fb
            at = S_SLOT + k
            if fel > 0.0:
                st = slot_force(j, model, k, g, fel, line_stiff(jp, j, e, g.worn))
                any_contact = True
                vimp = max(vimp, g.ddot)
                if wear_on and st.fn > 0.0:
                    _, _, k_wear = surface(jp, j, g.worn)
                    vol = p[P_AMPL] * k_wear * st.fn * g.slip * hs
                    vol_line += vol
                    row = line_cell(e)
                    cur[row, 1] += vol * g.q[0]
                    cur[j, 0] += vol
                dv0 = episode_impact_velocity(s[j, at], g.ddot, p[P_DV0_MIN],
                                              p[P_ONSET] != 0.0)
                if dv0 != s[j, at]:
                    changed = True
                s[j, at] = dv0
            elif s[j, at] != 0.0:
                s[j, at] = 0.0
                changed = True
        if vol_line > 0.0:
            # the part of the edge in contact, from the corner(s) beyond the wall
            xa = ga.q[0]
            xb = gb.q[0]
            if ga.delta > 0.0 and gb.delta > 0.0:
                x0, x1 = xa, xb
            elif ga.delta > 0.0:
                x0, x1 = xa, xa + (xb - xa) * ga.delta / (ga.delta - gb.delta)
            else:
                x0, x1 = xb + (xa - xb) * gb.delta / (gb.delta - ga.delta), xb
            ew, _, _ = surface(jp, j, ga.worn)
            span = abs(x1 - x0)
            mean = 0.5 * (ga.delta + gb.delta)
            # the face's other edge line: its corners' penetrations
            oa, ob = line_deltas(j, model, e ^ 1, slider)
            other = 0.5 * (oa + ob)
            if oa > 0.0 or ob > 0.0:
                other = max(other, 0.0)
            width = track_width(jp, j, wall, fa + fb, max(span, 1e-3 * length),
                                max(mean, max(ga.delta, gb.delta)), other, ew)
            row = line_cell(e)
            cur[row, 0] += vol_line
            cur[row, 2] += vol_line * x0
            cur[row, 3] += vol_line * x1
            cur[row, 4] += vol_line * 0.5 * (ga.across + gb.across)
            cur[row, 5] += vol_line * width
    if any_contact and s[j, S_DV0] == 0.0:
        # the joint's contact episode begins: one impact
        changed = True
        stats[W_WHOLE, M_IMPACTS + j] += 1.0
        stats[W_WHOLE, M_VIMP_MAX + j] = max(stats[W_WHOLE, M_VIMP_MAX + j], vimp)
        if in_settled:
            stats[W_SETTLED, M_IMPACTS + j] += 1.0
            stats[W_SETTLED, M_VIMP_MAX + j] = max(stats[W_SETTLED, M_VIMP_MAX + j], vimp)
    s[j, S_DV0] = 1.0 if any_contact else 0.0
    return changed


@compiled(inline="always")
def overlap_linear(lo, hi, x0, x1, a0, slope):
    """Integral over [lo, hi] intersected with [x0, x1] of the density a0 + slope (x - x0)."""
    lo = max(lo, x0)
    hi = min(hi, x1)
    if hi <= lo:
        return 0.0
    return a0 * (hi - lo) + 0.5 * slope * ((hi - x0) ** 2 - (lo - x0) ** 2)


@compiled
def deposit(wmap, j, jp, cur, wvol):
    """Spread joint j's accepted step wear on its wall maps (docs/physics.md 5.7): each
    edge line's volume V (``cur``'s line rows, :func:`accept`) over the track it wore, a
    rectangle of the wall: along the guide the part of the edge in contact [x0, x1] with a
    density linear along it whose centroid is the load's (the corners' forces are the line
    load's consistent nodal loads), across the wall the track's width w from the edge
    inward. Each bin deepens by the volume over it divided by its area: the depth Archard's
    k p s leaves where the track covers whole bins, and the same volume wherever the map's
    bins are finer or coarser. The step's volume (``cur[j, 0]``) adds to the worn volume
    ``wvol[j]``; both are cleared. Returns the largest depth of a bin written [m]."""
    nrow = wmap.shape[1]
    ncol = wmap.shape[2]
    band = nrow // 4
    blen = jp[j, J_XSPAN] / ncol
    top = 0.0
    for e in range(P_SLOTS // 2):
        row = line_cell(e)
        vol = cur[row, 0]
        if vol > 0.0:
            wall = e // 2
            half = wall_half(jp, j, wall)
            bhgt = 2.0 * half / band
            xc = cur[row, 1] / vol
            x0 = cur[row, 2] / vol
            x1 = cur[row, 3] / vol
            if x1 < x0:
                x0, x1 = x1, x0
            edge = cur[row, 4] / vol
            width = cur[row, 5] / vol
            a0 = edge - width if e % 2 == 1 else edge
            a1 = a0 + width
            span = x1 - x0
            if span <= 1e-12 * blen:
                # a point: its bin along the guide
                x0 = xc - 0.5e-12 * blen
                x1 = xc + 0.5e-12 * blen
                span = x1 - x0
            # the linear density over [x0, x1] with unit integral and centroid xc (held within
            # the middle third, where such a density is nowhere negative)
            mid = 0.5 * (x0 + x1)
            off = min(max(xc - mid, -span / 6.0), span / 6.0)
            slope = 12.0 * off / span ** 3
            dens0 = 1.0 / span - 0.5 * slope * span
            c0 = min(max(int(math.floor((x0 - jp[j, J_X0]) / blen)), 0), ncol - 1)
            c1 = min(max(int(math.floor((x1 - jp[j, J_X0]) / blen)), 0), ncol - 1)
            r0 = min(max(int(math.floor((a0 + half) / bhgt)), 0), band - 1)
            r1 = min(max(int(math.floor((a1 + half) / bhgt)), 0), band - 1)
            for c in range(c0, c1 + 1):
                lo = jp[j, J_X0] + c * blen if c > 0 else -math.inf
                hi = jp[j, J_X0] + (c + 1) * blen if c < ncol - 1 else math.inf
                fx = overlap_linear(lo, hi, x0, x1, dens0, slope)
                if fx <= 0.0:
                    continue
                for r in range(r0, r1 + 1):
                    blo = -half + r * bhgt if r > 0 else -math.inf
                    bhi = -half + (r + 1) * bhgt if r < band - 1 else math.inf
                    fa = (min(bhi, a1) - max(blo, a0)) / width if width > 0.0 else 1.0
                    if fa <= 0.0:
                        continue
                    at = wall * band + r
                    wmap[j, at, c] += vol * fx * fa / (blen * bhgt)
                    top = max(top, wmap[j, at, c])
        for i in range(N_CAP):
            cur[row, i] = 0.0
    wvol[j] += cur[j, 0]
    cur[j, 0] = 0.0
    return top


@compiled(inline="always")
def deposit_step(wmap, j, jp, cur, wvol):
    """The accepted step's wear on the wall maps (:func:`deposit`); the largest depth
    written [m] (``joints.PROTOCOL``)."""
    return deposit(wmap, j, jp, cur, wvol)


@compiled(inline="always")
def penetration(j, model, k, body):
    """Slot k's penetration [m] with the block at the state ``body`` (:func:`slot_state`;
    ``joints.PROTOCOL``)."""
    return slot_state(j, model, k, body).delta


@compiled(inline="always")
def section_offsets(jp, j, d, rate):
    """The block's section offset and its rate across its guide, over each direction's
    clearance c_y, c_z; along the guide, where the block is free, 0 over c
    (``joints.PROTOCOL``)."""
    c = jp[j, J_C]
    cy = jp[j, J_CY]
    cz = jp[j, J_CZ]
    return (0.0 / c, d[1] / cy, d[2] / cz), (0.0 / c, rate[1] / cy, rate[2] / cz)


#: The case's elastic law, never read: the walls' force is the lines' own
#: (:func:`line_load`; ``shared``).
elastic_law = shared.case_elastic_law
#: (pi, False): the slots' wear is :func:`accept`'s (``shared``).
paper_angle = shared.neutral_paper_angle
#: Zeros: the slots' wear is :func:`accept`'s (``shared``).
wear_surface = shared.neutral_wear_surface
#: False: the walls' wear waits per edge line, not as a cap (``shared``).
cap_mergeable = shared.neutral_cap_mergeable
#: 0: the walls' wear is :func:`deposit_step`'s (``shared``).
deposit_cap = shared.neutral_deposit_cap


@compiled(inline="always")
def rate_point(j, model, dg):
    """(True, False, zero, zero): the guide's stiff rate is its corners' own, always due,
    on no mobility of the kernel's (``joints.PROTOCOL``; :func:`force_rate`)."""
    zero = (0.0, 0.0, 0.0)
    return True, False, zero, zero


@compiled(inline="always")
def force_rate(j, model, dg, wp, y, law):
    """The largest stiff rate [1/s] of the corners' slots at the step's end, which
    :func:`contact` stored with ``full`` (dg[D_PRATE], :func:`slot_rate` on each corner's
    own mobility; ``joints.PROTOCOL``: wp, y and law not read)."""
    return dg[D_PRATE]
