#!/usr/bin/env python3
"""Validation probe (opt-in, a minute or two): the §3.2 free flow's velocity and pressure
profiles at the cube's station. Runs the flume of examples/flume_block.py without the cube and
prints, at the given times, the flow's depth at the station, the front's position and, in 1 cm
layers above the bed (points within --reach upstream of the station), the mean downstream
velocity and the mean pressure -tr(sigma)/3 beside the lithostatic rho g cos(theta) (h - z)
of a layer at rest under the flow's depth h (rho the bulk density). A plug flow moves as one
(the layers' speeds equal); a sheared one is faster at the surface than at the bed.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/flume_velocity_profile.py [--dx 0.01]
        [--width 0.06] [--viscosity 0.0503] [--times 0.32,0.36,0.40,0.45] [--station 0.51]
        [--basal-friction 0.21]

Defaults: the paper's numerics (dx 0.01 m, its blend as a PIC viscosity of 0.0503 m²/s) in a
0.06 m slice of the flume (the flow is uniform across it between smooth walls).
docs/coupled-results.md quotes its output.
"""
import argparse
import sys


def parse(argv):
    from mpmsdem.mpm import PAPER_VISCOSITY
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] (0.01)")
    ap.add_argument("--width", type=float, default=0.06, help="flume width [m] (0.06)")
    ap.add_argument("--viscosity", type=float, default=PAPER_VISCOSITY,
                    help="PIC viscosity of the flow's blend [m^2/s] (the paper's: %.4g)" % PAPER_VISCOSITY)
    ap.add_argument("--basal-friction", type=float, default=0.21, help="flow-bed friction (0.21, Table 1)")
    ap.add_argument("--times", default="0.32,0.36,0.40,0.45", help="times of the profiles [s], increasing")
    ap.add_argument("--station", type=float, default=0.51, help="x of the station [m] (the cube's face: 0.51)")
    ap.add_argument("--reach", type=float, default=0.05, help="the points within this much upstream [m] (0.05)")
    a = ap.parse_args(argv)
    try:
        a.times = [float(t) for t in a.times.split(",")]
    except ValueError:
        ap.error("--times %r: must be comma-separated times [s]" % a.times)
    if not (a.times[0] > 0 and all(t1 > t0 for t0, t1 in zip(a.times, a.times[1:]))):
        ap.error("--times %r: must be positive and increasing" % a.times)
    if not (a.reach > 0 and a.station > a.reach):
        ap.error("--station %g, --reach %g: need station > reach > 0 [m]" % (a.station, a.reach))
    return a


def main(argv):
    import mpmsdem
    a = parse(argv)
    import numpy as np
    from mpmsdem.flume import GLASS_BEADS, Flume
    from yade import O
    scene = Flume(dx=a.dx, width=a.width, flipViscosity=a.viscosity, basalFriction=a.basal_friction, verbose=False)
    print("§3.2 free flow, dx %g m, width %g m, %d points, O.dt %.3g s, %s, basal friction %g; v_x [m/s] in 1 cm "
          "layers (height of the layer's middle [mm]: speed), points %g-%g m" % (
              a.dx, a.width, scene.mpm.numParticles, O.dt, scene.flipBlend(), a.basal_friction, a.station - a.reach,
              a.station))
    for t in a.times:
        mpmsdem.run(max(1, int(round((t - O.time) / O.dt))), scene.coupled)
        p = scene.mpm.particles()
        x, v = p["x"], p["v"]
        at = (x[:, 0] > a.station - a.reach) & (x[:, 0] < a.station)
        if at.sum() < 10:
            print("t %.3f s: the flow is not at the station yet (front %.3f m)" % (O.time, x[:, 0].max()))
            continue
        z, vx = x[at, 2], v[at, 0]
        pressure = -p["stress"][at, :3].sum(axis=1) / 3.0
        layers = []
        for lo in np.arange(0.0, z.max(), 0.01):
            w = (z >= lo) & (z < lo + 0.01)
            if w.sum() > 3:
                layers.append((lo + 0.005, vx[w].mean(), pressure[w].mean()))
        speeds = [s for _, s, _ in layers]
        print("t %.3f s: depth %.3f m, front %.3f m, top/bottom layer %.2f | %s" % (
            O.time, z.max(), x[:, 0].max(), speeds[-1] / speeds[0],
            " ".join("%.0f:%.2f" % (1000 * h, s) for h, s, _ in layers)))
        weight = GLASS_BEADS["density"] * -scene.mpm.gravity[2]  # the bed-normal part of the resolved gravity
        print("           pressure [Pa] (lithostatic) | %s" % " ".join(
            "%.0f:%.0f(%.0f)" % (1000 * h, q, weight * max(z.max() - h, 0.0)) for h, _, q in layers))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
