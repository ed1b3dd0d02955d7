#!/usr/bin/env python3
"""Paper §3.3: three stacked wooden blocks in a horizontal flume (Liu et al. 2018 test, paper
Table 2), MPM–SDEM coupled.

    yade -n -x examples/liu2018_blocks.py [--full] [--out DIR] [--duration T] [--dx DX] [--ppc N]
                                          [--flip-alpha A] [--young E] [--backend cpu|cuda]
                                          [--precision double|float]
                                          [--blocks sdem|levelset] [--ls-spacing H] [--ls-nodes N]
                                          [--ls-kn K]
    /usr/bin/python3 examples/liu2018_blocks.py ...       (same, without YADE's GUI shell)

Scene (Table 2): horizontal flume 600 mm long, 200 mm wide; granular column 100 mm long ×
200 mm high, full width, at the upstream end; flow ρ 1300 kg/m³, φ 22° (μ_s = tan 22°), μ_2
0.60, E 50 kPa, ν 0.40, FLIP blend 0.99, basal friction 0.13. Three identical wooden blocks
20 (along the flume) × 198 (across) × 18 (high) mm, ρ 500 kg/m³, friction 0.60, barrier
stiffness 1e4 N/m, stacked; the bottom one glued to the bed (``blockedDOFs = "xyzXYZ"``).

Our readings where the paper leaves room:

- "stacked at 200 mm from the upstream end of the flume": the blocks' upstream face at
  x = 0.2 m from the flume's upstream end wall (x = 0, where the column's back rests), i.e.
  0.1 m downstream of the column front (the gate of the experiment).
- Flow–block friction: the paper gives one friction for the blocks (0.60) and one for the
  flow on the bed (0.13). As in the §3.2 example (flow–block = basal friction of the flow), the
  flow–block pair takes 0.13; ``--flow-friction`` changes it. Block–block and block–bed: 0.60.
- Resolution: the paper does not give its grid for §3.3; ``--full`` is dx = 0.01 m with 8 points
  per cell (32,000 material points), the resolution of its §3.2. The default is dx = 0.01 m with
  1 point per cell (4,000 points, material-point radius 6.2 mm against the 18 mm blocks; a
  few minutes on 2 cores).
- The stacked blocks start at the equilibrium overlap of the barrier law under the weight they
  carry (4 corner contacts per interface, as the narrow phase finds for two aligned faces):
  started exactly touching they would drop onto an undamped barrier (the paper's elastic law)
  and rattle by ~0.4 mm for the whole run.
- Time step: the block–block barrier contacts under the blocks' weight limit the step to about
  8e-5 s (rotation of the thin blocks), below the MPM step of the flow, and material points
  driven deep into the stiffening barrier at the impact lower it further (below 4e-5 s at
  dx = 0.01 m). The run starts at the smaller of half the MPM step and ``CONTACT_DT`` (the
  contact step is unknown before the first step), and the coupled engine then sets O.dt every
  step (``CoupledEngine(dtAuto=0.5)``): half the coupled critical step, and no more than lets a
  block move a tenth of its sweep radius, so that the middle block falling onto the bed enters
  the barrier over several steps (the glued bottom block is a fixed body and does not limit the
  step). The coupled engine stops the run if a step ever exceeds twice the critical step.

``--blocks levelset`` (paper §4.1: the same scene with level-set DEM blocks): the three blocks
are YADE ``LevelSet`` boxes of the same outer size (``yade.utils.levelSetBody("box", ...)``,
grid spacing ``--ls-spacing``, default 2 mm, and ``--ls-nodes`` boundary nodes, default the
paper's 602), the bottom one glued. The flow meets them through ``CoupledEngine(levelSets=...)``
with the SDEM run's flow–block friction and barrier stiffness (1e4 N/m); the flow still runs on
the SDEM bed. They meet each other through YADE's ``Ig2_LevelSet_LevelSet_ScGeom`` and the bed,
for them a YADE ``Wall`` at z = 0, through ``Ig2_Wall_LevelSet_ScGeom``, with
``Ip2_FrictMat_FrictMat_FrictPhys`` and ``Law2_ScGeom_FrictPhys_CundallStrack``: one linear
spring per pair of bodies (one contact point, the deepest boundary node), k_n = 1e4 N/m set
(``--ls-kn``)
directly (``MatchMaker`` of the Ip2 functor; the barrier's k_c, which the SDEM barrier exceeds
as it closes and shares among 4 corner contacts per interface), k_s = k_n/2.6 (the SDEM K_t at
ν 0.3), friction 0.60, no damping (as the SDEM barrier's). The upper blocks start at the
spring's equilibrium overlap (the weight carried over k_n). The coupled engine's ``dtAuto``
does not see these YADE contacts; the flume holds O.dt below 0.3 √(m/k_n) (0.57 ms for a block
at 1e4 N/m, above the flow's step: binding only for a stiffer ``--ls-kn``). They are not energy-conserving when a block rocks and slides on them
(docs/coupled-results.md, "§4.1: the §3.3 blocks as YADE LevelSet bodies"): loose blocks keep
bouncing where SDEM blocks come to rest. Not with ``--backend cuda`` or
``--precision float`` (the LevelSet coupling runs on the double-precision CPU solver only);
``coupled.h5`` and ``scene.pvd`` then hold the SDEM bed only, the force, travel and height
series of the blocks are in the PNG and summary.json as for SDEM blocks (no face/edge split).

Two runs: the free flow without blocks (h_f, v_f at the blocks' station when the front arrives,
for Eq 20), then the coupled run. Writes to ``--out`` (default ``results/liu2018_blocks``):
``coupled.h5``, ``sdem.h5``, ``mpm/mpm.h5``, ``scene.pvd`` (ParaView), ``liu2018_blocks.png``
(downstream flow force on each block, 10 ms mean, with Eq 20 for the bottom block; travel
distance and height of the middle and top blocks) and ``summary.json``. Prints the peak force
on the bottom block (paper: ≈ 9.7 N computed, 10.6 N from Eq 20), when the middle block falls
(paper: ~0.4 s) and when the flow first touches the top block (paper: ~0.5 s).
"""
import argparse
import json
import math
import os
import sys
import time

import mpmsdem
from mpmsdem import analysis
from mpmsdem.flume import Block, Flume
from mpmsdem.mpm import PAPER_VISCOSITY, flipReferenceArg

LENGTH, WIDTH = 0.6, 0.2                  # flume [m]
COLUMN_L, COLUMN_H = 0.1, 0.2             # L_i, H_i [m]
X_BLOCKS = 0.2                            # upstream face of the stack [m] (see the docstring)
HALF = (0.010, 0.099, 0.009)              # block outer half-extents [m]
RHO_FLOW, RHO_BLOCK = 1300.0, 500.0
KC = 1e4                                  # barrier stiffness [N/m]
SWEEP = HALF[2] / 10.0                    # R = h/20 of the smallest side, as Block's default
BED_SWEEP = 0.005                         # Flume's default bed R [m]
FREE_FLOW_LIMIT = 2.0                     # the free flow's time limit: a front later than this is an error [s]
CONTACT_DT = 4e-5                         # [s], see the docstring
CHUNK = 10                                # steps between sample checks in the coupled run
SMOOTH = 0.01                             # force averaging window [s]
FALL_DROP = HALF[2]                       # "fallen": centre half a block height below its start [m]
GRANULAR = {"density": RHO_FLOW, "young_modulus": 5e4, "poisson_ratio": 0.40,
            "mu_s": math.tan(math.radians(22.0)), "mu_2": 0.60}
NAMES = ("bottom", "middle", "top")
LS_SPACING, LS_NODES = 0.002, 602          # --blocks levelset defaults [m], boundary nodes per block
LS_KN = 1e4                               # YADE contact stiffness of the LevelSet blocks [N/m]


def lsContact(kn=LS_KN):
    """YADE's contact stiffnesses of the LevelSet blocks: k_n, and k_s = k_n/(2(1 + 0.3))."""
    return {"kn": kn, "ks": kn / (2 * (1 + 0.3))}


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--full", action="store_true", help="dx 0.01 m, 8 points per cell (32,000 material points)")
    ap.add_argument("--dx", type=float, default=None, help="grid spacing [m] (default 0.01)")
    ap.add_argument("--ppc", type=int, default=None, help="material points per cell (default 1, --full 8)")
    ap.add_argument("--duration", type=float, default=1.0, help="coupled run [s] (default 1.0)")
    ap.add_argument("--flow-friction", type=float, default=0.13, help="flow-block friction (default 0.13)")
    ap.add_argument("--young", type=float, default=GRANULAR["young_modulus"],
                    help="the flow's Young's modulus [Pa] (default Table 2's 5e4; > 0)")
    ap.add_argument("--flip-viscosity", type=float, default=None,
                    help="PIC viscosity of the flow's FLIP/PIC blend [m^2/s] > 0 (default: the scene default, 0.005; "
                         "with --full the paper's blend, 0.05)")
    ap.add_argument("--flip-alpha", type=float, default=None,
                    help="instead: the FLIP/PIC blend alpha of Eq 4, kept per --flip-reference-dt (0.99 if only that "
                         "is given)")
    ap.add_argument("--flip-reference-dt", type=flipReferenceArg, default=None,
                    help="with --flip-alpha: its reference step [s] > 0 (the paper's 5e-6 s: 2010 /s of PIC damping), "
                         "or 'step' (alpha per step, Eq 4 as written)")
    ap.add_argument("--out", default="results/liu2018_blocks", help="output folder")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    ap.add_argument("--precision", default="double", choices=("double", "float"))
    ap.add_argument("--no-plots", action="store_true", help="skip the PNG")
    ap.add_argument("--blocks", default="sdem", choices=("sdem", "levelset"),
                    help="the blocks as SDEM sphero-boxes (default) or YADE LevelSet boxes (paper §4.1)")
    ap.add_argument("--ls-spacing", type=float, default=LS_SPACING,
                    help="--blocks levelset: level-set grid spacing [m] > 0, at most the material points' radius "
                         "R_p0 (default %g)" % LS_SPACING)
    ap.add_argument("--ls-nodes", type=int, default=LS_NODES,
                    help="--blocks levelset: boundary nodes per block >= 8 (default the paper's %d)" % LS_NODES)
    ap.add_argument("--ls-kn", type=float, default=LS_KN,
                    help="--blocks levelset: YADE's normal contact stiffness of the blocks [N/m] > 0 (default %g; "
                         "k_s = k_n/2.6)" % LS_KN)
    a = ap.parse_known_args(argv)[0]
    if a.blocks == "levelset":
        if a.backend != "cpu":
            ap.error("--backend %s: --blocks levelset runs on the cpu backend only" % a.backend)
        if a.precision != "double":
            ap.error("--precision %s: --blocks levelset runs in double precision only" % a.precision)
        if not a.ls_spacing > 0:
            ap.error("--ls-spacing %r m: must be > 0" % a.ls_spacing)
        if a.ls_nodes < 8:
            ap.error("--ls-nodes %r: must be >= 8" % a.ls_nodes)
        if not a.ls_kn > 0:
            ap.error("--ls-kn %r N/m: must be > 0" % a.ls_kn)
    if a.flip_alpha is not None and a.flip_reference_dt is None:
        ap.error("--flip-alpha %g needs --flip-reference-dt (its reference step [s], or 'step')" % a.flip_alpha)
    if a.flip_viscosity is not None and (a.flip_alpha is not None or a.flip_reference_dt is not None):
        ap.error("--flip-viscosity: give it alone (--flip-alpha/--flip-reference-dt set the blend another way)")
    return a


def settings(a):
    dx = a.dx or 0.01
    ppc = a.ppc or (8 if a.full else 1)
    if not dx > 0:
        raise ValueError("--dx = %r m: must be > 0" % (dx,))
    if not a.duration > 0:
        raise ValueError("--duration = %r s: must be > 0" % (a.duration,))
    rp = analysis.pointRadius(dx, ppc)
    if getattr(a, "blocks", "sdem") == "levelset" and a.ls_spacing > rp:
        raise ValueError("--ls-spacing = %r m: must be at most the material points' radius R_p0 = %.4g m at dx %g m, "
                         "%d per cell" % (a.ls_spacing, rp, dx, ppc))
    return dx, ppc, a.duration


def stackedBlocks(flowFriction=0.13, levelSet=None, kn=LS_KN):
    """The three blocks, each upper one at the barrier's equilibrium overlap on the one below;
    with ``levelSet`` ({"spacing", "nSurfNodes"}) YADE LevelSet boxes, each upper one at the
    overlap of the linear spring ``kn`` [N/m] under the weight it carries."""
    weight = RHO_BLOCK * 8 * HALF[0] * HALF[1] * HALF[2] * 9.81
    if levelSet is not None:
        common = dict(half=HALF, x=X_BLOCKS, density=RHO_BLOCK, friction=0.60, flowFriction=flowFriction,
                      barrierStiffness=KC, levelSet=levelSet)
        zMiddle = 2 * HALF[2] - weight / kn - 2 * weight / kn  # Flume seats the bottom one W/k_n deep
        zTop = zMiddle + 2 * HALF[2] - weight / kn
        return [Block(z=0.0, blockedDOFs="xyzXYZ", **common), Block(z=zMiddle, **common), Block(z=zTop, **common)]
    zBottomTop = 2 * HALF[2] - analysis.equilibriumOverlap(weight, SWEEP + BED_SWEEP, KC, contacts=4)
    zMiddle = zBottomTop - analysis.equilibriumOverlap(2 * weight, 2 * SWEEP, KC, contacts=4)
    zTop = zMiddle + 2 * HALF[2] - analysis.equilibriumOverlap(weight, 2 * SWEEP, KC, contacts=4)
    common = dict(half=HALF, x=X_BLOCKS, sweepRadius=SWEEP, density=RHO_BLOCK, friction=0.60,
                  flowFriction=flowFriction, barrierStiffness=KC)
    # z = 0 makes Flume seat the bottom block on the bed at its own equilibrium overlap.
    return [Block(z=0.0, blockedDOFs="xyzXYZ", **common), Block(z=zMiddle, **common), Block(z=zTop, **common)]


def flipViscosity(a):
    """--flip-viscosity, or with --full and no other blend the paper's (docs/physics.md)."""
    if a.flip_viscosity is not None or a.flip_alpha is not None or a.flip_reference_dt is not None:
        return a.flip_viscosity
    return PAPER_VISCOSITY if a.full else None


def scene(dx, ppc, a, blocks=(), output=None, verbose=True):
    if not a.young > 0:
        raise ValueError("--young %r Pa: must be > 0" % (a.young,))
    s = Flume(inclineDeg=0.0, length=LENGTH, width=WIDTH, columnLength=COLUMN_L, columnHeight=COLUMN_H, dx=dx,
              ppc=ppc, granular=dict(GRANULAR, young_modulus=a.young), basalFriction=0.13, blocks=blocks, backend=a.backend, flipAlpha=a.flip_alpha,
              flipReferenceDt=a.flip_reference_dt, flipViscosity=flipViscosity(a),
              precision=a.precision, output=output, outputEvery=0.01, vtkEvery=0.05 if output else None,
              verbose=verbose, levelSetContact=lsContact(getattr(a, "ls_kn", LS_KN)))
    from yade import O
    O.dt = min(O.dt, CONTACT_DT)
    s.coupled.dtAuto = 0.5
    return s


def freeFlow(dx, ppc, a, verbose=True):
    """The flume without blocks until the front has passed the blocks' station."""
    from yade import O
    s = scene(dx, ppc, a, verbose=verbose)
    probe = analysis.FlowProbe(X_BLOCKS, halfWidth=dx, bedZ=0.0, L0=X_BLOCKS - COLUMN_L, window=0.05)
    while True:
        # the end is the front's passing, not known ahead: the progress line counts towards the limit
        mpmsdem.run(max(1, int(round(0.005 / O.dt))), s.coupled, endTime=FREE_FLOW_LIMIT, endIsBound=True)
        probe.sample(O.time, s.mpm.particles())
        if probe.arrival is not None and O.time > probe.arrival + probe.window:
            break
        if O.time >= FREE_FLOW_LIMIT:
            raise RuntimeError("free flow: the front did not reach x = %g m within %g s" % (X_BLOCKS, FREE_FLOW_LIMIT))
    return probe.result()


def runCoupled(s, duration, sampleEvery=0.002):
    """Scene.run with an adaptive O.dt and, per sample, the blocks' heights and MP contact counts
    in ``s.extra`` (and the smallest O.dt used in ``s.extra["dtMin"]``)."""
    from yade import O
    s.extra = {"z": [], "contacts": [], "dtMin": O.dt}
    end = O.time + duration
    nextSample = O.time + sampleEvery
    while O.time < end - 1e-12:
        mpmsdem.run(max(1, min(CHUNK, int(math.ceil((end - O.time) / O.dt - 1e-9)))), s.coupled, endTime=end)
        s.extra["dtMin"] = min(s.extra["dtMin"], O.dt)
        if O.time < nextSample - 1e-12 and O.time < end - 1e-12:
            continue
        nextSample += sampleEvery
        s.sample()
        s.extra["z"].append([O.bodies[i].state.pos[2] for i in s.blockIds])
        s.extra["contacts"].append([s.coupled.contactCount(i) for i in s.blockIds])


def events(s):
    """Peak smoothed force per block, the middle block's fall, the flow's first touch per block."""
    import numpy as np
    z = np.array(s.extra["z"])
    t = s.series(0)["t"]
    out = {}
    for k, name in enumerate(NAMES):
        peak, tPeak = s.peakForce(k, smooth=SMOOTH)
        out[name] = {"peak_force": peak, "peak_time": tPeak, "first_touch": analysis.touchTime(s.series(k)),
                     "travel": s.travel(k), "dz": float(z[-1, k] - z[0, k])}
    # after the impact transient: from 20 ms after the bottom block's peak to the end
    d = s.series(0)
    start = out["bottom"]["peak_time"] + 0.02
    out["bottom"]["mean_force_after"] = analysis.meanForceBetween(d, start, d["t"][-1]) \
        if start < d["t"][-1] else None
    fallen = np.nonzero(z[:, 1] < z[0, 1] - FALL_DROP)[0]
    out["middle"]["fall_time"] = float(t[fallen[0]]) if len(fallen) else None
    fallen = np.nonzero(z[:, 2] < z[0, 2] - FALL_DROP)[0]
    out["top"]["fall_time"] = float(t[fallen[0]]) if len(fallen) else None
    return out


def plot(s, ff, eq20, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    z = np.array(s.extra["z"])
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    for k, name in enumerate(NAMES):
        d = s.series(k)
        ax[0].plot(d["t"], analysis.meanForce(d, SMOOTH), label="%s block" % name)
    if ff:
        ax[0].axhline(eq20, color="k", ls="--", label="Eq 20, bottom block (Fr = %.2f)" % ff["Fr"])
    ax[0].axhline(9.7, color="grey", ls=":", label="paper §3.3, computed peak 9.7 N")
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("downstream flow force [N] (10 ms mean)")
    ax[0].legend(fontsize=8)
    for k in (1, 2):
        d = s.series(k)
        ax[1].plot(d["t"], d["travel"], label="%s block" % NAMES[k])
        ax[2].plot(d["t"], z[:, k] - HALF[2], label="%s block" % NAMES[k])
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("travel distance [m]")
    ax[1].legend()
    ax[2].set_xlabel("t [s]")
    ax[2].set_ylabel("bottom face height (centre − h/2) [m]")
    ax[2].legend()
    fig.suptitle("Stacked wooden blocks in the Liu et al. (2018) flume (paper §3.3), %s blocks, dx = %g m, "
                 "%d material points" % ("LevelSet" if s.levelSetIds else "SDEM", s.dx, s.mpm.numParticles))
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def levelSetOf(a):
    """--blocks levelset: the blocks' level-set grid ({"spacing", "nSurfNodes"}); else None."""
    return {"spacing": a.ls_spacing, "nSurfNodes": a.ls_nodes} if getattr(a, "blocks", "sdem") == "levelset" else None


def fmt(t):
    return "never" if t is None else "%.3f s" % t


def main(argv):
    a = parse(argv)
    dx, ppc, duration = settings(a)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    ff = freeFlow(dx, ppc, a)
    tFree = time.time() - t0
    area = min(ff["h_f"], 2 * HALF[2]) * 2 * HALF[1]
    eq20 = analysis.hydrodynamicForce(RHO_FLOW, ff["v_f"], ff["h_f"], area)
    print("free flow at x = %.2f m: front at %.3f s, h_f = %.4f m, v_f = %.3f m/s, Fr = %.2f; Eq 20 on the bottom "
          "block: %.2f N" % (X_BLOCKS, ff["arrival"], ff["h_f"], ff["v_f"], ff["Fr"], eq20))
    t1 = time.time()
    s = scene(dx, ppc, a, blocks=stackedBlocks(a.flow_friction, levelSetOf(a), a.ls_kn), output=out)
    runCoupled(s, duration)
    tCoupled = time.time() - t1
    ev = events(s)
    from yade import O
    summary = {"dx": dx, "ppc": ppc, "flip_blend": s.flipBlend(), "precision": a.precision,
               "particles": s.mpm.numParticles, "duration": duration,
               "dt_min": s.extra["dtMin"], "steps": O.iter,
               "blocks_kind": a.blocks, "level_set": levelSetOf(a),
               "yade_contact": lsContact(a.ls_kn) if a.blocks == "levelset" else None,
               "block_mass": [O.bodies[i].state.mass for i in s.blockIds],
               "block_ids": list(s.blockIds), "block_half": list(HALF),
               "flow_friction": a.flow_friction, "young_modulus": a.young, "free_flow": ff, "eq20_bottom": eq20, "blocks": ev,
               "paper": {"peak_force_bottom": 9.7, "eq20_bottom": 10.6, "middle_falls": 0.4, "top_hit": 0.5},
               "wall_seconds": {"free_flow": tFree, "coupled": tCoupled}, "timings": s.coupled.timings()}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if not a.no_plots:
        plot(s, ff, eq20, os.path.join(out, "liu2018_blocks.png"))
    b, m, tp = ev["bottom"], ev["middle"], ev["top"]
    print("bottom block (glued): peak downstream force %.2f N (10 ms mean) at %.3f s; Eq 20 %.2f N; paper 9.7 N "
          "computed, 10.6 N Eq 20" % (b["peak_force"], b["peak_time"], eq20))
    print("middle block: first touched %s, falls (centre %.0f mm down) %s, travel %.4f m; paper: falls ~0.4 s"
          % (fmt(m["first_touch"]), 1e3 * FALL_DROP, fmt(m["fall_time"]), m["travel"]))
    print("top block: first touched by the flow %s, falls %s, travel %.4f m; paper: hit ~0.5 s"
          % (fmt(tp["first_touch"]), fmt(tp["fall_time"]), tp["travel"]))
    print("outputs in %s (coupled.h5, scene.pvd, liu2018_blocks.png, summary.json); %d material points, %d steps, "
          "smallest O.dt %.3g s; wall time %.0f s + %.0f s" % (out, s.mpm.numParticles, O.iter, s.extra["dtMin"], tFree, tCoupled))
    return summary


if __name__ == "__main__" or "yade" in sys.argv[0]:
    main(sys.argv[1:])
