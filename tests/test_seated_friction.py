"""The seated start balances friction at the spherical joints A and B (docs/physics.md 1.2):
each ball sits where its contact force, normal and friction together, is the ideal joint's
reaction, so that the start is stationary. The journal of O has its own tests
(tests/test_revolute.py, ``journal_seat``); the guide P cannot be balanced by its seat (its
walls are planes and its friction acts along the guide, docs/physics.md 1.2).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_revolute import deviation_from_closed_form

from clearsweep.simulation import simulate

#: The ideal mechanism's joint forces at the start [N] (A, B, O, P rows).
IDEAL = {"joints": {"A": {"clearance": 0.0}, "B": {"clearance": 0.0}},
         "solver": {"duration": 0.001, "save_every": 10}}


def one_joint(joint, **spec):
    """Joint ``joint`` alone with clearance (the other spherical joint ideal)."""
    other = "B" if joint == "A" else "A"
    return {joint: spec, other: {"clearance": 0.0}}


@pytest.fixture(scope="module")
def ideal_forces():
    return simulate(IDEAL).joint_force.values[0]


@pytest.mark.parametrize("coating", ["none", "PTFE"])
def test_a_seated_ball_carries_the_ideal_reaction_with_its_friction(ideal_forces, coating):
    """A and B with 0.25 mm of clearance, seated, friction on: each ball's contact force at
    the start, normal and friction together, is the ideal joint's reaction to 1e-9 of its
    size. Measured: 3.4e-11 (A) and 6.9e-11 (B) on steel, 2.1e-11 and 2.8e-11 with PTFE.
    Seated along the reaction alone (before issue 41), the friction mu F_N across it was
    left over: 1.0 % of the reaction on steel (mu = 0.01), 16.7 % with PTFE (mu = 0.167)."""
    joints = {name: {"clearance": 2.5e-4, "coating": coating} for name in "AB"}
    ds = simulate({"joints": joints, "solver": {"duration": 0.001, "save_every": 10}})
    for j, name in enumerate("AB"):
        force = ds.joint_force.sel(joint=name).values[0]
        ideal = ideal_forces[j]
        assert float(ds.friction_force.sel(joint=name)[0]) > 0.0   # the ball slips from the start
        assert int(ds.impact_count.sel(joint=name)) == 0
        np.testing.assert_allclose(force, ideal, rtol=0, atol=1e-9 * np.linalg.norm(ideal))


@pytest.mark.parametrize("joint", ["A", "B"])
def test_a_tight_spherical_joint_with_friction_follows_the_closed_form(joint):
    """The joint's clearance at 1 nm, the penetration stop lifted, friction on: the seated
    ball starts in equilibrium, and the slider's acceleration follows the closed form to
    1e-3 of its peak over the first 0.05 s. Measured: A 7.4e-5, B 4.7e-5 (friction off:
    7.3e-5 and 2.0e-5). Seated along the reaction alone: A 4.6e-4, B 1.8e-3."""
    ds = simulate({"joints": one_joint(joint, clearance=1e-9),
                   "contact": {"max_penetration_fraction": 100.0},
                   "friction": {"enabled": True},
                   "solver": {"duration": 0.05, "save_every": 1}})
    assert str(ds.status.values) == "ok"
    assert float(ds.friction_force.sel(joint=joint)[0]) > 0.0
    assert deviation_from_closed_form(ds) < 1e-3


def test_a_seated_ball_with_friction_has_no_start_up_transient():
    """A PTFE-lined socket at A (mu = 0.167) with 0.25 mm of clearance, seated, friction on:
    over the first 0.05 s the slider's acceleration stays within 1 % of the settled peak
    (the closed form's over a revolution) of the closed form. Measured: 0.36 % (friction
    off: 0.060 %). Seated along the reaction alone, the unbalanced friction rang the ball
    in its socket: 2.2 %."""
    ds = simulate({"joints": one_joint("A", clearance=2.5e-4, coating="PTFE"),
                   "friction": {"enabled": True},
                   "solver": {"duration": 0.05, "save_every": 1}})
    assert int(ds.impact_count.sel(joint="A")) == 0
    assert deviation_from_closed_form(ds) < 0.01


def test_the_seat_turns_by_the_friction_angle(ideal_forces):
    """The ball's contact force leans off its normal by the friction angle atan(mu c_d)
    (PTFE: mu = 0.167, 9.48 degrees at full slip) and its size is the ideal reaction's: the
    normal force is |F| cos(phi), not |F| (before: |F|, and the total 1.4 % too large)."""
    angles = {}
    size = np.linalg.norm(ideal_forces[0])
    for enabled in (True, False):
        ds = simulate({"joints": one_joint("A", clearance=2.5e-4, coating="PTFE"),
                       "friction": {"enabled": enabled},
                       "solver": {"duration": 0.001, "save_every": 10}})
        fn = float(ds.normal_force.sel(joint="A")[0])
        friction = float(ds.friction_force.sel(joint="A")[0])
        angles[enabled] = math.degrees(math.atan2(friction, fn))
        assert math.hypot(fn, friction) == pytest.approx(size, rel=1e-9)
    assert angles[True] == pytest.approx(math.degrees(math.atan(0.167)), abs=1e-6)
    assert angles[False] == 0.0
