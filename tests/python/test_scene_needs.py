"""Inside YADE a step does only the work its scene needs, with the results of the full work:
bodies whose six DOFs are blocked count as fixed (their pairs with fixed bodies skip the
narrow phase) and move again when released; a coupled scene without material points moves
its blocks as the SDEM engine alone does; one without blocks moves its flow as the MPM engine
alone does."""
import numpy as np
import pytest

import mpmsdem
from mpmsdem import analysis
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
G = (0, 0, -9.81)
H, R, RHO, KC = 0.02, 0.003, 2000.0, 1e4
ROW = 6


def restingZ():
    """Centre height of a cube of outer half-size H at the overlap where its four face
    contacts with a slab (top face z = 0) carry its weight."""
    mass = RHO * mpmsdem.SpheroPolyhedron.box((H,) * 3, R).volume
    return H - analysis.equilibriumOverlap(mass * 9.81, 2 * R, KC, contacts=4)


def rowScene(row):
    """A fixed slab; a row of ROW cubes standing on it, each 0.1 mm into the slab and its
    neighbour (row = "fixed": fixed=True, "glued": blockedDOFs "xyzXYZ", None: no row); a
    cube resting on the slab away from the row and one sliding into the row's end at 0.1 m/s.
    Returns the engine, the material, the row's ids and the two free cubes' ids."""
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.4, barrierStiffness=KC, normalDamping=0.2)
    sdem.box((0.4, 0.3, 0.02), R, mat, pos=(0, 0, -0.02), fixed=True)
    ids = []
    if row:
        for k in range(ROW):
            i = sdem.box((H,) * 3, R, mat, pos=(-0.2 + k * (2 * H - 1e-4), -0.1, H - 1e-4), fixed=row == "fixed")
            if row == "glued":
                O.bodies[i].state.blockedDOFs = "xyzXYZ"
            ids.append(i)
    z = restingZ()
    rest = sdem.box((H,) * 3, R, mat, pos=(0.1, 0.1, z))
    xEnd = -0.2 + (ROW - 1) * (2 * H - 1e-4)
    pusher = sdem.box((H,) * 3, R, mat, pos=(xEnd + 2 * H + 1e-4, -0.1, z))
    O.bodies[pusher].state.vel = (-0.1, 0, 0)
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=G, damping=0)]
    O.dt = 1e-5
    return sdem, mat, ids, [rest, pusher]


def bodyState(ids):
    return np.array([[*O.bodies[i].state.pos, *O.bodies[i].state.ori, *O.bodies[i].state.vel,
                      *O.bodies[i].state.angVel] for i in ids])


def test_glued_blocks_count_as_fixed_and_skip_the_narrow_phase():
    steps = 3000
    runs = {}
    for row in ("fixed", "glued"):
        O.reset()
        sdem, _, ids, free = rowScene(row)
        touched = False
        for _ in range(30):
            mpmsdem.run(steps // 30, sdem)
            c = sdem.contacts()
            touched = touched or bool(((c["id1"] == ids[-1]) | (c["id2"] == ids[-1])).any())
        assert touched, "the pusher never reached the row"
        runs[row] = (sdem.narrowPhasePairs, bodyState(free + ids), O.forces.f(ids[0]))
    # the row's 2 ROW - 1 contacts with the slab and each other are never computed: only the free
    # cubes' pairs, the same number either way
    assert runs["glued"][0] == runs["fixed"][0]
    assert 2 * steps <= runs["fixed"][0] <= 3 * steps
    np.testing.assert_array_equal(runs["glued"][1], runs["fixed"][1])
    assert runs["glued"][2].norm() == 0  # no slab or neighbour force on a glued cube


def test_a_released_glued_block_moves_as_a_free_one():
    """A cube glued on the slab for 200 steps, then released, continues exactly as a cube that
    was free from the start (the glued one had not moved): the release is seen at the step it
    happens."""
    def cube(glued):
        O.reset()
        sdem = mpmsdem.SdemEngine(verbose=False)
        mat = mpmsdem.material(density=RHO, friction=0.4, barrierStiffness=KC)
        sdem.box((0.4, 0.3, 0.02), R, mat, pos=(0, 0, -0.02), fixed=True)
        c = sdem.box((H,) * 3, R, mat, pos=(0, 0, restingZ() - 1e-4))  # in contact, pushed up when free
        if glued:
            O.bodies[c].state.blockedDOFs = "xyzXYZ"
        O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=G, damping=0)]
        O.dt = 1e-5
        return sdem, c

    sdem, c = cube(glued=True)
    mpmsdem.run(200, sdem)
    assert sdem.narrowPhasePairs == 0
    O.bodies[c].state.blockedDOFs = ""
    mpmsdem.run(2000, sdem)
    released, pairs = bodyState([c]), sdem.narrowPhasePairs
    sdem, c = cube(glued=False)
    mpmsdem.run(2000, sdem)
    assert pairs == sdem.narrowPhasePairs == 2000
    assert abs(bodyState([c])[0, 2] - restingZ()) < 1e-4  # on the slab, not through it
    np.testing.assert_array_equal(released, bodyState([c]))


def emptyFlow():
    """An MpmEngine without particles (``particles=[]``): grid and walls only."""
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.02, "cells": [30, 20, 10], "origin": [-0.3, -0.2, -0.06]},
                            material=GLASS, particles=[], gravity=G, verbose=False)
    assert mpm.solver.numParticles == 0
    return mpm


def test_coupled_scene_without_particles_moves_its_blocks_as_sdem_alone():
    steps = 1500
    states = {}
    for coupled in (False, True):
        O.reset()
        sdem, mat, ids, free = rowScene("fixed")
        if coupled:
            mpm = emptyFlow()
            c = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, verbose=False)
            O.engines = [ForceResetter(), c.runner, NewtonIntegrator(gravity=G, damping=0)]
            mpmsdem.run(steps, c)
            assert mpm.solver.steps == steps and mpm.time == pytest.approx(O.time, rel=1e-12)
            assert all(c.force(i).norm() == 0 for i in free)
        else:
            mpmsdem.run(steps, sdem)
        states[coupled] = (bodyState(free), sdem.narrowPhasePairs)
    np.testing.assert_array_equal(states[True][0], states[False][0])
    assert states[True][1] == states[False][1]


def test_coupled_scene_without_blocks_moves_its_flow_as_mpm_alone():
    steps = 150
    flows = {}
    for coupled in (False, True):
        O.reset()
        mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 18], "origin": [0, 0, 0]}, material=GLASS,
                                particles=[{"lo": [0.04, 0.04, 0.03], "hi": [0.1, 0.08, 0.11], "ppc": 8}],
                                gravity=G, verbose=False)
        if coupled:
            sdem = mpmsdem.SdemEngine(verbose=False)
            c = mpmsdem.CoupledEngine(sdem, mpm, pairs={mpmsdem.material(density=2000): 0.3}, verbose=False)
            O.engines = [ForceResetter(), c.runner, NewtonIntegrator(gravity=G, damping=0)]
        else:
            c = mpm
            O.engines = [mpm.runner]
        O.dt = 0.5 * mpm.stableTimeStep()
        mpmsdem.run(steps, c)
        p = mpm.particles()
        flows[coupled] = (p["x"].copy(), p["v"].copy(), mpm.time)
        if coupled:
            assert c.totalContacts == 0
    for a, b in zip(flows[True], flows[False]):
        np.testing.assert_array_equal(a, b)


def test_a_block_stopped_with_dynamic_false_counts_as_fixed_until_released():
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.4, barrierStiffness=KC, normalDamping=0.2)
    sdem.box((0.4, 0.3, 0.02), R, mat, pos=(0, 0, -0.02), fixed=True)
    c = sdem.box((H,) * 3, R, mat, pos=(0, 0, restingZ()))
    O.bodies[c].state.vel = (0.05, 0, 0)  # sliding: moving bodies are not asked about every step
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=G, damping=0)]
    O.dt = 1e-5
    mpmsdem.run(100, sdem)
    assert sdem.narrowPhasePairs == 100
    O.bodies[c].dynamic = False  # stops it
    mpmsdem.run(100, sdem)
    assert sdem.narrowPhasePairs == 100
    z = O.bodies[c].state.pos[2]
    O.bodies[c].dynamic = True
    mpmsdem.run(100, sdem)
    assert sdem.narrowPhasePairs == 200
    assert abs(O.bodies[c].state.pos[2] - z) < 1e-4  # carried by the slab again
