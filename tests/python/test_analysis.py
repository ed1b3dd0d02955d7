"""Hand-derived values of mpmsdem.analysis helpers and of the validation probes that need no YADE scene."""
import math

import pytest

from mpmsdem import analysis
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


def test_box_face_loads_follow_the_block():
    """analysis.boxFaceLoads: a face contact's F_n counts on the face its normal leaves in the
    block's frame (the block tilted 30°); edge contacts count apart."""
    import numpy as np
    from mpmsdem.analysis import boxFaceLoads
    tilt = math.radians(30)
    c, s = math.cos(tilt), math.sin(tilt)
    rotation = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # about y: the top turns downstream
    up, back, front = rotation @ [0, 0, 1], rotation @ [-1, 0, 0], rotation @ [1, 0, 0]
    side = rotation @ [0, -1, 0]
    rows = [(up, 1.5, "face"), (up, 0.25, "face"), (back, 2.0, "face"), (front, 4.0, "face"), (side, 0.5, "face"),
            (up, 8.0, "edge"), ((up + back) / np.linalg.norm(up + back), 16.0, "vertex")]
    contacts = {"normal": np.array([r[0] for r in rows]), "normalForce": np.array([r[1] for r in rows]),
                "feature": [r[2] for r in rows]}
    loads = boxFaceLoads(contacts, rotation)
    assert loads == pytest.approx({"+z": 1.75, "-x": 2.0, "+x": 4.0, "-y": 0.5, "+y": 0.0, "-z": 0.0, "edges": 24.0},
                                  rel=1e-12)
    assert up[0] > 0.49  # tilted: the world's x would have taken the top's load
    empty = {"normal": np.zeros((0, 3)), "normalForce": np.zeros(0), "feature": []}
    assert set(boxFaceLoads(empty, rotation).values()) == {0.0}


def test_front_profile_of_a_hand_built_wedge():
    """A wedge-shaped front on a 1 mm lattice: its top rising 0.5 per unit length from 9 mm at a
    tip at x = 0.3 m, its underside lifted 6 mm off the bed; two points thrown 5 cm ahead. The tip is the
    fourth most downstream point, the nose the lowest point within a cell of it, and each depth
    the top of the column half a cell around its station: all read off the construction."""
    import numpy as np
    from mpmsdem.analysis import frontProfile
    pts = []
    for i in range(0, 101):                      # x = 0.3 - i mm
        x = 0.3 - 1e-3 * i
        top = 0.009 + 0.5 * (0.3 - x)
        pts += [(x, 0.0, z) for z in np.arange(0.006, top + 1e-12, 1e-3)]
    pts += [(0.35, 0.0, 0.02), (0.351, 0.0, 0.03)]  # spray ahead of the front
    p = {"x": np.array(pts)}
    r = frontProfile(p, cell=0.005, bedZ=0.0, behind=(0.02, 0.05))
    assert r["tip"] == pytest.approx(0.3, abs=1e-12)          # the spray (2 points) left out
    # the four foremost: the spray at 20 and 30 mm and, of the tip column (ties broken by order),
    # its last two points, 8 and 9 mm
    assert r["tipHeight"] == pytest.approx((0.02 + 0.03 + 0.009 + 0.008) / 4, abs=1e-12)
    assert r["nose"] == pytest.approx(0.006, abs=1e-12)
    # highest point within 2.5 mm of x = 0.28 / 0.25 m: the columns down to 0.278 / 0.248 m,
    # 22 / 52 mm behind the tip, topped at 9 + 0.5 * 22 = 20 mm and 9 + 0.5 * 52 = 35 mm
    assert r["depth"] == pytest.approx([0.020, 0.035], abs=1e-9)
    # a nose on the bed reads 0; no points behind the tip read 0 depth
    q = {"x": np.array([(0.1, 0, 0.0), (0.1, 0, 0.01), (0.1, 0, 0.02), (0.1, 0, 0.03)])}
    r = frontProfile(q, cell=0.01, behind=(0.05,))
    assert (r["tip"], r["nose"], r["depth"]) == (0.1, 0.0, [0.0]) and r["tipHeight"] == pytest.approx(0.015)
    with pytest.raises(ValueError, match="at least 4 points"):
        frontProfile({"x": np.zeros((3, 3))}, cell=0.01)


@pytest.mark.parametrize("Fr", [0.3, 1.0, 2.5, 6.0])
def test_reflected_bore_conserves_mass_and_momentum(Fr):
    # the bore's depth from its cubic, then mass and momentum across it checked directly, in the
    # frame of the bore (speed c upstream): h (v + c) = h2 c, h (v + c)² + g h²/2 = h2 c² + g h2²/2
    g, h = 9.81, 0.03
    v = Fr * math.sqrt(g * h)
    r = analysis.reflectedBoreDepth(Fr)
    h2 = r * h
    c = h * v / (h2 - h)  # from mass
    assert h * (v + c) ** 2 + 0.5 * g * h * h == pytest.approx(h2 * c * c + 0.5 * g * h2 * h2, rel=1e-12)
    # on flat ground with k = 1 the wall carries the hydrostatic load of the depth at rest
    assert analysis.reflectedBoreForce(1600.0, v, h, 0.2, 0.0) == pytest.approx(0.5 * 1600.0 * g * h2 * h2 * 0.2,
                                                                                 rel=1e-12)


def test_reflected_bore_at_its_hand_numbers():
    # Fr = 1: r solves r³ − r² − 3r + 1 = 0, whose root above 1 is 2.1700864866...; large Fr:
    # r² → 2 Fr², so the force over ρ v² h w tends to 1 (all the momentum flux, nothing more)
    r = analysis.reflectedBoreDepth(1.0)
    assert r ** 3 - r * r - 3 * r + 1 == pytest.approx(0.0, abs=1e-12)
    assert r == pytest.approx(2.1700864866260, rel=1e-10)
    rho, g, h, w = 1600.0, 9.81, 0.01, 0.04
    v = 100.0 * math.sqrt(g * h)
    ratio = analysis.reflectedBoreForce(rho, v, h, w, 0.0) / (rho * v * v * h * w)
    assert 1.0 < ratio < 1.0 + 1.0 / (math.sqrt(2) * 100.0) + 1e-4  # α_eff ≈ 1 + 1/(√2 Fr) from above
    with pytest.raises(ValueError, match="Fr"):
        analysis.reflectedBoreDepth(0.0)


def test_wall_superposed_force_by_hand():
    # 1600 kg/m³, 2 m/s, 2 cm deep, 4 cm wide, 30°: 1600·4·0.02·0.04 + ½·1600·9.81·cos30°·0.02²·0.04
    f = analysis.wallSuperposedForce(1600.0, 2.0, 0.02, 0.04, 30.0)
    assert f == pytest.approx(5.12 + 0.5 * 1600 * 9.81 * math.cos(math.radians(30)) * 4e-4 * 0.04, rel=1e-12)


def test_rest_time_of_a_block_decelerating_then_still():
    # records every 1 ms, half a millisecond off the round times; v(t) = 0.1 (1 - t) m/s until
    # t = 1 s, then 0: the centre is below 1 cm/s from the record at 0.9005 s on
    import numpy as np
    t = np.arange(1500) * 1e-3 + 5e-4
    v = np.maximum(0.1 * (1 - t), 0.0)
    assert analysis.restTime(t, v) == pytest.approx(0.9005, abs=1e-12)
    assert analysis.restTime(t, v, speedBelow=0.05) == pytest.approx(0.5005, abs=1e-12)
    # turning at 2 rad/s until the record at 1.1995 s: a point 1 cm out moves at 2 cm/s until the
    # next record; at 6 mm out (1.2 cm/s) it is not below the bound either; at 4 mm (8 mm/s) the
    # turn leaves the speed to decide (0.8 cm/s + the centre's below 0.2 cm/s from 0.9805 s)
    turn = np.degrees(np.minimum(2.0 * t, 2.0 * 1.1995))
    assert analysis.restTime(t, v, turn, radius=0.01) == pytest.approx(1.2005, abs=1e-12)
    assert analysis.restTime(t, v, turn, radius=0.006) == pytest.approx(1.2005, abs=1e-12)
    assert analysis.restTime(t, v, turn, radius=0.004) == pytest.approx(0.9805, abs=1e-12)
    assert analysis.restTime(t, v, turn) == pytest.approx(0.9005, abs=1e-12)  # a point: the turn moves nothing
    # a kick at the end: not at rest when the record ends
    kicked = v.copy()
    kicked[-1] = 0.02
    assert analysis.restTime(t, kicked) is None
    assert analysis.restTime(t, np.zeros_like(t)) == t[0]  # at rest from the first record
    for bad in ({"speedBelow": 0}, {"speedBelow": math.nan}, {"radius": -1e-3}):
        with pytest.raises(ValueError, match=list(bad)[0]):
            analysis.restTime(t, v, **bad)
    with pytest.raises(ValueError, match="rotation"):
        analysis.restTime(t, v, turn[:-1])


def test_interval_and_window_means_of_an_impulse_by_hand():
    """Records of an impulse J(t) = 2t + t^2 [N s] (force 2 + 2t): the mean between records is
    (J_i - J_{i-1}) / (t_i - t_{i-1}), and a window centred on a record whose ends fall on
    records gives the force at its centre exactly (J quadratic: the centred difference is
    exact); where the window reaches past the records, NaN."""
    np = pytest.importorskip("numpy")
    t = np.array([0.0, 1.0, 3.0])
    assert np.isnan(analysis.intervalMean(t, t ** 2)[0])
    assert analysis.intervalMean(t, t ** 2)[1:].tolist() == [1.0, 4.0]
    # per body columns: each column on its own
    both = analysis.intervalMean(t, np.stack([t ** 2, 3 * t], axis=1))
    assert both[1:].tolist() == [[1.0, 3.0], [4.0, 3.0]]
    t = np.arange(0, 101) * 1e-3
    J = 2 * t + t ** 2
    f = analysis.windowMean(t, J, 0.01)
    assert np.isnan(f[:5]).all() and np.isnan(f[-5:]).all() and not np.isnan(f[5:-5]).any()
    np.testing.assert_allclose(f[5:-5], 2 + 2 * t[5:-5], rtol=0, atol=1e-12)
    # window ends between records (h = 1 ms, w = 10.5 h): J is taken linear between them. The
    # chord of t^3 over [x0, x1] lies s (1 - s) h^2 (x0 + x1 + x) above it at x = x0 + s h: for a
    # quadratic the two ends' errors would cancel, for t^3 the upper end (s 1/4, x0 + x1 + x =
    # 3t + 16.25 h) and the lower (s 3/4, 3t - 16.25 h) leave 0.1875 x 32.5 h^3 / w over the
    # exact centred mean 3 t^2 + w^2 / 4
    h, w = 1e-3, 0.0105
    g = analysis.windowMean(t, t ** 3, w)
    np.testing.assert_allclose(g[6:-6] - (3 * t[6:-6] ** 2 + w ** 2 / 4), 0.1875 * 32.5 * h ** 3 / w, rtol=1e-6)
    with pytest.raises(ValueError, match="window"):
        analysis.windowMean(t, J, 0)
    with pytest.raises(ValueError, match="increase"):
        analysis.intervalMean([0.0, 0.0], [1.0, 2.0])


def test_a_blocks_mean_and_peak_force_are_read_from_its_impulse_by_hand():
    """A block pushed by F(t) = 2 + 2t - 60 (t - 0.05)^2 for t < 0.1 s, then 0.5 N, recorded
    every 1 ms: J(t) = 2t + t^2 - 20 (t - 0.05)^3 - 20 (0.05)^3 below 0.1 s. The mean between
    two records from J is the integral of F over the interval over its length, by hand; the
    peak of the 10 ms means is at the window centred on the force's maximum (t = 1/60 + 0.05 s
    to the nearest record, 0.067 s) and the records' own forces, made noisy, are not read where
    the series has the impulse; without one (older files) they are."""
    np = pytest.importorskip("numpy")
    t = np.arange(0, 201) * 1e-3
    F = np.where(t < 0.1, 2 + 2 * t - 60 * (t - 0.05) ** 2, 0.5)
    J1 = 2 * 0.1 + 0.01 - 20 * 0.05 ** 3 - 20 * 0.05 ** 3  # J at 0.1 s
    J = np.where(t < 0.1, 2 * t + t ** 2 - 20 * (t - 0.05) ** 3 - 20 * 0.05 ** 3, J1 + 0.5 * (t - 0.1))
    noisy = F + np.where(np.arange(len(t)) % 2 == 0, 3.0, -3.0)  # one step's force swings
    s = {"t": t, "Ft": noisy, "J": J}
    # over 0.02-0.08 s: [2t + t^2 - 20 (t - 0.05)^3] / 0.06 = (0.12 + 0.006 - 2 x 20 x 0.03^3) / 0.06
    assert analysis.meanForceBetween(s, 0.02, 0.08) == pytest.approx((0.12 + 0.006 - 40 * 0.03 ** 3) / 0.06, abs=1e-12)
    assert analysis.meanForceBetween(s, 0.15, 0.2) == pytest.approx(0.5, abs=1e-12)
    assert analysis.impulseMean(t, J, 0.15, 0.2) == analysis.meanForceBetween(s, 0.15, 0.2)
    assert analysis.forceSource(s) == "impulse"
    peak, tPeak = analysis.peakMeanForce(s, 0.01)
    # the 10 ms mean centred on 0.067 s: 2 + 2 x 0.067 - 60 [(0.067 - 0.05)^2 + 0.01^2 / 12]
    assert tPeak == pytest.approx(0.067, abs=1e-12)
    assert peak == pytest.approx(2 + 2 * 0.067 - 60 * (0.017 ** 2 + 0.01 ** 2 / 12), abs=1e-12)
    # no impulse recorded (or only NaN rows): the records' forces, noise and all
    old = {"t": t, "Ft": noisy, "J": np.full(len(t), np.nan)}
    assert analysis.forceSource(old) == "records" and analysis.forceSource({"t": t, "Ft": noisy}) == "records"
    assert analysis.meanForceBetween(old, 0.15, 0.2) == pytest.approx(noisy[150:].mean(), abs=1e-12)
    np.testing.assert_array_equal(analysis.meanForce(old, 0.01), analysis.runningMean(t, noisy, 0.01))
    with pytest.raises(ValueError, match="within the records"):
        analysis.meanForceBetween(s, 0.15, 0.25)
    with pytest.raises(ValueError, match="end"):
        analysis.impulseMean(t, J, 0.1, 0.1)
    with pytest.raises(ValueError, match="longer than the records"):
        analysis.peakMeanForce(s, 0.5)


def test_the_peak_window_mean_is_sought_over_every_window_not_only_those_centred_on_records():
    """Records every 3 ms of a block pushed by 20 N from 0.300 to 0.310 s (J exact at the records,
    linear between them): the 10 ms window from 0.300 to 0.310 s holds J(0.309) = 0.18 N s plus a
    third of the next interval's 0.02, 0.18667 N s, a mean of 18.67 N; the best window centred on
    a record (0.306 s: 0.301 to 0.311 s) has 17.33 N."""
    np = pytest.importorskip("numpy")
    t = np.round(np.arange(0, 201) * 3e-3, 12)
    J = 20.0 * np.clip(t - 0.3, 0.0, 0.01)
    peak, centre = analysis.peakWindowMean(t, J, 0.01)
    assert peak == pytest.approx(20 * (0.009 + 0.001 / 3) / 0.01, abs=1e-9)
    assert centre == pytest.approx(0.305, abs=1e-12)
    assert np.nanmax(analysis.windowMean(t, J, 0.01)) == pytest.approx(20 * (0.008 + 0.002 / 3) / 0.01, abs=1e-9)
    assert analysis.peakMeanForce({"t": t, "J": J, "Ft": np.zeros(len(t))}, 0.01) == (peak, centre)
    with pytest.raises(ValueError, match="window"):
        analysis.peakWindowMean(t, J, 0)


def test_effective_pic_viscosity_of_a_blend_per_step():
    # The blend before mpmsdem's (share 1 - e^-x, x = 4 nu dt / dx^2): nu (1 - e^-x) / x, nu at
    # small x, nu (1 - 1/e) at x = 1 (nu 0.25 m^2/s, dt 1e-4 s, dx 0.01 m), 0.774 nu at the
    # film's x 0.536 (Δx 0.0025 m, its step 2.327e-5 s)
    old = dict(share="exponential")
    assert analysis.effectivePicViscosity(0.036, 1e-12, 0.01, **old) == pytest.approx(0.036, rel=1e-9)
    assert analysis.effectivePicViscosity(0.25, 1e-4, 0.01, **old) == pytest.approx(0.25 * (1 - math.exp(-1)), rel=1e-12)
    assert analysis.effectivePicViscosity(0.25, 1e-4, 0.01, **old) == pytest.approx(0.158030139, rel=1e-8)
    x = 4 * 0.0360141 * 2.327e-5 / 0.0025 ** 2
    assert x == pytest.approx(0.5363, abs=1e-4)
    assert analysis.effectivePicViscosity(0.0360141, 2.327e-5, 0.0025, **old) / 0.0360141 == pytest.approx(0.7740, abs=1e-4)
    # mpmsdem's blend hands PIC the share x itself: the flow feels nu up to x = 1 (the stable
    # step), nu / x past it (a step of pure PIC)
    assert analysis.effectivePicViscosity(0.0360141, 2.327e-5, 0.0025) == 0.0360141
    assert analysis.effectivePicViscosity(0.25, 1e-4, 0.01) == pytest.approx(0.25, rel=1e-15)
    assert analysis.effectivePicViscosity(0.25, 2e-4, 0.01) == pytest.approx(0.125, rel=1e-15)
    # the joint set's viscosity held the old way at its dx 0.01 m step is the new way's 0.0347053
    dt = 0.5 * 0.3 * 0.01 / 29.005968  # the flume's O.dt: half the CFL step of the glass beads (E 1 MPa, ν 0.3, ρ 1600)
    assert analysis.effectivePicViscosity(0.0360141, dt, 0.01, **old) == pytest.approx(0.0347053, abs=1e-7)
    with pytest.raises(ValueError, match='share = .*"linear"'):
        analysis.effectivePicViscosity(0.01, 1e-4, 0.01, share="exp")
    for bad in ((0, 1e-4, 0.01), (0.01, -1e-4, 0.01), (0.01, 1e-4, float("nan"))):
        with pytest.raises(ValueError, match="must be finite and > 0"):
            analysis.effectivePicViscosity(*bad)


def test_point_radius_is_the_sphere_of_a_points_volume():
    # 8 points in a 1 cm cell: each 1.25e-7 m^3, the sphere of it 3.1018 mm (4/3 pi r^3 = 1.25e-7)
    assert analysis.pointRadius(0.01, 8) == pytest.approx(3.1017525e-3, rel=1e-7)
    assert 4.0 / 3.0 * math.pi * analysis.pointRadius(0.02, 27) ** 3 == pytest.approx(0.02 ** 3 / 27, rel=1e-12)
    assert analysis.pointRadius(0.01, 1) == pytest.approx(2 * analysis.pointRadius(0.01, 8), rel=1e-12)


def test_the_blow_by_parts_of_a_known_impulse():
    """analysis.blowParts on records every 1 ms of a cube struck from 0.3 s by 30 N for 3 ms,
    then 6 N: by hand, 30 N over 0-2 ms, (30 + 2 x 6) / 3 = 14 N over 2-5 ms, 6 N over 5-25 ms
    where the series holds the contact's first step; the records alone (their first force at
    0.301 s) count from 1 ms late and give 30, 6 and 6 N. A span past the last record is left
    out; none where the flow never came."""
    np = pytest.importorskip("numpy")
    t = np.arange(0, 451) * 1e-3
    F = np.where(t < 0.3 + 1e-9, 0.0, np.where(t < 0.303 + 1e-9, 30.0, 6.0))  # over the interval before t
    J = np.concatenate([[0.0], np.cumsum(F[1:] * np.diff(t))])
    records = {"t": t, "J": J, "Ft": F}
    exact = dict(records, first_contact=np.where(t >= 0.3, 0.3, np.nan))
    assert analysis.touchTime(records) == pytest.approx(0.301, abs=1e-12)
    assert analysis.touchTime(exact) == 0.3
    for s, want in ((exact, (30.0, 14.0, 6.0)), (records, (30.0, 6.0, 6.0))):
        parts = analysis.blowParts(s)
        assert sorted(parts) == ["load_0_2ms", "load_2_5ms", "load_5_25ms"]
        assert (parts["load_0_2ms"], parts["load_2_5ms"], parts["load_5_25ms"]) == pytest.approx(want, abs=1e-9)
    late = {"t": t, "J": J, "Ft": np.where(t < 0.44, 0.0, F)}
    assert list(analysis.blowParts(late)) == ["load_0_2ms", "load_2_5ms"]
    assert analysis.blowParts({"t": t, "J": 0 * J, "Ft": 0 * F}) == {}


def test_the_blows_line_of_action_by_parts():
    """analysis.blowLineOfAction: a cube pushed from 0.3004 s (between the 1 ms records) by 30 N
    downstream 4 mm above its centroid for 3 ms, then by 6 N 2 mm below it, recorded every 1 ms
    (J and the angular impulse Ly by hand): 4 mm over 0-2 ms, (30 x 0.004 x 1 + 6 x (-0.002) x 2)
    / (30 x 1 + 6 x 2) = 2.2857 mm over 2-5 ms, -2 mm over 5-25 ms, to round-off; NaN over a
    span without a downstream push; nothing from a series without the angular impulse."""
    np = pytest.importorskip("numpy")
    t, t0 = np.arange(0, 451) * 1e-3, 0.3004

    def J(x):  # the downstream impulse at time x
        x = np.asarray(x, dtype=float)
        return 30 * np.clip(x - t0, 0, 0.003) + 6 * np.clip(x - t0 - 0.003, 0, None)

    def Ly(x):  # its moment about the centroid: the push's height times it
        x = np.asarray(x, dtype=float)
        return 30 * 0.004 * np.clip(x - t0, 0, 0.003) - 6 * 0.002 * np.clip(x - t0 - 0.003, 0, None)

    s = {"t": t, "J": J(t), "Ly": Ly(t), "Ft": np.where(t > t0, 1.0, 0.0), "first_contact": np.where(t >= t0, t0, np.nan)}
    action = analysis.blowLineOfAction(s)
    assert sorted(action) == ["action_0_2ms", "action_2_5ms", "action_5_25ms"]
    assert action["action_0_2ms"] == pytest.approx(0.004, rel=1e-12)
    assert action["action_2_5ms"] == pytest.approx((0.12e-3 - 0.024e-3) / 0.042, rel=1e-12)
    assert action["action_5_25ms"] == pytest.approx(-0.002, rel=1e-12)
    lifted = dict(s, J=np.where(t > t0 + 0.01, J(t0 + 0.01), J(t)), Ly=np.where(t > t0 + 0.01, Ly(t0 + 0.01), Ly(t)))
    assert math.isnan(analysis.blowLineOfAction(lifted, spans=((0.02, 0.03),))["action_20_30ms"])
    assert analysis.blowLineOfAction({k: v for k, v in s.items() if k != "Ly"}) == {}


def test_the_blow_by_parts_from_the_step_of_the_first_contact():
    """Where the series holds the step the flow first touched the block in (coupled.h5's
    flow_first_contact), the parts count from it, between records: a cube struck from 0.3004 s
    (a step inside the record interval 0.300-0.301 s) by 30 N for 3 ms, then 6 N, recorded every
    1 ms: 30 N over 0-2 ms, (30 x 1 + 6 x 2) / 3 = 14 N over 2-5 ms and 6 N over 5-25 ms, by hand,
    to round-off; the records alone would count from 0.301 s, 0.6 ms late."""
    np = pytest.importorskip("numpy")
    t = np.arange(0, 451) * 1e-3
    t0 = 0.3004

    def J(x):  # the impulse of the force above at time x, by hand
        x = np.asarray(x, dtype=float)
        return 30 * np.clip(x - t0, 0, 0.003) + 6 * np.clip(x - t0 - 0.003, 0, None)

    first = np.where(t >= t0, t0, np.nan)  # known from the record after it on
    s = {"t": t, "J": J(t), "Ft": np.where(t > t0, 1.0, 0.0), "first_contact": first}
    assert analysis.firstContact(s) == t0 and analysis.touchTime(s) == t0
    parts = analysis.blowParts(s)
    assert parts["load_0_2ms"] == pytest.approx(30.0, rel=1e-12)
    assert parts["load_2_5ms"] == pytest.approx(14.0, rel=1e-12)
    assert parts["load_5_25ms"] == pytest.approx(6.0, rel=1e-12)
    assert analysis.firstContact({"t": t, "Ft": s["Ft"]}) is None  # written before it was recorded
