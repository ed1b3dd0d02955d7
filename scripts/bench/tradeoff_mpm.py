#!/usr/bin/env python3
"""MPM settings against accuracy and cost: grid spacing, points per cell, FLIP/PIC damping, precision.

The scene is examples/scenes/column_collapse.json (a glass-bead column, L_i = 0.1 m, H_i =
0.2 m, in a 0.05 m slot, 0.6 s), run through `mpmsdem-run` once per setting. Each run gives
the runout dL/L_i (driver's front position at the end), the deposit height H_f/H_i (99th
percentile of z) and its cost: steps and CPU seconds of the process (one thread). Every
output is compared with the reference setting (the finest grid, 8 points per cell, the scenes'
default PIC viscosity 0.005 m^2/s, double), and the cost is given relative to the default
setting (dx 0.01 m, 8 per cell, 0.005 m^2/s, double), all measured in this one command. The
FLIP/PIC blend is given as a PIC viscosity (the damping per second of the default, whatever the
step; docs/physics.md, "The blend as a viscosity").

    scripts/bench/tradeoff_mpm.py --build build [--quick] [--json FILE] [--markdown FILE] [--plot PNG]
                                  [--package-data] [--from-json FILE]

--package-data stores the study in py/mpmsdem/tradeoffs.json, where mpmsdem.tradeoffs.propose()
reads it; --from-json FILE re-reports a --json file without running.

--quick leaves out the finest grid (the reference is then dx 0.00625 m). The full set takes
about half an hour on one core. Uses the standard library, h5py and numpy (matplotlib for --plot).
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile

import h5py
import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(REPO, "examples", "scenes", "column_collapse.json")
L_I, H_I, SLOT = 0.1, 0.2, 0.05
DEFAULT = {"dx": 0.01, "ppc": 8, "viscosity": 0.005, "precision": "double"}
# grid spacings that divide the slot, the column's length and its height into whole cells
SPACINGS = (0.025, 0.0125, 0.01, 0.00625, 0.005)


def settings(quick):
    """The runs: each setting varies one knob from DEFAULT; the first is the reference."""
    finest = SPACINGS[-2] if quick else SPACINGS[-1]
    runs = [dict(DEFAULT, dx=finest)]
    runs += [dict(DEFAULT, dx=dx) for dx in SPACINGS if dx > finest]
    runs += [dict(DEFAULT, ppc=n) for n in (1, 27)]
    # the damping: a tenth of the default, four times it, the paper's (0.99 per 5e-6 s at dx 0.01 m)
    runs += [dict(DEFAULT, viscosity=nu) for nu in (0.0005, 0.02, 0.0503)]
    runs += [dict(DEFAULT, precision="float"), dict(DEFAULT, dx=finest, precision="float")]
    return runs


def scene_for(base, s):
    """column_collapse.json with grid spacing, points per cell, PIC viscosity and precision of s."""
    sc = json.loads(json.dumps(base))
    dx = s["dx"]
    margin = 2  # wall layers of the solver: the particles stay 2 cells inside the faces
    extent = [0.5, SLOT, 0.3]  # room for the runout (x), the slot (y), the column (z) [m]
    sc["grid"] = {"dx": dx, "origin": [-margin * dx] * 3,
                  "cells": [int(round(e / dx)) + 2 * margin for e in extent]}
    for k in ("flip_alpha", "flip_reference_dt"):
        sc.pop(k, None)
    sc["flip_viscosity"] = s["viscosity"]
    sc["particles"][0]["ppc"] = s["ppc"]
    sc["run"]["precision"] = s["precision"]
    sc["run"]["vtk"] = "none"
    sc["run"]["output_every"] = 0.6
    return sc


def run(exe, sc, tmp, name, timeout):
    path = os.path.join(tmp, name + ".json")
    out = os.path.join(tmp, name)
    with open(path, "w") as f:
        json.dump(sc, f)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([exe, path, "--out", out], capture_output=True, text=True, env=env, timeout=timeout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError("%s failed (exit %d): %s" % (name, proc.returncode, proc.stderr.strip()[-1500:]))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with h5py.File(os.path.join(out, "mpm.h5"), "r") as f:
        front = f["series/front_x"][:]
        steps = int(f["series/step"][-1]) if "series/step" in f else None
        names = sorted(f["snapshots"].keys())
        x = f["snapshots"][names[-1]]["x"][:]
    return {"runout": (front[-1] - L_I) / L_I, "height": float(np.percentile(x[:, 2], 99)) / H_I,
            "particles": int(x.shape[0]), "steps": steps, "cpu_s": cpu}


def label(s):
    return "dx %g, %d/cell, PIC viscosity %g m^2/s, %s" % (s["dx"], s["ppc"], s["viscosity"], s["precision"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build", help="build folder holding mpmsdem-run (default: build)")
    ap.add_argument("--exe", help="path of mpmsdem-run (overrides --build)")
    ap.add_argument("--quick", action="store_true", help="leave out the finest grid (dx 0.005 m)")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds allowed per run (default 3600)")
    ap.add_argument("--json", help="write the rows as JSON to this file")
    ap.add_argument("--markdown", help="append the table to this file")
    ap.add_argument("--plot", help="PNG: runout error against relative cost, one point per setting")
    ap.add_argument("--package-data", action="store_true",
                    help="store the study in py/mpmsdem/tradeoffs.json for mpmsdem.tradeoffs.propose()")
    ap.add_argument("--from-json", help="report rows of an earlier --json file instead of running")
    args = ap.parse_args()
    if args.from_json:
        with open(args.from_json) as f:
            return report(json.load(f), args, "python3 scripts/bench/tradeoff_mpm.py --json FILE, reported with --from-json FILE")
    exe = args.exe or os.path.join(args.build if os.path.isabs(args.build) else os.path.join(REPO, args.build),
                                   "mpmsdem-run")
    if not os.access(exe, os.X_OK):
        sys.exit("tradeoff_mpm: no executable mpmsdem-run at %s (build it, or pass --build/--exe)" % exe)
    with open(SCENE) as f:
        base = json.load(f)

    plan = settings(args.quick)
    rows = []
    command = "python3 scripts/bench/tradeoff_mpm.py" + (" --quick" if args.quick else "")
    with tempfile.TemporaryDirectory(prefix="tradeoff_mpm_") as tmp:
        for i, s in enumerate(plan):
            print("[%d/%d] %s ..." % (i + 1, len(plan), label(s)), end="", flush=True)
            r = run(exe, scene_for(base, s), tmp, "run%d" % i, args.timeout)
            r.update(s)
            r["commit"] = commit_id()
            rows.append(r)
            print(" runout %.3f, H_f/H_i %.3f, %d points, %s steps, %.1f CPU s"
                  % (r["runout"], r["height"], r["particles"], r["steps"], r["cpu_s"]), flush=True)
    return report(rows, args, command)


def commit_id():
    return subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip() or "unknown"


def package_data(rows, command):
    """Replace this study in py/mpmsdem/tradeoffs.json (the other studies stay)."""
    path = os.path.join(REPO, "py", "mpmsdem", "tradeoffs.json")
    data = {"studies": []}
    if os.path.exists(path):
        with open(path) as f:
            data = json.load(f)
    keys = {"dx": "dx", "ppc": "ppc", "viscosity": "flip_viscosity", "precision": "precision"}
    study = {
        "name": "mpm_column_collapse",
        "scene": "examples/scenes/column_collapse.json (L_i 0.1 m, H_i 0.2 m, 0.6 s)",
        "commit": rows[0].get("commit", "unknown"),
        "machine": "2-core x86_64 VM, one thread",
        "command": command,
        "reference": {keys[k]: rows[0][k] for k in keys},
        "rows": [{"settings": {keys[k]: r[k] for k in keys},
                  "errors": {"runout": r["runout_error"], "deposit_height": r["height_error"]},
                  "cost": r["cost"], "cpu_cost": r["cpu_cost"], "reference": i == 0,
                  # the damping is a model choice, not a resolution that converges to the
                  # reference: its rows show sensitivity and are not proposed
                  "sensitivity": r["viscosity"] != rows[0]["viscosity"]} for i, r in enumerate(rows)],
    }
    data["studies"] = [s for s in data["studies"] if s["name"] != study["name"]] + [study]
    with open(path, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    print("stored in %s" % os.path.relpath(path, REPO))


def report(rows, args, command):
    ref = rows[0]
    dflt = next(r for r in rows if all(r[k] == v for k, v in DEFAULT.items()))
    for r in rows:
        r["runout_error"] = (r["runout"] - ref["runout"]) / ref["runout"]
        r["height_error"] = (r["height"] - ref["height"]) / ref["height"]
        # The cost is the work, points x steps, against the default's: the MPM step costs the
        # same per point update at every setting within the scatter of CPU timings on a shared
        # machine (+-30 % between repeats), and it does not change between machines. The CPU
        # time is reported beside it (it also shows what float saves, which the work cannot).
        r["cost"] = float(r["particles"] * r["steps"]) / (dflt["particles"] * dflt["steps"])
        r["cpu_cost"] = r["cpu_s"] / dflt["cpu_s"]
    head = ["dx [m]", "points/cell", "PIC viscosity [m²/s]", "PIC damping [1/s]", "precision", "points", "steps",
            "dL/L_i", "vs ref", "H_f/H_i", "vs ref", "CPU s", "work / default", "CPU / default"]
    body = [["%g" % r["dx"], "%d" % r["ppc"], "%g" % r["viscosity"], "%.0f" % (4 * r["viscosity"] / r["dx"] ** 2),
             r["precision"], "%d" % r["particles"],
             str(r["steps"]), "%.3f" % r["runout"], "%+.1f %%" % (100 * r["runout_error"]), "%.3f" % r["height"],
             "%+.1f %%" % (100 * r["height_error"]), "%.1f" % r["cpu_s"], "%.3g" % r["cost"], "%.3g" % r["cpu_cost"]]
            for r in rows]
    widths = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
    print()
    print("  ".join(h.rjust(w) for h, w in zip(head, widths)))
    for b in body:
        print("  ".join(c.rjust(w) for c, w in zip(b, widths)))
    print("(reference: the first row; work: points x steps, CPU: CPU seconds, each against dx 0.01 m, 8/cell, "
          "PIC viscosity 0.005 m^2/s, double; PIC damping 4 nu / dx^2; one thread)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    if args.package_data:
        package_data(rows, command)
    if args.markdown:
        commit = commit_id()
        with open(args.markdown, "a") as f:
            f.write("\nColumn collapse (examples/scenes/column_collapse.json), commit %s, one thread:\n\n"
                    % rows[0].get("commit", commit))
            f.write("| " + " | ".join(head) + " |\n|" + "---|" * len(head) + "\n")
            for b in body:
                f.write("| " + " | ".join(b) + " |\n")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.5, 4))
        for r in rows[1:]:
            ax.scatter(r["cost"], abs(100 * r["runout_error"]), color="C1" if r["precision"] == "float" else "C0")
            ax.annotate(label(r).replace(", ", "\n", 1), (r["cost"], abs(100 * r["runout_error"])), fontsize=6)
        ax.set_xscale("log")
        ax.set_xlabel("work (points x steps) / default setting")
        ax.set_ylabel("|runout - reference| / reference [%]")
        ax.set_title("Column collapse: runout error against cost (reference: %s)" % label(ref), fontsize=8)
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
