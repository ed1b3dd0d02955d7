"""Blocks on a terrain by table (mpmsdem.field): the table read and refused clearly, each block
placed resting on the ground's slope, and the per-block report: travel, rotation, force, first
contact and the cover of debris over its top, against hand-made cases."""
import math

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
                        ("1,box:1x1x1,zero,0,0,1\n", "line 2: could not convert"),
                        ("1,box:1x1x1,nan,0,0,1\n", "line 2: x, y, heading_deg and mass must be finite")):
        bad = tmp_path / "bad.csv"
        bad.write_text(head + body)
        with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")):
            field.readBlockTable(str(bad))
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
    assert ra["cover"] == pytest.approx(expected, rel=1e-12) and ra["cover"] > 0.02 and ra["buried"]
    assert rb["cover"] == 0 and not rb["buried"]
    assert rb["travel"] == pytest.approx(0.05, rel=1e-9) and ra["travel"] == 0
    assert math.isnan(ra["first_contact"]) and ra["peak_force"] == 0  # no step taken yet


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
