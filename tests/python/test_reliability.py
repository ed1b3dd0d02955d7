"""Reliability of runs that fail, stop and restart (issue 8): saved failure states that can be
resumed, checkpoints that continue their outputs and restore from any folder, clear errors for
misordered engines and bad input."""
import gc
import json
import math
import os
import shutil
import warnings

import numpy as np
import pytest

import mpmsdem
from yade import O
from yade.minieigenHP import Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator

from scenes import DATA, KC, R, cubeOnSlab, run


def _finite(v):
    return all(math.isfinite(v[k]) for k in range(len(v)))


def _kill(engine):
    """What a killed process leaves: the engine gone, with its open output files closed. The
    runner's command keeps a reference in __main__ (see sdem._bindStep): drop it too."""
    import __main__
    for name in [n for n in vars(__main__) if n.startswith("_mpmsdem_")]:
        if getattr(getattr(__main__, name), "__self__", None) is engine:
            delattr(__main__, name)
    O.reset()
    gc.collect()


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
    _kill(eng)
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
        assert np.allclose(t, np.arange(10) * 0.01, atol=1e-9)  # history before the checkpoint kept
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
