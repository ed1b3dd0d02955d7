#!/usr/bin/env python3
"""MPM settings against the coupled outputs of the paper's §3.3 scene (three stacked blocks).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/bench/tradeoff_stacked_blocks.py
        [--out results/tradeoff_stacked_blocks] [--duration 0.35] [--quick] [--json FILE]
        [--markdown FILE] [--plot PNG] [--package-data] [--report-only]

docs/tradeoffs.md measures grid spacing, points per cell, FLIP/PIC damping and precision on the
column collapse, whose output is a runout. A user of the coupling reads forces and block motions
instead; this script measures the same knobs on them. Each setting runs
``examples/liu2018_blocks.py --dx --ppc --flip-viscosity --precision --duration --no-plots`` in its
own process on one thread (free flow first, then the coupled run with ``dtAuto``) and reads its
``summary.json``:

- peak downstream flow force on the glued bottom block (10 ms moving mean) and the mean force on
  it from 20 ms after that peak to the end (the sustained load),
- when the middle block falls (its centre half a block height below its start) and when the flow
  first touches the top block, both from the release,
- the travel of the middle and top blocks at the end,
- its cost: points x steps of the coupled run (the work), the coupled run's wall seconds (one
  thread, so its CPU time) and the whole process's CPU seconds.

One knob at a time from the default (dx 0.01 m, 8 points per cell, the paper's blend as a PIC
viscosity of 0.0503 m^2/s, double: the example's ``--full``); the reference is the finest grid (dx 0.005 m, 8 per cell; 256,000 points,
``--quick``: dx 1/150 m). Errors are relative to the reference (for event times: of the time
from the release), costs relative to the default, all measured in this one command. Every
finished run is kept under ``--out`` (its summary and CPU seconds), and a second call with the
same ``--out`` and ``--duration`` reports it without running it again, so an interrupted sweep
resumes. ``--package-data`` stores the study in py/mpmsdem/tradeoffs.json for
``mpmsdem.tradeoffs.propose(output="sustained_force" | "middle_fall_time")``.

Cost of the full set on one core of the 2-core CI-class VM: about an hour (the reference run is
most of it). Needs YADE's Python (the example runs in it), numpy, matplotlib for --plot.
"""
import argparse
import json
import os
import resource
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLE = os.path.join(REPO, "examples", "liu2018_blocks.py")
DEFAULT = {"dx": 0.01, "ppc": 8, "viscosity": 0.0503, "precision": "double"}
# Spacings with whole cells along the flume (0.6 m), its width (0.2 m) and the column (0.1 m).
SPACINGS = (0.02, 0.0125, 0.01, 1.0 / 150.0, 0.005)
KEYS = {"dx": "dx", "ppc": "ppc", "viscosity": "flip_viscosity", "precision": "precision"}
# relative errors stored for mpmsdem.tradeoffs: output name -> row key. Not the peak force: the
# 10 ms peak of the impact transient does not converge with the grid (docs/tradeoffs.md), so no
# setting can be proposed for an error in it.
OUTPUTS = {"sustained_force": "sustained", "middle_fall_time": "middle_fall"}


def plan(quick):
    """The runs, cheapest first so that an interrupted sweep has its small runs; the last is the reference."""
    finest = SPACINGS[-2] if quick else SPACINGS[-1]
    runs = [dict(DEFAULT, dx=dx) for dx in SPACINGS if dx > finest]
    runs += [dict(DEFAULT, ppc=1)]
    # the damping: the scenes' default (a tenth of the paper's), 0.02 m^2/s, twice the paper's
    runs += [dict(DEFAULT, viscosity=nu) for nu in (0.005, 0.02, 0.1)]
    runs += [dict(DEFAULT, precision="float"), dict(DEFAULT, ppc=27), dict(DEFAULT, dx=finest)]
    return runs


def name(s):
    return "dx%.5g_ppc%d_nu%g_%s" % (s["dx"], s["ppc"], s["viscosity"], s["precision"])


def label(s):
    return "dx %.3g, %d/cell, PIC viscosity %g m^2/s, %s" % (s["dx"], s["ppc"], s["viscosity"], s["precision"])


def runOne(s, folder, duration, timeout):
    """Run the example for setting s in its own process; return its row (kept in folder/row.json)."""
    rowPath = os.path.join(folder, "row.json")
    if os.path.exists(rowPath):
        with open(rowPath) as f:
            row = json.load(f)
        if row["duration"] == duration and all(row[k] == v for k, v in s.items()):
            return row, True
    os.makedirs(folder, exist_ok=True)
    cmd = [sys.executable, EXAMPLE, "--dx", repr(s["dx"]), "--ppc", str(s["ppc"]), "--flip-viscosity", repr(s["viscosity"]),
           "--precision", s["precision"], "--duration", repr(duration), "--no-plots", "--out", folder]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(os.path.join(folder, "log.txt"), "w") as log:
        proc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, timeout=timeout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        with open(os.path.join(folder, "log.txt")) as f:
            tail = f.read()[-1500:]
        raise RuntimeError("%s failed (exit %d); its log ends:\n%s" % (label(s), proc.returncode, tail))
    with open(os.path.join(folder, "summary.json")) as f:
        sm = json.load(f)
    b, m, t = sm["blocks"]["bottom"], sm["blocks"]["middle"], sm["blocks"]["top"]
    row = dict(s, duration=duration, particles=sm["particles"], steps=sm["steps"], dt_min=sm["dt_min"],
               peak=b["peak_force"], peak_time=b["peak_time"], sustained=b["mean_force_after"],
               middle_fall=m["fall_time"], top_touch=t["first_touch"], top_fall=t["fall_time"],
               middle_travel=m["travel"], top_travel=t["travel"], eq20=sm["eq20_bottom"],
               coupled_s=sm["wall_seconds"]["coupled"],
               cpu_s=(after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), commit=commitId())
    with open(rowPath, "w") as f:
        json.dump(row, f, indent=1)
    return row, False


def commitId():
    return subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip() or "unknown"


def relative(v, ref):
    return None if v is None or ref is None else (v - ref) / ref


def derive(rows):
    """Errors against the reference (the last row) and costs against the default setting."""
    ref = rows[-1]
    dflt = next(r for r in rows if all(r[k] == v for k, v in DEFAULT.items()))
    for r in rows:
        for key in ("peak", "sustained", "middle_fall", "top_touch", "middle_travel", "top_travel"):
            r[key + "_error"] = relative(r[key], ref[key])
        r["work"] = float(r["particles"] * r["steps"]) / (dflt["particles"] * dflt["steps"])
        r["coupled_cost"] = r["coupled_s"] / dflt["coupled_s"]
    return rows


def pct(v):
    return "–" if v is None else "%+.0f %%" % (100 * v)


def num(v, f):
    return "never" if v is None else f % v


def table(rows):
    head = ["dx [m]", "points/cell", "PIC viscosity [m²/s]", "precision", "points", "steps", "peak F [N]", "vs ref",
            "sustained F [N]", "vs ref", "middle falls [s]", "top touched [s]", "top falls [s]",
            "middle / top travel [m]", "coupled s", "work / default", "time / default"]
    body = [["%.4g" % r["dx"], "%d" % r["ppc"], "%g" % r["viscosity"], r["precision"], "%d" % r["particles"],
             "%d" % r["steps"], "%.1f" % r["peak"], pct(r["peak_error"]), num(r["sustained"], "%.2f"),
             pct(r["sustained_error"]), num(r["middle_fall"], "%.3f"), num(r["top_touch"], "%.3f"),
             num(r["top_fall"], "%.3f"), "%.3f / %.3f" % (r["middle_travel"], r["top_travel"]),
             "%.0f" % r["coupled_s"], "%.3g" % r["work"], "%.3g" % r["coupled_cost"]] for r in rows]
    return head, body


def printTable(head, body):
    widths = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
    print("  ".join(h.rjust(w) for h, w in zip(head, widths)))
    for b in body:
        print("  ".join(c.rjust(w) for c, w in zip(b, widths)))


def packageData(rows, command):
    """Replace this study in py/mpmsdem/tradeoffs.json (the other studies stay)."""
    path = os.path.join(REPO, "py", "mpmsdem", "tradeoffs.json")
    with open(path) as f:
        data = json.load(f)
    ref = rows[-1]
    study = {
        "name": "coupled_stacked_blocks",
        "scene": "examples/liu2018_blocks.py (paper §3.3, three stacked blocks, %g s)" % ref["duration"],
        "commit": ref["commit"],
        "machine": "2-core x86_64 VM, one thread",
        "command": command,
        "reference": {KEYS[k]: ref[k] for k in KEYS},
        "rows": [{"settings": {KEYS[k]: r[k] for k in KEYS},
                  "errors": {out: r[key + "_error"] for out, key in OUTPUTS.items()
                             if r[key + "_error"] is not None},
                  "cost": r["work"], "cpu_cost": r["coupled_cost"], "reference": r is ref,
                  # the damping is a model choice, not a resolution
                  "sensitivity": r["viscosity"] != ref["viscosity"]} for r in rows],
    }
    data["studies"] = [s for s in data["studies"] if s["name"] != study["name"]] + [study]
    with open(path, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    print("stored in %s" % os.path.relpath(path, REPO))


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    for ax, key, what in ((axes[0], "sustained_error", "sustained force on the bottom block"),
                          (axes[1], "middle_fall_error", "time the middle block falls")):
        for r in rows[:-1]:
            if r[key] is None:
                continue
            colour = "C1" if r["precision"] == "float" else ("C2" if r["viscosity"] != DEFAULT["viscosity"] else "C0")
            ax.scatter(r["work"], 100 * r[key], color=colour)
            ax.annotate(label(r).replace(", ", "\n", 1), (r["work"], 100 * r[key]), fontsize=6)
        ax.axhline(0.0, color="grey", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("work (points x steps) / default (dx 0.01 m, 8/cell)")
        ax.set_ylabel("%s: (value - reference) / reference [%%]" % what, fontsize=8)
    grid = sorted((r for r in rows if r["ppc"] == 8 and r["viscosity"] == DEFAULT["viscosity"] and r["precision"] == "double"),
                  key=lambda r: r["dx"])
    ax = axes[2]
    ax.plot([1e3 * r["dx"] for r in grid], [r["peak"] for r in grid], "o-", label="peak (10 ms mean)")
    ax.plot([1e3 * r["dx"] for r in grid], [r["sustained"] for r in grid], "s-", label="sustained (mean after it)")
    ax.set_xlabel("grid spacing dx [mm] (8 points per cell)")
    ax.set_ylabel("downstream flow force on the bottom block [N]")
    ax.legend(fontsize=8)
    fig.suptitle("Paper §3.3 stacked blocks: error against cost (reference: %s); green: damping, orange: float"
                 % label(rows[-1]), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join("results", "tradeoff_stacked_blocks"),
                    help="folder of the runs; finished runs in it are not run again")
    ap.add_argument("--duration", type=float, default=0.35,
                    help="coupled run [s] after the free flow (default 0.35: the impact and both falls)")
    ap.add_argument("--quick", action="store_true", help="reference dx 1/150 m instead of 0.005 m")
    ap.add_argument("--timeout", type=float, default=7200, help="seconds allowed per run (default 7200)")
    ap.add_argument("--json", help="write the rows as JSON to this file")
    ap.add_argument("--markdown", help="append the table to this file")
    ap.add_argument("--plot", help="PNG: force errors against relative cost")
    ap.add_argument("--package-data", action="store_true",
                    help="store the study in py/mpmsdem/tradeoffs.json for mpmsdem.tradeoffs.propose()")
    ap.add_argument("--report-only", action="store_true", help="report the finished runs in --out, run nothing")
    ap.add_argument("--workers", type=int, default=1, help="runs side by side, one thread each (default 1)")
    a = ap.parse_args(argv)
    if not a.duration > 0:
        ap.error("--duration = %r s: must be > 0" % a.duration)
    runs = plan(a.quick)
    if a.workers > 1 and not a.report_only:
        # the runs side by side, the largest (the reference, last) first; each on one thread, its
        # cost read as its work (points x steps), which sharing the machine does not change
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(a.workers) as pool:
            list(pool.map(lambda s: runOne(s, os.path.join(os.path.abspath(a.out), name(s)), a.duration, a.timeout),
                          reversed(runs)))
    rows = []
    for i, s in enumerate(runs):
        folder = os.path.join(os.path.abspath(a.out), name(s))
        if a.report_only:
            path = os.path.join(folder, "row.json")
            if not os.path.exists(path):
                sys.exit("tradeoff_stacked_blocks: %s has not run (no %s)" % (label(s), path))
            with open(path) as f:
                rows.append(json.load(f))
            continue
        print("[%d/%d] %s ..." % (i + 1, len(runs), label(s)), end="", flush=True)
        row, kept = runOne(s, folder, a.duration, a.timeout)
        rows.append(row)
        print(" %speak %.1f N, sustained %s N, middle falls %s s, %d points, %d steps, %.0f s"
              % ("(kept) " if kept else "", row["peak"], num(row["sustained"], "%.2f"),
                 num(row["middle_fall"], "%.3f"), row["particles"], row["steps"], row["coupled_s"]), flush=True)
    derive(rows)
    head, body = table(rows)
    print()
    printTable(head, body)
    print("(reference: the last row; work: points x steps of the coupled run, time: its wall seconds, one thread, "
          "each against dx 0.01 m, 8/cell, PIC viscosity 0.0503 m^2/s, double)")
    command = "OMP_NUM_THREADS=1 python3 scripts/bench/tradeoff_stacked_blocks.py" + (" --quick" if a.quick else "")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    if a.package_data:
        packageData(rows, command)
    if a.markdown:
        with open(a.markdown, "a") as f:
            f.write("\n| " + " | ".join(head) + " |\n|" + "---|" * len(head) + "\n")
            for b in body:
                f.write("| " + " | ".join(b) + " |\n")
    if a.plot:
        plot(rows, a.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
