"""A run that can only crawl says so: the driver's answers to the inputs that used to leave it
silent (a block at 1e3 or 1e30 m/s, a barrier of k_c 1e15 N/m with an automatic step, a block
far outside the grid), the YADE engine's floor on its automatic step, and a run whose step
collapsed refusing the same way after a SIGKILL and a restart.

The scene: a blob of 1,728 material points thrown at 2 m/s at a steel box (4 cm, R 2 mm) 7 cm
ahead, no gravity; the flow's P-wave speed is c_p = sqrt((λ + 2G)/ρ) = 29.0 m/s for E 1 MPa,
ν 0.3, ρ 1600, so the default run.max_block_speed is 290 m/s."""
import json
import math
import os
import signal
import subprocess
import time

import numpy as np
import pytest

import mpmsdem
import mpmsdem.driver

h5py = pytest.importorskip("h5py")


def scene(vel=(0, 0, 0), kc=None, pos=(0.15, 0.05, 0.05), **run):
    flow = {"friction": 0.3}
    if kc:
        flow["barrier_stiffness"] = kc
    return {"grid": {"dx": 0.01, "cells": [30, 14, 14], "origin": [-0.02, -0.02, -0.02]}, "gravity": [0, 0, 0],
            "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
            "particles": [{"lo": [0.0, 0.02, 0.02], "hi": [0.06, 0.08, 0.08], "ppc": 8, "velocity": [2, 0, 0]}],
            "block_materials": {"steel": {"density": 7800, "flow": flow}},
            "blocks": [{"material": "steel", "box": [0.02, 0.02, 0.02], "sweep_radius": 0.002, "position": list(pos),
                        "velocity": list(vel)}],
            "run": dict({"duration": 0.06, "dt": "auto", "output_every": 0.002, "vtk": "none"}, **run)}


def drive(tmp_path, sc, *args, timeout=120):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(sc))
    return subprocess.run([mpmsdem.driver.executable(), str(path), "--out", str(tmp_path / "out"), *args],
                          capture_output=True, text=True, timeout=timeout, env=dict(os.environ, OMP_NUM_THREADS="1"))


@pytest.mark.parametrize("speed", [1e3, 1e30])
def test_a_block_faster_than_any_wave_of_the_scene_is_refused_at_load(tmp_path, speed):
    r = drive(tmp_path, scene(vel=(speed, 0, 0)), timeout=30)
    assert r.returncode == 2, r.stdout + r.stderr
    assert "blocks[0] (id 0): speed %g m/s" % speed in r.stderr and "run.max_block_speed = 290.06 m/s" in r.stderr, \
        r.stderr
    assert not (tmp_path / "out" / "mpm.h5").exists()  # refused before any output


def test_a_crawling_run_reports_by_wall_time_and_names_the_block(tmp_path):
    # allowed by a raised max_block_speed and no step floor: the step is 0.1 R / v = 2e-7 s, the
    # 5 % lines would come after 15,000 steps; the wall-time lines come every 0.3 s
    sc = scene(vel=(1e3, 0, 0), max_block_speed=1e4, min_step_fraction=0, progress_every=0.3)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(sc))
    p = subprocess.Popen([mpmsdem.driver.executable(), str(path), "--out", str(tmp_path / "out")],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ, OMP_NUM_THREADS="1"))
    time.sleep(2.0)
    p.kill()
    out, _ = p.communicate()
    lines = [ln for ln in out.splitlines() if ln.startswith("[")]
    assert len(lines) >= 3, out
    assert all("dt=2e-07 s (block 0's approach: it moves at 1000 m/s" in ln for ln in lines), lines[:2]
    assert all(float(ln[1:ln.index("%")]) < 5 for ln in lines), lines  # none of them a 5 % line


def test_the_step_floor_stops_the_run_with_its_cause_and_the_last_good_state(tmp_path):
    r = drive(tmp_path, scene(vel=(1e3, 0, 0), max_block_speed=1e4, min_step_fraction=0.01), timeout=30)
    assert r.returncode == 3, r.stdout + r.stderr
    assert ("the automatic step fell to 2e-07 s at t = 0 s (step 0), below run.min_step_fraction = 0.01 of the "
            "flow's CFL step" in r.stderr), r.stderr
    assert "block 0's approach: it moves at 1000 m/s" in r.stderr and "last good state" in r.stderr
    with h5py.File(tmp_path / "out" / "mpm.h5", "r") as f:
        assert "min_step_fraction" in f.attrs["failure"]
        assert f["snapshots"][sorted(f["snapshots"])[-1]].attrs["step"] == 0


def test_a_stiff_barrier_shortens_the_step_before_the_first_contact(tmp_path):
    # k_c 1e15 N/m: the automatic step used to stay a CFL step (8.7e-5 s) until the blob's face
    # was in the barrier, then the run blew up (step 402). Now the step shrinks before the first
    # contact, and the blob only loses kinetic energy.
    r = drive(tmp_path, scene(kc=1e15), timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    with h5py.File(tmp_path / "out" / "mpm.h5", "r") as f:
        dt, ke = f["series/dt"][1:], f["series/kinetic_energy"][:]
    with h5py.File(tmp_path / "out" / "coupled.h5", "r") as f:
        vx = f["series/vel"][:, 0]
    assert vx[-1] > 0.1  # the blob hit the block and pushed it (a stiff impact: shorter than a record interval)
    assert ke.max() <= ke[0] * (1 + 1e-9)
    assert dt.min() < 1e-5 < dt.max()  # the step shrank, and grew back once the contacts had settled


def test_a_block_outside_the_grid_is_a_warning_and_a_far_away_pose_is_refused(tmp_path):
    r = drive(tmp_path, scene(pos=(5, 0.05, 0.05)), timeout=120)
    assert r.returncode == 0, r.stderr
    warning = "blocks[0] (id 0) can never touch the flow"
    assert warning in r.stderr and "[-0.02, 0.28]" in r.stderr, r.stderr
    for name in ("mpm.h5", "coupled.h5"):
        with h5py.File(tmp_path / "out" / name, "r") as f:
            assert warning in f.attrs["warnings"], name
    assert "no contact in this run" in r.stdout
    r = drive(tmp_path, scene(pos=(1e6, 0.05, 0.05)), timeout=30)
    assert r.returncode == 2 and "blocks[0] (id 0).position" in r.stderr and "100 grid diagonals" in r.stderr, r.stderr


def test_a_run_whose_step_collapsed_refuses_the_same_after_a_kill_and_a_restart(tmp_path):
    # k_c 1e9 N/m and a floor at a tenth of the CFL step: the step falls below it as the blob
    # closes on the block (about t = 0.033 s, after 16 snapshots). The unbroken run's refusal
    # is the reference; a run killed with SIGKILL at a random moment before it and restarted
    # (as often as it takes: a kill before the first snapshot leaves nothing to restart) stops
    # at the same step with the same words.
    sc = scene(kc=1e9, min_step_fraction=0.1)
    (tmp_path / "ref").mkdir()
    ref = drive(tmp_path / "ref", sc)
    assert ref.returncode == 3, ref.stdout[-1000:] + ref.stderr
    refusal = ref.stderr.splitlines()[0]
    assert "below run.min_step_fraction = 0.1" in refusal, ref.stderr
    rng = np.random.default_rng(7)
    work = tmp_path / "killed"
    work.mkdir()
    path = work / "scene.json"
    path.write_text(json.dumps(sc))
    exe = mpmsdem.driver.executable()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.Popen([exe, str(path), "--out", str(work / "out")], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, env=env)
    time.sleep(float(rng.uniform(0.2, 0.5)))
    p.send_signal(signal.SIGKILL)
    p.wait()
    for _ in range(5):
        r = subprocess.run([exe, str(path), "--out", str(work / "out"), "--restart"], capture_output=True, text=True,
                           timeout=120, env=env)
        if r.returncode != 2:
            break
        # killed before its first snapshot: nothing to restart from, run it again and kill later
        subprocess.run([exe, str(path), "--out", str(work / "out"), "--steps", "50"], capture_output=True, env=env,
                       check=True)
    assert r.returncode == 3, r.stdout[-1000:] + r.stderr
    assert r.stderr.splitlines()[0] == refusal
    assert math.isfinite(float(refusal.split("fell to ")[1].split(" s")[0]))


def test_yade_coupled_engine_floors_its_automatic_step_and_names_the_block(tmp_path):
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    sdem = mpmsdem.SdemEngine(verbose=False)
    steel = mpmsdem.material(density=7800, friction=0.3)
    cube = sdem.box((0.02, 0.02, 0.02), 0.002, steel, pos=(0.15, 0.05, 0.05))
    O.bodies[cube].state.vel = (500, 0, 0)
    sc = scene()
    mpm = mpmsdem.MpmEngine(grid=sc["grid"], material=sc["material"], particles=sc["particles"], gravity=(0, 0, 0),
                            output=str(tmp_path / "mpm"), outputEvery=0.01, verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={steel: {"friction": 0.3}}, dtAuto=0.5, minStepFraction=0.01,
                                    verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    # 500 m/s is beyond ten times the flow's P-wave speed (290 m/s): refused before the first step
    with pytest.raises(ValueError, match=r"body %d: speed 500 m/s .* exceeds maxBlockSpeed = 290.06" % cube):
        mpmsdem.run(1, coupled)
    assert O.iter == 0
    coupled.maxBlockSpeed = 1e4  # allowed, the floor stops it instead
    with pytest.raises(RuntimeError) as e:
        mpmsdem.run(20, coupled)
    text = str(e.value)
    assert "below minStepFraction = 0.01 of the flow's CFL step" in text, text
    assert "block %d's approach: it moves at 500 m/s" % cube in text, text
    assert "last snapshot in" in coupled.error  # the particles of the last good step were saved
    with pytest.raises(ValueError, match="minStepFraction"):
        mpmsdem.CoupledEngine(sdem, mpm, pairs={steel: {"friction": 0.3}}, minStepFraction=1.0)


def test_yade_coupled_engine_warns_of_a_block_outside_the_grid(tmp_path):
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    sdem = mpmsdem.SdemEngine(verbose=False)
    steel = mpmsdem.material(density=7800, friction=0.3)
    near = sdem.box((0.02, 0.02, 0.02), 0.002, steel, pos=(0.15, 0.05, 0.05))
    far = sdem.box((0.02, 0.02, 0.02), 0.002, steel, pos=(5.0, 0.05, 0.05))
    sc = scene()
    mpm = mpmsdem.MpmEngine(grid=sc["grid"], material=sc["material"], particles=sc["particles"], gravity=(0, 0, 0),
                            verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={steel: {"friction": 0.3}}, output=str(tmp_path / "out"),
                                    outputEvery=1e-3, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    with pytest.warns(RuntimeWarning, match="body %d can never touch the flow" % far) as record:
        mpmsdem.run(3, coupled)
    assert not any("body %d can" % near in str(w.message) for w in record)
    with h5py.File(tmp_path / "out" / "coupled.h5", "r", locking=False) as f:
        assert f.attrs["warnings"].startswith("body %d can never touch the flow" % far)
