"""Rigid-body numerics that no mechanism owns: a body's state from its coordinates, its
rotational equations in Euler angles, the ground's state, the Cholesky solve of the
constrained systems and the small vector helpers of the contact laws (docs/physics.md
section 2).

A mechanism's equations of motion (``dynamics``, the RSSP's) call these; none of them
names a body or a joint of a particular mechanism.
"""

import math

from .compiled import compiled
from .kinematics import add, cross, dot, gdot_phidot, gmat, mtv, mv, rot_mass, rotation, scale, sub
from .layout import Y_QD
from .target import on_device

#: The ground's body state (r, v, R, w): what a joint's socket on the ground moves with.
GROUND = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
          (0.0, 0.0, 0.0))


@compiled
def solve_spd(S, vz, b, nc, L):
    """Solve S x = vz[b] in place (vz[b] <- x) by Cholesky; L receives the factor. False if
    singular.

    On a CPU, six rows (the RSSP's Schur complement with A and B ideal) run
    :func:`cholesky` with the count a constant, which the compiler writes out: no loop
    counters, and the factor's entries forwarded in registers from their stores rather
    than read back between the divisions and square roots of each recurrence. Three rows
    (one of A and B ideal) take :func:`solve_spd3`, the same written out by hand, which
    holds the right-hand side in registers too (the compiler's version of three rows ran
    the one-clearance case about 2 % slower). The same operations in the same order:
    results to the bit (tests/test_multibody.py). Other sizes, and a device build, run the
    loops as they are."""
    if not on_device():
        if nc == 3:
            return solve_spd3(S, vz, b, L)
        if nc == 6:
            return cholesky(S, vz, b, 6, L)
    return cholesky(S, vz, b, nc, L)


@compiled(inline="always")
def cholesky(S, vz, b, nc, L):
    """:func:`solve_spd`'s loops: the factor row by row, then :func:`substitute`."""
    for i in range(nc):
        for j in range(i + 1):
            acc = S[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            if i == j:
                if acc <= 0.0:
                    return False
                L[i, i] = math.sqrt(acc)
            else:
                L[i, j] = acc / L[j, j]
    substitute(L, vz, b, nc)
    return True


@compiled
def chol_solve(L, vz, b, nc):
    """Solve L L^T x = vz[b] in place (:func:`substitute`; on a CPU, three rows by
    :func:`chol_solve3` and six with the count a constant, as :func:`solve_spd`)."""
    if not on_device():
        if nc == 3:
            chol_solve3(L, vz, b)
            return
        if nc == 6:
            substitute(L, vz, b, 6)
            return
    substitute(L, vz, b, nc)


@compiled(inline="always")
def substitute(L, vz, b, nc):
    """L L^T x = vz[b] in place: forward, then back substitution."""
    for i in range(nc):
        acc = vz[b, i]
        for k in range(i):
            acc -= L[i, k] * vz[b, k]
        vz[b, i] = acc / L[i, i]
    for i in range(nc - 1, -1, -1):
        acc = vz[b, i]
        for k in range(i + 1, nc):
            acc -= L[k, i] * vz[b, k]
        vz[b, i] = acc / L[i, i]


@compiled(inline="always")
def solve_spd3(S, vz, b, L):
    """:func:`solve_spd` of three rows, its loops written out: the same operations in the
    same order (results to the bit), the factor's entries and the right-hand side held in
    registers rather than stored to L and vz and read back between the steps of each
    recurrence, whose divisions and square roots follow one another (the one-clearance
    case's step-end evaluation about 8 % faster with :func:`dynamics.back_substitute3`;
    benchmarks/README.md, "Issue 42's CPU goals, measured again")."""
    acc = S[0, 0]
    if acc <= 0.0:
        return False
    l00 = math.sqrt(acc)
    L[0, 0] = l00
    l10 = S[1, 0] / l00
    L[1, 0] = l10
    acc = S[1, 1]
    acc -= l10 * l10
    if acc <= 0.0:
        return False
    l11 = math.sqrt(acc)
    L[1, 1] = l11
    l20 = S[2, 0] / l00
    L[2, 0] = l20
    acc = S[2, 1]
    acc -= l20 * l10
    l21 = acc / l11
    L[2, 1] = l21
    acc = S[2, 2]
    acc -= l20 * l20
    acc -= l21 * l21
    if acc <= 0.0:
        return False
    l22 = math.sqrt(acc)
    L[2, 2] = l22
    solve3(l00, l10, l11, l20, l21, l22, vz, b)
    return True


@compiled(inline="always")
def chol_solve3(L, vz, b):
    """:func:`chol_solve` of three rows, unrolled (:func:`solve3`)."""
    solve3(L[0, 0], L[1, 0], L[1, 1], L[2, 0], L[2, 1], L[2, 2], vz, b)


@compiled(inline="always")
def solve3(l00, l10, l11, l20, l21, l22, vz, b):
    """L L^T x = vz[b] in place for the lower triangle L of three rows given by its entries:
    :func:`chol_solve`'s loops written out, each sum in the loops' order."""
    acc = vz[b, 0]
    x0 = acc / l00
    acc = vz[b, 1]
    acc -= l10 * x0
    x1 = acc / l11
    acc = vz[b, 2]
    acc -= l20 * x0
    acc -= l21 * x1
    x2 = acc / l22
    x2 = x2 / l22
    acc = x1
    acc -= l21 * x2
    x1 = acc / l11
    acc = x0
    acc -= l10 * x1
    acc -= l20 * x2
    x0 = acc / l00
    vz[b, 0] = x0
    vz[b, 1] = x1
    vz[b, 2] = x2


@compiled
def quad_form(w, u, v):
    """u^T W v for the packed symmetric W."""
    return (u[0] * (w[0] * v[0] + w[1] * v[1] + w[2] * v[2])
            + u[1] * (w[1] * v[0] + w[3] * v[1] + w[4] * v[2])
            + u[2] * (w[2] * v[0] + w[4] * v[1] + w[5] * v[2]))


@compiled
def tangent_basis(n):
    """Two unit vectors orthogonal to the unit vector n."""
    if abs(n[0]) < 0.9:
        a = (1.0, 0.0, 0.0)
    else:
        a = (0.0, 1.0, 0.0)
    t1 = cross(n, a)
    t1 = scale(1.0 / math.sqrt(dot(t1, t1)), t1)
    return t1, cross(n, t1)


@compiled(inline="always")
def body_motion(y, r_at, phi_at):
    """Centroid position [m], velocity [m/s] and Euler-angle rates [rad/s] of the body whose
    coordinates start at y[r_at] (centroid) and y[phi_at] (angles)."""
    qd = Y_QD
    return ((y[r_at], y[r_at + 1], y[r_at + 2]),
            (y[qd + r_at], y[qd + r_at + 1], y[qd + r_at + 2]),
            (y[qd + phi_at], y[qd + phi_at + 1], y[qd + phi_at + 2]))


@compiled(inline="always")
def body_frame(tr, pd):
    """Rotation R and body angular velocity w = G phi_dot [rad/s] of a body from its Euler
    angles' trig(...) and rates pd."""
    return rotation(tr), mv(gmat(tr), pd)


@compiled(inline="always")
def body_state(y, tr, r_at, phi_at):
    """(r, v, R, w) of the body whose coordinates start at y[r_at] and y[phi_at], tr its
    Euler angles' trig(...): centroid position and velocity, rotation, body angular
    velocity."""
    r, v, pd = body_motion(y, r_at, phi_at)
    R, w = body_frame(tr, pd)
    return r, v, R, w


@compiled(inline="always")
def euler_equations(J, t, pd, N):
    """A body's rotational equations in its Euler angles, M phi_dd = Q: (Q = G^T (N - w x J w
    - J Gdot phi_dot), M = G^T J G, G) for principal inertia J, the angles' trig(...) t,
    their rates pd and the body-frame moment N (w = G pd)."""
    G = gmat(t)
    w = mv(G, pd)
    gq = gdot_phidot(t, pd[0], pd[1], pd[2])
    Jw = (J[0] * w[0], J[1] * w[1], J[2] * w[2])
    Jg = (J[0] * gq[0], J[1] * gq[1], J[2] * gq[2])
    return mtv(G, sub(N, add(cross(w, Jw), Jg))), rot_mass(J, G), G
