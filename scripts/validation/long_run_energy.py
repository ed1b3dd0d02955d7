#!/usr/bin/env python3
"""Long-run energy check (opt-in, minutes; not part of `make test`): 10^6 SDEM steps of two
conservative scenes, with the total mechanical energy sampled every 1000 steps.

* rest: a frictionless 0.1 m cube (R = h/20, rho 3000, k_c 1e4, elastic barrier) dropped from
  0.5 mm above its resting overlap onto a fixed slab, with a small spin about x and z so that
  it bounces and rocks on its four corners for the whole run.
* rattle: the same cube in zero gravity inside a closed box of fixed slabs 2 cm wider than it,
  launched at 0.5 m/s along (3, 2, 1) with a spin: some 2400 elastic face, edge and corner
  impacts over the run (rotations of the cube included).

Both are conservative (frictionless, no damping), so the energy E = kinetic (translation and
rotation) + gravity + barrier potential (Eq 10) may only oscillate about its initial value
(the leapfrog is symplectic: no secular drift). Reported per scene: the largest |E - E0|, and
the drift, the difference of the mean energy over the last and the first 10 % of the samples,
both relative to the energy that moves (the kinetic energy at the start plus, for rest, the
drop m g 0.5 mm). Bounds (exit status 1 beyond them): drift below 1e-4 and oscillation below
1e-3 of that energy, the state finite. They are meant for the default 10^6 steps: with fewer
than ~10^5 (under 100 samples) the drift cannot be told from the oscillation.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/long_run_energy.py \
        [--steps 1000000] [--scene rest|rattle|both]
"""
import argparse
import math
import sys
import time

import numpy as np

import mpmsdem
from mpmsdem import analysis
from yade import O
from yade.minieigenHP import Quaternion, Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

H, RHO, KC = 0.1, 3000.0, 1e4
R = H / 20
DRIFT_BOUND, OSCILLATION_BOUND = 1e-4, 1e-3


class EnergyProbe:
    """Total energy at step n, second order in dt. After YADE's step n the bodies hold x(n+1)
    and v(n+1/2), while the engine's barrier energy is that of x(n), from which it computed the
    forces. So the probe keeps x(n+1) and v(n+1/2) after step n and completes the sample after
    step n+1: v(n+1) = (v(n+1/2) + v(n+3/2))/2, barrier of x(n+1) (a plain read-out at one
    step would mix three instants and show an O(dt) error)."""

    def __init__(self, eng, ids, g, every):
        self.eng, self.ids, self.g, self.every = eng, ids, g, every
        self.pending = None
        self.samples = []
        self.smallestCriticalStep = math.inf

    def __call__(self):
        self.smallestCriticalStep = min(self.smallestCriticalStep, self.eng.criticalTimeStep)
        if O.iter % self.every == 0:
            self.pending = [(Vector3(O.bodies[i].state.pos), Quaternion(O.bodies[i].state.ori),
                             Vector3(O.bodies[i].state.vel), Vector3(O.bodies[i].state.angVel)) for i in self.ids]
        elif self.pending is not None:
            e = self.eng.energies()["barrier"]
            for i, (x, q, v, w) in zip(self.ids, self.pending):
                s = O.bodies[i].state
                vm, wm = 0.5 * (v + s.vel), 0.5 * (w + s.angVel)
                wb = q.conjugate() * wm
                e += 0.5 * s.mass * vm.squaredNorm() + 0.5 * sum(s.inertia[k] * wb[k] ** 2 for k in range(3))
                e -= s.mass * self.g.dot(x)
            self.samples.append(e)
            self.pending = None


def rest():
    """Returns the engine, the moving ids, gravity, the moving energy, and the time step."""
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.0, barrierStiffness=KC, normalDamping=0.0)
    eng.box((0.5, 0.5, 0.05), R, mat, pos=(0, 0, -0.05), fixed=True)
    m = RHO * mpmsdem.SpheroPolyhedron.box((H / 2,) * 3, R).volume
    delta = analysis.equilibriumOverlap(m * 9.81, 2 * R, KC, contacts=4)
    cube = eng.box((H / 2,) * 3, R, mat, pos=(0, 0, H / 2 - delta + 5e-4))
    O.bodies[cube].state.angVel = (0.05, 0, 0.2)
    g = Vector3(0, 0, -9.81)
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=g, damping=0)]
    kn = analysis.barrierStiffness(delta, 2 * R, KC)
    s = O.bodies[cube].state
    moving = m * 9.81 * 5e-4 + 0.5 * sum(s.inertia[k] * s.angVel[k] ** 2 for k in range(3))
    return eng, [cube], g, moving, 0.05 * math.sqrt(m / (4 * kn))


def rattle():
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.0, barrierStiffness=KC, normalDamping=0.0)
    half = H / 2 + 0.01  # inner half-width of the box
    for axis in range(3):
        for side in (-1, 1):
            ext = [half + 0.05] * 3
            ext[axis] = 0.025
            pos = [0.0, 0.0, 0.0]
            pos[axis] = side * (half + 0.025)
            eng.box(tuple(ext), R, mat, pos=tuple(pos), fixed=True)
    cube = eng.box((H / 2,) * 3, R, mat, pos=(0, 0, 0), ori=Quaternion(Vector3(1, 1, 0).normalized(), 0.1))
    s = O.bodies[cube].state
    s.vel = Vector3(3, 2, 1).normalized() * 0.5
    s.angVel = (0.3, -0.2, 0.5)
    g = Vector3(0, 0, 0)
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=g, damping=0)]
    wb = s.ori.conjugate() * s.angVel
    moving = 0.5 * s.mass * s.vel.squaredNorm() + 0.5 * sum(s.inertia[k] * wb[k] ** 2 for k in range(3))
    # about 0.1 of the smallest critical step of the impacts (2e-3 s, corner first); the time
    # step check ("raise") would stop the run were it ever too large
    return eng, [cube], g, moving, 2e-4


def run(name, build, steps):
    O.reset()
    eng, ids, g, moving, dt = build()
    O.dt = dt
    probe = EnergyProbe(eng, ids, g, 1000)
    import __main__
    __main__._long_run_probe = probe
    O.engines = O.engines + [PyRunner(command="_long_run_probe()", iterPeriod=1)]
    t0 = time.time()
    mpmsdem.run(steps, eng)
    wall = time.time() - t0
    e = np.array(probe.samples)
    k = max(len(e) // 10, 1)
    drift = (e[-k:].mean() - e[:k].mean()) / moving
    osc = np.abs(e - e[0]).max() / moving
    s = O.bodies[ids[0]].state
    finite = all(math.isfinite(x) for v in (s.pos, s.vel, s.angVel) for x in v)
    return dict(scene=name, steps=O.iter, dt=dt, t=O.time, moving=moving, drift=drift, oscillation=osc,
                wall=wall, finite=finite, dtOverCritical=dt / probe.smallestCriticalStep)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=1000000)
    ap.add_argument("--scene", choices=("rest", "rattle", "both"), default="both")
    a = ap.parse_args()
    scenes = [("rest", rest), ("rattle", rattle)]
    if a.scene != "both":
        scenes = [s for s in scenes if s[0] == a.scene]
    failed = False
    print("%-7s %9s %9s %9s %9s %11s %11s %11s %8s" % ("scene", "steps", "dt [s]", "dt/dt_c", "t [s]", "E_moving[J]",
                                                        "drift/E_m", "max|dE|/E_m", "wall[s]"))
    for name, build in scenes:
        r = run(name, build, a.steps)
        print("%-7s %9d %9.3g %9.3g %9.4g %11.4g %11.3e %11.3e %8.1f" % (
            r["scene"], r["steps"], r["dt"], r["dtOverCritical"], r["t"], r["moving"], r["drift"], r["oscillation"],
            r["wall"]))
        if not (r["finite"] and abs(r["drift"]) < DRIFT_BOUND and r["oscillation"] < OSCILLATION_BOUND):
            failed = True
            print("  FAILED: drift must stay below %g and the oscillation below %g of E_moving, the state finite"
                  % (DRIFT_BOUND, OSCILLATION_BOUND))
    sys.stdout.flush()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
