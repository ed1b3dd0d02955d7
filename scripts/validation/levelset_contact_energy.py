#!/usr/bin/env python3
"""Validation probe (a few seconds a case): energy of one §3.3 wooden block (20 × 198 × 18 mm,
500 kg/m³) as a YADE LevelSet box on a YADE Wall, with the contact settings of the flume's
LevelSet blocks (mpmsdem.flume.Flume, ``levelSetContact`` default: Ig2_Wall_LevelSet_ScGeom,
Ip2_FrictMat_FrictMat_FrictPhys with k_n 1e4 N/m, k_s k_n/2.6, friction 0.60,
Law2_ScGeom_FrictPhys_CundallStrack, no damping), no flow. The block starts with its centre
30 mm above the wall, tilted about an axis, and either dropped from rest or thrown (0.5 m/s
along x, spin (3, 0, 5) rad/s). Prints its energy (kinetic with rotation + m g z of the
centre) over that at the start, after ``--duration`` s, at each step ``--dt``.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/levelset_contact_energy.py
        [--dt 1e-4,1e-5] [--duration 1.0]

A dropped block keeps its energy (the spring is elastic, friction does no work without
sliding); a thrown one slides and rocks on one contact point (the deepest boundary node) that
jumps across its face, and need not. docs/coupled-results.md ("§4.1") quotes its output.
"""
import argparse
import math
import sys

HALF = (0.010, 0.099, 0.009)
CASES = (("dropped flat", 0.0, (1, 0, 0), False), ("dropped, tilted 0.5 deg about x", 0.5, (1, 0, 0), False),
         ("dropped, tilted 10 deg about (1,1,0)", 10.0, (1, 1, 0), False),
         ("thrown, tilted 5 deg about x", 5.0, (1, 0, 0), True))


def energyRatio(dt, tiltDeg, axis, thrown, duration=1.0, kn=1e4):
    """The block's energy after ``duration`` over its energy at the start."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade import O, utils
    from yade.minieigenHP import Quaternion, Vector3
    from yade.wrapper import (Bo1_LevelSet_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Wall_LevelSet_ScGeom,
                              InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                              Law2_ScGeom_FrictPhys_CundallStrack, MatchMaker, NewtonIntegrator)
    O.reset()
    mat = O.materials.append(FrictMat(density=500.0, frictionAngle=math.atan(0.6)))
    O.bodies.append(utils.wall(0.0, axis=2, material=mat))
    b = O.bodies.append(utils.levelSetBody("box", center=(0.2, 0.1, 0.03), extents=HALF, spacing=0.002,
                                           nSurfNodes=602, material=mat,
                                           orientation=Quaternion(Vector3(*axis).normalized(), math.radians(tiltDeg))))
    ip2 = Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=kn), ks=MatchMaker(algo="val", val=kn / 2.6))
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_LevelSet_Aabb(), Bo1_Wall_Aabb()], verletDist=0.001),
                 InteractionLoop([Ig2_Wall_LevelSet_ScGeom()], [ip2], [Law2_ScGeom_FrictPhys_CundallStrack()]),
                 NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = dt
    s = O.bodies[b].state
    if thrown:
        s.vel, s.angVel = Vector3(0.5, 0, 0), Vector3(3, 0, 5)

    def energy():
        w = s.ori.conjugate() * s.angVel
        return (0.5 * s.mass * s.vel.squaredNorm() + 0.5 * sum(s.inertia[k] * w[k] ** 2 for k in range(3))
                + s.mass * 9.81 * s.pos[2])
    e0 = energy()
    O.run(int(round(duration / dt)), True)
    return energy() / e0


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dt", default="1e-4,1e-5", help="steps [s], comma-separated, each > 0")
    ap.add_argument("--duration", type=float, default=1.0, help="[s] > 0 (1.0)")
    a = ap.parse_args(argv)
    try:
        steps = [float(x) for x in a.dt.split(",")]
    except ValueError:
        ap.error("--dt %r: must be comma-separated steps [s]" % a.dt)
    if not all(x > 0 for x in steps) or not a.duration > 0:
        ap.error("--dt and --duration must be > 0")
    print("| case | " + " | ".join("E/E0 at %g s, dt %g s" % (a.duration, x) for x in steps) + " |")
    print("|---|" + "---:|" * len(steps))
    for name, tilt, axis, thrown in CASES:
        print("| %s | %s |" % (name, " | ".join("%.3f" % energyRatio(x, tilt, axis, thrown, a.duration) for x in steps)),
              flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
