#!/usr/bin/env python3
"""Validation (opt-in, a few minutes a case on two cores): dry granular flows down the flume
striking a rigid wall across the whole width and a glued block, over a range of Froude numbers,
against the models of the impact force that do not come from a simulation.

Each case is the flume of §3.2 (the column of glass beads 0.3 m long and 0.2 m tall, the joint
set's flow and basal friction and PIC viscosity) at an incline θ, in a slice of the width with
frictionless side walls (a flow that is two-dimensional, as the wall spans it), with the
obstacle's upstream face L0 from the column front. Three driver runs (mpmsdem-run; the scenes are
built with YADE):

- **free**: no obstacle; the driver's flow probe at the station gives the arriving flow's h_f and
  v_f (means over the 50 ms after the front's arrival, over a 2 cm window) and Fr = v_f/√(g h_f)
  (the paper's definition), Fr′ = v_f/√(g cosθ h_f) (the theories');
- **wall**: a glued box across the whole width, 0.15 m tall, 2 cm thick: the flow's downstream
  force on it (10 ms means, from the recorded impulse: every step's force) and its peak F_peak (and
  the largest 20 ms mean, as §3.3's blow is read); at the end (the run lasts until 1 s after
  the free flow's arrival, the deposit then at rest: the flow's kinetic energy is given) the mean
  force F_end over the last 0.1 s, the deposit's depth h_d against the wall (its highest point
  within 2 cm upstream) and the coefficient k_end = F_end / (½ ρ g cosθ h_d² w);
- **block** (not by default): the §3.2 copper cube (h_b 0.02 m; another size with --block-size)
  glued at the same station on the centre line of a lane five cubes wide (frictionless sides: a row
  of cubes 0.1 m apart; another width with --lane): its F_peak.

The numbers set beside them: α = F_peak/(ρ v_f² h_f w) for the wall, against the reflected
bore that a wall sends into a steady flow (mass and momentum across a jump, material at rest
behind it; analysis.reflectedBoreForce, k 1) and against the design guides' superposition α ρ v²
h w + ½ k ρ g cosθ h² w with α = k = 1 (analysis.wallSuperposedForce); for the block, α_f =
F_peak/(ρ v_f² A) with A its face below h_f, against Eq 20 (α_f = 10.8 Fr^−1.3); and F_peak/F_static
for both with F_static = ½ ρ g h_f A (Eq 21's, k 1).

    OMP_NUM_THREADS=2 /usr/bin/python3 scripts/validation/impact_walls.py --out results/impact_walls \\
        [--incline 10,20,25,30,35] [--L0 0.5] [--dx 0.01] [--width 0.04] [--young E] [--cases free,wall,block] [--rest 1]
    /usr/bin/python3 scripts/validation/impact_walls.py --out results/impact_walls --report-only

On a machine with a GPU and no YADE (scripts/bench/gpu_run.sh --walls DIR): ``--prepare`` writes
the cases' scenes here, ``--run-prepared DIR --exe PATH --backend cuda`` runs them there (the free
flows first; a wall's deposit read there, where the snapshot is), and the first command again,
without ``--prepare``, reads them here. An obstacle's run lasts until --rest after its free flow's
arrival: prepared with its free flow in the same call, it takes that arrival where both run.

Each case's numbers go to OUT/<case>.json when it ends and finished cases are not run again; a
run that was interrupted continues from its last snapshot (every 0.1 s);
the table of all finished cases is printed and written to OUT/impact_walls.md, the figure
(α and F_peak/F_static against Fr, beside the models) to OUT/impact_walls.png, and for each
obstacle run at three spacings or more its blow over windows of 2 to 40 ms against Δx (each
window's limit where one is to trust, else a bracket: :func:`refinement`) to
OUT/impact_walls_refinement.md.
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flume_convergence import (CUBE, SERIES_EVERY, STATION_HALF, addPreparedOptions, commit, driverRun,  # noqa: E402
                               fmt, limitOf, partNames, runPreparedFolders, storeStudy, wholeCellsError,
                               windowLimits, writeJson)

COLUMN = 0.3              # the column's length along the flume [m] (§3.2)
WALL = (0.01, 0.075)      # the wall's half thickness along the flume and half height [m]
BLOW = 0.01               # window of the mean force for its peak [s]
BLOW_LONG = 0.02          # a longer one, as §3.3's blow is read (liu2018_force.py): the 10 ms peak of a cube
                          # falls with Δx where its 20 ms one converges [s]
WINDOWS = (0.002, 0.005, 0.01, 0.02, 0.04)  # the blow read over each of these too, for the refinement report [s]
LATER = (0.03, 0.07)      # after the first blow: the mean force over this window after the first touch [s], for
                          # the reflected bore's quasi-steady load
REST = 1.0                # by default an obstacle's run lasts this long after the free flow's arrival [s] (--rest)
END = 0.1                 # F_end: mean over the run's last END seconds [s]
DEPOSIT = 0.02            # h_d: the highest point within this distance upstream of the wall [m]
FLUME_BEYOND = 0.3        # the flume goes on this far past the station [m]: its end wall sends nothing back
                          # into the probe's 50 ms
RESTART_EVERY = 0.1       # a run saves a snapshot (a restart point) this often [s]
FREE_DURATION = 3.0       # the free flow's run at most [s] (it stops when the probe has read the front)
RHO = 1600.0              # the flow's bulk density [kg/m³] (the glass beads' of Table 1)
G = 9.81


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--incline", default="10,20,25,30,35", help="flume inclines θ [deg], comma-separated, in (0, 60)")
    ap.add_argument("--L0", type=float, default=0.5, help="the obstacle's upstream face from the column front [m] > 0")
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] > 0 (must divide --width)")
    ap.add_argument("--width", type=float, default=0.04, help="the wall's flume: width [m] > 0 (frictionless sides)")
    ap.add_argument("--young", type=float, default=None,
                    help="the flow's Young's modulus E [Pa] > 0 (default: the glass beads' of Table 1, 1e6): the "
                         "elastic wave speed √(E/ρ) sets how hard a front strikes")
    ap.add_argument("--rest", type=float, default=REST,
                    help="an obstacle's run lasts this long after the free flow's arrival [s] > 0.1 (default %g: the "
                         "deposit then at rest, for the wall's F_end and k_end; the first blow and the 30–70 ms "
                         "need 0.1)" % REST)
    ap.add_argument("--cases", default="free,wall", help="which runs: free, wall, block (comma-separated; "
                    "the block needs two cells per --block-size or more: the §3.2 cube Δx 0.01 m or finer)")
    ap.add_argument("--block-size", type=float, default=CUBE,
                    help="the glued cube's edge h_b [m] > 0 (default %g: the §3.2 cube); a bigger cube has more "
                         "cells per block height at the same Δx" % CUBE)
    ap.add_argument("--lane", type=float, default=None,
                    help="the block's lane: width [m], at least twice --block-size (default: five cubes wide, "
                         "rounded up to whole cells)")
    ap.add_argument("--step-factor", type=float, default=1.0,
                    help="the step as a fraction of the flume's own at --dx, in (0, 1] (default 1): at one Δx, "
                         "whether a number follows the step or the grid (the flume's step shrinks with Δx)")
    ap.add_argument("--out", default="results/impact_walls", help="folder of the runs")
    ap.add_argument("--package-data", action="store_true",
                    help="store the refinement of each wall and glued cube (three spacings of one obstacle, one of "
                         "them 0.01 m) in py/mpmsdem/tradeoffs.json (mpmsdem.tradeoffs: errors against the "
                         "extrapolated limit)")
    ap.add_argument("--study", default=None,
                    help="a folder of §5 cases (examples/parametric_study.py's JSON files, e.g. docs/data/study_s5) "
                         "drawn beside the runs on the figure's F_peak/F_static panel")
    ap.add_argument("--report-only", action="store_true",
                    help="only print and write the table of finished runs (read again from their outputs)")
    addPreparedOptions(ap, "a wall's deposit at the end")
    ap.add_argument("--child", nargs=3, metavar=("prepare", "KIND", "THETA"), help=argparse.SUPPRESS)
    ap.add_argument("--arrival", type=float, help=argparse.SUPPRESS)  # the free flow's, for an obstacle's duration
    a = ap.parse_args(argv)
    try:
        a.incline = [float(v) for v in a.incline.split(",")]
    except ValueError:
        ap.error("--incline = %r: comma-separated angles in degrees" % a.incline)
    if not all(0 < t < 60 for t in a.incline):
        ap.error("--incline = %r: each must be in (0, 60) deg" % a.incline)
    if not 0.1 < a.rest < float("inf"):
        ap.error("--rest = %r: must be > 0.1 s (the 30–70 ms window after the touch) and finite" % a.rest)
    for name in ("L0", "dx", "width", "block_size") + tuple(n for n in ("young", "lane") if getattr(a, n) is not None):
        if not 0 < getattr(a, name) < float("inf"):
            ap.error("--%s = %r: must be > 0 and finite" % (name.replace("_", "-"), getattr(a, name)))
    if not 0 < a.step_factor <= 1:
        ap.error("--step-factor = %r: must be in (0, 1] (a longer step than the flume's is not stable)" % a.step_factor)
    a.cases = a.cases.split(",")
    if not a.cases or not set(a.cases) <= {"free", "wall", "block"}:
        ap.error("--cases = %r: a comma-separated subset of free, wall, block" % ",".join(a.cases))
    why = wholeCellsError(a.dx, a.width)
    if {"free", "wall"} & set(a.cases) and why:  # the wall's slice
        ap.error("--dx = %r: %s" % (a.dx, why))
    if "block" in a.cases and a.block_size / a.dx < 2 - 1e-9:
        ap.error("--dx = %r: the block (--block-size %g m) would be %.1f cells tall; it needs two or more "
                 "(a cube one cell tall is thrown about as a point)" % (a.dx, a.block_size, a.block_size / a.dx))
    if a.lane is not None:
        if a.lane < 2 * a.block_size:
            ap.error("--lane = %r: must be at least twice --block-size (%g m): the flow passes the cube"
                     % (a.lane, a.block_size))
        why = wholeCellsError(a.dx, a.lane)
        if "block" in a.cases and why:
            ap.error("--dx = %r: %s (--lane)" % (a.dx, why))
    return a


def runName(a, kind, theta):
    name = "%s_t%g_L%g_dx%g%s%s" % (kind, theta, a.L0, a.dx, "" if a.young is None else "_E%g" % a.young,
                                    "" if a.step_factor == 1 else "_dtf%g" % a.step_factor)
    if kind == "block":  # the §3.2 cube in its five-cube lane keeps the name its runs always had
        name += ("" if a.block_size == CUBE else "_hb%g" % a.block_size) + ("" if a.lane is None else "_lane%g" % a.lane)
    return name


def laneWidth(a, kind):
    """The flume's width for a run: the wall's slice, or for the block --lane or by default a lane
    five cubes wide (the flow passes two cubes' width either side of it: in a lane of three, at Δx
    0.02 m, the flow jammed beside the cube and loaded it as a wall), rounded up to whole cells."""
    if kind == "block":
        return a.lane if a.lane is not None else math.ceil(5 * a.block_size / a.dx - 1e-9) * a.dx
    return a.width


def prepare(a, kind, theta, folder):
    """Write the run's driver scene (YADE builds it) and its meta.json."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from mpmsdem import driver
    from mpmsdem.flume import FLUME_SETTINGS, GLASS_BEADS, Block, Flume
    from yade import O
    joint = FLUME_SETTINGS["joint"]
    granular = dict(GLASS_BEADS, mu_2=joint["mu_2"])
    if a.young is not None:
        granular["young_modulus"] = a.young
    station = COLUMN + a.L0
    width = laneWidth(a, kind)
    blocks = []
    if kind == "wall":
        blocks = [Block(half=(WALL[0], width / 2, WALL[1]), x=station, density=2500, friction=0.0,
                        flowFriction=joint["flow_friction"], blockedDOFs="xyzXYZ")]
    elif kind == "block":
        blocks = [Block(half=(a.block_size / 2,) * 3, x=station, density=8900, friction=0.67,
                        flowFriction=joint["flow_friction"], blockedDOFs="xyzXYZ")]
    scene = Flume(blocks=blocks, dx=a.dx, width=width, inclineDeg=theta, length=station + FLUME_BEYOND,
                  columnLength=COLUMN, columnHeight=0.2, granular=granular,
                  basalFriction=joint["basal_friction"], sideWallFriction=0.0, flipViscosity=joint["flip_viscosity"],
                  verbose=False)
    dt = O.dt * a.step_factor
    every = max(1, round(SERIES_EVERY / dt)) * dt
    meta = {"kind": kind, "theta": theta, "young": granular["young_modulus"], "L0": a.L0, "dx": a.dx, "width": width,
            "station": station, "dt": dt, "points": scene.mpm.numParticles, "flip_blend": scene.flipBlend(),
            "prepared_commit": commit(), "step_factor": a.step_factor}
    if kind == "block":
        meta["block_size"] = a.block_size
    if kind == "free":
        driver.writeScene(os.path.join(folder, "scene.json"), scene.coupled, duration=FREE_DURATION, dt=dt,
                          seriesEvery=every, outputEvery=RESTART_EVERY, vtk="none", stopWhenProbed=True,
                          flowProbes=[{"x": station, "halfWidth": STATION_HALF, "bedZ": 0.0, "window": 0.05}])
    else:
        # without the free flow's arrival yet (prepared beside it): settleDuration sets it where they run
        meta.update(duration=None if a.arrival is None else a.arrival + a.rest, rest=a.rest,
                    free_case=runName(a, "free", theta))
        duration = meta["duration"] or FREE_DURATION
        driver.writeScene(os.path.join(folder, "scene.json"), scene.coupled, duration=duration, dt=dt,
                          seriesEvery=every, outputEvery=min(RESTART_EVERY, duration), vtk="none")
    writeJson(os.path.join(folder, "meta.json"), meta)


def readFree(folder):
    with open(os.path.join(folder, "out", "flow_probes.json")) as f:
        probe = json.load(f)["probes"][0]
    if probe["arrival"] is None:
        raise RuntimeError("%s: the free flow's front never reached the station" % folder)
    return {k: probe[k] for k in ("arrival", "h_f", "v_f", "Fr")}


def depositHeight(folder, meta):
    """A wall's deposit at the end: its highest point within DEPOSIT upstream of the wall [m], from
    the run's last snapshot (0 where no point is there)."""
    import h5py
    with h5py.File(os.path.join(folder, "out", "mpm.h5"), "r") as hf:
        last = sorted(hf["snapshots"].keys())[-1]
        x = hf["snapshots"][last]["x"][:]
    near = (x[:, 0] >= meta["station"] - DEPOSIT) & (x[:, 0] < meta["station"])
    return float(x[near, 2].max()) if near.any() else 0.0


def settleDuration(folder, meta):
    """An obstacle prepared beside its free flow: its run's duration, the free flow's arrival (read
    from the free case's folder beside it, run before it) + --rest, into its scene and meta.json."""
    if meta.get("duration") is not None:
        return meta
    free = os.path.join(os.path.dirname(os.path.abspath(folder)), meta["free_case"])
    if not os.path.exists(os.path.join(free, "out", "flow_probes.json")):
        raise RuntimeError("%s: its free flow %s has not run (it runs first: --run-prepared over both)"
                           % (os.path.basename(folder), meta["free_case"]))
    duration = readFree(free)["arrival"] + meta["rest"]
    path = os.path.join(folder, "scene.json")
    with open(path) as f:
        scene = json.load(f)
    scene["run"].update(duration=duration, output_every=min(RESTART_EVERY, duration))
    writeJson(path, scene)
    meta = dict(meta, duration=duration)
    writeJson(os.path.join(folder, "meta.json"), meta)
    return meta


def runLeg(folder, exe, backend=None, precision=None, threads=None):
    """The case's driver run (from its last restart point where one is there), without YADE or
    numpy: its wall time, where it ran and, for a wall where h5py is there to read it, the
    deposit's height at the end go to FOLDER/run.json (the snapshot is the whole flow); returns
    them."""
    with open(os.path.join(folder, "meta.json")) as f:
        meta = json.load(f)
    if meta["kind"] != "free":
        meta = settleDuration(folder, meta)
    resume = os.path.exists(os.path.join(folder, "out", "coupled.checkpoint.json" if meta["kind"] != "free"
                                         else "mpm.h5.restart"))
    started = commit()  # the checkout the driver starts from (HEAD may move during a run of hours)
    run = {"wall_seconds": driverRun(exe, folder, "scene.json", "out", ["--restart"] if resume else [], backend,
                                     precision, threads),
           "resumed": resume, "commit": meta.get("prepared_commit", started) if started == "unknown" else started,
           "backend": backend or "the scene's", "precision": precision or "the scene's",
           "threads": str(threads) if threads else os.environ.get("OMP_NUM_THREADS", "all")}
    if meta["kind"] == "wall":
        try:
            run["h_d"] = depositHeight(folder, meta)
        except ImportError:  # read later, where the run is read
            pass
    writeJson(os.path.join(folder, "run.json"), run)
    return run


def readObstacle(folder, meta, free, hd=None):
    """The obstacle's force numbers (see the module's docstring) against the models; ``hd`` a
    wall's deposit height where its run read it (else from the last snapshot)."""
    from mpmsdem import analysis
    s, _ = analysis.driverBlockSeries(os.path.join(folder, "out"), block=1)  # block 0: the flume's bed
    t = s["t"]
    peaks = {w: analysis.peakMeanForce(s, w) for w in WINDOWS}  # (peak, its centre); BLOW and BLOW_LONG among them
    peak, tPeak = peaks[BLOW]
    theta, h, v = meta["theta"], free["h_f"], free["v_f"]
    cos = math.cos(math.radians(theta))
    touch, source = analysis.touchTime(s), analysis.forceSource(s)
    r = {"F_peak": peak, "t_peak": tPeak, "F_peak_20ms": peaks[BLOW_LONG][0],
         "F_windows": {"%g" % (1e3 * w): p for w, (p, _) in peaks.items()},
         "F_end": analysis.meanForceBetween(s, t[-1] - END, t[-1]),
         "t_end": float(t[-1]), "first_touch": touch,
         "F_later": analysis.meanForceBetween(s, touch + LATER[0], touch + LATER[1]), "forces_from": source,
         "kinetic_end": float(s["flow_kinetic"][-1]), "kinetic_peak": float(s["flow_kinetic"].max()),
         "Fr_cos": v / math.sqrt(G * cos * h)}
    if source == "impulse":  # the blow by parts after the touch (every step's force)
        r["F_parts"] = analysis.blowParts(s)
    if meta["kind"] == "wall":
        w = meta["width"]
        hd = depositHeight(folder, meta) if hd is None else hd
        momentum = RHO * v * v * h * w
        r.update(h_d=hd, alpha=r["F_peak"] / momentum, alpha_later=r["F_later"] / momentum,
                 bore=analysis.reflectedBoreForce(RHO, v, h, w, theta) / momentum,
                 superposed=analysis.wallSuperposedForce(RHO, v, h, w, theta) / momentum,
                 k_end=r["F_end"] / (0.5 * RHO * G * cos * hd * hd * w) if hd > 0 else None,
                 ratio=r["F_peak"] / analysis.staticImpactForce(RHO, h, h * w))
    else:
        hb = blockSize(meta)
        area = min(h, hb) * hb
        r.update(alpha_f=r["F_peak"] / (RHO * v * v * area), alpha_later=r["F_later"] / (RHO * v * v * area),
                 eq20=analysis.dynamicPressureCoefficient(free["Fr"]),
                 ratio=r["F_peak"] / analysis.staticImpactForce(RHO, h, area))
    return r


def prepareCase(a, kind, theta, beside=False):
    """The case's folder OUT/<case>/ with its scene and meta.json (a child process builds them with
    YADE), unless they are there; an obstacle's needs its free flow's arrival (its run's end), or
    with ``beside`` its free flow prepared in OUT too (the duration is then set where they run).
    Returns (folder, the free flow's numbers or None)."""
    name = runName(a, kind, theta)
    folder = os.path.join(a.out, name)
    free = None
    if kind != "free":
        path = os.path.join(a.out, runName(a, "free", theta) + ".json")
        if os.path.exists(path):
            with open(path) as f:
                free = json.load(f)["free"]
        elif not (beside and os.path.exists(os.path.join(a.out, runName(a, "free", theta), "meta.json"))):
            raise RuntimeError("%s: needs the free flow at %g deg first (--cases free,...)" % (name, theta))
    os.makedirs(folder, exist_ok=True)
    if not os.path.exists(os.path.join(folder, "meta.json")):
        child = ["--child", "prepare", kind, repr(theta)] + a.argv
        if free:
            child += ["--arrival", repr(free["arrival"])]
        subprocess.run([sys.executable, os.path.abspath(__file__)] + child, check=True)
    return folder, free


def runCase(a, kind, theta, exe):
    """Prepare, run and read one case; a run done elsewhere (--run-prepared) is read, one that was
    interrupted continues from its last restart point (the free flow's probe records with it: the
    driver reads them again from its mpm.h5)."""
    name = runName(a, kind, theta)
    folder, free = prepareCase(a, kind, theta)
    with open(os.path.join(folder, "meta.json")) as f:
        meta = json.load(f)
    if os.path.exists(os.path.join(folder, "run.json")):
        with open(os.path.join(folder, "run.json")) as f:
            run = json.load(f)
    else:
        run = runLeg(folder, exe)
    r = dict(meta, **{k: v for k, v in run.items() if k != "h_d"})
    if kind == "free":
        r["free"] = readFree(folder)
    else:
        r.update(free=free, obstacle=readObstacle(folder, meta, free, run.get("h_d")))
    writeJson(os.path.join(a.out, name + ".json"), r)


def reread(out):
    """The obstacles' numbers read again from their runs' outputs (this script's reading of them)."""
    for path in glob.glob(os.path.join(out, "*.json")):
        with open(path) as f:
            r = json.load(f)
        folder = path[:-len(".json")]
        if r["kind"] != "free" and os.path.exists(os.path.join(folder, "out", "coupled.h5")):
            r["obstacle"] = readObstacle(folder, r, r["free"])
            writeJson(path, r)


COLUMNS = [  # (heading, value of a run); "–" where a run has none
    ("θ [°]", lambda r, f, o: "%g" % r["theta"]),
    ("L0 [m]", lambda r, f, o: "%g" % r["L0"]),
    ("Δx [m]", lambda r, f, o: "%g" % r["dx"]),
    ("E [MPa]", lambda r, f, o: "%g" % (r["young"] / 1e6)),
    ("cells in h_f", lambda r, f, o: "%.1f" % (f["h_f"] / r["dx"])),
    ("h_f [mm]", lambda r, f, o: "%.1f" % (1e3 * f["h_f"])),
    ("v_f [m/s]", lambda r, f, o: "%.2f" % f["v_f"]),
    ("Fr", lambda r, f, o: "%.2f" % f["Fr"]),
    ("Fr′", lambda r, f, o: "%.2f" % o["Fr_cos"]),
    ("obstacle", lambda r, f, o: "wall %g m wide" % r["width"] if r["kind"] == "wall" else
     "cube %g mm (%.1f cells) in a %g m lane" % (1e3 * blockSize(r), blockSize(r) / r["dx"], r["width"])),
    ("F_peak [N]", lambda r, f, o: "%.3g" % o["F_peak"]),
    ("F_peak 20 ms [N]", lambda r, f, o: fmt(o.get("F_peak_20ms"), "%.3g")),
    ("α peak", lambda r, f, o: "%.2f" % o.get("alpha", o.get("alpha_f"))),
    ("α 30–70 ms", lambda r, f, o: fmt(o.get("alpha_later"), "%.2f")),
    ("α bore", lambda r, f, o: fmt(o.get("bore"), "%.2f") if "bore" in o else "Eq 20: %.2f" % o["eq20"]),
    ("α superposed", lambda r, f, o: fmt(o.get("superposed"), "%.2f")),
    ("F_peak/F_static", lambda r, f, o: "%.1f" % o["ratio"]),
    ("F_end [N]", lambda r, f, o: fmt(o["F_end"], "%.3g") if r["kind"] == "wall" else "–"),
    ("h_d [mm]", lambda r, f, o: fmt(o.get("h_d") and 1e3 * o["h_d"], "%.0f")),
    ("k_end", lambda r, f, o: fmt(o.get("k_end"), "%.2f")),
    ("KE end/peak", lambda r, f, o: "%.1e" % (o["kinetic_end"] / o["kinetic_peak"])),
    ("commit", lambda r, f, o: r["commit"]),
]


def blockSize(r):
    """A block run's cube edge h_b [m] (runs before --block-size: the §3.2 cube's)."""
    return r.get("block_size", CUBE)


def loadRuns(folder):
    """The JSON files of ``folder``, read, in the order of their names: the finished runs of an
    OUT folder, or a study's cases."""
    runs = []
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        with open(path) as f:
            runs.append(json.load(f))
    return runs


def table(out):
    """The markdown table of every obstacle run in ``out``."""
    runs = loadRuns(out)
    lines = ["| " + " | ".join(h for h, _ in COLUMNS) + " |", "|" + "---:|" * (len(COLUMNS) - 1) + "---|"]
    for r in sorted(runs, key=lambda r: (r["kind"], r["theta"], r["L0"], -r["dx"], r["young"])):
        if r["kind"] != "free":
            lines.append("| " + " | ".join(v(r, r["free"], r["obstacle"]) for _, v in COLUMNS) + " |")
    return "\n".join(lines)


def obstacleOf(r):
    """What an obstacle run is, but for its spacing: its kind, incline, L0, E, cube edge, flume
    width and step factor (runs of one obstacle at several Δx share it; a lane rounded up to whole
    cells may differ in its last digits)."""
    return (r["kind"], r["theta"], r["L0"], r["young"], blockSize(r) if r["kind"] == "block" else None, round(r["width"], 9),
            r.get("step_factor", 1.0))


def refinement(out):
    """The blow of each obstacle with three or more spacings, read over every window of WINDOWS,
    against Δx: the three finest spacings' order and limit per window (:func:`windowLimits`: a
    limit to trust, or why not and, where it gives one, a bracket), and where every run has them
    its blow by parts (the mean force over each span of mpmsdem.analysis.BLOW_PARTS after the
    touch: order and limit, :func:`limitOf`). Markdown, with the cells per block height (a cube)
    or per flow depth (a wall) of each spacing."""
    groups = {}
    for r in loadRuns(out):
        if r["kind"] != "free" and "F_windows" in r["obstacle"]:
            groups.setdefault(obstacleOf(r), []).append(r)
    lines = []
    for key, rs in sorted(groups.items(), key=lambda kv: tuple(-1 if v is None else v for v in kv[0][1:])):
        rs = sorted(rs, key=lambda r: -r["dx"])
        if len(rs) < 3:
            continue
        kind, theta, L0, young, hb, width, factor = key
        cells = ["%.1f" % ((hb if hb else r["free"]["h_f"]) / r["dx"]) for r in rs]
        lines += ["", "%s, %g°, L0 %g m, E %g MPa%s: Δx %s m (%s cells per %s); limits over the three finest" % (
            "wall %g m wide" % width if kind == "wall" else "cube %g mm in a %g m lane" % (1e3 * hb, width),
            theta, L0, young / 1e6, "" if factor == 1 else ", step x%g" % factor, " / ".join("%g" % r["dx"] for r in rs),
            " / ".join(cells), "block height" if hb else "flow depth"), "",
            "| window [ms] | largest mean [N] | order | limit [N] | bracket [N] | note |", "|---:|---|---:|---:|---|---|"]
        finest = rs[-3:]
        rows = windowLimits({float(w) / 1e3: [r["obstacle"]["F_windows"][w] for r in finest]
                             for w in finest[-1]["obstacle"]["F_windows"]}, [r["dx"] for r in finest])
        for row in rows:
            w = "%g" % (1e3 * row["window"])
            note = row["why"] or ""
            lines.append("| %s | %s | %s | %s | %s | %s |" % (
                w, " / ".join("%.3g" % r["obstacle"]["F_windows"][w] for r in rs), fmt(row["order"], "%.2f"),
                fmt(row["limit"], "%.3g") if row["why"] is None else "–",
                "%.3g–%.3g" % row["bracket"] if row["bracket"] else "–", note))
        spans = [name for name in partNames()
                 if all(name in r["obstacle"].get("F_parts", {}) for r in rs)]
        if spans:
            lines += ["", "| after the touch [ms] | mean force [N] | order | limit [N] | note |", "|---|---|---:|---:|---|"]
        for name in spans:
            values = [r["obstacle"]["F_parts"][name] for r in rs]
            p, f0, why = limitOf(values[-3:], [r["dx"] for r in finest], positive=True)
            lines.append("| %s | %s | %s | %s | %s |" % (
                name[len("load_"):-len("ms")].replace("_", "–"), " / ".join("%.3g" % v for v in values),
                fmt(p, "%.2f"), fmt(f0, "%.3g") if why is None else "–", why or ""))
    return "\n".join(lines[1:])


def figure(out, study=None):
    """OUT/impact_walls.png: the walls' and the cubes' α against the Froude number of their flow
    (left), beside the models no one here produced (the reflected bore for the wall; Eq 20's α_f
    = 10.8 Fr^-1.3 after Thibert et al. 2008 and α = 5.3 Fr^-1.5 after Cui et al. 2015 for the
    cube), and F_peak/F_static against Fr (right) with Eq 21 at the paper's fit (α_f 0.18, k 1.6)
    and at its bound (α_f = k = 1); ``study``: a folder of §5 cases (examples/parametric_study.py's
    JSON files) drawn on the right as well. Each run's marker is filled by its Δx (the legend)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from mpmsdem import analysis
    runs = [r for r in loadRuns(out) if r["kind"] != "free"]
    if not runs:
        return None
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6))
    fr = np.linspace(1.2, 6.5, 100)
    dxs = sorted({r["dx"] for r in runs}, reverse=True)
    shade = {dx: plt.cm.viridis(0.15 + 0.7 * k / max(1, len(dxs) - 1)) for k, dx in enumerate(dxs)}
    obstacles = [("wall", None, "s", "wall")] + [
        ("block", hb, marker, "cube (h_b %g mm)" % (1e3 * hb))
        for hb, marker in zip(sorted({blockSize(r) for r in runs if r["kind"] == "block"}), "oDv^")]
    for kind, hb, marker, name in obstacles:
        for dx in dxs:
            rs = [r for r in runs if r["kind"] == kind and r["dx"] == dx and (hb is None or blockSize(r) == hb)]
            if not rs:
                continue
            x = [r["free"]["Fr"] for r in rs]
            alpha = [r["obstacle"].get("alpha", r["obstacle"].get("alpha_f")) for r in rs]
            label = "%s, Δx %g m" % (name, dx)
            left.plot(x, alpha, marker, color=shade[dx], label=label + ": 10 ms peak")
            later = [r["obstacle"].get("alpha_later") for r in rs]
            if None not in later:
                left.plot(x, later, marker, mfc="none", color=shade[dx], label=label + ": 30–70 ms")
            right.plot(x, [r["obstacle"]["ratio"] for r in rs], marker, color=shade[dx], label=label)
    walls = sorted((r for r in runs if r["kind"] == "wall"), key=lambda r: r["free"]["Fr"])
    if walls:
        left.plot([r["free"]["Fr"] for r in walls], [r["obstacle"]["bore"] for r in walls], "k-", lw=1,
                  label="wall: reflected bore (momentum balance)")
    left.plot(fr, analysis.dynamicPressureCoefficient(fr), "k--", lw=1, label="Eq 20: 10.8 Fr^-1.3 (Thibert et al. 2008)")
    left.plot(fr, 5.3 * fr ** -1.5, "k:", lw=1, label="5.3 Fr^-1.5 (Cui et al. 2015, debris flows)")
    left.set(xlabel="Fr = v_f / sqrt(g h_f)", ylabel="α = F / (ρ v_f² A)", yscale="log")
    left.legend(fontsize=6.5)
    if study:
        cases = [c for c in loadRuns(study)
                 if c.get("force_ratio") is not None and (c.get("free_flow") or {}).get("Fr") is not None]
        if cases:
            right.plot([c["free_flow"]["Fr"] for c in cases], [c["force_ratio"] for c in cases], "^", color="tab:red",
                       label="§5 cube (h_b 50 mm), Δx 0.01 m")
    right.plot(fr, analysis.impactForceRatio(fr), "k--", lw=1, label="Eq 21, the paper's fit (α_f 0.18, k 1.6)")
    right.plot(fr, analysis.impactForceRatio(fr, k=1.0, alphaF=1.0), "k:", lw=1, label="Eq 21, α_f = k = 1")
    right.set(xlabel="Fr = v_f / sqrt(g h_f)", ylabel="F_peak / F_static (F_static = ½ ρ g h_f A)", yscale="log")
    right.legend(fontsize=6.5)
    fig.tight_layout()
    path = os.path.join(out, "impact_walls.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# The outputs mpmsdem.tradeoffs offers from a wall's refinement, by the number each one is.
WALL_OUTPUTS = {"F_peak": "peak_force", "F_later": "quasi_steady_force", "F_end": "deposit_force"}
REFERENCE_DX = 0.01  # the spacing whose run has cost 1 (the paper's)


def restAfter(r):
    """How long an obstacle's run went on after the free flow's arrival [s] (its --rest)."""
    return r["duration"] - r["free"]["arrival"]


def packageStudy(runs, theta, L0, young, command):
    """The wall's refinement at one incline, L0 and E for py/mpmsdem/tradeoffs.json: over its
    three finest spacings, each run's relative error in each force of WALL_OUTPUTS against the
    value extrapolated to Δx 0 (Richardson) where the sequence gives one to trust, the others under
    ``unconverged``; the resolution as cells per flow depth (the run's own h_f over Δx); the
    work (points x steps of the wall's run) relative to the run at Δx 0.01 m. None when those
    runs are not all there."""
    rs = sorted([r for r in runs if r["kind"] == "wall" and (r["theta"], r["L0"], r["young"]) == (theta, L0, young)],
                key=lambda r: -r["dx"])[-3:]
    default = [r for r in rs if abs(r["dx"] - REFERENCE_DX) <= 1e-12 * REFERENCE_DX]
    if len(rs) != 3 or not default:
        return None
    h = [r["dx"] for r in rs]
    cells = [r["free"]["h_f"] / r["dx"] for r in rs]
    work = lambda r: r["points"] * r["duration"] / r["dt"]  # noqa: E731
    limits, unconverged, orders = {}, {}, {}
    for key, out in WALL_OUTPUTS.items():
        if key == "F_end" and min(restAfter(r) for r in rs) < REST - 1e-9:
            continue  # runs ended before the deposit rests (--rest below the default): no deposit's load
        vals = [r["obstacle"][key] for r in rs]
        p, f0, why = limitOf(vals, h, positive=True)
        if why:
            unconverged[out] = "%s on a wall at %s cells per flow depth (Δx %s m): %s N, %s" % (
                out, " / ".join("%.1f" % c for c in cells), " / ".join("%.4g" % d for d in h),
                " / ".join("%.4g" % v for v in vals), why)
        else:
            orders[out], limits[key] = p, f0
    viscosity = [float(r["flip_blend"].split()[2]) for r in rs]  # "PIC viscosity NU m^2/s (...)"
    rows = [{"settings": {"dx": r["dx"], "cells_per_flow_depth": c, "ppc": 8, "flip_viscosity": nu,
                          "precision": "double"},
             "errors": {WALL_OUTPUTS[k]: (r["obstacle"][k] - f0) / f0 for k, f0 in limits.items()},
             "cost": work(r) / work(default[0]), "cpu_cost": None, "reference": False, "sensitivity": False}
            for r, c, nu in zip(rs, cells, viscosity)]
    return {"name": "wall_impact_t%g_L%g_E%g" % (theta, L0, young),
            "scene": "scripts/validation/impact_walls.py (the §3.2 flume at %g°, a rigid wall across a %g m slice "
                     "%g m from the column, E %g Pa, PIC viscosity held)" % (theta, rs[0]["width"], L0, young),
            "commit": ", ".join(sorted({r["commit"] for r in rs})),
            "machine": "2-core x86_64 VM, one thread, shared (cpu_cost not measured)",
            "command": command,
            "reference": {"dx": 0.0},
            "extrapolated": "f0 of f = f0 + C dx^p through Δx %s m (Richardson, observed order p: %s)" % (
                " / ".join("%.4g" % d for d in h), ", ".join("%s %.2f" % (o, orders[o]) for o in sorted(orders))),
            "rows": rows, "unconverged": unconverged}


BLOCK_OUTPUTS = {"10": "glued_block_peak_force", "20": "glued_block_peak_force_20ms"}  # a cube's windows [ms]


def packageBlockStudy(rs, command):
    """A glued cube's refinement (one obstacle, three spacings or more, one of them 0.01 m) for
    py/mpmsdem/tradeoffs.json: every run's relative error in its blow over the windows of
    BLOCK_OUTPUTS against the limit kept through the three finest spacings
    (:func:`windowLimits`); a window without one under ``unconverged`` (a bracket is not offered
    as a reference: the 40 mm cube's fourth spacing fell outside the one its first three gave,
    docs/coupled-results.md). The
    cube's height [m] (cubes of two sizes in one flow differ at the same cells per block height:
    a setting to select by) and the resolution as cells per block height and per flow depth (the
    run's own h_f over Δx); the
    work (points x steps per simulated second: the runs may go on for different times after the
    blow) relative to the run at Δx 0.01 m. None when those runs are not there."""
    rs = sorted(rs, key=lambda r: -r["dx"])
    default = [r for r in rs if abs(r["dx"] - REFERENCE_DX) <= 1e-12 * REFERENCE_DX]
    if len(rs) < 3 or not default:
        return None
    finest = rs[-3:]
    limits = {"%g" % (1e3 * row["window"]): row for row in windowLimits(
        {float(w) / 1e3: [r["obstacle"]["F_windows"][w] for r in finest] for w in BLOCK_OUTPUTS},
        [r["dx"] for r in finest])}
    hb, cells = blockSize(rs[0]), ["%.1f" % (blockSize(r) / r["dx"]) for r in rs]
    errors, unconverged, how = [{} for _ in rs], {}, []
    for w, out in BLOCK_OUTPUTS.items():
        row, values = limits[w], [r["obstacle"]["F_windows"][w] for r in rs]
        if row["why"] is None:
            for e, f in zip(errors, values):
                e[out] = (f - row["limit"]) / row["limit"]
            how.append("%s: the limit %.4g N (order %.2f)" % (out, row["limit"], row["order"]))
        else:
            unconverged[out] = "%s of a glued %g mm cube at %s cells per block height (Δx %s m): %s N, %s" % (
                out, 1e3 * hb, " / ".join(cells), " / ".join("%.4g" % r["dx"] for r in rs),
                " / ".join("%.4g" % v for v in values), row["why"])
    work = lambda r: r["points"] / r["dt"]  # noqa: E731
    rows = []
    for r, e in zip(rs, errors):
        rows.append({"settings": {"dx": r["dx"], "block_height": hb, "cells_per_block_height": blockSize(r) / r["dx"],
                                  "cells_per_flow_depth": r["free"]["h_f"] / r["dx"], "ppc": 8,
                                  "flip_viscosity": float(r["flip_blend"].split()[2]), "precision": "double"},
                     "errors": e, "cost": work(r) / work(default[0]), "cpu_cost": None, "reference": False,
                     "sensitivity": False})
    return {"name": "glued_cube_%gmm_t%g_L%g_lane%g" % (1e3 * hb, rs[0]["theta"], rs[0]["L0"], round(rs[0]["width"], 9)),
            "scene": "scripts/validation/impact_walls.py (the §3.2 flume at %g°, a glued %g mm cube on the centre line "
                     "of a %g m lane %g m from the column, E %g Pa, PIC viscosity held)" % (
                         rs[0]["theta"], 1e3 * hb, round(rs[0]["width"], 9), rs[0]["L0"], rs[0]["young"]),
            "commit": ", ".join(sorted({r["commit"] for r in rs})),
            "machine": "2-core x86_64 VM, one or two threads, shared (cpu_cost not measured)",
            "command": command, "reference": {"dx": 0.0},
            "extrapolated": "through Δx %s m, the largest mean force over each window (flume_convergence.windowLimits): "
                            "%s" % (" / ".join("%.4g" % r["dx"] for r in finest), "; ".join(how)),
            "rows": rows, "unconverged": unconverged}


def packageData(out):
    """Store the refinement of every wall (incline, L0 and E) and every glued cube with three
    spacings (one of them 0.01 m)."""
    runs = loadRuns(out)
    stored = 0
    for theta, L0, young in sorted({(r["theta"], r["L0"], r["young"]) for r in runs if r["kind"] == "wall"}):
        dxs = sorted({r["dx"] for r in runs if r["kind"] == "wall" and (r["theta"], r["L0"], r["young"]) ==
                      (theta, L0, young)}, reverse=True)[-3:]
        rest = min(restAfter(r) for r in runs if r["kind"] == "wall" and r["dx"] in dxs and
                   (r["theta"], r["L0"], r["young"]) == (theta, L0, young))
        study = packageStudy(runs, theta, L0, young,
                             "OMP_NUM_THREADS=1 python3 scripts/validation/impact_walls.py --out OUT --incline %g "
                             "--L0 %g%s --dx D for D in %s, then --report-only --package-data" % (
                                 theta, L0, "" if rest >= REST - 1e-9 else " --rest %.3g" % rest,
                                 ", ".join("%g" % d for d in dxs)))
        if study is not None:
            storeStudy(study)
            stored += 1
    cubes = {}
    for r in runs:
        if r["kind"] == "block" and "F_windows" in r["obstacle"] and r.get("step_factor", 1.0) == 1.0:
            cubes.setdefault(obstacleOf(r), []).append(r)
    for (_, theta, L0, young, hb, width, _), rs in sorted(cubes.items()):
        study = packageBlockStudy(rs, "OMP_NUM_THREADS=1 python3 scripts/validation/impact_walls.py --out OUT --cases "
                                      "free,block --incline %g --L0 %g --block-size %g --lane %g --rest %.3g --dx D for "
                                      "D in %s, then --report-only --package-data" % (
                                          theta, L0, hb, width, min(restAfter(r) for r in rs),
                                          ", ".join("%g" % r["dx"] for r in sorted(rs, key=lambda r: -r["dx"]))))
        if study is not None:
            storeStudy(study)
            stored += 1
    if not stored:
        raise SystemExit("--package-data: no wall or cube has three finished spacings at one incline, L0 and E, one "
                         "of them %g m" % REFERENCE_DX)


def main(argv):
    a = parse(argv)
    a.argv = argv
    if a.run_prepared:
        def run(folder):
            r = runLeg(folder, a.exe, a.backend, a.precision, a.threads)
            print("%s: %.0f s (%s)" % (os.path.basename(folder), r["wall_seconds"], r["backend"]), flush=True)
        # done: run there, or run and read here (cases of before run.json have only their numbers)
        return runPreparedFolders(a, lambda folder: any(os.path.exists(p) for p in (
            os.path.join(folder, "run.json"), folder.rstrip(os.sep) + ".json")), run,
            first=lambda folder: os.path.basename(folder.rstrip(os.sep)).startswith("free_"))
    if a.child:
        kind, theta = a.child[1], float(a.child[2])
        prepare(a, kind, theta, os.path.join(a.out, runName(a, kind, theta)))
        return
    os.makedirs(a.out, exist_ok=True)
    if a.prepare:  # an obstacle's case needs its free flow's numbers: run or read the free flows first
        for theta in a.incline:
            for kind in [k for k in ("free", "wall", "block") if k in a.cases]:
                if not os.path.exists(os.path.join(a.out, runName(a, kind, theta) + ".json")):
                    print("prepared %s" % prepareCase(a, kind, theta, beside=True)[0], flush=True)
        return
    if not a.report_only:
        import mpmsdem.driver
        exe = mpmsdem.driver.executable()
        for theta in a.incline:
            for kind in ("free", "wall", "block"):
                if kind not in a.cases:
                    continue
                if os.path.exists(os.path.join(a.out, runName(a, kind, theta) + ".json")):
                    print("%s: done before" % runName(a, kind, theta))
                    continue
                t0 = time.time()
                print("%s: running ..." % runName(a, kind, theta), flush=True)
                runCase(a, kind, theta, exe)
                print("%s: %.0f s" % (runName(a, kind, theta), time.time() - t0), flush=True)
    else:
        reread(a.out)
    text = table(a.out)
    print(text)
    with open(os.path.join(a.out, "impact_walls.md"), "w") as f:
        f.write(text + "\n")
    text = refinement(a.out)
    if text:
        print(text)
        with open(os.path.join(a.out, "impact_walls_refinement.md"), "w") as f:
            f.write(text + "\n")
    drawn = figure(a.out, a.study)
    if drawn:
        print("drew %s" % drawn)
    if a.package_data:
        packageData(a.out)


if __name__ == "__main__":
    main(sys.argv[1:])
