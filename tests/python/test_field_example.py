"""examples/field_valley.py, the field-scale example, on a coarse grid for a short time: it runs
from a YADE-less Python as a user would, conserves the debris, keeps it above the ground, and
writes maps whose deposit holds the source's volume."""
import csv
import json
import os
import subprocess
import sys

import numpy as np

import mpmsdem
import mpmsdem.driver
import pytest

import children

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def test_field_example_runs_and_its_maps_hold_the_debris(tmp_path):
    out = str(tmp_path / "field")
    proc = subprocess.run([sys.executable, os.path.join(REPO, "examples", "field_valley.py"), "--dx", "1.0",
                           "--duration", "3", "--out", out, "--no-plots", "--blocks", "12"],
                          capture_output=True, text=True, env=children.env(OMP_NUM_THREADS=1), timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    s = json.load(open(os.path.join(out, "summary.json")))
    assert s["mass"] == s["mass_seeded"] and s["below_ground"] == 0 and s["unmapped_points"] == 0
    h5py = pytest.importorskip("h5py")
    assert s["flip_damping_rate"] == pytest.approx(4 * 0.3125 / 1.0 ** 2, rel=1e-12)  # the default ν at dx 1 m
    assert s["front_x"] > 15.0  # the debris left its source (x 2-8 m) and ran down the valley
    assert s["blocks"] == 12 and s["blocks_below_ground"] == 0
    with h5py.File(os.path.join(out, "blocks.h5"), "r") as f:
        assert len(f["id"]) == 12 and f["cover"].attrs["unit"] == "m"
        # the blocks the flow never touched stand where placed (settling on their corners: 2.2 cm of
        # "travel"); the one the front reached in 3 s (at 5 /s of damping, the example's default)
        # is pushed down the plain by more than its settling
        untouched, travel = f["peak_force"][:] == 0, f["travel"][:]
        assert untouched.sum() >= 6 and np.all(travel[untouched] < 0.05) and np.all(travel[~untouched] > 0.05)
    lines = open(os.path.join(out, "blocks.csv")).read().splitlines()
    assert lines[0].startswith("id,x0 [m]") and len(lines) == 13
    assert "about" in proc.stdout and "s left" in proc.stdout  # progress with the time left
    with h5py.File(os.path.join(out, "mpm.h5"), "r") as f:
        last = sorted(f["snapshots"].keys())[-1]
        volume = f["snapshots"][last]["volume0"][:].sum()
    header = dict(line.split() for line in open(os.path.join(out, "maps", "deposit_thickness.asc")).readlines()[:6])
    thickness = np.loadtxt(os.path.join(out, "maps", "deposit_thickness.asc"), skiprows=6)
    assert thickness.sum() * float(header["cellsize"]) ** 2 == pytest.approx(volume, rel=1e-6)
    for name in ("max_thickness.tif", "max_speed.asc", "flow_maps.png", "max_momentum_flux.tif",
                 "max_dynamic_pressure.tif", "arrival_time.tif"):
        assert os.path.getsize(os.path.join(out, "maps", name)) > 0

    def grid(name):  # i along x, j along y; NaN for no data
        v = np.loadtxt(os.path.join(out, "maps", name + ".asc"), skiprows=6)[::-1].T
        return np.where(v == -9999.0, np.nan, v)
    # pressure and arrival where the flow was at least 0.1 m thick (the default), and only there;
    # the source's nodes at t 0, the rest by the run's end (its last sample)
    thick, arrival, pressure = grid("max_thickness"), grid("arrival_time"), grid("max_dynamic_pressure")
    assert s["map_min_thickness"] == 0.1
    assert np.all(np.isfinite(arrival[thick >= 0.1 * (1 + 1e-8)]))
    assert np.all(np.isnan(arrival[thick < 0.1 * (1 - 1e-8)]))
    assert np.array_equal(np.isfinite(arrival), np.isfinite(pressure))
    assert np.nanmin(arrival) == 0 and 0.5 < np.nanmax(arrival) <= s["duration"] and np.any(np.isnan(arrival))
    assert s["max_momentum_flux"] == pytest.approx(np.nanmax(grid("max_momentum_flux")), rel=1e-8)
    assert s["max_momentum_flux"] > 0
    with h5py.File(os.path.join(out, "blocks.h5"), "r") as f:
        assert f["cover_depth"].attrs["unit"] == "m" and f["x_map"][:].tolist() == f["x"][:].tolist()
        assert f["force_series"]["mean_force"].shape == (12, len(f["force_series"]["time"]))
        assert len(f["force_series"]["time"]) >= 250  # 10 ms windows over 3 s
    assert open(os.path.join(out, "rescue.csv")).readline().startswith("id,status,x_map [m]")
    assert "search and rescue (rescue.csv): %d blocks" % s["blocks_to_find"] in proc.stdout
    assert os.path.getsize(os.path.join(out, "terrain.vtk")) > 0 and os.path.exists(os.path.join(out, "scene.pvd"))
    bad = subprocess.run([sys.executable, os.path.join(REPO, "examples", "field_valley.py"), "--dx", "0", "--out", out],
                         capture_output=True, text=True, env=children.env())
    assert bad.returncode != 0 and "--dx = 0.0 m: must be > 0" in bad.stderr, bad.stderr[-2000:]


def test_field_example_runs_on_a_raster_file_moved_by_its_origin(tmp_path):
    # The valley written as a georeferenced ESRI ASCII grid far from the origin, read back with
    # --terrain and moved to the grid's zero by --origin: the same debris runs down it.
    from mpmsdem.terrain import Terrain
    v = Terrain.valley(60.0, 16.0, 0.5, slope_deg=28.0, side_slope_deg=30.0, floor_width=4.0, runout=34.0)
    v.x0, v.y0 = 500000.0, 4100000.0
    v.heights = v.heights + 250.0
    dem = str(tmp_path / "valley.asc")
    v.writeAsc(dem)
    # two blocks of a table (grid frame) on the plain's floor, out of the flow's reach in 2 s
    from mpmsdem import field
    table = str(tmp_path / "blocks.csv")
    field.writeBlockTable(table, [{"id": k, "shape": "box:1.0x1.0x1.0", "x": x, "y": 8.0, "heading_deg": 0.0,
                                   "mass": 2000.0} for k, x in enumerate((45.0, 52.0))])
    out = str(tmp_path / "field")
    proc = subprocess.run([sys.executable, os.path.join(REPO, "examples", "field_valley.py"), "--dx", "1.0",
                           "--duration", "2", "--out", out, "--no-plots", "--terrain", dem,
                           "--origin", "500000", "4100000", "250", "--block-table", table],
                          capture_output=True, text=True, env=children.env(OMP_NUM_THREADS=1), timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    s = json.load(open(os.path.join(out, "summary.json")))
    assert s["mass"] == s["mass_seeded"] and s["below_ground"] == 0 and s["blocks"] == 2
    assert s["front_x"] > 12.0 and s["map_offset"] == [500000.0, 4100000.0, 250.0]
    for name in ("deposit_thickness", "arrival_time", "max_momentum_flux"):
        header = dict(line.split() for line in open(os.path.join(out, "maps", name + ".asc")).readlines()[:6])
        assert float(header["xllcenter"]) == 500000.0 and float(header["yllcenter"]) == 4100000.0  # the map's own place
    # the blocks in the map's own coordinates: the grid frame's moved back by the origin
    rows = list(csv.DictReader(open(os.path.join(out, "blocks.csv"))))
    assert len(rows) == 2
    for r in rows:
        for a in ("x", "y", "z"):
            shift = {"x": 500000.0, "y": 4100000.0, "z": 250.0}[a]
            assert float(r[a + "_map [m]"]) == pytest.approx(float(r[a + " [m]"]) + shift, abs=1e-4 + 1e-5 * abs(
                float(r[a + " [m]"])))
        assert float(r["y_map [m]"]) == pytest.approx(4100008.0, abs=0.05) and r["buried"] == "0"


def test_field_example_writes_a_driver_scene_that_runs_without_yade(tmp_path):
    # --driver-scene: the flow, the terrain (its heights inline) and the blocks with their ground
    # material, for mpmsdem-run on a machine without YADE; the driver keeps every block on its
    # 4 corners on the ground while the flow comes down.
    scene = str(tmp_path / "field.json")
    proc = subprocess.run([sys.executable, os.path.join(REPO, "examples", "field_valley.py"), "--dx", "1.0",
                           "--blocks", "12", "--duration", "1", "--driver-scene", scene, "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, env=children.env())
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    s = json.load(open(scene))
    assert len(s["blocks"]) == 12 and s["terrain"]["nx"] == 121 and s["terrain_material"]["friction"] == 0.7
    r = subprocess.run([mpmsdem.driver.executable(), scene, "--bench"], capture_output=True, text=True,
                       env=children.env(OMP_NUM_THREADS=1))
    assert r.returncode == 0, r.stderr[-3000:]
    bench = json.loads(r.stdout.strip().splitlines()[-1])
    assert bench["blocks"] == 12 and bench["block_contacts"] == 48 and bench["time"] >= 1.0
    for b in bench["moving_blocks"]:
        assert np.linalg.norm(np.array(b["end"]) - np.array(b["start"])) < 0.05  # settled where placed


def test_a_driver_scene_for_a_finer_grid_seeds_what_the_example_seeds(tmp_path):
    # --driver-scene builds its engines on a grid of at least 0.5 m and writes the scene for the
    # --dx asked: the driver then seeds the same debris the example seeds at that dx.
    example = os.path.join(REPO, "examples", "field_valley.py")
    scene = str(tmp_path / "fine.json")
    proc = subprocess.run([sys.executable, example, "--dx", "0.4", "--blocks", "0", "--duration", "0.05",
                           "--driver-scene", scene, "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, env=children.env())
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    s = json.load(open(scene))
    assert s["grid"]["dx"] == 0.4
    r = subprocess.run([mpmsdem.driver.executable(), scene, "--bench", "--steps", "5"], capture_output=True, text=True,
                       env=children.env(OMP_NUM_THREADS=1))
    assert r.returncode == 0, r.stderr[-3000:]
    bench = json.loads(r.stdout.strip().splitlines()[-1])
    out = str(tmp_path / "run")
    proc = subprocess.run([sys.executable, example, "--dx", "0.4", "--blocks", "0", "--duration", "0.05", "--no-plots",
                           "--out", out], capture_output=True, text=True, env=children.env(OMP_NUM_THREADS=1))
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert bench["particles"] == json.load(open(os.path.join(out, "summary.json")))["points"] > 40000
