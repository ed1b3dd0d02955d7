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


def test_the_impact_probes_face_loads_follow_the_block():
    """scripts/validation/flume_impact_probe.py faceLoads: a face contact's F_n counts on the face
    its normal leaves in the block's frame (the block tilted); edge contacts, other faces and
    other blocks do not count."""
    import importlib.util
    import os
    import numpy as np
    import mpmsdem  # noqa: F401  (YADE's types)
    from yade.minieigenHP import Quaternion, Vector3
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    spec = importlib.util.spec_from_file_location("probe", os.path.join(root, "scripts", "validation",
                                                                        "flume_impact_probe.py"))
    probe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(probe)
    tilt = math.radians(30)
    ori = Quaternion(Vector3(0, 1, 0), tilt)  # leaning forward: the top turns downstream
    up = [math.sin(tilt), 0, math.cos(tilt)]  # the top face's normal in the world
    back = [-math.cos(tilt), 0, math.sin(tilt)]  # the upstream face's
    front = [math.cos(tilt), 0, -math.sin(tilt)]  # the downstream face's
    rows = [(up, 1.5, "face", 7), (up, 0.25, "face", 7), (back, 2.0, "face", 7), (front, 4.0, "face", 7),
            (up, 8.0, "edge", 7), (back, 16.0, "face", 9)]
    contacts = {"normal": np.array([r[0] for r in rows]), "normalForce": np.array([r[1] for r in rows]),
                "feature": [r[2] for r in rows], "block": np.array([r[3] for r in rows])}
    top, upstream = probe.faceLoads(contacts, 7, ori)
    assert top == pytest.approx(1.75, rel=1e-12)
    assert upstream == pytest.approx(2.0, rel=1e-12)
    assert probe.faceLoads(contacts, 8, ori) == (0.0, 0.0)
