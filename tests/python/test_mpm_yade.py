"""The MPM engine from a YADE script: an MPM-only scene, conservation, outputs readable with
h5py and ParaView files, clear errors."""
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import mpmsdem
from yade import O

MATERIAL = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def blob(**kw):
    return mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [20, 20, 40], "origin": [-0.1, -0.1, -0.2]},
                             material=MATERIAL, particles=[{"lo": [-0.03, -0.03, 0.0], "hi": [0.03, 0.03, 0.06],
                                                            "ppc": 8, "velocity": [0.5, 0, 0]}],
                             gravity=(0, 0, -9.81), **kw)


def test_free_fall_conserves_mass_and_gains_exactly_mg_t():
    mpm = blob()
    O.engines = [mpm.runner]
    O.dt = 0.5 * mpm.stableTimeStep()
    p0 = mpm.particles()
    n_steps = 400
    mpmsdem.run(n_steps, mpm)
    p1 = mpm.particles()
    M = p0["mass"].sum()
    assert p1["mass"].sum() == M  # mass carried by particles: exactly conserved
    assert len(p1["mass"]) == 6 * 6 * 6 * 8
    t = n_steps * O.dt
    dP = (p1["mass"][:, None] * p1["v"]).sum(axis=0) - (p0["mass"][:, None] * p0["v"]).sum(axis=0)
    expected = np.array([0.0, 0.0, -9.81 * M * t])
    assert np.allclose(dP, expected, rtol=0, atol=1e-10 * abs(expected[2]))
    # a free blob stays stress-free-ish and keeps its shape: centre of mass follows the parabola
    com0 = (p0["mass"][:, None] * p0["x"]).sum(axis=0) / M
    com1 = (p1["mass"][:, None] * p1["x"]).sum(axis=0) / M
    # x_com(t) = x0 + v0 t + g t^2/2, up to the O(dt) offset of the symplectic update
    assert abs(com1[0] - (com0[0] + 0.5 * t)) <= 1e-9 + 0.5 * O.dt
    assert abs(com1[2] - (com0[2] - 0.5 * 9.81 * t * t)) <= 9.81 * t * O.dt


def test_diagnostics_are_the_particle_sums_and_the_free_fall_energy_balance():
    """MpmEngine.diagnostics() (computed in C++, slice by slice) against numpy sums of the same
    particles; a free-falling blob gains M g^2 t^2 / 2 of kinetic energy and loses as much
    potential energy, to within the half-step offset of its positions (no stress work)."""
    mpm = blob()
    O.engines = [mpm.runner]
    O.dt = 0.5 * mpm.stableTimeStep()
    d0 = mpm.diagnostics()
    mpmsdem.run(200, mpm)
    d = mpm.diagnostics()
    p = mpm.particles()
    m, x, v = p["mass"], p["x"], p["v"]
    g = np.array([0, 0, -9.81])
    assert d["kinetic_energy"] == pytest.approx(0.5 * float((m * (v ** 2).sum(axis=1)).sum()), rel=1e-12)
    assert d["potential_energy"] == pytest.approx(-float((m * (x @ g)).sum()), rel=1e-12)
    assert np.allclose(d["centre_of_mass"], (m @ x) / m.sum(), rtol=0, atol=1e-14)
    assert d["front_x"] == x[:, 0].max() and d["height_z"] == x[:, 2].max()
    assert d["max_speed"] == pytest.approx(float(np.sqrt((v ** 2).sum(axis=1).max())), rel=1e-15)
    assert d["flowing_fraction"] == float((p["phase"] == 1).sum()) / len(m)
    assert mpm.kineticEnergy() == d["kinetic_energy"]
    # free fall: the kinetic energy gained is M g^2 t^2 / 2 (the blob's momentum grows by exactly
    # M g t), and the potential energy lost matches it to within the step's offset of the
    # positions (half a step of the fall, 0.5 % here)
    gain = d["kinetic_energy"] - d0["kinetic_energy"]
    assert gain == pytest.approx(0.5 * m.sum() * (9.81 * O.time) ** 2, rel=1e-9)
    lost = d0["potential_energy"] - d["potential_energy"]
    assert lost == pytest.approx(gain, rel=1e-2)


def test_outputs_are_readable_with_h5py_and_paraview(tmp_path):
    h5py = pytest.importorskip("h5py")
    out = tmp_path / "run"
    mpm = blob(output=str(out), outputEvery=0.01)
    O.engines = [mpm.runner]
    O.dt = 0.5 * mpm.stableTimeStep()
    n = int(0.035 / O.dt) + 1
    mpmsdem.run(n, mpm)
    # the writer is still open (a live run): read without HDF5 file locking, as the writer does
    with h5py.File(out / "mpm.h5", "r", locking=False) as f:
        t = f["series/time"][:]
        assert np.all(np.diff(t) > 0)
        snaps = sorted(f["snapshots"].keys())
        assert len(snaps) == 4  # t = 0 (first step), 0.01, 0.02, 0.03
        last = f["snapshots"][snaps[-1]]
        x = last["x"][:]
        assert x.shape == (1728, 3)
        assert abs(last.attrs["time"] - 0.03) <= O.dt
        # the snapshot holds the state at its time: centre of mass drifted by v0 t along x
        p = mpm.particles()
        drift = x[:, 0].mean() - f["snapshots"][snaps[0]]["x"][:, 0].mean()
        assert abs(drift - 0.5 * (last.attrs["time"] - f["snapshots"][snaps[0]].attrs["time"])) <= 1e-9
        assert x[:, 2].min() >= -0.2
    root = ET.parse(out / "particles.pvd").getroot()
    files = [d.get("file") for d in root.iter("DataSet")]
    assert len(files) == 4 and all(os.path.exists(out / f) for f in files)
    assert p["x"].shape == (1728, 3)


def test_scene_errors_name_the_parameter():
    with pytest.raises(ValueError, match="dxx"):
        mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [10, 10, 10], "dxx": 1}, material=MATERIAL,
                          particles=[{"lo": [0.03, 0.03, 0.03], "hi": [0.05, 0.05, 0.05]}])
    with pytest.raises(ValueError, match="poisson_ratio"):
        mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [10, 10, 10]}, material=dict(MATERIAL, poisson_ratio=0.5),
                          particles=[{"lo": [0.03, 0.03, 0.03], "hi": [0.05, 0.05, 0.05]}])
    with pytest.raises(ValueError, match="particles"):
        mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [10, 10, 10]}, material=MATERIAL,
                          particles=[{"lo": [0.0, 0.0, 0.0], "hi": [0.05, 0.05, 0.05]}])  # inside the wall layer
    mpm = blob()
    O.engines = [mpm.runner]
    O.dt = 10 * mpm.stableTimeStep()
    with pytest.raises(RuntimeError, match="dt = .* s: must be in"):
        mpmsdem.run(2, mpm)


def test_checkpoint_restart_reproduces_the_run_exactly(tmp_path):
    # A collapsing column stepped 300 times in one go, and 150 + checkpoint + restore + 150:
    # the state (positions, velocities, stresses) and the clock must be identical.
    def column():
        return mpmsdem.MpmEngine(grid={"dx": 0.02, "cells": [20, 6, 14], "origin": [-0.04, -0.04, -0.04]},
                                 material={"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3,
                                           "mu_s": 0.38, "mu_2": 0.64},
                                 particles=[{"lo": [0, 0, 0], "hi": [0.1, 0.04, 0.2], "ppc": 8}], walls={"-z": 0.4})
    dt = 2e-4
    ref = column()
    for _ in range(300):
        ref.step(dt)
    a = column()
    for _ in range(150):
        a.step(dt)
    a.save(tmp_path / "mpm.ckpt.h5")
    b = mpmsdem.MpmEngine.restore(tmp_path / "mpm.ckpt.h5")
    assert b.time == a.time and b.solver.steps == 150
    for _ in range(150):
        b.step(dt)
    p, q = ref.particles(), b.particles()
    for k in ("x", "v", "stress", "J", "phase"):
        assert np.array_equal(p[k], q[k]), k
    assert b.time == ref.time and b.solver.steps == 300
    assert np.abs(p["x"] - column().particles()["x"]).max() > 1e-3  # it did move


def test_driver_restart_appends_and_reproduces(tmp_path):
    import json
    import subprocess
    import mpmsdem.driver
    exe = mpmsdem.driver.executable()
    h5py = pytest.importorskip("h5py")
    scene = {"grid": {"dx": 0.02, "cells": [20, 6, 14], "origin": [-0.04, -0.04, -0.04]}, "walls": {"-z": 0.4},
             "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
             "particles": [{"lo": [0, 0, 0], "hi": [0.1, 0.04, 0.2], "ppc": 8}],
             "run": {"duration": 0.1, "dt": 2e-4, "output_every": 0.02, "series_every": 0.004, "vtk": "none"}}
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    run = lambda *args: subprocess.run([exe, str(path), *args], check=True, capture_output=True)  # noqa: E731
    run("--out", str(tmp_path / "one"), "--steps", "400")
    run("--out", str(tmp_path / "two"), "--steps", "200")
    run("--out", str(tmp_path / "two"), "--steps", "200", "--restart")
    with h5py.File(tmp_path / "one" / "mpm.h5", "r") as f1, h5py.File(tmp_path / "two" / "mpm.h5", "r") as f2:
        assert sorted(f1["snapshots"]) == sorted(f2["snapshots"])  # 0, 0.02, ..., 0.08 s: nothing twice
        last = sorted(f1["snapshots"])[-1]
        assert f2["snapshots"][last].attrs["step"] == 400
        for k in ("x", "v", "stress"):
            assert np.array_equal(f1["snapshots"][last][k][:], f2["snapshots"][last][k][:]), k
        assert np.array_equal(f1["series/time"][:], f2["series/time"][:])
    # a run killed between snapshots: its series goes past the last snapshot (emulated by
    # deleting the final snapshot of a 290-step run, from mpm.h5 and from the copy a restart
    # goes back to); the restart drops those rows
    run("--out", str(tmp_path / "three"), "--steps", "290")
    for name in ("mpm.h5", "mpm.h5.restart"):
        with h5py.File(tmp_path / "three" / name, "r+") as f:
            last = sorted(f["snapshots"])[-1]
            assert f["snapshots"][last].attrs["step"] == 290
            del f["snapshots"][last]
            assert f["series/time"][-1] > 0.055  # rows at 0.044 ... 0.056 s, past the 0.04 s snapshot
    run("--out", str(tmp_path / "three"), "--steps", "200", "--restart")  # from step 200, t = 0.04 s
    with h5py.File(tmp_path / "one" / "mpm.h5", "r") as f1, h5py.File(tmp_path / "three" / "mpm.h5", "r") as f3:
        assert np.array_equal(f1["series/time"][:], f3["series/time"][:])
        assert np.array_equal(f1["series/kinetic_energy"][:], f3["series/kinetic_energy"][:])
    # a run killed while HDF5 rewrote mpm.h5's bookkeeping: the file no longer opens (emulated
    # by overwriting its first half); the restart goes back to mpm.h5.restart, the file as of
    # the last snapshot (step 290), and ends where the unbroken run ends, to the last bit
    run("--out", str(tmp_path / "four"), "--steps", "290")
    h5 = tmp_path / "four" / "mpm.h5"
    with open(h5, "r+b") as f:
        f.write(b"\x5a" * (h5.stat().st_size // 2))
    with pytest.raises(OSError):
        h5py.File(h5, "r")
    run("--out", str(tmp_path / "four"), "--steps", "110", "--restart")
    with h5py.File(tmp_path / "one" / "mpm.h5", "r") as f1, h5py.File(h5, "r") as f4:
        for k in ("time", "kinetic_energy", "front_x", "centre_of_mass"):
            assert np.array_equal(f1["series"][k][:], f4["series"][k][:]), k
        # one snapshot more than the unbroken run's: the end of the 290-step run, at 0.058 s
        assert [f4["snapshots"][k].attrs["step"] for k in sorted(f4["snapshots"])] == [0, 100, 200, 290, 300, 400]
        a, b = f1["snapshots"][sorted(f1["snapshots"])[-1]], f4["snapshots"][sorted(f4["snapshots"])[-1]]
        for k in ("x", "v", "stress", "J"):
            assert np.array_equal(a[k][:], b[k][:]), k
    # without a restart point (a run stopped before its first snapshot was whole): refused
    (tmp_path / "four" / "mpm.h5.restart").unlink()
    r = subprocess.run([exe, str(path), "--out", str(tmp_path / "four"), "--restart"], capture_output=True, text=True)
    assert r.returncode == 2 and "restart point" in r.stderr, r.stderr


SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "scenes")


@pytest.mark.parametrize("name", sorted(n for n in os.listdir(SCENES) if n.endswith(".json")))
def test_shipped_scenes_load_and_step(name):
    # Every example scene parses, seeds the particle count and mass its boxes imply, and steps.
    import json
    path = os.path.join(SCENES, name)
    scene = json.load(open(path))
    solver = mpmsdem._mpmsdem.MpmSolver(open(path).read())
    dx = scene["grid"]["dx"]
    count, mass = 0, 0.0
    for b in scene["particles"]:
        cells = np.prod([round((h - l) / dx) for l, h in zip(b["lo"], b["hi"])])
        ppc = b.get("ppc", 8)
        count += cells * (ppc if isinstance(ppc, int) else np.prod(ppc))
        mass += scene["material"]["density"] * cells * dx ** 3
    assert solver.numParticles == count
    p0 = solver.particles()
    assert abs(p0["mass"].sum() - mass) <= 1e-12 * mass
    dt = 0.5 * solver.stableTimeStep()
    solver.run(3, dt)
    assert solver.steps == 3 and abs(solver.time - 3 * dt) <= 1e-15
    assert solver.particles()["mass"].sum() == p0["mass"].sum()


def test_cuda_backend_without_a_gpu_is_a_clear_error():
    if mpmsdem.cudaAvailable():
        pytest.skip("a CUDA device is present: the CUDA backend is tested by test_mpm (CpuAndCudaAgree)")
    with pytest.raises(RuntimeError, match="no CUDA device|without the CUDA backend|CUDA"):
        mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [10, 10, 10]}, material=MATERIAL,
                          particles=[{"lo": [0.03, 0.03, 0.03], "hi": [0.05, 0.05, 0.05]}],
                          backend="cuda", precision="float")


def test_float_on_the_cpu_backend_falls_freely_to_float_round_off():
    mpm = blob(precision="float")
    assert mpm.solver.name == "cpu-float"
    O.engines = [mpm.runner]
    O.dt = 0.5 * mpm.stableTimeStep()
    p0 = mpm.particles()
    assert np.array_equal(p0["x"].astype(np.float32), p0["x"])  # held in float
    n_steps = 100
    mpmsdem.run(n_steps, mpm)
    p1 = mpm.particles()
    M = p0["mass"].sum()
    assert p1["mass"].sum() == M
    t = n_steps * O.dt
    dP = (p1["mass"][:, None] * p1["v"]).sum(axis=0) - (p0["mass"][:, None] * p0["v"]).sum(axis=0)
    # float round-off: each step leaves every particle velocity with a rounding of at most about
    # eps/2 of |v| <= 0.55 m/s, of the same sign for all in the worst case (the blob moves as one):
    # |dP - M g t| <= steps (eps/2) M vmax, 6e-5 of M g t (measured 1.3e-6)
    eps = float(np.finfo(np.float32).eps)
    vmax = np.sqrt((p1["v"] ** 2).sum(axis=1)).max()
    tol = n_steps * 0.5 * eps * M * vmax
    assert np.allclose(dP, [0.0, 0.0, -9.81 * M * t], rtol=0, atol=tol)


def test_outputs_record_the_flip_blend_and_a_restart_across_blends_is_refused(tmp_path):
    # The damping per second is a model quantity: every mpm.h5 names it, and a run written with
    # another blend (here: a file from before it was recorded) is not continued.
    import json
    import math
    import subprocess
    import mpmsdem.driver
    exe = mpmsdem.driver.executable()
    h5py = pytest.importorskip("h5py")
    scene = {"grid": {"dx": 0.02, "cells": [20, 6, 14], "origin": [-0.04, -0.04, -0.04]}, "walls": {"-z": 0.4},
             "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
             "particles": [{"lo": [0, 0, 0], "hi": [0.1, 0.04, 0.2], "ppc": 1}],
             "run": {"duration": 0.1, "dt": 2e-4, "output_every": 0.02, "vtk": "none"}}
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    out = tmp_path / "out"
    r = subprocess.run([exe, str(path), "--out", str(out), "--steps", "20"], capture_output=True, text=True)
    # the default: a PIC viscosity of 0.005 m^2/s, 4 nu/dx^2 = 50 /s at this dx of 0.02 m
    assert r.returncode == 0 and "FLIP/PIC blend PIC viscosity 0.005 m^2/s, share 4 nu dt/dx^2 (PIC damping 50 /s at dx 0.02 m)" in r.stdout, \
        r.stdout
    for name in ("mpm.h5", "mpm.h5.restart"):  # the file and the copy a restart goes back to
        with h5py.File(out / name, "r+") as f:
            assert f.attrs["flip_viscosity"] == 0.005 and f.attrs["flip_damping_rate"] == pytest.approx(50, rel=1e-12)
            assert math.isnan(f.attrs["flip_alpha"]) and math.isnan(f.attrs["flip_reference_dt"])
            del f.attrs["flip_blend"]
    r = subprocess.run([exe, str(path), "--out", str(out), "--steps", "20", "--restart"], capture_output=True, text=True)
    assert r.returncode == 2 and "not recorded" in r.stderr and "50 /s" in r.stderr, r.stderr
    # a run of the blend that kept exp(-4 nu dt/dx^2) of FLIP recorded these words: it is another flow
    for name in ("mpm.h5", "mpm.h5.restart"):
        with h5py.File(out / name, "r+") as f:
            f.attrs["flip_blend"] = "PIC viscosity 0.005 m^2/s (PIC damping 50 /s at dx 0.02 m)"
    r = subprocess.run([exe, str(path), "--out", str(out), "--steps", "20", "--restart"], capture_output=True, text=True)
    assert r.returncode == 2 and "blended FLIP/PIC as PIC viscosity 0.005 m^2/s (PIC damping" in r.stderr, r.stderr
    assert "this scene as PIC viscosity 0.005 m^2/s, share 4 nu dt/dx^2" in r.stderr, r.stderr
    # the YADE engine records the same; the paper's blend reads 2010 /s at its dx of 0.01 m, and
    # as a viscosity it is the same at any dx
    eng = mpmsdem.MpmEngine(grid=scene["grid"], material=scene["material"], particles=scene["particles"],
                            flipReferenceDt=mpmsdem.mpm.PAPER_STEP, output=str(tmp_path / "yade"), outputEvery=0.01,
                            verbose=False)
    assert eng.solver.flipBlend == "alpha 0.99 per 5e-06 s (PIC damping 2010 /s, PIC viscosity 0.201007 m^2/s at dx 0.02 m)"
    assert eng.solver.flipDampingRate(1e-4) == pytest.approx(-math.log(0.99) / 5e-6, rel=1e-12)
    with h5py.File(tmp_path / "yade" / "mpm.h5", "r", locking=False) as f:  # the engine still writes it
        assert f.attrs["flip_blend"] == eng.solver.flipBlend and f.attrs["flip_damping_rate"] == pytest.approx(2010.07, abs=0.01)
        assert f.attrs["flip_viscosity"] == pytest.approx(2010.07 * 0.02 ** 2 / 4, abs=1e-5)
    eng = mpmsdem.MpmEngine(grid=scene["grid"], material=scene["material"], particles=scene["particles"],
                            flipViscosity=mpmsdem.mpm.PAPER_VISCOSITY, verbose=False)
    # the paper's share 0.01 per 5e-6 s at dx 0.01 m: 0.05 m^2/s, 2000 /s there, a quarter at dx 0.02 m
    assert eng.solver.flipViscosity(1e-4) == pytest.approx(0.05, rel=1e-14)
    assert eng.solver.flipDampingRate(1e-4) == pytest.approx(2000.0 / 4, rel=1e-14)
    with pytest.raises(ValueError, match="flip_reference_dt"):
        mpmsdem.MpmEngine(grid=scene["grid"], material=scene["material"], particles=scene["particles"],
                          flipReferenceDt=0, verbose=False)
    with pytest.raises(ValueError, match="flip_alpha.*flip_reference_dt"):
        mpmsdem.MpmEngine(grid=scene["grid"], material=scene["material"], particles=scene["particles"],
                          flipAlpha=0.95, verbose=False)
