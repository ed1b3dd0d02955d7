#!/usr/bin/env python3
"""SDEM benchmark: mpmsdem's sphero-polyhedra against YADE's own LevelSet and Polyhedra.

Scenes (all three methods run in this one process, so their ratios are comparable):

1. Head-on collision of two equal cubes (paper §4.2): side h = 0.1 m and 0.3 m, centroids
   0.4 m apart, +-1 m/s, frictionless, dt = 5e-6 s, run through impact and separation.
   Reports µs/step, speed after impact (exact answer 1 m/s), transverse and angular
   velocity (exact answer 0) and the relative change of kinetic energy (exact answer 0).
2. A pile of 50 cubes (h = 0.1 m, four staggered layers, random tilts) dropped into a fixed box (floor + 4 walls) under
   gravity. Reports µs/step, number of contacts, final kinetic energy, mean and top
   centroid height.

For mpmsdem the per-step cost is split into: YADE's own loop (ForceResetter + Newton, run
without any contact engine), the PyRunner call (an empty ``PyRunner(command='pass')``
minus YADE's loop), the bridge (read state, compute contacts, write forces, from
``SdemEngine.timings()``) and the remaining Python glue of the engine's step.

Run with Debian's python and one thread::

    OMP_NUM_THREADS=1 PYTHONPATH=build/python:/usr/lib/x86_64-linux-gnu/yade-double/py \\
        /usr/bin/python3 scripts/bench/bench_sdem.py [--quick] [--repeat N] [--markdown FILE]

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
from yade import O, utils
from yade import polyhedra_utils
from yade.minieigenHP import Quaternion, Vector3
from yade.wrapper import (Bo1_LevelSet_Aabb, Bo1_Polyhedra_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat,
                          Ig2_LevelSet_LevelSet_ScGeom, Ig2_Polyhedra_Polyhedra_PolyhedraGeom,
                          Ig2_Wall_LevelSet_ScGeom, Ig2_Wall_Polyhedra_PolyhedraGeom, InsertionSortCollider,
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
    O.engines = [ForceResetter(),
                 InsertionSortCollider([Bo1_LevelSet_Aabb()], verletDist=0),
                 InteractionLoop([Ig2_LevelSet_LevelSet_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=kn),
                                                                  ks=MatchMaker(algo="val", val=kn * POISSON))],
                                 [Law2_ScGeom_FrictPhys_CundallStrack(sphericalBodies=False)]),
                 newton((0, 0, 0), 0.0)]
    O.dt = 5e-6
    return ids, None


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
    O.engines = [ForceResetter(),
                 InsertionSortCollider([Bo1_Polyhedra_Aabb()], verletDist=0),
                 InteractionLoop([Ig2_Polyhedra_Polyhedra_PolyhedraGeom()],
                                 [Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                                 [Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
                 newton((0, 0, 0), 0.0)]
    O.dt = 5e-6
    return ids, None


def collision_figures(ids, e0):
    speeds = [O.bodies[i].state.vel.norm() for i in ids]
    trans = max(math.hypot(O.bodies[i].state.vel[1], O.bodies[i].state.vel[2]) for i in ids)
    ang = max(O.bodies[i].state.angVel.norm() for i in ids)
    vx = [O.bodies[i].state.vel[0] for i in ids]
    return {"speed": sum(speeds) / len(speeds), "transverse": trans, "angular": ang,
            "dE": kinetic(ids) / e0 - 1.0, "separated": vx[0] < 0 < vx[1]}


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


def pile_layout():
    """Centroids and orientations of the pile's 50 cubes: four layers, 4x4 and 3x3 alternately,
    the 3x3 layers shifted by half a pitch so that cubes land on edges and corners of the layer
    below; seeded random tilts."""
    rnd = random.Random(12345)
    out = []
    for k, n in enumerate((4, 3, 4, 3)):
        for j in range(n):
            for i in range(n):
                p = Vector3((i - (n - 1) / 2) * PILE_PITCH, (j - (n - 1) / 2) * PILE_PITCH,
                            PILE_H / 2 + 0.03 + k * PILE_VPITCH)
                axis = Vector3(rnd.uniform(-1, 1), rnd.uniform(-1, 1), rnd.uniform(-1, 1))
                axis.normalize()
                q = Quaternion(axis, math.radians(rnd.uniform(-PILE_TILT, PILE_TILT)))
                out.append((p, q))
    return out


def build_pile_sdem(engineMode="sdem"):
    O.reset()
    sdem = mpmsdem.SdemEngine(dtCheck="warn")
    mat = mpmsdem.material(density=DENSITY, friction=PILE_FRICTION, poisson=POISSON, barrierStiffness=KC,
                           normalDamping=0.0, tangentialDamping=0.1)
    R = PILE_H / 20.0
    a, t, hh = PILE_INNER / 2, PILE_WALL / 2, PILE_HEIGHT / 2
    sdem.box((a + 2 * t, a + 2 * t, t), R, mat, pos=(0, 0, -t), fixed=True)            # floor
    sdem.box((t, a, hh), R, mat, pos=(-a - t, 0, hh), fixed=True)                       # -x wall
    sdem.box((t, a, hh), R, mat, pos=(a + t, 0, hh), fixed=True)                        # +x wall
    sdem.box((a + 2 * t, t, hh), R, mat, pos=(0, -a - t, hh), fixed=True)               # -y wall
    sdem.box((a + 2 * t, t, hh), R, mat, pos=(0, a + t, hh), fixed=True)                # +y wall
    ids = [sdem.box((PILE_H / 2,) * 3, R, mat, pos=p, ori=q) for p, q in pile_layout()]
    middle = {"sdem": [sdem.runner], "pass": [PyRunner(command="pass", iterPeriod=1)], "none": []}[engineMode]
    O.engines = [ForceResetter()] + middle + [newton((0, 0, -9.81), PILE_DAMPING)]
    O.dt = PILE_DT
    return ids, sdem


def add_walls(matId):
    a = PILE_INNER / 2
    for axis, sense, pos in ((2, 1, 0.0), (0, 1, -a), (0, -1, a), (1, 1, -a), (1, -1, a)):
        O.bodies.append(utils.wall(pos, axis=axis, sense=sense, material=matId))


def build_pile_levelset(kn):
    O.reset()
    mat = O.materials.append(FrictMat(density=DENSITY, frictionAngle=math.atan(PILE_FRICTION), young=1e6,
                                      poisson=POISSON))
    add_walls(mat)
    ids = []
    for p, q in pile_layout():
        bd = utils.levelSetBody("box", center=p, extents=(PILE_H / 2,) * 3, spacing=PILE_H / 20.0,
                                nSurfNodes=602, nodesPath=2, material=mat, orientation=q)
        ids.append(O.bodies.append(bd))
    O.engines = [ForceResetter(),
                 InsertionSortCollider([Bo1_LevelSet_Aabb(), Bo1_Wall_Aabb()], verletDist=0),
                 InteractionLoop([Ig2_LevelSet_LevelSet_ScGeom(), Ig2_Wall_LevelSet_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=kn),
                                                                  ks=MatchMaker(algo="val", val=kn * POISSON))],
                                 [Law2_ScGeom_FrictPhys_CundallStrack(sphericalBodies=False)]),
                 newton((0, 0, -9.81), PILE_DAMPING)]
    O.dt = PILE_DT
    return ids, None


def build_pile_polyhedra(kv):
    O.reset()
    mat = O.materials.append(PolyhedraMat(density=DENSITY, young=2 * kv, poisson=POISSON,
                                          frictionAngle=math.atan(PILE_FRICTION)))
    add_walls(mat)
    ids = []
    for p, q in pile_layout():
        bd = polyhedra_utils.polyhedra(O.materials[mat], v=cube_vertices(PILE_H / 2))
        bd.state.pos = p
        bd.state.ori = q
        ids.append(O.bodies.append(bd))
    O.engines = [ForceResetter(),
                 InsertionSortCollider([Bo1_Polyhedra_Aabb(), Bo1_Wall_Aabb()], verletDist=0),
                 InteractionLoop([Ig2_Polyhedra_Polyhedra_PolyhedraGeom(), Ig2_Wall_Polyhedra_PolyhedraGeom()],
                                 [Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                                 [Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
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


def yade_contacts():
    return sum(1 for i in O.interactions if i.isReal)


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
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short runs (~30 s in all)")
    ap.add_argument("--repeat", type=int, default=None, help="timed runs per case, minimum taken (default 3, quick 1)")
    ap.add_argument("--markdown", metavar="FILE", help="append the tables and the command to FILE")
    ap.add_argument("--no-polyhedra", action="store_true", help="skip YADE Polyhedra (the slowest peer)")
    args = ap.parse_args(argv)
    repeat = args.repeat or (1 if args.quick else 3)
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: OMP_NUM_THREADS is not 1; YADE's loops may use several threads", file=sys.stderr)
    warnings.filterwarnings("ignore", message=r"NewtonIntegrator.damping")  # the pile damps all methods alike

    rows = []      # (scene, method, us/step, figures-string)
    parts_rows = []
    notes = []
    stiff = {}     # h -> peers' linear stiffness kn [N/m]

    # ---- scene 1: head-on collisions
    collisions = [(0.1, 60000), (0.3, 60000)]
    if args.quick:
        collisions = [(0.1, 60000), (0.3, 30000)]
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
                     "(LevelSet), kv = %.3g N/m^3 (Polyhedra)" % (h, dmax * 1e3, ncontact, kn, kv))

        def after_col(ids, extra, e0):
            return collision_figures(ids, e0)
        t, d, parts = sdem_breakdown(lambda mode: build_collision_sdem(h, mode), steps, repeat, after_col)
        rows.append((scene, "mpmsdem SDEM", t, d))
        parts_rows.append((scene, t, parts, d.get("warnings", 0)))
        t, d = measure(lambda: build_collision_levelset(h, kn), steps, repeat, after_col)
        rows.append((scene, "YADE LevelSet", t, d))
        if not args.no_polyhedra:
            t, d = measure(lambda: build_collision_polyhedra(h, kv), steps, repeat, after_col)
            rows.append((scene, "YADE Polyhedra", t, d))
        # the contact phase alone (the free flight above is mostly overhead): start 0.1 mm apart and
        # run as long as the longer of the SDEM contact and the peers' linear contact (pi sqrt(mu/kn)), +20 %;
        # short runs, so 3x as many repeats
        linear = math.pi * math.sqrt(m / 2 / kn) / 5e-6
        csteps = int(1.2 * max(ncontact, linear))
        cscene = "contact phase h=%.1f m (%d steps)" % (h, csteps)
        t, d, parts = sdem_breakdown(lambda mode: build_collision_sdem(h, mode, True), csteps, 3 * repeat,
                                     after_col)
        rows.append((cscene, "mpmsdem SDEM", t, d))
        parts_rows.append((cscene, t, parts, d.get("warnings", 0)))
        t, d = measure(lambda: build_collision_levelset(h, kn, True), csteps, 3 * repeat, after_col)
        rows.append((cscene, "YADE LevelSet", t, d))
        if not args.no_polyhedra:
            t, d = measure(lambda: build_collision_polyhedra(h, kv, True), csteps, 3 * repeat, after_col)
            rows.append((cscene, "YADE Polyhedra", t, d))

    # ---- scene 2: pile
    psteps = 1500 if args.quick else 5000
    scene = "pile 50 cubes (%d steps)" % psteps
    # peers' stiffness: that matched to SDEM in the collision of cubes of the same size
    knPile = stiff.get(PILE_H) or 2 * (0.5 * (DENSITY * PILE_H ** 3 / 2) * 4.0) / delta_max_sdem(PILE_H, 60000)[0] ** 2
    notes.append("pile: peers' kn = %.3g N/m (LevelSet), kv = %.3g N/m^3 (Polyhedra), as for h = %.1f m; "
                 "YADE Wall bodies for the peers' floor and walls; NewtonIntegrator damping %.1f for all; "
                 "dt %g s" % (knPile, knPile / PILE_H ** 2, PILE_H, PILE_DAMPING, PILE_DT))

    def after_sdem_pile(ids, extra, e0):
        return pile_figures(ids, sdem_pairs(extra))

    def after_peer_pile(ids, extra, e0):
        return pile_figures(ids, yade_contacts())
    t, d, parts = sdem_breakdown(build_pile_sdem, psteps, repeat, after_sdem_pile)
    rows.append((scene, "mpmsdem SDEM", t, d))
    parts_rows.append((scene, t, parts, d.get("warnings", 0)))
    t, d = measure(lambda: build_pile_levelset(knPile), psteps, repeat, after_peer_pile)
    rows.append((scene, "YADE LevelSet", t, d))
    if not args.no_polyhedra:
        # one run only: Polyhedra is by far the slowest here, its noise does not matter
        t, d = measure(lambda: build_pile_polyhedra(knPile / PILE_H ** 2), psteps, 1, after_peer_pile)
        rows.append((scene, "YADE Polyhedra", t, d))

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
