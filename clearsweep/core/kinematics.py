"""Rigid-body kinematics with ZYX Euler angles (paper Eq. 19; DESIGN 1-2).

R = Rz(alpha) Ry(beta) Rx(gamma); body angular velocity w' = G(phi) phi_dot.
3-vectors are tuples, 3x3 matrices 9-tuples in row-major order.
"""

import math

from numba import njit


@njit(cache=True)
def rotation(a, b, g):
    """R = Rz(a) Ry(b) Rx(g) as a row-major 9-tuple."""
    ca, sa = math.cos(a), math.sin(a)
    cb, sb = math.cos(b), math.sin(b)
    cg, sg = math.cos(g), math.sin(g)
    return (ca * cb, -sa * cg + ca * sb * sg, sa * sg + ca * sb * cg,
            sa * cb, ca * cg + sa * sb * sg, -ca * sg + sa * sb * cg,
            -sb, cb * sg, cb * cg)


@njit(cache=True)
def gmat(b, g):
    """G(phi) with w' = G phi_dot (body frame), row-major 9-tuple."""
    cb, sb = math.cos(b), math.sin(b)
    cg, sg = math.cos(g), math.sin(g)
    return (-sb, 0.0, 1.0,
            cb * sg, cg, 0.0,
            cb * cg, -sg, 0.0)


@njit(cache=True)
def gdot_phidot(b, g, ad, bd, gd):
    """The velocity-quadratic part of w'_dot: G_dot(phi, phi_dot) phi_dot."""
    cb, sb = math.cos(b), math.sin(b)
    cg, sg = math.cos(g), math.sin(g)
    return (-cb * bd * ad,
            (-sb * sg * bd + cb * cg * gd) * ad - sg * gd * bd,
            (-sb * cg * bd - cb * sg * gd) * ad - cg * gd * bd)


@njit(cache=True)
def mv(m, v):
    """Matrix (9-tuple) times vector."""
    return (m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
            m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
            m[6] * v[0] + m[7] * v[1] + m[8] * v[2])


@njit(cache=True)
def mtv(m, v):
    """Transposed matrix (9-tuple) times vector."""
    return (m[0] * v[0] + m[3] * v[1] + m[6] * v[2],
            m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
            m[2] * v[0] + m[5] * v[1] + m[8] * v[2])


@njit(cache=True)
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@njit(cache=True)
def rot_mass(j, gm):
    """Rotational mass block G^T J G (symmetric, as a row-major 9-tuple) for diagonal J."""
    out = [0.0] * 9
    for r in range(3):
        for c in range(3):
            out[3 * r + c] = (gm[r] * j[0] * gm[c] + gm[3 + r] * j[1] * gm[3 + c]
                              + gm[6 + r] * j[2] * gm[6 + c])
    return (out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8])


@njit(cache=True)
def point_jacobian_rot(rm, u, gm):
    """-R u~ G: the 3x3 block d r_P / d phi of a body point at body offset u (row-major)."""
    # column c of G is (gm[c], gm[3+c], gm[6+c]); -R (u x g_c) = R (g_c x u)
    out = [0.0] * 9
    for c in range(3):
        gc = (gm[c], gm[3 + c], gm[6 + c])
        col = mv(rm, cross(gc, u))
        out[c] = col[0]
        out[3 + c] = col[1]
        out[6 + c] = col[2]
    return (out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8])


@njit(cache=True)
def point_state(r, rv, rm, w, u):
    """Position and velocity of the body point at body offset u.

    r, rv: centroid position and velocity (global); rm: rotation; w: body-frame angular
    velocity; u: body-frame offset.
    """
    ru = mv(rm, u)
    return add(r, ru), add(rv, mv(rm, cross(w, u)))


@njit(cache=True)
def point_accel_quadratic(rm, w, gdpd, u):
    """Velocity-dependent part of a body point's acceleration: R (Gdot phidot x u + w x (w x u))."""
    return mv(rm, add(cross(gdpd, u), cross(w, cross(w, u))))
