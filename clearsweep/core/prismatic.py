"""The prismatic clearance joint: the slider's block in a guide with clearance
(docs/physics.md section 3.7, docs/modelling.md).

A joint type of the shape docs/architecture.md ("Joint types") describes, with one
difference: a block touches its guide at up to eight corners at once, not at one point.
The guide is fixed in the ground along the global x axis at the height z_s; its four walls
lie at y = +-(b + c_y) and z - z_s = +-(h + c_z), where the block (length 2a along the
guide, width 2b, height 2h) sits centred with the gaps c_y and c_z. The block slides along
x, moves across the guide (y, z) and tilts (its three angles) within its clearances.

Each of the block's eight corners faces one y wall and one z wall: 16 corner-wall pairs
("slots", k = 2 corner + 0 for the y wall, + 1 for the z wall). A slot is in contact where
its corner lies beyond its wall; its force is the contact law of a rounded corner of edge
radius r_c on a flat wall, F_el = K delta^n with K = 4 E* sqrt(r_c) / 3 (Hertz's modulus E*,
``params.hertz_modulus``) and n = 3/2 (Hertz; the case's exponent under
``contact.elastic: hertz``), with the case's damping law on the
slot's own impact velocity, and the improved Coulomb friction on the corner's slip over the
wall (along and across the guide). Every slot's force acts at its corner.

- :func:`gap`: a slot's wall, outward normal and penetration against the wall's worn
  position c + h, h read from the wall's wear map at the corner (its bin, or with
  ``wear.interpolate`` bilinearly, :func:`wall_read`, whose gradient tilts the corner's
  force onto the worn wall's normal: :func:`slot_state`);
- the wall maps: the joint's map rows split in four bands, one per wall (+y, -y, +z, -z),
  each ``npolar // 4`` rows across the wall by ``nazim`` columns along the guide
  (x from jp[J_X0] over jp[J_XSPAN]), each bin holding the depth of the corners' track
  over it: :func:`wall_bin`, :func:`wall_read`, :func:`track_width`, :func:`deposit`;
- :func:`contact`: the sum over the slots (force, moment, dissipated power) and, at a
  step's end, the joint's diagnostics: those of the most deeply penetrating slot, the
  total elastic energy, the guide's total force and the largest stiff rate of a slot;
- :func:`accept`: an accepted step's corner impacts and the wear each slot leaves on its
  wall's map (``rk4.accept_substep``), :func:`seat` the slots of a seated start;
- :func:`contact_angle`, :func:`contact_area`: the Hertz patch of a rounded corner,
  a = sqrt(r_c delta).
"""

import math
from collections import namedtuple

from .compiled import compiled
from .contact import (
    contact_damping,
    elastic_energy,
    episode_impact_velocity,
    friction_magnitude,
    normal_force,
    reachable_penetration,
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
    J_COAT,
    J_CY,
    J_CZ,
    J_HEIGHT,
    J_LENGTH,
    J_RI,
    J_WIDTH,
    J_X0,
    J_XSPAN,
    M_IMPACTS,
    M_VIMP_MAX,
    P_AMPL,
    P_DT,
    P_DV0_MIN,
    P_EXPONENT,
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

#: The corners' elastic exponent where the case keeps the paper's (spherical) law: Hertz's
#: point contact of a rounded corner on a flat wall.
CORNER_EXPONENT = 1.5

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


@compiled
def corner_law(p):
    """The exponent n of a corner's power law: the case's Hertz exponent under
    ``contact.elastic: hertz``, else :data:`CORNER_EXPONENT`."""
    law = p[P_EXPONENT]
    return law if law != 0.0 else CORNER_EXPONENT


@compiled(inline="always")
def corner_sign(corner, bit):
    """+1 where the corner (0..7) lies on the positive side along the axis of ``bit`` (1: x,
    2: y, 4: z), else -1."""
    return 1.0 if corner & bit else -1.0


@compiled
def slot_corner(jp, j, k):
    """Slot k's corner u in the block's frame [m] (its centroid the origin)."""
    corner = k // 2
    return (0.5 * corner_sign(corner, 1) * jp[j, J_LENGTH],
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
def slot_cell(k):
    """Where slot k's step wear waits in ``cur`` (layout.CAP_SLOT_ROW): (row, first column)."""
    return CAP_SLOT_ROW + k // 2, 3 * (k % 2)


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
def track_width(jp, j, wall, delta, nrow):
    """Width w [m] across wall ``wall`` of the track a corner wears at penetration
    ``delta`` (> 0): its Hertz patch 2 a = 2 sqrt(r_c delta), at most a bin's extent
    across the wall (``nrow`` the map's rows; a wider patch spreads over the bin)."""
    return min(2.0 * math.sqrt(jp[j, J_RI] * delta), 2.0 * wall_half(jp, j, wall) / (nrow // 4))


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
def gap(jp, j, wmap, p, k, q):
    """Gap geometry of slot k of prismatic joint j with its corner at the global point q:
    (n, across, h, slope, worn, c_eff, delta): the wall's outward unit normal, the corner's
    position across the wall [m], the wall's wear depth there h [m] (0 without feedback;
    the bin's, or with ``wear.interpolate`` the bilinear read of :func:`wall_read`), h's
    gradient with respect to the corner (global, tangent to the wall; zero for the bin
    read), whether the wall's coating is worn through in the bin under the corner, the
    local clearance c + h and the penetration delta = (corner beyond the block's nominal
    face) - c_eff [m] (negative: a gap), whose gradient with respect to the corner is
    n - slope: the worn wall's normal."""
    zs = p[P_ZS]
    wall, s = slot_wall(k)
    if wall < 2:
        n = (0.0, s, 0.0)
        out = s * q[1] - 0.5 * jp[j, J_WIDTH]
        c = jp[j, J_CY]
        across = q[2] - zs
    else:
        n = (0.0, 0.0, s)
        out = s * (q[2] - zs) - 0.5 * jp[j, J_HEIGHT]
        c = jp[j, J_CZ]
        across = q[1]
    feedback = p[P_FEEDBACK] != 0.0
    binned = feedback and p[P_INTERP] == 0.0
    coat = jp[j, J_COAT]
    h = 0.0
    slope = (0.0, 0.0, 0.0)
    worn = False
    if feedback and not binned:
        h, dh_dx, dh_da = wall_read(wmap, j, jp, wall, q[0], across)
        slope = (dh_dx, 0.0, dh_da) if wall < 2 else (dh_dx, dh_da, 0.0)
    if binned or coat < math.inf:
        row, col = wall_bin(jp, j, wall, q[0], across, wmap.shape[1], wmap.shape[2])
        depth = wmap[j, row, col]
        if binned:
            h = depth
        worn = coat < math.inf and coating_worn(depth, coat)
    return n, across, h, slope, worn, c + h, out - c - h


@compiled
def contact_angle(pen, rc):
    """Half-angle psi [rad] of the rounded corner's (edge radius r_c) surface inside the
    Hertz patch at penetration ``pen``: sin psi = a / r_c, a = sqrt(r_c pen)."""
    if pen <= 0.0:
        return 0.0
    return math.asin(min(1.0, math.sqrt(pen / rc)))


@compiled
def contact_area(pen, rc):
    """Hertz patch pi a^2 = pi r_c pen [m^2] of a rounded corner on a flat wall."""
    return math.pi * rc * max(pen, 0.0)


@compiled
def corner_mobility(p, u, nb):
    """Inverse mass [1/kg] of the block's motion at body point u along the body-frame unit
    vector nb, the block alone (its centroid free, its rotation free): 1/m4 +
    (u x nb)^T J4^-1 (u x nb). The rod that joint B ties to the block only adds mass, so this
    bounds the mechanism's value from above (a stiff rate at least as fast)."""
    a = cross(u, nb)
    return (1.0 / p[P_M4] + a[0] * a[0] / p[P_J4] + a[1] * a[1] / p[P_J4 + 1]
            + a[2] * a[2] / p[P_J4 + 2])


@compiled
def slot_state(j, model, k, slider):
    """Slot k's contact, a :data:`Slot`. ``slider``: the block's body state (r, v, R, w).

    On a sloped worn wall (the bilinear read, the gap's ``slope`` s != 0) the penetration
    delta = out - c - h(x, across) has the gradient m = n - s with respect to the corner, and
    the normal force derives from the corner's elastic potential U(delta, c_eff)
    (docs/physics.md 3.5, 3.7): -F_N m - X s on the block, X = dU/dc_eff at fixed delta while
    F_N > 0 (0 otherwise). The guide does not move, so its power is exactly
    -F_N delta_dot - X h_dot with delta_dot = m . v_q and h_dot = s . v_q, v_q the corner's
    velocity; the damping part (F_N - F_el) delta_dot + (X - U_c) h_dot is booked as
    dissipated. Friction stays tangent to the wall, against the corner's slip over it: its
    power is then its dot product with that slip whatever the normal force's direction.
    A flat wall (s = 0) gives -F_N n.
    """
    p = model.p
    jp = model.jp
    r4, v4, R4, w4 = slider
    u = slot_corner(jp, j, k)
    q = add(r4, mv(R4, u))
    n, across, h, slope, worn, c_eff, delta = gap(jp, j, model.wmap, p, k, q)
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
    zero = (0.0, 0.0, 0.0)
    if delta <= 0.0:
        return Slot(delta, ddot, 0.0, 0.0, 0.0, 0.0, zero, zero, 0.0, q, n, vt, slip, across,
                    worn, c_eff, h, u)
    ew, mu, _ = surface(jp, j, worn)
    rc = jp[j, J_RI]
    law = corner_law(p)
    kappa = contact_damping(model.s[j, S_SLOT + k], ddot, p)
    fn, fel, dfd, dfdd = normal_force(delta, ddot, c_eff, ew, rc, c_eff, law, kappa)
    if sloped:
        # U = delta F_el / (n + 1), F_el = A c_eff (delta / c_eff)^n with A ~ sqrt(c_eff)
        # (R_j = c_eff): U ~ c_eff^(3/2 - n), so dU/dc_eff = (3/2 - n) U / c_eff
        uc = (1.5 - law) * elastic_energy(delta, c_eff, ew, rc, c_eff, law) / c_eff
        x = uc if fn > 0.0 else 0.0
        fnormal = add(scale(-fn, n), scale(fn - x, slope))
        pdiss = (fn - fel) * ddot + (x - uc) * hdot
    else:
        fnormal = scale(-fn, n)
        pdiss = (fn - fel) * ddot
    force = fnormal
    if p[P_FRICTION] != 0.0 and slip > 0.0:
        ft = friction_magnitude(mu, fn, slip, p[P_V0], p[P_V1])
        force = add(force, scale(-ft / slip, vt))
    # friction: its work on the corner's slip
    pdiss -= dot(sub(force, fnormal), vt)
    return Slot(delta, ddot, fn, fel, dfd, dfdd, force, fnormal, pdiss, q, n, vt, slip, across,
                worn, c_eff, h, u)


@compiled
def slot_rate(j, model, k, st, R4):
    """Largest stiff rate [1/s] of slot k in contact or closing within one output step
    (docs/physics.md section 4), from the block's mobility at the corner
    (:func:`corner_mobility`); 0 for a slot that stays open. ``st``: :func:`slot_state`."""
    p = model.p
    jp = model.jp
    delta = st.delta
    ddot = st.ddot
    c_eff = st.c_eff
    u = st.u_body
    if not (delta > 0.0 or delta + ddot * p[P_DT] > 0.0):
        return 0.0
    m_eff = 1.0 / corner_mobility(p, u, mtv(R4, st.n))
    rate = stiff_rate(m_eff, st.dfd, st.dfdd)
    ew, mu, _ = surface(jp, j, st.worn)
    rc = jp[j, J_RI]
    law = corner_law(p)
    if ddot > 0.0:
        dpred = reachable_penetration(max(delta, 0.0), m_eff, ddot, c_eff, ew, rc, c_eff, law)
        kappa = contact_damping(model.s[j, S_SLOT + k], ddot, p)
        _, _, dfp, dfdp = normal_force(dpred, ddot, c_eff, ew, rc, c_eff, law, kappa)
        rate = max(rate, stiff_rate(m_eff, dfp, dfdp))
    if p[P_FRICTION] != 0.0 and mu > 0.0 and st.fn > 0.0:
        # the tangential inverse mass, bounded by the largest over directions
        jmin = min(p[P_J4], min(p[P_J4 + 1], p[P_J4 + 2]))
        inv_t = 1.0 / p[P_M4] + dot(u, u) / jmin
        slope = 1.0 / (p[P_V1] - p[P_V0]) if st.slip < p[P_V1] else 1.0 / st.slip
        rate = max(rate, mu * st.fn * slope * inv_t)
    return rate


@compiled
def contact(j, model, slider, full, dg):
    """The guide's action on the block of prismatic joint j: (force [N], moment about the
    block's centroid in the block's frame [N m], power dissipated by damping and friction
    [W]), summed over the slots. ``slider``: the block's body state (r, v, R, w).

    With ``full`` (a step's end), joint j's diagnostics into dg: the contact values of the
    slot that penetrates deepest (or, with none in contact, of the one nearest to contact),
    the block's offset (0, y, z - z_s) from the guide's axis, the elastic energy of all
    slots, the guide's total force on the block and the largest stiff rate of a slot
    (D_PRATE)."""
    p = model.p
    r4, v4, R4, w4 = slider
    force = (0.0, 0.0, 0.0)
    moment = (0.0, 0.0, 0.0)
    pdiss = 0.0
    uel = 0.0
    rate = 0.0
    best = -math.inf
    law = corner_law(p)
    for k in range(P_SLOTS):
        st = slot_state(j, model, k, slider)
        if full:
            rate = max(rate, slot_rate(j, model, k, st, R4))
            if st.delta > best:
                best = st.delta
                store_slot(dg, j, st)
        if st.delta <= 0.0:
            continue
        f = st.force
        force = add(force, f)
        moment = add(moment, cross(st.u_body, mtv(R4, f)))
        pdiss += st.pdiss
        if full:
            ew, _, _ = surface(model.jp, j, st.worn)
            uel += elastic_energy(st.delta, st.c_eff, ew, model.jp[j, J_RI], st.c_eff, law)
    if full:
        dg[D_UEL + j] = uel
        dg[D_PRATE] = rate
        dg[D_ECC + j] = math.sqrt(r4[1] * r4[1] + (r4[2] - p[P_ZS]) * (r4[2] - p[P_ZS]))
        dg[D_OFFSET + 3 * j] = 0.0
        dg[D_OFFSET + 3 * j + 1] = r4[1]
        dg[D_OFFSET + 3 * j + 2] = r4[2] - p[P_ZS]
        for i in range(3):
            dg[D_JOINT_FORCE + 3 * j + i] = force[i]
    return force, moment, pdiss


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
def seat(j, model, slider):
    """A seated start's slots: each corner that starts in contact begins its episode without
    an impact (impact velocity at the floor)."""
    p = model.p
    s = model.s
    for k in range(P_SLOTS):
        st = slot_state(j, model, k, slider)
        s[j, S_SLOT + k] = (episode_impact_velocity(0.0, st.ddot, p[P_DV0_MIN], False)
                            if st.delta > 0.0 else 0.0)
    s[j, S_DV0] = 0.0


@compiled
def accept(j, model, slider, hs, in_settled, stats, cur):
    """An accepted (sub-)step of length hs ends with the block in state ``slider``: each
    slot's contact episode (an onset is an impact, counted with its approach rate; the
    impact velocity follows ``contact.episode_impact_velocity``), and the wear of each slot
    in contact, Archard's V = k F_N |v_t| hs: V / w, its track's width w
    (:func:`track_width`), into ``cur`` per slot (:func:`slot_cell`: V / w, (V / w) x,
    (V / w) a; spread on the wall's map once the step is accepted, :func:`deposit`) and V
    into ``cur[j, 0]`` (the joint's own row, which the other joints' wear leaves unused).

    Returns whether a slot's episode state changed (the step-end evaluation must be redone).
    """
    p = model.p
    jp = model.jp
    s = model.s
    changed = False
    wear_on = p[P_WEAR] != 0.0
    any_contact = False
    for k in range(P_SLOTS):
        st = slot_state(j, model, k, slider)
        ddot = st.ddot
        at = S_SLOT + k
        if st.delta > 0.0:
            any_contact = True
            if wear_on and st.fn > 0.0:
                _, _, k_wear = surface(jp, j, st.worn)
                vol = p[P_AMPL] * k_wear * st.fn * st.slip * hs
                wall, _ = slot_wall(k)
                # the volume over the track's width: its depth times the length along the guide
                line = vol / track_width(jp, j, wall, st.delta, model.wmap.shape[1])
                row, col = slot_cell(k)
                cur[row, col] += line
                cur[row, col + 1] += line * st.q[0]
                cur[row, col + 2] += line * st.across
                cur[j, 0] += vol
            dv0 = episode_impact_velocity(s[j, at], ddot, p[P_DV0_MIN], p[P_ONSET] != 0.0)
            if s[j, at] == 0.0:
                changed = True
                stats[W_WHOLE, M_IMPACTS + j] += 1.0
                stats[W_WHOLE, M_VIMP_MAX + j] = max(stats[W_WHOLE, M_VIMP_MAX + j], ddot)
                if in_settled:
                    stats[W_SETTLED, M_IMPACTS + j] += 1.0
                    stats[W_SETTLED, M_VIMP_MAX + j] = max(stats[W_SETTLED, M_VIMP_MAX + j],
                                                           ddot)
            elif dv0 != s[j, at]:
                changed = True
            s[j, at] = dv0
        elif s[j, at] != 0.0:
            s[j, at] = 0.0
            changed = True
    s[j, S_DV0] = 1.0 if any_contact else 0.0
    return changed


@compiled
def deposit(wmap, j, jp, cur, wvol):
    """Spread joint j's accepted step wear on its wall maps (docs/physics.md 5.7): each
    slot's track wear (``cur``'s slot rows: sum of V / w, V the sub-step's volume and w
    its track's width, :func:`track_width`) on the bin of its mean position (weighted
    alike: a corner's Hertz patch, tens of microns across, lies well inside a bin), which
    deepens by it over the bin's length along the guide: the depth of the corner's track,
    Archard's k p s, whatever the bins' sizes. The step's volume (``cur[j, 0]``) adds to
    the worn volume ``wvol[j]``; both are cleared. Returns the largest depth of a bin
    written [m]."""
    nrow = wmap.shape[1]
    ncol = wmap.shape[2]
    length = jp[j, J_XSPAN] / ncol
    top = 0.0
    for k in range(P_SLOTS):
        cr, cc = slot_cell(k)
        line = cur[cr, cc]
        if line > 0.0:
            wall, _ = slot_wall(k)
            row, col = wall_bin(jp, j, wall, cur[cr, cc + 1] / line, cur[cr, cc + 2] / line,
                                nrow, ncol)
            wmap[j, row, col] += line / length
            top = max(top, wmap[j, row, col])
        cur[cr, cc] = 0.0
        cur[cr, cc + 1] = 0.0
        cur[cr, cc + 2] = 0.0
    wvol[j] += cur[j, 0]
    cur[j, 0] = 0.0
    return top
