#!/usr/bin/env python3
"""Model only what the scene needs: each saving against the run it should cost the same as.

    OMP_NUM_THREADS=1 PYTHONPATH=build/python:<YADE's py folder> /usr/bin/python3 \\
        scripts/bench/bench_scene_needs.py [--build build] [--repeat 5] [--markdown FILE]

Each saving and its reference run in the same command, in YADE (mpmsdem's engines in
O.engines) and in the C++ driver mpmsdem-run (coupled scenes with blocks from JSON):

a. a coupled scene with blocks and no material points against the SDEM engine alone. YADE
   only: the scene format needs particles, so the flow loads a snapshot without any; the
   driver's scene files cannot describe such a scene.
b. a coupled scene with material points and no blocks against the MPM engine alone. YADE:
   CoupledEngine with an SdemEngine without bodies; driver: "blocks": [] against no key.
c. a free cube resting on a fixed slab, plus 20 blocks standing on the slab in a touching
   row, fixed or with all six DOFs blocked, against the cube on the slab alone (YADE also
   counts the narrow-phase pairs per step). The driver's runs carry one material point in a
   small grid away from the blocks; its own split gives the blocks stage.
d. a coupled scene with every output on (YADE: sdem.h5, mpm.h5, coupled.h5, ParaView files,
   yade.plot; driver: mpm.h5, coupled.h5, scene.pvd) every step, every 100 steps (driver also
   every 1000), and off.
   YADE: each step is timed on its own and the median is the cost of a step without output
   (mpm.h5's series row every 10 MPM steps is an output step of its own, in the mean).
   Driver: with t_k the cost per step for outputs every k steps, t_k = c + o / k, so the
   cost of a step without output is c = (10 t_1000 - t_100) / 9 (the every-step runs, all
   file writing, vary too much to be part of it).

Costs are CPU time of the thread that runs the steps (YADE: stamped from a PyRunner inside
YADE's loop, after a few untimed steps; driver: the difference of a 2n-step and an n-step
run over n, from the child's rusage, one thread), so that a machine shared with other runs
adds less noise than wall time would; every case is run --repeat times, interleaved with
its reference, and the minimum is kept.
"""
import argparse
import json
import math
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import mpmsdem
from mpmsdem import analysis
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
G = (0.0, 0.0, -9.81)
H, R, RHO, KC = 0.02, 0.003, 2000.0, 1e4   # cubes of outer half-size H, sweep radius R
ROW = 20                                     # blocks in the row of item c
WARMUP = 5                                   # untimed steps before each timed window

# ------------------------------------------------------------------ timing inside YADE's loop
_STAMPS = []
_ENGINES = []  # the engines of the scene being timed, for mpmsdem.run's checks


def _stamp():
    # CPU time of the thread running YADE's loop (the stamping PyRunner runs in it), not wall
    # time: on a machine shared with other runs, the scheduler's pauses would read as cost
    _STAMPS.append(time.thread_time())


def stampedRun(steps, every):
    """Run `steps` steps after WARMUP untimed ones, stamped every `every` steps (1: each step
    timed on its own); returns the stamps [s]."""
    import builtins
    builtins._benchSceneNeedsStamp = _stamp
    mpmsdem.run(WARMUP, *_ENGINES)
    del _STAMPS[:]
    O.engines = O.engines + [PyRunner(command="import builtins; builtins._benchSceneNeedsStamp()",
                                      iterPeriod=every, initRun=True)]
    O.run(steps + 1, True)
    O.engines = O.engines[:-1]
    for e in _ENGINES:
        e.check()
    if len(_STAMPS) != steps // every + 1:
        raise RuntimeError("timing stamps: %d, expected %d" % (len(_STAMPS), steps // every + 1))
    return list(_STAMPS)


def usPerStep(steps):
    s = stampedRun(steps, steps)
    return {"total": (s[-1] - s[0]) / steps * 1e6}


def usPerStepSplit(steps, key, stages):
    """usPerStep of the coupled engine in _ENGINES[0], plus r[key]: the µs per step of its
    ``stages`` (keys of its timings(), wall time: the engine's own split)."""
    c = _ENGINES[0]
    c.resetTimings()
    r = usPerStep(steps)
    t = c.timings()
    r[key] = 1e6 * sum(t[k] for k in stages) / t["steps"]
    return r


def interleaved(cases, repeat):
    """cases: {name: (build, measure)}, build() setting up a fresh scene and returning its
    engines, measure() a dict of numbers. Every repeat runs each case once, in turn, so that
    the machine's load drifts over all of them alike; returns {name: each number's minimum}."""
    out = {}
    for _ in range(repeat):
        for name, (build, measure) in cases.items():
            O.reset()
            _ENGINES[:] = build()
            r = measure()
            out[name] = {k: min(v, out[name][k]) for k, v in r.items()} if name in out else r
    return out


def newton():
    return NewtonIntegrator(gravity=G, damping=0)


# ------------------------------------------------------------------ scenes
def restingZ():
    """Centre height of a cube resting on a slab whose top face is z = 0 (its four face
    contacts carry its weight)."""
    mass = RHO * mpmsdem.SpheroPolyhedron.box((H,) * 3, R).volume
    return H - analysis.equilibriumOverlap(mass * 9.81, 2 * R, KC, contacts=4)


def slabScene(row=None, cubes=1):
    """A fixed slab (top face z = 0) with `cubes` free cubes resting on it and, with `row`
    ("fixed" or "blocked"), ROW blocks standing on it in a row, each 0.1 mm into the slab and
    into its neighbour. Returns (engine, material)."""
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.4, barrierStiffness=KC, normalDamping=0.2)
    sdem.box((0.5, 0.3, 0.02), R, mat, pos=(0, 0, -0.02), fixed=True)
    for k in range(ROW if row else 0):
        i = sdem.box((H,) * 3, R, mat, pos=(-0.45 + k * (2 * H - 1e-4), -0.2, H - 1e-4), fixed=row == "fixed")
        if row == "blocked":
            O.bodies[i].state.blockedDOFs = "xyzXYZ"
    for k in range(cubes):
        sdem.box((H,) * 3, R, mat, pos=(-0.2 + 0.1 * k, 0.1, restingZ()))
    return sdem, mat


def emptyFlow():
    """An MpmEngine over the slab (dx 0.01 m, 100 x 60 x 20 cells) without particles."""
    return mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [100, 60, 20], "origin": [-0.5, -0.3, -0.05]},
                             material=GLASS, particles=[], gravity=G, verbose=False)


COLUMN = {"grid": {"dx": 0.01, "cells": [28, 18, 24], "origin": [-0.02, -0.02, -0.02]},
          "particles": [{"lo": [0, 0, 0], "hi": [0.08, 0.06, 0.1], "ppc": 8}]}


def columnFlow(**kw):
    """A granular column of 3,840 material points collapsing in a box."""
    return mpmsdem.MpmEngine(grid=COLUMN["grid"], material=GLASS, particles=COLUMN["particles"], gravity=G,
                             verbose=False, **kw)


# 512 points sliding at 1 m/s along x on a slab whose top face is z = 0.02 m (lowest points
# 0.4 mm above it), towards a cube resting on the slab
BLOB = {"grid": {"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, -0.009]},
        "particles": [{"lo": [0.04, 0.05, 0.021], "hi": [0.08, 0.09, 0.061], "ppc": 8, "velocity": [1, 0, 0]}]}


def blobScene(out=None, every=None):
    """The coupled BLOB scene; with `out`, every engine writes its outputs every `every` s."""
    sdem = mpmsdem.SdemEngine(verbose=False, output=out and os.path.join(out, "sdem"), outputEvery=every,
                              vtkEvery=every if out else None)
    mat = mpmsdem.material(density=RHO, friction=0.4, barrierStiffness=KC, normalDamping=0.2)
    sdem.box((0.14, 0.08, 0.01), R, mat, pos=(0.12, 0.07, 0.01), fixed=True)  # top face z = 0.02
    sdem.box((H,) * 3, R, mat, pos=(0.16, 0.07, 0.02 + restingZ()))
    mpm = mpmsdem.MpmEngine(grid=BLOB["grid"], material=GLASS, particles=BLOB["particles"], gravity=G, verbose=False,
                            output=out and os.path.join(out, "mpm"), outputEvery=every)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, verbose=False, output=out, outputEvery=every,
                                    vtkEvery=every if out else None, plot=bool(out))
    O.engines = [ForceResetter(), coupled.runner, newton()]
    O.dt = 2e-5
    return coupled


# ------------------------------------------------------------------ YADE measurements
def yadeA(repeat, steps):
    def alone():
        sdem, _ = slabScene(cubes=2)
        O.engines = [ForceResetter(), sdem.runner, newton()]
        O.dt = 1e-5
        return [sdem]

    def coupled():
        sdem, mat = slabScene(cubes=2)
        c = mpmsdem.CoupledEngine(sdem, emptyFlow(), pairs={mat: 0.3}, verbose=False)
        O.engines = [ForceResetter(), c.runner, newton()]
        O.dt = 1e-5
        return [c]

    return interleaved({"coupled": (coupled, lambda: usPerStepSplit(steps, "flow", ("coupling", "mpm"))),
                        "alone": (alone, lambda: usPerStep(steps))}, repeat)


def yadeB(repeat, steps):
    def alone():
        mpm = columnFlow()
        O.engines = [mpm.runner]
        O.dt = 0.5 * mpm.stableTimeStep()
        return [mpm]

    def coupled():
        mpm = columnFlow()
        c = mpmsdem.CoupledEngine(mpmsdem.SdemEngine(verbose=False), mpm,
                                  pairs={mpmsdem.material(density=RHO): 0.3}, verbose=False)
        O.engines = [ForceResetter(), c.runner, newton()]
        O.dt = 0.5 * mpm.stableTimeStep()
        return [c]

    return interleaved({"coupled": (coupled, lambda: usPerStepSplit(steps, "coupling", ("coupling",))),
                        "alone": (alone, lambda: usPerStep(steps))}, repeat)


def yadeC(repeat, steps):
    def build(row):
        def b():
            sdem, _ = slabScene(row=row)
            O.engines = [ForceResetter(), sdem.runner, newton()]
            O.dt = 1e-5
            return [sdem]
        return b

    def pairs():
        # builds from before the counter have none (run against an older build): n/a
        return getattr(_ENGINES[0], "narrowPhasePairs", math.nan)

    def measure():
        pairs0 = pairs()
        r = usPerStep(steps)
        r["pairs"] = (pairs() - pairs0) / (steps + 1)
        return r
    return interleaved({row: (build(row), measure) for row in (None, "fixed", "blocked")}, repeat)


def yadeD(repeat, steps, tmp):
    def build(every):
        def b():
            folder = tempfile.mkdtemp(dir=tmp)
            return [blobScene(folder if every else None, every * 2e-5 if every else None)]
        return b

    def measure(every):
        def m():
            from yade import plot
            plot.reset()
            s = stampedRun(steps if every != 1 else max(50, steps // 10), 1)
            d = [b - a for a, b in zip(s, s[1:])]
            return {"median": 1e6 * statistics.median(d), "mean": 1e6 * sum(d) / len(d)}
        return m
    return interleaved({every: (build(every), measure(every)) for every in (1, 100, None)}, repeat)


# ------------------------------------------------------------------ driver measurements
def driverRun(exe, scene, folder, steps, bench):
    """One mpmsdem-run; returns its CPU seconds and, with --bench, its JSON line."""
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
    cmd = [exe, path, "--steps", str(steps)] + (["--bench"] if bench else ["--out", os.path.join(folder, "out")])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise RuntimeError("%s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()[-800:]))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, json.loads(p.stdout.strip().splitlines()[-1]) if bench else None


def driverCases(exe, scenes, repeat, tmp):
    """scenes: {name: (scene, steps, bench)}. CPU µs per step of each one's step loop: the
    difference of the fastest 2n-step run and the fastest n-step run, over n (set-up, seeding
    and the last records cancel), each the minimum of `repeat` rounds that run every scene in
    turn; with --bench also the blocks stage of the fastest long run (wall time: the driver's
    own split)."""
    shortRun, longRun, blocks = {}, {}, {}
    for _ in range(repeat):
        for name, (scene, steps, bench) in scenes.items():
            cpu, _ = driverRun(exe, scene, tempfile.mkdtemp(dir=tmp), steps, bench)
            shortRun[name] = min(cpu, shortRun.get(name, math.inf))
            cpu, r = driverRun(exe, scene, tempfile.mkdtemp(dir=tmp), 2 * steps, bench)
            if cpu < longRun.get(name, math.inf):
                longRun[name] = cpu
                if r and "stage_seconds" in r:
                    blocks[name] = 1e6 * r["stage_seconds"]["blocks"] / (2 * steps)
    out = {}
    for name, (_, steps, _) in scenes.items():
        out[name] = {"total": 1e6 * (longRun[name] - shortRun[name]) / steps}
        if name in blocks:
            out[name]["blocks"] = blocks[name]
    return out


def flowScene(grid, particles, dt, blocks=None, materials=None, **run):
    s = {"grid": grid, "material": GLASS, "gravity": list(G), "particles": particles,
         "run": dict({"duration": 1.0, "dt": dt, "vtk": "raw"}, **run)}
    if blocks is not None:
        s["blocks"] = blocks
    if materials is not None:
        s["block_materials"] = materials
    return s


BLOCK_MATERIAL = {"steel": {"density": RHO, "friction": 0.4, "barrier_stiffness": KC, "normal_damping": 0.2,
                            "flow": {"friction": 0.3}}}


def box(pos, half=(H,) * 3, **kw):
    return dict({"material": "steel", "box": list(half), "sweep_radius": R, "position": list(pos)}, **kw)


def driverB(exe, repeat, steps, tmp):
    base = flowScene(COLUMN["grid"], COLUMN["particles"], "auto", dt_factor=0.5)
    return driverCases(exe, {"coupled": (dict(base, blocks=[]), steps, True), "alone": (base, steps, True)},
                       repeat, tmp)


def driverC(exe, repeat, steps, tmp):
    # one material point in a small grid far from the blocks: the step is the blocks' step
    grid = {"dx": 0.01, "cells": [8, 8, 8], "origin": [2.0, 2.0, 2.0]}
    particles = [{"lo": [2.03, 2.03, 2.03], "hi": [2.04, 2.04, 2.04], "ppc": 1}]
    scenes = {}
    for row in (None, "fixed", "blocked"):
        blocks = [box((0, 0, -0.02), half=(0.5, 0.3, 0.02), fixed=True)]
        for k in range(ROW if row else 0):
            extra = {"fixed": True} if row == "fixed" else {"blocked_dofs": "xyzXYZ"}
            blocks.append(box((-0.45 + k * (2 * H - 1e-4), -0.2, H - 1e-4), **extra))
        blocks.append(box((-0.2, 0.1, restingZ())))
        scenes[row] = (flowScene(grid, particles, 1e-5, blocks=blocks, materials=BLOCK_MATERIAL), steps, True)
    return driverCases(exe, scenes, repeat, tmp)


def driverD(exe, repeat, steps, tmp):
    dt = 2e-5
    blocks = [box((0.12, 0.07, 0.01), half=(0.14, 0.08, 0.01), fixed=True), box((0.16, 0.07, 0.02 + restingZ()))]
    scenes = {}
    for every in (1, 100, 1000, None):
        run = {"output_every": every * dt, "series_every": every * dt} if every else {}
        scene = flowScene(BLOB["grid"], BLOB["particles"], dt, blocks=blocks, materials=BLOCK_MATERIAL, **run)
        scenes[every] = (scene, steps if every != 1 else max(50, steps // 20), every is None)
    out = driverCases(exe, scenes, repeat, tmp)
    # t_k = c + o / k from k = 100 and 1000: the every-step runs write files every step and
    # vary too much for their share to be taken out of a step without output
    out["nonOutput"] = (10 * out[1000]["total"] - out[100]["total"]) / 9
    return out


# ------------------------------------------------------------------ report
def commit():
    try:
        here = os.path.dirname(os.path.abspath(__file__))
        return subprocess.run(["git", "-C", here, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def table(rows):
    head = "| item | path | run | µs/step | reference run | µs/step | ratio | work per step |"
    lines = [head, "|---|---|---|---:|---|---:|---:|---|"]
    for item, path, run, us, ref, usRef, note in rows:
        ratio = "%.2f" % (us / usRef) if usRef else "–"
        lines.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
            item, path, run, "%.1f" % us, ref, "%.1f" % usRef if usRef else "–", ratio, note))
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build", help="build folder holding mpmsdem-run (default: build)")
    ap.add_argument("--repeat", type=int, default=5, help="runs per case, minimum taken (default 5)")
    ap.add_argument("--markdown", metavar="FILE", help="write the table, machine and command to FILE")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat = %r: must be >= 1" % args.repeat)
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: OMP_NUM_THREADS is not 1: the timings are meant for one thread", file=sys.stderr)
    exe = os.path.join(args.build, "mpmsdem-run")
    if not os.path.exists(exe):
        exe = shutil.which("mpmsdem-run")
    rep = args.repeat
    rows = []
    tmp = tempfile.mkdtemp(prefix="bench_scene_needs_")
    try:
        a = yadeA(rep, 3000)
        rows.append(("a", "YADE", "CoupledEngine: slab + 2 resting cubes, no material points (grid 100×60×20)",
                     a["coupled"]["total"], "SdemEngine alone", a["alone"]["total"],
                     "MPM step + coupling pass %.1f µs" % a["coupled"]["flow"]))
        b = yadeB(rep, 150)
        rows.append(("b", "YADE", "CoupledEngine: 3,840-point column, an SdemEngine without bodies",
                     b["coupled"]["total"], "MpmEngine alone", b["alone"]["total"],
                     "coupling pass %.1f µs" % b["coupled"]["coupling"]))
        if exe:
            b = driverB(exe, rep, 150, tmp)
            rows.append(("b", "driver", "column, `\"blocks\": []`", b["coupled"]["total"], "column, no `blocks` key",
                         b["alone"]["total"], "one code path (no coupled world is built): the ratio is the noise"))
        c = yadeC(rep, 3000)
        for row, name in (("fixed", "fixed"), ("blocked", "blockedDOFs xyzXYZ")):
            rows.append(("c", "YADE", "cube on slab + %d blocks in a touching row, %s" % (ROW, name), c[row]["total"],
                         "cube on slab", c[None]["total"], "narrow-phase pairs %.1f (reference %.1f)" % (
                             c[row]["pairs"], c[None]["pairs"])))
        if exe:
            c = driverC(exe, rep, 3000, tmp)
            for row, name in (("fixed", "`fixed`"), ("blocked", "`blocked_dofs` xyzXYZ")):
                rows.append(("c", "driver", "cube on slab + %d blocks in a touching row, %s" % (ROW, name),
                             c[row]["total"], "cube on slab", c[None]["total"],
                             "blocks stage %.1f µs (reference %.1f)" % (c[row]["blocks"], c[None]["blocks"])))
        d = yadeD(rep, 1000, tmp)
        for every in (100, 1):
            rows.append(("d", "YADE", "blob + cube on slab, outputs every %d step%s: median step" % (
                every, "s" if every > 1 else ""), d[every]["median"], "outputs off: median step", d[None]["median"],
                "mean step %.1f µs (off %.1f)" % (d[every]["mean"], d[None]["mean"])))
        if exe:
            d = driverD(exe, rep, 2000, tmp)
            rows.append(("d", "driver", "blob + cube on slab, outputs on: step without output, "
                         "(10 t₁₀₀₀ − t₁₀₀) / 9", d["nonOutput"], "outputs off (`--bench`)", d[None]["total"],
                         "mean step t_k, outputs every k steps: k = 1 %.0f µs, 100 %.1f µs, 1000 %.1f µs" % (
                             d[1]["total"], d[100]["total"], d[1000]["total"])))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    load = ", ".join("%.1f" % x for x in os.getloadavg())
    cmd = "OMP_NUM_THREADS=%s %s %s" % (os.environ.get("OMP_NUM_THREADS", "unset"), "python3",
                                        " ".join(["scripts/bench/bench_scene_needs.py"] + (argv or sys.argv[1:])))
    report = "\n".join([
        table(rows), "",
        "Commit %s; %s, %d cores, load average %s; CPU time of the thread running the steps, minimum of %d "
        "interleaved run(s); driver: %s." % (commit(), platform.processor() or platform.machine(), os.cpu_count(),
                                             load, rep, exe or "not found"),
        "Command: `%s`" % cmd])
    print(report)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(report + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
