#!/usr/bin/env python3
"""Validation (opt-in, minutes to an hour a spacing on two cores): the §3.2 flume under grid
refinement. For each grid spacing the coupled scene of examples/flume_block.py (the copper cube
of Table 1, h_b 0.02 m, on the centre line; a chosen flow and friction set) runs through the C++
driver mpmsdem-run in two legs (the scenes are built with YADE, then only the driver runs):

- the free flow without the cube, to 50 ms past the front's arrival at the cube's station: the
  arrival, h_f and v_f (the driver's flow probe: means over those 50 ms, over a fixed 2 cm window
  along the flume at every Δx), Fr and Eq 20 of that flow (α_f = 10.8 Fr^−1.3 on the cube's face
  below h_f); and the front's profile when it reaches the station (its saved state): the tip (the
  20 most downstream points) and their mean height above the bed, the nose (the lowest material
  point within one cell of the tip; beside it the height of a point resting on the bed, its
  contact radius R_p0 of Eq 13) and the depth 2 and 5 cm behind the tip;
- the coupled run with the cube, started from the free flow's state saved when its front was
  3 cm and two cells short of the cube (mpmsdem-run --flow-from: the same run, bit for bit,
  without the flow's way there): first touch (the step the flow first touched the cube in,
  where coupled.h5 records it, else the first 1 ms record with a force: analysis.touchTime),
  the first blow (the largest 10 ms mean of the
  flow's downstream force within 50 ms of the touch) and the blow by parts (the mean force over
  0–2, 2–5 and 5–25 ms after the touch, and the height of its line of action above the cube's
  centroid over each: analysis.blowLineOfAction), the plateau (mean force over 0.4–0.5 s),
  the cube's tilt and travel at 0.5 s. The means are taken from the impulse coupled.h5 records
  (every step's force; "forces_from": "impulse"); outputs written before it was recorded give
  them from the records' own forces, one step's each ("records").

The damping of the FLIP/PIC blend is a model quantity, so refinement must say which one it
holds (``--hold``): ``viscosity`` keeps the PIC viscosity ν [m²/s] (damping rate 4ν/Δx² grows
as Δx shrinks: the flow converges to a viscous one), ``rate`` keeps the damping rate per
second of the set at Δx 0.01 m (ν scales with Δx²: towards the inviscid μ(I) flow).

    OMP_NUM_THREADS=2 /usr/bin/python3 scripts/validation/flume_convergence.py \\
        --dx 0.01,0.0071428571,0.005 --hold viscosity --out results/convergence [--settings joint]
    /usr/bin/python3 scripts/validation/flume_convergence.py --out results/convergence --report-only --extrapolate

On a machine with a GPU and no YADE, the runs are prepared here and their legs run there:

    /usr/bin/python3 scripts/validation/flume_convergence.py --dx 0.0025 --duration 0.4 --out DIR --prepare
    python3 scripts/validation/flume_convergence.py --run-prepared DIR --exe PATH/mpmsdem-run --backend cuda
        (or scripts/bench/gpu_run.sh --convergence DIR: its outputs but the snapshots come back)
    /usr/bin/python3 scripts/validation/flume_convergence.py --dx 0.0025 --duration 0.4 --out DIR

The last call reads the legs run there (the front's profile read there too, where the whole
flow's snapshot is) and runs nothing.

Each spacing's numbers go to OUT/<run>.json when it ends (its scenes, logs and outputs to
OUT/<run>/), and finished spacings are not run again: an interrupted sequence continues, a
finished free leg is kept (--rerun-coupled runs the coupled legs again from it). The
table of every finished run in OUT is printed (markdown) and written to OUT/convergence.md;
with --extrapolate, the three finest spacings of each set, damping and width also get, per
quantity, the observed order p and the value at Δx 0 of f = f0 + C Δx^p through the three
points where the differences keep their sign and shrink, and say so where they do not.
"""
import argparse
import glob
import json
import math
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
REFERENCE_DX = 0.01          # the spacing where the sets were calibrated [m]
STATION_HALF = 0.01          # half the window along the flume that h_f and v_f are read over [m]
BLOW_WINDOW = 0.05           # the first blow is looked for within this time after the touch [s]
PLATEAU = (0.4, 0.5)         # [s]
SERIES_EVERY = 0.001         # records of the probe and the cube [s]
RESTART_EVERY = 0.05         # the free flow saves a snapshot (a restart point) this often [s]
AHEAD = 0.03                 # the coupled run starts from the free flow with its front this far (and two cells,
                             # the grid's reach) short of the cube [m]: no point within its bounding sphere yet
CUBE = 0.02                  # the cube's side h_b [m] (examples/flume_block.py)
FOREMOST = 20                # the front's tip: the 20 most downstream points (their mean height: where its edge runs)
AT = 0.5                     # tilt and travel read at this time [s]
WINDOWS = (0.005, 0.02, 0.03)  # the first blow is also given as the largest mean over these [s]


def addPreparedOptions(ap, readThere):
    """The options of runs prepared here and run on a machine with a driver and no YADE (a GPU's):
    --prepare, --run-prepared DIR and the driver's --exe, --backend, --precision, --threads,
    --workers. ``readThere``: what the runs read there, where numpy and h5py are."""
    ap.add_argument("--prepare", action="store_true",
                    help="only write the runs' scenes into OUT/<run>/ (YADE builds them), for --run-prepared on "
                         "another machine; bring OUT back and call again without it to read the runs")
    ap.add_argument("--run-prepared", metavar="DIR",
                    help="run the runs prepared in DIR with the driver alone (no YADE; numpy and h5py, where there, "
                         "read %s), skipping those done" % readThere)
    ap.add_argument("--exe", default="mpmsdem-run", help="--run-prepared: the driver (mpmsdem-run on the PATH)")
    ap.add_argument("--backend", choices=("cpu", "cuda"), help="--run-prepared: the backend (the scenes': cpu)")
    ap.add_argument("--precision", choices=("double", "float"), help="--run-prepared: the precision (the scenes')")
    ap.add_argument("--threads", type=int, help="--run-prepared: OMP_NUM_THREADS of the driver (as set)")
    ap.add_argument("--workers", type=int, default=1, help="--run-prepared: runs at a time; 1 (a run takes the device)")


def runPreparedFolders(a, done, run, first=lambda folder: False):
    """``run(folder)`` for every run prepared in a.run_prepared (a folder with its meta.json) for
    which ``done(folder)`` is false, one after another, those for which ``first(folder)`` holds
    first, then by name (``--workers`` above 1 is refused: a run takes the whole device), without
    YADE; a run done before is skipped, so a stopped call is taken up by the next."""
    if a.workers != 1:
        raise SystemExit("--workers = %d: a prepared run takes a whole device; run them one at a time (1)" % a.workers)
    folders = sorted((os.path.dirname(p) for p in glob.glob(os.path.join(a.run_prepared, "*", "meta.json"))),
                     key=lambda folder: (not first(folder), folder))
    if not folders:
        raise SystemExit("--run-prepared %s: no prepared run there (--prepare writes them)" % a.run_prepared)
    for folder in folders:
        if done(folder):
            print("%s: done before" % os.path.basename(folder))
            continue
        run(folder)


def driverRun(exe, folder, scene, out, extra, backend=None, precision=None, threads=None):
    """mpmsdem-run on one of a run's scenes (examples/driver_runs.runDriver: no YADE, no numpy),
    its output in FOLDER/OUT.log; its wall seconds."""
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    from driver_runs import runDriver
    return runDriver(exe, os.path.join(folder, scene), os.path.join(folder, out), os.path.join(folder, out + ".log"),
                     extra, backend, precision, threads)


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dx", default="0.01,0.0071428571,0.005",
                    help="grid spacings [m], comma-separated, each > 0 and dividing the width into whole cells "
                         "(0.01, 0.2/28, 0.005: a ratio of 1.40 and 1.43)")
    ap.add_argument("--hold", choices=("viscosity", "rate"), default="viscosity",
                    help="what of the set's FLIP/PIC damping stays fixed under refinement (viscosity)")
    ap.add_argument("--settings", choices=("joint", "table1"), default="joint",
                    help="flow and friction set of mpmsdem.flume.FLUME_SETTINGS (joint)")
    ap.add_argument("--width", type=float, default=0.2, help="flume width [m] (0.2, the experiment's)")
    ap.add_argument("--ppc", type=int, default=8,
                    help="material points per cell, a cube (8, the paper's): at a fixed Δx more points shrink "
                         "their contact radius R_p0 (Eq 13) and nothing of the grid")
    ap.add_argument("--duration", type=float, default=0.5,
                    help="coupled run [s] > 0 (0.5; shorter runs report no plateau, tilt or travel)")
    ap.add_argument("--out", default="results/convergence", help="folder of the runs' JSON files")
    ap.add_argument("--report-only", action="store_true", help="only print and write the table of finished runs")
    ap.add_argument("--reread", action="store_true",
                    help="read each finished run's cube numbers in OUT again from its outputs (after a change to "
                         "what is read), without running anything")
    ap.add_argument("--rerun-coupled", action="store_true",
                    help="run each spacing's coupled leg again from the free flow kept in OUT (after a change to "
                         "what the records hold); its JSON before goes to OUT/<run>.json.previous")
    ap.add_argument("--extrapolate", action="store_true", help="Richardson estimates where the sequence allows")
    ap.add_argument("--package-data", action="store_true",
                    help="store the spacings of --settings/--hold/--width as a study in py/mpmsdem/tradeoffs.json "
                         "(mpmsdem.tradeoffs: errors against the limit extrapolated through the three finest)")
    addPreparedOptions(ap, "the front's profile")
    ap.add_argument("--child", nargs=2, metavar=("prepare", "DX"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    try:
        a.dx = [float(v) for v in a.dx.split(",")]
    except ValueError:
        ap.error("--dx = %r: comma-separated grid spacings in m" % a.dx)
    if not all(0 < d < float("inf") for d in a.dx):
        ap.error("--dx = %r: each spacing must be > 0 and finite" % a.dx)
    if not 0 < a.duration < float("inf"):
        ap.error("--duration = %r s: must be > 0 (the plateau, tilt and travel need >= %g s)" % (a.duration, AT))
    if not 0 < a.width < float("inf"):
        ap.error("--width = %r m: must be > 0" % a.width)
    for d in a.dx:
        why = wholeCellsError(d, a.width)
        if why:
            ap.error("--dx = %r: %s" % (d, why))
    if a.ppc < 1 or round(a.ppc ** (1.0 / 3.0)) ** 3 != a.ppc:
        ap.error("--ppc = %r: must be a perfect cube (1, 8, 27, ...)" % a.ppc)
    return a


def wholeCellsError(dx, width):
    """What is wrong with a spacing ``dx`` that does not divide ``width`` into whole cells (the
    flume's side walls lie on grid planes, mpmsdem.flume.Flume), naming two that do; None where
    it divides it. Checked where the options are read, before anything runs."""
    cells = width / dx
    if round(cells) >= 1 and abs(cells - round(cells)) < 1e-6 * cells:
        return None
    return "must divide the width %g m into whole cells, e.g. %.8g or %.8g m" % (
        width, width / max(1, math.floor(cells)), width / math.ceil(cells))


def viscosity(a, dx):
    """PIC viscosity [m²/s] of the run at ``dx``: the set's, or scaled to keep its damping rate."""
    from mpmsdem.flume import FLUME_SETTINGS
    from mpmsdem.mpm import PAPER_VISCOSITY
    nu = FLUME_SETTINGS[a.settings]["flip_viscosity"] or PAPER_VISCOSITY
    return nu if a.hold == "viscosity" else nu * (dx / REFERENCE_DX) ** 2


def runName(a, dx):
    return "%s_%s_w%g_dx%.6g%s" % (a.settings, a.hold, a.width, dx, "" if a.ppc == 8 else "_ppc%d" % a.ppc)


def group(r):
    """What a refinement sequence holds fixed: set, damping held, width and points per cell (runs
    before --ppc had 8)."""
    return r["settings"], r["hold"], r["width"], r.get("ppc", 8)


def example(a, dx):
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import flume_block
    args = flume_block.parse(["--full", "--settings", a.settings, "--dx", str(dx), "--width", str(a.width),
                              "--flip-viscosity", repr(viscosity(a, dx)), "--duration", str(a.duration)])
    return flume_block, args


def prepare(a, dx, folder):
    """Write the run's two driver scenes (YADE builds them): free.json, the flume without the
    cube, with a flow probe at the cube's station and the flow's state saved when its front is
    AHEAD short of the cube and when it reaches the station; coupled.json, with the cube, at the
    same step. Returns the facts the report needs."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from mpmsdem import driver
    from mpmsdem.flume import Flume
    from yade import O
    fb, args = example(a, dx)
    station = fb.COLUMN + fb.L0
    common = dict(dx=dx, ppc=a.ppc, width=a.width, verbose=False, **fb.flumeKeywords(args))
    scene = Flume(blocks=[fb.copperCube(flowFriction=args.flow_friction)], **common)
    dt = O.dt
    every = max(1, round(SERIES_EVERY / dt)) * dt
    driver.writeScene(os.path.join(folder, "coupled.json"), scene.coupled, duration=a.duration, dt=dt,
                      seriesEvery=every, outputEvery=a.duration, vtk="none")
    meta = {"points": scene.mpm.numParticles, "dt": dt, "dx": dx, "flip_blend": scene.flipBlend(), "station": station,
            "duration": a.duration, "prepared_commit": commit()}
    O.reset()
    scene = Flume(**common)  # the cube's step for the free flow too: --flow-from continues it
    driver.writeScene(os.path.join(folder, "free.json"), scene.coupled, duration=2.0, dt=dt,
                      flowProbes=[{"x": station, "halfWidth": STATION_HALF, "bedZ": 0.0, "window": 0.05}],
                      seriesEvery=every, outputEvery=RESTART_EVERY, vtk="none", stopWhenProbed=True,
                      snapshotWhenFrontAt=[station - AHEAD - 2 * dx, station])
    writeMeta(folder, meta)


def analysisModule():
    """mpmsdem.analysis, read from the checkout without importing the package (which needs YADE):
    what the legs of a prepared run read where only numpy and h5py are."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("mpmsdem_analysis", os.path.join(ROOT, "py", "mpmsdem", "analysis.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def frontOf(folder, dx):
    """The front's profile when it reached the station (see the module's docstring), from the free
    flow's snapshot of that moment."""
    import h5py
    with open(os.path.join(folder, "free", "front_snapshot_1.json")) as f:
        front = json.load(f)
    with h5py.File(os.path.join(folder, "free", "mpm.h5"), "r") as h:
        p = {"x": h["snapshots/%06d/x" % front["snapshot"]][()]}
    return dict(analysisModule().frontProfile(p, cell=dx, behind=(0.02, 0.05), minPoints=FOREMOST), time=front["time"])


def freeFlow(folder, dx, ppc, front=None):
    """The free flow's numbers at the cube's station (see the module's docstring); ``front`` its
    profile where the legs read it (else from the snapshot)."""
    from mpmsdem import analysis
    with open(os.path.join(folder, "free", "flow_probes.json")) as f:
        probe = json.load(f)["probes"][0]
    if probe["arrival"] is None:
        raise RuntimeError("%s: the free flow's front never reached the cube's station" % folder)
    r = {k: probe[k] for k in ("arrival", "h_f", "v_f", "Fr")}
    r["front"] = front or frontOf(folder, dx)
    r["resting_point_height"] = analysis.pointRadius(dx, ppc)
    r["eq20"] = analysis.hydrodynamicForce(1600.0, r["v_f"], r["h_f"], min(r["h_f"], CUBE) * CUBE)
    return r


def coupled(folder, duration):
    """The coupled run's numbers (see the module's docstring)."""
    import numpy as np
    from mpmsdem import analysis
    s, _ = analysis.driverBlockSeries(os.path.join(folder, "coupled"))
    t, ft = s["t"], s["Ft"]
    t0 = analysis.touchTime(s)
    if t0 is None:
        return {"first_touch": None}
    late = t[-1] >= AT - 2 * SERIES_EVERY  # the last record may fall just short of AT; a short run (a check's) has none
    if "J" in s:  # the impulse between records holds every step's force
        smooth = analysis.windowMean(t, s["J"], 0.01)
        end = min(PLATEAU[1], t[-1])  # (the last record may fall just short of it)
        plateau = (np.interp(end, t, s["J"]) - np.interp(PLATEAU[0], t, s["J"])) / (end - PLATEAU[0]) if late else None
        source = "impulse"
    else:  # outputs written before it: the records' own forces, one step's each
        smooth = analysis.runningMean(t, ft, 0.01)
        window = (t >= PLATEAU[0]) & (t <= PLATEAU[1])
        plateau = ft[window].mean() if window.any() else None
        source = "records"
    w = (t >= t0) & (t <= t0 + BLOW_WINDOW) & np.isfinite(smooth)
    j = int(np.argmax(np.where(w, smooth, -np.inf)))
    extra = {}
    if source == "impulse":
        # the blow over other windows, and the impulse of its first 20 ms (none before the touch)
        for window in WINDOWS:
            m = analysis.windowMean(t, s["J"], window)
            m = np.where(w & np.isfinite(m), m, -np.inf)
            extra["blow_%gms" % (1e3 * window)] = float(m.max())
        extra["impulse_20ms"] = float(np.interp(t0 + 0.02, t, s["J"]))
        extra.update(analysis.blowParts(s))
        extra.update(analysis.blowLineOfAction(s))
    return {"first_touch": t0, "blow": float(smooth[j]), "blow_time": float(t[j]), "forces_from": source, **extra,
            "plateau": float(plateau) if late else None,
            "tilt_at": float(np.interp(AT, t, s["tilt"])) if late else None,
            "travel_at": float(np.interp(AT, t, s["travel"])) if late else None,
            "rotation_end": float(s["rotation"][-1]), "travel_end": float(s["travel"][-1]), "time_end": float(t[-1])}


def sameRunAtReference(a, dx):
    """The finished viscosity-held run that a rate-held one at the reference spacing would repeat
    (the two holds give the same viscosity there, hence the same scenes): its JSON path, or None."""
    if a.hold != "rate" or abs(dx - REFERENCE_DX) > 1e-12 * REFERENCE_DX:
        return None
    path = os.path.join(a.out, runName(argparse.Namespace(**dict(vars(a), hold="viscosity")), dx) + ".json")
    return path if os.path.exists(path) else None


def writeJson(path, data):
    """``data`` to the JSON file ``path``, whole or not at all (through a temporary file: a killed
    run leaves the old file)."""
    with open(path + ".tmp", "w") as f:
        json.dump(data, f, indent=1)
    os.replace(path + ".tmp", path)


def writeResult(a, dx, r):
    """OUT/<run>.json, whole or not at all; returns ``r``."""
    writeJson(os.path.join(a.out, runName(a, dx) + ".json"), r)
    return r


def prepareRun(a, dx):
    """The run's folder OUT/<run>/ with its scenes and meta.json (written by a child process that
    builds them with YADE), unless they are there."""
    folder = os.path.join(a.out, runName(a, dx))
    os.makedirs(folder, exist_ok=True)
    if not os.path.exists(os.path.join(folder, "meta.json")):
        subprocess.run([sys.executable, os.path.abspath(__file__), "--child", "prepare", repr(dx)] + a.argv, check=True)
    return folder


def writeMeta(folder, meta):
    writeJson(os.path.join(folder, "meta.json"), meta)


def flowFromThere(free):
    """Whether the free leg's folder holds the state the coupled leg starts from (--flow-from
    front_snapshot_0.json: its checkpoint and the snapshot it names)."""
    marker = os.path.join(free, "front_snapshot_0.json")
    if not os.path.exists(marker):
        return False
    with open(marker) as f:
        m = json.load(f)
    return (os.path.exists(os.path.join(free, m["checkpoint"])) and
            os.path.exists(os.path.join(free, "mpm.snapshots", "%06d.h5" % m["snapshot"])))


def runLegs(folder, exe, backend=None, precision=None, threads=None):
    """The free leg unless it ended before, then the coupled leg from the free flow's state, with
    the driver ``exe`` (the scenes' backend and precision unless given). Needs neither YADE nor
    numpy: a prepared run goes to a machine that has a driver and a Python alone. A leg that was
    interrupted continues from its last restart point (--restart; the free flow's probe records
    with it, the driver reads them again from its mpm.h5). What each leg took, where it ran and
    the front's profile (where numpy and h5py are there to read it: the snapshot is the whole
    flow) go to meta.json; returns it."""
    with open(os.path.join(folder, "meta.json")) as f:
        meta = json.load(f)
    started = commit()  # the checkout the driver starts from (HEAD may move during a run of hours)
    if started == "unknown":  # a copy without git (a GPU machine's): the checkout that prepared it
        started = meta.get("prepared_commit", started)

    def leg(scene, out, extra):
        return driverRun(exe, folder, scene, out, extra, backend, precision, threads)
    free = os.path.join(folder, "free")
    resume = os.path.exists(os.path.join(folder, "coupled", "coupled.checkpoint.json"))
    if meta.get("free_wall") is not None and not resume and not flowFromThere(free):
        # the free leg ended elsewhere and its state did not come back (the archives of prepared
        # runs leave snapshots and restart points out): the coupled leg cannot start from it
        print("%s: the free leg's state to start the coupled leg from is not here: the free leg again"
              % os.path.basename(folder), flush=True)
        meta.pop("free_wall", None)
    if meta.get("free_wall") is None:  # written when the free leg ended: its outputs are whole
        resume = False
        again = all(os.path.exists(os.path.join(free, f)) for f in ("mpm.h5.restart", "coupled.checkpoint.json"))
        if not again and os.path.isdir(free):
            shutil.rmtree(free)  # what a stopped or returned leg left: a fresh start
        meta.update(free_wall=leg("free.json", "free", ["--restart"] if again else []), free_resumed=again,
                    free_commit=started)
        meta.pop("front", None)
        writeMeta(folder, meta)
    if "front" not in meta:
        try:
            meta["front"] = frontOf(folder, meta["dx"])
            meta.pop("front_error", None)
        except ImportError:  # read later, where the run is read
            pass
        except Exception as e:  # noqa: BLE001  (the coupled leg still runs; the report says what failed)
            meta["front_error"] = "%s: %s" % (type(e).__name__, e)
        writeMeta(folder, meta)
    with open(os.path.join(folder, "free", "front_snapshot_0.json")) as f:
        start = json.load(f)["step"]
    steps = int(round(meta["duration"] / meta["dt"])) - start
    flowFrom = ["--restart"] if resume else ["--flow-from", os.path.join(folder, "free", "front_snapshot_0.json")]
    meta.update(coupled_wall=leg("coupled.json", "coupled", flowFrom + ["--steps", str(steps)]), coupled_from_step=start,
                resumed=resume, commit=started, backend=backend or "the scene's", precision=precision or "the scene's",
                threads=str(threads) if threads else os.environ.get("OMP_NUM_THREADS", "all"))
    writeMeta(folder, meta)
    return meta


def runOne(a, dx, exe):
    """Prepare, run and read one spacing; writes OUT/<run>.json and returns its numbers. Legs run
    before (by --run-prepared elsewhere, or by a call that stopped after them) are read, not run
    again."""
    same = sameRunAtReference(a, dx)
    if same:
        with open(same) as f:
            r = json.load(f)
        return writeResult(a, dx, dict(r, hold=a.hold, same_run_as=os.path.basename(same)))
    folder = prepareRun(a, dx)
    with open(os.path.join(folder, "meta.json")) as f:
        meta = dict(json.load(f), dx=dx)  # (runs prepared before it was kept)
    previous = os.path.join(a.out, runName(a, dx) + ".json.previous")
    before = {}
    if a.rerun_coupled:
        if os.path.isdir(os.path.join(folder, "coupled")):
            shutil.rmtree(os.path.join(folder, "coupled"))
        meta.pop("coupled_wall", None)
        if os.path.exists(previous):
            with open(previous) as f:
                before = json.load(f)
        if meta.get("free_wall") is None and before:  # a run finished before meta.json kept it
            meta.update(free_wall=before["wall_seconds"]["free"],
                        free_commit=before.get("free_commit") or before.get("commit"))
        writeMeta(folder, meta)
    if meta.get("coupled_wall") is None:
        writeMeta(folder, meta)
        meta = runLegs(folder, exe)
    r = dict({k: v for k, v in meta.items() if k not in ("front", "coupled_wall")},
             free=freeFlow(folder, dx, a.ppc, meta.get("front")), coupled=coupled(folder, meta["duration"]), dx=dx,
             hold=a.hold, settings=a.settings, width=a.width, ppc=a.ppc, viscosity=viscosity(a, dx),
             damping_rate=4 * viscosity(a, dx) / dx ** 2, cells_per_block=CUBE / dx,
             wall_seconds={"free": meta["free_wall"], "coupled": meta["coupled_wall"]},
             free_commit=meta.get("free_commit") or meta["commit"])
    return writeResult(a, dx, r)


def runPrepared(a):
    """The legs of every run prepared in a.run_prepared (``--prepare``) that has not run them."""
    def run(folder):
        meta = runLegs(folder, a.exe, a.backend, a.precision, a.threads)
        print("%s: free leg %.0f s, coupled leg %.0f s (%s)" % (os.path.basename(folder), meta["free_wall"],
                                                               meta["coupled_wall"], meta["backend"]), flush=True)
    def done(folder):
        with open(os.path.join(folder, "meta.json")) as f:
            return json.load(f).get("coupled_wall") is not None
    runPreparedFolders(a, done, run)


def commit():
    try:
        return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def load(out):
    runs = []
    for path in sorted(glob.glob(os.path.join(out, "*.json"))):
        with open(path) as f:
            runs.append(json.load(f))
    return sorted(runs, key=lambda r: group(r) + (-r["dx"],))


def fmt(v, spec):
    return "–" if v is None else spec % v


COLUMNS = ("set, damping held", "width [m]", "Δx [m]", "cells per h_b", "O.dt [s]", "PIC damping [1/s]",
           "front at station [s]", "h_f [mm]", "v_f [m/s]", "Fr", "Eq 20 [N]", "tip height [mm]",
           "nose above bed [mm] (resting point)",
           "depth 2 / 5 cm behind tip [mm]", "first touch [s]", "first blow, 10 ms [N]", "blow / Eq 20",
           "mean force 0–2 / 2–5 / 5–25 ms after the touch [N]",
           "its line of action above the centroid, the same spans [mm]",
           "plateau 0.4–0.5 s [N]", "tilt at 0.5 s [°]", "travel at 0.5 s [m]", "wall free + coupled [s]")


def table(runs):
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    parts = partNames()
    loads, actions = [n for n in parts if n.startswith("load")], [n for n in parts if n.startswith("action")]
    for r in runs:
        ff, cp, fr = r["free"], r["coupled"], r["free"]["front"]
        blow = cp.get("blow")
        row = ["%s, %s%s" % (r["settings"], r["hold"], "" if r.get("ppc", 8) == 8 else ", %d per cell" % r["ppc"]),
               "%g" % r["width"], "%.4g" % r["dx"], "%.1f" % r["cells_per_block"],
               "%.3g" % r["dt"], "%.0f" % r["damping_rate"], "%.3f" % ff["arrival"], "%.1f" % (1e3 * ff["h_f"]),
               "%.3f" % ff["v_f"], "%.2f" % ff["Fr"], "%.2f" % ff["eq20"], fmt(fr.get("tipHeight") and 1e3 * fr["tipHeight"], "%.1f"),
               "%.1f (%.1f)" % (1e3 * fr["nose"], 1e3 * ff["resting_point_height"]),
               "%.0f / %.0f" % (1e3 * fr["depth"][0], 1e3 * fr["depth"][1]),
               fmt(cp.get("first_touch"), "%.3f"), fmt(blow, "%.2f"),
               fmt(blow / ff["eq20"] if blow is not None else None, "%.2f"),
               " / ".join(fmt(cp.get(name), "%.2f") for name in loads),
               " / ".join(fmt(cp.get(name) and 1e3 * cp[name], "%.1f") for name in actions),
               fmt(cp.get("plateau"), "%.2f"),
               fmt(cp.get("tilt_at"), "%.1f"), fmt(cp.get("travel_at"), "%.3f"),
               "%.0f + %.0f" % (r["wall_seconds"]["free"], r["wall_seconds"]["coupled"])]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def richardson(f, h):
    """Observed order p and extrapolated value of f at three spacings h (coarsest first, any
    ratios): f(h) = f0 + C h^p through the three points. None when the differences change sign
    or do not shrink as that form needs (not in the asymptotic range)."""
    (f1, f2, f3), (h1, h2, h3) = f, h
    d1, d2 = f2 - f1, f3 - f2
    if d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
        return None
    g = lambda p: (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p)  # noqa: E731  (rises with p)
    lo, hi = 0.05, 8.0
    if not g(lo) < d1 / d2 < g(hi):
        return None
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) < d1 / d2 else (lo, mid)
    p = 0.5 * (lo + hi)
    return p, f3 + d2 * h3 ** p / (h2 ** p - h3 ** p)


def limitOf(f, h, positive=False):
    """(order, limit, None) of f at three spacings h (coarsest first) where a limit can be
    trusted, else (order or None, limit or None, why not). Beyond :func:`richardson`'s form, the
    limit must lie no farther from the finest run than the three runs lie apart: on an exact
    power law that asks for an order of at least ln 2 / ln(h1/h3) (first order over Δx halved,
    one half over Δx quartered). A lower order puts the limit several measured steps past the
    finest run, resting on the sequence going on as it went (order 0.55 over spacing ratios 1.4
    puts it 4.6 last steps away). With ``positive`` (a mean push on an obstacle, a time, a depth)
    a limit at or below zero is not kept either: a power law may pass zero where the quantity
    cannot, and the trade-off studies divide by the limit."""
    e = richardson(f, h)
    if e is None:
        d1, d2 = f[1] - f[0], f[2] - f[1]
        if d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
            return None, None, "not monotone"
        # monotone, but the last step is too large against the one before for any order the
        # spacings allow (or too small: an order past richardson's range)
        return None, None, "monotone, but its steps (%.3g, %.3g) do not shrink as a power law's would" % (
            abs(d1), abs(d2))
    if positive and e[1] <= 0:
        return e[0], e[1], "its limit %.4g is not positive, as this quantity must be" % e[1]
    if abs(f[2] - e[1]) > abs(f[0] - f[2]):
        return e[0], e[1], "order %.2f: its limit %.4g lies farther from the finest run than the runs lie apart" % e
    return e[0], e[1], None


def windowLimits(byWindow, h):
    """A blow read over several windows, each at three spacings h (coarsest first): ``byWindow``
    maps a window [s] to its three values (the largest mean force over that window in each run).
    Returns, per window (shortest first), a dict of its values, order, limit and why
    (:func:`limitOf` of a push, kept only above zero; also not kept where a longer window's kept
    limit exceeds this window's limit: run by run the largest mean over a shorter window is never
    below that over a longer one, so neither can their limits be. The longest windows are kept first: a window the flow
    crosses in a few cells is the worst resolved), and ``bracket`` (lo, hi) for a window without
    a kept limit: the limit lies at or above the kept limits of longer windows and at or below
    those of shorter ones and, on the assumption that a sequence that fell (rose) at every
    refinement goes on doing so, at or below (above) the finest run's value; None where one side
    is missing or the sides cross."""
    rows = []
    for w in sorted(byWindow):
        p, f0, why = limitOf(byWindow[w], h, positive=True)
        rows.append({"window": w, "values": list(byWindow[w]), "order": p, "limit": f0, "why": why, "bracket": None})
    kept = {}
    for r in reversed(rows):
        if r["why"] is not None:
            continue
        above = [v for v, lim in kept.items() if lim > r["limit"]]
        if above:
            r["why"] = "limit %.4g below the %g ms window's %.4g" % (r["limit"], 1e3 * min(above), kept[min(above)])
        else:
            kept[r["window"]] = r["limit"]
    for r in rows:
        if r["window"] in kept:
            continue
        f = r["values"]
        lows = [lim for v, lim in kept.items() if v > r["window"]]
        highs = [lim for v, lim in kept.items() if v < r["window"]]
        if f[0] > f[1] > f[2]:
            highs.append(f[2])
        elif f[0] < f[1] < f[2]:
            lows.append(f[2])
        if lows and highs and max(lows) <= min(highs):
            r["bracket"] = (max(lows), min(highs))
    return rows


def limitText(f, h, positive=False):
    """One line's verdict of :func:`limitOf`."""
    p, f0, why = limitOf(f, h, positive)
    return "order %.2f, extrapolated to Δx 0: %.4g" % (p, f0) if why is None else "no limit to trust (%s)" % why


QUANTITIES = (("free", "arrival"), ("free", "h_f"), ("free", "v_f"), ("front", "tipHeight"), ("coupled", "first_touch"),
              ("coupled", "blow"),
              ("coupled", "plateau"), ("coupled", "tilt_at"), ("coupled", "travel_at"))


def isPositiveQuantity(key):
    """Whether a quantity of a run's numbers cannot be zero or less (a time, a depth, a speed, a
    mean push), so that no limit at or below zero is kept (:func:`limitOf`). A tilt, a travel, the
    front's nose height and a line of action may tend to zero or cross it."""
    return key in ("arrival", "h_f", "v_f", "first_touch", "blow", "plateau") or key.startswith("load_")


def partNames():
    """The keys of the blow by parts in a run's coupled numbers (mpmsdem.analysis.BLOW_PARTS):
    the mean force over each, then the height of its line of action."""
    analysis = analysisModule()
    return [analysis.blowPartName(span, kind) for kind in ("load", "action") for span in analysis.BLOW_PARTS]


def extrapolations(runs):
    """Observed order and extrapolated value of each quantity (the blow by parts after the blow)
    over the three finest spacings of each set, damping and width (:func:`limitOf`)."""
    blow = QUANTITIES.index(("coupled", "blow")) + 1
    quantities = QUANTITIES[:blow] + tuple(("coupled", name) for name in partNames()) + QUANTITIES[blow:]
    lines, groups = [], {}
    for r in runs:
        groups.setdefault(group(r), []).append(r)
    for g, rs in sorted(groups.items()):
        rs = sorted(rs, key=lambda r: -r["dx"])[-3:]
        if len(rs) != 3:
            continue
        for part, key in quantities:
            vals = [(r["free"]["front"] if part == "front" else r[part]).get(key) for r in rs]
            if None in vals:
                continue
            lines.append("- %s, %s, width %g m%s, %s at Δx %s: %s -> %s" % (
                g[0], g[1], g[2], "" if g[3] == 8 else ", %d per cell" % g[3], key, ", ".join("%.4g" % r["dx"] for r in rs), ", ".join("%.4g" % v for v in vals),
                limitText(vals, [r["dx"] for r in rs], isPositiveQuantity(key))))
    return "\n".join(lines)


# The outputs mpmsdem.tradeoffs offers from this study, by the quantity each one is.
OUTPUTS = {("free", "arrival"): "front_arrival", ("free", "h_f"): "flow_depth", ("free", "v_f"): "flow_speed",
           ("coupled", "first_touch"): "first_touch", ("coupled", "blow"): "block_peak_force",
           ("coupled", "plateau"): "plateau_force", ("coupled", "tilt_at"): "tilt", ("coupled", "travel_at"): "travel"}


def packageStudy(runs, settings, hold, width, command):
    """The study of the spacings of one set, damping and width (8 points per cell) for
    py/mpmsdem/tradeoffs.json: each run's relative error against the value extrapolated to Δx 0
    through the three finest (:func:`limitOf`) where they give one to trust, the outputs where
    they do not under ``unconverged``, and the work of each run per simulated second (points /
    step: the runs may end at different times) relative to the run at the reference spacing.
    None without three spacings or without that run."""
    rs = sorted([r for r in runs if group(r) == (settings, hold, width, 8)], key=lambda r: -r["dx"])
    finest = rs[-3:]
    default = [r for r in rs if abs(r["dx"] - REFERENCE_DX) <= 1e-12 * REFERENCE_DX]
    if len(rs) < 3 or not default:
        return None
    h = [r["dx"] for r in finest]
    work = lambda r: r["points"] / r["dt"]  # noqa: E731
    limits, unconverged = {}, {}
    for (part, key), out in OUTPUTS.items():
        vals = [r[part].get(key) for r in finest]
        if None in vals:
            continue
        p, f0, why = limitOf(vals, h, isPositiveQuantity(key))
        if why:
            unconverged[out] = "%s at %s cells per block height (Δx %s m): %s, %s" % (
                out, " / ".join("%.1f" % r["cells_per_block"] for r in finest), " / ".join("%.4g" % d for d in h),
                " / ".join("%.4g" % v for v in vals), why)
        else:
            limits[(part, key)] = f0
    rows = [{"settings": {"dx": r["dx"], "cells_per_block_height": r["cells_per_block"], "ppc": 8,
                          "flip_viscosity": r["viscosity"], "precision": "double"},
             "errors": {OUTPUTS[q]: (r[q[0]][q[1]] - f0) / f0 for q, f0 in limits.items()
                        if r[q[0]].get(q[1]) is not None},
             "cost": work(r) / work(default[0]), "cpu_cost": None, "reference": False, "sensitivity": False}
            for r in rs]
    return {"name": "coupled_cube_impact_%s_held" % hold,
            "scene": "examples/flume_block.py --full (paper §3.2, the copper cube h_b 0.02 m), %s set, %g m wide, "
                     "0.5 s, PIC %s held" % (settings, width, hold),
            "commit": ", ".join(sorted({r["commit"] for r in rs} | {r.get("free_commit", r["commit"]) for r in rs})),
            "machine": "2-core x86_64 VM, two threads, shared (cpu_cost not measured)",
            "command": command,
            "reference": {"dx": 0.0},
            "extrapolated": "f0 of f = f0 + C dx^p through Δx %s m (Richardson, observed order p)" % (
                " / ".join("%.4g" % d for d in h)),
            "rows": rows, "unconverged": unconverged}


def packageData(runs, settings, hold, width, command):
    """Replace this study in py/mpmsdem/tradeoffs.json (the other studies stay)."""
    study = packageStudy(runs, settings, hold, width, command)
    if study is None:
        raise SystemExit("--package-data: the %s set held by %s at width %g m needs three finished spacings, one "
                         "of them %g m" % (settings, hold, width, REFERENCE_DX))
    storeStudy(study)


def storeStudy(study):
    """Replace the study of this name in py/mpmsdem/tradeoffs.json (the other studies stay),
    through a temporary file: a killed run leaves the old file whole."""
    path = os.path.join(ROOT, "py", "mpmsdem", "tradeoffs.json")
    with open(path) as f:
        data = json.load(f)
    data["studies"] = [s for s in data["studies"] if s["name"] != study["name"]] + [study]
    with open(path + ".tmp", "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    os.replace(path + ".tmp", path)
    print("stored the study %s in %s" % (study["name"], path))


def main(argv):
    a = parse(argv)
    a.argv = argv
    if a.run_prepared:
        return runPrepared(a)
    os.makedirs(a.out, exist_ok=True)
    if a.child:
        prepare(a, float(a.child[1]), os.path.join(a.out, runName(a, float(a.child[1]))))
        return
    if a.prepare:
        for dx in a.dx:
            print("prepared %s" % prepareRun(a, dx), flush=True)
        return
    if a.reread:
        for path in sorted(glob.glob(os.path.join(a.out, "*.json"))):
            with open(path) as f:
                r = json.load(f)
            folder = path[:-len(".json")]
            if "same_run_as" in r or not os.path.exists(os.path.join(folder, "coupled", "coupled.h5")):
                continue
            r["coupled"] = coupled(folder, r["duration"])
            writeJson(path, r)
    elif not a.report_only:
        import mpmsdem.driver
        exe = mpmsdem.driver.executable()
        for dx in a.dx:
            path = os.path.join(a.out, runName(a, dx) + ".json")
            if os.path.exists(path) and not a.rerun_coupled:
                print("%s: done before (%s)" % (runName(a, dx), path))
                continue
            if a.rerun_coupled and os.path.exists(path):
                os.replace(path, path + ".previous")  # what the rerun replaces, kept beside it
            t0 = time.time()
            print("%s: running (PIC viscosity %.4g m²/s, %s) ..." % (runName(a, dx), viscosity(a, dx), exe), flush=True)
            runOne(a, dx, exe)
            print("%s: %.0f s" % (runName(a, dx), time.time() - t0), flush=True)
    runs = load(a.out)
    text = table(runs)
    if a.extrapolate:
        text += "\n\n" + extrapolations(runs)
    print(text)
    with open(os.path.join(a.out, "convergence.md"), "w") as f:
        f.write(text + "\n")
    if a.package_data:
        packageData(runs, a.settings, a.hold, a.width,
                    "OMP_NUM_THREADS=2 python3 scripts/validation/flume_convergence.py --dx %s --hold %s --out OUT, "
                    "then --report-only --package-data" % (",".join("%.10g" % d for d in sorted(a.dx, reverse=True)),
                                                           a.hold))


if __name__ == "__main__":
    main(sys.argv[1:])
