#!/usr/bin/env python3
"""Check: paper §4.2, head-on collision of two equal sphero-cubes (h = 0.1 m and 0.3 m,
R = h/20, rho 3000, k_c 1e4, frictionless, elastic barrier), centroids 0.4 m apart, +-1 m/s,
dt 5e-6 s as in the paper.

The barrier is conservative and the contact patch is symmetric: each block must leave at
1 m/s (0.5 %), with no transverse velocity (< 1e-6 m/s) and no spin (< 1e-6 rad/s), and the
largest overlap must stay below R_i + R_j (cores never touch).

    /usr/bin/python3 scripts/checks/check_head_on.py
"""
import math
import sys

import mpmsdem
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner


def collide(h):
    O.reset()
    eng = mpmsdem.SdemEngine()
    mat = mpmsdem.material(density=3000, friction=0.0, barrierStiffness=1e4)
    a = eng.box((h / 2,) * 3, h / 20, mat, pos=(-0.2, 0, 0))
    b = eng.box((h / 2,) * 3, h / 20, mat, pos=(0.2, 0, 0))
    O.bodies[a].state.vel = (1, 0, 0)
    O.bodies[b].state.vel = (-1, 0, 0)
    peak = [0.0]
    import __main__
    __main__._peak = lambda: peak.__setitem__(0, max([peak[0]] + list(eng.contacts()["overlap"])))
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0),
                 PyRunner(command="_peak()", iterPeriod=10)]
    O.dt = 5e-6
    gap = 0.4 - h
    t_contact = gap / 2.0
    # run until the blocks have separated: contact lasts < 0.1 s for both sizes here
    mpmsdem.run(int((t_contact + 0.15) / O.dt), eng)
    va, vb = O.bodies[a].state.vel, O.bodies[b].state.vel
    wa, wb = O.bodies[a].state.angVel, O.bodies[b].state.angVel
    return dict(speedA=-va[0], speedB=vb[0], transverse=max(math.hypot(va[1], va[2]), math.hypot(vb[1], vb[2])),
                spin=max(wa.norm(), wb.norm()), peakOverlapOverR=peak[0] / (2 * h / 20),
                contactsLeft=len(eng.contacts()["overlap"]))


def main():
    failures = []
    print("%6s %10s %10s %12s %12s %10s" % ("h[m]", "speedA", "speedB", "transverse", "spin", "maxδ/R"))
    for h in (0.1, 0.3):
        r = collide(h)
        print("%6.2f %10.6f %10.6f %12.3e %12.3e %10.3f" % (h, r["speedA"], r["speedB"], r["transverse"], r["spin"],
                                                             r["peakOverlapOverR"]))
        for k in ("speedA", "speedB"):
            if abs(r[k] - 1.0) > 0.005:
                failures.append("h = %g: %s = %.6f m/s, must be 1 +- 0.5 %%" % (h, k, r[k]))
        if r["transverse"] >= 1e-6 or r["spin"] >= 1e-6:
            failures.append("h = %g: transverse %.3e m/s, spin %.3e rad/s (must be < 1e-6)" % (h, r["transverse"], r["spin"]))
        if not 0.05 < r["peakOverlapOverR"] < 1.0 or r["contactsLeft"]:
            failures.append("h = %g: peak overlap %.3f R, %d contacts left" % (h, r["peakOverlapOverR"], r["contactsLeft"]))
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("OK: elastic, straight, spin-free collisions")


if __name__ == "__main__":
    main()
