"""Blocks on a terrain by table (mpmsdem.field): the table read and refused clearly, each block
placed resting on the ground's slope, and the per-block report: travel, rotation, force, first
contact and the cover of debris over its top, against hand-made cases."""
import math
import re

import numpy as np
import pytest

import mpmsdem
from mpmsdem import field
from mpmsdem.terrain import Terrain
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator

MATERIAL = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def test_block_tables_are_read_and_bad_rows_refused_by_line(tmp_path):
    good = tmp_path / "blocks.csv"
    rows = [{"id": 3, "shape": "box:4.4x1.8x1.5", "x": 1.0, "y": 2.0, "heading_deg": 30.0, "mass": 1400.0},
            {"id": 5, "shape": "car.obj*0.001", "x": -1.0, "y": 0.5, "heading_deg": 0.0, "mass": 900.0}]
    field.writeBlockTable(str(good), rows)
    assert field.readBlockTable(str(good)) == rows
    head = "id,shape,x,y,heading_deg,mass\n"
    for body, words in (("1,box:1x1,0,0,0,10\n", "line 2: shape 'box:1x1': a box is 'box:LxWxH'"),
                        ("1,box:1x1x1,0,0,0,0\n", "line 2: mass = 0.0 kg: must be > 0"),
                        ("1,box:1x1x1,0,0,0,1\n1,box:1x1x1,2,0,0,1\n", "line 3: id 1 given twice"),
                        ("1,house.ply,0,0,0,1\n", "must be 'box:LxWxH' or a mesh file"),
                        ("1,box:1x1x1,zero,0,0,1\n", "line 2: x = 'zero': not a number"),
                        ("1.5,box:1x1x1,0,0,0,1\n", "line 2: id = '1.5': not an integer"),
                        # found by tests/python/test_fuzz_readers.py: a short row, a bad scale
                        ("-0\n", "line 2: 1 values for the 6 columns of the header"),
                        ("1,car.obj*x,0,0,0,1\n", "line 2: shape 'car.obj*x': the scale after '*' must be a number > 0"),
                        ("1,car.obj*-2,0,0,0,1\n", "the scale after '*' must be a number > 0"),
                        ("1,box:1x1x1,nan,0,0,1\n", "line 2: x, y, heading_deg and mass must be finite")):
        bad = tmp_path / "bad.csv"
        bad.write_text(head + body)
        with pytest.raises(ValueError, match=re.escape(words)):
            field.readBlockTable(str(bad))
    (tmp_path / "latin1.csv").write_bytes(head.encode() + b"1,box:1x1x1,0,0,0,1 \xe9\n")
    with pytest.raises(ValueError, match="latin1.csv: not UTF-8 text"):
        field.readBlockTable(str(tmp_path / "latin1.csv"))
    (tmp_path / "nocol.csv").write_text("id,shape,x,y,mass\n1,box:1x1x1,0,0,1\n")
    with pytest.raises(ValueError, match="missing column"):
        field.readBlockTable(str(tmp_path / "nocol.csv"))


def test_blocks_are_placed_resting_on_the_slope_and_stay(tmp_path):
    # Two boxes on a 20 deg terrain slope (friction 0.7 > tan 20 deg), turned by their headings:
    # their bases lie along the slope (the box's own z is the ground's normal), their mass is the
    # table's; they settle onto their corners (a tenth of their sweep radius of drop and the
    # barrier's overlap, about a centimetre; their rocking decays by half every 0.08 s) and then
    # stay: less than 0.1 mm over the second half of a second.
    O.reset()
    ground = Terrain.plane((-3.0, -3.0), (3.0, 3.0), 0.25, z0=1.0, slope_x_deg=20.0)
    sdem = mpmsdem.SdemEngine(dtCheck="raise", verbose=False)
    sdem.terrain(ground, mpmsdem.material(density=2500, friction=0.7, barrierStiffness=3e6))
    rows = [{"id": 0, "shape": "box:1.0x1.0x1.0", "x": -1.0, "y": 0.0, "heading_deg": 25.0, "mass": 2000.0},
            {"id": 1, "shape": "box:2.0x1.0x0.5", "x": 1.0, "y": 1.0, "heading_deg": -10.0, "mass": 1000.0}]
    mats = {}
    ids = field.placeBlocks(sdem, ground, rows, lambda rho: mats.setdefault(
        round(rho, 6), mpmsdem.material(density=rho, friction=0.7, barrierStiffness=3e6, normalDamping=0.3,
                                        tangentialDamping=0.5)))
    th = math.radians(20.0)
    n = np.array([math.sin(th), 0, math.cos(th)])
    for i, r in zip(ids, rows):
        b = O.bodies[i]
        assert b.state.mass == pytest.approx(r["mass"], rel=1e-9)
        up = np.array(list(b.state.ori * mpmsdem.sdem.Vector3(0, 0, 1)))
        assert np.allclose(up, n, atol=1e-9)  # its base along the slope
    placed = [np.array(list(O.bodies[i].state.pos)) for i in ids]
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 2e-4
    mpmsdem.run(2500, sdem)
    settled = [np.array(list(O.bodies[i].state.pos)) for i in ids]
    mpmsdem.run(2500, sdem)
    for i, p, q in zip(ids, placed, settled):
        assert np.linalg.norm(q - p) < 0.02
        assert np.linalg.norm(np.array(list(O.bodies[i].state.pos)) - q) < 1e-4
    assert len(sdem.contacts()["normalForce"]) == 8  # 4 corners each on the ground


def test_the_report_gives_each_block_its_travel_force_contact_and_cover():
    # A column of material resting on a block and a block beside it, on flat ground: the first is
    # buried under the column's material above its top (its thickness over the block's plan
    # circle), the second is not; a block shifted by hand reports its travel and turn.
    O.reset()
    ground = Terrain.plane((0.0, 0.0), (0.4, 0.2), 0.01, z0=0.02)
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=700, friction=0.5)
    sdem.terrain(ground, mat)
    a = sdem.box((0.02, 0.02, 0.02), 0.002, mat, pos=(0.1, 0.1, 0.0405))
    b = sdem.box((0.02, 0.02, 0.02), 0.002, mat, pos=(0.3, 0.1, 0.0405))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [44, 24, 20], "origin": [-0.02, -0.02, 0.0]},
                            material=MATERIAL, particles=[{"lo": [0.07, 0.07, 0.07], "hi": [0.13, 0.13, 0.1],
                                                           "ppc": 8}],
                            terrain=ground, verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: {"friction": 0.3}}, verbose=False)
    tracker = field.BlockTracker(coupled, [a, b])
    O.bodies[b].state.pos = O.bodies[b].state.pos + mpmsdem.sdem.Vector3(0.03, 0.04, 0.0)
    rows = tracker.report(mpm.particles())
    ra, rb = rows
    assert not ra["outside_grid"] and not rb["outside_grid"]
    O.bodies[b].state.pos = O.bodies[b].state.pos + mpmsdem.sdem.Vector3(1.0, 0, 0)  # beyond the grid's 0.42 m
    assert tracker.report(mpm.particles())[1]["outside_grid"]
    # a: the material above its top (z 0.061) within its plan circle (radius 0.02 sqrt 2): the
    # column's part over the circle, 3.0 cm thick (z 0.07 to 0.10)
    x = mpm.particles()["x"]
    inside = np.hypot(x[:, 0] - 0.1, x[:, 1] - 0.1) <= 0.02 * math.sqrt(2) + 1e-12
    expected = mpm.particles()["volume0"][inside & (x[:, 2] > ra["top"])].sum() / (math.pi * 2 * 0.02 ** 2)
    assert ra["top"] == pytest.approx(0.0405 + 0.02, abs=1e-9)
    assert ra["cover"] == pytest.approx(expected, rel=1e-12) and ra["cover"] > 0.02
    # the column (x, y 0.07-0.13) spans a's whole plan (0.08-0.12): buried; at its centre, the
    # points above the top within dx (0.01 m) of it, over that disc
    centre = np.hypot(x[:, 0] - 0.1, x[:, 1] - 0.1) <= 0.01
    depth = mpm.particles()["volume0"][centre & (x[:, 2] > ra["top"])].sum() / (math.pi * 0.01 ** 2)
    assert ra["cover_depth"] == pytest.approx(depth, rel=1e-12) and 0.02 < ra["cover_depth"] < 0.04
    assert ra["cover_fraction"] == 1 and ra["buried"] and not ra["partly_buried"]
    assert rb["cover"] == 0 and rb["cover_depth"] == 0 and rb["cover_fraction"] == 0
    assert not rb["buried"] and not rb["partly_buried"]
    assert ra["x_map"] == ra["x"] and ra["z0_map"] == ra["z0"]  # a made terrain: the map is the grid frame
    assert rb["travel"] == pytest.approx(0.05, rel=1e-9) and ra["travel"] == 0
    assert math.isnan(ra["first_contact"]) and ra["peak_force"] == 0  # no step taken yet


def test_the_report_tells_each_block_how_deep_and_how_much_of_its_plan_is_under_debris(tmp_path):
    # Three 4 cm blocks (outer plan 0.04 m square, top 0.0605 m) on a raster read from a file far
    # from the origin; points of debris placed by hand, some above the tops, some below. The flow
    # grid's dx 0.01 m gives the defaults: the centre's disc of radius 0.01 m (its area
    # pi 1e-4 m²), a sample covered by a point above the top within 0.005 m, 10 x 10 samples at
    # the plan's cell centres x, y = centre +- 0.002, 0.006, ..., 0.018 m.
    dem = str(tmp_path / "ground.asc")
    flat = Terrain.plane((0.0, 0.0), (0.4, 0.2), 0.01, z0=250.02)
    flat.x0, flat.y0 = 500000.0, 4100000.0
    flat.writeAsc(dem)
    ground = Terrain.read(dem, origin=(500000.0, 4100000.0, 250.0))
    O.reset()
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=700, friction=0.5)
    a, b, c = [sdem.box((0.02, 0.02, 0.02), 0.002, mat, pos=(x, 0.1, 0.0405)) for x in (0.1, 0.2, 0.3)]
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [44, 24, 20], "origin": [-0.02, -0.02, 0.0]},
                            material=MATERIAL, particles=[], verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: {"friction": 0.3}}, verbose=False)
    tracker = field.BlockTracker(coupled, [a, b, c], terrain=ground)
    O.bodies[c].state.pos = O.bodies[c].state.pos + mpmsdem.sdem.Vector3(0.03, 0.04, 0.0)  # c moved 5 cm
    # a: two points above its top within 0.01 m of its centre (1e-6 and 3e-6 m³), one above it
    # 0.0113 m away on the diagonal (4e-6 m³), one below its top (5e-6 m³), one above it beyond its
    # plan (8e-6 m³, 0.022 m from the nearest sample). Samples covered: 4 by (0.1, 0.1), 4 by
    # (0.104, 0.1), two of them the first's, 4 by (0.108, 0.108): 10 of 100.
    pa = [((0.1, 0.1, 0.07), 1e-6), ((0.104, 0.1, 0.08), 3e-6), ((0.108, 0.108, 0.07), 4e-6),
          ((0.1, 0.1, 0.05), 5e-6), ((0.14, 0.1, 0.07), 8e-6)]
    # b: a layer of points 5 mm apart over x 0.1775-0.2225, y 0.0775-0.1225 (2.5e-7 m³ each, a
    # 1 cm layer) above its top, and as many below it: every sample lies within 0.0036 m of a
    # point above; the disc holds the 12 at (+-0.0025, +-0.0025), (+-0.0025, +-0.0075),
    # (+-0.0075, +-0.0025) from the centre
    g = np.arange(10) * 0.005
    layer = [((0.1775 + u, 0.0775 + w), 2.5e-7) for u in g for w in g]
    pb = [((x, y, 0.07), v) for (x, y), v in layer] + [((x, y, 0.05), 1e-6) for (x, y), _ in layer]
    # c (now at 0.33, 0.14): points below its top, one above it 0.03 m from its old centre, 0.022 m
    # beyond its plan's samples
    pc = [((0.33, 0.14, 0.05), 1e-6), ((0.32, 0.13, 0.03), 1e-6), ((0.33, 0.1, 0.07), 1e-6)]
    pts = pa + pb + pc
    particles = {"x": np.array([p for p, _ in pts]), "volume0": np.array([v for _, v in pts])}
    ra, rb, rc = tracker.report(particles)
    assert ra["top"] == pytest.approx(0.0605, abs=1e-12)
    assert ra["cover_depth"] == pytest.approx(4e-6 / (math.pi * 1e-4), rel=1e-12)
    assert ra["cover_fraction"] == 0.1 and ra["partly_buried"] and not ra["buried"]
    assert ra["cover"] == pytest.approx(8e-6 / (math.pi * 2 * 0.02 ** 2), rel=1e-12)  # the circle's, as before
    assert rb["cover_depth"] == pytest.approx(12 * 2.5e-7 / (math.pi * 1e-4), rel=1e-12)
    assert rb["cover_fraction"] == 1 and rb["buried"] and not rb["partly_buried"]
    assert rc["cover_depth"] == 0 and rc["cover_fraction"] == 0 and rc["cover"] == 0
    assert not rc["buried"] and not rc["partly_buried"] and rc["travel"] == pytest.approx(0.05, rel=1e-9)
    # positions in the map's own coordinates: the grid frame moved back by the origin
    for r in (ra, rb, rc):
        assert (r["x_map"], r["y_map"], r["z_map"]) == (r["x"] + 500000.0, r["y"] + 4100000.0, r["z"] + 250.0)
        assert (r["x0_map"], r["y0_map"], r["z0_map"]) == (r["x0"] + 500000.0, r["y0"] + 4100000.0,
                                                           r["z0"] + 250.0)
    assert rc["x_map"] == pytest.approx(500000.33, abs=1e-9) and rc["y0_map"] == pytest.approx(4100000.1, abs=1e-9)
    # radii and samples of one's own: a disc of 3 mm holds the first point only; 2 x 2 samples
    # (x, y = 0.09, 0.11) each within 0.015 m of (0.1, 0.1): a covered whole
    own = field.BlockTracker(coupled, [a], depthRadius=0.003, coverRadius=0.015, planSamples=2).report(particles)[0]
    assert own["cover_depth"] == pytest.approx(1e-6 / (math.pi * 0.003 ** 2), rel=1e-12)
    assert own["cover_fraction"] == 1 and own["buried"]
    # samples out of reach of every point (0.1 mm): none covered, but debris at its centre: partly buried
    far = field.BlockTracker(coupled, [a], coverRadius=1e-4, planSamples=2).report(particles)[0]
    assert far["cover_fraction"] == 0 and far["cover_depth"] > 0 and far["partly_buried"] and not far["buried"]
    for kw, words in (({"depthRadius": 0}, "depthRadius = 0 m: must be > 0"),
                      ({"coverRadius": float("nan")}, "coverRadius = nan m"),
                      ({"planSamples": 0}, "planSamples = 0: must be an integer >= 1")):
        with pytest.raises(ValueError, match=words):
            field.BlockTracker(coupled, [a], **kw)
    # the search's list: buried, partly buried or moved more than minTravel; deepest first
    rescue = field.rescueList([ra, rb, rc], minTravel=0.01)
    assert [(r["id"], r["status"]) for r in rescue] == [(a, "partly buried"), (b, "buried"), (c, "moved")]
    assert [r["id"] for r in field.rescueList([rc, rb, ra], minTravel=0.1)] == [a, b]
    with pytest.raises(ValueError, match="minTravel = -1 m"):
        field.rescueList([ra], minTravel=-1)
    lines = open(field.writeRescue(str(tmp_path / "rescue.csv"), rescue)).read().splitlines()
    assert lines[0] == ("id,status,x_map [m],y_map [m],z_map [m],cover_depth [m],cover_fraction [1],travel [m],"
                        "x [m],y [m]")
    assert lines[1].startswith("%d,partly buried,500000.1000,4100000.1000,250.0405,0.0127324,0.1,0," % a)
    assert len(lines) == 4
    # blocks.csv and blocks.h5 with the new columns, the map's coordinates to 0.1 mm, the series
    csvPath, h5Path = field.writeReport(str(tmp_path), [ra, rb, rc], series=tracker.series(),
                                        attrs={"map_offset": mpmsdem.terrain.mapOffset(ground), "crs": None})
    head, first = open(csvPath).read().splitlines()[:2]
    assert head.startswith("id,x0 [m],y0 [m],z0 [m],x [m],y [m],z [m],x0_map [m],y0_map [m],z0_map [m],x_map [m]")
    assert "cover_depth [m],cover_fraction [1],buried,partly_buried,outside_grid" in head
    cells = dict(zip(head.split(","), first.split(",")))
    assert cells["x_map [m]"] == "500000.1000" and cells["partly_buried"] == "1" and cells["buried"] == "0"
    h5py = pytest.importorskip("h5py")
    with h5py.File(h5Path, "r") as f:
        assert f["cover_depth"].attrs["unit"] == "m" and f["cover_fraction"].attrs["unit"] == "1"
        assert f["partly_buried"][:].tolist() == [True, False, False]
        assert f.attrs["map_offset"].tolist() == [500000.0, 4100000.0, 250.0] and "crs" not in f.attrs
        assert f["force_series"]["mean_force"].shape == (3, 0) and f["force_series"]["time"].attrs["unit"] == "s"
    with pytest.raises(ValueError, match="series: its blocks"):
        field.writeReport(str(tmp_path), [rb, ra, rc], series=tracker.series())


def test_a_mesh_block_from_the_table_rests_on_its_base(tmp_path):
    # A block from a mesh file in millimetres (a 2 x 1 x 0.8 m box as OBJ, '*0.001'): placed by the
    # table with the table's mass, it settles onto the ground on its four base corners.
    O.reset()
    obj = tmp_path / "van.obj"
    v = [(x, y, z) for x in (0, 2000) for y in (0, 1000) for z in (0, 800)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    obj.write_text("".join("v %g %g %g\n" % p for p in v) + "".join("f %d %d %d %d\n" % q for q in faces))
    table = tmp_path / "blocks.csv"
    field.writeBlockTable(str(table), [{"id": 0, "shape": "van.obj*0.001", "x": 0.0, "y": 0.0, "heading_deg": 30.0,
                                        "mass": 1500.0}])
    ground = Terrain.plane((-3.0, -3.0), (3.0, 3.0), 0.5, z0=0.0)
    sdem = mpmsdem.SdemEngine(dtCheck="raise", verbose=False)
    sdem.terrain(ground, mpmsdem.material(density=2500, friction=0.7, barrierStiffness=3e6))
    ids = field.placeBlocks(sdem, ground, field.readBlockTable(str(table)),
                            lambda rho: mpmsdem.material(density=rho, friction=0.7, barrierStiffness=3e6,
                                                         normalDamping=0.3, tangentialDamping=0.5),
                            folder=str(tmp_path))
    b = O.bodies[ids[0]]
    assert b.state.mass == pytest.approx(1500.0, rel=1e-9)
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 2e-4
    mpmsdem.run(2500, sdem)
    c = sdem.contacts()
    assert len(c["normalForce"]) == 4 and set(c["id2"]) == {-1}
    assert c["normalForce"].sum() == pytest.approx(1500.0 * 9.81, rel=5e-3)
    assert abs(b.state.pos[2] - 0.4) < 0.01  # its centre half its height above the ground


def test_the_tracker_takes_the_peak_and_its_window_mean_of_a_known_force():
    # A flow force made by hand on one block, step by step: 1 N everywhere but 101 N during one
    # step of 1 ms. The largest step value is 101 N at that step; its 10 ms window holds 10 steps,
    # so the window mean is (9 x 1 + 101) / 10 = 11 N, reported at the window's end; the first
    # contact is the first step.
    O.reset()
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=700, friction=0.5)
    a = sdem.box((0.02, 0.02, 0.02), 0.002, mat, pos=(0.1, 0.1, 0.0405))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [44, 24, 20], "origin": [-0.02, -0.02, 0.0]},
                            material=MATERIAL, particles=[], verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: {"friction": 0.3}}, verbose=False)
    tracker = field.BlockTracker(coupled, [a], window=0.01)
    O.engines = []
    O.dt = 1e-3
    for step in range(1, 41):
        O.step()  # the clock: O.time = step ms
        coupled.force = (lambda f: (lambda i: mpmsdem.sdem.Vector3(0, f, 0)))(101.0 if step == 25 else 1.0)
        tracker._step()
    assert tracker.peak[0] == 101.0 and tracker.peakTime[0] == pytest.approx(0.025)
    assert tracker.peakMean[0] == pytest.approx(11.0, rel=1e-12) and tracker.peakMeanTime[0] == pytest.approx(0.03)
    assert tracker.firstContact[0] == pytest.approx(0.001)
    # the window means as a time series: 1, 1, 11, 1 N at the windows' ends
    series = tracker.series()
    assert series["id"].tolist() == [a] and series["window"] == 0.01
    np.testing.assert_allclose(series["time"], [0.01, 0.02, 0.03, 0.04], rtol=1e-12)
    np.testing.assert_allclose(series["mean_force"], [[1.0, 1.0, 11.0, 1.0]], rtol=1e-12)
    with pytest.raises(ValueError, match="window = 0"):
        field.BlockTracker(coupled, [a], window=0)


def test_points_held_by_the_grid_walls_are_counted_on_the_sides_and_top_not_the_floor():
    # Grid box [0, 1] x [0, 0.5] x [0, 0.4] m of 0.01 m cells: the walls act 2 cells inside each
    # face, the count takes 3. One point by each side face and the top, one near the floor and
    # one in the middle; masses 1..7 kg.
    grid = {"origin": [0.0, 0.0, 0.0], "dx": 0.01, "cells": [100, 50, 40]}
    x = np.array([[0.025, 0.2, 0.1], [0.975, 0.2, 0.1], [0.5, 0.029, 0.1], [0.5, 0.475, 0.1], [0.5, 0.2, 0.375],
                  [0.5, 0.2, 0.005], [0.5, 0.2, 0.2]])
    mass = np.arange(1.0, 8.0)
    count, held = field.pointsAtGridWalls({"x": x, "mass": mass}, grid)
    assert count == 5 and held == pytest.approx(1 + 2 + 3 + 4 + 5, rel=1e-15)
    # just beyond the 3 cells: not held
    count, _ = field.pointsAtGridWalls({"x": np.array([[0.0301, 0.2, 0.1], [0.9699, 0.2, 0.1]]), "mass": [1, 1]}, grid)
    assert count == 0
    assert field.pointsAtGridWalls({"x": x, "mass": mass}, grid, layers=1)[0] == 0
    with pytest.raises(ValueError, match="layers"):
        field.pointsAtGridWalls({"x": x, "mass": mass}, grid, layers=0)
