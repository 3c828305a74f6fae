"""Contact laws, friction, and the contact response of a clearance joint (docs/physics.md section 3).

Pure functions of floats in SI units, the choice of surface values (coated or base), and
:func:`respond`: from a joint type's gap geometry to the force pair, the composition that
every joint type (``spherical``, ``revolute``) ends its ``contact`` with.
The elastic law (``n``: 0.0 the paper's, else the exponent of the power law) and the damping
law (its hysteresis factor as a fraction, ``params.pack``) are parameters of the case
(docs/physics.md section 3.2).
"""

import math
from collections import namedtuple

from .compiled import compiled
from .kinematics import add, cross, dot, mtv, mv, scale, sub
from .layout import (
    D_CEFF,
    D_DDOT,
    D_DELTA,
    D_DFD,
    D_DFDD,
    D_ECC,
    D_FN,
    D_FT,
    D_HWEAR,
    D_NGLOBAL,
    D_NORMAL,
    D_OFFSET,
    D_UEL,
    D_VT,
    D_WORN,
    J_EW,
    J_EW_BASE,
    J_FILM,
    J_K,
    J_K_BASE,
    J_MU,
    J_MU_BASE,
    J_RI,
    J_RJ,
    P_DV0_MIN,
    P_FRICTION,
    P_HYST_DEN,
    P_HYST_NUM,
    P_V0,
    P_V1,
    S_DV0,
)
from .target import on_device


@compiled
def stiffness_factor(ew, ri):
    """K = 4 pi E_w R_i / 5 [N/m], the factor of every coated contact stiffness (Table 1)."""
    return 4.0 * math.pi * ew * ri / 5.0


@compiled
def power_coefficient(ew, ri, rj):
    """A = 4 E* sqrt(R_i R_j) / 3 [N/m] of the power law F_el = A c (delta / c)^n: with
    n = 3/2 Hertz's law of a ball in a conforming socket, K = 4 E* sqrt(R_i R_j / c) / 3;
    ``ew`` is Hertz's modulus E* (jp[J_EW] of a power-law joint, docs/physics.md section
    3.2)."""
    return 4.0 * ew * math.sqrt(ri * rj) / 3.0


@compiled
def elastic_force(delta, c, ew, ri, rj, n):
    """Elastic part F_el [N] and its slope dF_el/d delta [N/m].

    n = 0 (the paper's law): F_el = k_N(delta) delta, k_N = K (2 delta c + delta^2) / (c + delta)^2,
    K = :func:`stiffness_factor` (Table 1, exponent 1). n > 0: the power law
    F_el = A c (delta / c)^n, A = :func:`power_coefficient`.
    """
    if n != 0.0:
        a = power_coefficient(ew, ri, rj)
        xp = max(delta / c, 0.0) ** (n - 1.0)
        return a * delta * xp, n * a * xp
    kk = stiffness_factor(ew, ri)
    cd = c + delta
    f = kk * delta * delta * (2.0 * c + delta) / (cd * cd)
    df = kk * delta * (4.0 * c * c + 3.0 * c * delta + delta * delta) / (cd * cd * cd)
    return f, df


@compiled
def elastic_energy(delta, c, ew, ri, rj, n):
    """Elastic energy U [J] whose derivative is F_el (docs/physics.md section 8).

    Power law (n > 0): U = delta F_el / (n + 1). The paper's law (n = 0):
    U = K [delta^2/2 - c^2 ln(1 + delta/c) + c^2 delta/(c + delta)] = K c^2 u(x), x = delta/c,
    u(x) = x^2/2 - log1p(x) + x/(1+x). The leading terms cancel (u ~ 2 x^3 / 3), so small x
    uses the series u = sum_{n>=3} (-1)^(n+1) (n-1)/n x^n.
    """
    if delta <= 0.0:
        return 0.0
    if n != 0.0:
        return delta * elastic_force(delta, c, ew, ri, rj, n)[0] / (n + 1.0)
    kk = stiffness_factor(ew, ri)
    x = delta / c
    if x < 1e-2:
        u = 0.0
        for n in range(11, 2, -1):
            sign = 1.0 if n % 2 == 1 else -1.0
            u = (u + sign * (n - 1.0) / n) * x if n > 3 else (u + sign * (n - 1.0) / n)
        u *= x * x * x
    else:
        u = 0.5 * x * x - math.log1p(x) + x / (1.0 + x)
    return kk * c * c * u


@compiled
def hysteresis_fraction(law, cr):
    """(numerator, denominator) of the hysteresis factor chi_N delta_dot0 / k_N [-] of damping
    law ``law`` (its index in choices.DAMPING_LAWS) at restitution c_r (docs/physics.md 3.2).

    0 the paper's 20 (1 - c_r) / (13 c_r) (Table 1); 1 Lankarani & Nikravesh 1990,
    3 (1 - c_r^2) / 4; 2 Hunt & Crossley 1975, 3 (1 - c_r) / 2; 3 Flores et al. 2011,
    8 (1 - c_r) / (5 c_r); 4 Gonthier et al. 2004, (1 - c_r^2) / c_r; 5 Carvalho & Martins
    2019, 3 (1 - c_r)(11 - c_r) / (2 (1 + 9 c_r)). Kept as a fraction so that the paper's
    law rounds as it always has.
    """
    if law == 1:
        return 3.0 * (1.0 - cr) * (1.0 + cr), 4.0
    if law == 2:
        return 3.0 * (1.0 - cr), 2.0
    if law == 3:
        return 8.0 * (1.0 - cr), 5.0 * cr
    if law == 4:
        return (1.0 - cr) * (1.0 + cr), cr
    if law == 5:
        return 3.0 * (1.0 - cr) * (11.0 - cr), 2.0 * (1.0 + 9.0 * cr)
    return 20.0 * (1.0 - cr), 13.0 * cr


@compiled
def damping_factor(num, den, dv0):
    """kappa = num / (den delta_dot0) [s/m], so that chi_N = kappa k_N: the hysteresis factor
    num / den of :func:`hysteresis_fraction` over the impact velocity delta_dot0 [m/s]."""
    return num / (den * dv0)


@compiled
def episode_impact_velocity(dv0, ddot, floor, onset):
    """Impact velocity delta_dot0 [m/s] of a contact episode after an accepted step in contact.

    ``dv0`` is the episode's value so far (0 at its onset), ``ddot`` the normal approach rate
    at the step's end. At the onset: max(ddot, floor); then, ``onset`` false (the default),
    the fastest approach seen in the episode, or, ``onset`` true, the onset value kept for
    the whole episode. With delta_dot <= delta_dot0 the damping term stays below
    the hysteresis factor times F_el whatever the floor, so the floor only keeps delta_dot0
    positive; on an isolated impact (approach slowing from the onset) both give the onset value.
    """
    if dv0 == 0.0:
        return max(ddot, floor)
    if onset:
        return dv0
    return max(dv0, ddot)


@compiled
def normal_force(delta, ddot, c, ew, ri, rj, n, kappa):
    """Normal force F_N = F_el (1 + kappa delta_dot), clamped at 0 [N]; F_el of the elastic
    law ``n`` (:func:`elastic_force`).

    Returns (F_N, F_el, dF/d delta, dF/d delta_dot).
    """
    fel, dfel = elastic_force(delta, c, ew, ri, rj, n)
    fac = 1.0 + kappa * ddot
    fn = fel * fac
    if fn < 0.0:
        return 0.0, fel, 0.0, 0.0
    return fn, fel, dfel * fac, kappa * fel


@compiled
def friction_factor(vt, v0, v1):
    """Dynamic correction c_d of the improved Coulomb law (docs/physics.md section 3.3)."""
    if vt < v0:
        return 0.0
    if vt > v1:
        return 1.0
    return (vt - v0) / (v1 - v0)


@compiled
def stiff_rate(m_eff, k, c):
    """Largest root magnitude |s| of m s^2 + c s + k = 0 [1/s] (docs/physics.md section 4)."""
    if m_eff <= 0.0:
        return 0.0
    disc = c * c - 4.0 * m_eff * k
    if disc <= 0.0:
        return math.sqrt(max(k, 0.0) / m_eff)
    return (c + math.sqrt(disc)) / (2.0 * m_eff)


@compiled
def contact_damping(dv0, ddot, p):
    """kappa [s/m] of a contact whose episode impact velocity is ``dv0`` [m/s] (0: the episode
    begins within this step, and the approach rate ``ddot`` of the evaluation, floored at
    p[P_DV0_MIN], stands in for it), with the case's damping law (docs/physics.md section 3.2)."""
    if dv0 <= 0.0:
        dv0 = max(ddot, p[P_DV0_MIN])
    return damping_factor(p[P_HYST_NUM], p[P_HYST_DEN], dv0)


@compiled
def reachable_penetration(delta, m_eff, ddot, c, ew, ri, rj, n):
    """Penetration delta_pred [m] that an approach at ``ddot`` [m/s] > 0 with effective mass
    ``m_eff`` [kg] can reach from ``delta`` [m], by energy (docs/physics.md section 4.2):
    the paper's law from U ~ 2 K delta^3 / (3 c), delta_pred^3 = delta^3 + 3 m_eff ddot^2 c / (4 K);
    the power law from U = A c^(1-n) delta^(n+1) / (n + 1)."""
    if n != 0.0:
        a = power_coefficient(ew, ri, rj)
        top = delta ** (n + 1.0) + 0.5 * (n + 1.0) * m_eff * ddot * ddot * c ** (n - 1.0) / a
        return top ** (1.0 / (n + 1.0))
    kk = stiffness_factor(ew, ri)
    return (delta ** 3 + 0.75 * m_eff * ddot * ddot * c / kk) ** (1.0 / 3.0)


@compiled
def friction_magnitude(mu, fn, vt, v0, v1):
    """|F_t| = mu c_d(|v_t|) F_N [N] of the improved Coulomb law (docs/physics.md section 3.3)."""
    return mu * friction_factor(vt, v0, v1) * fn


@compiled
def surface(jp, j, worn):
    """(modulus [Pa] of the joint's law (jp[J_EW]), mu [-], k [m^2/N]) that joint j's contact
    uses: the coated surface's, or the base material's where the coating is worn through
    (``worn``; wear.worn_surface says where). The one place where the coating/base switch
    is made."""
    if worn:
        return jp[j, J_EW_BASE], jp[j, J_MU_BASE], jp[j, J_K_BASE]
    return jp[j, J_EW], jp[j, J_MU], jp[j, J_K]


#: What a joint type's ``contact`` (:func:`respond`) returns for one clearance joint (Numba compiles a namedtuple as a
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


def _respond(j, model, ball, socket, pb, ps, geo, law, energy):
    """Contact state and force of clearance joint j from its gap geometry ``geo`` (what a
    joint type's ``gap`` returns: e, n, d_s, n_s, h, slope, worn, c_eff, delta) at ball
    centre pb and socket centre ps, with the elastic law ``law`` (:func:`elastic_force`'s
    n): the composition that every joint type's ``contact`` ends with (docs/physics.md
    section 3).

    ``ball``: the ball's body (centroid rb, velocity vb, rotation Rb, body-frame angular
    velocity wb) and the ball centre's body offset ub, as the tuple (rb, vb, Rb, wb, ub);
    ``socket``: (rs, vs, Rs, ws_, us) likewise. ``model`` (a :data:`work.Model`) holds p, jp
    and s. ``energy``: also compute the elastic energy (else 0 where not needed).
    Returns a :data:`ContactState`. The whole arrays jp and s are passed with the joint
    index, never a row of them: a row is a new array view, formed at every call.

    On a sloped worn surface (bilinear map read, the gap's ``slope`` s != 0) the
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
    rb, vb, Rb, wb, _ = ball
    rs, vs, Rs, ws_, _ = socket
    e, n, d_s, n_s, h, slope, worn, c_eff, delta = geo
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
        # Coulomb's part and the lubricant film's viscous shear (joint O's; 0 elsewhere)
        ft = friction_magnitude(mu, fn, vtn, p[P_V0], p[P_V1]) + jp[j, J_FILM] * vtn
        force = add(force, scale(-ft / vtn, vt))
        pdiss += ft * vtn
    return ContactState(force, force_normal, qj, qi, fn, dfd, dfdd, delta, ddot, e, line, d_s, n_s, vtn, c_eff,
                        h, uel if energy else 0.0, pdiss, worn_flag)


def _named(func, name):
    """A copy of the plain function ``func`` under another name (its own compiled cache)."""
    import types

    copy = types.FunctionType(func.__code__, func.__globals__, name, func.__defaults__,
                              func.__closure__)
    copy.__qualname__ = name
    copy.__doc__ = func.__doc__
    return copy


#: :func:`_respond` as a call: the device build's, where inlining it into each joint type's
#: ``contact`` costs registers (1,252 against 1,076 B of spill stores per thread,
#: ``python -m clearsweep.ptx``).
respond = compiled(_named(_respond, "respond"))

#: :func:`_respond` inlined into each joint type's ``contact``: the CPU build's, where the
#: call cost the two-clearance case 14 % of its steps/s.
respond_inline = compiled(inline="always")(_named(_respond, "respond_inline"))


@compiled(inline="always")
def compose(j, model, ball, socket, pb, ps, geo, law, energy):
    """:func:`_respond` as each build takes it, the call every joint type's ``contact`` ends
    with: inlined in the CPU build (:data:`respond_inline`), called in a device build
    (:data:`respond`; ``target.on_device``)."""
    if on_device():
        return respond(j, model, ball, socket, pb, ps, geo, law, energy)
    return respond_inline(j, model, ball, socket, pb, ps, geo, law, energy)


@compiled
def store_contact(dg, j, cres):
    """Copy one joint's contact state (a :data:`ContactState`) into the diagnostics vector."""
    fn = cres.fn
    dg[D_FN + j] = fn
    ft_vec = sub(cres.force, cres.force_normal)   # the friction force
    dg[D_FT + j] = math.sqrt(dot(ft_vec, ft_vec))
    dg[D_DELTA + j] = cres.delta
    dg[D_DDOT + j] = cres.ddot
    dg[D_ECC + j] = cres.ecc
    for i in range(3):
        dg[D_OFFSET + 3 * j + i] = cres.offset_socket[i]
        dg[D_NORMAL + 3 * j + i] = cres.normal_socket[i]
    dg[D_VT + j] = cres.slip_speed
    dg[D_CEFF + j] = cres.c_eff
    dg[D_HWEAR + j] = cres.wear_depth
    dg[D_UEL + j] = cres.elastic_energy
    dg[D_DFD + j] = cres.dfn_ddelta
    dg[D_DFDD + j] = cres.dfn_dddot
    dg[D_WORN + j] = cres.worn_through
    for i in range(3):
        dg[D_NGLOBAL + 3 * j + i] = cres.normal[i]


@compiled(inline="always")
def seat_episode(j, model, dg):
    """A one-point joint j in contact at a case's first evaluation (a seated start): its
    contact episode begins without an impact, at the impact velocity of its approach rate
    in the diagnostics dg (:func:`episode_impact_velocity` at the episode's onset), into
    ``model.s``; True (the start is evaluated again). The shared part of the one-point
    types' ``seat`` (``joints.PROTOCOL``)."""
    model.s[j, S_DV0] = episode_impact_velocity(0.0, dg[D_DDOT + j], model.p[P_DV0_MIN], False)
    return True


@compiled(inline="always")
def offsets_over(d, rate, c):
    """A one-point joint's section offset d [m] and its rate [m/s] (socket frame), each
    over the radial clearance c [m]: the one-point types' ``section_offsets``
    (``joints.PROTOCOL``)."""
    return (d[0] / c, d[1] / c, d[2] / c), (rate[0] / c, rate[1] / c, rate[2] / c)
