#!/usr/bin/env python3
"""Check: a coarse version of the paper's §3.3 scene (three stacked wooden blocks in the
Liu et al. 2018 horizontal flume, Table 2 materials, MPM–SDEM coupled in YADE) against stored
reference numbers.

Coarse scene (under a minute on one core): the full geometry of examples/liu2018_blocks.py
(flume 0.6 × 0.2 m, column 0.1 × 0.2 m, blocks 20 × 198 × 18 mm at x = 0.2 m, the bottom one
glued) at dx 0.02 m with 1 point per cell (500 material points), 0.5 s: the impact and the
loose blocks pushed downstream (the middle one by 0.12 m, the top one by 0.09 m).

Asserts (physics that cannot drift):
- the glued block never moves: its position is exactly the initial one at every sample;
- the flow's mass is the seeded mass, exactly;
- every block's position, velocity and orientation stay finite;
- the flow reaches the stack and pushes the loose blocks downstream (travel > 0).

Against the stored reference (scripts/checks/reference/liu2018_blocks.json), each within 1 %
(two-sided): the peak downstream force on the bottom block (the largest 10 ms mean, from the
impulse), the travel of the middle and the top block (the push itself, not the position, 0.21 m
at the start, so a stack that is not pushed fails). A run gives the same digits on any thread
count, and a build that rounds otherwise moves them by 1e-10 (docs/validation.md, "What the checks' bands let through"); the change of the blend in
7fe22ea moved the middle block's travel by 2 %, which the 25 % band of before let through.

    /usr/bin/python3 scripts/checks/check_liu2018_blocks.py [--regenerate]

``--regenerate`` stores the numbers of this run as the new reference (after a deliberate
change of the method; say why in the commit).
"""
import math
import os

import mpmsdem
from mpmsdem import analysis
from mpmsdem.flume import Block, Flume
from yade import O

HERE = os.path.dirname(os.path.abspath(__file__))
REF = os.path.join(HERE, "reference", "liu2018_blocks.json")
TOL = {"peak_force_bottom": 0.01, "travel_middle": 0.01, "travel_top": 0.01}
HALF, SWEEP, KC, RHO = (0.010, 0.099, 0.009), 0.0009, 1e4, 500.0
GRANULAR = {"density": 1300, "young_modulus": 5e4, "poisson_ratio": 0.40, "mu_s": math.tan(math.radians(22.0)),
            "mu_2": 0.60}


def blocks():
    # Seated at the barrier's equilibrium overlap, as in the example: exactly touching they
    # would rattle on the undamped barrier.
    w = RHO * 8 * HALF[0] * HALF[1] * HALF[2] * 9.81
    zMid = 2 * HALF[2] - analysis.equilibriumOverlap(w, SWEEP + 0.005, KC, 4) \
        - analysis.equilibriumOverlap(2 * w, 2 * SWEEP, KC, 4)
    zTop = zMid + 2 * HALF[2] - analysis.equilibriumOverlap(w, 2 * SWEEP, KC, 4)
    common = dict(half=HALF, x=0.2, sweepRadius=SWEEP, density=RHO, friction=0.60, flowFriction=0.13,
                  barrierStiffness=KC)
    return [Block(z=0.0, blockedDOFs="xyzXYZ", **common), Block(z=zMid, **common), Block(z=zTop, **common)]



def run():
    scene = Flume(inclineDeg=0.0, length=0.6, width=0.2, columnLength=0.1, columnHeight=0.2, dx=0.02, ppc=1,
                  granular=GRANULAR, basalFriction=0.13, blocks=blocks(), verbose=False)
    O.dt = min(O.dt, 4e-5)  # the block-block contact step (example's CONTACT_DT) before it is known
    # O.dt follows the coupled critical step and the blocks' approach step every step, as
    # examples/liu2018_blocks.py does: the middle block falling onto the bed at ~0.35 s enters
    # the barrier over several steps (at the flow's step, 3.2e-4 s, it went deep in one).
    scene.coupled.dtAuto = 0.5
    m0 = float(scene.mpm.particles()["mass"].sum())
    glued = O.bodies[scene.blockIds[0]].state
    p0, q0 = tuple(glued.pos), tuple(glued.ori[k] for k in range(4))
    moved, allFinite = 0, True
    end = 0.5
    nextSample = 0.002
    while O.time < end - 1e-12:
        n = max(1, min(10, int(math.ceil((end - O.time) / O.dt - 1e-9))))
        mpmsdem.run(n, scene.coupled)
        if O.time >= nextSample - 1e-12:
            scene.sample()
            nextSample += 0.002
        if tuple(glued.pos) != p0 or tuple(glued.ori[k] for k in range(4)) != q0:
            moved += 1
        allFinite = allFinite and all(analysis.stateIsFinite(O.bodies[i].state) for i in scene.blockIds)
    peak, tPeak = scene.peakForce(0, smooth=0.01)
    p = scene.mpm.particles()
    return {"peak_force_bottom": peak, "peak_time": tPeak,
            "travel_middle": scene.travel(1), "travel_top": scene.travel(2), "glued_moved": moved,
            "mass_error": abs(float(p["mass"].sum()) - m0), "finite": allFinite, "particles": scene.mpm.numParticles,
            "steps": O.iter}


def main():
    args = analysis.referenceCheckArguments(__doc__)
    r = run()
    print("liu2018 blocks (coarse §3.3): %d material points, %d steps; bottom block peak force %.3f N at %.3f s; "
          "travel middle %.4f m, top %.4f m" % (r["particles"], r["steps"], r["peak_force_bottom"], r["peak_time"],
                                                 r["travel_middle"], r["travel_top"]))
    failures = []
    if r["glued_moved"]:
        failures.append("the glued block moved (%d samples off its initial position/orientation)" % r["glued_moved"])
    if r["mass_error"] != 0:
        failures.append("flow mass changed by %g kg" % r["mass_error"])
    if not r["finite"]:
        failures.append("a block's state is not finite")
    if not (r["travel_middle"] > 0 and r["travel_top"] > 0 and r["peak_force_bottom"] > 0):
        failures.append("the flow did not push the stack (travel middle %g m, top %g m, peak %g N)"
                        % (r["travel_middle"], r["travel_top"], r["peak_force_bottom"]))
    failures += analysis.checkAgainstReference(r, REF, TOL, args.regenerate,
                                               stored=("peak_force_bottom", "peak_time", "travel_middle", "travel_top",
                                                       "particles"))
    analysis.finishCheck(failures)


main()
