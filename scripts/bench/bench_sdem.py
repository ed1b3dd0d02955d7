#!/usr/bin/env python3
"""SDEM benchmark: mpmsdem's sphero-polyhedra against YADE's own LevelSet, Polyhedra and sphere clumps.

Scenes (all four methods run in this one process, so their ratios are comparable):

1. Head-on collision of two equal cubes (paper §4.2): side h = 0.1 m and 0.3 m, centroids
   0.4 m apart, +-1 m/s, frictionless, dt = 5e-6 s, run through impact and separation.
   Reports µs/step, speed after impact (exact answer 1 m/s), transverse and angular
   velocity (exact answer 0) and the relative change of kinetic energy (exact answer 0).
2. Three equal cubes (h = 0.1 m) stacked on a fixed floor under gravity, settled with
   NewtonIntegrator damping. Reports µs/step and the errors against the static answer:
   floor force against the total weight, each contact's force against the weight above it,
   centroid heights against the start heights minus the equilibrium overlaps, lateral drift
   and tilt (exact answer 0).
3. A pile of cubes (h = 0.1 m, --pile-count, default 100; staggered layers, random tilts)
   dropped into a fixed box (floor + 4 walls) under gravity. Reports µs/step, number of
   contacts, final kinetic energy, mean and top centroid height.

Sphere clumps: a cube is n^3 touching spheres of radius h/2n (--clump-n, default 4) in one
YADE clump, with YADE's sphere contact (ScGeom, FrictPhys, CundallStrack).

For mpmsdem the per-step cost is split into: YADE's own loop (ForceResetter + Newton, run
without any contact engine), the PyRunner call (an empty ``PyRunner(command='pass')``
minus YADE's loop), the bridge (read state, compute contacts, write forces, from
``SdemEngine.timings()``) and the remaining Python glue of the engine's step.

Run with Debian's python and one thread::

    OMP_NUM_THREADS=1 PYTHONPATH=build/python:/usr/lib/x86_64-linux-gnu/yade-double/py \\
        /usr/bin/python3 scripts/bench/bench_sdem.py [--quick] [--repeat N] [--markdown FILE] \\
        [--pile-count N] [--clump-n N] [--only collision,stack,pile]

Timings are the minimum over --repeat runs of the same scene (the accuracy figures are
deterministic and come from the last run).
"""
import argparse
import datetime
import math
import os
import platform
import random
import sys
import time
import warnings

import mpmsdem  # imports yade first
import mpmsdem.analysis
from yade import O, utils
from yade import polyhedra_utils
from yade.minieigenHP import Quaternion, Vector3
from yade.wrapper import (Bo1_LevelSet_Aabb, Bo1_Polyhedra_Aabb, Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter,
                          FrictMat, Ig2_LevelSet_LevelSet_ScGeom, Ig2_Polyhedra_Polyhedra_PolyhedraGeom,
                          Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_LevelSet_ScGeom, Ig2_Wall_Polyhedra_PolyhedraGeom,
                          Ig2_Wall_Sphere_ScGeom, InsertionSortCollider,
                          InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                          Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys, Law2_PolyhedraGeom_PolyhedraPhys_Volumetric,
                          Law2_ScGeom_FrictPhys_CundallStrack, MatchMaker, NewtonIntegrator, PolyhedraMat,
                          PyRunner)

DENSITY = 3000.0      # kg/m^3 (paper §3.1 block)
KC = 1e4              # N/m, barrier stiffness k_c (paper)
POISSON = 0.3

# ---------------------------------------------------------------------------- helpers


def kinetic(ids):
    """Total kinetic energy (translation + rotation) of bodies [J]."""
    e = 0.0
    for i in ids:
        s = O.bodies[i].state
        e += 0.5 * s.mass * s.vel.squaredNorm()
        w = s.ori.conjugate() * s.angVel          # body frame, where inertia is diagonal
        e += 0.5 * (s.inertia[0] * w[0] ** 2 + s.inertia[1] * w[1] ** 2 + s.inertia[2] * w[2] ** 2)
    return e


_STAMPS = []


def _stamp():
    _STAMPS.append((O.iter, time.perf_counter()))


def timed_run(steps):
    """Run `steps` YADE steps; return the wall seconds of exactly `steps` steps.

    Timed from inside YADE's loop by a PyRunner that fires only at the first and the last step
    (two calls in all): ``O.run(n, True)`` returns on a 40 ms polling grid, which would dominate
    short runs, and polling ``O.running`` from Python competes for the GIL with PyRunners.
    One extra step is run to reach the second stamp.
    """
    import builtins
    builtins._benchSdemStamp = _stamp
    del _STAMPS[:]
    stamper = PyRunner(command="import builtins; builtins._benchSdemStamp()", iterPeriod=steps, initRun=True)
    O.engines = O.engines + [stamper]
    O.run(steps + 1, True)
    O.engines = O.engines[:-1]
    if len(_STAMPS) != 2 or _STAMPS[1][0] - _STAMPS[0][0] != steps:
        raise RuntimeError("timing stamps %r do not span %d steps" % (_STAMPS, steps))
    return _STAMPS[1][1] - _STAMPS[0][1]


def cube_vertices(half):
    return [Vector3(sx * half, sy * half, sz * half) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]


def newton(gravity, damping):
    return NewtonIntegrator(gravity=gravity, damping=damping)


# ---------------------------------------------------------------------------- scene builders
# Each builder resets O, creates bodies and engines, and returns (ids of moving bodies, extra).


def start_x(h, contactOnly):
    """Centroid x of the right cube: 0.2 m (paper), or a 0.1 mm gap for the contact-phase runs."""
    return h / 2 + 5e-5 if contactOnly else 0.2


def build_collision_sdem(h, engineMode="sdem", contactOnly=False):
    """engineMode: 'sdem' (the plugin), 'pass' (empty PyRunner), 'none' (YADE loop only)."""
    O.reset()
    sdem = mpmsdem.SdemEngine(dtCheck="warn")
    mat = mpmsdem.material(density=DENSITY, friction=0.0, poisson=POISSON, barrierStiffness=KC,
                           normalDamping=0.0, tangentialDamping=0.1)
    R = h / 20.0
    x = start_x(h, contactOnly)
    a = sdem.box((h / 2,) * 3, R, mat, pos=(-x, 0, 0))
    b = sdem.box((h / 2,) * 3, R, mat, pos=(x, 0, 0))
    O.bodies[a].state.vel = Vector3(1, 0, 0)
    O.bodies[b].state.vel = Vector3(-1, 0, 0)
    middle = {"sdem": [sdem.runner], "pass": [PyRunner(command="pass", iterPeriod=1)], "none": []}[engineMode]
    O.engines = [ForceResetter()] + middle + [newton((0, 0, 0), 0.0)]
    O.dt = 5e-6
    return [a, b], sdem


def levelset_engines(kn, gravity, damping, walls):
    """YADE's LevelSet loop: linear springs kn (shear kn * POISSON), Cundall-Strack friction,
    with wall contacts when ``walls``."""
    bounds = [Bo1_LevelSet_Aabb()] + ([Bo1_Wall_Aabb()] if walls else [])
    geoms = [Ig2_LevelSet_LevelSet_ScGeom()] + ([Ig2_Wall_LevelSet_ScGeom()] if walls else [])
    return [ForceResetter(),
            InsertionSortCollider(bounds, verletDist=0),
            InteractionLoop(geoms,
                            [Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=kn),
                                                             ks=MatchMaker(algo="val", val=kn * POISSON))],
                            [Law2_ScGeom_FrictPhys_CundallStrack(sphericalBodies=False)]),
            newton(gravity, damping)]


def build_collision_levelset(h, kn, contactOnly=False):
    O.reset()
    mat = O.materials.append(FrictMat(density=DENSITY, frictionAngle=0.0, young=1e6, poisson=POISSON))
    # grid spacing h/20 (as the paper's node-size/side ratio); 602 surface nodes as in the paper
    ids = []
    x0 = start_x(h, contactOnly)
    for x, v in ((-x0, 1.0), (x0, -1.0)):
        bd = utils.levelSetBody("box", center=(x, 0, 0), extents=(h / 2,) * 3, spacing=h / 20.0,
                                nSurfNodes=602, nodesPath=2, material=mat)
        i = O.bodies.append(bd)
        O.bodies[i].state.vel = Vector3(v, 0, 0)
        ids.append(i)
    O.engines = levelset_engines(kn, (0, 0, 0), 0.0, walls=False)
    O.dt = 5e-6
    return ids, None


def polyhedra_engines(gravity, damping, walls):
    """YADE's Polyhedra loop (volumetric law), with wall contacts when ``walls``."""
    bounds = [Bo1_Polyhedra_Aabb()] + ([Bo1_Wall_Aabb()] if walls else [])
    geoms = [Ig2_Polyhedra_Polyhedra_PolyhedraGeom()] + ([Ig2_Wall_Polyhedra_PolyhedraGeom()] if walls else [])
    return [ForceResetter(),
            InsertionSortCollider(bounds, verletDist=0),
            InteractionLoop(geoms, [Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                            [Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
            newton(gravity, damping)]


def build_collision_polyhedra(h, kv, contactOnly=False):
    """kv: volumetric stiffness [N/m^3] (force = kv * overlap volume)."""
    O.reset()
    # Ip2: 1/kn = 1/Y1 + 1/Y2 -> Y = 2 kv
    mat = O.materials.append(PolyhedraMat(density=DENSITY, young=2 * kv, poisson=POISSON, frictionAngle=0.0))
    ids = []
    x0 = start_x(h, contactOnly)
    for x, v in ((-x0, 1.0), (x0, -1.0)):
        bd = polyhedra_utils.polyhedra(O.materials[mat], v=cube_vertices(h / 2))
        bd.state.pos = Vector3(x, 0, 0)
        i = O.bodies.append(bd)
        O.bodies[i].state.vel = Vector3(v, 0, 0)
        ids.append(i)
    O.engines = polyhedra_engines((0, 0, 0), 0.0, walls=False)
    O.dt = 5e-6
    return ids, None


# sphere clumps -------------------------------------------------------------------------

CLUMP_N = 4             # spheres per cube edge (--clump-n); 4 gives r = h/8


def clump_cube(h, n, matId, pos, ori=None):
    """Append a cube of side h as a clump of n^3 equal, touching spheres (r = h/2n) whose outer
    tips lie on the cube's faces; returns the clump id. The spheres fill pi/6 of the cube, so
    their material is denser by 6/pi to give the clump the cube's mass."""
    r = h / (2 * n)
    q = ori if ori is not None else Quaternion.Identity
    c = Vector3(*pos)
    spheres = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                local = Vector3(-h / 2 + r * (2 * i + 1), -h / 2 + r * (2 * j + 1), -h / 2 + r * (2 * k + 1))
                spheres.append(utils.sphere(c + q * local, r, material=matId))
    cid, _ = O.bodies.appendClumped(spheres)
    return cid


def clump_material(kn, friction, n):
    """Sphere material and the sphere-sphere law, stiffness per sphere contact kn / n^2: a flat
    face of a clump touches a face-aligned neighbour (or a wall) with n^2 spheres at once, so the
    face contact has the peers' stiffness kn."""
    mat = O.materials.append(FrictMat(density=DENSITY * 6 / math.pi, frictionAngle=math.atan(friction),
                                      young=1e6, poisson=POISSON))
    ksph = kn / n ** 2
    law = InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                          [Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=ksph),
                                                           ks=MatchMaker(algo="val", val=ksph * POISSON))],
                          [Law2_ScGeom_FrictPhys_CundallStrack()])
    return mat, law


def build_collision_clumps(h, kn, contactOnly=False, n=None):
    n = n or CLUMP_N
    O.reset()
    mat, law = clump_material(kn, 0.0, n)
    ids = []
    x0 = start_x(h, contactOnly)
    for x, v in ((-x0, 1.0), (x0, -1.0)):
        i = clump_cube(h, n, mat, (x, 0, 0))
        O.bodies[i].state.vel = Vector3(v, 0, 0)
        ids.append(i)
    # YADE's default verletDist (a fraction of the smallest sphere radius), the usual sphere setup
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]), law, newton((0, 0, 0), 0.0)]
    O.dt = 5e-6
    return ids, None


def collision_figures(ids, e0):
    speeds = [O.bodies[i].state.vel.norm() for i in ids]
    trans = max(math.hypot(O.bodies[i].state.vel[1], O.bodies[i].state.vel[2]) for i in ids)
    ang = max(O.bodies[i].state.angVel.norm() for i in ids)
    vx = [O.bodies[i].state.vel[0] for i in ids]
    return {"speed": sum(speeds) / len(speeds), "transverse": trans, "angular": ang,
            "dE": kinetic(ids) / e0 - 1.0, "separated": vx[0] < 0 < vx[1]}


# stack -------------------------------------------------------------------------------

STACK_COUNT = 3         # equal cubes, one on the other
STACK_H = 0.1           # cube side [m]
STACK_FLOOR = 0.2       # half-width of the SDEM floor box [m] (peers: a YADE Wall)
STACK_DAMPING = 0.5     # NewtonIntegrator damping, the same for all methods
STACK_DT = 1e-4


_ORI0 = {}


def remember_orientations(ids):
    """Tilts are measured from the start: a clump's orientation is that of its principal axes,
    which for a cube of spheres need not be the world frame."""
    _ORI0.clear()
    for i in ids:
        _ORI0[i] = Quaternion(O.bodies[i].state.ori)


def stack_start(k):
    """Centroid height of cube k (0 = bottom): the outer surfaces just touch, nothing overlaps."""
    return STACK_H / 2 + k * STACK_H


def build_stack_sdem(engineMode="sdem"):
    O.reset()
    sdem = mpmsdem.SdemEngine(dtCheck="warn")
    mat = mpmsdem.material(density=DENSITY, friction=PILE_FRICTION, poisson=POISSON, barrierStiffness=KC,
                           normalDamping=0.0, tangentialDamping=0.1)
    R = STACK_H / 20.0
    t = PILE_WALL / 2
    floor = sdem.box((STACK_FLOOR, STACK_FLOOR, t), R, mat, pos=(0, 0, -t), fixed=True)
    ids = [sdem.box((STACK_H / 2,) * 3, R, mat, pos=(0, 0, stack_start(k))) for k in range(STACK_COUNT)]
    middle = {"sdem": [sdem.runner], "pass": [PyRunner(command="pass", iterPeriod=1)], "none": []}[engineMode]
    O.engines = [ForceResetter()] + middle + [newton((0, 0, -9.81), STACK_DAMPING)]
    O.dt = STACK_DT
    remember_orientations(ids)
    sdem.floorId = floor
    return ids, sdem


def build_stack_levelset(kn):
    O.reset()
    mat = O.materials.append(FrictMat(density=DENSITY, frictionAngle=math.atan(PILE_FRICTION), young=1e6,
                                      poisson=POISSON))
    O.bodies.append(utils.wall(0.0, axis=2, sense=1, material=mat))
    ids = [O.bodies.append(utils.levelSetBody("box", center=(0, 0, stack_start(k)), extents=(STACK_H / 2,) * 3,
                                              spacing=STACK_H / 20.0, nSurfNodes=602, nodesPath=2, material=mat))
           for k in range(STACK_COUNT)]
    O.engines = levelset_engines(kn, (0, 0, -9.81), STACK_DAMPING, walls=True)
    O.dt = STACK_DT
    remember_orientations(ids)
    return ids, None


def build_stack_polyhedra(kv):
    O.reset()
    mat = O.materials.append(PolyhedraMat(density=DENSITY, young=2 * kv, poisson=POISSON,
                                          frictionAngle=math.atan(PILE_FRICTION)))
    O.bodies.append(utils.wall(0.0, axis=2, sense=1, material=mat))
    ids = []
    for k in range(STACK_COUNT):
        bd = polyhedra_utils.polyhedra(O.materials[mat], v=cube_vertices(STACK_H / 2))
        bd.state.pos = Vector3(0, 0, stack_start(k))
        ids.append(O.bodies.append(bd))
    O.engines = polyhedra_engines((0, 0, -9.81), STACK_DAMPING, walls=True)
    O.dt = STACK_DT
    remember_orientations(ids)
    return ids, None


def build_stack_clumps(kn, n=None):
    n = n or CLUMP_N
    O.reset()
    mat, law = clump_material(kn, PILE_FRICTION, n)
    O.bodies.append(utils.wall(0.0, axis=2, sense=1, material=mat))
    ids = [clump_cube(STACK_H, n, mat, (0, 0, stack_start(k))) for k in range(STACK_COUNT)]
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]), law,
                 newton((0, 0, -9.81), STACK_DAMPING)]
    O.dt = STACK_DT
    remember_orientations(ids)
    return ids, None


def stack_pair_forces_yade():
    """Vertical force carried across each body pair {lower, upper} [N], summed over the pair's
    interactions (clump members counted for their clump); the floor Wall is body 0."""
    out = {}
    for i in O.interactions:
        if not i.isReal:
            continue
        a, b = owner(i.id1), owner(i.id2)
        key = tuple(sorted((a, b)))
        out[key] = out.get(key, 0.0) + abs(i.phys.normalForce[2])
    return out, {}


def stack_pair_forces_sdem(sdem):
    c = sdem.contacts()
    out, points = {}, {}
    for a, b, f, nrm in zip(list(c["id1"]), list(c["id2"]), list(c["normalForce"]), list(c["normal"])):
        key = tuple(sorted((int(a), int(b))))
        out[key] = out.get(key, 0.0) + abs(float(f) * float(nrm[2]))
        points[key] = points.get(key, 0) + 1
    return out, points


def stack_figures(ids, floorId, pairForces, overlapOf):
    """Errors against the static answer: contact k (0 = floor) carries the weight of the cubes
    from k up; the stack stays on the axis, untilted; centroid k sits at its start height minus
    the equilibrium overlaps of the contacts below it (overlapOf(load, key) [m])."""
    g = 9.81
    masses = [O.bodies[i].state.mass for i in ids]
    below = [floorId] + ids[:-1]
    fErr, zErr, zExact = 0.0, 0.0, 0.0
    for k, i in enumerate(ids):
        load = g * sum(masses[k:])
        key = tuple(sorted((below[k], i)))
        fErr = max(fErr, abs(pairForces.get(key, 0.0) / load - 1.0))
        zExact += overlapOf(load, key)
        zErr = max(zErr, abs(O.bodies[i].state.pos[2] - (stack_start(k) - zExact)))
    W = g * sum(masses)
    floor = abs(O.forces.f(floorId)[2]) / W - 1.0
    drift = max(math.hypot(O.bodies[i].state.pos[0], O.bodies[i].state.pos[1]) for i in ids)
    tilt = 0.0
    for i in ids:
        ang = abs(float((O.bodies[i].state.ori * _ORI0[i].conjugate()).toAxisAngle()[1])) % (2 * math.pi)
        tilt = max(tilt, math.degrees(min(ang, 2 * math.pi - ang)))
    return {"floor": floor, "fErr": fErr, "zErr": zErr, "drift": drift, "tilt": tilt, "Ek": kinetic(ids),
            "dFloor": overlapOf(W, tuple(sorted((floorId, ids[0]))))}


# pile --------------------------------------------------------------------------------

PILE_H = 0.1            # cube side [m]
PILE_PITCH = 0.135      # horizontal lattice pitch [m]
PILE_VPITCH = 0.15      # vertical pitch of the layers [m]
PILE_TILT = 10.0        # random initial tilt, up to this many degrees about a random axis
PILE_INNER = 0.56       # inner side of the box [m]
PILE_WALL = 0.05        # wall thickness (SDEM boxes) [m]
PILE_HEIGHT = 0.7       # wall height [m]
PILE_FRICTION = 0.5
PILE_DAMPING = 0.2      # NewtonIntegrator damping, the same for all methods
PILE_DT = 1e-4


def pile_layout(count=50):
    """Centroids and orientations of the pile's cubes: layers of 4x4 and 3x3 alternately (50 cubes
    fill four layers, 100 eight), the 3x3 layers shifted by half a pitch so that cubes land on
    edges and corners of the layer below; the last layer is filled row by row; seeded random
    tilts (the first 50 cubes are the same whatever the count)."""
    rnd = random.Random(12345)
    out = []
    k = 0
    while len(out) < count:
        n = 4 if k % 2 == 0 else 3
        for j in range(n):
            for i in range(n):
                p = Vector3((i - (n - 1) / 2) * PILE_PITCH, (j - (n - 1) / 2) * PILE_PITCH,
                            PILE_H / 2 + 0.03 + k * PILE_VPITCH)
                axis = Vector3(rnd.uniform(-1, 1), rnd.uniform(-1, 1), rnd.uniform(-1, 1))
                axis.normalize()
                q = Quaternion(axis, math.radians(rnd.uniform(-PILE_TILT, PILE_TILT)))
                out.append((p, q))
        k += 1
    return out[:count]


def pile_wall_height(count):
    """PILE_HEIGHT, or higher when the top layer starts above it (SDEM's walls are finite boxes;
    the peers' Wall bodies are unbounded planes)."""
    top = max(p[2] for p, _ in pile_layout(count)) + PILE_H
    return max(PILE_HEIGHT, top)


def build_pile_sdem(engineMode="sdem", count=50):
    O.reset()
    sdem = mpmsdem.SdemEngine(dtCheck="warn")
    mat = mpmsdem.material(density=DENSITY, friction=PILE_FRICTION, poisson=POISSON, barrierStiffness=KC,
                           normalDamping=0.0, tangentialDamping=0.1)
    R = PILE_H / 20.0
    a, t, hh = PILE_INNER / 2, PILE_WALL / 2, pile_wall_height(count) / 2
    sdem.box((a + 2 * t, a + 2 * t, t), R, mat, pos=(0, 0, -t), fixed=True)            # floor
    sdem.box((t, a, hh), R, mat, pos=(-a - t, 0, hh), fixed=True)                       # -x wall
    sdem.box((t, a, hh), R, mat, pos=(a + t, 0, hh), fixed=True)                        # +x wall
    sdem.box((a + 2 * t, t, hh), R, mat, pos=(0, -a - t, hh), fixed=True)               # -y wall
    sdem.box((a + 2 * t, t, hh), R, mat, pos=(0, a + t, hh), fixed=True)                # +y wall
    ids = [sdem.box((PILE_H / 2,) * 3, R, mat, pos=p, ori=q) for p, q in pile_layout(count)]
    middle = {"sdem": [sdem.runner], "pass": [PyRunner(command="pass", iterPeriod=1)], "none": []}[engineMode]
    O.engines = [ForceResetter()] + middle + [newton((0, 0, -9.81), PILE_DAMPING)]
    O.dt = PILE_DT
    return ids, sdem


def add_walls(matId):
    a = PILE_INNER / 2
    for axis, sense, pos in ((2, 1, 0.0), (0, 1, -a), (0, -1, a), (1, 1, -a), (1, -1, a)):
        O.bodies.append(utils.wall(pos, axis=axis, sense=sense, material=matId))


def build_pile_levelset(kn, count=50):
    O.reset()
    mat = O.materials.append(FrictMat(density=DENSITY, frictionAngle=math.atan(PILE_FRICTION), young=1e6,
                                      poisson=POISSON))
    add_walls(mat)
    ids = []
    for p, q in pile_layout(count):
        bd = utils.levelSetBody("box", center=p, extents=(PILE_H / 2,) * 3, spacing=PILE_H / 20.0,
                                nSurfNodes=602, nodesPath=2, material=mat, orientation=q)
        ids.append(O.bodies.append(bd))
    O.engines = levelset_engines(kn, (0, 0, -9.81), PILE_DAMPING, walls=True)
    O.dt = PILE_DT
    return ids, None


def build_pile_polyhedra(kv, count=50):
    O.reset()
    mat = O.materials.append(PolyhedraMat(density=DENSITY, young=2 * kv, poisson=POISSON,
                                          frictionAngle=math.atan(PILE_FRICTION)))
    add_walls(mat)
    ids = []
    for p, q in pile_layout(count):
        bd = polyhedra_utils.polyhedra(O.materials[mat], v=cube_vertices(PILE_H / 2))
        bd.state.pos = p
        bd.state.ori = q
        ids.append(O.bodies.append(bd))
    O.engines = polyhedra_engines((0, 0, -9.81), PILE_DAMPING, walls=True)
    O.dt = PILE_DT
    return ids, None


def build_pile_clumps(kn, count=50, n=None):
    n = n or CLUMP_N
    O.reset()
    mat, law = clump_material(kn, PILE_FRICTION, n)
    add_walls(mat)
    ids = [clump_cube(PILE_H, n, mat, p, q) for p, q in pile_layout(count)]
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]), law,
                 newton((0, 0, -9.81), PILE_DAMPING)]
    O.dt = PILE_DT
    return ids, None


def pile_figures(ids, contacts):
    zs = [O.bodies[i].state.pos[2] for i in ids]
    return {"contacts": contacts, "Ek": kinetic(ids), "zmean": sum(zs) / len(zs), "ztop": max(zs),
            "escaped": sum(1 for i in ids if abs(O.bodies[i].state.pos[0]) > PILE_INNER / 2
                           or abs(O.bodies[i].state.pos[1]) > PILE_INNER / 2 or O.bodies[i].state.pos[2] < 0)}


def sdem_pairs(sdem):
    c = sdem.contacts()
    return len(set(zip(list(c["id1"]), list(c["id2"])))) if len(c["id1"]) else 0


def owner(i):
    """The body a force acts on: the clump for a clump member, else the body itself."""
    b = O.bodies[i]
    return b.clumpId if b.isClumpMember else i


def yade_contacts():
    """Body pairs in contact (pairs of clumps for clumps, not sphere pairs)."""
    return len(set(tuple(sorted((owner(i.id1), owner(i.id2)))) for i in O.interactions if i.isReal))


# ---------------------------------------------------------------------------- measuring


def measure(build, steps, repeat, after=None):
    """Build and run a scene `repeat` times; returns (min µs/step, figures of the last run; for
    mpmsdem also its bridge timings, each the minimum over the runs)."""
    best = float("inf")
    data = None
    bestTimings = {}
    for _ in range(repeat):
        ids, extra = build()
        e0 = kinetic(ids)
        if extra is not None:
            extra.resetTimings()
        dt = timed_run(steps)
        if extra is not None:
            extra.check()
        best = min(best, dt / steps * 1e6)
        data = after(ids, extra, e0) if after else None
        if extra is not None:
            for k, v in extra.timings().items():
                bestTimings[k] = min(v, bestTimings.get(k, float("inf")))
            data = dict(data or {}, timings=dict(bestTimings), warnings=extra.timeStepWarnings)
    return best, data


def sdem_breakdown(buildSdem, steps, repeat, after):
    """µs/step of the plugin run and its parts (each a minimum over `repeat`)."""
    total, data = measure(lambda: buildSdem("sdem"), steps, repeat, after)
    bestParts = {k: data["timings"][k] / steps * 1e6 for k in ("read", "compute", "write")}
    yadeOnly, _ = measure(lambda: buildSdem("none"), steps, repeat)
    withPass, _ = measure(lambda: buildSdem("pass"), steps, repeat)
    bridge = bestParts["read"] + bestParts["compute"] + bestParts["write"]
    parts = {"yade": yadeOnly, "pyrunner": max(0.0, withPass - yadeOnly), "read": bestParts["read"],
             "compute": bestParts["compute"], "write": bestParts["write"]}
    parts["glue"] = total - bridge - withPass
    return total, data, parts


def delta_max_sdem(h, steps):
    """Peak overlap [m] and number of steps in contact of the SDEM collision (sampled every
    10 steps; an untimed run)."""
    ids, sdem = build_collision_sdem(h)
    peak = [0.0]
    inContact = [0]

    def sample():
        c = sdem.contacts()
        if len(c["overlap"]):
            peak[0] = max(peak[0], float(max(c["overlap"])))
            inContact[0] += 10
    import builtins
    builtins._benchSdemSample = sample
    O.engines = O.engines + [PyRunner(command="import builtins; builtins._benchSdemSample()", iterPeriod=10)]
    O.run(steps, True)
    sdem.check()
    return peak[0], inContact[0]


# ---------------------------------------------------------------------------- main


def main(argv=None):
    global CLUMP_N
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short runs (~30 s in all)")
    ap.add_argument("--repeat", type=int, default=None, help="timed runs per case, minimum taken (default 3, quick 1)")
    ap.add_argument("--markdown", metavar="FILE", help="append the tables and the command to FILE")
    ap.add_argument("--no-polyhedra", action="store_true", help="skip YADE Polyhedra (the slowest peer)")
    ap.add_argument("--no-clumps", action="store_true", help="skip the sphere-clump cubes")
    ap.add_argument("--clump-n", type=int, default=CLUMP_N,
                    help="spheres per cube edge of a clump, n^3 in all, radius h/2n (default %d)" % CLUMP_N)
    ap.add_argument("--pile-count", type=int, default=None, help="cubes in the pile (default 100, quick 30)")
    ap.add_argument("--pile-steps", type=int, default=None, help="steps of the pile (default 8000, quick 1500)")
    ap.add_argument("--stack-steps", type=int, default=None, help="steps of the stack (default 10000, quick 3000)")
    ap.add_argument("--only", default="collision,stack,pile", help="comma-separated scenes to run")
    args = ap.parse_args(argv)
    CLUMP_N = args.clump_n
    scenes = set(args.only.split(","))
    pileCount = args.pile_count or (30 if args.quick else 100)
    repeat = args.repeat or (1 if args.quick else 3)
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: OMP_NUM_THREADS is not 1; YADE's loops may use several threads", file=sys.stderr)
    warnings.filterwarnings("ignore", message=r"NewtonIntegrator.damping")  # the pile damps all methods alike

    rows = []      # (scene, method, us/step, figures-string)
    parts_rows = []
    notes = []
    stiff = {}     # h -> peers' linear stiffness kn [N/m]

    def compare(scene, steps, reps, sdem_build, after_sdem, levelset, polyhedra, clumps, after_peer, poly_reps=None):
        # SDEM with its cost breakdown, then the peers (builders without arguments) on the same scene
        t, d, parts = sdem_breakdown(sdem_build, steps, reps, after_sdem)
        rows.append((scene, "mpmsdem SDEM", t, d))
        parts_rows.append((scene, t, parts, d.get("warnings", 0)))
        for method, build, n, skip in (("YADE LevelSet", levelset, reps, False),
                                       ("YADE Polyhedra", polyhedra, poly_reps or reps, args.no_polyhedra),
                                       ("YADE clump %d^3" % CLUMP_N, clumps, reps, args.no_clumps)):
            if not skip:
                t, d = measure(build, steps, n, after_peer)
                rows.append((scene, method, t, d))

    # ---- scene 1: head-on collisions
    collisions = [(0.1, 60000), (0.3, 60000)]
    if args.quick:
        collisions = [(0.1, 60000), (0.3, 30000)]
    if "collision" not in scenes:
        collisions = []
    for h, steps in collisions:
        scene = "collision h=%.1f m (%d steps)" % (h, steps)
        dmax, ncontact = delta_max_sdem(h, steps)
        # match peers to the SDEM peak overlap: same relative kinetic energy stored at the same depth
        m = DENSITY * h ** 3
        erel = 0.5 * (m / 2) * 2.0 ** 2
        kn = 2 * erel / dmax ** 2                 # linear spring [N/m]
        kv = kn / h ** 2                          # volumetric [N/m^3]: face overlap volume = h^2 * delta
        stiff[h] = kn
        notes.append("h=%.1f m: SDEM peak overlap %.3g mm, in contact for about %d steps -> peers kn = %.3g N/m "
                     "(LevelSet), kv = %.3g N/m^3 (Polyhedra), %.3g N/m per sphere pair (clumps, %d^2 pairs "
                     "per face)" % (h, dmax * 1e3, ncontact, kn, kv, kn / CLUMP_N ** 2, CLUMP_N))

        def after_col(ids, extra, e0):
            return collision_figures(ids, e0)
        compare(scene, steps, repeat, lambda mode: build_collision_sdem(h, mode), after_col,
                lambda: build_collision_levelset(h, kn), lambda: build_collision_polyhedra(h, kv),
                lambda: build_collision_clumps(h, kn), after_col)
        # the contact phase alone (the free flight above is mostly overhead): start 0.1 mm apart and
        # run as long as the longer of the SDEM contact and the peers' linear contact (pi sqrt(mu/kn)), +20 %;
        # short runs, so 3x as many repeats
        linear = math.pi * math.sqrt(m / 2 / kn) / 5e-6
        csteps = int(1.2 * max(ncontact, linear))
        cscene = "contact phase h=%.1f m (%d steps)" % (h, csteps)
        compare(cscene, csteps, 3 * repeat, lambda mode: build_collision_sdem(h, mode, True), after_col,
                lambda: build_collision_levelset(h, kn, True), lambda: build_collision_polyhedra(h, kv, True),
                lambda: build_collision_clumps(h, kn, True), after_col)

    # peers' stiffness for the stack and the pile: that matched to SDEM in the collision of cubes of
    # the same size
    knPile = stiff.get(PILE_H) or 2 * (0.5 * (DENSITY * PILE_H ** 3 / 2) * 4.0) / delta_max_sdem(PILE_H, 60000)[0] ** 2

    # ---- scene 2: three stacked cubes
    if "stack" in scenes:
        ssteps = args.stack_steps or (3000 if args.quick else 10000)
        scene = "stack of %d cubes (%d steps)" % (STACK_COUNT, ssteps)
        R2 = 2 * STACK_H / 20.0

        def after_sdem_stack(ids, extra, e0):
            forces, points = stack_pair_forces_sdem(extra)
            # a face-face patch carries the load on its corner points, equally by symmetry
            return stack_figures(ids, extra.floorId, forces,
                                 lambda load, key: mpmsdem.analysis.equilibriumOverlap(load, R2, KC, points.get(key, 4)))

        def after_peer_stack(ids, extra, e0):
            forces, _ = stack_pair_forces_yade()
            return stack_figures(ids, 0, forces, lambda load, key: load / knPile)
        compare(scene, ssteps, repeat, build_stack_sdem, after_sdem_stack, lambda: build_stack_levelset(knPile),
                lambda: build_stack_polyhedra(knPile / STACK_H ** 2), lambda: build_stack_clumps(knPile),
                after_peer_stack)
        notes.append("stack: %d cubes h = %.1f m on a floor (SDEM: a fixed box; peers: a YADE Wall), outer "
                     "surfaces touching at the start, gravity 9.81, NewtonIntegrator damping %.1f for all, dt %g s; "
                     "peers' kn as in the pile; exact overlaps: SDEM equilibriumOverlap over the patch's contact "
                     "points, peers load/kn" % (STACK_COUNT, STACK_H, STACK_DAMPING, STACK_DT))

    # ---- scene 3: pile
    if "pile" in scenes:
        psteps = args.pile_steps or (1500 if args.quick else 8000)
        scene = "pile %d cubes (%d steps)" % (pileCount, psteps)
        notes.append("pile: peers' kn = %.3g N/m (LevelSet), kv = %.3g N/m^3 (Polyhedra), as for h = %.1f m; "
                     "YADE Wall bodies for the peers' floor and walls; NewtonIntegrator damping %.1f for all; "
                     "dt %g s" % (knPile, knPile / PILE_H ** 2, PILE_H, PILE_DAMPING, PILE_DT))

        def after_sdem_pile(ids, extra, e0):
            return pile_figures(ids, sdem_pairs(extra))

        def after_peer_pile(ids, extra, e0):
            return pile_figures(ids, yade_contacts())
        # Polyhedra one run only: it is by far the slowest here, its noise does not matter
        compare(scene, psteps, repeat, lambda mode: build_pile_sdem(mode, pileCount), after_sdem_pile,
                lambda: build_pile_levelset(knPile, pileCount),
                lambda: build_pile_polyhedra(knPile / PILE_H ** 2, pileCount),
                lambda: build_pile_clumps(knPile, pileCount), after_peer_pile, poly_reps=1)

    # ---- report
    out = format_report(rows, parts_rows, notes, repeat, args)
    print(out)
    if args.markdown:
        with open(args.markdown, "a") as f:
            f.write(out + "\n")
    return 0


def fmt_fig(d):
    if d is None:
        return ""
    if "speed" in d:
        s = "speed %.5f m/s, transverse %.2e m/s, angular %.2e rad/s, dE/E %+.2e" % (
            d["speed"], d["transverse"], d["angular"], d["dE"])
        if not d["separated"]:
            s += " (NOT separated)"
        return s
    if "floor" in d:
        return ("floor force %+.1e, pair forces %.1e, heights %.2g mm (floor overlap %.3g mm), drift %.2g mm, "
                "tilt %.2g°, Ek %.2g J" % (d["floor"], d["fErr"], d["zErr"] * 1e3, d["dFloor"] * 1e3,
                                          d["drift"] * 1e3, d["tilt"], d["Ek"]))
    s = "contacts %d, Ek %.3g J, z mean %.4f m, z top %.4f m" % (d["contacts"], d["Ek"], d["zmean"], d["ztop"])
    if d["escaped"]:
        s += ", %d cubes outside the box" % d["escaped"]
    return s


def format_report(rows, parts_rows, notes, repeat, args):
    cmd = "OMP_NUM_THREADS=%s PYTHONPATH=%s %s scripts/bench/bench_sdem.py %s" % (
        os.environ.get("OMP_NUM_THREADS", "unset"), os.environ.get("PYTHONPATH", ""), sys.executable,
        " ".join(sys.argv[1:]))
    lines = []
    lines.append("### SDEM run %s (%s, %s)" % (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
                                                 platform.node(), platform.processor() or platform.machine()))
    lines.append("")
    lines.append("Command: `%s` (timings: minimum of %d run(s))" % (cmd, repeat))
    lines.append("")
    lines.append("| scene | method | µs/step | vs SDEM | figures |")
    lines.append("|---|---|---:|---:|---|")
    ref = {}
    for scene, method, t, d in rows:
        if method.startswith("mpmsdem"):
            ref[scene] = t
    for scene, method, t, d in rows:
        lines.append("| %s | %s | %.1f | %.2f | %s |" % (scene, method, t, t / ref[scene], fmt_fig(d)))
    lines.append("")
    lines.append("mpmsdem per-step breakdown (µs/step):")
    lines.append("")
    lines.append("| scene | total | YADE loop | PyRunner | bridge read | compute | write | Python glue | dt warnings |")
    lines.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene, t, p, w in parts_rows:
        lines.append("| %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %d |" % (
            scene, t, p["yade"], p["pyrunner"], p["read"], p["compute"], p["write"], p["glue"], w))
    lines.append("")
    for n in notes:
        lines.append("- " + n)
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
