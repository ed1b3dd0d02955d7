"""scripts/validation/avaframe_peer.py: its analysis on rasters built by hand (always), and its
smallest case against AvaFrame (when .venv-peers/ holds AvaFrame: tools/install-deps.sh, which
`make test` runs, makes it).

The comparison run: the hockey-small case (AvaFrame's HS topography, 10 m high, a 1 m raster and
grid, 128 m³) by our flow (the field example, PIC viscosity 1.25 m²/s) and by AvaFrame com1DFA
(Coulomb μ = our μ_s, 0.38). Measured (docs/field.md, "Against AvaFrame"): our deposit front at
21 m, AvaFrame's at 24 m along the path, a ratio of 0.875 (the same with one thread and two; 22 m
against 24 m, 0.917, in a first layout with the release 2 m nearer the top on a 20 m wide
raster, over whose sides 9.5 % of AvaFrame's mass left). Each front is a raster node, so one
node (1 m) on either moves the ratio by about 0.04:
the ratio is held to 0.875 ± 0.1 (two nodes each way, and under 1: ours stops short of the
peer). Our centre-of-mass travel angle exceeds AvaFrame's by 5.6° (34.2° against 28.6°; 5.2° in
the first layout, 4.7–5.8° in the three 0.5 m cases of docs/field.md): held to 5.6 ± 2.5°, which
covers every case measured. The release volumes agree within 1 % (AvaFrame's particles against
our points; measured: 10⁻⁶).
"""
import importlib.util
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "scripts", "validation", "avaframe_peer.py")
VENV_PYTHON = os.path.join(ROOT, ".venv-peers", "bin", "python")

spec = importlib.util.spec_from_file_location("avaframe_peer", SCRIPT)
peer = importlib.util.module_from_spec(spec)
spec.loader.exec_module(peer)


def test_the_path_coordinate_is_the_arc_length_to_the_nearest_point():
    path = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]  # an L: 20 m
    s, d = peer.projectOnPath(np.array([5.0, 12.0, -3.0, 20.0]), np.array([2.0, 4.0, 0.0, 15.0]), path)
    assert s == pytest.approx([5.0, 14.0, 0.0, 20.0])  # (12, 4) is nearest (10, 4) on the second leg
    assert d == pytest.approx([2.0, 2.0, 3.0, math.hypot(10.0, 5.0)])
    assert peer.pathLength(path) == 20.0
    sp, x, y = peer.pointsOnPath(path, 7.0)
    assert sp == pytest.approx([0, 7, 14, 20]) and x == pytest.approx([0, 7, 10, 10]) and y == pytest.approx(
        [0, 0, 4, 10])


def slope():
    """21 x 3 nodes 1 m apart along x (y 0, 1, 2): ground at 45 deg from 10 m at x 0 down to 0 at
    x 10, flat beyond; the release 1 m thick over x 0-2; a deposit 0.3 m thick over x 12-15 and
    0.05 m over x 16-17."""
    x = np.arange(21.0)
    heights = np.repeat(np.maximum(10.0 - x, 0.0)[:, None], 3, axis=1)
    release = np.zeros((21, 3))
    release[0:3] = 1.0
    deposit = np.zeros((21, 3))
    deposit[12:16] = 0.3
    deposit[16:18] = 0.05
    return heights, release, deposit, [(0.0, 1.0), (20.0, 1.0)]


def test_runout_travel_angle_and_deposit_area():
    heights, release, deposit, path = slope()
    top = peer.releaseTop(release, heights, 0.0, 0.0, 1.0, path)
    assert (top["s"], top["z"]) == (0.0, 10.0)
    end = peer.farthest(deposit, heights, 0.0, 0.0, 1.0, path, 0.1)
    assert (end["s"], end["z"]) == (15.0, 0.0)
    assert peer.travelAngle(top, end) == pytest.approx(math.degrees(math.atan(10.0 / 15.0)))  # 33.69 deg
    thin = peer.farthest(deposit, heights, 0.0, 0.0, 1.0, path, 0.04)  # the 0.05 m fringe counts
    assert peer.travelAngle(top, thin) == pytest.approx(math.degrees(math.atan(10.0 / 17.0)))
    assert peer.depositArea(deposit, 1.0, 0.1) == 12.0  # 4 nodes along x, 3 across, 1 m² each
    assert peer.depositArea(deposit, 0.5, 0.04) == 18 * 0.25
    assert peer.farthest(deposit, heights, 0.0, 0.0, 1.0, path, 1.0) is None
    assert math.isnan(peer.travelAngle(top, None))


def test_profile_reads_the_raster_between_nodes():
    # h = x y on nodes 2 m apart from (1, 1): bilinear reading is exact for it
    X, Y = peer.nodes((6, 5), 1.0, 1.0, 2.0)
    h = X * Y
    s, p = peer.profile(h, 1.0, 1.0, 2.0, [(1.0, 2.0), (11.0, 7.0)], step=math.hypot(10, 5) / 4)
    xs, ys = 1.0 + 10.0 * np.arange(5) / 4, 2.0 + 5.0 * np.arange(5) / 4
    assert s == pytest.approx(np.arange(5) * math.hypot(10, 5) / 4)
    assert p == pytest.approx(xs * ys)
    # a straight path along the middle of a deposit that steps from 0 to 1 between x 4 and 6
    step = np.zeros((6, 3))
    step[3:] = 1.0
    s, p = peer.profile(step, 0.0, 0.0, 2.0, [(0.0, 2.0), (10.0, 2.0)], step=1.0)
    assert p == pytest.approx([0, 0, 0, 0, 0, 0.5, 1, 1, 1, 1, 1])


def test_centroid_and_the_centre_of_mass_travel_angle():
    # two columns on one row 3 m apart: 1 m of debris on ground at 2 m, 3 m on ground at 0
    heights = np.zeros((4, 1))
    heights[0, 0] = 2.0
    h = np.zeros((4, 1))
    h[0, 0], h[3, 0] = 1.0, 3.0
    c = peer.centroid(h, heights, 0.0, 0.0, 1.0, [(0.0, 0.0), (3.0, 0.0)])
    assert c["x"] == pytest.approx(2.25)  # (0 x 1 + 3 x 3) / 4
    assert c["z"] == pytest.approx(1.75)  # (1 x (2 + 0.5) + 3 x (0 + 1.5)) / 4
    assert c["s"] == pytest.approx(2.25)
    assert peer.centroid(np.zeros((4, 1)), heights, 0.0, 0.0, 1.0, [(0.0, 0.0), (3.0, 0.0)]) is None


def test_arrival_at_stations():
    times = [0.0, 0.1, 0.2]
    series = np.zeros((3, 3, 1))  # three nodes along the path at s 0, 5, 10
    series[:, 0, 0] = 0.5  # thick from the start
    series[2, 1, 0] = 0.1  # at the threshold at 0.2 s
    series[:, 2, 0] = 0.09  # never thick enough
    arrival = peer.arrivalMap(times, series, 0.1)
    assert arrival[0, 0] == 0.0 and arrival[1, 0] == 0.2 and math.isnan(arrival[2, 0])
    got = peer.stationArrivals(arrival, np.array([[0.0], [5.0], [10.0]]), [0.0, 3.0, 5.0, 7.0])
    assert got[:3] == [0.0, 0.2, 0.2] and math.isnan(got[3])


def test_esri_ascii_grids_are_read_on_their_nodes(tmp_path):
    corner = tmp_path / "corner.asc"
    corner.write_text("ncols 3\nnrows 2\nxllcorner 100\nyllcorner 200\ncellsize 2\nNODATA_value -9999\n"
                      "1 2 3\n4 5 -9999\n")  # north row first
    v, x0, y0, s = peer.readAsc(str(corner))
    assert (x0, y0, s) == (101.0, 201.0, 2.0)  # cell centres
    assert v.shape == (3, 2)
    assert v[0, 0] == 4.0 and v[1, 0] == 5.0 and math.isnan(v[2, 0])  # the south row: 4 5 nodata
    assert v[:, 1].tolist() == [1.0, 2.0, 3.0]
    centre = tmp_path / "centre.asc"
    centre.write_text("ncols 2\nnrows 2\nxllcenter 0.5\nyllcenter 1.5\ncellsize 1\n7 8\n9 10\n")
    v, x0, y0, s = peer.readAsc(str(centre))
    assert (x0, y0) == (0.5, 1.5) and v[0, 0] == 9.0 and v[1, 1] == 8.0


def test_the_release_raster_holds_the_box_the_example_seeds(tmp_path):
    """On a flat DEM the release is the example's box (snapped to its grid) times its height."""
    from mpmsdem.terrain import Terrain
    dem = str(tmp_path / "flat.asc")
    Terrain.plane((0.0, 0.0), (20.0, 10.0), 0.5).writeAsc(dem)
    fv = peer.loadExample()
    s = {"dem": dem, "origin": (0.0, 0.0, 0.0), "release": (2.2, 2.0, 6.1, 6.0), "depth": 1.0, "dx": 0.5}
    h, ground = peer.releaseField(fv, s)
    _, _, box = fv.scene(fv.parse(peer.exampleArgs(s)), 0.5)
    lo, hi = box["lo"], box["hi"]
    assert h.sum() * 0.25 == pytest.approx((hi[0] - lo[0]) * (hi[1] - lo[1]) * hi[2], rel=1e-12)
    X, Y = peer.nodes(h.shape, 0.0, 0.0, 0.5)
    outside = (X < lo[0] - 0.25) | (X > hi[0] + 0.25) | (Y < lo[1] - 0.25) | (Y > hi[1] + 0.25)
    assert h[outside].max() == 0.0 and h.max() == pytest.approx(hi[2])


def test_a_missing_environment_is_a_clear_error(tmp_path, capsys):
    rc = peer.main(["--case", "hockey-small", "--venv", str(tmp_path / "none"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2
    assert "AvaFrame's virtual environment is missing" in err and "make test" in err
    assert "tools/install-deps.sh" in err


def _peer_missing():
    if not os.path.exists(VENV_PYTHON):
        return ".venv-peers/ is missing: run `make test` or `bash tools/install-deps.sh` to create it with AvaFrame"
    try:
        peer.peerPython(os.path.dirname(os.path.dirname(VENV_PYTHON)))
    except peer.PeerMissing as e:
        return str(e)
    return None


@pytest.mark.skipif(_peer_missing() is not None, reason=str(_peer_missing()))
def test_the_smallest_case_against_avaframe(tmp_path):
    env = dict(os.environ, OMP_NUM_THREADS="2")
    r = subprocess.run([sys.executable, SCRIPT, "--case", "hockey-small", "--out", str(tmp_path), "--threads", "2"],
                       capture_output=True, text=True, timeout=900, env=env)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    with open(tmp_path / "comparison.json") as f:
        result = json.load(f)
    ours, theirs = [run["values"] for run in result["runs"]]
    assert ours["volume0"] == pytest.approx(theirs["volume0"], rel=0.01)
    assert ours["volume_end"] == pytest.approx(ours["volume0"], rel=1e-9)  # our mass stays on the raster
    ratio = ours["runout"] / theirs["runout"]
    assert 0.775 <= ratio <= 0.975, "our front %.1f m, AvaFrame's %.1f m" % (ours["runout"], theirs["runout"])
    difference = ours["com_angle"] - theirs["com_angle"]
    assert 3.1 <= difference <= 8.1, "centre-of-mass travel angles %.1f and %.1f deg" % (ours["com_angle"],
                                                                                            theirs["com_angle"])
    assert (tmp_path / "comparison.png").stat().st_size > 10000
