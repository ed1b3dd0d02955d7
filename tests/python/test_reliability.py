"""Reliability of runs that fail, stop and restart (issue 8): saved failure states that can be
resumed, checkpoints that continue their outputs and restore from any folder, clear errors for
misordered engines and bad input."""
import json
import math
import os
import shutil
import warnings

import numpy as np
import pytest

import mpmsdem
import mpmsdem.driver
from yade import O
from yade.minieigenHP import Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator

from scenes import DATA, KC, R, cubeOnSlab, forget, run


def _finite(v):
    return all(math.isfinite(v[k]) for k in range(len(v)))


# ---------------------------------------------------------------- 1. failure state resumable
def test_blown_up_run_saves_a_state_that_resumes_with_a_smaller_step(tmp_path):
    # dt = 0.01 s is ~10x the critical step of the landing cube: with dtCheck="warn" it is
    # driven into the bed until the cores interpenetrate. The state YADE holds then is the
    # broken one; the saved state must be the last good one, from which a 100x smaller step
    # continues without error.
    prefix = str(tmp_path / "failed")
    eng, cube, slab, m = cubeOnSlab(gap=0.001, dtCheck="warn", saveOnFailure=prefix, verbose=False)
    O.dt = 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(RuntimeError, match="interpenetrate") as err:
            run(eng, 200)
    msg = str(err.value)
    assert "O.load" in msg and "SdemEngine.restore" in msg and "smaller O.dt" in msg
    failedIter = O.iter
    O.reset()
    O.load(prefix + ".yade.gz")
    s = O.bodies[cube].state
    assert _finite(s.pos) and _finite(s.vel) and _finite(s.angVel)
    with open(prefix + ".sdem.json") as f:
        saved = json.load(f)
    assert saved["time"] == pytest.approx((failedIter - 1) * 0.01, abs=1e-12)  # one step before the failure
    eng2 = mpmsdem.SdemEngine.restore(prefix + ".sdem.json", dtCheck="raise", verbose=False)
    O.engines = [ForceResetter(), eng2.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-4
    run(eng2, 500)
    s = O.bodies[cube].state
    assert _finite(s.pos) and s.pos[2] > 0.04  # bounced off the bed, not through it


# ---------------------------------------------------------------- 2. restore continues outputs
def test_restore_continues_outputs_and_dissipation_without_duplicates(tmp_path):
    h5py = pytest.importorskip("h5py")
    out, ck = tmp_path / "out", tmp_path / "ck"
    eng, cube, slab, m = cubeOnSlab(thetaDeg=30.0, mu=0.1, output=str(out), outputEvery=0.01, vtkEvery=0.02,
                                    verbose=False)
    O.dt = 1e-4
    run(eng, 500)                                   # checkpoint at t = 0.05 s
    eng.save(str(ck) + ".sdem.json")
    O.save(str(ck) + ".yade.gz")
    friction = eng.energies()["friction"]
    assert friction > 0
    run(eng, 300)                                   # ... the run goes on to 0.08 s, then is killed
    forget(eng)
    O.load(str(ck) + ".yade.gz")
    eng2 = mpmsdem.SdemEngine.restore(str(ck) + ".sdem.json", output=str(out), outputEvery=0.01, vtkEvery=0.02,
                                      verbose=False)
    assert eng2.energies()["friction"] == friction
    O.engines = [ForceResetter(), eng2.runner, NewtonIntegrator(gravity=O.engines[-1].gravity, damping=0)]
    run(eng2, 500)                                  # to 0.1 s
    assert eng2.energies()["friction"] > friction
    with h5py.File(out / "sdem.h5", "r", locking=False) as f:
        t = f["series/time"][:]
        assert np.all(np.diff(t) > 0)               # nothing twice, never back in time
        # history before the checkpoint kept, and the run's final state (t = 0.1 s) recorded
        assert np.allclose(t, np.arange(11) * 0.01, atol=1e-9)
        for name in ("step", "pos", "ori", "vel", "contacts"):
            assert f["series/" + name].shape[0] == len(t), name
    import xml.etree.ElementTree as ET
    times = [float(d.get("timestep")) for d in ET.parse(out / "bodies.pvd").getroot().iter("DataSet")]
    assert np.allclose(times, np.arange(5) * 0.02, atol=1e-9)


# ---------------------------------------------------------------- 3. self-contained checkpoints
def test_checkpoint_restores_from_another_folder_without_the_mesh_file(tmp_path, monkeypatch):
    # A mesh body described by a relative path: the checkpoint must carry its geometry, so that
    # it restores, with the same contact features, after the mesh file is gone.
    work, other = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    other.mkdir()
    shutil.copy(os.path.join(DATA, "l_prism.obj"), work / "block.obj")
    monkeypatch.chdir(work)
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=500.0, friction=0.3, barrierStiffness=KC, normalDamping=0.3)
    eng.box((1.0, 1.0, 0.05), R, mat, pos=(0, 0, -0.05), fixed=True)
    block = eng.mesh("block.obj", R, mat, pos=(0, 0, 0.051))
    g = Vector3(2.0, 0, -9.81)                      # slides: tangential histories matter
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=g, damping=0)]
    O.dt = 5e-5
    run(eng, 400)
    eng.save("ck.sdem.json")
    O.save("ck.yade.gz")
    assert len(eng.contacts()["overlap"]) > 0
    run(eng, 400)
    ref = Vector3(O.bodies[block].state.pos)
    for name in ("ck.sdem.json", "ck.yade.gz"):
        shutil.move(str(work / name), str(other / name))
    shutil.rmtree(work)
    monkeypatch.chdir(other)
    O.reset()
    O.load("ck.yade.gz")
    eng2 = mpmsdem.SdemEngine.restore("ck.sdem.json", verbose=False)
    O.engines = [ForceResetter(), eng2.runner, NewtonIntegrator(gravity=g, damping=0)]
    run(eng2, 400)
    assert (O.bodies[block].state.pos - ref).norm() < 1e-12


# ---------------------------------------------------------------- 4. driver restart, same scene
def _driver():
    return mpmsdem.driver.executable()


SCENE = {"grid": {"dx": 0.02, "cells": [12, 6, 10], "origin": [-0.04, -0.04, -0.04]},
         "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
         "particles": [{"lo": [0, 0, 0], "hi": [0.08, 0.04, 0.08], "ppc": 8}],
         "run": {"duration": 0.01, "dt": 2e-4, "output_every": 0.004, "vtk": "none"}}


def test_driver_restart_refuses_an_edited_scene(tmp_path):
    import subprocess
    exe = _driver()
    path, out = tmp_path / "scene.json", str(tmp_path / "out")
    drive = lambda scene, *a: (path.write_text(json.dumps(scene)),  # noqa: E731
                               subprocess.run([exe, str(path), "--out", out, *a], capture_output=True, text=True))[1]
    assert drive(SCENE, "--steps", "20").returncode == 0
    edited = json.loads(json.dumps(SCENE))
    edited["material"]["mu_s"] = 0.5
    edited["particles"][0]["hi"][2] = 0.06
    r = drive(edited, "--restart")
    assert r.returncode == 2, r.stderr
    assert "material.mu_s" in r.stderr and "particles" in r.stderr and "run.duration" in r.stderr
    # a longer run, another output cadence or backend are what a restart is for
    longer = json.loads(json.dumps(SCENE))
    longer["run"]["duration"] = 0.02
    longer["description"] = "the same run, longer"
    r = drive(longer, "--restart", "--steps", "5")
    assert r.returncode == 0, r.stderr


# ---------------------------------------------------------------- 5. one copy of the particles
CRUSH = {"grid": {"dx": 0.01, "cells": [12, 12, 14], "origin": [0, 0, 0]},
         "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
         "particles": [{"lo": [0.03, 0.03, 0.02], "hi": [0.09, 0.09, 0.08], "ppc": 8}],
         "gravity": [0, 0, -1e5], "walls": {"-z": "noslip"}}  # crushed to J < 1e-3 in a few hundred steps


def _snapshots(path):
    import h5py
    with h5py.File(path, "r", locking=False) as f:
        return [(int(g.attrs["step"]), g["x"][:], g["J"][:]) for _, g in sorted(f["snapshots"].items())]


def test_a_crushed_mpm_engine_leaves_its_last_good_state_with_one_copy_or_two(tmp_path):
    # keepLastGoodState on: the state at the start of the failed step is saved (once: the last
    # step's outputs may have written it already); off: the same run fails at the same step, and
    # the last good state is the last snapshot written before the failure, equal to the twin's.
    runs = {}
    for keep in (True, False):
        out = tmp_path / ("keep" if keep else "lean")
        mpm = mpmsdem.MpmEngine(grid=CRUSH["grid"], material=CRUSH["material"], particles=CRUSH["particles"],
                                gravity=CRUSH["gravity"], walls=CRUSH["walls"], output=str(out), outputEvery=2.79e-4,
                                keepLastGoodState=keep, verbose=False)
        O.engines = [mpm.runner]
        O.dt = 9.3e-5
        with pytest.raises(RuntimeError, match="volume ratio J"):
            mpmsdem.run(500, mpm)
        assert mpm.solver.holdsLastGoodState == keep
        runs[keep] = (O.iter, mpm.error, _snapshots(out / "mpm.h5"))
        O.reset()
    (iterKeep, errKeep, snapKeep), (iterLean, errLean, snapLean) = runs[True], runs[False]
    assert iterKeep == iterLean == 89                                           # step 90 fails
    assert "last good state saved as the last snapshot" in errKeep
    assert "partly advanced (keepLastGoodState is off)" in errLean and "last good state: the last snapshot" in errLean
    stepsKeep, stepsLean = [s[0] for s in snapKeep], [s[0] for s in snapLean]
    assert stepsLean == list(range(0, 88, 3))                                   # every 3 steps
    assert stepsKeep == stepsLean + [89]                                        # and the step's start, once
    for a, b in zip(snapKeep, snapLean):                                        # the same run to the last bit
        np.testing.assert_array_equal(a[1], b[1])
        np.testing.assert_array_equal(a[2], b[2])
    assert snapKeep[-1][2].min() >= 1e-3 and snapLean[-1][2].min() >= 1e-3


def test_driver_with_one_copy_names_the_last_snapshot_as_the_last_good_state(tmp_path):
    import subprocess
    import h5py
    exe = _driver()
    results = {}
    for keep in (True, False):
        scene = dict(CRUSH, keep_last_good_state=keep,
                     run={"duration": 0.02, "dt": "auto", "dt_factor": 0.9, "output_every": 1e-3, "vtk": "none"})
        path, out = tmp_path / ("scene%d.json" % keep), tmp_path / ("out%d" % keep)
        path.write_text(json.dumps(scene))
        r = subprocess.run([exe, str(path), "--out", str(out)], capture_output=True, text=True,
                           env=dict(os.environ, OMP_NUM_THREADS="1"))
        assert r.returncode == 3, r.stderr
        with h5py.File(out / "mpm.h5", "r", locking=False) as f:
            results[keep] = (r.stderr, dict(f.attrs), [int(g.attrs["step"]) for _, g in sorted(f["snapshots"].items())])
    (errKeep, attrsKeep, stepsKeep), (errLean, attrsLean, stepsLean) = results[True], results[False]
    assert "volume ratio J" in attrsKeep["failure"] and "volume ratio J" in attrsLean["failure"]
    assert "saved as snapshot" in errKeep and "failure_snapshot" in attrsKeep
    assert "last good state: the last snapshot in" in errLean and "failure_snapshot" not in attrsLean
    assert stepsLean == stepsKeep[:-1] and len(stepsLean) > 5                  # the same, none at the failure


# ---------------------------------------------------------------- 6. engine order
def test_misplaced_or_missing_sdem_runner_is_a_clear_error():
    from yade.wrapper import PyRunner
    eng, cube, slab, m = cubeOnSlab(gap=0.001, verbose=False)
    O.dt = 1e-4
    newton = NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)
    for engines in ([ForceResetter(), newton, eng.runner],     # runner after the integrator
                    [eng.runner, newton],                       # no ForceResetter
                    [ForceResetter(), newton]):                 # no runner: the cube would fall through
        O.engines = engines
        with pytest.raises(ValueError, match=r"ForceResetter\(\), sdem.runner, NewtonIntegrator"):
            run(eng, 2)
        assert O.iter == 0
    # plain O.run: the runner checks on its first step
    O.engines = [ForceResetter(), newton, eng.runner]
    with pytest.raises(RuntimeError, match=r"ForceResetter\(\), sdem.runner, NewtonIntegrator"):
        O.run(1, True)
    with pytest.raises(RuntimeError, match=r"ForceResetter\(\), sdem.runner, NewtonIntegrator"):
        eng.check()
    eng.error = None
    O.engines = [ForceResetter(), eng.runner, newton]
    run(eng, 2)                                                 # the right order runs


def test_mpm_runner_missing_is_a_clear_error():
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.02, "cells": [8, 8, 8], "origin": [0, 0, 0]},
                            material={"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.3,
                                      "mu_2": 0.6},
                            particles=[{"lo": [0.04, 0.04, 0.04], "hi": [0.08, 0.08, 0.08], "ppc": 1}], verbose=False)
    O.engines = []
    O.dt = 1e-4
    with pytest.raises(ValueError, match="MpmEngine's runner"):
        mpmsdem.run(2, mpm)
    O.engines = [mpm.runner]
    mpmsdem.run(2, mpm)
    assert mpm.solver.steps == 2


def test_runner_of_a_scene_loaded_elsewhere_says_how_to_rebuild(tmp_path):
    # A saved scene loaded in a process that has not rebuilt the engine: its PyRunner's
    # command must say what to do, not raise a NameError on a generated name.
    import subprocess
    import sys
    eng, cube, slab, m = cubeOnSlab(gap=0.001, verbose=False)
    O.dt = 1e-4
    run(eng, 2)
    O.save(str(tmp_path / "scene.yade.gz"))
    code = ("import mpmsdem\nfrom yade import O\nO.load(%r)\ntry:\n    O.run(1, True)\nexcept Exception as e:\n"
            "    print('ERROR', e)\n" % str(tmp_path / "scene.yade.gz"))
    import children
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=children.env())
    text = r.stdout + r.stderr
    assert "not registered in this process" in text and "SdemEngine.restore" in text, text
    assert "NameError" not in text, text


# ---------------------------------------------------------------- 7. bad input named
def test_non_finite_or_mistyped_sdem_inputs_name_the_parameter():
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=1000)
    with pytest.raises(ValueError, match="pos = .*finite"):
        eng.box((0.05,) * 3, 0.005, mat, pos=(float("nan"), 0, 0))
    with pytest.raises(ValueError, match="ori = .*finite"):
        eng.box((0.05,) * 3, 0.005, mat, ori=(float("nan"), 0, 0, 1))
    with pytest.raises(ValueError, match="ori = "):
        eng.box((0.05,) * 3, 0.005, mat, ori=(0, 0, 0, 0))
    with pytest.raises(ValueError, match="density = 'abc': must be a number"):
        mpmsdem.material(density="abc")
    with pytest.raises(ValueError, match="friction = "):
        mpmsdem.material(density=1000, friction=None)
    assert eng.ids == []


def test_mpm_engine_takes_numpy_and_names_a_nan():
    grid = {"dx": 0.02, "cells": np.array([8, 8, 8]), "origin": np.zeros(3)}
    mat = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": np.float64(0.3), "mu_2": 0.6}
    box = {"lo": np.array([0.04, 0.04, 0.04]), "hi": np.array([0.08, 0.08, 0.08]), "ppc": np.int64(1)}
    mpm = mpmsdem.MpmEngine(grid=grid, material=mat, particles=[box], gravity=np.array([0, 0, -9.81]), verbose=False)
    assert mpm.numParticles == 8
    with pytest.raises(ValueError, match=r"material.mu_s = nan: must be a finite number"):
        mpmsdem.MpmEngine(grid=grid, material=dict(mat, mu_s=float("nan")), particles=[box], verbose=False)
    with pytest.raises(ValueError, match=r"particles\[0\].hi\[2\] = inf"):
        mpmsdem.MpmEngine(grid=grid, material=mat, particles=[dict(box, hi=[0.08, 0.08, float("inf")])],
                          verbose=False)


def test_driver_names_bad_scene_files_and_sizes(tmp_path):
    import subprocess
    exe = _driver()
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE).replace('"density": 1600', '"density": 1e999'))
    r = subprocess.run([exe, str(path), "--bench", "--steps", "1"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "out of range" in r.stderr, r.stderr
    r = subprocess.run([exe, "/dev/zero", "--bench", "--steps", "1"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "/dev/zero" in r.stderr and "regular" in r.stderr, r.stderr
    # device stage timing goes with --bench on the CUDA backend
    path.write_text(json.dumps(SCENE))
    r = subprocess.run([exe, str(path), "--device-stages", "--steps", "1"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "--device-stages: only with --bench" in r.stderr, r.stderr
    r = subprocess.run([exe, str(path), "--bench", "--device-stages", "--backend", "cpu", "--steps", "1"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "--device-stages" in r.stderr and "cpu backend" in r.stderr, r.stderr
    # 600^3 cells would need ~14 GB as a dense grid; the CPU backend holds the node columns the
    # flow reaches, so the small flow runs under a 2 GB cap
    huge = json.loads(json.dumps(SCENE))
    huge["grid"] = {"dx": 0.02, "cells": [600, 600, 600], "origin": [-0.04, -0.04, -0.04]}
    path.write_text(json.dumps(huge))
    capped = ["bash", "-c", 'ulimit -v 2000000 && exec "$0" "$1" --bench --steps 1', exe, str(path)]
    r = subprocess.run(capped, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    # filled with material (1.7e9 points, hundreds of GB) it does not: a message naming grid.cells, exit 2
    huge["particles"] = [{"lo": [0, 0, 0], "hi": [11.9, 11.9, 11.9], "ppc": 8}]
    path.write_text(json.dumps(huge))
    r = subprocess.run(capped, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "out of memory" in r.stderr and "grid.cells = [600, 600, 600]" in r.stderr, r.stderr


def test_driver_bench_rate_leaves_out_the_warmup_steps_as_the_peer_does(tmp_path):
    # The Taichi peer times its steps after two warm-up steps; ours must count the same steps
    # (the first step sorts the seeded particles from scratch), else the ratio is biased.
    import subprocess
    exe = _driver()
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    for steps, warm in ((6, 2), (2, 0)):
        r = subprocess.run([exe, str(path), "--bench", "--steps", str(steps)], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 0, r.stderr
        out = json.loads(r.stdout.strip().splitlines()[-1])
        assert out["steps"] == steps and out["warmup_steps"] == warm
        assert 0 <= out["warmup_seconds"] < out["seconds"]
        assert (warm == 0) == (out["warmup_seconds"] == 0)
        rate = out["particles"] * (steps - warm) / (out["seconds"] - out["warmup_seconds"])
        assert out["particle_updates_per_s"] == pytest.approx(rate, rel=1e-12)
