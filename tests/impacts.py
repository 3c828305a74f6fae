"""One ball-in-socket impact, integrated with the kernel's contact functions: the harness
that measures the restitution a contact law delivers (docs/physics.md section 3.2).

A 1-DOF model of the normal approach: the penetration x of a ball of mass ``m_eff`` that
meets the socket wall at ``v_in``, under the normal force of ``core.contact`` alone (no
gravity, no friction), integrated by RK4 at ``steps`` steps per two periods of the
contact's linearised vibration at its deepest penetration.
"""

import math

import numpy as np

from clearsweep.core import layout as L
from clearsweep.core.contact import (
    damping_factor,
    elastic_force,
    episode_impact_velocity,
    hysteresis_fraction,
    normal_force,
    reachable_penetration,
)

C = 2.5e-4      # radial clearance [m]
RI = 0.015      # socket radius [m]
RJ = RI - C     # ball radius [m]
EW = 1.1e11     # equivalent modulus [Pa]


def hertz_modulus_steel():
    """Hertz's contact modulus E* [Pa] of steel on steel from the material table's E and nu,
    in closed form: E* = [(1 - nu^2)/E + (1 - nu^2)/E]^-1 = E / (2 (1 - nu^2)) (Johnson,
    Contact Mechanics, 1985, eq. 4.22)."""
    from clearsweep.materials import load_materials

    steel = load_materials()["steel"]
    return steel.youngs_modulus_Pa / (2.0 * (1.0 - steel.poisson_ratio ** 2))


def impact_restitution(cr, v_in, m_eff=1.0, ew=EW, steps=4000, latch_floor=None, law=0, exponent=0.0,
                       onset=False):
    """Velocity ratio out/in of one ball-in-socket impact.

    ``law``: the damping law's index in choices.DAMPING_LAWS; ``exponent``: 0 the paper's
    elastic law, n > 0 the power law. Without ``latch_floor``: delta_dot0 = v_in throughout.
    With it: the kernel's discrete latch (``episode_impact_velocity`` after every step in
    contact, its running maximum or, ``onset``, its onset value; before the first such step
    each stage uses its own approach rate, as ``dynamics.contact`` does), starting half a
    step before touching.
    """
    dmax = reachable_penetration(0.0, m_eff, v_in, C, ew, RI, RJ, exponent)
    omega = math.sqrt(elastic_force(dmax, C, ew, RI, RJ, exponent)[1] / m_eff)
    h = 4 * math.pi / omega / steps
    num, den = hysteresis_fraction(law, cr)
    x, v = (0.0, v_in) if latch_floor is None else (-0.5 * h * v_in, v_in)
    dv0 = v_in if latch_floor is None else 0.0

    def acc(x, v):
        if x <= 0:
            return 0.0
        kappa = damping_factor(num, den, dv0 if dv0 > 0.0 else max(v, latch_floor))
        return -normal_force(x, v, C, ew, RI, RJ, exponent, kappa)[0] / m_eff

    for _ in range(20 * steps):
        k1x, k1v = v, acc(x, v)
        k2x, k2v = v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v)
        k3x, k3v = v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v)
        k4x, k4v = v + h * k3v, acc(x + h * k3x, v + h * k3v)
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
        v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if latch_floor is not None:
            dv0 = episode_impact_velocity(dv0, v, latch_floor, onset) if x > 0 else 0.0
        if x < 0 and v < 0:
            return -v / v_in
    raise AssertionError("ball did not leave the contact")


def scipy_impact(force, mass, v_in, cr, a_ext=0.0, rounds=4):
    """One impact of the 1-DOF model mass x'' = -F_N(x, x') + mass a_ext from x = 0 at x' =
    v_in until the contact opens, integrated by scipy (DOP853, rtol 1e-12); ``force(x, v,
    kappa)`` gives F_N with the damping factor kappa = 20 (1 - c_r) / (13 c_r x'_0) of the
    paper's law, x'_0 the impact's fastest approach (contact.impact_velocity's default): a
    fixed point of the model's own trajectory, reached in ``rounds`` rounds from v_in.

    Returns (duration [s], {"force": peak F_N [N], "penetration": peak x [m], "ratio": the
    exit/entry velocity ratio})."""
    from scipy.integrate import solve_ivp

    def leaves(t, z):
        return z[0] if t > 0.0 else 1.0
    leaves.terminal = True
    leaves.direction = -1
    dv0 = v_in
    for _ in range(rounds):
        kappa = 20.0 * (1.0 - cr) / (13.0 * cr * dv0)

        def rhs(_, z, kappa=kappa):
            return [z[1], -force(z[0], z[1], kappa) / mass + a_ext]

        sol = solve_ivp(rhs, (0.0, 1e-2), [0.0, v_in], method="DOP853", rtol=1e-12,
                        atol=[1e-17, 1e-12], events=leaves, dense_output=True)
        t_out = sol.t_events[0][0]
        z = sol.sol(np.linspace(0.0, t_out, 100001))
        dv0 = z[1].max()
    return t_out, {"force": max(force(x, v, kappa) for x, v in z.T), "penetration": z[0].max(),
                   "ratio": -sol.y_events[0][0][1] / v_in}


def kernel_impact(raw, ds, j):
    """The first contact episode of clearance joint j in a kernel run whose rows are its
    steps: (k0, k1: its first and last rows in contact, v_in: the approach rate where the
    penetration, linear between rows, crosses 0 on the way in, {"force": the rows' peak F_N
    [N], "penetration": their peak [m], "ratio": the exit/entry velocity ratio})."""
    delta = raw.d[:, L.D_DELTA + j]
    ddot = raw.d[:, L.D_DDOT + j]
    k0 = int(np.argmax(delta > 0.0))
    k1 = k0 + int(np.argmax(delta[k0:] <= 0.0)) - 1
    assert k0 > 2 and k1 > k0 + 100

    def crossing(k):
        f = delta[k] / (delta[k] - delta[k + 1])
        return ddot[k] + f * (ddot[k + 1] - ddot[k])

    v_in = crossing(k0 - 1)
    name = str(ds.joint.values[j])
    return k0, k1, v_in, {"force": ds.normal_force.sel(joint=name).values[k0:k1 + 1].max(),
                          "penetration": ds.penetration.sel(joint=name).values[k0:k1 + 1].max(),
                          "ratio": -crossing(k1) / v_in}
