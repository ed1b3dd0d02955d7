#!/usr/bin/env python3
"""Block sweep radius R/h_b against cost and outputs (paper Appendix D), on the coarse §3.2 flume.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/bench/tradeoff_sweep_radius.py
        [--sizes 20,40] [--ratios 1/200,1/100,1/50,1/20,1/10,1/8] [--duration 1.2] [--window 0.4 0.7]
        [--engine yade|driver] [--exe PATH] [--jobs 1] [--threads 1] [--out results/tradeoff_sweep_radius]
        [--markdown docs/tradeoffs.md] [--plot docs/img/tradeoff_sweep_radius.png] [--report-only]
        [--dx 0.02] [--settings table1|joint] [--backend cpu|cuda] [--precision double|float]
        [--prepare | --collect]

The scene is examples/flume_block.py's coarse one (dx 0.02 m, 12,000 material points, the copper
cube's upstream face at the column front + L0, elastic barrier, α 0.99 per step at the flume's
O.dt) with only the cube changed: side h_b (``--sizes``, mm) and sweep radius R = ratio × h_b
(``--ratios``). A 40 mm cube keeps the 20 mm cube's upstream face, so the flow meets it at the same
station after the same run-out L0; its grid is one cell taller (the flume makes room above the
tallest block), which is empty space.

Each configuration runs in its own process (one at a time unless ``--jobs``; OMP_NUM_THREADS =
``--threads``) and reports: travel distance at the end, peak F_t (downstream flow force on the
cube, 10 ms moving mean) and its time, mean F_t over ``--window``, the largest rotation of the
cube from its start pose, its highest rise above the bed, the time of the first flow contact, the
time step, the coupled contact critical step, the number of steps, the wall and CPU seconds of the
step loop, and cost relative to the R = h_b/20 run of the same size in the same command (wall,
CPU, steps). F_t changes by tens of newtons from one step to the next while single points strike
the face, so a mean of 2 ms records depends on the steps they fall on (records one step apart
gave 9.61 and 10.43 N for the same run); with ``--engine yade`` the means come from the impulse
summed every step, with the driver from its 2 ms records (as ``flume_block.py --from-driver``).

Time step. The flume sets O.dt = 0.5 × the MPM CFL step at rest. Every step the coupled engine
computes its contact critical step: per moving block sqrt(m / (Σk_block-block + Σk_MP)) and its
rotational counterpart, and per MP contact sqrt(m_p / max(k_n, K_t)), with the tangent barrier
stiffness k_n of Eq 10 at the current overlap, times the SDEM safety factor (the driver checks the
same function, pkg/coupling/CoupledWorld.cpp). With ``--engine yade`` (default) the run reads it
after every step and takes min(O.dt of the flume, 0.9 × that step) for the next one, so a radius
that forces a smaller step gets it and pays for it; the flow keeps its PIC damping per second
(``--flip-reference-dt``: default the scene's 5e-5 s, 201 /s; 5e-6 for the paper's 2010 /s).
``--engine driver`` runs the same scene through mpmsdem-run (``--exe``) with the flume's fixed
O.dt, which the driver checks against the same critical step every step (a run whose step is too
large stops and is reported as failed); it is faster per step but does not report the critical
step's value.

Results: ``--out``/h<mm>_r<ratio>/result.json per run, ``--out``/results.json for all; a table
on stdout, ``--markdown FILE`` replaces (or appends) the generated section of FILE between its
markers, ``--plot PNG`` draws travel and peak force against R/h_b (log x, one line per size) and
the cost ratio. ``--report-only`` redoes table, markdown and plot from ``--out``.

``--dx 0.01`` is the paper's resolution (96,000 material points; its own generated section of
``--markdown``). ``--settings`` names the flow and friction set of mpmsdem.flume.FLUME_SETTINGS:
``table1`` (default: Table 1 as we read it, the flume's default blend) or ``joint`` (the set
``examples/flume_block.py --full`` runs by default: basal and side-wall friction, μ₂, flow–cube
friction and the PIC viscosity of our joint design at dx 0.01 m; its own generated section).
The driver runs the MPM on ``--backend`` in ``--precision``. Where the driver is to run on
another machine (a GPU machine without YADE), ``--prepare`` writes each run's
scene (``--out``/h<mm>_r<ratio>/scene.json, with prepared.json) and ``--out``/run_driver.sh, which
runs them all there (``MPMSDEM_RUN``: the driver, ``JOBS``: runs at a time) and leaves each run's
coupled.h5 and driver.log in its folder; with that folder back, ``--collect`` reads them into
result.json files and reports as the other modes do.
"""
import argparse
import fractions
import glob
import importlib.util
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import types

from bench_mpm import machine  # same folder: shared with the other benchmarks

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
DX = 0.02                   # grid spacing of the coarse scene [m] (--dx)
SAMPLE = 0.002              # record interval [s], as flume_block.py's coupled records
SMOOTH = 0.01               # moving mean of F_t for the peak [s] (docs/coupled-results.md)
REFERENCE_RATIO = 1.0 / 20  # the paper's recommended R/h_b: the cost reference
DX_RANGE = (0.005, 0.02)    # m: coarser than the coarse scene leaves the 20 mm cube inside one cell
SIZE_RANGE = (0.0, 100.0)   # mm: a cube wider than half the 0.2 m flume would be another scene
RATIO_RANGE = (0.0, 0.5)    # R must stay below half the side (a box core of positive size)


def markers(dx, settings="table1"):
    """The generated section of one resolution and set in --markdown: the coarse one's, or tagged
    by dx and by a set other than table1."""
    tag = ("" if dx == DX else " --dx %g" % dx) + ("" if settings == "table1" else " --settings %s" % settings)
    return ("<!-- tradeoff_sweep_radius.py%s: begin generated section -->" % tag,
            "<!-- tradeoff_sweep_radius.py%s: end generated section -->" % tag)


def resultMarkers(results):
    """markers() of the runs the results come from, whatever flags read them back."""
    return markers(results[0].get("dx", DX), results[0].get("settings", "table1"))


# ---------------------------------------------------------------------------------------- input
def parseRatio(text):
    s = text.strip()
    try:
        v = float(fractions.Fraction(s))
    except (ValueError, ZeroDivisionError):
        raise ValueError("--ratios: %r is not a number or a fraction such as 1/20" % text)
    if not (RATIO_RANGE[0] < v < RATIO_RANGE[1]):
        raise ValueError("--ratios: %s = %g is out of range: R/h_b must be in (%g, %g) (the sweep radius must be "
                         "smaller than half the cube's side)" % (s, v, RATIO_RANGE[0], RATIO_RANGE[1]))
    return v


def ratioLabel(v):
    f = fractions.Fraction(v).limit_denominator(1000)
    return "%d/%d" % (f.numerator, f.denominator) if abs(float(f) - v) < 1e-12 * v else "%g" % v


def parseSize(text):
    try:
        v = float(text)
    except ValueError:
        raise ValueError("--sizes: %r is not a number (cube side in mm)" % text)
    if not (SIZE_RANGE[0] < v <= SIZE_RANGE[1]):
        raise ValueError("--sizes: %g mm is out of range: the cube side h_b must be in (%g, %g] mm"
                         % (v, SIZE_RANGE[0], SIZE_RANGE[1]))
    return v


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="20,40", help="cube sides h_b [mm], comma-separated, each in (0, 100]")
    ap.add_argument("--ratios", default="1/200,1/100,1/50,1/20,1/10,1/8",
                    help="R/h_b values, comma-separated fractions or decimals, each in (0, 0.5)")
    ap.add_argument("--duration", type=float, default=1.2, help="simulated time per run [s], in (0, 5]")
    ap.add_argument("--window", type=float, nargs=2, default=(0.4, 0.7), metavar=("T0", "T1"),
                    help="window of the mean F_t after the impact [s] (default 0.4 0.7, as docs/coupled-results.md)")
    ap.add_argument("--engine", default="yade", choices=("yade", "driver"),
                    help="yade: CoupledEngine in YADE, reports the critical step (default); driver: mpmsdem-run")
    ap.add_argument("--exe", default=None, help="mpmsdem-run for --engine driver (default: on the PATH, else "
                                                "build/mpmsdem-run)")
    ap.add_argument("--jobs", type=int, default=1, help="runs at a time (default 1), in [1, number of cores]")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each run (default 1), >= 1")
    ap.add_argument("--out", default=os.path.join("results", "tradeoff_sweep_radius"), help="output folder")
    ap.add_argument("--markdown", metavar="FILE", default=None,
                    help="replace the generated section of FILE (between its markers; appended if absent)")
    ap.add_argument("--plot", metavar="PNG", default=None, help="write the plot to PNG")
    ap.add_argument("--report-only", action="store_true",
                    help="no runs: table, --markdown and --plot from the result.json files in --out")
    ap.add_argument("--flip-reference-dt", default=None,
                    help="reference step of the flow's FLIP/PIC blend [s] > 0 (default: the scene default, 5e-5 s, "
                         "201 /s of PIC damping; 5e-6: the paper's blend, 2010 /s), or 'step' (alpha per step, Eq 4)")
    ap.add_argument("--dx", type=float, default=DX,
                    help="grid spacing [m] (default 0.02, the coarse scene; 0.01: the paper's), in [0.005, 0.02]")
    ap.add_argument("--settings", default="table1", choices=("table1", "joint"),
                    help="flow and friction set (mpmsdem.flume.FLUME_SETTINGS): table1 (default) or joint (the "
                         "set of examples/flume_block.py --full, with its PIC viscosity)")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"), help="MPM backend of --engine driver")
    ap.add_argument("--precision", default="double", choices=("double", "float"),
                    help="MPM precision of --engine driver")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--prepare", action="store_true",
                      help="write the driver scenes and run_driver.sh to run them elsewhere; no runs")
    mode.add_argument("--collect", action="store_true",
                      help="read the driver runs of run_driver.sh in --out into result.json files, then report")
    ap.add_argument("--one", nargs=2, metavar=("H_MM", "RATIO"), help=argparse.SUPPRESS)  # a child run
    a = ap.parse_args(argv)
    try:
        from mpmsdem.mpm import flipReferenceArg
        if a.flip_reference_dt is not None:
            a.flip_reference_dt = flipReferenceArg(a.flip_reference_dt)
        a.sizeList = [parseSize(s) for s in a.sizes.split(",") if s.strip()]
        a.ratioList = [parseRatio(s) for s in a.ratios.split(",") if s.strip()]
        if not a.sizeList:
            raise ValueError("--sizes: empty: give at least one cube side in mm, e.g. 20,40")
        if not a.ratioList:
            raise ValueError("--ratios: empty: give at least one R/h_b, e.g. 1/20")
        if not (math.isfinite(a.duration) and 0 < a.duration <= 5):
            raise ValueError("--duration = %g s: must be in (0, 5]" % a.duration)
        t0, t1 = a.window
        if not (math.isfinite(t0) and math.isfinite(t1) and 0 <= t0 < t1):
            raise ValueError("--window = %g %g s: must satisfy 0 <= T0 < T1" % (t0, t1))
        cores = os.cpu_count() or 1
        if not 1 <= a.jobs <= cores:
            raise ValueError("--jobs = %d: must be in [1, %d] (the number of cores)" % (a.jobs, cores))
        if a.threads < 1:
            raise ValueError("--threads = %d: must be >= 1" % a.threads)
        if not (math.isfinite(a.dx) and DX_RANGE[0] <= a.dx <= DX_RANGE[1]):
            raise ValueError("--dx = %g m: must be in [%g, %g]" % (a.dx, DX_RANGE[0], DX_RANGE[1]))
        if a.settings == "joint" and a.flip_reference_dt is not None:
            raise ValueError("--flip-reference-dt is for --settings table1: the joint set fixes the flow's PIC "
                             "viscosity")
        if (a.prepare or a.collect) and a.engine != "driver":
            raise ValueError("--prepare and --collect are for --engine driver")
        if (a.backend, a.precision) != ("cpu", "double") and a.engine != "driver":
            raise ValueError("--backend and --precision are for --engine driver (YADE runs take the flume's own)")
        if a.engine == "driver" and not (a.report_only or a.prepare or a.collect):
            a.exe = a.exe or shutil.which("mpmsdem-run") or os.path.join(ROOT, "build", "mpmsdem-run")
            if not (os.path.isfile(a.exe) and os.access(a.exe, os.X_OK)):
                raise ValueError("--exe = %s: not an executable file (the mpmsdem-run driver, e.g. "
                                 "build/mpmsdem-run)" % a.exe)
            a.exe = os.path.abspath(a.exe)
        elif a.exe is not None and a.engine != "driver":
            raise ValueError("--exe is for --engine driver only")
        if a.markdown and os.path.isdir(a.markdown):
            raise ValueError("--markdown = %s: a folder, must be a Markdown file" % a.markdown)
        if a.plot and not a.plot.lower().endswith(".png"):
            raise ValueError("--plot = %s: must be a .png path" % a.plot)
    except ValueError as e:
        ap.error(str(e))
    return a


def runName(hmm, ratio):
    return "h%g_r%s" % (hmm, ratioLabel(ratio).replace("/", "-"))


# ----------------------------------------------------------------------------------- child run
def loadExample():
    # the flume's station and column come from the example, so the two cannot drift apart
    spec = importlib.util.spec_from_file_location("flume_block", os.path.join(ROOT, "examples", "flume_block.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def buildScene(ex, h, ratio, flipReferenceDt, dx, settings):
    from mpmsdem.flume import FLUME_SETTINGS, Block, Flume
    st = FLUME_SETTINGS[settings]
    # the example's own mapping of a set to the flume's keywords (its coarse scene: full=False)
    kw = ex.flumeKeywords(types.SimpleNamespace(full=False, **st))
    cube = Block(half=(h / 2,) * 3, x=ex.COLUMN + ex.L0, sweepRadius=ratio * h, density=8900, friction=0.67,
                 flowFriction=st["flow_friction"])
    return Flume(dx=dx, blocks=[cube], verbose=False, flipReferenceDt=flipReferenceDt, **kw)


def runYade(a, h, ratio, folder):
    import mpmsdem  # before yade: it finds YADE's folder in a plain python3
    from yade import O
    from yade.wrapper import PyRunner
    ex = loadExample()
    sc = buildScene(ex, h, ratio, a.flip_reference_dt, a.dx, a.settings)
    base = O.dt  # the flume's step
    coupled = sc.coupled
    # "warn" lets a step that outgrows the contact step finish and be counted.
    coupled.dtCheck = "warn"
    cid = sc.blockIds[0]
    body = O.bodies[cid]
    ori0 = body.state.ori
    x0, z0 = body.state.pos[0], body.state.pos[2]
    st = {"minContact": math.inf, "tMinContact": None, "minDt": base, "limited": 0, "next": 0.0, "rows": [],
          "impulse": 0.0, "lastDt": base, "maxRot": 0.0, "maxRise": -math.inf, "stepT": [], "stepI": []}

    def angle():
        d = math.degrees((body.state.ori * ori0.conjugate()).toAngleAxis()[0])
        return min(d, 360 - d)

    def account():
        # F_t is spiky from one step to the next (single points strike the face): its time
        # means come from the impulse summed every step, not from the 2 ms records.
        t = sc.mpm.time
        if O.iter > 0:
            st["impulse"] += coupled.force(cid)[0] * st["lastDt"]
        rot, rise = angle(), body.state.pos[2] - z0
        st["maxRot"], st["maxRise"] = max(st["maxRot"], rot), max(st["maxRise"], rise)
        st["stepT"].append(t)
        st["stepI"].append(st["impulse"])
        if t >= st["next"] * (1 - 1e-12):  # the driver's record times, for a like-for-like series
            st["rows"].append((t, body.state.pos[0] - x0, rise, coupled.force(cid)[0], rot))
            while st["next"] <= t * (1 + 1e-12):
                st["next"] += SAMPLE

    def beforeStep():
        # Runs first in the step: the block state and flow force are those of time t (what
        # coupled.h5 records at t), and the O.dt set here is the one YADE adds to O.time.
        account()
        dt = base
        if O.iter > 0:
            c = coupled.contactTimeStep
            if c < st["minContact"]:
                st["minContact"], st["tMinContact"] = c, sc.mpm.time
            dt = min(base, 0.9 * c)
            if dt < base:
                st["limited"] += 1
            st["minDt"] = min(st["minDt"], dt)
        # the last step ends on the duration, as the driver's does
        rest = a.duration - sc.mpm.time
        O.dt = rest if 1e-9 * base < rest < dt else dt
        st["lastDt"] = O.dt

    import builtins
    builtins._tradeoffBeforeStep = beforeStep  # PyRunner commands are evaluated in builtins' reach
    O.engines = [PyRunner(command="_tradeoffBeforeStep()", iterPeriod=1, initRun=True)] + list(O.engines)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    while sc.mpm.time < a.duration * (1 - 1e-12):
        # steps are never longer than base: a chunk counted with it cannot pass the duration
        n = max(1, min(500, int(math.ceil((a.duration - sc.mpm.time) / base - 1e-9))))
        mpmsdem.run(n, coupled)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    if coupled.contactTimeStep < st["minContact"]:
        st["minContact"], st["tMinContact"] = coupled.contactTimeStep, sc.mpm.time
    st["next"] = min(st["next"], sc.mpm.time)  # the end state is always recorded
    account()
    t, travel, rise, ft, rot = (list(c) for c in zip(*st["rows"]))
    return {"t": t, "travel": travel, "rise": rise, "Ft": ft, "rotation": rot, "step_t": st["stepT"],
            "step_impulse": st["stepI"]}, {
        "engine": "yade", "flip_blend": sc.flipBlend(), "dt_flume": base, "dt_min": st["minDt"], "contact_limited_steps": st["limited"],
        "dt_warnings": int(coupled.timeStepWarnings), "contact_step_min": st["minContact"],
        "contact_step_min_time": st["tMinContact"], "steps": int(O.iter), "wall_s": wall, "cpu_s": cpu,
        "particles": int(sc.mpm.numParticles), "cube_mass": float(body.state.mass), "end_time": float(sc.mpm.time),
        "max_rotation_step_deg": st["maxRot"], "max_rise_step": st["maxRise"]}


def prepareDriver(a, h, ratio, folder):
    """Write the run's driver scene (folder/scene.json, its outputs to folder/driver) and
    folder/prepared.json (what reading its outputs needs); returns the latter."""
    import mpmsdem.driver  # before yade: it finds YADE's folder in a plain python3
    from yade import O
    ex = loadExample()
    sc = buildScene(ex, h, ratio, a.flip_reference_dt, a.dx, a.settings)
    base = O.dt
    prepared = {"flip_blend": sc.flipBlend(), "cube_index": sc.sdem.ids.index(sc.blockIds[0]), "cube_mass": float(O.bodies[sc.blockIds[0]].state.mass),
                "dt": base, "particles": int(sc.mpm.numParticles), "backend": a.backend, "precision": a.precision,
                "dx": a.dx, "duration": a.duration, "settings": a.settings}
    mpmsdem.driver.writeScene(os.path.join(folder, "scene.json"), sc.coupled, duration=a.duration, dt=base,
                              outputDir="driver", outputEvery=a.duration, seriesEvery=SAMPLE, vtk="none",
                              backend=a.backend, precision=a.precision)
    with open(os.path.join(folder, "prepared.json"), "w") as f:
        json.dump(prepared, f, indent=1)
    return prepared


def readDriver(folder, prepared, cpuSeconds=None):
    """The series and run facts of a finished driver run in folder (driver.log, driver/coupled.h5)."""
    import h5py
    from mpmsdem import analysis
    logPath = os.path.join(folder, "driver.log")
    if not os.path.exists(logPath):
        raise RuntimeError("not run (no driver.log)")
    with open(logPath) as f:
        log = f.read()
    done = re.search(r"done, t = (\S+) s, (\d+) steps, (\S+) s wall", log)
    if not done:
        lines = [line for line in log.strip().splitlines() if line.strip()]
        raise RuntimeError("mpmsdem-run did not finish; its last line: %s" % (lines[-1] if lines else "(none)"))
    low = re.search(r"smallest contact step (\S+) s at t = (\S+) s", log)
    cube = prepared["cube_index"]
    block, _ = analysis.driverBlockSeries(os.path.join(folder, "driver"), block=cube)
    with h5py.File(os.path.join(folder, "driver", "coupled.h5"), "r", locking=False) as f:
        z = f["series"]["pos"][:, 3 * cube + 2]  # the cube's height (driverBlockSeries reads along the flume)
    series = {"t": block["t"].tolist(), "travel": block["travel"].tolist(), "rise": (z - z[0]).tolist(),
              "Ft": block["Ft"].tolist(), "rotation": block["rotation"].tolist()}
    if "first_contact" in block:  # files written before it was recorded have none
        series["first_contact"] = block["first_contact"].tolist()
    return series, {"engine": "driver", "backend": prepared.get("backend", "cpu"),
                    "precision": prepared.get("precision", "double"), "dt_flume": prepared["dt"],
                    "flip_blend": prepared.get("flip_blend", "alpha 0.99 per step (prepared before it was recorded)"),
                    "dt_min": prepared["dt"], "contact_limited_steps": 0, "dt_warnings": 0,
                    "contact_step_min": float(low.group(1)) if low else None,
                    "contact_step_min_time": float(low.group(2)) if low else None,
                    "steps": int(done.group(2)), "wall_s": float(done.group(3)),
                    # the whole driver process (seeding and output included), not only its step loop
                    "cpu_s": cpuSeconds, "particles": prepared["particles"], "cube_mass": prepared["cube_mass"],
                    "end_time": float(done.group(1))}


def runDriver(a, h, ratio, folder):
    import resource
    prepared = prepareDriver(a, h, ratio, folder)
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads))
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([a.exe, "scene.json"], capture_output=True, text=True, env=env, cwd=folder)
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(os.path.join(folder, "driver.log"), "w") as f:
        f.write(p.stdout + p.stderr)
    if p.returncode != 0:
        msg = (p.stderr.strip().splitlines() or ["exit status %d" % p.returncode])[-1]
        raise RuntimeError("mpmsdem-run exit %d: %s" % (p.returncode, msg))
    return readDriver(folder, prepared, (cpu1.ru_utime + cpu1.ru_stime) - (cpu0.ru_utime + cpu0.ru_stime))


def firstTurn(series, deg=45.0):
    """Time of the first record with the cube turned by ``deg`` or more (None: never)."""
    for t, r in zip(series["t"], series["rotation"]):
        if r >= deg:
            return float(t)
    return None


def summarise(series, window):
    import numpy as np
    from mpmsdem import analysis
    t = np.asarray(series["t"])
    ft = np.asarray(series["Ft"])
    w = max(1, int(round(SMOOTH / np.median(np.diff(t)))))
    smooth = np.convolve(ft, np.ones(w) / w, mode="same")  # as flume_block.py --from-driver
    j = int(np.argmax(smooth))
    touched = np.nonzero(ft != 0)[0]
    covered = t[-1] >= window[1] * (1 - 1e-9)
    inWin = (t >= window[0]) & (t <= window[1])
    rot = np.asarray(series["rotation"])
    out = {"travel": float(series["travel"][-1]), "peak_force_sampled": float(smooth[j]),
           "peak_time_sampled": float(t[j]),
           "mean_force_window_sampled": float(ft[inWin].mean()) if covered and inWin.any() else None,
           "first_touch_sampled": float(t[touched[0]]) if touched.size else None,
           "max_rotation_deg": float(rot.max()), "rotation_end_deg": float(rot[-1]),
           "max_rise": float(np.max(series["rise"])), "force_measure": "2 ms records",
           "rotation45_time": firstTurn(series)}
    out["peak_force"], out["peak_time"] = out["peak_force_sampled"], out["peak_time_sampled"]
    out["mean_force_window"] = out["mean_force_window_sampled"]
    # the contact's first step where the driver recorded it, else the first record with a force
    out["first_touch"] = analysis.touchTime(series)
    if "step_impulse" in series:
        ts, imp = np.asarray(series["step_t"]), np.asarray(series["step_impulse"])
        # the impulse at ts[k] holds the step that ended there: the first one it grew in began
        # at ts[k - 1] (the contact's first step, where a record holds the step before it)
        grew = np.nonzero(imp != 0)[0]
        out["first_touch"] = float(ts[grew[0] - 1]) if grew.size and grew[0] > 0 else None
        half = SMOOTH / 2
        mid = ts[(ts >= ts[0] + half) & (ts <= ts[-1] - half)]
        if mid.size:
            mean = (np.interp(mid + half, ts, imp) - np.interp(mid - half, ts, imp)) / SMOOTH
            k = int(np.argmax(mean))
            out["peak_force"], out["peak_time"] = float(mean[k]), float(mid[k])
        out["mean_force_window"] = (float((np.interp(window[1], ts, imp) - np.interp(window[0], ts, imp)) /
                                          (window[1] - window[0])) if covered else None)
        out["force_measure"] = "impulse summed every step"
    return out


def child(a):
    hmm, ratio = float(a.one[0]), float(a.one[1])
    folder = os.path.join(a.out, runName(hmm, ratio))
    os.makedirs(folder, exist_ok=True)
    if a.prepare:
        prepareDriver(a, hmm / 1000.0, ratio, folder)
        return
    load0 = os.getloadavg()
    series, run = (runYade if a.engine == "yade" else runDriver)(a, hmm / 1000.0, ratio, folder)
    writeResult(a, hmm, ratio, folder, series, run, list(load0), list(os.getloadavg()))


def writeResult(a, hmm, ratio, folder, series, run, loadBefore, loadAfter):
    """folder/result.json and series.json of a finished run (loads: None where not known)."""
    result = {"h_mm": hmm, "ratio": ratio, "ratio_label": ratioLabel(ratio), "sweep_radius": ratio * hmm / 1000.0,
              "duration": a.duration, "window": list(a.window), "threads": a.threads, "dx": a.dx, "settings": a.settings,
              "load_before": loadBefore, "load_after": loadAfter}
    result.update(run)
    result.update(summarise(series, a.window))
    if "max_rotation_step_deg" in run:  # sampled every step, finer than the records
        result["max_rotation_deg"], result["max_rise"] = run["max_rotation_step_deg"], run["max_rise_step"]
    with open(os.path.join(folder, "series.json"), "w") as f:
        json.dump(series, f)
    with open(os.path.join(folder, "result.json"), "w") as f:
        json.dump(result, f, indent=1)


# ---------------------------------------------------------------------------------------- parent
def commit():
    try:
        return subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True).strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def childCommand(a, hmm, ratio):
    cmd = [sys.executable, os.path.abspath(__file__), "--one", repr(hmm), repr(ratio), "--duration", repr(a.duration),
           "--window", repr(a.window[0]), repr(a.window[1]), "--engine", a.engine, "--threads", str(a.threads),
           "--out", a.out, "--dx", repr(a.dx), "--settings", a.settings, "--backend", a.backend,
           "--precision", a.precision,
           ] + ([] if a.flip_reference_dt is None else ["--flip-reference-dt", str(a.flip_reference_dt)])
    if a.prepare:
        cmd += ["--prepare"]
    elif a.engine == "driver":
        cmd += ["--exe", a.exe]
    return cmd


RUN_DRIVER_SH = """#!/usr/bin/env bash
# Runs this sweep's prepared driver scenes (tradeoff_sweep_radius.py --prepare): MPMSDEM_RUN (the
# driver, default mpmsdem-run on the PATH), JOBS runs at a time (default 1), OMP_NUM_THREADS each
# (with JOBS > 1, at most the cores over JOBS: unset, every run takes every core). Runs sharing one
# GPU take turns on it: four at once on one H200 took 219 s each, 55 s a run.
# Each run leaves driver.log and driver/coupled.h5 in its folder; then, with YADE:
#   tradeoff_sweep_radius.py --collect --out THIS_FOLDER (and the --sizes, --ratios, --dx given to --prepare)
set -u
run=$(readlink -f "$(command -v "${MPMSDEM_RUN:-mpmsdem-run}")") || { echo "no driver: set MPMSDEM_RUN"; exit 2; }
cd "$(dirname "$0")"
machine=$({ grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'; echo "$(getconf _NPROCESSORS_ONLN) cores";
  nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null; } | paste -sd, - | sed 's/,/, /g; s/"//g')
one='cd "$1" && "$0" scene.json --backend %(backend)s --precision %(precision)s > driver.log 2>&1 && echo "$1 done" || echo "$1 FAILED (see $1driver.log)"'
start=$SECONDS
ls -d h*_r*/ | xargs -P "${JOBS:-1}" -n 1 sh -c "$one" "$run"
printf '{"machine": "%%s", "jobs": %%d, "threads": "%%s", "wall_total": %%d}\\n' "$machine" "${JOBS:-1}" "${OMP_NUM_THREADS:-all cores}" $((SECONDS - start)) > run_driver.json
"""


def runAll(a, runs):
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads))
    pending, active, failed = list(runs), [], []
    k = 0
    while pending or active:
        while pending and len(active) < a.jobs:
            hmm, ratio = pending.pop(0)
            folder = os.path.join(a.out, runName(hmm, ratio))
            os.makedirs(folder, exist_ok=True)
            stale = os.path.join(folder, "prepared.json" if a.prepare else "result.json")
            if os.path.exists(stale):
                os.remove(stale)
            log = open(os.path.join(folder, "run.log"), "w")
            p = subprocess.Popen(childCommand(a, hmm, ratio), stdout=log, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
            active.append((p, hmm, ratio, folder, log, time.time()))
        time.sleep(0.5)
        for item in list(active):
            p, hmm, ratio, folder, log, started = item
            if p.poll() is None:
                continue
            active.remove(item)
            log.close()
            k += 1
            head = "[%d/%d] h_b %g mm, R/h_b %s (R %.3g mm)" % (k, len(runs), hmm, ratioLabel(ratio), ratio * hmm)
            path = os.path.join(folder, "prepared.json" if a.prepare else "result.json")
            if p.returncode != 0 or not os.path.exists(path):
                with open(os.path.join(folder, "run.log")) as f:
                    lines = [line.strip() for line in f if line.strip()]
                why = lines[-1] if lines else "exit status %d" % p.returncode
                failed.append((hmm, ratio, why))
                print("%s: FAILED after %.0f s: %s (log: %s)" % (head, time.time() - started, why,
                                                                   os.path.join(folder, "run.log")), flush=True)
                continue
            with open(path) as f:
                r = json.load(f)
            if a.prepare:
                print("%s: scene written, %d material points, dt %.4g s" % (head, r["particles"], r["dt"]), flush=True)
                continue
            print("%s: travel %.4f m, peak F_t %.3f N at %.3f s, max rotation %.1f deg, dt %.3g s, %d steps, %.0f s "
                  "loop wall" % (head, r["travel"], r["peak_force"], r["peak_time"], r["max_rotation_deg"],
                                 r["dt_min"], r["steps"], r["wall_s"]), flush=True)
    return failed


def collect(out, sizes=None, ratios=None):
    results = []
    for path in sorted(glob.glob(os.path.join(out, "h*_r*", "result.json"))):
        with open(path) as f:
            r = json.load(f)
        if sizes is not None and not any(abs(r["h_mm"] - s) < 1e-9 for s in sizes):
            continue
        if ratios is not None and not any(abs(r["ratio"] - v) < 1e-12 for v in ratios):
            continue
        seriesPath = os.path.join(os.path.dirname(path), "series.json")
        if "rotation45_time" not in r and os.path.exists(seriesPath):  # results of an older version
            with open(seriesPath) as f:
                r["rotation45_time"] = firstTurn(json.load(f))
        results.append(r)
    results.sort(key=lambda r: (r["h_mm"], r["ratio"]))
    for r in results:
        ref = [q for q in results if q["h_mm"] == r["h_mm"] and abs(q["ratio"] - REFERENCE_RATIO) < 1e-12]
        r["wall_ratio"] = r["wall_s"] / ref[0]["wall_s"] if ref else None
        r["cpu_ratio"] = r["cpu_s"] / ref[0]["cpu_s"] if ref and r.get("cpu_s") and ref[0].get("cpu_s") else None
        r["steps_ratio"] = r["steps"] / ref[0]["steps"] if ref else None
    return results


def fmt(v, f, missing="–"):
    return missing if v is None else f % v


def table(results):
    head = ("| h_b [mm] | R/h_b | R [mm] | travel at end [m] | peak F_t, 10 ms mean [N] at [s] | mean F_t %s s [N] | "
            "max rotation [deg] (45° at [s]) | highest rise [mm] | first touch [s] | dt [s] | "
            "min contact step [s] at [s] | steps | loop wall [s] | loop CPU [s] | "
            "cost / (R = h_b/20): wall, CPU, steps |")
    win = results[0]["window"] if results else [0, 0]
    lines = [head % ("%g–%g" % tuple(win)), "|" + "---:|" * 15]
    ratio = lambda r, k: fmt(r.get(k), "%.3f")  # noqa: E731
    for r in results:
        dt = "%.4g" % r["dt_min"] if not r["contact_limited_steps"] else "%.4g (contact, %d steps)" % (
            r["dt_min"], r["contact_limited_steps"])
        cs = ("%.3g at %.3f" % (r["contact_step_min"], r["contact_step_min_time"])
              if r["contact_step_min"] is not None else "≥ dt (driver check)")
        cells = (r["h_mm"], r["ratio_label"], 1000 * r["sweep_radius"], r["travel"], r["peak_force"], r["peak_time"],
                 fmt(r["mean_force_window"], "%.3f"), "%.1f (%s)" % (r["max_rotation_deg"], fmt(
                     r.get("rotation45_time"), "%.3f", "never")), 1000 * r["max_rise"],
                 fmt(r["first_touch"], "%.3f"), dt, cs, r["steps"], r["wall_s"], fmt(r.get("cpu_s"), "%.0f"),
                 ratio(r, "wall_ratio"), ratio(r, "cpu_ratio"), ratio(r, "steps_ratio"))
        lines.append("| %g | %s | %.3g | %.4f | %.3f at %.3f | %s | %s | %.1f | %s | %s | %s | %d | %.0f | %s | "
                     "%s, %s, %s |" % cells)
    return "\n".join(lines)


def section(results, meta):
    begin, end = resultMarkers(results)
    loads = [x for r in results for x in (r["load_before"], r["load_after"]) if x]
    load = ("1-minute load average %.2f–%.2f at the starts and ends of the runs" % (
        min(x[0] for x in loads), max(x[0] for x in loads)) if loads else "load average not recorded")
    r0 = results[0]
    where = "engine: %s" % r0["engine"]
    if r0["engine"] == "driver":
        where += " (MPM %s-%s)" % (r0.get("backend", "cpu"), r0.get("precision", "double"))
    lines = [begin, "",
             "Command: `%s`" % meta["command"], "",
             "Commit %s; machine: %s; %d thread(s) per run, %d run(s) at a time; %s; dx %g m; flow and friction "
             "set %s, the flow's blend %s; %g s simulated per run; %s%s." % (
                 meta["commit"], meta["machine"], r0["threads"], meta["jobs"], where, r0.get("dx", DX),
                 r0.get("settings", "table1"), r0.get("flip_blend", "not recorded"), r0["duration"], load,
                 "; whole sweep %.1f min" % (meta["wall_total"] / 60) if meta.get("wall_total") else ""),
             "", table(results), ""]
    for hmm, ratio, why in meta.get("failed", []):
        lines.append("- h_b %g mm, R/h_b %s: **failed**: %s" % (hmm, ratioLabel(ratio), why))
    if meta.get("failed"):
        lines.append("")
    lines.append(end)
    return "\n".join(lines)


def writeMarkdown(path, text, begin, end):
    old = open(path).read() if os.path.exists(path) else ""
    if begin in old and end in old:
        i, j = old.index(begin), old.index(end) + len(end)
        new = old[:i] + text + old[j:]
    else:
        new = old + ("\n" if old and not old.endswith("\n") else "") + ("\n" if old else "") + text + "\n"
    with open(path, "w") as f:
        f.write(new)


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(12, 3.6))
    ratios = sorted({r["ratio"] for r in results})
    for c, hmm in enumerate(sorted({r["h_mm"] for r in results})):
        rs = [r for r in results if r["h_mm"] == hmm]
        x = [r["ratio"] for r in rs]
        lab, col = "h_b = %g mm" % hmm, "C%d" % c
        ax[0].plot(x, [r["travel"] for r in rs], "o-", color=col, label=lab)
        ax[1].plot(x, [r["peak_force"] for r in rs], "o-", color=col, label=lab)
        if all(r["wall_ratio"] is not None for r in rs):
            ax[2].plot(x, [r["wall_ratio"] for r in rs], "o-", color=col, label=lab + ", wall")
            ax[2].plot(x, [r["steps_ratio"] for r in rs], "x--", color=col, label=lab + ", steps")
        if all(r.get("cpu_ratio") is not None for r in rs):
            ax[2].plot(x, [r["cpu_ratio"] for r in rs], "s:", ms=3, color=col, label=lab + ", CPU")
    ax[0].axvspan(1 / 50, 1 / 10, color="0.92", zorder=0, label="paper's window 1/50–1/10")
    titles = ("travel distance at the end [m]", "peak F_t, 10 ms mean [N]", "cost relative to R = h_b/20")
    for a_, ttl in zip(ax, titles):
        a_.set_xscale("log")
        a_.set_xticks(ratios)
        a_.set_xticklabels([ratioLabel(v) for v in ratios], fontsize=7)
        a_.minorticks_off()
        a_.set_xlabel("R / h_b (log)")
        a_.set_title(ttl, fontsize=10)
        a_.axvline(REFERENCE_RATIO, color="0.7", lw=0.8, zorder=0)
        a_.legend(fontsize=7)
    ax[2].axhline(1.0, color="0.5", lw=0.6)
    r0 = results[0]
    st = r0.get("settings", "table1")
    fig.suptitle("Block sweep radius, %s §3.2 flume (dx %g m, %g s%s)" % (
        "coarse" if r0.get("dx", DX) == DX else "paper-resolution", r0.get("dx", DX), r0["duration"],
        "" if st == "table1" else ", %s set" % st), fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=72)


def prepareAll(a, argv, metaPath):
    """--prepare: every run's scene (a child process each, YADE builds it) and run_driver.sh."""
    os.makedirs(a.out, exist_ok=True)
    runs = [(h, r) for h in a.sizeList for r in a.ratioList]
    failed = runAll(a, runs)
    meta = {"command": "python3 %s, then %s/run_driver.sh" % (" ".join(
                [os.path.relpath(os.path.abspath(__file__), ROOT)] + list(argv)), os.path.basename(a.out)),
            "commit": commit(), "jobs": a.jobs}
    with open(metaPath, "w") as f:
        json.dump(meta, f, indent=1)
    script = os.path.join(a.out, "run_driver.sh")
    with open(script, "w") as f:
        f.write(RUN_DRIVER_SH % {"backend": a.backend, "precision": a.precision})
    os.chmod(script, 0o755)
    print("%d scenes in %s; run them with MPMSDEM_RUN=... JOBS=... %s, then --collect" % (
        len(runs) - len(failed), a.out, script))
    return 1 if failed else 0


def collectDriverRuns(a, metaPath):
    """--collect: result.json of every run that run_driver.sh finished; the sweep's facts."""
    meta = {"command": "(not recorded)", "commit": "?", "jobs": 1}
    if os.path.exists(metaPath):
        with open(metaPath) as f:
            meta.update(json.load(f))
    ran = os.path.join(a.out, "run_driver.json")
    if not os.path.exists(ran):
        raise SystemExit("--collect: no %s: run run_driver.sh in that folder first" % ran)
    with open(ran) as f:
        facts = json.load(f)
    meta.update(machine=facts["machine"], jobs=facts["jobs"], wall_total=facts["wall_total"])
    a.threads = int(facts["threads"]) if facts["threads"].isdigit() else os.cpu_count() or 1
    meta["failed"] = []
    for hmm in a.sizeList:
        for ratio in a.ratioList:
            folder = os.path.join(a.out, runName(hmm, ratio))
            try:
                with open(os.path.join(folder, "prepared.json")) as f:
                    prepared = json.load(f)
                for name, value in (("dx", a.dx), ("duration", a.duration)):
                    if prepared[name] != value:  # the results would be labelled with the wrong run's settings
                        raise SystemExit("--collect: --%s = %g, but %s was prepared with %g: give the value of "
                                         "--prepare" % (name, value, folder, prepared[name]))
                if prepared.get("settings", "table1") != a.settings:
                    raise SystemExit("--collect: --settings %s, but %s was prepared with %s: give the value of "
                                     "--prepare" % (a.settings, folder, prepared.get("settings", "table1")))
                series, run = readDriver(folder, prepared)
            except (OSError, RuntimeError, KeyError) as e:
                meta["failed"].append((hmm, ratio, str(e)))
                continue
            writeResult(a, hmm, ratio, folder, series, run, None, None)
    with open(metaPath, "w") as f:
        json.dump(meta, f, indent=1)
    return meta


def main(argv):
    a = parse(argv)
    if a.one:
        return child(a)
    a.out = os.path.abspath(a.out)
    metaPath = os.path.join(a.out, "sweep.json")
    if a.prepare:
        return prepareAll(a, argv, metaPath)
    if a.collect:
        meta = collectDriverRuns(a, metaPath)
    elif a.report_only:
        # the facts of the sweep that made the results, not of this read-out
        meta = {"command": "(not recorded)", "commit": "?", "machine": "?", "jobs": a.jobs, "failed": []}
        if os.path.exists(metaPath):
            with open(metaPath) as f:
                meta.update(json.load(f))
    else:
        meta = {"command": "OMP_NUM_THREADS=%d python3 %s" % (a.threads, " ".join(
                    [os.path.relpath(os.path.abspath(__file__), ROOT)] + list(argv))),
                "commit": commit(), "machine": machine(), "jobs": a.jobs}
        os.makedirs(a.out, exist_ok=True)
        runs = [(h, r) for h in a.sizeList for r in a.ratioList]
        print("%d runs (h_b %s mm x R/h_b %s), %g s each, engine %s, %d at a time, OMP_NUM_THREADS=%d; outputs in %s"
              % (len(runs), ", ".join("%g" % h for h in a.sizeList), ", ".join(ratioLabel(r) for r in a.ratioList),
                 a.duration, a.engine, a.jobs, a.threads, a.out), flush=True)
        t0 = time.time()
        meta["failed"] = runAll(a, runs)
        meta["wall_total"] = time.time() - t0
        with open(metaPath, "w") as f:
            json.dump(meta, f, indent=1)
    results = collect(a.out, a.sizeList, a.ratioList)
    if not results:
        print("no finished runs in %s" % a.out, file=sys.stderr)
        return 1
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    print(table(results))
    if meta.get("wall_total"):
        print("whole sweep: %.1f min wall" % (meta["wall_total"] / 60))
    if a.markdown:
        writeMarkdown(a.markdown, section(results, meta), *resultMarkers(results))
        print("generated section written to %s" % a.markdown)
    if a.plot:
        plot(results, a.plot)
        print("plot written to %s" % a.plot)
    return 1 if meta["failed"] else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
