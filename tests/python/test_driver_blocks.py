"""The plain C++ driver runs coupled scenes (blocks in the JSON scene, pkg/coupling/CoupledScene.hpp):
a scene written from a YADE set-up by mpmsdem.driver.writeScene gives the same block trajectories
and flow forces through mpmsdem-run as through YADE (its rigid-body update is YADE's
NewtonIntegrator's, blockedDOFs included), and bad block entries are refused by name."""
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import mpmsdem
from mpmsdem import driver
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator

import children

h5py = pytest.importorskip("h5py")

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
G = (0, 0, -9.81)


def driver_exe():
    return mpmsdem.driver.executable()


def scene(out, stiffness=None, velocity=(1.0, 0, 0), blob=True):
    """A granular blob falls onto and pushes two blocks resting on a fixed bed: a tilted
    convex hull (unequal principal moments: exact aspherical rotation) and a box that may only
    slide along x and turn about z (blockedDOFs 'yzXY'). stiffness: k_c of the flow–bed and
    flow–block pairs [N/m] (None: the default); velocity: the blob's [m/s]; blob False: the
    same scene without particles."""
    sdem = mpmsdem.SdemEngine(verbose=False)
    bedMat = mpmsdem.material(density=2500, friction=0.4)
    wood = mpmsdem.material(density=700, friction=0.5)
    bed = sdem.box((0.16, 0.08, 0.01), 0.002, bedMat, pos=(0.12, 0.07, 0.01), fixed=True)
    pts = [(0, 0, 0), (0.04, 0, 0), (0, 0.03, 0), (0.035, 0.03, 0.005), (0.005, 0.004, 0.025), (0.03, 0.025, 0.03)]
    hull = sdem.polyhedron([(x + 0.11, y + 0.03, z + 0.0205) for x, y, z in pts], 0.002, wood)
    box = sdem.box((0.012, 0.015, 0.01), 0.002, wood, pos=(0.125, 0.1, 0.0305))
    O.bodies[box].state.blockedDOFs = "yzXY"
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [26, 16, 12], "origin": [-0.01, -0.01, -0.01]},
                            material=GLASS, particles=[{"lo": [0.03, 0.03, 0.03], "hi": [0.08, 0.11, 0.07],
                                                        "ppc": 8, "velocity": list(velocity)}] if blob else [],
                            gravity=G, verbose=False)
    bedPair, woodPair = {"friction": 0.3}, {"friction": 0.2, "normalDamping": 0.1}
    if stiffness is not None:
        bedPair["barrierStiffness"] = woodPair["barrierStiffness"] = stiffness
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={bedMat: bedPair, wood: woodPair},
                                    output=str(out), outputEvery=4e-5, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=G, damping=0)]
    O.dt = 4e-5
    return coupled, (bed, hull, box)


def series(path):
    with h5py.File(path, "r", locking=False) as f:
        s = f["series"]
        return {k: np.array(s[k]) for k in s}, json.loads(f.attrs["ids"])


def run_both(coupled, path, steps, tmp_path):
    """YADE runs ``steps`` steps of ``coupled``, then the driver the scene it wrote to ``path``;
    both record every step into tmp_path/yade and tmp_path/driver: their series and ids (the
    records hold the initial state and every step's), and the driver's completed process."""
    mpmsdem.run(steps, coupled)
    r = subprocess.run([driver_exe(), path, "--steps", str(steps)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    y, yid = series(tmp_path / "yade" / "coupled.h5")
    d, did = series(tmp_path / "driver" / "coupled.h5")
    assert len(y["time"]) == len(d["time"]) == steps + 1
    return (y, yid), (d, did), r


def test_driver_matches_yade_for_the_same_coupled_scene(tmp_path):
    exe = driver_exe()
    coupled, (bed, hull, box) = scene(tmp_path / "yade")
    steps = 1200
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=O.dt, seriesEvery=O.dt,
                             outputEvery=0.02, outputDir=str(tmp_path / "driver"), vtk="none")
    # Both record every step the state at t (blocks and particles), with the flow forces of the
    # step that led there: record 0 is the initial state, the last one the state after the run.
    (y, yid), (d, did), r = run_both(coupled, path, steps, tmp_path)
    # where the step loop went, in shares that add up: the records (every step here) and the
    # snapshots (every 0.02 s) are timed apart from the time-step control
    split = re.search(r"step loop: MPM step ([-\d.]+) %, MP-block coupling ([-\d.]+) %, blocks ([-\d.]+) %, "
                      r"records ([-\d.]+) %, snapshots ([-\d.]+) %, time-step control ([-\d.]+) %", r.stdout)
    assert split, r.stdout[-2000:]
    shares = [float(v) for v in split.groups()]
    assert sum(shares) == pytest.approx(100, abs=0.5) and min(shares) >= -0.1
    assert shares[3] > 1 and shares[4] > 0.1  # records every step, a snapshot every 0.02 s
    assert yid == did == [bed, hull, box]
    assert np.abs(y["time"] - d["time"]).max() <= 1e-12
    # the flow did act: the blocks moved and were pushed
    assert np.abs(d["pos"][-1, 3:6] - d["pos"][0, 3:6]).max() > 2e-3
    assert np.abs(y["flow_force"][:, 3:]).max() > 0.05
    # same trajectories, forces and energies: round-off only (measured: 5e-16 relative in
    # position, 4e-14 in velocity, rotation and force after 1200 steps)
    for k in ("pos", "vel", "rotation", "flow_force", "face_force", "edge_force", "flow_impulse", "flow_angular_impulse",
              "flow_kinetic", "block_kinetic"):
        a, b = y[k], d[k]
        assert np.abs(a - b).max() <= 1e-11 * np.abs(a).max(), k
    # the same first contacts (the steps' starts, sums of the same steps), NaN until then
    assert np.isfinite(d["flow_first_contact"][-1]).any()
    np.testing.assert_allclose(y["flow_first_contact"], d["flow_first_contact"], rtol=1e-12, atol=0, equal_nan=True)
    # blockedDOFs 'yzXY' held in the driver: y, z fixed, rotation about z only; the bed fixed
    p = d["pos"][:, 6:9]
    assert np.abs(p[:, 1:] - p[0, 1:]).max() == 0
    assert np.abs(d["rotation"][:, 6:8]).max() == 0
    assert np.abs(d["rotation"][:, 8]).max() > 1e-4
    assert np.abs(d["pos"][:, 0:3] - d["pos"][0, 0:3]).max() == 0
    # --bench writes nothing but sums each moving block up: the same steps, so the records'
    # last pose and, over records taken every step, the largest flow force and its time
    r = subprocess.run([exe, path, "--steps", str(steps), "--bench"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    bench = json.loads(r.stdout.strip().splitlines()[-1])
    assert [b["block"] for b in bench["moving_blocks"]] == [1, 2]  # the fixed bed is left out
    for b in bench["moving_blocks"]:
        c = slice(3 * b["block"], 3 * b["block"] + 3)
        assert b["start"] == d["pos"][0, c].tolist() and b["end"] == d["pos"][-1, c].tolist()
        assert b["rotation_deg"] == pytest.approx(np.degrees(np.linalg.norm(d["rotation"][-1, c])), rel=1e-9)
        f = np.linalg.norm(d["flow_force"][:, c], axis=1)
        assert b["peak_flow_force"] == f.max() and b["peak_flow_force_time"] == d["time"][f.argmax()]
        fx = d["flow_force"][:, c][:, 0]
        assert b["peak_flow_force_x"] == fx.max() and b["peak_flow_force_x_time"] == d["time"][fx.argmax()]


def test_driver_runs_a_coupled_scene_without_particles_as_yade_does(tmp_path):
    """"particles": [] (MpmEngine(particles=[])): the blocks move under gravity and their own
    contacts alone, the same in the driver and in YADE, with no flow force and no flow front."""
    coupled, (bed, hull, box) = scene(tmp_path / "yade", blob=False)
    steps = 1200
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=O.dt, seriesEvery=O.dt,
                             outputEvery=0.02, outputDir=str(tmp_path / "driver"), vtk="none")
    with open(path) as f:
        assert json.load(f)["particles"] == []
    (y, _), (d, _), r = run_both(coupled, path, steps, tmp_path)
    assert "0 particles" in r.stdout
    assert np.abs(y["flow_force"]).max() == np.abs(d["flow_force"]).max() == 0
    # the hull starts 0.5 mm above the bed's barrier and lands: it moved, the same in both
    assert np.abs(d["pos"][-1, 3:6] - d["pos"][0, 3:6]).max() > 1e-4
    for k in ("pos", "vel", "rotation"):
        assert np.abs(y[k] - d[k]).max() <= 1e-11 * np.abs(y[k]).max(), k
    with h5py.File(tmp_path / "driver" / "mpm.h5", "r", locking=False) as f:
        assert np.isnan(f["series/front_x"][:]).all() and (f["series/kinetic_energy"][:] == 0).all()
        assert f["series/time"][-1] == pytest.approx(steps * O.dt, rel=1e-12)


def test_driver_matches_yade_on_a_terrain(tmp_path):
    """A blob falls onto a 10 deg planar terrain and pushes a box that rests on it: the flow's
    ground and the block's are the scene's terrain (MpmEngine(terrain=...), SdemEngine.terrain),
    and the driver runs the scene YADE writes with the same trajectories to round-off."""
    from mpmsdem.terrain import Terrain
    from yade.minieigenHP import Quaternion, Vector3
    exe = driver_exe()
    th = math.radians(10.0)
    ground = Terrain.plane((-0.05, -0.05), (0.3, 0.2), 0.02, z0=0.08, slope_x_deg=10.0, friction=0.3)
    sdem = mpmsdem.SdemEngine(verbose=False)
    wood = mpmsdem.material(density=700, friction=0.5)
    sdem.terrain(ground, mpmsdem.material(density=2500, friction=0.4))
    n = Vector3(math.sin(th), 0, math.cos(th))
    foot = Vector3(0.14, 0.07, float(ground.height(0.14, 0.07)))
    sdem.box((0.012, 0.015, 0.01), 0.002, wood, pos=foot + n * (0.01 + 0.0005), ori=Quaternion(Vector3(0, 1, 0), th))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [26, 16, 16], "origin": [-0.01, -0.01, -0.01]},
                            material=GLASS, particles=[{"lo": [0.03, 0.03, 0.0], "hi": [0.08, 0.11, 0.12], "ppc": 8,
                                                        "velocity": [1.0, 0, 0]}],
                            gravity=G, terrain=ground, verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={wood: {"friction": 0.2}}, output=str(tmp_path / "yade"),
                                    outputEvery=4e-5, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=G, damping=0)]
    O.dt = 4e-5
    steps = 2000
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=O.dt, seriesEvery=O.dt,
                             outputEvery=0.02, outputDir=str(tmp_path / "driver"), vtk="none")
    assert json.load(open(path))["terrain_material"]["friction"] == 0.4
    (y, _), (d, _), _ = run_both(coupled, path, steps, tmp_path)
    assert np.linalg.norm(d["pos"][-1] - d["pos"][0]) > 1e-3  # landed, pushed down the slope
    assert np.abs(d["flow_force"]).max() > 0.01
    for k in ("pos", "vel", "rotation", "flow_force"):
        assert np.abs(y[k] - d[k]).max() <= 1e-11 * np.abs(y[k]).max(), k
    # the box stands on the ground: its lowest core corner stays above the surface
    corner = d["pos"][-1] - 0.008 * np.array([n[0], n[1], n[2]])
    assert corner[2] > float(ground.height(corner[0], corner[1])) - 0.01
    # a scene whose blocks have no ground contact is refused by the driver, naming the key
    bad = json.load(open(path))
    del bad["terrain_material"]
    json.dump(bad, open(str(tmp_path / "bad.json"), "w"))
    r = subprocess.run([exe, str(tmp_path / "bad.json"), "--steps", "1"], capture_output=True, text=True)
    assert r.returncode != 0 and "terrain_material: required" in r.stderr + r.stdout


@pytest.mark.parametrize("stiffness, steps", [(1e5, 1500), (1e7, 3000)])
def test_driver_auto_step_follows_yade_dtAuto(tmp_path, stiffness, steps):
    """"dt": "auto" in the driver and dtAuto in YADE choose the same steps from the same
    contacts (coupling.coupledAutoStep: the coupled critical step times the factor, bounded by
    the blocks' and the particles' approach steps and a growth cap), so the same scene runs the
    same step sequence and the same trajectories through both, while the blob lands on the
    blocks and contacts come and go. A stiffer flow barrier (k_c 1e5 N/m) and a blob thrown
    down onto the bed make the MP–bed and MP–block contacts, not the MPM CFL step, set the
    step; at k_c 1e7 N/m the particles' approach step does at each first touch (without it that
    run stopped at step 185, its step above twice the contact step)."""
    coupled, (bed, hull, box) = scene(tmp_path / "yade", stiffness=stiffness, velocity=(1.0, 0, -1.0))
    coupled.dtAuto = 0.5
    coupled.outputEvery = 1e-9  # a record every step, as the driver's seriesEvery below
    O.dt = 1.0  # above any step dtAuto sets: the first step is dtAuto's own, as in the driver
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt="auto", dtFactor=0.5,
                             seriesEvery=1e-9, outputEvery=0.02, outputDir=str(tmp_path / "driver"), vtk="none")
    (y, _), (d, _), _ = run_both(coupled, path, steps, tmp_path)
    dt = np.diff(d["time"])
    # the steps did change (contacts of the landing blob set them: 2.9e-5 to 5.0e-5 s at k_c
    # 1e5, 6.5e-6 to 4.9e-5 s at 1e7), and both took the same ones
    assert dt.max() > 1.5 * dt.min() and dt.min() > 0
    assert np.abs(np.diff(y["time"]) - dt).max() <= 1e-9 * dt.max()
    # the flow did act, and the trajectories agree to round-off (measured at k_c 1e5: 5e-15
    # relative in position and force, 5e-13 in velocity and rotation after 1500 steps)
    assert np.abs(d["pos"][-1, 3:9] - d["pos"][0, 3:9]).max() > 2e-3
    for k in ("pos", "vel", "rotation", "flow_force"):
        a, b = y[k], d[k]
        assert np.abs(a - b).max() <= 1e-11 * np.abs(a).max(), k


def h5tree(path):
    """The series datasets of an HDF5 file by name, and its snapshots' datasets by their time."""
    series, snaps = {}, {}
    with h5py.File(path, "r", locking=False) as f:
        for k in f.get("series", {}):
            series[k] = np.array(f["series"][k])
        for g in f.get("snapshots", {}).values():
            snaps[float(g.attrs["time"])] = {k: np.array(g[k]) for k in g}
    return series, snaps


def assertSameSeries(whole, split):
    """Every series dataset of the HDF5 file ``split`` equals that of ``whole`` to the bit;
    returns their snapshots (h5tree's) for the caller's checks."""
    a, sa = h5tree(whole)
    b, sb = h5tree(split)
    assert sorted(a) == sorted(b), split
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg="%s:%s" % (split, k))
    return sa, sb


@pytest.mark.parametrize("dt, stiffness", [(4e-5, 1e5), ("auto", 1e7)])
def test_coupled_driver_restart_continues_the_same_run_bit_for_bit(tmp_path, dt, stiffness):
    """A coupled run stopped and restarted (--restart) is the run that was not stopped: every
    record of coupled.h5 and mpm.h5 and the last particles equal to the last bit, with a fixed
    step and with "dt": "auto" (whose next step depends on the contact and approach steps the
    checkpoint carries). Also when the checkpoint is older than the last snapshot (a run killed
    between the two): the run continues from the checkpoint's snapshot, and what was written
    after it is replaced."""
    exe = driver_exe()
    coupled, _ = scene(tmp_path / "yade", stiffness=stiffness, velocity=(1.0, 0, -1.0))
    steps = 1200
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=dt, dtFactor=0.5,
                             seriesEvery=1e-9, outputEvery=2e-3, outputDir=str(tmp_path / "whole"), vtk="none")

    def drive(out, n, restart=False):
        r = subprocess.run([exe, path, "--out", str(out), "--steps", str(n)] + (["--restart"] if restart else []),
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r.stdout

    drive(tmp_path / "whole", steps)
    first = steps // 2
    if dt == "auto":
        # stop where the next step shrinks: there the contact and approach steps the checkpoint
        # carries choose it (where it grows, the growth cap does, from the last step alone)
        with h5py.File(tmp_path / "whole" / "mpm.h5", "r", locking=False) as f:
            steps_taken = np.array(f["series/dt"])  # record i: the step that led to it
        first = next(i for i in range(steps // 4, 3 * steps // 4) if steps_taken[i + 1] < steps_taken[i])
    split = tmp_path / "split"
    drive(split, first)
    old = (split / "coupled.checkpoint.json").read_text()
    # stopped while the blob presses on the blocks: MP-block histories held, the hull turning
    c = json.loads(old)
    assert len(c["coupling_histories"]) > 0
    assert np.abs(c["bodies"][1]["ang_mom"]).max() > 0 and c["contact_step"] is not None
    assert "restarting" in drive(split, steps // 4, restart=True)
    # as if the run had been killed after its last snapshot and before that snapshot's checkpoint
    (split / "coupled.checkpoint.json").write_text(old)
    drive(split, steps - first, restart=True)
    for name in ("coupled.h5", "mpm.h5"):
        sa, sb = assertSameSeries(tmp_path / "whole" / name, split / name)
        # the split run also saved its state where it stopped (and, dropped with its checkpoint,
        # a quarter run later), off the output times of an automatic step: the rest are the same
        assert set(sa) <= set(sb) and len(sb) - len(sa) <= 1, name
        for t in sa:
            for k in sa[t]:
                np.testing.assert_array_equal(sa[t][k], sb[t][k], err_msg="%s: snapshot at %g s, %s" % (name, t, k))
    assert max(sb) == max(sa)
    d, _ = series(split / "coupled.h5")
    assert len(d["time"]) == steps + 1 and (np.diff(d["time"]) > 0).all()
    assert np.abs(d["flow_force"][:, 3:]).max() > 0.05 and np.abs(d["pos"][-1, 3:6] - d["pos"][0, 3:6]).max() > 1e-4
    if dt == "auto":
        assert np.ptp(np.diff(d["time"])) > 0  # the contacts did set the steps


def test_a_restart_from_a_checkpoint_without_impulses_counts_them_from_there(tmp_path):
    """A run continued from a checkpoint (and coupled.h5) of a version that kept no impulses:
    the restart goes on, every series keeps a row per record (NaN impulses before the restart),
    and from there the impulse changes between records are those of the unbroken run
    (round-off: the sums start from another origin)."""
    exe = driver_exe()
    coupled, _ = scene(tmp_path / "yade", stiffness=1e5, velocity=(1.0, 0, -1.0))
    steps = 1200
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=4e-5, seriesEvery=1e-9,
                             outputEvery=2e-3, outputDir=str(tmp_path / "whole"), vtk="none")

    def drive(out, n, restart=False):
        r = subprocess.run([exe, path, "--out", str(out), "--steps", str(n)] + (["--restart"] if restart else []),
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr

    drive(tmp_path / "whole", steps)
    split = tmp_path / "split"
    drive(split, steps // 2)
    c = json.loads((split / "coupled.checkpoint.json").read_text())
    assert np.abs(np.array(c.pop("coupling_impulse"))[:, :3]).max() > 0  # the blob had pushed the blocks
    c.pop("coupling_first_contact")  # nor the first contacts, kept later still
    (split / "coupled.checkpoint.json").write_text(json.dumps(c))
    for name in ("coupled.h5", "coupled.h5.restart"):
        with h5py.File(split / name, "a") as f:
            del f["series/flow_impulse"], f["series/flow_angular_impulse"], f["series/flow_first_contact"]
    drive(split, steps - steps // 2, restart=True)
    w, _ = series(tmp_path / "whole" / "coupled.h5")
    d, _ = series(split / "coupled.h5")
    restart = steps // 2  # the record at the restart is the old run's
    for k in ("flow_impulse", "flow_angular_impulse"):
        assert d[k].shape == w[k].shape == (steps + 1, w["pos"].shape[1])
        assert np.isnan(d[k][:restart + 1]).all() and np.isfinite(d[k][restart + 1:]).all()
        np.testing.assert_allclose(np.diff(d[k][restart + 1:], axis=0), np.diff(w[k][restart + 1:], axis=0), rtol=0,
                                   atol=1e-12 * np.abs(w[k]).max())
    # which block the flow had touched is not known there: no first contact, before or after
    assert np.isfinite(w["flow_first_contact"][-1]).any() and np.isnan(d["flow_first_contact"]).all()
    np.testing.assert_array_equal(d["pos"], w["pos"])


def test_a_signal_stops_the_coupled_driver_with_its_state_saved_and_restart_goes_on_bit_for_bit(tmp_path):
    """SIGTERM (as `timeout` or a batch system sends it) stops a coupled run after the step in
    progress with exit status 4, its state saved as a snapshot with the coupled checkpoint of
    that step; --restart for the remaining steps then gives every record of the unbroken run to
    the last bit. A second SIGTERM while it saves changes nothing."""
    exe = driver_exe()
    coupled, _ = scene(tmp_path / "yade", velocity=(1.0, 0, -1.0))
    steps = 6000
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=4e-5, seriesEvery=1e-9,
                             outputEvery=0.05, outputDir=str(tmp_path / "whole"), vtk="none")
    r = subprocess.run([exe, path, "--steps", str(steps)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    split = tmp_path / "split"
    proc = subprocess.Popen([exe, path, "--out", str(split), "--steps", str(steps)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    lines = []
    for line in proc.stdout:  # the progress line at 5 % of the steps: well inside the step loop
        lines.append(line)
        if line.startswith("[  5.0%]"):
            proc.send_signal(subprocess.signal.SIGTERM)
            proc.send_signal(subprocess.signal.SIGTERM)
            break
    lines += proc.stdout.readlines()
    assert proc.wait() == 4, "".join(lines)
    stopped = [ln for ln in lines if "stopped by SIGTERM" in ln]
    assert len(stopped) == 1 and "--restart continues the run" in stopped[0], "".join(lines)
    checkpoint = json.loads((split / "coupled.checkpoint.json").read_text())
    first = checkpoint["step"]
    assert steps // 20 <= first < steps  # stopped between the 5 % line and the end, off the output times
    _, snaps = h5tree(split / "mpm.h5")
    assert abs(max(snaps) - checkpoint["time"]) <= 1e-12 * checkpoint["time"]
    r = subprocess.run([exe, path, "--out", str(split), "--steps", str(steps - first), "--restart"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assertSameSeries(tmp_path / "whole" / "coupled.h5", split / "coupled.h5")
    sa, sb = assertSameSeries(tmp_path / "whole" / "mpm.h5", split / "mpm.h5")
    assert set(sa) <= set(sb) and len(sb) - len(sa) == 1  # and the stop's own snapshot
    for t in sa:
        for k in sa[t]:
            np.testing.assert_array_equal(sa[t][k], sb[t][k], err_msg="snapshot at %g s, %s" % (t, k))
    d, _ = series(split / "coupled.h5")
    assert len(d["time"]) == steps + 1 and np.abs(d["flow_force"][:, 3:]).max() > 0.05


def test_coupled_driver_restart_refuses_outputs_it_cannot_continue(tmp_path):
    exe = driver_exe()
    coupled, _ = scene(tmp_path / "yade")
    out = tmp_path / "o"
    path = driver.writeScene(str(tmp_path / "scene.json"), coupled, duration=1.0, dt=4e-5, outputEvery=2e-3,
                             outputDir=str(out), vtk="none")
    r = subprocess.run([exe, path, "--steps", "60"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    checkpoint = json.loads((out / "coupled.checkpoint.json").read_text())
    assert checkpoint["step"] == 60 and checkpoint["snapshot"] == 2  # t = 0, 2e-3 s and the end
    cases = [({"snapshot": 7}, "snapshot"), ({"step": 59}, "not of one time"), ({"format": "x"}, "format"),
             ({"bodies": checkpoint["bodies"][:2]}, "blocks")]
    for change, expect in cases:
        (out / "coupled.checkpoint.json").write_text(json.dumps(dict(checkpoint, **change)))
        r = subprocess.run([exe, path, "--steps", "10", "--restart"], capture_output=True, text=True)
        assert r.returncode == 2 and "--restart" in r.stderr and expect in r.stderr, (change, r.stderr)
    (out / "coupled.checkpoint.json").unlink()
    r = subprocess.run([exe, path, "--steps", "10", "--restart"], capture_output=True, text=True)
    assert r.returncode == 2 and "coupled.checkpoint.json is missing" in r.stderr, r.stderr


def test_bad_block_entries_are_refused_by_name(tmp_path):
    exe = driver_exe()
    base = {"grid": {"dx": 0.02, "cells": [10, 10, 10], "origin": [0, 0, 0]}, "material": GLASS,
            "particles": [{"lo": [0.04, 0.04, 0.04], "hi": [0.08, 0.08, 0.08], "ppc": 1}],
            "run": {"duration": 0.001, "vtk": "none"},
            "block_materials": {"wood": {"density": 700, "flow": {"friction": 0.2}}},
            "blocks": [{"material": "wood", "box": [0.02, 0.02, 0.02], "sweep_radius": 0.002,
                        "position": [0.14, 0.1, 0.1]}]}
    cases = [
        (("blocks", 0, "material"), "steel", "blocks[0].material"),
        (("blocks", 0, "sweep_radius"), 0.03, "sweepRadius"),
        (("blocks", 0, "blocked_dofs"), "xq", "blocks[0].blocked_dofs"),
        (("blocks", 0, "orientation"), [1, 1, 0, 0], "blocks[0].orientation"),
        (("blocks", 0, "colour"), "red", "unknown key 'blocks[0].colour'"),
        (("block_materials", "wood", "density"), -1, "block_materials.wood.density"),
        (("block_materials", "wood", "flow"), {"friction": -0.1}, "block_materials.wood.flow.friction"),
    ]
    for keys, value, expect in cases:
        s = json.loads(json.dumps(base))
        target = s
        for k in keys[:-1]:
            target = target[k]
        target[keys[-1]] = value
        path = tmp_path / "bad.json"
        path.write_text(json.dumps(s))
        r = subprocess.run([exe, str(path), "--out", str(tmp_path / "o")], capture_output=True, text=True)
        assert r.returncode == 2 and expect in r.stderr, (keys, r.stderr)
    # a core table that is not closed
    s = json.loads(json.dumps(base))
    del s["blocks"][0]["box"]
    s["blocks"][0]["core"] = {"vertices": [[0, 0, 0], [0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.02]],
                              "faces": [[0, 2, 1], [0, 1, 3], [0, 3, 2]]}
    (tmp_path / "bad.json").write_text(json.dumps(s))
    r = subprocess.run([exe, str(tmp_path / "bad.json"), "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2 and "blocks[0]" in r.stderr and "core.faces" in r.stderr, r.stderr


def same_values(a, b, path="scene"):
    """Nested JSON values equal, numbers to 1e-12 relative; returns the first difference's path."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return "%s: keys %s" % (path, sorted(set(a) ^ set(b)))
        return next((d for d in (same_values(a[k], b[k], "%s.%s" % (path, k)) for k in sorted(a)) if d), None)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return "%s: %d against %d entries" % (path, len(a), len(b))
        return next((d for d in (same_values(x, y, "%s[%d]" % (path, i)) for i, (x, y) in enumerate(zip(a, b))) if d),
                    None)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return None if a == pytest.approx(b, rel=1e-12, abs=1e-15) else "%s: %r against %r" % (path, a, b)
    return None if a == b else "%s: %r against %r" % (path, a, b)


@pytest.mark.parametrize("name, flags", [("flume_block.json", []), ("flume_block_full.json", ["--full"])])
def test_stored_flume_scenes_are_what_the_example_writes(tmp_path, name, flags):
    # examples/scenes holds the §3.2 flume as driver scenes (a GPU machine, which has no YADE, runs
    # them): a change of examples/flume_block.py (its seeding, materials, step) must reach them.
    repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    stored = json.load(open(os.path.join(repo, "examples", "scenes", name)))
    written = str(tmp_path / name)
    proc = subprocess.run([sys.executable, os.path.join(repo, "examples", "flume_block.py"), *flags,
                           "--driver-scene", written, "--out", stored["run"]["output_dir"]],
                          capture_output=True, text=True, env=children.env())
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    stored.pop("description")
    difference = same_values(json.load(open(written)), stored)
    assert difference is None, ("examples/scenes/%s differs from what examples/flume_block.py %s--driver-scene "
                                "writes (%s): write it again" % (name, " ".join(flags) + " " if flags else "",
                                                                  difference))


def test_flume_example_defaults_to_the_named_settings_of_its_resolution(tmp_path):
    # --full runs the joint design's set (calibrated at dx 0.01 m), the coarse grid Table 1's;
    # --settings picks one by name and a single option changes one value of it.
    repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    example = os.path.join(repo, "examples", "flume_block.py")
    from mpmsdem.flume import FLUME_SETTINGS
    from mpmsdem.mpm import PAPER_VISCOSITY

    def scene(*flags):
        written = str(tmp_path / "scene.json")
        proc = subprocess.run([sys.executable, example, *flags, "--driver-scene", written, "--out", str(tmp_path / "o")],
                              capture_output=True, text=True, env=children.env())
        assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
        s = json.load(open(written))
        flows = sorted(m["flow"]["friction"] for m in s["block_materials"].values())
        return (s["material"]["mu_2"], s.get("flip_viscosity"), s["walls"]["+y"], flows)

    joint, table1 = FLUME_SETTINGS["joint"], FLUME_SETTINGS["table1"]
    assert scene("--full") == (0.7221, 0.0347053, 0.111, [0.2778, 0.3938])
    assert (joint["mu_2"], joint["flip_viscosity"], joint["side_wall_friction"]) == (0.7221, 0.0347053, 0.111)
    assert scene("--full", "--settings", "table1") == (0.65, pytest.approx(PAPER_VISCOSITY, rel=1e-12), 0.0,
                                                       [0.21, 0.21])
    assert (table1["mu_2"], table1["basal_friction"]) == (0.65, 0.21)
    assert scene() == (0.65, None, 0.0, [0.21, 0.21])  # None: the scenes' default blend on the coarse grid
    assert scene("--settings", "joint", "--mu-2", "0.7") == (0.7, 0.0347053, 0.111, [0.2778, 0.3938])


def test_flume_example_takes_the_flow_and_friction_settings(tmp_path):
    # examples/flume_block.py --basal-friction/--mu-2/--flow-friction/--side-wall-friction/
    # --flip-viscosity reach the scene (the joint design's sets are run with them); a value out of
    # range is refused naming the option.
    repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    example = os.path.join(repo, "examples", "flume_block.py")
    written = str(tmp_path / "set.json")
    proc = subprocess.run([sys.executable, example, "--driver-scene", written, "--out", str(tmp_path / "o"),
                           "--mu-2", "0.72", "--basal-friction", "0.28", "--flow-friction", "0.39",
                           "--side-wall-friction", "0.11", "--flip-viscosity", "0.036"],
                          capture_output=True, text=True, env=children.env())
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    scene = json.load(open(written))
    assert scene["material"]["mu_2"] == 0.72 and scene["flip_viscosity"] == 0.036
    assert scene["walls"]["+y"] == scene["walls"]["-y"] == 0.11
    flows = sorted(m["flow"]["friction"] for m in scene["block_materials"].values())
    assert flows == [0.28, 0.39]  # the bed takes the basal friction, the cube the flow-cube friction
    for flag, value, words in (("--mu-2", "0.2", "--mu-2 = 0.2: must be > mu_s = 0.24"),
                               ("--basal-friction", "-0.1", "--basal-friction = -0.1: must be >= 0"),
                               ("--flip-viscosity", "0", "--flip-viscosity = 0.0 m²/s: must be > 0")):
        proc = subprocess.run([sys.executable, example, "--driver-scene", written, flag, value],
                              capture_output=True, text=True, env=children.env())
        assert proc.returncode != 0 and words in proc.stderr, proc.stderr[-2000:]
