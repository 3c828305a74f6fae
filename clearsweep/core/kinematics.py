"""Rigid-body kinematics with ZYX Euler angles (paper Eq. 19; docs/physics.md sections 1-2).

R = Rz(alpha) Ry(beta) Rx(gamma); body angular velocity w' = G(phi) phi_dot.
3-vectors are tuples, 3x3 matrices 9-tuples in row-major order.
"""

import math

from .compiled import compiled

#: Below this |x| (2^-27) the correctly rounded cos x is 1.0 and sin x is x, to the bit.
#: Six of the nine Euler angles are held near 0 by constraints (the crank's alpha and beta,
#: the rod's gamma, the slider's), so most evaluations skip their libm calls.
TINY_ANGLE = 2.0 ** -27


@compiled
def cos_sin(x):
    """(cos x, sin x), exact for |x| < TINY_ANGLE without calling libm."""
    if abs(x) < TINY_ANGLE:
        return 1.0, x
    return math.cos(x), math.sin(x)


@compiled
def trig(a, b, g):
    """(cos a, sin a, cos b, sin b, cos g, sin g): computed once per body and evaluation."""
    ca, sa = cos_sin(a)
    cb, sb = cos_sin(b)
    cg, sg = cos_sin(g)
    return (ca, sa, cb, sb, cg, sg)


@compiled
def rotation(tr):
    """R = Rz(a) Ry(b) Rx(g) as a row-major 9-tuple, from trig(a, b, g)."""
    ca, sa, cb, sb, cg, sg = tr
    return (ca * cb, -sa * cg + ca * sb * sg, sa * sg + ca * sb * cg,
            sa * cb, ca * cg + sa * sb * sg, -ca * sg + sa * sb * cg,
            -sb, cb * sg, cb * cg)


@compiled
def gmat(tr):
    """G(phi) with w' = G phi_dot (body frame), row-major 9-tuple, from trig(a, b, g)."""
    cb, sb, cg, sg = tr[2], tr[3], tr[4], tr[5]
    return (-sb, 0.0, 1.0,
            cb * sg, cg, 0.0,
            cb * cg, -sg, 0.0)


@compiled
def gdot_phidot(tr, ad, bd, gd):
    """The velocity-quadratic part of w'_dot: G_dot(phi, phi_dot) phi_dot."""
    cb, sb, cg, sg = tr[2], tr[3], tr[4], tr[5]
    return (-cb * bd * ad,
            (-sb * sg * bd + cb * cg * gd) * ad - sg * gd * bd,
            (-sb * cg * bd - cb * sg * gd) * ad - cg * gd * bd)


@compiled
def mv(m, v):
    """Matrix (9-tuple) times vector."""
    return (m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
            m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
            m[6] * v[0] + m[7] * v[1] + m[8] * v[2])


@compiled
def mtv(m, v):
    """Transposed matrix (9-tuple) times vector."""
    return (m[0] * v[0] + m[3] * v[1] + m[6] * v[2],
            m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
            m[2] * v[0] + m[5] * v[1] + m[8] * v[2])


@compiled
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@compiled
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@compiled
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@compiled
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@compiled
def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@compiled
def rot_mass(j, gm):
    """Rotational mass block G^T J G (symmetric, row-major 9-tuple) for diagonal J."""
    m00 = gm[0] * j[0] * gm[0] + gm[3] * j[1] * gm[3] + gm[6] * j[2] * gm[6]
    m01 = gm[0] * j[0] * gm[1] + gm[3] * j[1] * gm[4] + gm[6] * j[2] * gm[7]
    m02 = gm[0] * j[0] * gm[2] + gm[3] * j[1] * gm[5] + gm[6] * j[2] * gm[8]
    m11 = gm[1] * j[0] * gm[1] + gm[4] * j[1] * gm[4] + gm[7] * j[2] * gm[7]
    m12 = gm[1] * j[0] * gm[2] + gm[4] * j[1] * gm[5] + gm[7] * j[2] * gm[8]
    m22 = gm[2] * j[0] * gm[2] + gm[5] * j[1] * gm[5] + gm[8] * j[2] * gm[8]
    return (m00, m01, m02, m01, m11, m12, m02, m12, m22)


@compiled
def point_jacobian_rot(rm, u, gm):
    """-R u~ G: the 3x3 block d r_P / d phi of a body point at body offset u (row-major).

    Column c is R (g_c x u), g_c the c-th column of G.
    """
    c0 = mv(rm, cross((gm[0], gm[3], gm[6]), u))
    c1 = mv(rm, cross((gm[1], gm[4], gm[7]), u))
    c2 = mv(rm, cross((gm[2], gm[5], gm[8]), u))
    return (c0[0], c1[0], c2[0], c0[1], c1[1], c2[1], c0[2], c1[2], c2[2])


@compiled
def point_state(r, rv, rm, w, u):
    """Position and velocity of the body point at body offset u.

    r, rv: centroid position and velocity (global); rm: rotation; w: body-frame angular
    velocity; u: body-frame offset.
    """
    ru = mv(rm, u)
    return add(r, ru), add(rv, mv(rm, cross(w, u)))


@compiled
def point_accel_quadratic(rm, w, gdpd, u):
    """Velocity-dependent part of a body point's acceleration: R (Gdot phidot x u + w x (w x u))."""
    return mv(rm, add(cross(gdpd, u), cross(w, cross(w, u))))


@compiled
def body_moment(R, r, q, f):
    """Body-frame moment of the global force f applied at global point q."""
    return mtv(R, cross(sub(q, r), f))
