"""Outputs as docs/outputs.md describes them: layout of sdem.h5 and mpm.h5, the final state of
a run recorded, the coupled checkpoint continuing bit-for-bit, bodies added mid-run refused
while a per-body output is being written."""

import json
import math
import os

import numpy as np
import pytest

import mpmsdem
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator

from scenes import cubeOnSlab, forget, run

h5py = pytest.importorskip("h5py")

DRIVER_SERIES = {"time", "step", "dt", "kinetic_energy", "front_x", "height_z", "centre_of_mass", "max_speed",
                 "flowing_fraction", "gasified_fraction"}  # pkg/run/OutputRun.cpp, recordSeries
GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def test_sdem_h5_layout_and_the_final_state_of_a_run_is_recorded(tmp_path):
    eng, cube, slab, m = cubeOnSlab(thetaDeg=20.0, mu=0.2, output=str(tmp_path), outputEvery=0.01, verbose=False)
    O.dt = 1e-4
    run(eng, 1000)                                  # a 0.1 s run
    pos = np.array(O.bodies[cube].state.pos)
    with h5py.File(tmp_path / "sdem.h5", "r", locking=False) as f:
        s = f["series"]
        assert set(s) == {"time", "step", "pos", "ori", "vel", "angVel", "force", "torque", "contacts"}
        t = s["time"][:]
        assert len(t) == 11 and t[-1] == pytest.approx(0.1, abs=1e-12)  # 0, 0.01, ..., 0.1: the end included
        assert s["step"].dtype == np.float64 and s["step"][-1] == 1000
        assert list(np.asarray(eval(f.attrs["ids"]))) == [slab, cube]
        assert s["pos"].shape == (11, 6) and s["ori"].shape == (11, 8) and s["contacts"].shape == (11,)
        np.testing.assert_array_equal(s["pos"][-1, 3:], pos)          # the state YADE holds at the end
        final = s["force"][-1, 3:].copy()
        assert final[2] > 0                                           # resting on the bed
    # the final record's force is the one the next step computes, and taking it changed nothing
    run(eng, 1)
    np.testing.assert_array_equal(np.array(eng.force(cube)), final)
    run(eng, 99)                                    # continuing: no duplicate of t = 0.1
    with h5py.File(tmp_path / "sdem.h5", "r", locking=False) as f:
        t = f["series/time"][:]
        assert np.all(np.diff(t) > 0)
        np.testing.assert_allclose(t[10:], [0.1, 0.1001, 0.11], rtol=0, atol=1e-12)  # each run's end, then the grid


def test_mpm_h5_has_the_driver_series_and_snapshot_0_before_step_1(tmp_path):
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.02, "cells": [10, 6, 10], "origin": [-0.04, -0.04, -0.04]},
                            material=GLASS, particles=[{"lo": [0, 0, 0], "hi": [0.08, 0.04, 0.08], "ppc": 1}],
                            output=str(tmp_path), outputEvery=0.002, verbose=False)
    p0 = mpm.particles()
    x0 = p0["x"].copy()
    O.engines = [mpm.runner]
    O.dt = 2e-4
    mpmsdem.run(25, mpm)
    with h5py.File(tmp_path / "mpm.h5", "r", locking=False) as f:
        assert set(f["series"]) == DRIVER_SERIES
        s = f["series"]
        n = len(s["time"])
        assert all(s[k].shape[0] == n for k in DRIVER_SERIES)
        assert s["centre_of_mass"].shape == (n, 3)
        # step 0, then every 10 steps, then the final state (step 25)
        np.testing.assert_array_equal(s["step"][:], [0, 10, 20, 25])
        assert s["time"][-1] == pytest.approx(0.005, abs=1e-12) and s["dt"][0] == 0 and s["dt"][-1] == 2e-4
        snap0 = f["snapshots/000000"]
        assert snap0.attrs["time"] == 0 and snap0.attrs["step"] == 0
        np.testing.assert_array_equal(snap0["x"][:], x0)
        # a snapshot holds what MpmEngine.particles() gives, array for array (one table for both)
        assert set(snap0) == set(p0)
        for name in p0:
            np.testing.assert_array_equal(snap0[name][:], p0[name], err_msg=name)
        np.testing.assert_allclose(p0["density"], p0["mass"] / (p0["J"] * p0["volume0"]), rtol=1e-15)
        assert p0["stress"].shape == (len(x0), 6) and p0["phase"].shape == (len(x0),)
        assert sorted(f["snapshots"]) == ["000000", "000001", "000002"]  # t = 0, 0.002, 0.004
        com = s["centre_of_mass"][-1]
        p = mpm.particles()
        np.testing.assert_allclose(com, (p["mass"][:, None] * p["x"]).sum(0) / p["mass"].sum(), rtol=0, atol=1e-12)


def _coupledScene(out=None, dtAuto=None, barrierStiffness=1e4):
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    cube = sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.08, 0.05, 0.05], "hi": [0.10, 0.09, 0.09], "ppc": 8,
                                        "velocity": [3, 0, 0]}], gravity=(0, 0, -9.81), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: {"friction": 0.3, "tangentialDamping": 0.2,
                                                              "barrierStiffness": barrierStiffness}},
                                    output=out, outputEvery=1e-4 if out else None, verbose=False, dtAuto=dtAuto)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-5
    return coupled, cube


@pytest.mark.parametrize("dtAuto, kc, before", [(None, 1e4, 250), (0.2, 1e6, 100), (0.5, 1e8, 91)],
                         ids=["fixed dt", "dtAuto", "dtAuto at first touch"])
def test_coupled_checkpoint_continues_bit_for_bit(tmp_path, dtAuto, kc, before):
    # With dtAuto (and a flow-block barrier stiff enough for the contact step to set O.dt) the
    # restored engine keeps the control, and its first step takes the O.dt the unbroken run
    # took, from the contact step saved with the checkpoint (at step 100 the blob is on the
    # block and the contact step sets O.dt) or, at k_c 1e8 N/m, from the particles' approach
    # step (at step 91 the blob's face is closing on the barrier: that step sets O.dt, below
    # both the critical step and the growth cap).
    out = str(tmp_path / "out")
    coupled, cube = _coupledScene(out, dtAuto, kc)
    mpmsdem.run(before, coupled)
    if dtAuto is None:
        assert coupled.contactCount(cube) > 10      # the blob is on the block: histories matter
        assert coupled.energies()["friction"] > 0
    elif kc < 1e8:  # the contact step, not the MPM one, sets the next step
        assert coupled.contactCount(cube) > 10
        assert coupled.contactTimeStep < coupled.mpm.stableTimeStep()
    else:
        assert coupled.contactCount(cube) == 0
        assert coupled.particleApproachStep < min(0.5 * coupled.criticalTimeStep(), 1.01 * O.dt)
    ck = mpmsdem.saveCheckpoint(str(tmp_path / "ck"), coupled)
    mpmsdem.run(150, coupled)
    ref = {"x": coupled.mpm.particles()["x"].copy(), "v": coupled.mpm.particles()["v"].copy(),
           "body": [*O.bodies[cube].state.pos, *O.bodies[cube].state.ori, *O.bodies[cube].state.angVel],
           "friction": coupled.energies()["friction"], "time": O.time, "first": coupled.firstContact(cube)}
    with h5py.File(tmp_path / "out" / "coupled.h5", "r", locking=False) as f:
        refSeries = {k: f["series/" + k][:] for k in f["series"]}
    forget(coupled, coupled.sdem, coupled.mpm)
    coupled2 = mpmsdem.loadCheckpoint(ck, output=out, outputEvery=1e-4, verbose=False)
    assert O.engines[1] is coupled2.runner
    mpmsdem.run(150, coupled2)
    np.testing.assert_array_equal(coupled2.mpm.particles()["x"], ref["x"])
    np.testing.assert_array_equal(coupled2.mpm.particles()["v"], ref["v"])
    assert [*O.bodies[cube].state.pos, *O.bodies[cube].state.ori, *O.bodies[cube].state.angVel] == ref["body"]
    assert coupled2.energies()["friction"] == ref["friction"]
    assert coupled2.dtAuto == dtAuto and O.time == ref["time"]
    with h5py.File(tmp_path / "out" / "coupled.h5", "r", locking=False) as f:  # records after the checkpoint replaced, once
        for k, v in refSeries.items():
            np.testing.assert_array_equal(f["series/" + k][:], v, err_msg=k)
    # the first contact kept, or (the cube not touched yet at step 91) made at the same step
    assert math.isfinite(ref["first"]) and coupled2.firstContact(cube) == ref["first"]
    # from a checkpoint written before the first contacts were kept: a cube the flow had touched
    # (its impulse says so) keeps none; one not touched yet gets it at the same step
    path = os.path.join(ck, "coupled.coupled.json")
    with open(path) as f:
        data = json.load(f)
    del data["firstContact"]
    with open(path, "w") as f:
        json.dump(data, f)
    forget(coupled2, coupled2.sdem, coupled2.mpm)
    coupled3 = mpmsdem.loadCheckpoint(ck, verbose=False)
    mpmsdem.run(150, coupled3)
    touched = before != 91
    assert math.isnan(coupled3.firstContact(cube)) if touched else coupled3.firstContact(cube) == ref["first"]


@pytest.mark.parametrize("before", [0, 120], ids=["checkpoint before the first step", "after 120 steps"])
def test_a_coupled_h5_damaged_by_a_kill_is_replaced_on_restore(tmp_path, before):
    """A kill in the middle of an HDF5 flush can leave coupled.h5 unreadable (emulated: a run in
    a process of its own that ends without closing anything, then its file's first half
    overwritten). Restoring puts back the file as the checkpoint saw it (coupled.h5.restart)
    or, for a checkpoint taken before the first step, when no coupled.h5 existed yet, starts the
    file afresh; either way the continued run's records equal the unbroken run's."""
    import subprocess
    import sys
    out, ck = tmp_path / "out", tmp_path / "ck"
    killed = ("import os, sys\nsys.path.insert(0, %r)\nimport mpmsdem, test_outputs\n"
              "coupled, cube = test_outputs._coupledScene(%r)\nif %d: mpmsdem.run(%d, coupled)\n"
              "mpmsdem.saveCheckpoint(%r, coupled)\nmpmsdem.run(100, coupled)\nos._exit(0)\n"
              % (os.path.dirname(os.path.abspath(__file__)), str(out), before, before, str(ck)))
    import children
    subprocess.run([sys.executable, "-c", killed], check=True, capture_output=True, env=children.env())
    assert (out / "coupled.h5.restart").exists() == bool(before)
    h5 = out / "coupled.h5"
    with h5py.File(h5, "r", locking=False) as f:
        refSeries = {k: f["series/" + k][:] for k in f["series"]}
    assert len(refSeries["time"]) > 10
    with open(h5, "r+b") as f:
        f.write(b"\x5a" * (h5.stat().st_size // 2))
    with pytest.raises(OSError):
        h5py.File(h5, "r", locking=False)
    coupled = mpmsdem.loadCheckpoint(mpmsdem.lastCheckpoint(str(ck)), output=str(out), outputEvery=1e-4, verbose=False)
    mpmsdem.run(100, coupled)
    with h5py.File(h5, "r", locking=False) as f:
        assert set(f["series"]) == set(refSeries)
        for k, v in refSeries.items():
            np.testing.assert_array_equal(f["series/" + k][:], v, err_msg=k)


def test_a_half_written_coupled_checkpoint_is_refused(tmp_path):
    coupled, cube = _coupledScene()
    mpmsdem.run(20, coupled)
    prefix = str(tmp_path / "ck")
    O.save(prefix + ".yade.gz")
    coupled.save(prefix)
    mpmsdem.run(10, coupled)
    coupled.sdem.save(prefix + ".sdem.json")        # a save killed after its first file
    forget(coupled, coupled.sdem, coupled.mpm)
    O.load(prefix + ".yade.gz")
    with pytest.raises(ValueError, match="different times.*earlier checkpoint"):
        mpmsdem.CoupledEngine.restore(prefix, verbose=False)


def test_adding_a_body_while_a_per_body_output_is_written_is_refused_at_the_call(tmp_path):
    eng, cube, slab, m = cubeOnSlab(gap=0.001, output=str(tmp_path / "s"), outputEvery=0.01, verbose=False)
    mat = mpmsdem.material(density=1000)
    extra = eng.box((0.02,) * 3, 0.002, mat, pos=(0.3, 0, 0.1))   # before the first step: fine
    O.dt = 1e-4
    run(eng, 10)
    n = len(O.bodies)
    with pytest.raises(ValueError, match=r"box\(\): adding a body after the run started writing .*sdem.h5.*new "
                                         r"output folder"):
        eng.box((0.02,) * 3, 0.002, mat, pos=(0.6, 0, 0.1))
    assert len(O.bodies) == n and eng.ids == [slab, cube, extra]   # nothing half-added
    run(eng, 10)
    # the coupled engine's coupled.h5 is per block too
    forget(eng)
    coupled, cube = _coupledScene(str(tmp_path / "c"))
    mpmsdem.run(2, coupled)
    with pytest.raises(ValueError, match=r"polyhedron\(\): .*coupled.h5"):
        coupled.sdem.polyhedron([(0, 0, 0), (0.01, 0, 0), (0, 0.01, 0), (0, 0, 0.01)], 0.001, mat,
                                pos=(0.2, 0.07, 0.07))
    # without outputs, blocks may join a running coupled scene (tests/python/test_coupled_yade.py)
