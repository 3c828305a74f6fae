"""One ball-in-socket impact, integrated with the kernel's contact functions: the harness
that measures the restitution a contact law delivers (docs/physics.md section 3.2).

A 1-DOF model of the normal approach: the penetration x of a ball of mass ``m_eff`` that
meets the socket wall at ``v_in``, under the normal force of ``core.contact`` alone (no
gravity, no friction), integrated by RK4 at ``steps`` steps per two periods of the
contact's linearised vibration at its deepest penetration.
"""

import math

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
