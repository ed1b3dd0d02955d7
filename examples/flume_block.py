#!/usr/bin/env python3
"""Paper §3.2: a copper cube in an inclined glass-bead flume (Table 1), MPM–SDEM coupled.

    yade -n -x examples/flume_block.py [--full] [--out DIR] [--duration T] [--dx DX]
                                       [--backend cpu|cuda] [--precision double|float]
                                       [--settings joint|table1] [--basal-friction MU] [--mu-2 MU] [--flow-friction MU]
                                       [--side-wall-friction MU] [--flip-viscosity NU]
    /usr/bin/python3 examples/flume_block.py ...          (same, without YADE's GUI shell)
    /usr/bin/python3 examples/flume_block.py --full --driver-scene flume.json   (scene for mpmsdem-run)
    /usr/bin/python3 examples/flume_block.py --from-driver DIR   (plot a finished mpmsdem-run from DIR)

Default: a coarse version (dx = 0.02 m, 12,000 material points, a few minutes on 2 cores).
``--full``: the paper's resolution (dx = 0.01 m, 8 points per cell, 96,000 material points).

The flow and friction settings (``--settings``, ``mpmsdem.flume.FLUME_SETTINGS``): with ``--full``
by default ``joint``, the set of our joint design at that resolution that tells the paper's story
(the cube pushed, turning through 45° near 0.72 s, no tumbling; docs/coupled-results.md); on the
coarse grid, where nothing was calibrated, Table 1's (``table1``). The options
``--basal-friction`` … ``--flip-viscosity`` change single values of the chosen set.

Two runs: first the free flow without the block (calibration: flow depth h_f and velocity v_f
at the block's station when the front arrives, Fr = v_f/√(g h_f), Fr1 = v_f/√(g L0)), then the
coupled run with the cube. Writes to ``--out`` (default ``results/flume_block``): the coupled
run's ``coupled.h5`` / ``sdem.h5`` / ``mpm/mpm.h5`` (h5py), ``scene.pvd`` (ParaView: particles
and the cube, and the flow's contact forces on it), ``flume_block.png`` (travel distance and
velocity; F_t with the hydrodynamic model of Eq 20 using α_f = 10.8 Fr^−1.3; F_f/F_t;
rotation), ``flume_block_faces.png`` (the flow's normal load on each face of the cube, CPU
backend) and ``summary.json``.
"""
import argparse
import json
import os
import sys
import time

import mpmsdem
import mpmsdem.driver
from mpmsdem import analysis
from mpmsdem.flume import FLUME_SETTINGS, GLASS_BEADS, Block, Flume
from mpmsdem.mpm import PAPER_VISCOSITY

HB = 0.02          # cube side h_b [m]
CUBE_REACH = HB * 3 ** 0.5 / 2  # its corners from its centre [m] (the sweep radius rounds them within that)
SETTING_OPTIONS = ("basal_friction", "mu_2", "flow_friction", "side_wall_friction", "flip_viscosity")
L0 = 0.21          # from the column front (the gate) to the cube's upstream face [m] (our reading of §3.2)
COLUMN = 0.3       # L_i [m]


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--full", action="store_true", help="paper resolution: dx 0.01 m, 96,000 material points")
    ap.add_argument("--dx", type=float, default=None, help="grid spacing [m] (default 0.02, --full 0.01)")
    ap.add_argument("--duration", type=float, default=None, help="coupled run [s] (default 1.2, --full 2.0)")
    ap.add_argument("--width", type=float, default=0.2,
                    help="flume width [m] (0.2, the experiment's); the cube stays on the centre line. Between smooth "
                         "side walls (--side-wall-friction 0, table1) a narrower flume is a slice of the wide one (0.1 m "
                         "gives the same cube motion at half the cost); with side-wall friction (joint: 0.111) it is a "
                         "different flume, the walls slow a narrow flow more (first touch 0.341 s at 0.1 m against "
                         "0.317 s at 0.2 m, dx 0.01 m): docs/coupled-results.md")
    ap.add_argument("--no-free-flow", action="store_true",
                    help="skip the run without the cube (the front's arrival, h_f, v_f, Fr and the Eq 20 line)")
    ap.add_argument("--out", default="results/flume_block", help="output folder")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    ap.add_argument("--precision", default="double", choices=("double", "float"))
    ap.add_argument("--no-plots", action="store_true", help="skip the PNG")
    ap.add_argument("--settings", choices=sorted(FLUME_SETTINGS), default=None,
                    help="named flow and friction set (mpmsdem.flume.FLUME_SETTINGS): joint (our joint design's, "
                         "calibrated at dx 0.01 m; the default with --full) or table1 (Table 1's; the default on the "
                         "coarse grid)")
    ap.add_argument("--basal-friction", type=float, default=None,
                    help="flow–bed friction, >= 0 (table1: 0.21, joint: 0.2778)")
    ap.add_argument("--mu-2", type=float, default=None,
                    help="the flow's maximum dynamic friction μ₂, > μ_s = %g (table1: 0.65, joint: 0.7221)"
                         % GLASS_BEADS["mu_s"])
    ap.add_argument("--flow-friction", type=float, default=None,
                    help="flow–cube friction, >= 0 (not in the paper; table1, our reading: 0.21, joint: 0.3938)")
    ap.add_argument("--side-wall-friction", type=float, default=None,
                    help="flow–side wall friction, >= 0 (0: smooth walls; table1: 0, joint: 0.111)")
    ap.add_argument("--flip-viscosity", type=float, default=None,
                    help="PIC viscosity of the flow's FLIP/PIC blend [m²/s] > 0 (joint: 0.0347053; table1: the "
                         "paper's, %g, with --full, the scene default, 0.005, on the coarse grid; docs/physics.md)"
                         % PAPER_VISCOSITY)
    ap.add_argument("--driver-scene", metavar="JSON", default=None,
                    help="write the coupled scene (with the cube, same O.dt) for the C++ driver mpmsdem-run to "
                         "JSON and exit (e.g. to run it on a GPU machine: mpmsdem-run JSON --backend cuda)")
    ap.add_argument("--from-driver", metavar="DIR", default=None,
                    help="plot and summarise a finished mpmsdem-run of this scene from its output folder DIR "
                         "(coupled.h5) instead of running; the Eq 20 line needs the free flow and is left out")
    a = ap.parse_known_args(argv)[0]
    if a.settings is None:
        a.settings = "joint" if a.full else "table1"
    for k in SETTING_OPTIONS:
        if getattr(a, k) is None:
            setattr(a, k, FLUME_SETTINGS[a.settings][k])
    return a


def copperCube(y=None, friction=0.67, flowFriction=0.21):
    """The §3.2 copper cube (h_b 0.02 m, ρ 8900, Table 1) with its upstream face L0 from the
    column front, on the flume's centre line unless ``y`` [m]; ``friction`` cube–bed (Table 1:
    0.67), ``flowFriction`` flow–cube (our reading: 0.21)."""
    return Block(half=(HB / 2,) * 3, x=COLUMN + L0, y=y, density=8900, friction=friction, flowFriction=flowFriction)


def flumeKeywords(a):
    """The flow's settings as Flume keywords: its FLIP/PIC blend (--flip-viscosity; by default
    the paper's, α 0.99 per its 5e-6 s step at dx 0.01 m, a PIC viscosity of 0.05 m²/s that
    keeps that flow at any --dx, with --full, and the scene default, 0.005 m²/s, on the coarse
    grid; docs/physics.md), μ₂, the basal and the side walls' friction. ValueError naming the
    option out of its range."""
    for name, value in (("--basal-friction", a.basal_friction), ("--flow-friction", a.flow_friction),
                        ("--side-wall-friction", a.side_wall_friction)):
        if not (value >= 0 and value < float("inf")):
            raise ValueError("%s = %r: must be >= 0 and finite" % (name, value))
    if not (a.mu_2 > GLASS_BEADS["mu_s"] and a.mu_2 < float("inf")):
        raise ValueError("--mu-2 = %r: must be > mu_s = %g (the mu(I) friction rises from mu_s to mu_2)"
                         % (a.mu_2, GLASS_BEADS["mu_s"]))
    kw = {"granular": dict(GLASS_BEADS, mu_2=a.mu_2), "basalFriction": a.basal_friction,
          "sideWallFriction": a.side_wall_friction}
    if a.flip_viscosity is not None:
        if not (a.flip_viscosity > 0 and a.flip_viscosity < float("inf")):
            raise ValueError("--flip-viscosity = %r m²/s: must be > 0 and finite" % (a.flip_viscosity,))
        kw["flipViscosity"] = a.flip_viscosity
    elif a.full:
        kw["flipViscosity"] = PAPER_VISCOSITY
    return kw


def settings(a):
    dx = a.dx or (0.01 if a.full else 0.02)
    duration = a.duration or (2.0 if a.full else 1.2)
    if not dx > 0:
        raise ValueError("--dx = %r m: must be > 0" % (dx,))
    return dx, duration


def freeFlow(dx, a, verbose=True):
    """The flume without the cube until the front has passed the cube's station."""
    station = COLUMN + L0
    scene = Flume(dx=dx, width=a.width, backend=a.backend, precision=a.precision, verbose=verbose, **flumeKeywords(a))
    probe = analysis.FlowProbe(station, halfWidth=dx, bedZ=0.0, L0=L0, window=0.05)
    from yade import O
    while True:
        mpmsdem.run(max(1, int(round(0.005 / O.dt))), scene.coupled)
        probe.sample(O.time, scene.mpm.particles())
        if probe.arrival is not None and O.time > probe.arrival + probe.window:
            break
        if O.time > 3.0:
            raise RuntimeError("free flow: the front did not reach x = %g m within 3 s" % station)
    return probe.result()


def coupled(dx, duration, a, out, verbose=True):
    cube = copperCube(flowFriction=a.flow_friction)
    scene = Flume(dx=dx, width=a.width, blocks=[cube], backend=a.backend, precision=a.precision, **flumeKeywords(a),
                  output=out, outputEvery=0.01,
                  vtkEvery=0.05, verbose=verbose)
    scene.run(duration, sampleEvery=0.002)
    return scene


def plot(s, title, ff, path):
    """The four panels of Figs 8–9 from a block series ``s`` (keys of :meth:`Flume.series`)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    t = s["t"]
    fig, ax = plt.subplots(2, 2, figsize=(11, 7))
    ax[0, 0].plot(t, s["travel"], label="travel distance S_b [m]")
    ax[0, 0].plot(t, s["vx"], label="velocity v_b [m/s]")
    ax[0, 0].set_xlabel("t [s]")
    ax[0, 0].legend()
    ax[0, 0].set_title("Block kinematics")
    smooth = lambda f: analysis.runningMean(t, f, 0.01)  # noqa: E731
    ax[0, 1].plot(t, analysis.meanForce(s, 0.01),
                  label="F_t (flow on block, downstream; from the %s)" % analysis.forceSource(s))
    ax[0, 1].plot(t, smooth(s["Ff"]), label="F_f (faces)", alpha=0.7)
    ax[0, 1].plot(t, smooth(s["Fe"]), label="F_e (edges, vertices)", alpha=0.7)
    if ff:
        A = min(ff["h_f"], HB) * HB
        Feq = analysis.hydrodynamicForce(1600.0, ff["v_f"], ff["h_f"], A)
        ax[0, 1].axhline(Feq, color="k", ls="--", label="Eq 20, α_f = 10.8 Fr^-1.3 (Fr = %.2f)" % ff["Fr"])
    ax[0, 1].set_xlabel("t [s]")
    ax[0, 1].set_ylabel("force [N] (10 ms mean)")
    ax[0, 1].legend(fontsize=8)
    ax[0, 1].set_title("Impact force")
    # the faces' share from the records alike (the impulse is kept for the whole block only)
    ratio = np.where(np.abs(smooth(s["Ft"])) > 1e-3, smooth(s["Ff"]) / np.where(smooth(s["Ft"]) == 0, 1, smooth(s["Ft"])),
                     np.nan)
    ax[1, 0].plot(t, ratio)
    ax[1, 0].set_ylim(-0.2, 1.2)
    ax[1, 0].set_xlabel("t [s]")
    ax[1, 0].set_ylabel("F_f / F_t")
    ax[1, 1].plot(t, s["rotation"], label="rotation (whole angle)")
    if "tilt" in s:
        ax[1, 1].plot(t, s["tilt"], "--", label="tilt (tipping)")
        ax[1, 1].plot(t, s["yaw"], ":", label="yaw (turning on the bed)")
        ax[1, 1].legend(fontsize=8)
    ax[1, 1].set_xlabel("t [s]")
    ax[1, 1].set_ylabel("angle [deg]")
    fig.suptitle(title)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.035 * title.count("\n")))  # room for a two-line title
    fig.savefig(path, dpi=90)


def plotFaces(s, title, path):
    """The flow's normal load on each face of the cube against time (10 ms means), with its tilt:
    which face the flow pushes, and whether any material rides on its top."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t, f = s["t"], s["faces"]
    smooth = lambda v: analysis.runningMean(t, v, 0.01)  # noqa: E731
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for label, v in (("upstream face (-x)", f["-x"]), ("top (+z)", f["+z"]), ("downstream face (+x)", f["+x"]),
                     ("sides (±y)", f["-y"] + f["+y"]), ("edges and corners", f["edges"])):
        ax.plot(t, smooth(v), label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("normal load F_n [N] (10 ms mean)")
    ax.legend(fontsize=8, loc="upper left")
    tilt = ax.twinx()
    tilt.plot(t, s["tilt"], "k:", label="tilt")
    tilt.set_ylabel("tilt [deg] (dotted)")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def blockEvents(s, duration):
    """The §3.2 targets of a cube's series (keys of Flume.series): first touch, F_t at 0.4 s (its
    mean over 0.395–0.405 s) and over 0.4–0.7 s (both from the impulse), rotation (and, where the
    series has them, tilt and yaw) at 0.4/0.5/0.7 s, when the rotation reaches 45°, the speed at
    the end (downstream: speed_end; of the centre: centre_speed_end), when it comes to rest for
    good (rest_time, None while still moving: :func:`mpmsdem.analysis.restTime`, no point of the
    cube faster than 1 cm/s from then on); the keys of calibrate_flume.flumeRun."""
    import numpy as np
    t, ft, rot = s["t"], s["Ft"], s["rotation"]
    touch = analysis.touchTime(s)
    turned = np.nonzero(rot >= 45.0)[0]
    out = {"first_touch": duration if touch is None else touch,
           "t45": float(t[turned[0]]) if len(turned) else duration,
           "rotation_deg": float(rot[-1]), "max_rotation_deg": float(rot.max()), "speed_end": float(abs(s["vx"][-1])),
           "centre_speed_end": float(s["speed"][-1]),
           "rest_time": analysis.restTime(t, s["speed"], rot, CUBE_REACH) if len(t) > 1 else None}
    if "tilt" in s:
        out.update(max_tilt_deg=float(s["tilt"].max()), max_yaw_deg=float(np.abs(s["yaw"]).max()))
    for label, at in (("04", 0.4), ("05", 0.5), ("07", 0.7)):
        if duration >= at:
            out["rotation_" + label] = float(np.interp(at, t, rot))
            if "tilt" in s:
                out["tilt_" + label] = float(np.interp(at, t, s["tilt"]))
    if duration >= 0.405:
        out["force_04"] = analysis.meanForceBetween(s, 0.395, 0.405)
    if duration >= 0.7:
        out["force_mean"] = analysis.meanForceBetween(s, 0.4, 0.7)
    return out


def restText(restTime, speedEnd):
    """When the cube came to rest, with the thresholds that define it, or its speed at the end."""
    if restTime is None:
        return "still moving at the end (centre %.3f m/s)" % speedEnd
    return "at rest from %.2f s (no point of it faster than %g m/s)" % (restTime, analysis.REST_SPEED)


def driverScene(dx, duration, a):
    """Write the coupled scene as the C++ driver's JSON (mpmsdem.driver.writeScene)."""
    from yade import O
    cube = copperCube(flowFriction=a.flow_friction)
    scene = Flume(dx=dx, width=a.width, blocks=[cube], backend=a.backend, precision=a.precision, verbose=False,
                  **flumeKeywords(a))
    mpmsdem.driver.writeScene(a.driver_scene, scene.coupled, duration=duration, dt=O.dt, outputDir=a.out,
                              outputEvery=0.05, seriesEvery=0.002)
    print("driver scene for the cube in the flume (dx %g m, %d material points, O.dt %.3g s, %g s) written to %s: "
          "mpmsdem-run %s" % (dx, scene.mpm.numParticles, O.dt, duration, a.driver_scene, a.driver_scene))


def fromDriver(a):
    """Plot and summarise a driver run of this scene (e.g. one made on a GPU machine)."""
    s, scene = analysis.driverBlockSeries(a.from_driver)
    import h5py
    with h5py.File(os.path.join(a.from_driver, "mpm.h5"), "r") as f:
        blend = f.attrs.get("flip_blend", "not recorded (written before the blend was recorded: alpha per step)")
    peak, tPeak = analysis.peakMeanForce(s, 0.01)
    summary = {"dx": scene["grid"]["dx"], "duration": float(s["t"][-1]), "travel": float(s["travel"][-1]),
               "peak_force": peak, "peak_time": tPeak, "rotation_deg": float(s["rotation"][-1]),
               "dt": scene["run"].get("dt"), "flip_blend": blend,
               "rest_time": analysis.restTime(s["t"], s["speed"], s["rotation"], CUBE_REACH)}
    with open(os.path.join(a.from_driver, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if not a.no_plots:
        plot(s, "Copper cube in a glass-bead flume (paper §3.2), dx = %g m, mpmsdem-run" % summary["dx"], None,
             os.path.join(a.from_driver, "flume_block.png"))
    print("copper cube after %.2f s (driver run in %s): travel distance %.4f m, rotation %.1f deg, %s; peak "
          "downstream impact force %.3f N (10 ms mean) at %.3f s; summary.json and flume_block.png written there"
          % (summary["duration"], a.from_driver, summary["travel"], summary["rotation_deg"],
             restText(summary["rest_time"], s["speed"][-1]), summary["peak_force"], summary["peak_time"]))
    return summary


def resolutionNote(dx):
    """What refinement measured of the cube's force at this run's cells per block height (the
    studies of docs/coupled-results.md, "The impact under grid refinement" and the wall's, through
    mpmsdem.tradeoffs): the arriving flow's depth error there (and the cube's touch, blow, plateau
    and tilt where they have a limit), which of them gave no limit to trust, how far a glued cube of this
    cube's height (the row nearest in height and cells per block height) is from its converged
    first blow at the nearest cells per block height measured, and how far a
    wall's converging first blow still is from its limit at the finest spacing measured."""
    from mpmsdem import tradeoffs
    cells = HB / dx
    p = tradeoffs.nearest("flow_depth", cells_per_block_height=cells)
    measured = sorted(q.settings["cells_per_block_height"] for q in tradeoffs.table("flow_depth")
                      if q.study["name"] == p.study["name"])
    note = ("resolution: the cube is %.1f cells tall (dx %g m). Refinement of this scene (%s) measured the arriving "
            "flow's depth %+.0f %% off its extrapolated limit at %.1f cells per block height" % (
                cells, dx, p.study["scene"].split("), ", 1)[-1], 100 * p.error, p.settings["cells_per_block_height"]))
    names = {"first_touch": "first touch", "block_peak_force": "first blow (10 ms mean)",
             "plateau_force": "plateau force", "tilt": "tilt"}
    loose = [n for o, n in names.items() if any("cells per block height" in w for w in tradeoffs.unconverged(o))]
    known = tradeoffs.outputs()
    for output, name in names.items():
        if name not in loose and output in known:
            q = tradeoffs.nearest(output, cells_per_block_height=cells)
            note += ", the %s %+.0f %% off its limit" % (name, 100 * q.error)
    if loose:  # the limits come from the three finest spacings
        note += "; the %s gave no limit to trust over %.1f to %.1f cells per block height" % (
            " and ".join([", ".join(loose[:-1])] * (len(loose) > 1) + loose[-1:]), measured[-3], measured[-1])
    try:  # a glued cube whose first blow converged: of this cube's height, at its nearest cells per block height
        glued = tradeoffs.nearest("glued_block_peak_force", block_height=HB, cells_per_block_height=cells)
    except ValueError:  # no study converged in it
        glued = None
    if glued:
        note += ("; a glued cube %g mm tall in a 20 deg flow took a first blow (10 ms mean) that converges, %+.0f %% "
                 "off its limit at %.1f cells per block height" % (
                     1e3 * glued.settings["block_height"], 100 * glued.error, glued.settings["cells_per_block_height"]))
    try:
        wall = [q for q in tradeoffs.table("peak_force") if "cells_per_flow_depth" in q.settings]
    except ValueError:  # no study converged in it
        wall = []
    if wall:
        finest = max(wall, key=lambda q: q.settings["cells_per_flow_depth"])
        note += ("; a wall's first blow converges from above, still %+.0f %% off its limit at %.1f cells per flow "
                 "depth" % (100 * finest.error, finest.settings["cells_per_flow_depth"]))
    return note + " (docs/coupled-results.md)"


def main(argv):
    a = parse(argv)
    if a.from_driver:
        return fromDriver(a)
    dx, duration = settings(a)
    if a.driver_scene:
        return driverScene(dx, duration, a)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    ff = None if a.no_free_flow else freeFlow(dx, a)
    tFree = time.time() - t0
    if ff:
        print("free flow at x = %.2f m: front at %.3f s, h_f = %.4f m, v_f = %.3f m/s, Fr = %.2f, Fr1 = %.2f"
              % (COLUMN + L0, ff["arrival"], ff["h_f"], ff["v_f"], ff["Fr"], ff["Fr1"]))
    t1 = time.time()
    scene = coupled(dx, duration, a, out)
    tCoupled = time.time() - t1
    peak, tPeak = scene.peakForce(0, smooth=0.01)
    s = scene.series(0)
    from yade import O
    summary = {"dx": dx, "width": a.width, "particles": scene.mpm.numParticles, "duration": duration, "dt": O.dt,
               "flip_blend": scene.flipBlend(), "free_flow": ff,
               "settings": dict({k: getattr(a, k) for k in SETTING_OPTIONS}, name=a.settings),
               "travel": scene.travel(0), "peak_force": peak, "peak_time": tPeak,
               "rotation_deg": float(s["rotation"][-1]), "tilt_deg": float(s["tilt"][-1]),
               "yaw_deg": float(s["yaw"][-1]), "events": blockEvents(s, duration),
               "eq20_force": analysis.hydrodynamicForce(1600.0, ff["v_f"], ff["h_f"], min(ff["h_f"], HB) * HB)
               if ff else None,
               "wall_seconds": {"free_flow": tFree, "coupled": tCoupled}, "timings": scene.coupled.timings()}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if not a.no_plots:
        names = {"basal_friction": "basal friction", "mu_2": "μ₂", "flow_friction": "flow–cube friction",
                 "side_wall_friction": "side-wall friction", "flip_viscosity": "PIC viscosity [m²/s]"}
        changed = ", ".join("%s %g" % (names[k], getattr(a, k)) for k in SETTING_OPTIONS
                            if getattr(a, k) != FLUME_SETTINGS[a.settings][k])
        changed = "settings %s%s" % (a.settings, ", with " + changed if changed else "")
        plot(scene.series(0), "Copper cube in a glass-bead flume (paper §3.2), dx = %g m, %d material points%s"
             % (scene.dx, scene.mpm.numParticles, "\n" + changed), ff,
             os.path.join(out, "flume_block.png"))
        if "faces" in s:
            plotFaces(s, "The flow's load on each face of the cube (its own frame), dx = %g m" % scene.dx,
                      os.path.join(out, "flume_block_faces.png"))
    print("copper cube after %.2f s: travel distance %.4f m, rotation %.1f deg (tilt %.1f, yaw %.1f), %s; peak "
          "downstream impact force %.3f N (10 ms mean) at %.3f s%s" % (
              duration, summary["travel"], summary["rotation_deg"], summary["tilt_deg"], summary["yaw_deg"],
              restText(summary["events"]["rest_time"], s["speed"][-1]), peak, tPeak,
              "; Eq 20: %.3f N" % summary["eq20_force"] if ff else ""))
    print(resolutionNote(dx))
    print("outputs in %s (coupled.h5, scene.pvd, flume_block.png, flume_block_faces.png, summary.json); wall time "
          "%.0f s + %.0f s"
          % (out, tFree, tCoupled))
    return summary


if __name__ == "__main__":  # also under `yade -x`, which runs scripts as __main__
    main(sys.argv[1:])
