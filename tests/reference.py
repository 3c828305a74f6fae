"""Slow, plain-numpy reference right-hand side of the RSSP mechanism (docs/physics.md sections 1-3, 8)
and of the planar slider-crank (docs/mechanisms.md).

Everything is built the obvious way, independently of the kernel's structured solver:

- one function ``constraints(q, t)`` straight from the table of docs/physics.md section 2;
- its Jacobian ``Cq``, ``C_t`` and the velocity-quadratic acceleration term ``h`` by
  finite differences (``C_ddot = Cq qdd + h``);
- the mass matrix from the kinetic energy with the body angular velocity taken from
  ``w~ = R^T R_dot`` (derivatives of the elementary rotations), and the velocity-quadratic
  generalised force from Lagrange's equations by finite differences;
- gravity and the contact law of docs/physics.md section 3, applied at the contact points through
  finite-difference point Jacobians;
- joint O with clearance (the crank's journal in the ground's bearing, axis x at the origin):
  the revolute's rows keep the axial one (x of the crank's point O; the tilt and driver rows
  stay), and the journal's contact force (Hertz's law of internal cylinders, n = 3/2, with
  the conformal radius, section 3.6) acts at the contact point on the crank;
- joint P with clearance (the slider's block in the ground's guide, axis x at height z_s):
  the prismatic rows go, and each of the block's eight corners (rounded, edge radius r_c)
  pushes on the wall it crosses with Hertz's point-on-flat law, F = (4/3) E* sqrt(r_c)
  delta^(3/2), damping and friction written from their formulas, at the corner
  (section 3.7); on walls worn by a given map read bilinearly (``wear.feedback`` and
  ``wear.interpolate``), the depth from scipy's linear interpolation between the bin
  centres and the force along the penetration's gradient, by differences (section 3.5);
- an elastic bushing at A, B or O (``jp[j, J_BUSHING]``): the joint's rows go (at O the
  axial row stays) and the linear spring-damper F = -(k_r e_r + c_r w_r) - (k_a e_a + c_a w_a)
  acts at the ball point on both bodies, e the ball point's offset from the socket point,
  w the ball point's velocity against the socket's material point there (by point
  Jacobians), split along the socket body's local x axis (the ground's: global x);
- the elastic law of the case (``p[P_EXPONENT]``): the paper's k_N at A and B and Hertz's
  n = 3/2 at O (0), or the power law F_el = (4/3) E* sqrt(R_i R_j) c^(1-n) delta^n at A, B
  and O (``contact.elastic: hertz``, n > 0);
- the slider's guide along the global axis ``p[P_GUIDE]`` (0: x, the RSSP; 1: y, the planar
  slider-crank, whose bodies are the RSSP's): the guide is the line through (0, 0, z_s) along
  that axis, and the prismatic rows hold the slider's offset from it along the two directions
  across it (e_z x e_guide and e_z) and its three angles; the slider-crank's guide with
  clearance keeps the rows of its plane's normal: the slider's offset along e_z x e_guide
  (x = 0) and its angles alpha4 = beta4 = 0, its block (length along the guide, width along
  e_z x e_guide, height along e_z) meeting the same four walls;
- the full dense (18 + m) x (18 + m) KKT system solved with ``numpy.linalg.solve``.

Finite differences use fourth-order five-point stencils (errors stated in ``STEP_*``).
Only the index constants of ``clearsweep.core.layout`` and the joints' rows
(``clearsweep.core.joints.INDEX``) are used from the kernel package.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from clearsweep.core import layout as L
from clearsweep.core.joints import INDEX, N_JOINTS

#: Step of the first-derivative stencils in q (m and rad). Five-point stencil: truncation
#: ~ STEP^4 / 30 * |f^(5)| ~ 1e-12 / 30 * 0.2 m, round-off ~ eps * |f| / STEP ~ 2e-17 / 1e-3,
#: i.e. ~1e-13 relative for the constraint Jacobian and the point Jacobians.
STEP_Q = 1e-3
#: Largest coordinate change of the second-derivative stencil along (qd, 1): the step in the
#: path parameter is STEP_PATH / max|qd|. Truncation ~ STEP_PATH^4 w^2 |C| / 90 ~ 5e-11 and
#: round-off ~ 5 eps |C| / (STEP_PATH / w)^2 ~ 2e-10 m/s^2 in float64 (w ~ 2 pi rad/s,
#: |C terms| ~ 0.2 m), against |h| ~ 5 m/s^2; acceleration_terms works in extended precision
#: where available, which removes the round-off part.
STEP_PATH = 5e-3

# body blocks of q: crank 0:6, rod 6:12, slider 12:18; each [r (3), phi (3)]
CRANK, ROD, SLIDER = 0, 1, 2
# joints: rows of jp (the spherical joints A, B; the crank's revolute O)
JOINT_A, JOINT_B, JOINT_O, JOINT_P = INDEX["A"], INDEX["B"], INDEX["O"], INDEX["P"]
#: Exponent of the journal's Hertz law (internal cylinders; Flores et al. 2008).
JOURNAL_EXPONENT = 1.5


# ---------------------------------------------------------------------------
# rotations (R = Rz(alpha) Ry(beta) Rx(gamma)) and their derivatives
# ---------------------------------------------------------------------------

def rx(g):
    c, s = np.cos(g), np.sin(g)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry(b):
    c, s = np.cos(b), np.sin(b)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def drx(g):
    c, s = np.cos(g), np.sin(g)
    return np.array([[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])


def dry(b):
    c, s = np.cos(b), np.sin(b)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def drz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


def rotation(phi):
    a, b, g = phi
    return rz(a) @ ry(b) @ rx(g)


def rotation_derivatives(phi):
    """dR/d alpha, dR/d beta, dR/d gamma."""
    a, b, g = phi
    return (drz(a) @ ry(b) @ rx(g), rz(a) @ dry(b) @ rx(g), rz(a) @ ry(b) @ drx(g))


def vee(s):
    """Axial vector of a skew-symmetric matrix."""
    return np.array([s[2, 1], s[0, 2], s[1, 0]])


def body_rate_matrix(phi):
    """G with w' = G phi_dot, from w'~ = R^T R_dot = sum_k R^T (dR/d phi_k) phi_dot_k."""
    r = rotation(phi)
    return np.column_stack([vee(r.T @ d) for d in rotation_derivatives(phi)])


# ---------------------------------------------------------------------------
# finite differences
# ---------------------------------------------------------------------------

def d1(f, x, h):
    """Five-point central first derivative of f at scalar x."""
    return (8.0 * (f(x + h) - f(x - h)) - (f(x + 2 * h) - f(x - 2 * h))) / (12.0 * h)


def d2(f, x, h):
    """Five-point central second derivative of f at scalar x."""
    return (-f(x + 2 * h) + 16.0 * f(x + h) - 30.0 * f(x) + 16.0 * f(x - h)
            - f(x - 2 * h)) / (12.0 * h * h)


def jacobian(f, x, h=STEP_Q):
    """df/dx (rows: outputs) by five-point differences in every coordinate."""
    x = np.array(x)
    h = x.dtype.type(h)
    cols = []
    for k in range(x.size):
        def fk(s, k=k):
            xs = x.copy()
            xs[k] += s
            return np.atleast_1d(f(xs))
        cols.append(d1(fk, 0.0, h))
    return np.column_stack(cols)


# ---------------------------------------------------------------------------
# the mechanism
# ---------------------------------------------------------------------------

@dataclass
class Mechanism:
    """Parameters read from the packed vectors p, jp (layout index constants)."""

    p: np.ndarray
    jp: np.ndarray
    wmap: np.ndarray | None = None      # the wear map (N_JOINTS x rows x columns) [m]
    l2: float = field(init=False)
    l3: float = field(init=False)
    zs: float = field(init=False)

    def __post_init__(self):
        p = self.p
        self.l2, self.l3, self.zs = p[L.P_L2], p[L.P_L3], p[L.P_ZS]
        self.mass = np.array([p[L.P_M2], p[L.P_M3], p[L.P_M4]])
        self.inertia = [np.array(p[k:k + 3]) for k in (L.P_J2, L.P_J3, L.P_J4)]
        self.gravity = np.array(p[L.P_G:L.P_G + 3])
        self.omega, self.theta0 = p[L.P_OMEGA], p[L.P_THETA0]
        self.a, self.b = p[L.P_BAUM_A], p[L.P_BAUM_B]
        self.u_O = np.array([0.0, 0.0, 0.5 * self.l2])     # crank point at O
        self.u_A2 = np.array([0.0, 0.0, -0.5 * self.l2])   # crank pin (ball of A)
        self.u_A3 = np.array([-0.5 * self.l3, 0.0, 0.0])   # rod socket of A
        self.u_B3 = np.array([0.5 * self.l3, 0.0, 0.0])    # rod ball of B
        self.u_B4 = np.zeros(3)                             # slider socket of B (centroid)
        self.bushing = [self.jp[j, L.J_BUSHING] != 0.0 for j in range(N_JOINTS)]
        self.ideal = [self.jp[j, L.J_CLEARANCE] == 0.0 and not self.bushing[j]
                      for j in range(N_JOINTS)]
        # the elastic law: 0 the paper's (Hertz's n = 3/2 at the journal), n > 0 the power law
        self.exponent = float(p[L.P_EXPONENT])
        # the guide: the line through (0, 0, z_s) along the global axis e_guide; the slider's
        # offset from it is measured along e_across (horizontal, across the guide) and e_z
        self.guide = int(p[L.P_GUIDE])
        assert self.guide in (0, 1), "the guide runs along global x or y"
        e_z = np.array([0.0, 0.0, 1.0])
        self.e_guide = np.eye(3)[self.guide]
        self.e_across = np.cross(e_z, self.e_guide)       # x: +y (the RSSP); y: -x
        self.e_up = e_z
        self.guide_origin = np.array([0.0, 0.0, self.zs])
        # the guide's frame: the block's length, width and height along its columns
        self.guide_basis = np.column_stack([self.e_guide, self.e_across, self.e_up])
        # the slider-crank is planar: its rod is held in the plane of the guide and e_z (its
        # centroid's offset along the plane's normal 0, its axis in the plane: alpha3 = pi/2),
        # and its A and B are pins across that plane, whose constraints are the two in it
        self.planar = self.guide == 1
        self.in_plane = np.array([self.e_guide, e_z]) if self.planar else np.eye(3)

    # spherical joint j: (ball body, ball offset, socket body, socket offset)
    def joint_bodies(self, j):
        if j == JOINT_A:
            return CRANK, self.u_A2, ROD, self.u_A3
        return ROD, self.u_B3, SLIDER, self.u_B4

    def rows(self):
        """Row ranges of constraints(): dict name -> slice."""
        k = 3 if self.ideal[JOINT_O] else 1
        out = {"O": slice(0, k), "angles2": slice(k, k + 2), "driver": slice(k + 2, k + 3)}
        k += 3
        pin = len(self.in_plane)
        for j, name in ((JOINT_A, "A"), (JOINT_B, "B")):
            if self.ideal[j]:
                out[name] = slice(k, k + pin)
                k += pin
        if self.planar:
            out["planar"] = slice(k, k + 2)
            k += 2
        out["spin3"] = slice(k, k + 1)
        rows_p = 5 if self.ideal[JOINT_P] else (3 if self.planar else 0)
        out["prismatic"] = slice(k + 1, k + 1 + rows_p)
        out["m"] = k + 1 + rows_p
        return out

    def constraints(self, q, t):
        """C(q, t), docs/physics.md section 2's table (in q's precision)."""
        c = []
        p_o = point(q, CRANK, self.u_O)                          # revolute O at the origin;
        c.extend(p_o if self.ideal[JOINT_O] else p_o[:1])        # with clearance, axial only
        c.extend([q[3], q[4]])                                   # alpha2 = beta2 = 0
        c.append(q[5] - (self.theta0 + self.omega * t))          # driver
        if self.ideal[JOINT_A]:                                  # spherical A: rod - crank pin
            c.extend(self.in_plane @ (point(q, ROD, self.u_A3) - point(q, CRANK, self.u_A2)))
        if self.ideal[JOINT_B]:                                  # spherical B: slider - rod end
            c.extend(self.in_plane @ (point(q, SLIDER, self.u_B4) - point(q, ROD, self.u_B3)))
        if self.planar:                                          # the rod in the plane
            normal = np.cross(self.e_guide, np.array([0.0, 0.0, 1.0]))
            c.extend([q[6:9] @ normal, q[9] - np.pi / 2])
        c.append(q[11])                                          # rod spin gamma3 = 0
        if self.ideal[JOINT_P]:                                  # prismatic: on the guide's
            off = q[12:15] - self.guide_origin                   # line, unrotated
            c.extend([off @ self.e_across, off @ self.e_up, q[15], q[16], q[17]])
        elif self.planar:                                        # the free block in the plane
            off = q[12:15] - self.guide_origin
            c.extend([off @ self.e_across, q[15], q[16]])
        return np.array(c)

    def mass_matrix(self, q):
        """M from T = 1/2 sum(m |r_dot|^2 + w'^T J w'), w' = G(phi) phi_dot."""
        m = np.zeros((18, 18))
        for b in range(3):
            i = 6 * b
            m[i:i + 3, i:i + 3] = self.mass[b] * np.eye(3)
            g = body_rate_matrix(q[i + 3:i + 6])
            m[i + 3:i + 6, i + 3:i + 6] = g.T @ np.diag(self.inertia[b]) @ g
        return m

    def kinetic_energy(self, q, qd):
        return 0.5 * qd @ self.mass_matrix(q) @ qd

    def quadratic_force(self, q, qd):
        """Q_v = dT/dq - d/dt(dT/dq_dot) at qdd = 0, by finite differences."""
        dtdq = jacobian(lambda x: self.kinetic_energy(x, qd), q)[0]
        hs = STEP_Q / max(1.0, np.max(np.abs(qd)))
        mdot = d1(lambda s: self.mass_matrix(q + s * qd), 0.0, hs)
        return dtdq - mdot @ qd

    def gravity_force(self):
        qg = np.zeros(18)
        for b in range(3):
            qg[6 * b:6 * b + 3] = self.mass[b] * self.gravity
        return qg


def point(q, body, u):
    """Global position of the point at body offset u."""
    i = 6 * body
    return q[i:i + 3] + rotation(q[i + 3:i + 6]) @ u


def point_jacobian(q, body, u):
    """d r_P / dq (3 x 18) of a body-fixed point, by finite differences."""
    return jacobian(lambda x: point(x, body, u), q)


def body_offset(q, body, x):
    """Body-frame offset of the global point x."""
    i = 6 * body
    return rotation(q[i + 3:i + 6]).T @ (x - q[i:i + 3])


# ---------------------------------------------------------------------------
# contact (docs/physics.md section 3), unworn socket
# ---------------------------------------------------------------------------

def normal_force(delta, ddot, c, ew, ri, kappa):
    """F_N = k_N(delta) delta (1 + kappa delta_dot), clamped >= 0; and F_el = k_N delta."""
    if delta <= 0.0:
        return 0.0, 0.0
    kn = (4.0 * np.pi * ew * ri / 5.0) * (2.0 * delta * c + delta ** 2) / (c + delta) ** 2
    fel = kn * delta
    return max(0.0, fel * (1.0 + kappa * ddot)), fel


def friction_factor(vt, v0, v1):
    """c_d of docs/physics.md section 3.3 as the piecewise-linear curve through its corners
    (v0, 0) and (v1, 1), held flat outside them: np.interp, not the kernel's branches."""
    return float(np.interp(vt, [v0, v1], [0.0, 1.0]))


@dataclass
class ContactResult:
    force: np.ndarray           # on the ball, global [N]
    generalized: np.ndarray     # generalised force of the pair (18)
    n: np.ndarray
    delta: float
    ddot: float
    ecc: float
    vt: np.ndarray
    fn: float
    fel: float
    ft: float
    kappa: float
    dfn_ddelta: float
    dfn_dddot: float
    pdiss: float
    j_rel: np.ndarray           # d(Q_j on ball)/dq - d(Q_i on socket)/dq (3 x 18)
    q_ball: np.ndarray
    q_socket: np.ndarray


def contact(mech: Mechanism, j, q, qd, dv0_stored=0.0):
    """Contact state and forces of clearance joint j (A, B: spherical in the RSSP, journals in
    the slider-crank; O: the journal; P: the block's corners; a bushing at A, B or O). A
    slider-crank pin (``mech.planar``) is a journal in a bearing: its gap in the plane (y,
    z; the axial offset is the rod's held row), the journal's law as O's."""
    if mech.bushing[j]:
        return bushing_contact(mech, j, q, qd)
    if j == JOINT_O:
        return journal_contact(mech, q, qd, dv0_stored)
    if j == JOINT_P:
        return block_contact(mech, q, qd)
    jp = mech.jp[j]
    c, ri, rj, ew = jp[L.J_C], jp[L.J_RI], jp[L.J_RJ], jp[L.J_EW]
    bb, ub, sb, us = mech.joint_bodies(j)
    pb = point(q, bb, ub)
    ps = point(q, sb, us)
    d = pb - ps
    if mech.planar:
        d[0] = 0.0                                       # a pin: the gap in the plane
    e = np.linalg.norm(d)
    n = d / e if e > 0.0 else np.array([1.0, 0.0, 0.0])  # centred: no contact, any n
    qj = pb + rj * n
    qi = ps + ri * n
    jj = point_jacobian(q, bb, body_offset(q, bb, qj))
    ji = point_jacobian(q, sb, body_offset(q, sb, qi))
    n_pin = mech.exponent if mech.exponent > 0.0 else JOURNAL_EXPONENT

    def law(delta, ddot, kappa):
        if mech.planar:
            return journal_force(delta, ddot, c, ew, ri, rj, kappa, n_pin)
        if mech.exponent > 0.0:
            return journal_force(delta, ddot, c, ew, ri, rj, kappa, mech.exponent)
        return normal_force(delta, ddot, c, ew, ri, kappa)

    return respond(mech, j, qd, e, n, e - c, qj, qi, jj, ji, law, dv0_stored)


def bushing_contact(mech: Mechanism, j, q, qd):
    """Force of the bushing at joint j: the linear spring-damper between the ball point and the
    socket point (A: crank pin / rod end; B: rod end / slider centroid; O: the crank's point O
    / the origin on the ground), split along the socket body's local x axis."""
    jp = mech.jp[j]
    if j == JOINT_O:
        bb, ub, sb, us = CRANK, mech.u_O, None, None
    else:
        bb, ub, sb, us = mech.joint_bodies(j)
    pb = point(q, bb, ub)
    jj = point_jacobian(q, bb, ub)
    if sb is None:                      # the ground: at the origin, unrotated
        ps, axis, ji = np.zeros(3), np.array([1.0, 0.0, 0.0]), np.zeros((3, 18))
    else:
        ps = point(q, sb, us)
        axis = rotation(q[6 * sb + 3:6 * sb + 6])[:, 0]
        ji = point_jacobian(q, sb, body_offset(q, sb, pb))   # the socket's point at pb
    e = pb - ps
    w = (jj - ji) @ qd

    def parts(v):
        along = float(axis @ v) * axis
        return along, v - along

    e_a, e_r = parts(e)
    w_a, w_r = parts(w)
    force = -(jp[L.J_K_RADIAL] * e_r + jp[L.J_C_RADIAL] * w_r
              + jp[L.J_K_AXIAL] * e_a + jp[L.J_C_AXIAL] * w_a)
    pdiss = float(jp[L.J_C_RADIAL] * w_r @ w_r + jp[L.J_C_AXIAL] * w_a @ w_a)
    size = float(np.linalg.norm(e))
    n = e / size if size > 0.0 else np.array([1.0, 0.0, 0.0])
    return ContactResult(force=force, generalized=jj.T @ force - ji.T @ force, n=n, delta=0.0,
                         ddot=float(n @ w), ecc=size, vt=np.zeros(3),
                         fn=float(np.linalg.norm(force)), fel=0.0, ft=0.0, kappa=0.0,
                         dfn_ddelta=jp[L.J_K_RADIAL], dfn_dddot=jp[L.J_C_RADIAL], pdiss=pdiss,
                         j_rel=jj - ji, q_ball=pb, q_socket=pb)


def journal_force(delta, ddot, c, ew, ri, rj, kappa, n=JOURNAL_EXPONENT):
    """The journal's F_N = F_el (1 + kappa delta_dot), clamped >= 0, and F_el: Hertz's law of a
    cylinder in a conforming cylindrical bearing, F_el = (4/3) E* sqrt(R_i R_j / c) delta^(3/2)
    (the conformal pair's radius R_i R_j / (R_i - R_j), R_i - R_j = c; Flores et al. 2008);
    with another exponent n the power law (4/3) E* sqrt(R_i R_j / c) c^(3/2 - n) delta^n
    (docs/physics.md section 3.2; c^0 = 1 exactly at n = 3/2). The power law at A and B too."""
    if delta <= 0.0:
        return 0.0, 0.0
    fel = 4.0 / 3.0 * ew * np.sqrt(ri * rj / c) * delta ** n * c ** (JOURNAL_EXPONENT - n)
    return max(0.0, fel * (1.0 + kappa * ddot)), fel


def journal_contact(mech: Mechanism, q, qd, dv0_stored=0.0):
    """Contact state and forces of joint O: the crank's journal (centre: the crank point O)
    in the ground's bearing (centre at the origin, axis x), the gap in the bearing's plane."""
    jp = mech.jp[JOINT_O]
    c, ri, rj, ew = jp[L.J_C], jp[L.J_RI], jp[L.J_RJ], jp[L.J_EW]
    pb = point(q, CRANK, mech.u_O)
    d = np.array([0.0, pb[1], pb[2]])                    # the axial offset is the ideal row's
    e = np.linalg.norm(d)
    n = d / e if e > 0.0 else np.array([0.0, 1.0, 0.0])
    qj = pb + rj * n                                     # on the journal
    qi = ri * n                                          # on the bearing, which does not move
    jj = point_jacobian(q, CRANK, body_offset(q, CRANK, qj))

    n_law = mech.exponent if mech.exponent > 0.0 else JOURNAL_EXPONENT

    def law(delta, ddot, kappa):
        return journal_force(delta, ddot, c, ew, ri, rj, kappa, n_law)

    return respond(mech, JOINT_O, qd, e, n, e - c, qj, qi, jj, np.zeros_like(jj), law, dv0_stored)


def wall_depth(mech: Mechanism, wall, x, across):
    """Depth [m] of guide wall ``wall`` (0..3: +y, -y, +z, -z; its band of P's map, rows
    across the wall, columns along the guide) at x along the guide and ``across`` (z - z_s on
    a y wall, y on a z wall): scipy's linear interpolation between the bin centres, the
    point held inside the rectangle of the centres."""
    from scipy.interpolate import RegularGridInterpolator

    jp = mech.jp[JOINT_P]
    band_rows = mech.wmap.shape[1] // 4
    ncol = mech.wmap.shape[2]
    half = (0.5 * jp[L.J_HEIGHT] + jp[L.J_CZ]) if wall < 2 else (0.5 * jp[L.J_WIDTH] + jp[L.J_CY])
    xs = jp[L.J_X0] + (np.arange(ncol) + 0.5) * jp[L.J_XSPAN] / ncol
    ac = -half + (np.arange(band_rows) + 0.5) * 2.0 * half / band_rows
    band = mech.wmap[JOINT_P, wall * band_rows:(wall + 1) * band_rows]
    if band_rows == 1:
        return float(np.interp(x, xs, band[0]))
    read = RegularGridInterpolator((ac, xs), band)
    return float(read([[np.clip(across, ac[0], ac[-1]), np.clip(x, xs[0], xs[-1])]])[0])


def edge_loads(da, db, kl, length):
    """The loads [N] that an edge line of length ``length`` [m], pressed into its wall by da
    at its end a and db at its end b (linear between), puts on its two ends: the pressure
    per unit length kl max(delta(s), 0) against the linear shape functions (1 - s/L, s/L),
    integrated by scipy's quad (the kink where delta = 0 given to it)."""
    from scipy.integrate import quad

    def delta(s):
        return da + (db - da) * s / length

    if da <= 0.0 and db <= 0.0:
        return 0.0, 0.0
    kink = [length * da / (da - db)] if da * db < 0.0 else None
    fa = quad(lambda s: kl * max(delta(s), 0.0) * (1.0 - s / length), 0.0, length,
              points=kink, epsabs=0.0, epsrel=1e-13)[0]
    fb = quad(lambda s: kl * max(delta(s), 0.0) * s / length, 0.0, length,
              points=kink, epsabs=0.0, epsrel=1e-13)[0]
    return fa, fb


def block_contact(mech: Mechanism, q, qd):
    """Contact state and forces of joint P: the block (length 2a, width 2b, height 2h about
    the slider's centroid) against its guide's walls (at y = +-(b + c_y), z = z_s +- (h + c_z),
    worn by ``mech.wmap`` where the case reads it bilinearly). Each wall meets the block's
    face along the face's two long edges, each a line whose penetration is linear between
    its end corners and whose pressure per unit length is k_l max(delta, 0),
    k_l = E* sqrt(W / (pi L)) (docs/physics.md 3.7; W the face's width, L its length): each
    corner takes its line's load on it (:func:`edge_loads`) as a point force, with a fresh
    episode's damping on its own approach rate. The result's force and generalised force
    are the sums over the corners; its contact values those of the corner that penetrates
    deepest."""
    jp = mech.jp[JOINT_P]
    half = 0.5 * np.array([jp[L.J_BLOCK_LENGTH], jp[L.J_WIDTH], jp[L.J_HEIGHT]])
    clear = {1: jp[L.J_CY], 2: jp[L.J_CZ]}
    centre = np.array([0.0, 0.0, mech.zs])
    # the guide's axes (along, across, up): the block's sides along them at zero rotation
    basis = mech.guide_basis
    ew = jp[L.J_EW]
    worn = (mech.wmap is not None and mech.p[L.P_FEEDBACK] != 0.0
            and mech.p[L.P_INTERP] != 0.0)
    pairs = [((sx, sy, sz), axis) for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)
             for axis in (1, 2)]

    def penetration(x, n, axis, wall):
        local = basis.T @ (x - centre)
        h = wall_depth(mech, wall, local[0], local[3 - axis]) if worn else 0.0
        return float(n @ (x - centre)) - half[axis] - clear[axis] - h

    def normal(signs, axis):
        n = signs[axis] * basis[:, axis]
        return n, 2 * (axis - 1) + (0 if signs[axis] > 0 else 1)

    depth = {}
    for signs, axis in pairs:
        n, wall = normal(signs, axis)
        depth[signs, axis] = penetration(point(q, SLIDER, basis @ (np.array(signs) * half)),
                                         n, axis, wall)
    loads = {}
    for (signs, axis), da in depth.items():
        if signs[0] > 0:
            continue
        other = (1, signs[1], signs[2])
        width = 2.0 * half[3 - axis]
        kl = ew * np.sqrt(width / (np.pi * 2.0 * half[0]))
        loads[signs, axis], loads[other, axis] = edge_loads(da, depth[other, axis], kl,
                                                            2.0 * half[0])
    total = np.zeros(3)
    gen = np.zeros(18)
    pdiss = 0.0
    deepest = None
    for signs, axis in pairs:
        u = basis @ (np.array(signs) * half)
        corner = point(q, SLIDER, u)
        jc = point_jacobian(q, SLIDER, u)
        n, wall = normal(signs, axis)
        delta = depth[signs, axis]
        fel = loads[signs, axis]

        def law(delta, ddot, kappa, fel=fel):
            if fel <= 0.0:
                return 0.0, 0.0
            return max(0.0, fel * (1.0 + kappa * ddot)), fel

        grad = None
        if worn:
            step = 1e-6
            grad = np.array([(penetration(corner + step * e, n, axis, wall)
                              - penetration(corner - step * e, n, axis, wall)) / (2.0 * step)
                             for e in np.eye(3)])
        res = respond(mech, JOINT_P, qd, 0.0, n, delta, corner, corner, jc,
                      np.zeros_like(jc), law, 0.0, grad)
        if res.fn > 0.0:
            # the kernel's bound on dF_N / d delta at a corner: its line's k_l L / 2
            width = 2.0 * half[3 - axis]
            kl = ew * np.sqrt(width / (np.pi * 2.0 * half[0]))
            res.dfn_ddelta = kl * half[0] * (1.0 + res.kappa * res.ddot)
        if deepest is None or delta > deepest.delta:
            deepest = res
        if fel > 0.0:
            total = total + res.force
            gen = gen + res.generalized
            pdiss += res.pdiss
    r = q[12:15] - centre
    deepest.ecc = float(np.hypot(r @ mech.e_across, r @ mech.e_up))
    deepest.force = total
    deepest.generalized = gen
    deepest.pdiss = pdiss
    return deepest


def respond(mech: Mechanism, j, qd, e, n, delta, qj, qi, jj, ji, law, dv0_stored, grad=None):
    """Forces of clearance joint j with eccentricity e, normal n and penetration delta, whose
    contact points qj (ball side, point Jacobian jj) and qi (socket side, ji) move with qd;
    ``law(delta, delta_dot, kappa)`` gives (F_N, F_el). ``grad``: delta's gradient with
    respect to the contact point where it is not n (a worn guide wall): the approach rate is
    grad . v and the normal force -F_N grad; the slip stays the velocity's part across n."""
    p, mu = mech.p, mech.jp[j, L.J_MU]
    j_rel = jj - ji
    v = j_rel @ qd
    vt = v - float(n @ v) * n
    if grad is None:
        grad = n
    ddot = float(grad @ v)
    vtn = float(np.linalg.norm(vt))
    dv0 = dv0_stored if dv0_stored > 0.0 else max(ddot, p[L.P_DV0_MIN])
    cr = p[L.P_CR]
    kappa = 20.0 * (1.0 - cr) / (13.0 * cr * dv0)
    fn, fel = law(delta, ddot, kappa)
    force = -fn * grad
    ft = 0.0
    if fn > 0.0 and p[L.P_FRICTION] != 0.0 and vtn > 0.0:
        ft = mu * friction_factor(vtn, p[L.P_V0], p[L.P_V1]) * fn
        force = force - ft * vt / vtn
    # slopes of F_N (kappa held fixed), by differences
    hd = 1e-3 * max(delta, 1e-9)
    dfd = 0.0
    if delta > 3.0 * hd:
        dfd = d1(lambda x: law(x, ddot, kappa)[0], delta, hd)
    hv = 1e-3 * max(abs(ddot), 1e-6)
    dfdd = d1(lambda x: law(delta, x, kappa)[0], ddot, hv) if fn > 0.0 else 0.0
    # dissipated power: -(power of the contact forces) - dU/dt
    pdiss = -(force @ v) - fel * ddot if fel > 0.0 else 0.0
    gen = jj.T @ force - ji.T @ force
    return ContactResult(force=force, generalized=gen, n=n, delta=delta, ddot=ddot, ecc=e,
                         vt=vt, fn=fn, fel=fel, ft=ft, kappa=kappa, dfn_ddelta=dfd,
                         dfn_dddot=dfdd, pdiss=pdiss, j_rel=j_rel, q_ball=qj, q_socket=qi)


# ---------------------------------------------------------------------------
# the augmented system
# ---------------------------------------------------------------------------

@dataclass
class Reference:
    qdd: np.ndarray
    lam: np.ndarray
    torque: float
    reaction_O: np.ndarray
    joint_force: np.ndarray     # (N_JOINTS, 3), on the balls; O's: the bearing's on the crank
    contacts: dict
    mass: np.ndarray
    cq: np.ndarray
    rhs: np.ndarray
    force: np.ndarray           # total applied generalised force
    mobility: np.ndarray        # constrained inverse mass W (18 x 18)
    drive_power: float
    dissipation: float
    rows: dict


def acceleration_terms(mech: Mechanism, q, qd, t):
    """Cq, C_t, C and h with C_ddot = Cq qdd + h (h by a second difference along (qd, 1)).

    Evaluated in numpy's extended precision where the platform has one (round-off of the
    second difference ~1e-13 instead of ~1e-10 m/s^2), returned as float64.
    """
    x = np.longdouble
    q, qd, t = q.astype(x), qd.astype(x), x(t)
    cfun = lambda z: mech.constraints(z, t)  # noqa: E731
    cq = jacobian(cfun, q)
    ct = d1(lambda s: mech.constraints(q, t + s), x(0.0), x(STEP_Q))
    hs = x(STEP_PATH) / max(x(1.0), np.max(np.abs(qd)))
    h = d2(lambda s: mech.constraints(q + s * qd, t + s), x(0.0), hs)
    return (cq.astype(float), ct.astype(float), cfun(q).astype(float), h.astype(float))


def evaluate(t, y, p, jp, dv0_stored=(0.0, 0.0), wmap=None) -> Reference:
    """Solve the full KKT system of docs/physics.md section 2 at state y (layout.Y_*) and time t;
    ``dv0_stored``: the stored impact velocities of the first joints (the rest 0); ``wmap``:
    the wear map that joint P's walls are read from (none: unworn)."""
    mech = Mechanism(np.asarray(p, float), np.asarray(jp, float), wmap)
    q = np.array(y[:L.N_Q], float)
    qd = np.array(y[L.Y_QD:L.Y_QD + L.N_Q], float)
    rows = mech.rows()
    m = rows["m"]

    mass = mech.mass_matrix(q)
    force = mech.gravity_force() + mech.quadratic_force(q, qd)
    dv0_stored = tuple(dv0_stored) + (0.0,) * (N_JOINTS - len(dv0_stored))
    contacts = {}
    for j in range(N_JOINTS):
        if not mech.ideal[j]:
            contacts[j] = contact(mech, j, q, qd, dv0_stored[j])
            force = force + contacts[j].generalized

    cq, ct, cval, h = acceleration_terms(mech, q, qd, t)
    cdot = cq @ qd + ct
    rhs = -h - 2.0 * mech.a * cdot - mech.b ** 2 * cval

    kkt = np.zeros((18 + m, 18 + m))
    kkt[:18, :18] = mass
    kkt[:18, 18:] = cq.T
    kkt[18:, :18] = cq
    sol = np.linalg.solve(kkt, np.concatenate([force, rhs]))
    qdd, lam = sol[:18], sol[18:]

    def constraint_force(name):
        """Generalised force -Cq^T lambda of one group of rows."""
        sl = rows[name]
        return -cq[sl].T @ lam[sl]

    # driver: its generalised force is -lambda e_gamma2; power = torque * gamma2_dot
    q_drive = constraint_force("driver")
    torque = q_drive[5]
    drive_power = float(q_drive @ qd)
    # the bearing's force on the crank: the revolute rows' (on the crank's centroid
    # coordinates), and with clearance the journal's contact force
    reaction_O = constraint_force("O")[0:3]
    if not mech.ideal[JOINT_O]:
        reaction_O = reaction_O + contacts[JOINT_O].force
    joint_force = np.zeros((N_JOINTS, 3))
    joint_force[JOINT_O] = reaction_O
    for j, name in ((JOINT_A, "A"), (JOINT_B, "B")):
        ball = mech.joint_bodies(j)[0]
        if mech.ideal[j]:
            joint_force[j] = constraint_force(name)[6 * ball:6 * ball + 3]
        else:
            joint_force[j] = contacts[j].force
    # the guide's force on the slider: the prismatic rows' on its centroid, or the corners'
    joint_force[JOINT_P] = (constraint_force("prismatic")[12:15] if mech.ideal[JOINT_P]
                            else contacts[JOINT_P].force)

    minv = np.linalg.inv(mass)
    s = cq @ minv @ cq.T
    mobility = minv - minv @ cq.T @ np.linalg.solve(s, cq @ minv)
    dissipation = sum(c.pdiss for c in contacts.values())
    return Reference(qdd=qdd, lam=lam, torque=float(torque), reaction_O=reaction_O,
                     joint_force=joint_force, contacts=contacts, mass=mass, cq=cq, rhs=rhs,
                     force=force, mobility=mobility, drive_power=drive_power,
                     dissipation=float(dissipation), rows=rows)


def point_mobility(ref: Reference, j):
    """W_p = J_rel W J_rel^T of clearance joint j: a_rel = W_p F for F on the ball."""
    jr = ref.contacts[j].j_rel
    return jr @ ref.mobility @ jr.T


def stiff_rates(ref: Reference, j, p, jp):
    """docs/physics.md section 4 rates of clearance joint j at its current state: (elastic/damping, friction, m_eff).

    elastic/damping: the largest root magnitude of m_eff s^2 + (dF/d delta_dot) s + dF/d delta;
    friction: mu c_d' F_N times the largest inverse mass across the tangent plane, c_d' the
    ramp slope 1/(v1 - v0) (meaningful for v0 <= |v_t| <= v1 only).
    """
    cres = ref.contacts[j]
    wp = point_mobility(ref, j)
    n = cres.n
    m_eff = 1.0 / float(n @ wp @ n)
    roots = np.roots([m_eff, cres.dfn_dddot, cres.dfn_ddelta])
    elastic = float(np.max(np.abs(roots)))
    proj = np.eye(3) - np.outer(n, n)
    inv_t = float(np.max(np.linalg.eigvalsh(proj @ wp @ proj)))
    friction = 0.0
    if p[L.P_FRICTION] != 0.0 and cres.fn > 0.0:
        friction = jp[j, L.J_MU] * cres.fn / (p[L.P_V1] - p[L.P_V0]) * inv_t
    return elastic, friction, m_eff
