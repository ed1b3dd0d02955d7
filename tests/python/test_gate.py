"""The release gate from Python: MpmEngine(gate=...) holds a column with the momentum balance
of its impulse, Flume(gate=...) holds the column until open_at and releases it from the bed up,
bad gate parameters are ValueErrors naming them."""
import math

import numpy as np
import pytest

import mpmsdem
from mpmsdem.flume import Flume

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def engine(gate, gravity=(0, 0, -9.81), walls=None):
    """A quasi-2D column 0.06 m long, 0.08 m high at x in [0.02, 0.08] (dx 0.01 m)."""
    return mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [20, 5, 14], "origin": [0, 0, 0]}, material=GLASS,
                             particles=[{"lo": [0.02, 0.02, 0.02], "hi": [0.08, 0.03, 0.1], "ppc": [2, 1, 2]}],
                             gravity=gravity, walls=walls, gate=gate, verbose=False)


def test_gate_holds_a_column_on_an_incline_and_its_impulse_balances_the_momentum():
    """Free-slip bed and walls, the column away from the back wall: only the gate holds it, so
    the flow's x momentum changes by M g sin(a) t plus the gate's impulse (exact up to
    round-off), and at rest the gate carries M g sin(a)."""
    a = math.radians(10)
    g = (9.81 * math.sin(a), 0, -9.81 * math.cos(a))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [16, 5, 12], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.05, 0.02, 0.02], "hi": [0.11, 0.03, 0.08], "ppc": [2, 1, 2]}],
                            gravity=g, gate={"x": 0.11, "open_at": 100}, flipAlpha=0.0, flipReferenceDt="step",
                            verbose=False)
    p = mpm.particles()
    M, p0 = p["mass"].sum(), (p["mass"] * p["v"][:, 0]).sum()
    dt = 0.5 * mpm.stableTimeStep()
    n, window = int(0.3 / dt), int(0.1 / dt)
    for i in range(n):
        if i == n - window:
            j0 = mpm.solver.gateImpulse()[0]
        mpm.step(dt)
    p = mpm.particles()
    J = mpm.solver.gateImpulse()
    t = mpm.time
    weight = M * 9.81 * math.sin(a)
    assert (p["mass"] * p["v"][:, 0]).sum() - p0 == pytest.approx(weight * t + J[0], abs=1e-10 * weight * t)
    assert J[1] == 0 and J[2] == 0  # smooth gate
    assert -(J[0] - j0) / (window * dt) == pytest.approx(weight, rel=0.03)
    assert np.abs(p["v"]).max() < 0.02
    assert p["x"][:, 0].max() <= 0.11 + 1e-4


def test_instant_gate_opens_at_open_at_and_infinite_speed_means_instant():
    mpm = engine({"x": 0.08, "speed": math.inf, "open_at": 0.05})
    assert mpm.solver.gateEdgeHeight(0.05) == 0.0
    assert math.isinf(mpm.solver.gateEdgeHeight(0.0500001))
    dt = 0.5 * mpm.stableTimeStep()
    while mpm.time < 0.05:
        mpm.step(dt)
    held = mpm.front()
    assert held <= 0.08 + 1e-4
    J = mpm.solver.gateImpulse()
    while mpm.time < 0.15:
        mpm.step(dt)
    assert mpm.front() > held + 0.02  # released (0.037 m measured)
    assert mpm.solver.gateImpulse() == J  # and the gate is gone


@pytest.mark.parametrize("gate, name", [
    ({"x": 0.3}, "gate.x"),
    ({"x": 0.08, "speed": -1}, "gate.speed"),
    ({"x": 0.08, "open_at": -0.1}, "gate.open_at"),
    ({"x": 0.08, "friction": -0.2}, "gate.friction"),
    ({"x": 0.08, "speed": float("nan")}, "gate.speed"),
    ({"x": 0.08, "height": 0.1}, "gate.height"),
    ({"speed": 1.0}, "gate.x"),
    (0.08, "gate"),
])
def test_bad_gate_parameters_are_value_errors_naming_them(gate, name):
    with pytest.raises(ValueError, match=r"\b%s\b" % name.replace(".", r"\.")):
        engine(gate)


def test_gate_read_outs_need_a_gate():
    mpm = engine(None)
    with pytest.raises(ValueError, match="gate"):
        mpm.solver.gateImpulse()


def flume(gate):
    return Flume(length=0.5, width=0.04, columnLength=0.1, columnHeight=0.2, dx=0.02, ppc=8, verbose=False,
                 gate=gate)


def test_flume_gate_holds_the_column_then_releases_it_from_the_bed_up():
    """Gate lifted at 1 m/s from t = 0.1 s. Before: the column stays behind it (without a gate
    its front is 0.037 m further by then). While the edge rises: no material above it is past
    the gate, and material flows out beneath it (once the edge is about 3 dx = 0.06 m above the
    bed the lowest points are free: 16 points out at 0.2 s measured)."""
    xg = 0.1
    free = flume(None)
    free.run(0.1)
    assert free.mpm.front() > xg + 0.02

    scene = flume({"speed": 1.0, "open_at": 0.1})
    scene.run(0.1)
    assert scene.mpm.front() <= xg + 1e-4
    assert scene.gateImpulse()[0] < 0  # it holds the column
    checked = 0
    while scene.mpm.time < 0.2:
        scene.run(0.01)
        x = scene.mpm.particles()["x"]
        above = x[:, 2] >= scene.gateEdgeHeight() + 0.002
        checked += int(above.sum())
        assert x[above, 0].max(initial=0) <= xg + 1e-4
    assert checked > 100
    assert (x[:, 0] > xg).sum() > 0  # released beneath the edge


def test_flume_gate_rejects_unknown_keys():
    with pytest.raises(ValueError, match="gate"):
        flume({"speed": 1, "x": 0.2})


@pytest.mark.parametrize("dx", [0.015, 0.03, -0.01])
def test_flume_refuses_a_spacing_that_does_not_divide_its_width(dx):
    """The side walls lie on grid planes: a dx that leaves part of a cell across the width is a
    ValueError naming dx (and, for a positive dx, the two nearest spacings that fit)."""
    with pytest.raises(ValueError, match=r"dx = %r m: must" % dx) as err:
        Flume(length=0.5, width=0.2, columnLength=0.1, columnHeight=0.1, dx=dx, ppc=8, verbose=False)
    if dx > 0:
        near = sorted(0.2 / n for n in (math.floor(0.2 / dx), math.ceil(0.2 / dx)))
        assert all(repr(v) in str(err.value) for v in near)
