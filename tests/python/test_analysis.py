"""Hand-derived values of mpmsdem.analysis helpers and of the validation probes that need no YADE scene."""
import math

import pytest

from mpmsdem.analysis import tiltAndYaw


def quat(angleDeg, axis):
    a = math.radians(angleDeg)
    n = math.sqrt(sum(c * c for c in axis))
    return (math.cos(a / 2),) + tuple(c / n * math.sin(a / 2) for c in axis)


def mul(p, q):
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz, pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx, pw * qz + px * qy - py * qx + pz * qw)


def angleAxis(q):
    w, x, y, z = q
    s = math.sqrt(x * x + y * y + z * z)
    return 2 * math.atan2(s, w), (x, y, z)


@pytest.mark.parametrize("angle, axis, tilt, yaw", [
    (30, (0, 1, 0), 30, 0),     # tipped forward about the cross axis
    (30, (1, 0, 0), 30, 0),     # tipped sideways
    (30, (0, 0, 1), 0, 30),     # turned on the bed
    (-30, (0, 0, 1), 0, -30),
    (180, (0, 1, 0), 180, 0),   # upside down
    (0, (0, 0, 1), 0, 0),
    (200, (0, 0, 1), 0, -160),  # yaw kept in (-180, 180]
])
def test_tilt_and_yaw_of_single_rotations(angle, axis, tilt, yaw):
    got = tiltAndYaw(math.radians(angle), axis)
    assert got == pytest.approx((tilt, yaw), abs=1e-9)


@pytest.mark.parametrize("yawDeg, tiltDeg, tiltAxis", [(40, 25, (0, 1, 0)), (-70, 60, (1, 1, 0)), (120, 10, (1, -2, 0))])
def test_a_turn_then_a_tip_splits_into_both_angles(yawDeg, tiltDeg, tiltAxis):
    """A turn about z followed by a tip about a horizontal axis (q = q_tip q_turn) is split
    back into the two angles, whatever the horizontal axis."""
    angle, axis = angleAxis(mul(quat(tiltDeg, tiltAxis), quat(yawDeg, (0, 0, 1))))
    assert tiltAndYaw(angle, axis) == pytest.approx((tiltDeg, yawDeg), abs=1e-9)
    # the tilt is the lean of the body's z axis whatever the order of the two turns
    angle, axis = angleAxis(mul(quat(yawDeg, (0, 0, 1)), quat(tiltDeg, tiltAxis)))
    assert tiltAndYaw(angle, axis)[0] == pytest.approx(tiltDeg, abs=1e-9)


def test_the_impact_probes_face_loads_follow_the_block_and_eq10():
    """scripts/validation/flume_impact_probe.py faceLoads: a point's barrier force (Eq 10) counts
    on the face it faces in the block's frame, points off the face's footprint do not."""
    import importlib.util
    import os
    import numpy as np
    import mpmsdem  # noqa: F401  (YADE's types)
    from yade.minieigenHP import Quaternion, Vector3
    from mpmsdem.analysis import barrierForce
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    spec = importlib.util.spec_from_file_location("probe", os.path.join(root, "scripts", "validation",
                                                                        "flume_impact_probe.py"))
    probe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(probe)
    core, radius, kc = (0.009, 0.009, 0.009), 0.001, 1e4
    v0 = 1e-6 / 8
    rp = (3 * v0 / (4 * math.pi)) ** (1 / 3)
    R = rp + radius
    tilt = math.radians(30)
    ori = Quaternion(Vector3(0, 1, 0), tilt)  # leaning forward: the top turns downstream
    pos = (0.5, 0.03, 0.01)
    up = np.array([math.sin(tilt), 0, math.cos(tilt)])  # the top face's normal
    back = np.array([-math.cos(tilt), 0, math.sin(tilt)])  # the upstream face's normal
    gaps = (0.6 * R, 0.9 * R)
    x = [np.array(pos) + (core[0] + gaps[0]) * up,                       # on the top face
         np.array(pos) + (core[0] + gaps[1]) * back + 0.004 * up,        # on the upstream face, off centre
         np.array(pos) + (core[0] + 0.5 * R) * up + 0.0095 * back,      # above the top's upstream edge: neither
         np.array(pos) + (core[0] + 1.1 * R) * up]                       # too far: no contact
    particles = {"x": np.array(x), "volume0": np.full(len(x), v0)}
    top, upstream = probe.faceLoads(particles, pos, ori, core, radius, kc)
    assert top == pytest.approx(barrierForce(R - gaps[0], R, kc), rel=1e-12)
    assert upstream == pytest.approx(barrierForce(R - gaps[1], R, kc), rel=1e-12)
    assert top > upstream > 0
