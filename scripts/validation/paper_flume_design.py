#!/usr/bin/env python3
"""Validation study (opt-in, minutes per case): the §3.2 copper-cube flume at the paper's
resolution (dx 0.01 m, 8 points per cell, 96,000 material points) under one-at-a-time changes
of the flow's numerics and friction, against the paper's §3.2 numbers. It maps which knob
moves which target before a joint calibration (examples/calibrate_flume.py) spends hundreds of
runs on them.

Every case is ``examples/calibrate_flume.py:flumeRun`` with dx 0.01 m: the coupled YADE scene
of examples/flume_block.py, run as its own process by mpmsdem.sweep; finished cases are kept
in ``--out``/runs.jsonl, so the same command after an interruption (or in a later session)
runs only the cases not yet done. Cases (``--cases`` picks a comma-separated subset):

    paper        the paper's blend, 2010 /s (α 0.99 per its 5e-6 s step), Table 1 frictions
    default      the scene default, 201 /s
    damping4000  twice the paper's damping per second
    basal030     basal friction 0.30 (Table 1: 0.21), paper blend
    mu2_080      μ₂ 0.80 (Table 1: 0.65; Appendix C range up to 0.8), paper blend
    walls021     side-wall friction 0.21 (smooth in the paper's scene), paper blend
    flow040      flow–cube friction 0.40 (0.21), paper blend
    flow067      flow–cube friction 0.67 (the cube–bed value), paper blend
    basal015     basal friction 0.15, paper blend
    flow000      a smooth cube (flow–cube friction 0), paper blend
    flow067_basal015   flow–cube friction 0.67 and basal friction 0.15, paper blend
    half_flow067       half the paper's damping (1005 /s) with flow–cube friction 0.67

``--lhs N`` adds N joint cases ``lhs01`` … spread over the calibration's space by a Latin
hypercube (seed ``--seed``): PIC damping 1000–4000 /s (log-uniform), basal friction 0.15–0.30,
μ₂ 0.65–0.80, flow–cube friction 0–0.67, side-wall friction 0–0.21 (``LHS_RANGES``).

Targets (paper §3.2, Figs 8–9): first touch ~0.25 s (experiment 0.3 s), F_t 0.32 N at 0.4 s,
~0.20 N plateau, 45° at 0.72 s and turning on past it, at rest in the end. Prints the table
with each case's setting, Δx, step and damping per second, the relative misfit of the first
four targets and of the rotation at 0.7 s (45°), their sum of squares (the calibration's loss;
the lowest is named), and writes it to ``--out``/design.md.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/paper_flume_design.py [--cases paper,basal030]
        [--lhs 20] [--duration 0.8] [--out results/paper_flume_design] [--report]

``--report`` prints the table of the cases the store already holds and runs nothing (what a
design stopped part-way has so far).

Through the plain C++ driver (a GPU machine has no YADE): the same cases written as driver
scenes here, run there, read back here (the same numbers as the YADE runs, to round-off):

    /usr/bin/python3 scripts/validation/paper_flume_design.py --prepare DIR [--cases ...] [--lhs 20]
    python3 scripts/validation/paper_flume_design.py --run-prepared DIR --exe PATH/mpmsdem-run --backend cuda [--workers N]
    /usr/bin/python3 scripts/validation/paper_flume_design.py --collect DIR       (table in DIR/design.md)
"""
import argparse
import json
import math
import os
import random
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PAPER_RATE = -math.log(0.99) / 5e-6  # 2010.07 /s
CASES = {
    "paper": {"flipDampingRate": PAPER_RATE},
    "default": {},
    "damping4000": {"flipDampingRate": 2 * PAPER_RATE},
    "basal030": {"flipDampingRate": PAPER_RATE, "basalFriction": 0.30},
    "mu2_080": {"flipDampingRate": PAPER_RATE, "mu_2": 0.80},
    "walls021": {"flipDampingRate": PAPER_RATE, "sideWallFriction": 0.21},
    "flow040": {"flipDampingRate": PAPER_RATE, "flowFriction": 0.40},
    "flow067": {"flipDampingRate": PAPER_RATE, "flowFriction": 0.67},
    "basal015": {"flipDampingRate": PAPER_RATE, "basalFriction": 0.15},
    "flow000": {"flipDampingRate": PAPER_RATE, "flowFriction": 0.0},
    "flow067_basal015": {"flipDampingRate": PAPER_RATE, "flowFriction": 0.67, "basalFriction": 0.15},
    "half_flow067": {"flipDampingRate": PAPER_RATE / 2, "flowFriction": 0.67},
}
# the joint design's space: (name, low, high, log-uniform)
LHS_RANGES = [("flipDampingRate", 1000.0, 4000.0, True), ("basalFriction", 0.15, 0.30, False),
              ("mu_2", 0.65, 0.80, False), ("flowFriction", 0.0, 0.67, False), ("sideWallFriction", 0.0, 0.21, False)]


def latinHypercube(n, seed):
    """n cases over LHS_RANGES: each range cut into n equal strata (in log for the damping), one
    case per stratum of every parameter, strata paired at random (seeded)."""
    rng = random.Random(seed)
    columns = []
    for name, lo, hi, log in LHS_RANGES:
        strata = list(range(n))
        rng.shuffle(strata)
        a, b = (math.log(lo), math.log(hi)) if log else (lo, hi)
        u = [a + (b - a) * (k + rng.random()) / n for k in strata]
        columns.append([round(math.exp(v) if log else v, 4) for v in u])
    return {"lhs%02d" % (i + 1): {name: col[i] for (name, _, _, _), col in zip(LHS_RANGES, columns)}
            for i in range(n)}


# (result key, label, paper's value or None, format)
COLUMNS = [("first_touch", "first touch [s]", 0.25, "%.3f"), ("force_04", "F_t at 0.4 s [N]", 0.32, "%.2f"),
           ("force_mean", "F_t 0.4–0.7 s [N]", 0.20, "%.2f"), ("rotation_04", "rot 0.4 s [°]", None, "%.0f"),
           ("rotation_05", "rot 0.5 s [°]", None, "%.0f"), ("rotation_07", "rot 0.7 s [°]", None, "%.0f"),
           ("t45", "45° at [s]", 0.72, "%.3f"), ("max_rotation_deg", "max rot [°]", 45, "%.0f"),
           ("travel", "travel [m]", None, "%.3f"), ("speed_end", "speed at end [m/s]", 0.0, "%.3f")]


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated subset of: " + ", ".join(CASES))
    ap.add_argument("--duration", type=float, default=0.8, help="simulated time per case [s], in [0.7, 3] (0.8)")
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] (0.01, the paper's)")
    ap.add_argument("--workers", type=int, default=1, help="cases at a time, also of --run-prepared (1)")
    ap.add_argument("--out", default=os.path.join("results", "paper_flume_design"), help="results folder")
    ap.add_argument("--lhs", type=int, default=0, help="add N joint cases by a Latin hypercube (0)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the Latin hypercube (1)")
    ap.add_argument("--report", action="store_true",
                    help="the table of the cases already in --out's store; runs nothing")
    ap.add_argument("--prepare", metavar="DIR", help="write the cases as driver scenes into DIR/CASE")
    ap.add_argument("--run-prepared", metavar="DIR", help="run the prepared cases in DIR with mpmsdem-run")
    ap.add_argument("--collect", metavar="DIR", help="the table of the cases run in DIR (DIR/design.md)")
    ap.add_argument("--exe", default="mpmsdem-run", help="--run-prepared: the driver (mpmsdem-run on the PATH)")
    ap.add_argument("--backend", choices=("cpu", "cuda"), help="--run-prepared: the backend (the scenes': cpu)")
    ap.add_argument("--threads", type=int, help="--run-prepared: OMP_NUM_THREADS of the driver (as set)")
    a = ap.parse_args(argv)
    if a.lhs < 0:
        ap.error("--lhs %d: must be >= 0" % a.lhs)
    a.cases_ = dict(CASES, **latinHypercube(a.lhs, a.seed)) if a.lhs else dict(CASES)
    a.caseList = [c.strip() for c in a.cases.split(",") if c.strip()] + sorted(set(a.cases_) - set(CASES))
    unknown = [c for c in a.caseList if c not in a.cases_]
    if unknown or not a.caseList:
        ap.error("--cases %r: give names among %s" % (a.cases, ", ".join(CASES)))
    if not 0.7 <= a.duration <= 3:
        ap.error("--duration %g s: must be in [0.7, 3] (the targets run to 0.7 s)" % a.duration)
    if not 0.005 <= a.dx <= 0.02:
        ap.error("--dx %g m: must be in [0.005, 0.02]" % a.dx)
    return a


# The targets a case is scored on (the calibration's loss, mpmsdem.calibrate): the paper's
# values that a 0.8 s run can show. "At rest in the end" needs a longer run and is read from the
# speed at the end instead; a 45° time equal to the duration means "not reached" (a lower bound).
# The rotation at 0.7 s (45°: the paper's cube reaches 45° at 0.72 s) keeps a cube that tumbles
# away early, and so feels less force, from scoring as if it matched the paper's slow turn.
LOSS_TARGETS = [("first_touch", 0.25), ("force_04", 0.32), ("force_mean", 0.20), ("t45", 0.72),
                ("rotation_07", 45.0)]
# A cube turned further than this has tumbled (the rotation angle of its orientation wraps past
# 180°, so a cube that turned over can show a small rotation at 0.7 s): not the paper's story,
# whatever its loss. The paper's cube turns on past 45° towards its next face (Fig 9, inset d3).
MAX_TURN = 100.0


def misfits(result):
    """Relative misfit (ours − paper) / paper of each of LOSS_TARGETS, and their sum of squares."""
    m = {k: (result[k] - ref) / ref for k, ref in LOSS_TARGETS if k in result}
    return m, sum(v * v for v in m.values()) if len(m) == len(LOSS_TARGETS) else math.nan


def setting(params):
    """A case's parameters other than the resolution and the duration, as text."""
    return ", ".join("%s %g" % (k, v) for k, v in sorted(params.items()) if k not in ("dx", "duration")) or "Table 1"


def table(names, records, a, params):
    head = ("| case | setting | damping [1/s] | " + " | ".join(c[1] for c in COLUMNS)
            + " | misfit touch / F_t 0.4 / plateau / 45° / rot 0.7 | loss |")
    rows = [head, "|" + "---|" * (len(COLUMNS) + 5),
            "| paper | Table 1 | 2010 (α 0.99 per 5e-6 s) | "
            + " | ".join("—" if c[2] is None else "%g" % c[2] for c in COLUMNS) + " | 0 | 0 |"]
    losses = {}
    for name, r in zip(names, records):
        if r["status"] != "ok":
            rows.append("| %s | %s | **failed**: %s |" % (name, setting(params[name]),
                                                          r.get("error", "?").splitlines()[-1][:120]))
            continue
        v = r["result"]
        m, losses[name] = misfits(v)
        # a 45° time at the run's end is "not reached by then": shown as a bound
        unturned = "t45" in v and v["t45"] >= a.duration * (1 - 1e-9)
        cells = [("> %.2f" % a.duration if k == "t45" and unturned else fmt % v[k]) if k in v else "—"
                 for k, _, _, fmt in COLUMNS]
        rows.append("| %s | %s | %s | %s | %s | %.2f |" % (
            name, setting(params[name]), v.get("flip_blend", "?"), " | ".join(cells),
            " / ".join(("≥ " if k == "t45" and unturned else "") + "%+.0f %%" % (100 * m[k]) if k in m else "—"
                       for k, _ in LOSS_TARGETS), losses[name]))
    byName = dict(zip(names, records))
    scored = [n for n in losses if losses[n] == losses[n] and byName[n]["result"].get("max_rotation_deg", 0) <= MAX_TURN]
    rows.append("")
    if scored:
        best = min(scored, key=losses.get)
        rows.append("Lowest loss (the sum of the squared relative misfits of first touch, F_t at 0.4 s, the "
                    "0.4–0.7 s plateau, the 45° time and the rotation at 0.7 s) among the cases whose cube turned "
                    "no more than %g° (the paper's turns on past 45° towards its next face, it does not tumble): "
                    "%s (%s), %.2f." % (MAX_TURN, best, setting(params[best]), losses[best]))
    else:
        rows.append("No case kept its cube from turning more than %g° (the paper's does not tumble)." % MAX_TURN)
    return "\n".join(rows)


def caseParams(a, name):
    return dict(a.cases_[name], dx=a.dx, duration=a.duration)


def prepare(a):
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    from calibrate_flume import prepareFlume
    for name in a.caseList:
        prepareFlume(os.path.join(a.prepare, name), **caseParams(a, name))
        print("prepared %s" % os.path.join(a.prepare, name))


def runPrepared(a):
    """The prepared cases without YADE or numpy, ``--workers`` at a time (a case with its
    done.json is skipped)."""
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    from driver_runs import STOPPED_EXIT, DriverStopped, eachCase, runDriver, stopDriversOnSignals
    cases = [os.path.join(a.run_prepared, name) for name in sorted(os.listdir(a.run_prepared))]
    cases = [c for c in cases if os.path.isfile(os.path.join(c, "case.json"))
             and not os.path.exists(os.path.join(c, "done.json"))]

    def runOne(case):
        with open(os.path.join(case, "case.json")) as f:
            steps = json.load(f)["steps"]
        seconds = runDriver(a.exe, os.path.join(case, "scene.json"), os.path.join(case, "out"),
                            os.path.join(case, "out.log"), ["--steps", str(steps)], a.backend, None, a.threads)
        with open(os.path.join(case, "done.json"), "w") as f:
            json.dump({"seconds": seconds, "backend": a.backend or "scene's", "exe": a.exe}, f)
        print("%s: %d steps in %.0f s" % (os.path.basename(case), steps, seconds))

    try:
        with stopDriversOnSignals():
            eachCase(runOne, cases, a.workers)
    except DriverStopped as e:
        print("--run-prepared %s: stopped by a signal (%s); the same command runs the cases without done.json "
              "again" % (a.run_prepared, e))
        return STOPPED_EXIT


def collect(a):
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    from calibrate_flume import flumeResultOfDriver
    names = sorted(n for n in os.listdir(a.collect) if os.path.exists(os.path.join(a.collect, n, "done.json")))
    if not names:
        raise SystemExit("--collect %s: no case there has been run (done.json); --run-prepared first" % a.collect)
    records = [{"status": "ok", "result": flumeResultOfDriver(os.path.join(a.collect, n))} for n in names]
    params = {n: json.load(open(os.path.join(a.collect, n, "case.json")))["params"] for n in names}
    text = ("§3.2 flume through mpmsdem-run, %s.\n\n" % a.collect + table(names, records, a, params) + "\n")
    with open(os.path.join(a.collect, "design.md"), "w") as f:
        f.write(text)
    print(text)


def report(a):
    """The table of the cases whose results the store holds (the others are left out)."""
    from mpmsdem import sweep
    path = os.path.join(a.out, "runs.jsonl")
    # (readStore skips the half-written last line of a design still running)
    ok = {r["key"]: r for r in sweep.readStore(path) if r["status"] == "ok"}
    names = [name for name in a.caseList if sweep.runKey(caseParams(a, name)) in ok]
    records = [ok[sweep.runKey(caseParams(a, name))] for name in names]
    print("%d of the %d cases are in %s\n" % (len(names), len(a.caseList), path))
    print(table(names, records, a, {n: caseParams(a, n) for n in names}))


def main(argv):
    a = parse(argv)
    if a.report:
        return report(a)
    if a.run_prepared:
        return runPrepared(a)
    if a.prepare:
        return prepare(a)
    if a.collect:
        return collect(a)
    import mpmsdem  # noqa: F401  (finds YADE for the sweep's children)
    from mpmsdem import sweep
    os.makedirs(a.out, exist_ok=True)
    cases = [caseParams(a, c) for c in a.caseList]
    task = "%s:flumeRun" % os.path.join(ROOT, "examples", "calibrate_flume.py")
    records = sweep.runAll(task, cases, os.path.join(a.out, "runs.jsonl"), workers=a.workers,
                           describe=lambda rec: "first touch %.3f s, F_t(0.4 s) %.2f N, 45° at %.3f s" % (
                               rec["result"]["first_touch"], rec["result"].get("force_04", math.nan),
                               rec["result"]["t45"]) if rec["status"] == "ok" else "")
    text = ("§3.2 flume, dx %g m, 8 points per cell, the flume's step 0.5 × the CFL step at rest (5.17e-5 s at dx "
            "0.01 m), %g s per case; commit and machine: see the command's caller.\n\n" % (a.dx, a.duration)
            + table(a.caseList, records, a, {c: caseParams(a, c) for c in a.caseList}) + "\n")
    with open(os.path.join(a.out, "design.md"), "w") as f:
        f.write(text)
    print(text)
    return 1 if sweep.failed(records) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
