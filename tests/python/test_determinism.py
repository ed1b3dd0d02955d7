"""Determinism: the same scene run in separate processes, on one or two OpenMP threads, writes
bit-identical outputs. Every parallel sum in the plugin is reduced in a fixed order (MPM
scatter by coloured blocks, MP–block shares per chunk in chunk order) so that a result never
depends on the thread count or the schedule; these tests hold that promise for an SDEM scene
with a convex hull and a non-convex mesh colliding with friction, and for a coupled scene of
a few hundred material points hitting a block.

Each scene runs in a child process (``python test_determinism.py sdem|coupled OUTDIR``): the
thread count of OpenMP is fixed when the process starts."""
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data")


def sdemScene(out):
    import mpmsdem
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    eng = mpmsdem.SdemEngine(output=out, outputEvery=2e-3, verbose=False)
    mat = mpmsdem.material(density=500.0, friction=0.4, barrierStiffness=1e4, normalDamping=0.3)
    eng.box((0.6, 0.6, 0.05), 0.005, mat, pos=(0, 0, -0.05), fixed=True)            # bed, top at z = 0
    eng.mesh(os.path.join(DATA, "l_prism.obj"), 0.005, mat, pos=(0, 0, 0.0505))     # non-convex, on the bed
    pts = [(-0.04, -0.03, 0), (0.05, -0.04, 0.01), (0.03, 0.05, -0.01), (-0.05, 0.04, 0.0),
           (0.0, 0.0, 0.06), (0.02, -0.01, 0.055), (-0.01, 0.02, -0.02)]
    from yade.minieigenHP import Quaternion, Vector3
    eng.polyhedron(pts, 0.004, mat, pos=(0.02, 0.03, 0.14), ori=Quaternion(Vector3(1, 1, 0).normalized(), 0.6))
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=(2.0, 0.5, -9.81), damping=0)]
    O.dt = 5e-5
    mpmsdem.run(2400, eng)
    return eng


def coupledScene(out):
    import mpmsdem
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]},
                            material={"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24,
                                      "mu_2": 0.65},
                            particles=[{"lo": [0.06, 0.05, 0.05], "hi": [0.10, 0.09, 0.09], "ppc": 8,
                                        "velocity": [2, 0, 0.3]}],
                            gravity=(0, 0, -9.81), output=os.path.join(out, "mpm"), outputEvery=2e-3, verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, output=out, outputEvery=5e-4, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-5
    mpmsdem.run(900, coupled)
    return coupled


def _child(kind, out):
    import mpmsdem  # noqa: F401  (finds YADE, as a user's script does: no YADE folder on PYTHONPATH here)
    from yade import O
    os.makedirs(out, exist_ok=True)
    eng = {"sdem": sdemScene, "coupled": coupledScene}[kind](out)
    sdem = eng if kind == "sdem" else eng.sdem
    final = {}
    for i in sdem.ids:
        s = O.bodies[i].state
        final["b%d" % i] = np.array([*s.pos, *s.ori, *s.vel, *s.angVel, *O.forces.f(i), *O.forces.t(i)])
    if kind == "coupled":
        p = eng.mpm.particles()
        for k in ("x", "v", "stress", "J"):
            final["mp_" + k] = p[k]
        final["contacts"] = np.array([eng.totalContacts])
    np.savez(os.path.join(out, "final.npz"), **final)


def _run(kind, out, threads):
    import children
    r = subprocess.run([sys.executable, os.path.abspath(__file__), kind, str(out)],
                       env=children.env(OMP_NUM_THREADS=threads), capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr


def _h5Arrays(path):
    h5py = pytest.importorskip("h5py")
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
        for name, g in f.get("snapshots", {}).items():  # snapshot files are external links
            for k, d in g.items():
                out["snapshots/%s/%s" % (name, k)] = d[()]
    return out


def _sameBits(a, b, what):
    assert a.keys() == b.keys(), what
    for k in a:
        x, y = np.asarray(a[k]), np.asarray(b[k])
        assert x.shape == y.shape and x.dtype == y.dtype, "%s: %s" % (what, k)
        assert x.tobytes() == y.tobytes(), "%s: %s differs (max |diff| %g)" % (
            what, k, float(np.max(np.abs(x.astype(float) - y.astype(float)))))


def _compare(runs, files):
    first = runs[0]
    for other in runs[1:]:
        for name in files:
            _sameBits(_h5Arrays(first / name), _h5Arrays(other / name), "%s vs %s, %s" % (first.name, other.name, name))
        with np.load(first / "final.npz") as a, np.load(other / "final.npz") as b:
            _sameBits(dict(a), dict(b), "%s vs %s, final state" % (first.name, other.name))


def test_sdem_hull_and_mesh_collision_is_bit_identical_across_processes_and_threads(tmp_path):
    runs = [tmp_path / "t1a", tmp_path / "t1b", tmp_path / "t2"]
    for out, threads in zip(runs, (1, 1, 2)):
        _run("sdem", out, threads)
    with np.load(runs[0] / "final.npz") as a:
        hull, prism = a["b2"], a["b1"]
    # the scene is not trivially at rest: the hull fell onto the prism and both move
    assert hull[2] < 0.13 and np.linalg.norm(hull[7:10]) > 1e-3 and np.linalg.norm(prism[7:10]) > 1e-3
    assert _h5Arrays(runs[0] / "sdem.h5")["series/contacts"].max() >= 2
    _compare(runs, ["sdem.h5"])


def test_coupled_blob_hitting_a_block_is_bit_identical_on_one_and_two_threads(tmp_path):
    runs = [tmp_path / "t1", tmp_path / "t2"]
    for out, threads in zip(runs, (1, 2)):
        _run("coupled", out, threads)
    series = _h5Arrays(runs[0] / "coupled.h5")
    assert series["series/contacts"].max() > 20          # the blob hit the block
    assert series["series/vel"][-1, 0] > 0.01            # and pushed it
    _compare(runs, ["coupled.h5", "mpm/mpm.h5"])


if __name__ == "__main__":
    _child(sys.argv[1], sys.argv[2])
