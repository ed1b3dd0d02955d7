#!/usr/bin/env python3
"""Validation probe (about a minute on one core): the energy of the two loose §3.3 blocks as YADE
LevelSet bodies (examples/liu2018_blocks.py --blocks levelset, Δx 0.01 m, 1 point per cell,
dtAuto 0.5) once the flow has let go of them. Samples every 5 steps the middle and top blocks'
energy (kinetic with rotation + m g z of the centre), their material-point contacts and their
YADE contacts; prints the energy of the two at ``--from`` and at the end, whether the flow
touched either after ``--from``, their highest centres after ``--from``, and the energy change
per kind of contact the blocks had in each sampled interval (flow, bed, other blocks, none).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/liu2018_levelset_energy.py
        [--ls-spacing 0.002] [--duration 1.0] [--from 0.3]

docs/coupled-results.md ("§4.1") quotes its output.
"""
import argparse
import importlib.util
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ls-spacing", type=float, default=0.002, help="level-set grid spacing [m] > 0 (0.002)")
    ap.add_argument("--duration", type=float, default=1.0, help="coupled run [s] > 0 (1.0)")
    ap.add_argument("--from", dest="start", type=float, default=0.3, help="start of the accounting [s] (0.3)")
    a = ap.parse_args(argv)
    if not (a.ls_spacing > 0 and a.duration > a.start >= 0):
        ap.error("--ls-spacing must be > 0 and 0 <= --from < --duration")
    import numpy as np
    import mpmsdem
    from yade import O
    spec = importlib.util.spec_from_file_location("liu2018_blocks", os.path.join(ROOT, "examples", "liu2018_blocks.py"))
    L = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(L)
    ex = L.parse(["--blocks", "levelset", "--ls-spacing", repr(a.ls_spacing)])
    s = L.scene(0.01, 1, ex, blocks=L.stackedBlocks(ex.flow_friction, L.levelSetOf(ex)), verbose=False)
    bed, ids = s.levelSetBedId, s.blockIds

    def energy(i):
        st = O.bodies[i].state
        w = st.ori.conjugate() * st.angVel
        return (0.5 * st.mass * st.vel.squaredNorm() + 0.5 * sum(st.inertia[k] * w[k] ** 2 for k in range(3))
                + st.mass * 9.81 * st.pos[2])

    rows = []  # t, then per loose block: energy, centre height, flow contacts, on the bed, YADE contacts
    while O.time < a.duration - 1e-12:
        mpmsdem.run(5, s.coupled)
        r = [O.time]
        for i in ids[1:]:
            others = [I.id1 + I.id2 - i for I in O.interactions.withBody(i) if I.isReal]
            r += [energy(i), O.bodies[i].state.pos[2], s.coupled.contactCount(i), int(bed in others), len(others)]
        rows.append(r)
    R = np.array(rows)
    t = R[:, 0]
    k0 = int(np.searchsorted(t, a.start))
    after = t[1:] > a.start
    e0 = R[k0, 1] + R[k0, 6]
    e1 = R[-1, 1] + R[-1, 6]
    print("LevelSet h %g mm: energy of the middle + top blocks %.4f J at %.3f s, %.4f J at %.3f s (%+.1f %%)"
          % (1e3 * a.ls_spacing, e0, t[k0], e1, t[-1], 100 * (e1 / e0 - 1)))
    for j, name in ((1, "middle"), (6, "top")):
        dE = np.diff(R[:, j])
        flow, onBed = R[1:, j + 2] > 0, R[1:, j + 3] > 0
        other = (R[1:, j + 4] - R[1:, j + 3]) > 0
        print("%s block: %.4f J -> %.4f J; flow contacts after %.2f s: %d; highest centre after it %.4f m"
              % (name, R[k0, j], R[-1, j], a.start, int(R[k0:, j + 2].max()), R[k0:, j + 1].max()))
        for label, m in (("flow only", flow & ~onBed & ~other), ("bed only", onBed & ~flow & ~other),
                         ("blocks only", other & ~flow & ~onBed), ("mixed", (flow.astype(int) + onBed + other) > 1),
                         ("no contact at the sample", ~flow & ~onBed & ~other)):
            print("  %-25s %5d intervals after %.2f s, energy change %+.4f J" % (label, (m & after).sum(), a.start,
                                                                               dE[m & after].sum()))


if __name__ == "__main__":
    main(sys.argv[1:])
