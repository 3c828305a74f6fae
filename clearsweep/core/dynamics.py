"""Equations of motion of the RSSP mechanism (docs/physics.md sections 2-3; paper Eq. 5, 29).

The Baumgarte-stabilised augmented system

    [ M   Cq^T ] [ qdd    ]   [ Qe + Q_contact            ]
    [ Cq  0    ] [ lambda ] = [ gamma - 2 a C_dot - b^2 C ]

is solved exactly by exploiting its structure. Every constraint except the ideal spherical
joints acts on one body only and fixes a coordinate's acceleration directly (crank: revolute
O + driver, 6 rows on 6 coordinates, or 4 where O has clearance: the driver, the two tilts
and the axial position; rod spin gamma3 = 0; slider: y, z and three angles). The remaining
free coordinates z = [r3, alpha3, beta3, x4, y2, z2] carry a block-diagonal mass matrix and
at most six rows (ideal A, ideal B), solved through the Schur complement S = C M^-1 C^T; the
crank's y2, z2 (its centroid in the bearing's plane) are free only where O has clearance,
and otherwise carry a zero inverse mass and zero columns, which leave every product as it
was. The crank's multipliers (torque, reaction at O) follow from its own equations once the
joint forces are known. Implemented: gamma3 = 0 as published (paper Eq. 24).

Where the slider's guide (joint P) has clearance, the slider's y4, z4 join the free
coordinates (z gains them as its last two, inverse mass 1/m4, else 0 as for the crank's),
and its three angles follow from its own rotational equations with the corners' contact
moments: joint B holds the slider at its centroid, which the angles do not move, so they
are not coupled to the other free coordinates. The planar slider-crank's guide (along y)
frees its z4 alone (column 9; column 8, its x4, held by :func:`planar_slider` with alpha4
and beta4) and gamma4 (:func:`planar_slider_rotation`), the guide's type evaluated in the
frame it is written in (:func:`free_slider`).

The joints' contacts are their types' ``contact`` (``joints.PROTOCOL``), reached through
``jointkinds``: a one-point joint's through ``jointkinds.contact``, the guide's block through
``jointkinds.multi_contact`` (with ``in_type_frame`` and ``from_type_frame`` for the
slider-crank's guide); this module calls no type's contact by name.
"""

import math

import numpy as np
from numba import types

from . import jointkinds as kinds
from .compiled import compile_lock, compiled
from .joints import BODIES, FREE, INDEX, JOINTS
from .jointset import ALL, NONE, SLIDER_CRANK, Build, guide_axis, has_clearance, is_bushing, is_free
from .kinematics import (
    add,
    body_moment,
    cross,
    dot,
    gdot_phidot,
    gmat,
    mtv,
    mv,
    point_accel_quadratic,
    point_jacobian_rot,
    point_state,
    rotation,
    scale,
    sub,
    trig,
)
from .layout import (
    D_CEFF,
    D_CONS,
    D_DDOT,
    D_DELTA,
    D_DFD,
    D_DFDD,
    D_ECC,
    D_FN,
    D_FT,
    D_HWEAR,
    D_JOINT_FORCE,
    D_KE,
    D_NGLOBAL,
    D_NORMAL,
    D_PDISS,
    D_PDRIVE,
    D_PE_GRAV,
    D_RATE,
    D_REACTION_O,
    D_SLIDER_ACC,
    D_TORQUE,
    D_UEL,
    D_VT,
    J_BLOCK_LENGTH,
    J_CLEARANCE,
    N_D,
    N_JOINTS,
    N_Q,
    N_S,
    P_BAUM_A,
    P_BAUM_B,
    P_G,
    P_GUIDE,
    P_J2,
    P_J3,
    P_J4,
    P_L2,
    P_L3,
    P_M2,
    P_M3,
    P_M4,
    P_OMEGA,
    P_THETA0,
    P_ZS,
    ST_OK,
    ST_SINGULAR,
    Y_DISS,
    Y_PHI2,
    Y_PHI3,
    Y_PHI4,
    Y_QD,
    Y_R2,
    Y_R3,
    Y_R4,
    Y_WORK,
)
from .multibody import (
    GROUND,
    body_frame,
    body_motion,
    body_state,
    chol_solve,
    euler_equations,
    solve_spd,
)
from .target import on_device
from .work import Model, Solve

#: Free coordinates of the equations of motion (``joints.FREE``: x3, y3, z3, alpha3, beta3,
#: x4, y2, z2, y4, z4), the columns of C and the length of vz's rows.
NZ = len(FREE)

#: The joints' rows (joints.JOINTS), as constants of the compiled code.
JOINT_A = INDEX["A"]
JOINT_B = INDEX["B"]
JOINT_O = INDEX["O"]
JOINT_P = INDEX["P"]


@compiled(inline="always")
def o_free(spec, jp):
    """Whether joint O's journal is free in the bearing's plane, by its clearance or as a
    bushing (in the build's joint set ``spec``, then in the case): read from jp where it is
    needed rather than kept live through the right-hand side (a GPU thread's registers: 16 B
    fewer spill stores, ``python -m clearsweep.ptx``)."""
    return is_free(spec, jp, JOINT_O)


@compiled(inline="always")
def p_free(spec, jp):
    """Whether joint P has clearance, the slider's block free across its guide and in its
    angles (read from jp where needed, as :func:`o_free`): the RSSP's block across its guide
    (y4, z4) and in its three angles; the planar slider-crank's (``jointset.guide_axis`` 1)
    in its plane only, across the guide (z4) and tilting about x (gamma4), its x4, alpha4
    and beta4 held (:func:`planar_slider`)."""
    return has_clearance(spec, jp, JOINT_P)




#: Free coordinates but those the guide P frees (the slider's y4, z4: ``joints.FREE``'s last,
#: free only where P has clearance).
NZ_HELD = sum(1 for coordinate in FREE if coordinate.freed_by != "P")

#: Each moving body's packed mass (``layout.P_M*``), by its name in ``joints.BODIES``.
BODY_MASS = {"crank": P_M2, "rod": P_M3, "slider": P_M4}
if set(BODY_MASS) != {body.name for body in BODIES if body.y_r is not None}:
    raise ImportError("dynamics.BODY_MASS names another set of bodies than joints.BODIES")


def mass_groups(free):
    """The inverse-mass groups of the free coordinates ``free`` (``joints.FREE``): each
    distinct (body, the joint that frees it) among the centroid coordinates, in the table's
    order. A group's coordinates share one inverse mass, 1/m of the body or 0 where its
    joint holds it; the rod's two angles are its rotational block (``rod_equations``'
    mr_inv), no group."""
    groups: list[tuple[str, str | None]] = []
    for coordinate in free:
        key = (coordinate.body, coordinate.freed_by)
        if coordinate.axis in ("x", "y", "z") and key not in groups:
            groups.append(key)
    return tuple(groups)


#: The free coordinates' inverse-mass groups (:func:`mass_groups` of ``joints.FREE``): the
#: rod's centroid, the slider along its guide, the crank's centroid in the bearing's plane
#: (freed by O), the slider across its guide (freed by P); :func:`minv_apply`'s minv[0] to
#: minv[3] in that order.
MASS_GROUPS = mass_groups(FREE)
#: Each group's body's packed mass (``layout.P_M*``), a compile-time tuple.
GROUP_MASS = tuple(BODY_MASS[body] for body, _ in MASS_GROUPS)
#: Each group's freeing joint's row (-1: free in every build), a compile-time tuple.
GROUP_JOINT = tuple(-1 if joint is None else INDEX[joint] for _, joint in MASS_GROUPS)
#: Each free coordinate's group (its index in :data:`MASS_GROUPS`; -1: the rod's angles),
#: which :func:`minv_apply` applies column by column.
COLUMN_GROUP = tuple(MASS_GROUPS.index((c.body, c.freed_by)) if c.axis in ("x", "y", "z")
                     else -1 for c in FREE)
if COLUMN_GROUP != (0, 0, 0, -1, -1, 1, 2, 2, 3, 3):
    raise ImportError(f"minv_apply applies the groups by column as (0, 0, 0, -1, -1, 1, 2, 2, "
                      f"3, 3); joints.FREE gives {COLUMN_GROUP}")


@compiled(inline="always")
def group_inverse_mass(spec, p, jp, k):
    """The inverse mass [1/kg] of group k of :data:`MASS_GROUPS`: 1/m of its body, or 0
    where its joint holds it (neither clearance nor a bushing: ``jointset.is_free``, a
    constant False where the build has neither)."""
    joint = GROUP_JOINT[k]
    if joint >= 0 and not is_free(spec, jp, joint):
        return 0.0
    return 1.0 / p[GROUP_MASS[k]]


@compiled(inline="always")
def row_dot(A, i, B, k, minv, start):
    """start + the sum over the free coordinates in use of A[i, c] B[k, c], added in order:
    the first NZ_HELD, a constant count a compiler unrolls as it did before joint P, then the
    slider's two where it is free (minv[3] != 0)."""
    acc = start
    for c in range(NZ_HELD):
        acc += A[i, c] * B[k, c]
    if minv[3] != 0.0:
        for c in range(NZ_HELD, NZ):
            acc += A[i, c] * B[k, c]
    return acc


@compiled
def minv_apply(minv, mr_inv, vz, v, out):
    """vz[out] = M_zz^-1 vz[v] for the block-diagonal free-coordinate mass matrix (v, out:
    rows of the work array vz; minv: the inverse masses of :data:`MASS_GROUPS` (1/m3, 1/m4,
    1/m2 and 1/m4 again, the third 0 where the crank is held in its bearing, the fourth 0
    where the slider is held in its guide), applied by :data:`COLUMN_GROUP`, and the rod's
    x3's, 1/m3, or 0 where the slider-crank holds its rod in its plane). The
    slider-crank's slider takes the columns as: 5 its y4 along the guide, 8 its x4 (held
    across its plane, :func:`planar_slider`: no row reaches it, its force 0), 9 its z4."""
    vz[out, 0] = minv[4] * vz[v, 0]
    vz[out, 1] = minv[0] * vz[v, 1]
    vz[out, 2] = minv[0] * vz[v, 2]
    vz[out, 3] = mr_inv[0] * vz[v, 3] + mr_inv[1] * vz[v, 4]
    vz[out, 4] = mr_inv[2] * vz[v, 3] + mr_inv[3] * vz[v, 4]
    vz[out, 5] = minv[1] * vz[v, 5]
    vz[out, 6] = minv[2] * vz[v, 6]
    vz[out, 7] = minv[2] * vz[v, 7]
    if minv[3] != 0.0:
        vz[out, 8] = minv[3] * vz[v, 8]
        vz[out, 9] = minv[3] * vz[v, 9]


@compiled
def constrained_apply(vz, g, C, L, nc, minv, mr_inv, w1, w2, lam):
    """vz[w1] = W vz[g], W the constrained inverse mass of the free coordinates (Schur form;
    g, w1, w2, lam: rows of the work array vz)."""
    minv_apply(minv, mr_inv, vz, g, w1)
    if nc == 0:
        return
    for i in range(nc):
        vz[lam, i] = row_dot(C, i, vz, w1, minv, 0.0)
    chol_solve(L, vz, lam, nc)
    back_substitute(vz, g, C, lam, nc, minv, mr_inv, w2, w1)


@compiled
def back_substitute(vz, f, C, lam, nc, minv, mr_inv, tmp, out):
    """vz[out] = M_zz^-1 (vz[f] - C^T vz[lam]): free accelerations from the multipliers
    (f, lam, tmp, out: rows of the work array vz). On a CPU, three multipliers take
    :func:`back_substitute3` and six :func:`back_substitute_rows` with their count a
    constant (as ``multibody.solve_spd``; the same sums in the same order)."""
    if not on_device():
        if nc == 3:
            back_substitute3(vz, f, C, lam, minv, mr_inv, tmp, out)
            return
        if nc == 6:
            back_substitute_rows(vz, f, C, lam, 6, minv, mr_inv, tmp, out)
            return
    back_substitute_rows(vz, f, C, lam, nc, minv, mr_inv, tmp, out)


@compiled(inline="always")
def back_substitute_rows(vz, f, C, lam, nc, minv, mr_inv, tmp, out):
    """:func:`back_substitute`'s loops."""
    for k in range(NZ_HELD):
        acc = vz[f, k]
        for i in range(nc):
            acc -= C[i, k] * vz[lam, i]
        vz[tmp, k] = acc
    if minv[3] != 0.0:
        for k in range(NZ_HELD, NZ):
            acc = vz[f, k]
            for i in range(nc):
                acc -= C[i, k] * vz[lam, i]
            vz[tmp, k] = acc
    minv_apply(minv, mr_inv, vz, tmp, out)


@compiled(inline="always")
def back_substitute3(vz, f, C, lam, minv, mr_inv, tmp, out):
    """:func:`back_substitute` of three multipliers, held in registers rather than read
    from vz again for each free coordinate (a store to vz's row ``tmp`` may, as far as the
    compiler knows, change them)."""
    l0 = vz[lam, 0]
    l1 = vz[lam, 1]
    l2 = vz[lam, 2]
    for k in range(NZ_HELD):
        acc = vz[f, k]
        acc -= C[0, k] * l0
        acc -= C[1, k] * l1
        acc -= C[2, k] * l2
        vz[tmp, k] = acc
    if minv[3] != 0.0:
        for k in range(NZ_HELD, NZ):
            acc = vz[f, k]
            acc -= C[0, k] * l0
            acc -= C[1, k] * l1
            acc -= C[2, k] * l2
            vz[tmp, k] = acc
    minv_apply(minv, mr_inv, vz, tmp, out)


@compiled
def point_mobility(j, Jr, C, L, nc, minv, mr_inv, vz, g):
    """Mobility W_p of joint j's relative contact motion, a_rel = W_p F for the force pair
    (F on the ball, -F on the socket); symmetric 3x3 as (xx, xy, xz, yy, yz, zz) [1/kg].

    The rod carries one side of A and B (A's socket, B's ball; Jr its rotation Jacobian
    block); the crank's rotation is driven, its centroid free in the bearing's plane (y, z)
    where O has clearance (minv[2] = 1/m2, else 0: immobile); B's socket moves with the
    slider along its guide only (global axis ``g``: X for the RSSP, Y for the
    slider-crank); O's bearing is the ground. With no ideal joint left (nc = 0)
    W_p = I/m3 + A Mr^-1 A^T (+ e_x e_x^T / m4 at B, + (e_y e_y^T + e_z e_z^T) / m2 at A) in
    closed form, and (e_y e_y^T + e_z e_z^T) / m2 at O.
    """
    xs = minv[1] if j == JOINT_B else 0.0
    # the crank's centroid in its bearing's plane (A, O), or the slider's across its guide (B)
    cs = minv[2] if j != JOINT_B else minv[3]
    if j == JOINT_O and nc == 0:
        return (0.0, 0.0, 0.0, cs, 0.0, cs)
    # the inverse masses along x and y: the slider-crank's slider moves along y, held in x
    ex = xs if (j != JOINT_B or g == 0) else 0.0
    ey = cs if (j != JOINT_B or g == 0) else xs
    if nc == 0:
        im = minv[0]
        a0 = (Jr[0], Jr[3], Jr[6])
        a1 = (Jr[1], Jr[4], Jr[7])
        b0 = (mr_inv[0] * a0[0] + mr_inv[1] * a1[0], mr_inv[0] * a0[1] + mr_inv[1] * a1[1],
              mr_inv[0] * a0[2] + mr_inv[1] * a1[2])
        b1 = (mr_inv[2] * a0[0] + mr_inv[3] * a1[0], mr_inv[2] * a0[1] + mr_inv[3] * a1[1],
              mr_inv[2] * a0[2] + mr_inv[3] * a1[2])
        return (minv[4] + ex + a0[0] * b0[0] + a1[0] * b1[0], a0[0] * b0[1] + a1[0] * b1[1],
                a0[0] * b0[2] + a1[0] * b1[2], im + ey + a0[1] * b0[1] + a1[1] * b1[1],
                a0[1] * b0[2] + a1[1] * b1[2], im + cs + a0[2] * b0[2] + a1[2] * b1[2])
    # general case: g_k = J^T e_k, W_p[a, b] = g_a . (W g_b)
    # rows of vz: 0-2 g_k, 3-4 work, 5 the result (xx, xy, xz, yy, yz, zz), 6 W g_b
    rod = 0.0 if j == JOINT_O else 1.0
    crank = 1.0 if j == JOINT_O else (-1.0 if j == JOINT_A else 0.0)
    for k in range(3):
        vz[k, 0] = rod if k == 0 else 0.0
        vz[k, 1] = rod if k == 1 else 0.0
        vz[k, 2] = rod if k == 2 else 0.0
        vz[k, 3] = rod * Jr[3 * k]
        vz[k, 4] = rod * Jr[3 * k + 1]
        vz[k, 5] = -1.0 if (j == JOINT_B and k == g) else 0.0
        vz[k, 6] = crank if k == 1 else 0.0
        vz[k, 7] = crank if k == 2 else 0.0
        # the slider across its guide: y4 (the RSSP's; the slider-crank's x4 is held)
        vz[k, 8] = -1.0 if (j == JOINT_B and k == 1 and g == 0) else 0.0
        vz[k, 9] = -1.0 if (j == JOINT_B and k == 2) else 0.0
    for b in range(3):
        constrained_apply(vz, b, C, L, nc, minv, mr_inv, 6, 3, 4)
        for a in range(b + 1):
            acc = row_dot(vz, a, vz, 6, minv, 0.0)
            # (a, b) with a <= b -> packed index
            if a == 0:
                vz[5, b] = acc
            elif a == 1:
                vz[5, 2 + b] = acc
            else:
                vz[5, 5] = acc
    return (vz[5, 0], vz[5, 1], vz[5, 2], vz[5, 3], vz[5, 4], vz[5, 5])




#: Rows of evaluate's work array vz (float64[VZ_ROWS, NZ], one value per free coordinate or
#: constraint row): the free coordinates' generalised forces, the constraint right-hand
#: sides, the free accelerations, M^-1 times the forces, the multipliers, two work rows.
VZ_FORCE = 0
VZ_RHS = 1
VZ_ZDD = 2
VZ_MINV_FORCE = 3
VZ_LAMBDA = 4
VZ_WORK1 = 5
VZ_WORK2 = 6
VZ_ROWS = 8





@compiled(inline="always")
def slider_state(y):
    """(r, v, R, w) of the slider's block at state y, its angles' trig(...) formed here."""
    return body_state(y, trig(y[Y_PHI4], y[Y_PHI4 + 1], y[Y_PHI4 + 2]), Y_R4, Y_PHI4)


@compiled(inline="always")
def crank_accelerations(t, y, p, t2):
    """Accelerations of the driven crank (revolute O + driver, Baumgarte rows): (pdd2, wd2,
    rdd2), its Euler-angle and body angular accelerations and its centroid acceleration."""
    a_b = p[P_BAUM_A]
    b_b = p[P_BAUM_B]
    uO = (0.0, 0.0, 0.5 * p[P_L2])
    theta = p[P_THETA0] + p[P_OMEGA] * t
    r2, v2, pd2 = body_motion(y, Y_R2, Y_PHI2)
    R2, w2 = body_frame(t2, pd2)
    gq2 = gdot_phidot(t2, pd2[0], pd2[1], pd2[2])
    pdd2 = (-2.0 * a_b * pd2[0] - b_b * b_b * y[Y_PHI2],
            -2.0 * a_b * pd2[1] - b_b * b_b * y[Y_PHI2 + 1],
            -2.0 * a_b * (pd2[2] - p[P_OMEGA]) - b_b * b_b * (y[Y_PHI2 + 2] - theta))
    wd2 = add(mv(gmat(t2), pdd2), gq2)
    pO, vO = point_state(r2, v2, R2, w2, uO)
    rdd2 = sub(sub(scale(-2.0 * a_b, vO), scale(b_b * b_b, pO)),
               mv(R2, add(cross(wd2, uO), cross(w2, cross(w2, uO)))))
    return pdd2, wd2, rdd2


@compiled(inline="always")
def fixed_accelerations(y, p, dy, held, g):
    """Accelerations that the other single-body constraints fix (Baumgarte rows): the rod's
    spin gamma3 and, where the slider is ``held`` in its guide (joint P ideal), its other
    horizontal coordinate (y for the RSSP's guide along x, x for the slider-crank's along y;
    ``g``: the guide's axis), held at 0, and its z, held at z_s (returned: gdd3, ydd4, zdd4,
    ydd4 that other coordinate's; 0, 0 where it is free) and its angles (written into dy)."""
    a_b = p[P_BAUM_A]
    b_b = p[P_BAUM_B]
    qd = Y_QD
    gdd3 = -2.0 * a_b * y[qd + Y_PHI3 + 2] - b_b * b_b * y[Y_PHI3 + 2]
    if not held:
        return gdd3, 0.0, 0.0
    h = 1 - g
    ydd4 = -2.0 * a_b * y[qd + Y_R4 + h] - b_b * b_b * y[Y_R4 + h]
    zdd4 = -2.0 * a_b * y[qd + Y_R4 + 2] - b_b * b_b * (y[Y_R4 + 2] - p[P_ZS])
    for k in range(3):
        dy[qd + Y_PHI4 + k] = -2.0 * a_b * y[qd + Y_PHI4 + k] - b_b * b_b * y[Y_PHI4 + k]
    return gdd3, ydd4, zdd4


@compiled
def free_slider(j, y, t4, model, N4, full, dg, dy, spec):
    """The slider's block free in its guide (joint P with clearance): the corners' contacts
    (its type's ``contact``, through ``jointkinds.multi_contact``; with ``full``, P's
    diagnostics into dg) and the block's angular accelerations under their moment and
    ``N4`` (B's, where B has clearance) into dy. Returns (the guide's force on the block
    [N], the power it dissipates [W], whether the rotational mass block was regular).
    ``spec``: the build's joint set, here a run-time value (one build of this function
    serves every set; the guide's axis, ``jointset.guide_axis``, tested at run time as
    before).

    The planar slider-crank's guide (axis 1, along y) is the type's turned into it: the
    type sees the block in the frame it is written in (``jointkinds.in_type_frame``) and
    its force and moment come back to global axes and the slider's body frame
    (``jointkinds.from_type_frame``), and so do P's force and contact normal in dg (its
    offset stays in the type's frame: along, side, up); the block turns in the plane only
    (:func:`planar_slider_rotation`). The type's stiff-rate bound at a corner
    (``prismatic.corner_mobility``) reads the block's principal inertias in its own body
    axes, which the turn swaps (x' = y): the same for the ``flores_benchmark`` preset's
    block, whose three are equal."""
    r4, v4, R4, w4 = body_state(y, t4, Y_R4, Y_PHI4)
    gr, gv, gR, gw = GROUND
    zero = (0.0, 0.0, 0.0)
    if guide_axis(spec) == 1:
        rq, vq, Rq, wq = kinds.in_type_frame(spec, j, (r4, v4, R4, w4))
        force, moment, _, pdiss = kinds.multi_contact(spec, j, model, (rq, vq, Rq, wq, zero),
                                                      (gr, gv, gR, gw, zero), full, dg)
        force = kinds.from_type_frame(spec, j, force)
        moment = kinds.from_type_frame(spec, j, moment)
        if full:
            for at in (D_JOINT_FORCE, D_NGLOBAL, D_NORMAL):
                back = kinds.from_type_frame(spec, j, (dg[at + 3 * j], dg[at + 3 * j + 1],
                                                       dg[at + 3 * j + 2]))
                for i in range(3):
                    dg[at + 3 * j + i] = back[i]
        ok = planar_slider_rotation(y, model.p, t4, add(N4, moment), dy)
        return force, pdiss, ok
    force, moment, _, pdiss = kinds.multi_contact(spec, j, model, (r4, v4, R4, w4, zero),
                                                  (gr, gv, gR, gw, zero), full, dg)
    ok = slider_rotation(y, model.p, t4, add(N4, moment), dy)
    return force, pdiss, ok


@compiled(inline="always")
def planar_slider(y, p):
    """The slider-crank's free block held in its plane (Baumgarte rows, as
    :func:`planar_rod` holds the rod): x4 = 0 and its angles alpha4 = beta4 = 0, so that it
    tilts about x only (gamma4) and stays off its guide's side walls. Returns the
    accelerations (x4dd, a4dd, b4dd)."""
    a_b = p[P_BAUM_A]
    b_b = p[P_BAUM_B]
    qd = Y_QD
    return (-2.0 * a_b * y[qd + Y_R4] - b_b * b_b * y[Y_R4],
            -2.0 * a_b * y[qd + Y_PHI4] - b_b * b_b * y[Y_PHI4],
            -2.0 * a_b * y[qd + Y_PHI4 + 1] - b_b * b_b * y[Y_PHI4 + 1])


@compiled(inline="always")
def planar_slider_rotation(y, p, t4, N4, dy):
    """The slider-crank's free block's angular accelerations (joint P with clearance): alpha4
    and beta4 held (:func:`planar_slider`), gamma4 from the third of its rotational
    equations G^T J G phi_dd = G^T (N4 - w x J w - J gdot phi_dot), the held angles'
    accelerations known (the rows' multipliers act on the first two only); written into
    dy. False where gamma4's diagonal term is not positive."""
    qd = Y_QD
    J4 = (p[P_J4], p[P_J4 + 1], p[P_J4 + 2])
    pd4 = (y[qd + Y_PHI4], y[qd + Y_PHI4 + 1], y[qd + Y_PHI4 + 2])
    b, m, _ = euler_equations(J4, t4, pd4, N4)
    _, a4dd, b4dd = planar_slider(y, p)
    if not m[8] > 0.0:
        return False
    dy[qd + Y_PHI4] = a4dd
    dy[qd + Y_PHI4 + 1] = b4dd
    dy[qd + Y_PHI4 + 2] = (b[2] - m[6] * a4dd - m[7] * b4dd) / m[8]
    return True



@compiled(inline="always")
def slider_rotation(y, p, t4, N4, dy):
    """The free slider's angular accelerations (joint P with clearance) from its rotational
    equations G^T J G phi_dd = G^T (N4 - w x J w - J gdot phi_dot), written into dy; False
    where the 3x3 mass block is singular (an Euler-angle limit)."""
    qd = Y_QD
    J4 = (p[P_J4], p[P_J4 + 1], p[P_J4 + 2])
    pd4 = (y[qd + Y_PHI4], y[qd + Y_PHI4 + 1], y[qd + Y_PHI4 + 2])
    b, m, _ = euler_equations(J4, t4, pd4, N4)
    # Cramer's rule on the symmetric 3x3 block
    c0 = m[4] * m[8] - m[5] * m[7]
    c1 = m[5] * m[6] - m[3] * m[8]
    c2 = m[3] * m[7] - m[4] * m[6]
    det = m[0] * c0 + m[1] * c1 + m[2] * c2
    if not det > 0.0:
        return False
    x0 = (b[0] * c0 + b[1] * (m[2] * m[7] - m[1] * m[8]) + b[2] * (m[1] * m[5] - m[2] * m[4])) / det
    x1 = (b[0] * c1 + b[1] * (m[0] * m[8] - m[2] * m[6]) + b[2] * (m[2] * m[3] - m[0] * m[5])) / det
    x2 = (b[0] * c2 + b[1] * (m[1] * m[6] - m[0] * m[7]) + b[2] * (m[0] * m[4] - m[1] * m[3])) / det
    dy[qd + Y_PHI4] = x0
    dy[qd + Y_PHI4 + 1] = x1
    dy[qd + Y_PHI4 + 2] = x2
    return True


HALF_PI = 0.5 * math.pi


@compiled(inline="always")
def planar_rod(y, p):
    """The slider-crank's rod held in the crank's plane (Baumgarte rows on x3 = 0 and
    alpha3 = pi/2, the rod's axis in the plane): their accelerations (x3dd, a3dd). Its pins'
    axial play is ideal, as the crank bearing's at O: balls free across the plane left it
    (rounding grew 1,000-fold a revolution under the benchmark's impacts)."""
    a_b = p[P_BAUM_A]
    b_b = p[P_BAUM_B]
    x3dd = -2.0 * a_b * y[Y_QD + Y_R3] - b_b * b_b * y[Y_R3]
    a3dd = -2.0 * a_b * y[Y_QD + Y_PHI3] - b_b * b_b * (y[Y_PHI3] - HALF_PI)
    return x3dd, a3dd


@compiled(inline="always")
def rod_equations(F3, N3, F4x, y, t3, J3, gdd3, vz, g, a3dd):
    """Generalised forces of the free coordinates (x3, y3, z3, alpha3, beta3, x4) into
    vz[VZ_FORCE]; returns (mr_inv, ok): the inverse of the rod's 2x2 rotational mass block
    over (alpha3, beta3) (row-major 4-tuple) and whether that block is positive definite.
    The slider-crank (``g`` 1) holds alpha3 (its acceleration ``a3dd``, :func:`planar_rod`):
    beta3's 1x1 block alone."""
    qd = Y_QD
    pd3 = (y[qd + Y_PHI3], y[qd + Y_PHI3 + 1], y[qd + Y_PHI3 + 2])
    Qp3, Mr3, _ = euler_equations(J3, t3, pd3, N3)
    vz[VZ_FORCE, 0] = F3[0]
    vz[VZ_FORCE, 1] = F3[1]
    vz[VZ_FORCE, 2] = F3[2]
    vz[VZ_FORCE, 3] = Qp3[0] - Mr3[2] * gdd3
    vz[VZ_FORCE, 4] = Qp3[1] - Mr3[5] * gdd3
    vz[VZ_FORCE, 5] = F4x
    if g == 1:
        vz[VZ_FORCE, 4] -= Mr3[3] * a3dd
        if not Mr3[4] > 0.0:
            return (0.0, 0.0, 0.0, 0.0), False
        return (0.0, 0.0, 0.0, 1.0 / Mr3[4]), True
    det = Mr3[0] * Mr3[4] - Mr3[1] * Mr3[3]
    if not det > 0.0:
        return (0.0, 0.0, 0.0, 0.0), False
    return (Mr3[4] / det, -Mr3[1] / det, -Mr3[3] / det, Mr3[0] / det), True


@compiled(inline="always")
def ideal_joint_rows(model, spec, y, t2, t3, wd2, rdd2, fixed, C, vz):
    """Rows of C (over the free coordinates) and right-hand sides vz[VZ_RHS] of the ideal
    spherical joints (A: crank pin = rod end; B: rod end = slider). Returns (nc, cons): the
    rows written and the largest position violation of these joints [m]. Where O has
    clearance the crank's centroid acceleration in the bearing's plane (rdd2's y, z) is
    free, a column of A's rows, and rdd2 brings only its axial part to the right-hand side.
    The slider-crank (``jointset.guide_axis`` 1) holds its rod in the crank's plane (x3 and
    alpha3 held, :func:`planar_rod`): its A and B are pins across that plane, whose rows are
    the two in it (y, z), the axial one the rod's hold. ``fixed``: the accelerations that
    single-body constraints fix, (gdd3, ydd4, zdd4, a3dd) (:func:`fixed_accelerations`,
    :func:`planar_rod`); ``model``: p and jp; ``spec``: the build's joint set (``jointset``)."""
    gdd3, ydd4, zdd4, a3dd = fixed
    p = model.p
    jp = model.jp
    a_b = p[P_BAUM_A]
    b_b = p[P_BAUM_B]
    uA2 = (0.0, 0.0, -0.5 * p[P_L2])
    uA3 = (-0.5 * p[P_L3], 0.0, 0.0)
    uB3 = (0.5 * p[P_L3], 0.0, 0.0)
    nc = 0
    cons = 0.0
    g = guide_axis(spec)
    i0 = g      # the first row: x (the RSSP), or y (the slider-crank's pins, x held)
    if not is_free(spec, jp, JOINT_A):
        free = o_free(spec, jp)
        if free:
            rdd2 = (rdd2[0], 0.0, 0.0)
        r2, v2, R2, w2 = body_state(y, t2, Y_R2, Y_PHI2)
        r3, v3, pd3 = body_motion(y, Y_R3, Y_PHI3)
        R3, w3 = body_frame(t3, pd3)
        G3 = gmat(t3)
        gq3 = gdot_phidot(t3, pd3[0], pd3[1], pd3[2])
        # crank pin acceleration (fully known: the crank is driven)
        a2A = add(rdd2, mv(R2, add(cross(wd2, uA2), cross(w2, cross(w2, uA2)))))
        JrA = point_jacobian_rot(R3, uA3, G3)
        p3A, v3A = point_state(r3, v3, R3, w3, uA3)
        p2A, v2A = point_state(r2, v2, R2, w2, uA2)
        cpos = sub(p3A, p2A)
        cvel = sub(v3A, v2A)
        quad = point_accel_quadratic(R3, w3, gq3, uA3)
        for i in range(i0, 3):
            r = nc + i - i0
            for k in range(NZ):
                C[r, k] = 0.0
            C[r, i] = 1.0
            C[r, 3] = JrA[3 * i]
            C[r, 4] = JrA[3 * i + 1]
            if free and i > 0:
                C[r, 5 + i] = -1.0
            rhs = (-2.0 * a_b * cvel[i] - b_b * b_b * cpos[i] - JrA[3 * i + 2] * gdd3
                   - quad[i] + a2A[i])
            if g == 1:
                rhs -= JrA[3 * i] * a3dd      # alpha3 held: its acceleration known
            vz[VZ_RHS, r] = rhs
            cons = max(cons, abs(cpos[i]))
        nc += 3 - i0
    if not is_free(spec, jp, JOINT_B):
        r3, v3, pd3 = body_motion(y, Y_R3, Y_PHI3)
        R3, w3 = body_frame(t3, pd3)
        G3 = gmat(t3)
        gq3 = gdot_phidot(t3, pd3[0], pd3[1], pd3[2])
        r4, v4, _ = body_motion(y, Y_R4, Y_PHI4)
        JrB = point_jacobian_rot(R3, uB3, G3)
        p3B, v3B = point_state(r3, v3, R3, w3, uB3)
        cpos = sub(r4, p3B)
        cvel = sub(v4, v3B)
        quad = point_accel_quadratic(R3, w3, gq3, uB3)
        # the slider's y, z: fixed by its guide, or free (columns 8, 9) where P has
        # clearance; its coordinate along the guide (x; the slider-crank's y) is column 5
        slide = p_free(spec, jp)
        if slide:
            known4 = (0.0, 0.0, 0.0)
        elif g == 0:
            known4 = (0.0, ydd4, zdd4)
        else:
            known4 = (ydd4, 0.0, zdd4)     # the slider-crank's x held, y along its guide
        for i in range(i0, 3):
            r = nc + i - i0
            for k in range(NZ):
                C[r, k] = 0.0
            C[r, i] = -1.0
            C[r, 3] = -JrB[3 * i]
            C[r, 4] = -JrB[3 * i + 1]
            rhs = (-2.0 * a_b * cvel[i] - b_b * b_b * cpos[i] - known4[i]
                   + JrB[3 * i + 2] * gdd3 + quad[i])
            if g == 1:
                rhs += JrB[3 * i] * a3dd
            vz[VZ_RHS, r] = rhs
            cons = max(cons, abs(cpos[i]))
        C[nc, 5] = 1.0          # the guide's row: x's (the RSSP), y's (the slider-crank)
        if slide and g == 0:
            C[nc + 1, 8] = 1.0
            C[nc + 2, 9] = 1.0
        elif slide:
            C[nc + 1, 9] = 1.0  # the slider-crank's z row (its x4 held, column 8 unused)
        nc += 3 - i0
    return nc, cons


@compiled(inline="always")
def schur_solve(C, S, L, nc, minv, mr_inv, vz):
    """Free accelerations into vz[VZ_ZDD] and the ideal joints' multipliers into
    vz[VZ_LAMBDA], by the Schur complement S = C M^-1 C^T (Cholesky). False if singular."""
    minv_apply(minv, mr_inv, vz, VZ_FORCE, VZ_MINV_FORCE)
    if nc == 0:
        for k in range(NZ):
            vz[VZ_ZDD, k] = vz[VZ_MINV_FORCE, k]
        return True
    for i in range(nc):
        vz[VZ_LAMBDA, i] = row_dot(C, i, vz, VZ_MINV_FORCE, minv, -vz[VZ_RHS, i])
    for jj in range(nc):
        for k in range(NZ):
            vz[VZ_WORK1, k] = C[jj, k]
        minv_apply(minv, mr_inv, vz, VZ_WORK1, VZ_WORK2)
        for i in range(jj, nc):
            acc = row_dot(C, i, vz, VZ_WORK2, minv, 0.0)
            S[i, jj] = acc
            S[jj, i] = acc
    if not solve_spd(S, vz, VZ_LAMBDA, nc, L):
        return False
    back_substitute(vz, VZ_FORCE, C, VZ_LAMBDA, nc, minv, mr_inv, VZ_WORK1, VZ_ZDD)
    return True


@compiled(inline="always")
def crank_reactions(p, F2, N2, y, t2, pdd2, rdd2):
    """The crank's multipliers from its own equations once the forces on it are known:
    (drive torque [N m], lambda_O [N], the revolute's multiplier on the crank)."""
    m2 = p[P_M2]
    J2 = (p[P_J2], p[P_J2 + 1], p[P_J2 + 2])
    uO = (0.0, 0.0, 0.5 * p[P_L2])
    qd = Y_QD
    pd2 = (y[qd + Y_PHI2], y[qd + Y_PHI2 + 1], y[qd + Y_PHI2 + 2])
    R2 = rotation(t2)
    Qp2, Mr2, G2 = euler_equations(J2, t2, pd2, N2)
    Mp2 = mv(Mr2, pdd2)
    lamO = sub(F2, scale(m2, rdd2))
    JO = point_jacobian_rot(R2, uO, G2)
    lam_ang = sub(sub(Qp2, Mp2), mtv(JO, lamO))
    return -lam_ang[2], lamO


@compiled(inline="always")
def kinetic_energy(p, y, t2, t3, t4):
    """Kinetic energy of crank, rod and slider [J]."""
    m2 = p[P_M2]
    m3 = p[P_M3]
    m4 = p[P_M4]
    J2 = (p[P_J2], p[P_J2 + 1], p[P_J2 + 2])
    J3 = (p[P_J3], p[P_J3 + 1], p[P_J3 + 2])
    J4 = (p[P_J4], p[P_J4 + 1], p[P_J4 + 2])
    _, v2, pd2 = body_motion(y, Y_R2, Y_PHI2)
    _, v3, pd3 = body_motion(y, Y_R3, Y_PHI3)
    _, v4, pd4 = body_motion(y, Y_R4, Y_PHI4)
    w2 = mv(gmat(t2), pd2)
    w3 = mv(gmat(t3), pd3)
    w4 = mv(gmat(t4), pd4)
    ke = 0.5 * (m2 * dot(v2, v2) + m3 * dot(v3, v3) + m4 * dot(v4, v4))
    ke += 0.5 * (J2[0] * w2[0] ** 2 + J2[1] * w2[1] ** 2 + J2[2] * w2[2] ** 2)
    ke += 0.5 * (J3[0] * w3[0] ** 2 + J3[1] * w3[1] ** 2 + J3[2] * w3[2] ** 2)
    ke += 0.5 * (J4[0] * w4[0] ** 2 + J4[1] * w4[1] ** 2 + J4[2] * w4[2] ** 2)
    return ke


@compiled(inline="always")
def assemble_qdd(dy, y, rdd2, pdd2, zdd, gdd3, ydd4, zdd4, g):
    """The state's derivative dy: the velocities, then the accelerations of the crank
    (rdd2, pdd2), the rod (zdd[0:5], its spin gdd3) and the slider (zdd[5] along the guide,
    global axis ``g``; ydd4 along the other horizontal axis, zdd4)."""
    qd = Y_QD
    for k in range(N_Q):
        dy[k] = y[qd + k]
    dy[qd + Y_R2] = rdd2[0]
    dy[qd + Y_R2 + 1] = rdd2[1]
    dy[qd + Y_R2 + 2] = rdd2[2]
    dy[qd + Y_PHI2] = pdd2[0]
    dy[qd + Y_PHI2 + 1] = pdd2[1]
    dy[qd + Y_PHI2 + 2] = pdd2[2]
    dy[qd + Y_R3] = zdd[0]
    dy[qd + Y_R3 + 1] = zdd[1]
    dy[qd + Y_R3 + 2] = zdd[2]
    dy[qd + Y_PHI3] = zdd[3]
    dy[qd + Y_PHI3 + 1] = zdd[4]
    dy[qd + Y_PHI3 + 2] = gdd3
    dy[qd + Y_R4 + g] = zdd[5]
    dy[qd + Y_R4 + 1 - g] = ydd4
    dy[qd + Y_R4 + 2] = zdd4


def _rod_side(joint):
    """+1 where the rod carries the joint's ball, -1 its socket, 0 neither."""
    return 1 if joint.ball.body == "rod" else (-1 if joint.socket.body == "rod" else 0)


#: Each joint's side on the rod (``joints.JOINTS``): +1 the rod carries its ball (B), -1
#: its socket (A), 0 neither (O, P): the one body of the RSSP whose rotation a joint's
#: mobility reads (:func:`point_mobility`).
ROD_SIDE = tuple(_rod_side(joint) for joint in JOINTS)

#: Each joint's attachment on the rod (its offsets as multiples of l3, along the rod's x
#: axis; 0 where the rod carries neither side).
ROD_FACTOR = tuple(next((att.factors[0] for att in (joint.ball, joint.socket)
                         if att.body == "rod"), 0.0) for joint in JOINTS)


@compiled
def rate_mobility(j, p, t3, r3, off_ball, off_socket, solve, mobility, g):
    """Mobility W_p of joint j's relative motion at the points its type's ``rate_point``
    names (:func:`point_mobility`, every constraint in place; ``mobility``: the solve's
    (cons, nc, minv, mr_inv); t3, r3: the rod's sines and cosines and its centroid). The
    rod's side is read at the joint's attachment on the rod moved by its offset there
    (``off_ball`` where the rod carries the ball, ``off_socket`` where it carries the
    socket): a zero offset is the attachment itself, a contact point's through the rod's
    frame; a joint the rod carries neither side of has no rod Jacobian."""
    _, nc, minv, mr_inv = mobility
    R3 = rotation(t3)
    G3 = gmat(t3)
    side = ROD_SIDE[j]
    u = (ROD_FACTOR[j] * p[P_L3], 0.0, 0.0)
    off = off_ball if side > 0 else off_socket
    if off[0] == 0.0 and off[1] == 0.0 and off[2] == 0.0:
        Jr = point_jacobian_rot(R3, u, G3)
    elif side == 0:
        Jr = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    else:
        qrod = add(add(r3, mv(R3, u)), off)
        Jr = point_jacobian_rot(R3, mtv(R3, sub(qrod, r3)), G3)
    return point_mobility(j, Jr, solve.C, solve.L, nc, minv, mr_inv, solve.vz, g)


@compiled(inline="always")
def end_diagnostics(model, spec, y, trigs, dy, dg, solve, acc, loads, mobility):
    """The diagnostics of an evaluation at a (sub-)step's end (:func:`evaluate` with
    ``full``): the slider's acceleration, the drive torque, each joint's force, the powers
    and energies, the constraint violation completed with the crank's and the slider's own
    constraints, and the stiff rate of the joints in or near contact (docs/physics.md
    section 4). ``trigs``: the bodies' (t2, t3, t4); ``acc``: the solve's (zdd, ydd4,
    zdd4); ``loads``: (fA, fB, torque, lamO, pdiss); ``mobility``: (cons, nc, minv,
    mr_inv), the ideal joints' violation and the solve's rows and inverse masses."""
    p = model.p
    jp = model.jp
    t2, t3, t4 = trigs
    zdd, ydd4, zdd4 = acc
    fA, fB, torque, lamO, pdiss = loads
    cons, nc, minv, mr_inv = mobility
    grav = (p[P_G], p[P_G + 1], p[P_G + 2])
    dg[D_SLIDER_ACC] = zdd[5]
    dg[D_TORQUE] = torque
    for i in range(3):
        # the bearing's force on the crank: the ideal revolute's reaction, or O's contact
        # force (stored with the contact) and the axial reaction
        f_o = dg[D_JOINT_FORCE + 3 * JOINT_O + i] if o_free(spec, jp) else 0.0
        dg[D_REACTION_O + i] = f_o - lamO[i]
        dg[D_JOINT_FORCE + 3 * JOINT_A + i] = fA[i]
        dg[D_JOINT_FORCE + 3 * JOINT_B + i] = fB[i]
        dg[D_JOINT_FORCE + 3 * JOINT_O + i] = f_o - lamO[i]
    if not p_free(spec, jp):
        # the ideal guide's reaction on the slider, from the slider's equations: across the
        # guide only (the guide takes no load along it, global axis g)
        g = guide_axis(spec)
        h = 1 - g
        dg[D_JOINT_FORCE + 3 * JOINT_P + g] = 0.0
        dg[D_JOINT_FORCE + 3 * JOINT_P + h] = p[P_M4] * (ydd4 - grav[h]) + fB[h]
        dg[D_JOINT_FORCE + 3 * JOINT_P + 2] = p[P_M4] * (zdd4 - grav[2]) + fB[2]
    dg[D_PDRIVE] = dy[Y_WORK]
    dg[D_PDISS] = pdiss
    dg[D_KE] = kinetic_energy(p, y, t2, t3, t4)
    r2 = (y[Y_R2], y[Y_R2 + 1], y[Y_R2 + 2])
    r3 = (y[Y_R3], y[Y_R3 + 1], y[Y_R3 + 2])
    r4 = (y[Y_R4], y[Y_R4 + 1], y[Y_R4 + 2])
    dg[D_PE_GRAV] = -(p[P_M2] * dot(grav, r2) + p[P_M3] * dot(grav, r3) + p[P_M4] * dot(grav, r4))
    R2 = rotation(t2)
    pO = add(r2, mv(R2, (0.0, 0.0, 0.5 * p[P_L2])))
    if o_free(spec, jp):
        cons = max(cons, abs(pO[0]))    # the axial position only: y, z move in the bearing
    else:
        cons = max(cons, max(abs(pO[0]), max(abs(pO[1]), abs(pO[2]))))
    if not p_free(spec, jp):
        cons = max(cons, max(abs(y[Y_R4 + 1 - guide_axis(spec)]), abs(y[Y_R4 + 2] - p[P_ZS])))
    if guide_axis(spec) == 1:
        # the rod held in the slider-crank's plane: its centroid's x and its ends' (alpha3)
        cons = max(cons, max(abs(y[Y_R3]), 0.5 * p[P_L3] * abs(y[Y_PHI3] - HALF_PI)))
        if p_free(spec, jp):
            # the free block held in it too: its x4, its corners' reach of alpha4 and beta4
            reach = 0.5 * jp[JOINT_P, J_BLOCK_LENGTH]
            cons = max(cons, max(abs(y[Y_R4]), reach * max(abs(y[Y_PHI4]),
                                                           abs(y[Y_PHI4 + 1]))))
    dg[D_CONS] = cons
    # the stiff rate of each joint with clearance or a bushing: its type's, on the mobility
    # of the points it names (docs/physics.md section 4)
    rate = 0.0
    for j in range(N_JOINTS):
        if not (is_bushing(spec, jp, j) or has_clearance(spec, jp, j)):
            continue
        due, mobile, off_ball, off_socket = kinds.rate_point(spec, j, model, dg)
        if not due:
            continue
        wp = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        if mobile:
            wp = rate_mobility(j, p, t3, r3, off_ball, off_socket, solve, mobility,
                               guide_axis(spec))
        rate = max(rate, kinds.force_rate(spec, j, model, dg, wp, y,
                                          kinds.elastic_law(spec, p, j)))
    dg[D_RATE] = rate


#: Local variables that Numba must type as plain int64: a constant argument would otherwise
#: compile the callee once per value (a Literal specialisation).
_NOT_LITERAL = {"joint_a": types.int64, "joint_b": types.int64, "joint_o": types.int64,
                "joint_p": types.int64}


@compiled(inline="always", locals=_NOT_LITERAL)
def applied_loads(y, t2, t3, t4, model, spec, full, dg, dy):
    """The forces and moments on the crank, the rod and the slider from gravity and from the
    joints with clearance or a bushing (each joint's type's ``contact``: its state into dg
    with ``full``; the guide's block through :func:`free_slider`, which writes its free
    accelerations' share into dy): (F2, N2, F3, N3, F4, fA, fB, pdiss, ok); fA, fB the
    contact forces on the balls of A and B (zero where ideal), pdiss the power dissipated
    [W], ok False where the guide's equations are singular.

    Each body's rotation, angular velocity and the other products of its Euler angles'
    sines and cosines (``t2``, ``t3``, ``t4``: ``trig``, computed once by :func:`evaluate`)
    are formed again in each part that uses them (:func:`body_state`), rather than all up
    front: few values then stay live across the contacts, which is what a GPU thread's
    registers hold (``python -m clearsweep.ptx``). The crank's and rod's frames are the
    exception on a CPU, formed once before the contacts (forming them in each contact cost
    the CPU about 3 %); a device build (``target.on_device``) forms them in each contact."""
    p = model.p
    jp = model.jp
    joint_a = JOINT_A
    joint_b = JOINT_B
    joint_o = JOINT_O
    joint_p = JOINT_P
    uA2 = (0.0, 0.0, -0.5 * p[P_L2])
    uA3 = (-0.5 * p[P_L3], 0.0, 0.0)
    uB3 = (0.5 * p[P_L3], 0.0, 0.0)
    zero = (0.0, 0.0, 0.0)
    grav = (p[P_G], p[P_G + 1], p[P_G + 2])
    F2 = scale(p[P_M2], grav)
    N2 = zero
    F3 = scale(p[P_M3], grav)
    N3 = zero
    F4 = scale(p[P_M4], grav)
    N4 = zero
    pdiss = 0.0
    if full:
        clear_contacts(dg)
    fA = zero
    fB = zero
    # crank and rod frames: once before the contacts on a CPU; in a device build each
    # contact forms those it uses (few values live across the contacts: a GPU thread's
    # registers), the rod's twice when both joints have clearance
    local = on_device()
    if not local:
        r2, v2, R2, w2 = body_state(y, t2, Y_R2, Y_PHI2)
        r3, v3, R3, w3 = body_state(y, t3, Y_R3, Y_PHI3)
    # joint A: ball = crank pin, socket = rod end (socket frame: rod)
    if is_free(spec, jp, joint_a):
        if local:
            r2, v2, R2, w2 = body_state(y, t2, Y_R2, Y_PHI2)
            r3, v3, R3, w3 = body_state(y, t3, Y_R3, Y_PHI3)
        fA, mA2, mA3, dA = kinds.contact(spec, joint_a, model, (r2, v2, R2, w2, uA2),
                                         (r3, v3, R3, w3, uA3), full, dg)
        F2 = add(F2, fA)
        N2 = add(N2, mA2)
        F3 = sub(F3, fA)
        N3 = sub(N3, mA3)
        pdiss += dA
    # joint B: ball = rod end, socket = slider (socket frame: slider)
    if is_free(spec, jp, joint_b):
        if local:
            r3, v3, R3, w3 = body_state(y, t3, Y_R3, Y_PHI3)
        r4, v4, R4, w4 = body_state(y, t4, Y_R4, Y_PHI4)
        fB, mB3, mB4, dB = kinds.contact(spec, joint_b, model, (r3, v3, R3, w3, uB3),
                                         (r4, v4, R4, w4, zero), full, dg)
        F3 = add(F3, fB)
        N3 = add(N3, mB3)
        F4 = sub(F4, fB)
        if p_free(spec, jp):
            N4 = sub(N4, mB4)
        pdiss += dB
    # joint O: ball = crank journal, socket = the ground's bearing (socket frame: global)
    if o_free(spec, jp):
        if local:
            r2, v2, R2, w2 = body_state(y, t2, Y_R2, Y_PHI2)
        gr, gv, gR, gw = GROUND
        # with full, the contact force on the journal into dg, completed by the axial
        # reaction below (kept there rather than live across the solve: a GPU thread's
        # registers)
        fO, mO2, _, dO = kinds.contact(spec, joint_o, model,
                                       (r2, v2, R2, w2, (0.0, 0.0, 0.5 * p[P_L2])),
                                       (gr, gv, gR, gw, zero), full, dg)
        F2 = add(F2, fO)
        N2 = add(N2, mO2)
        pdiss += dO

    # joint P: ball = the slider's block, socket = the ground's guide (global frame)
    if p_free(spec, jp):
        # the joint set as a run-time int64, not the build's literal: one build of
        # free_slider serves every set, as one did when it took the guide's axis
        fP, dP, ok = free_slider(joint_p, y, t4, model, N4, full, dg, dy, np.int64(spec))
        if not ok:
            return F2, N2, F3, N3, F4, fA, fB, pdiss, False
        F4 = add(F4, fP)
        pdiss += dP
    return F2, N2, F3, N3, F4, fA, fB, pdiss, True


@compiled(locals=_NOT_LITERAL)
def evaluate(t, y, model, dy, dg, full, solve, spec=ALL):
    """Right-hand side dy = f(t, y) of the mechanism; with ``full``, diagnostics into dg.

    Parameters
    ----------
    t : float
        Time [s].
    y : float64[38]
        State (layout.Y_*): q, qd, drive work, dissipated energy.
    model : work.Model
        p, jp: packed parameters (layout.P_*, layout.J_*); s: float64[N_JOINTS, N_S], the
        discrete contact state (impact velocity, contact angle) per joint; wmap:
        float64[N_JOINTS, npolar, nazim], the wear maps [m].
    dy : float64[38]
        Output derivative.
    dg : float64[N_D]
        Output diagnostics (forces, contact state, energies, constraint violation and the
        stiff rate of docs/physics.md section 4), written only with ``full``.
    full : bool
        An evaluation at a (sub-)step's end, whose diagnostics are used; RK4 stages and
        dopri5's inner stages need the derivative only.
    solve : work.Solve
        The float64 work arrays C, S, L (NZ x NZ) and vz (VZ_ROWS x NZ).
    spec : int
        The build's joint set (``jointset``: the joints that may have clearance), a
        compile-time constant of the integrators' builds: the joints outside it are ideal
        and their code is folded away. Default: every joint, each tested at run time.

    Returns
    -------
    int
        layout.ST_OK or layout.ST_SINGULAR.

    Each body's Euler-angle sines and cosines are computed once (``trig``); the frames
    formed from them, where the loads need them, are :func:`applied_loads`' arrangement.
    """
    p = model.p
    jp = model.jp
    C = solve.C
    S = solve.S
    L = solve.L
    vz = solve.vz
    joint_a = JOINT_A
    joint_b = JOINT_B
    qd = Y_QD
    t2 = trig(y[Y_PHI2], y[Y_PHI2 + 1], y[Y_PHI2 + 2])
    t3 = trig(y[Y_PHI3], y[Y_PHI3 + 1], y[Y_PHI3 + 2])
    t4 = trig(y[Y_PHI4], y[Y_PHI4 + 1], y[Y_PHI4 + 2])
    uA2 = (0.0, 0.0, -0.5 * p[P_L2])

    # ---- applied forces: gravity, the joints' contacts and bushings ----
    F2, N2, F3, N3, F4, fA, fB, pdiss, ok = applied_loads(y, t2, t3, t4, model, spec, full, dg,
                                                          dy)
    if not ok:
        return ST_SINGULAR

    # ---- accelerations that single-body constraints fix ----
    pdd2, wd2, rdd2 = crank_accelerations(t, y, p, t2)
    g = guide_axis(spec)
    gdd3, ydd4, zdd4 = fixed_accelerations(y, p, dy, not p_free(spec, jp), g)

    # ---- the free coordinates: rod equations, ideal joints, Schur solve ----
    J3 = (p[P_J3], p[P_J3 + 1], p[P_J3 + 2])
    x3dd, a3dd = planar_rod(y, p) if g == 1 else (0.0, 0.0)
    mr_inv, ok = rod_equations(F3, N3, F4[g], y, t3, J3, gdd3, vz, g, a3dd)
    if not ok:
        return ST_SINGULAR
    # the crank's centroid in the bearing's plane: free where O has clearance (forces
    # gravity, O's contact and A's contact, inverse mass 1/m2), else held (zero, 0)
    vz[VZ_FORCE, 6] = F2[1] if o_free(spec, jp) else 0.0
    vz[VZ_FORCE, 7] = F2[2] if o_free(spec, jp) else 0.0
    # the slider across its guide likewise, where P has clearance (forces gravity, P's and
    # B's contacts)
    # (the slider-crank's: z4 alone, its column 8 x4 held, :func:`planar_slider`)
    vz[VZ_FORCE, 8] = F4[1] if p_free(spec, jp) and g == 0 else 0.0
    vz[VZ_FORCE, 9] = F4[2] if p_free(spec, jp) else 0.0
    # the groups' inverse masses from the free-coordinate table, and the rod's x3's (held
    # in the slider-crank's plane, :func:`planar_rod`)
    minv = (group_inverse_mass(spec, p, jp, 0), group_inverse_mass(spec, p, jp, 1),
            group_inverse_mass(spec, p, jp, 2), group_inverse_mass(spec, p, jp, 3),
            0.0 if g == 1 else 1.0 / p[GROUP_MASS[0]])
    nc, cons = ideal_joint_rows(model, spec, y, t2, t3, wd2, rdd2, (gdd3, ydd4, zdd4, a3dd), C,
                                vz)
    if not schur_solve(C, S, L, nc, minv, mr_inv, vz):
        return ST_SINGULAR
    if g == 1:      # the rod held in the slider-crank's plane
        zdd = (x3dd, vz[VZ_ZDD, 1], vz[VZ_ZDD, 2], a3dd, vz[VZ_ZDD, 4], vz[VZ_ZDD, 5])
    else:
        zdd = (vz[VZ_ZDD, 0], vz[VZ_ZDD, 1], vz[VZ_ZDD, 2], vz[VZ_ZDD, 3], vz[VZ_ZDD, 4],
               vz[VZ_ZDD, 5])
    if o_free(spec, jp):
        rdd2 = (rdd2[0], vz[VZ_ZDD, 6], vz[VZ_ZDD, 7])
    if p_free(spec, jp):
        ydd4 = vz[VZ_ZDD, 8] if g == 0 else planar_slider(y, p)[0]
        zdd4 = vz[VZ_ZDD, 9]

    assemble_qdd(dy, y, rdd2, pdd2, zdd, gdd3, ydd4, zdd4, g)

    # ---- joint forces on the balls; crank multipliers ----
    k0 = 0
    if not is_free(spec, jp, joint_a):
        fA = (vz[VZ_LAMBDA, 0], vz[VZ_LAMBDA, 1], vz[VZ_LAMBDA, 2])
        k0 = 3
        if g == 1:      # the slider-crank's pin rows: y, z
            fA = (0.0, vz[VZ_LAMBDA, 0], vz[VZ_LAMBDA, 1])
            k0 = 2
        r2 = (y[Y_R2], y[Y_R2 + 1], y[Y_R2 + 2])
        R2 = rotation(t2)
        qA = add(r2, mv(R2, uA2))
        F2 = add(F2, fA)
        N2 = add(N2, body_moment(R2, r2, qA, fA))
    if not is_free(spec, jp, joint_b):
        if g == 1:
            fB = (0.0, vz[VZ_LAMBDA, k0], vz[VZ_LAMBDA, k0 + 1])
        else:
            fB = (vz[VZ_LAMBDA, k0], vz[VZ_LAMBDA, k0 + 1], vz[VZ_LAMBDA, k0 + 2])
    # with O's clearance, lamO keeps the axial reaction only (its y, z vanish to rounding)
    torque, lamO = crank_reactions(p, F2, N2, y, t2, pdd2, rdd2)
    dy[Y_WORK] = torque * y[qd + Y_PHI2 + 2]
    dy[Y_DISS] = pdiss
    if not full:
        return ST_OK

    end_diagnostics(model, spec, y, (t2, t3, t4), dy, dg, solve, (zdd, ydd4, zdd4),
                    (fA, fB, torque, lamO, pdiss), (cons, nc, minv, mr_inv))
    return ST_OK


@compiled(inline="always")
def clear_contacts(dg):
    """Zero both joints' contact diagnostics (an ideal joint keeps zeros)."""
    for j in range(N_JOINTS):
        dg[D_FN + j] = 0.0
        dg[D_FT + j] = 0.0
        dg[D_DELTA + j] = 0.0
        dg[D_DDOT + j] = 0.0
        dg[D_VT + j] = 0.0
        dg[D_UEL + j] = 0.0
        dg[D_HWEAR + j] = 0.0
        dg[D_ECC + j] = 0.0
        dg[D_CEFF + j] = 0.0
        dg[D_DFD + j] = 0.0
        dg[D_DFDD + j] = 0.0


@compiled
def evaluate_ideal(t, y, model, dy, dg, full, solve):
    """:func:`evaluate` in the build of the ideal mechanism (joint set ``jointset.NONE``:
    every joint's clearance folded away, the smallest build), for the seated start; the
    same build as ideal cases' kernel, where they run on one of that set."""
    return evaluate(t, y, model, dy, dg, full, solve, NONE)


def _diagnostics_at(t, y, p, jp, wmap, ideal=False):
    """The diagnostics dg (N_D) of one full :func:`evaluate` at state y and time t, from a
    fresh contact state and fresh work arrays, or None where the evaluation fails: what
    :func:`ideal_joint_forces` (``ideal``: the ideal mechanism's build) and
    :func:`start_contacts` read."""
    dg = np.zeros(N_D)
    solve = Solve(np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((NZ, NZ)),
                  np.zeros((VZ_ROWS, NZ)))
    model = Model(p, jp, np.zeros((N_JOINTS, N_S)), wmap)
    args = (float(t), np.ascontiguousarray(y, dtype=np.float64), model, np.zeros(y.shape[0]),
            dg, True, solve)
    if p[P_GUIDE] == 1.0:
        # the slider-crank's builds (its guide along y): the set a constant, as the kernel's
        build = (NONE if ideal else ALL) | SLIDER_CRANK
        fn, extra = evaluate, (Build(build),)
    else:
        build = NONE if ideal else ALL
        fn, extra = (evaluate_ideal if ideal else evaluate), ()
    if (fn, build) in _HOST_READY:
        status = fn(*args, *extra)
    else:
        # the first call in this process may compile: once per machine (compiled.compile_lock)
        with compile_lock(fn, f"host{build}"):
            status = fn(*args, *extra)
        _HOST_READY.add((fn, build))
    return dg if status == ST_OK else None


#: The host's evaluations (:func:`_diagnostics_at`) this process has compiled or loaded:
#: (function, joint set).
_HOST_READY: set = set()


def ideal_joint_forces(t, y, p, jp):
    """Forces on the balls [N] (N_JOINTS x 3, global frame; O's: on the crank's journal) of
    the mechanism with every joint ideal, at state y and time t: the reactions a seated
    start leans the balls on.

    Plain Python around the compiled :func:`evaluate_ideal` (the argument types that
    rk4.integrate uses): a compiled wrapper of its own would optimise evaluate's code once
    more.
    """
    jp_ideal = jp.copy()
    jp_ideal[:, J_CLEARANCE] = 0.0
    out = np.full((N_JOINTS, 3), np.nan)
    dg = _diagnostics_at(t, y, p, jp_ideal, np.zeros((N_JOINTS, 1, 1)), ideal=True)
    if dg is None:
        return out
    for j in range(N_JOINTS):
        for i in range(3):
            out[j, i] = dg[D_JOINT_FORCE + 3 * j + i]
    return out


def start_contacts(y, p, jp, wmap):
    """Each clearance joint's contact at state y and t = 0, as the kernel computes it: the
    force on the ball [N] (N_JOINTS x 3, global frame), the normal force F_N [N] and the
    normal's line (global, unit). The contact state is a fresh episode's (no impact velocity
    yet). Plain Python around the compiled :func:`evaluate`, as :func:`ideal_joint_forces`;
    ``params.seated_offsets`` balances the spherical joints' friction with it."""
    force = np.full((N_JOINTS, 3), np.nan)
    fn = np.full(N_JOINTS, np.nan)
    normal = np.full((N_JOINTS, 3), np.nan)
    dg = _diagnostics_at(0.0, y, p, jp, np.ascontiguousarray(wmap, dtype=np.float64))
    if dg is None:
        return force, fn, normal
    for j in range(N_JOINTS):
        fn[j] = dg[D_FN + j]
        for i in range(3):
            force[j, i] = dg[D_JOINT_FORCE + 3 * j + i]
            normal[j, i] = dg[D_NGLOBAL + 3 * j + i]
    return force, fn, normal
