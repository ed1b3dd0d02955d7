#!/usr/bin/env python3
"""Validation probe (opt-in, minutes): how the flow meets the §3.2 copper cube. Runs the
coupled scene of examples/flume_block.py (the cube on the centre line, or --dy off it, set
--yaw0 degrees off face-on) and records every 2 ms the flow's force and torque on the cube
(torque about its centroid), its position, velocity, tilt and yaw, and the number of material
points touching it. Prints 20 ms means from the first touch on: the force F_x and F_z, the
height of the force's line of action relative to the centroid (T_y / F_x), tilt, yaw, the
cube's speed and centroid height; then the first touch, the impulse of the first 30 ms and the
speed 30 ms after the touch. Writes the series to --out (npz: t, pos, vel, force, torque, tilt,
yaw, contacts). At the first touch and every 4 ms for 20 ms after it, the state of the flow
within 6 cm upstream of the cube (and 3 cm either side of its centre): how many points, the
share of them gasified (stress-free), their mean density and mean pressure. With --faces, the
normal load of the flow on the cube's top face and on its upstream face in each 20 ms window:
F_n (Eq 10) of the contacts of the step (CoupledEngine.contacts()) whose core feature is that
face (contacts at edges and corners are left out; the tangential forces are not included).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/flume_impact_probe.py [--dx 0.01]
        [--width 0.2] [--duration 0.6] [--viscosity 0.0503] [--yaw0 0] [--dy 0] [--out FILE]
        [--ppc 8] [--young 1e6] [--flow-stiffness 1e4] [--dt-factor 0.5] [--blocked DOFS] [--faces]

Defaults: the paper's numerics (dx 0.01 m, its blend as a PIC viscosity of 0.0503 m²/s), the
0.2 m flume, 0.6 s. docs/coupled-results.md ("Why our cube tips") quotes its output.
"""
import argparse
import math
import os
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def parse(argv):
    from mpmsdem.mpm import PAPER_VISCOSITY
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] (0.01)")
    ap.add_argument("--width", type=float, default=0.2, help="flume width [m] (0.2; a slice: the cube is on its centre)")
    ap.add_argument("--duration", type=float, default=0.6, help="simulated time [s], > 0.35 (0.6)")
    ap.add_argument("--viscosity", type=float, default=PAPER_VISCOSITY,
                    help="PIC viscosity of the flow's blend [m^2/s] (the paper's: %.4g)" % PAPER_VISCOSITY)
    ap.add_argument("--yaw0", type=float, default=0.0, help="the cube's start off face-on, about the bed normal [deg]")
    ap.add_argument("--dy", type=float, default=0.0, help="the cube's offset from the centre line [m]")
    ap.add_argument("--ppc", type=int, default=8, help="material points per cell (8, the paper's)")
    ap.add_argument("--young", type=float, default=1e6, help="the flow's Young's modulus [Pa] (1e6, Table 1)")
    ap.add_argument("--flow-stiffness", type=float, default=1e4,
                    help="barrier stiffness k_c of the cube's contacts [N/m] (1e4, the paper's), bed and flow")
    ap.add_argument("--dt-factor", type=float, default=0.5,
                    help="O.dt as a fraction of the flow's stable step at the start (0.5; a softer flow needs less "
                         "to keep the contact step)")
    ap.add_argument("--blocked", default="",
                    help="the cube's blocked degrees of freedom (YADE's blockedDOFs): xyzXYZ holds it in place (the "
                         "flow's force on a cube it does not move), XYZ lets it slide without turning")
    ap.add_argument("--faces", action="store_true",
                    help="the flow's normal load on the cube's top and upstream faces (from the step's contacts)")
    ap.add_argument("--out", default=os.path.join("results", "flume_impact_probe.npz"), help="series file (npz)")
    a = ap.parse_args(argv)
    if not a.duration > 0.35:
        ap.error("--duration %g s: must be > 0.35 (the flow reaches the cube at about 0.3 s)" % a.duration)
    if not abs(a.dy) < a.width / 2 - 0.01:
        ap.error("--dy %g m: the cube must stay inside the flume (|dy| < width/2 - 0.01 m)" % a.dy)
    return a


def upstreamState(scene, x0, yc):
    """(t, points, gasified share, mean density [kg/m³], mean pressure [Pa]) of the flow within
    6 cm upstream of x0 (and 2.5 cm past it) and 3 cm either side of yc."""
    import numpy as np
    p = scene.mpm.particles()
    x = p["x"]
    m = (x[:, 0] > x0 - 0.06) & (x[:, 0] < x0 + 0.025) & (np.abs(x[:, 1] - yc) < 0.03)
    pressure = -p["stress"][m, :3].sum(axis=1) / 3.0
    return (scene.mpm.time, int(m.sum()), float((p["phase"][m] == 2).mean()), float(p["density"][m].mean()),
            float(pressure.mean()))


def main(argv):
    import mpmsdem
    a = parse(argv)
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import numpy as np
    from flume_block import copperCube
    from mpmsdem.analysis import boxFaceLoads, tiltAndYaw
    from mpmsdem.flume import Flume
    from yade import O
    from yade.minieigenHP import Quaternion, Vector3
    from mpmsdem.flume import GLASS_BEADS
    cube = copperCube(y=a.width / 2 + a.dy)
    cube.barrierStiffness = a.flow_stiffness
    cube.blockedDOFs = a.blocked
    scene = Flume(dx=a.dx, width=a.width, blocks=[cube], flipViscosity=a.viscosity, verbose=False, ppc=a.ppc,
                  granular=dict(GLASS_BEADS, young_modulus=a.young), dtFactor=a.dt_factor)
    body = scene.blockIds[0]
    if a.yaw0:
        O.bodies[body].state.ori = Quaternion(Vector3(0, 0, 1), math.radians(a.yaw0))
    mass = O.bodies[body].state.mass
    every = max(1, int(round(0.002 / O.dt)))
    rows, upstream, touch = [], [], None
    while O.time < a.duration - 0.5 * O.dt:
        mpmsdem.run(every, scene.coupled)
        st = O.bodies[body].state
        f, t = scene.coupled.force(body), scene.coupled.torque(body)
        if touch is None and f[0] != 0:
            touch = O.time
        if touch is not None and round((O.time - touch) / 0.002) in (0, 2, 4, 6, 8, 10):
            upstream.append(upstreamState(scene, cube.x, st.pos[1]))
        tilt, yaw = tiltAndYaw(*st.ori.toAngleAxis())
        if a.faces:
            loads = boxFaceLoads(scene.coupled.contacts(body), st.ori.toRotationMatrix())
            faces = (loads["+z"], loads["-x"])
        else:
            faces = (0.0, 0.0)
        rows.append([O.time, *st.pos, *st.vel, *f, *t, tilt, yaw, scene.coupled.contactCount(body), *faces])
    r = np.array(rows)
    s = {"t": r[:, 0], "pos": r[:, 1:4], "vel": r[:, 4:7], "force": r[:, 7:10], "torque": r[:, 10:13],
         "tilt": r[:, 13], "yaw": r[:, 14], "contacts": r[:, 15], "top_load": r[:, 16], "upstream_load": r[:, 17]}
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    np.savez(a.out, **s)
    t, fx = s["t"], s["force"][:, 0]
    print("§3.2 cube, dx %g m, width %g m, %d material points (%d per cell), E %g Pa, k_c %g N/m, O.dt %.3g s, %s; "
          "yaw0 %g deg, dy %g m%s" % (a.dx, a.width, scene.mpm.numParticles, a.ppc, a.young, a.flow_stiffness, O.dt,
                                    scene.flipBlend(), a.yaw0, a.dy, ", blockedDOFs " + a.blocked if a.blocked else ""))
    print("  the flow 6 cm upstream:  t [s]  points  gasified  density [kg/m3]  pressure [Pa]")
    for u in upstream:
        print("                         %.3f  %6d  %8.2f  %15.0f  %13.0f" % u)
    touched = np.nonzero(np.abs(fx) > 0)[0]
    if not len(touched):
        print("the flow did not touch the cube by %g s" % a.duration)
        return 1
    t0 = t[touched[0]]
    print("  t [s]   F_x [N]  F_z [N]  line of action [mm]  tilt [deg]  yaw [deg]  v_x [m/s]  z_c [mm]  points%s"
          % ("  top face [N]  upstream face [N]" if a.faces else ""))
    for lo in np.arange(t0 - 0.01, t[-1], 0.02):
        w = (t >= lo) & (t < lo + 0.02)
        if not w.any():
            continue
        Fx, Fz, Ty = s["force"][w, 0].mean(), s["force"][w, 2].mean(), s["torque"][w, 1].mean()
        print("  %.3f  %7.3f  %7.3f  %19s  %10.1f  %9.2f  %9.2f  %8.1f  %6.0f%s"
              % (lo, Fx, Fz, "%.1f" % (1e3 * Ty / Fx) if Fx else "-", s["tilt"][w].mean(), s["yaw"][w].mean(),
                 s["vel"][w, 0].mean(), 1e3 * s["pos"][w, 2].mean(), s["contacts"][w].mean(),
                 "  %12.3f  %17.3f" % (s["top_load"][w].mean(), s["upstream_load"][w].mean()) if a.faces else ""))
    w = (t >= t0) & (t <= t0 + 0.03)
    after = int(np.argmin(np.abs(t - t0 - 0.03)))
    print("first touch %.3f s; impulse of the first 30 ms %.4f N s (the cube's mass times its speed then: %.4f); "
          "largest 2 ms force %.2f N; speed 30 ms after the touch %.2f m/s"
          % (t0, np.trapz(fx[w], t[w]), mass * s["vel"][after, 0], fx[w].max(), s["vel"][after, 0]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
