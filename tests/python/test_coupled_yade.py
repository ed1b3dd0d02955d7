"""MPM–SDEM coupling inside YADE (paper §2.3): momentum conservation through YADE's
NewtonIntegrator, a wall holding a granular layer against earth-pressure theory, outputs a
user reads (h5py, ParaView, yade.plot), clear errors for wrong set-ups."""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import mpmsdem
from mpmsdem import analysis
from yade import O, plot
from yade.wrapper import ForceResetter, NewtonIntegrator

from scenes import pushFreeBody

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def blob_and_cube(fixed=False, precision="double", **kw):
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    cube = sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07), fixed=fixed)
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.04, 0.05, 0.05], "hi": [0.08, 0.09, 0.09], "ppc": 8,
                                        "velocity": [1, 0, 0]}], gravity=(0, 0, 0), verbose=False,
                            precision=precision)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, verbose=False, **kw)
    return sdem, mpm, coupled, cube


def test_blob_hitting_a_free_block_conserves_momentum_through_yade():
    sdem, mpm, coupled, cube = blob_and_cube()
    v0 = np.array(O.bodies[cube].state.vel)
    p0, p1, hit = pushFreeBody(coupled, mpm, cube)
    assert hit > 4, "the blob never touched the block"
    assert O.bodies[cube].state.vel[0] > 0.1  # pushed downstream
    assert np.linalg.norm(p1 - p0) == pytest.approx(0, abs=1e-9 * np.linalg.norm(p0))
    # the flow is the free block's only load: its impulse is the block's momentum change
    J = np.array(coupled.impulse(cube))
    dp = O.bodies[cube].state.mass * (np.array(O.bodies[cube].state.vel) - v0)
    assert np.linalg.norm(J - dp) == pytest.approx(0, abs=1e-9 * np.linalg.norm(J))
    t = coupled.timings()
    assert t["steps"] == 3000 and t["coupling"] > 0 and t["mpm"] > 0


def test_a_blow_above_the_centroid_turns_the_block_by_its_angular_impulse(tmp_path):
    """A blob striking the upper half of a free cube (frictionless contacts, no gravity): the
    flow is the cube's only load, so its angular impulse about the centroid is the cube's angular
    momentum I ω (a cube's inertia is isotropic), to round-off; it turns the cube about +y (a push
    downstream above the centroid); coupled.h5 holds it (analysis.driverBlockSeries' Ly). Over
    the blow's first 2 ms the blob loads the upper half of the upstream face (horizontal pushes between the
    centroid and the top, 13 mm above it with the rounding) and the top edge (whose downward push
    turns the other way): its line of action crosses the centroid's vertical between the centroid
    and the top. (Later the blob runs over the top face downstream of the centroid, whose downward
    push turns the cube the same way as the upstream one: the crossing then lies above the top.)"""
    out = str(tmp_path / "run")
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.0)
    cube = sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 16], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.04, 0.05, 0.07], "hi": [0.08, 0.09, 0.11], "ppc": 8,
                                        "velocity": [1, 0, 0]}], gravity=(0, 0, 0), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.0}, verbose=False, output=out, outputEvery=0.002)
    _, _, hit = pushFreeBody(coupled, mpm, cube)
    assert hit > 4, "the blob never touched the block"
    b = O.bodies[cube].state
    L, Iw = np.array(coupled.angularImpulse(cube)), b.inertia[0] * np.array(b.angVel)
    assert b.inertia[0] == pytest.approx(b.inertia[1], rel=1e-12) == pytest.approx(b.inertia[2], rel=1e-12)
    assert np.linalg.norm(L - Iw) == pytest.approx(0, abs=1e-9 * np.linalg.norm(L))
    assert L[1] > 0 and abs(L[0]) < 1e-3 * L[1] and abs(L[2]) < 1e-3 * L[1]
    s, scene = analysis.driverBlockSeries(out)
    assert scene is None and s["Ly"][-1] == pytest.approx(L[1], rel=1e-12) and s["Ly"][0] == 0
    action = analysis.blowLineOfAction(s)
    print("line of action above the centroid: %s" % {k: "%.2f mm" % (1e3 * v) for k, v in action.items()})
    assert 0 < action["action_0_2ms"] < 0.013 and action["action_2_5ms"] > 0


@pytest.mark.parametrize("precision", ["double", "float"])
def test_contacts_of_the_last_step_make_the_block_sums(precision):
    sdem, mpm, coupled, cube = blob_and_cube(precision=precision)
    wood = mpmsdem.material(density=500, friction=0.3)
    far = sdem.box((0.01,) * 3, 0.003, wood, pos=(0.2, 0.03, 0.03), fixed=True)  # out of the blob's reach
    coupled.setPair(wood, 0.3)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    assert len(coupled.contacts()["particle"]) == 0  # no step yet
    while coupled.contactCount(cube) < 10:
        mpmsdem.run(20, coupled)
        assert O.time < 0.05, "the blob never reached the block"
    c = coupled.contacts()
    F = np.linalg.norm(coupled.force(cube))
    tol = (1e-12 if precision == "double" else 1e-5) * F
    assert len(c["particle"]) == coupled.contactCount(cube) and set(c["block"]) == {cube}
    assert c["force"].sum(axis=0) == pytest.approx(np.array(coupled.force(cube)), abs=tol)
    edges = np.array([f != "face" for f in c["feature"]])
    assert c["force"][edges].sum(axis=0) == pytest.approx(np.array(coupled.edgeForce(cube)), abs=tol)
    # the blob moves along +x into the cube's upstream face: the points push it downstream
    assert np.all(c["normal"][:, 0] < 0) and c["force"][:, 0].sum() > 0
    assert np.all(c["point"][:, 0] < O.bodies[cube].state.pos[0] - 0.02 + 1e-3)
    assert len(set(c["particle"])) == len(c["particle"])  # one block: one contact per point
    mine, other = coupled.contacts(cube), coupled.contacts(far)
    assert len(other["particle"]) == 0 and np.array_equal(mine["particle"], c["particle"])
    with pytest.raises(ValueError):
        coupled.contacts(10 ** 6)


def test_fixed_wall_carries_the_thrust_of_a_granular_layer_at_rest():
    """A fixed SDEM wall holds a granular layer (frictionless base and sides, so every vertical
    section carries the same horizontal force): the wall's force equals the section force
    -∫σ_xx dA = -Σ σ_xx V / L of the layer's own stresses, and the thrust coefficient
    K = F / (½ρgh²w) lies between Rankine's active and passive values of the material's
    friction angle (any static stress state of a Mohr-Coulomb material does)."""
    dx, ppc, h, w, L = 0.01, 8, 0.06, 0.04, 0.1
    rp = (3 * dx ** 3 / ppc / (4 * math.pi)) ** (1 / 3)  # Eq 13
    Rw, hx = 0.004, 0.02
    sdem = mpmsdem.SdemEngine(verbose=False)
    steel = mpmsdem.material(density=7800, friction=0.0)
    xLast = L - dx / 4  # the wall's core face where the last column of points just touches it
    wall = sdem.box((hx, 0.04, 0.06), Rw, steel, pos=(xLast + rp + Rw + hx - Rw, w / 2, 0.05), fixed=True)
    mpm = mpmsdem.MpmEngine(grid={"dx": dx, "cells": [18, 8, 12], "origin": [-2 * dx, -2 * dx, -2 * dx]},
                            material=GLASS, particles=[{"lo": [0, 0, 0], "hi": [L, w, h], "ppc": ppc}],
                            walls={"-x": "free", "+x": "free", "-y": "free", "+y": "free", "-z": "free"},
                            gravity=(0, 0, -9.81), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={steel: {"friction": 0.0, "normalDamping": 0.3}},
                                    verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 0.5 * mpm.stableTimeStep()
    wallF, sectionF = [], []
    while O.time < 0.45:
        mpmsdem.run(50, coupled)
        if O.time > 0.35:
            p = mpm.particles()
            wallF.append(coupled.force(wall)[0])
            sectionF.append(-(p["stress"][:, 0] * p["J"] * p["volume0"]).sum() / L)
    F, S = float(np.mean(wallF)), float(np.mean(sectionF))
    assert F == pytest.approx(S, rel=0.03), "wall %.4f N against section force %.4f N" % (F, S)
    sinphi = math.sin(math.atan(GLASS["mu_s"]))
    Ka, Kp = (1 - sinphi) / (1 + sinphi), (1 + sinphi) / (1 - sinphi)
    K = F / (0.5 * GLASS["density"] * 9.81 * h ** 2 * w)
    assert Ka <= K <= Kp, "K = %.3f outside [Ka %.3f, Kp %.3f]" % (K, Ka, Kp)
    assert abs(coupled.force(wall)[2]) < 0.02 * F  # smooth wall: no shear
    assert O.bodies[wall].state.vel.norm() == 0
    # The contacts behind the sums: they add up to the wall's force and torque, each sits
    # between its point's centre and the wall (R_p0 - δ/2 from the centre, along the normal),
    # and the pressure grows with depth as in a layer at rest: the resultant acts a third of
    # the way up (a linear pressure profile; K does not vary much with depth).
    c = coupled.contacts()
    n = len(c["particle"])
    assert n == coupled.contactCount(wall) > 20 and set(c["block"]) == {wall}
    assert c["force"].sum(axis=0) == pytest.approx(np.array(coupled.force(wall)), abs=1e-12 * F)
    arm = c["point"] - np.array(O.bodies[wall].state.pos)
    assert np.cross(arm, c["force"]).sum(axis=0) == pytest.approx(np.array(coupled.torque(wall)), abs=1e-12 * F)
    faces = np.array([f == "face" for f in c["feature"]])
    assert c["force"][faces].sum(axis=0) == pytest.approx(np.array(coupled.faceForce(wall)), abs=1e-12 * F)
    centre = mpm.particles()["x"][c["particle"]]
    gap = ((centre - c["point"]) * c["normal"]).sum(axis=1)
    assert gap == pytest.approx(rp - c["overlap"] / 2, abs=1e-9)
    assert np.all(c["normal"][:, 0] < -0.99) and np.all(c["normalForce"] > 0)
    zc = (c["force"][:, 0] * c["point"][:, 2]).sum() / c["force"][:, 0].sum()
    assert 0.25 * h < zc < 0.42 * h, "resultant %.4f m above the base, h = %.3f m" % (zc, h)


def test_outputs_h5py_paraview_and_yade_plot(tmp_path):
    import h5py
    out = str(tmp_path / "run")
    sdem, mpm, coupled, cube = blob_and_cube(output=out, outputEvery=0.002, vtkEvery=0.01, plot=True)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    mpmsdem.run(3000, coupled)
    with h5py.File(os.path.join(out, "coupled.h5"), "r", locking=False) as f:
        s = f["series"]
        n = s["time"].shape[0]
        assert n == 16  # t = 0, then every 2 ms up to 0.03 s (the state the run ended with)
        assert s["time"][0] == 0 and s["time"][-1] == pytest.approx(0.03, abs=1e-12)
        for name in ("pos", "vel", "rotation", "flow_force", "face_force", "edge_force", "flow_torque", "flow_impulse",
                     "flow_angular_impulse"):
            assert s[name].shape == (n, 3), name
        # the impulse between records is the block's momentum change over them (no other load)
        m = O.bodies[cube].state.mass
        np.testing.assert_allclose(np.diff(s["flow_impulse"][:], axis=0), m * np.diff(s["vel"][:], axis=0), rtol=0,
                                   atol=1e-9 * np.abs(s["flow_impulse"][:]).max())
        assert s["flow_impulse"][0].tolist() == [0, 0, 0] and s["flow_impulse"][-1, 0] > 0
        assert s["contacts"].shape == (n, 1)
        # the first contact: the start of a step within the record interval before the first
        # record with an impulse, NaN in the records before it, the same in every one after
        first, k = s["flow_first_contact"][:, 0], int(np.nonzero(s["flow_impulse"][:, 0])[0][0])
        fc = coupled.firstContact(cube)
        assert s["time"][k - 1] <= fc < s["time"][k]
        assert np.isnan(first[:k]).all() and (first[k:] == fc).all()
        assert fc == pytest.approx(round(fc / O.dt) * O.dt, abs=1e-12)  # a step's start
        # F_t = F_f + F_e at every record (paper §3.2.3)
        np.testing.assert_allclose(s["flow_force"][:], s["face_force"][:] + s["edge_force"][:], rtol=0, atol=1e-12)
        assert s["flow_force"][:, 0].max() > 0  # pushed downstream at some record
        # energy bookkeeping: flow kinetic energy goes into the block and into dissipation
        e0 = s["flow_kinetic"][0] + s["block_kinetic"][0]
        e1 = s["flow_kinetic"][-1] + s["block_kinetic"][-1]
        assert e1 < e0
        assert s["block_kinetic"][-1] > 0
    root = ET.parse(os.path.join(out, "scene.pvd")).getroot()
    parts = [int(d.get("part")) for d in root.iter("DataSet")]
    assert parts.count(0) == parts.count(1) == parts.count(2) == 4
    for d in root.iter("DataSet"):
        assert os.path.getsize(os.path.join(out, d.get("file"))) > 0
    # the contacts of the last file are those of the run's last step (contacts())
    last = [d.get("file") for d in root.iter("DataSet") if d.get("part") == "2"][-1]
    text = open(os.path.join(out, last), "rb").read()
    assert b'NumberOfPoints="%d"' % len(coupled.contacts()["particle"]) in text
    assert len(plot.data["t"]) == 16
    assert max(plot.data["Ft_%d" % cube]) > 0


def test_wrong_engine_lists_and_missing_pairs_are_refused():
    sdem, mpm, coupled, cube = blob_and_cube()
    O.dt = 1e-5
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, 0), damping=0), coupled.runner]
    with pytest.raises(RuntimeError, match="ForceResetter.*coupled.runner.*NewtonIntegrator"):
        mpmsdem.run(1, coupled)
    O.reset()
    sdem, mpm, coupled, cube = blob_and_cube()
    O.engines = [ForceResetter(), sdem.runner, coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    with pytest.raises(RuntimeError, match="steps both"):
        mpmsdem.run(1, coupled)
    O.reset()
    sdem, mpm, coupled, cube = blob_and_cube()
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    with pytest.raises(RuntimeError, match="gravity"):
        mpmsdem.run(1, coupled)
    O.reset()
    sdem, mpm, coupled, cube = blob_and_cube()
    other = mpmsdem.material(density=500)
    sdem.box((0.01,) * 3, 0.002, other, pos=(0.2, 0.07, 0.07))
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    with pytest.raises(RuntimeError, match="coupling pair for SDEM material 1"):
        mpmsdem.run(1, coupled)
    with pytest.raises(ValueError, match="pairs"):
        mpmsdem.CoupledEngine(sdem, mpm, pairs={})
    with pytest.raises(ValueError, match="unknown key"):
        mpmsdem.CoupledEngine(sdem, mpm, pairs={other: {"frction": 0.2}})
    with pytest.raises(ValueError, match="coupling friction"):
        mpmsdem.CoupledEngine(sdem, mpm, pairs={other: -0.1})


def test_particles_seeded_inside_a_block_are_refused_at_the_first_step():
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000)
    cube = sdem.box((0.02,) * 3, 0.003, mat, pos=(0.06, 0.07, 0.07))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.04, 0.05, 0.05], "hi": [0.08, 0.09, 0.09], "ppc": 8}],
                            gravity=(0, 0, 0), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    with pytest.raises(RuntimeError, match="reached the core of block %d" % cube):
        mpmsdem.run(1, coupled)


def test_flow_at_station_and_froude_numbers_by_hand():
    x = np.array([[0.50, 0, 0.01], [0.505, 0, 0.03], [0.51, 0, 0.05], [0.49, 0, 0.02], [0.60, 0, 0.2]])
    v = np.array([[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0], [2.0, 0, 0], [9.0, 0, 0]])
    m = np.array([1.0, 1.0, 2.0, 1.0, 1.0])
    h, vf = analysis.flowAtStation({"x": x, "v": v, "mass": m}, 0.5, 0.011, bedZ=0.0)
    assert h == pytest.approx(0.05, abs=1e-15)
    assert vf == pytest.approx((1 + 2 + 6 + 2) / 5.0, abs=1e-15)
    probe = analysis.FlowProbe(0.5, 0.011, L0=0.2, window=0.1)
    probe.sample(0.0, {"x": x + [1, 0, 0], "v": v, "mass": m})  # front not there yet
    probe.sample(0.1, {"x": x, "v": v, "mass": m})
    r = probe.result()
    assert r["arrival"] == 0.1
    assert r["Fr"] == pytest.approx(2.2 / math.sqrt(9.81 * 0.05), rel=1e-12)
    assert r["Fr1"] == pytest.approx(2.2 / math.sqrt(9.81 * 0.2), rel=1e-12)


def test_check_against_reference_stores_then_flags_drift_both_ways(tmp_path):
    ref = str(tmp_path / "ref" / "scene.json")
    assert analysis.checkAgainstReference({"travel": 0.2, "peak": 5.0, "n": 7}, ref, {"travel": 0.1, "peak": 0.2},
                                          regenerate=True, stored=("travel", "peak", "n")) == []
    assert analysis.checkAgainstReference({"travel": 0.219, "peak": 4.01}, ref, {"travel": 0.1, "peak": 0.2}) == []
    high = analysis.checkAgainstReference({"travel": 0.221, "peak": 5.0}, ref, {"travel": 0.1, "peak": 0.2})
    low = analysis.checkAgainstReference({"travel": 0.2, "peak": 3.99}, ref, {"travel": 0.1, "peak": 0.2})
    assert len(high) == 1 and high[0].startswith("travel = 0.2210 drifted 10.5 %")
    assert len(low) == 1 and low[0].startswith("peak = 3.9900 drifted 20.2 %")


def test_flume_splits_the_flows_load_on_a_held_smooth_cube_by_face():
    # A smooth 4 cm cube (flow-block friction 0) glued to the bed of a coarse flume: every face
    # contact pushes along its face's normal, so the downstream force through the faces (F_f)
    # is the upstream face's load minus the downstream face's at every sample; the front loads
    # the upstream face first.
    from mpmsdem.flume import Block, Flume
    scene = Flume(length=0.6, width=0.1, columnLength=0.1, columnHeight=0.1, dx=0.02, ppc=8, verbose=False,
                  blocks=[Block(half=(0.02, 0.02, 0.02), x=0.14, flowFriction=0.0, blockedDOFs="xyzXYZ")])
    scene.run(0.3, sampleEvery=0.005)
    s = scene.series(0)
    f = s["faces"]
    assert set(f) == {"-x", "+x", "-y", "+y", "-z", "+z", "edges"}
    assert f["-x"].max() > 1.0, "the flow never reached the cube"
    np.testing.assert_allclose(f["-x"] - f["+x"], s["Ff"], rtol=0, atol=1e-12 * f["-x"].max())
    first = np.nonzero(f["-x"] + f["+z"] + f["edges"] > 0)[0][0]
    assert f["-x"][first] > 0 and f["+x"][first] == 0
    assert all(v.min() >= 0 for v in f.values())
    # the flow's front (its most downstream point): the column's last points (0.1 m - dx/4) at the
    # start; when the flow first loads the cube, within a point's reach of its upstream face (x 0.14
    # m less R_p0 = 6.2 mm of Eq 13 at dx 0.02 m, 8 per cell: 0.1338 m) and short of its centre
    # (0.16 m); and the flow's own at the end
    fr = s["flow_front"]
    print("front at the first sample %.4f m, at the first contact %.4f m, at the end %.4f m" % (fr[0], fr[first], fr[-1]))
    assert 0.094 < fr[0] < 0.1 and 0.1338 <= fr[first] < 0.16 and np.all(np.diff(fr[:first + 1]) >= 0)
    assert fr[-1] == scene.mpm.diagnostics()["front_x"]
