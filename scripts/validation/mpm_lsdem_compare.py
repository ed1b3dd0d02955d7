#!/usr/bin/env python3
"""Validation probe (opt-in, one to three minutes a run on one core at the default resolution): paper
§4.1, MPM–SDEM against MPM–LSDEM. Runs the §3.3 scene (examples/liu2018_blocks.py: three
stacked wooden blocks in the Liu et al. 2018 flume, the bottom one glued) with the blocks as
SDEM sphero-boxes and as YADE LevelSet boxes (``--blocks levelset``, one run per level-set grid
spacing), at one flow resolution, and prints and writes a markdown table: the middle and top
blocks' travel at the end, when each falls, the peak flow force on the bottom block (10 ms
mean), the coupled run's wall time, steps and wall time per step (each run in its own process,
one after the other, in this command), and the LevelSet runs' differences from the SDEM run.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/mpm_lsdem_compare.py
        [--dx 0.01] [--ppc 1] [--flip-viscosity NU] [--duration 1.0] [--ls-spacing 0.002[,0.004,...]]
        [--ls-nodes 602]
        [--out results/mpm_lsdem_compare] [--snapshots 0.40,0.45,0.50] [--snapshots-only]

The paper's §4.1 gives, against the experiment (Liu et al. 2018), the top block's travel 4.0 %
(SDEM) and 10.7 % (LSDEM) off and the middle block's 1.4 % and 1.7 % off, but not the measured
travel itself; what this script can compare is the two block models with everything else the
same. The signs of the paper's differences are not given either, so the paper's LSDEM − SDEM
difference is only bounded: |10.7 ± 4.0| % (6.7 or 14.7 %) of the measured travel for the top
block, |1.7 ± 1.4| % (0.3 or 3.1 %) for the middle one. The table is written to
``OUT/compare.md`` and the numbers to ``OUT/compare.json``; docs/coupled-results.md quotes it.

The paper's Fig 12 shows the runs side by side at t = 0.40, 0.45 and 0.50 s; ``OUT/fig12.png`` is
ours: one row per run, one column per time of ``--snapshots``, each panel a side view (x along the
flume, z up) of the material points coloured by speed and the outline of each block's projection.
The panels are the recorded states (the flow's snapshots, every 0.05 s in the example, and the
blocks' records in coupled.h5 at the same time), never interpolated: a time with no snapshot within
half a snapshot interval is refused. ``--snapshots-only`` redraws the figure from the run folders
of an earlier call (same ``--out`` and ``--ls-spacing``) without running anything.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flume_convergence import commit  # noqa: E402  (same folder: the checkout's commit, as the other validations)
EXAMPLE = os.path.join(ROOT, "examples", "liu2018_blocks.py")
PAPER = {"top": {"sdem": 4.0, "lsdem": 10.7}, "middle": {"sdem": 1.4, "lsdem": 1.7}}  # % off the experiment


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] > 0 (default the example's 0.01)")
    ap.add_argument("--ppc", type=int, default=1, help="material points per cell, a cube (default 1)")
    ap.add_argument("--flip-viscosity", type=float, default=None,
                    help="PIC viscosity of the flow's FLIP/PIC blend [m²/s] > 0 (default: the example's at --dx; "
                         "the paper's is mpmsdem.mpm.PAPER_VISCOSITY, 0.05)")
    ap.add_argument("--duration", type=float, default=1.0, help="coupled run [s] > 0 (default 1.0)")
    ap.add_argument("--ls-spacing", default="0.002",
                    help="level-set grid spacings [m], comma-separated, each > 0 and at most the points' radius "
                         "R_p0 (default 0.002)")
    ap.add_argument("--ls-nodes", type=int, default=602, help="boundary nodes per LevelSet block >= 8 (default 602)")
    ap.add_argument("--out", default=os.path.join("results", "mpm_lsdem_compare"), help="output folder")
    ap.add_argument("--snapshots", default="0.40,0.45,0.50",
                    help="times [s] of the side views in OUT/fig12.png, comma-separated, each within the run's "
                         "duration (default the paper's Fig 12: 0.40,0.45,0.50)")
    ap.add_argument("--snapshots-only", action="store_true",
                    help="only redraw OUT/fig12.png from the run folders an earlier call wrote in OUT")
    a = ap.parse_args(argv)
    try:
        a.ls_spacing = [float(h) for h in a.ls_spacing.split(",")]
    except ValueError:
        ap.error("--ls-spacing %r: must be comma-separated spacings [m]" % a.ls_spacing)
    if not all(h > 0 for h in a.ls_spacing):
        ap.error("--ls-spacing %r: every spacing must be > 0" % (a.ls_spacing,))
    if not a.dx > 0:
        ap.error("--dx %r: must be > 0" % a.dx)
    from mpmsdem.analysis import pointRadius
    rp = pointRadius(a.dx, a.ppc)
    coarse = [h for h in a.ls_spacing if h > rp]
    if coarse:  # the example would refuse them, after the runs before them
        ap.error("--ls-spacing %s: every spacing must be at most the points' radius R_p0 = %.4g m at --dx %g, "
                 "--ppc %d" % (",".join("%g" % h for h in coarse), rp, a.dx, a.ppc))
    if not a.duration > 0:
        ap.error("--duration %r: must be > 0" % a.duration)
    if a.flip_viscosity is not None and not (a.flip_viscosity > 0 and a.flip_viscosity < float("inf")):
        ap.error("--flip-viscosity %r: must be > 0 and finite" % a.flip_viscosity)
    if a.ls_nodes < 8:
        ap.error("--ls-nodes %r: must be >= 8" % a.ls_nodes)
    try:
        a.snapshots = [float(t) for t in a.snapshots.split(",")]
    except ValueError:
        ap.error("--snapshots %r: must be comma-separated times [s]" % a.snapshots)
    duration, source = a.duration, "--duration"
    if a.snapshots_only:  # the runs on disk set the bound, not this call's --duration
        for _, folder in runFolders(a):
            if not os.path.exists(os.path.join(folder, "summary.json")):
                ap.error("--snapshots-only: no finished run in %s (run once without --snapshots-only)" % folder)
        with open(os.path.join(runFolders(a)[0][1], "summary.json")) as f:
            duration, source = json.load(f)["duration"], "the runs' summary.json"
    late = [t for t in a.snapshots if not 0 <= t <= duration]
    if late:
        ap.error("--snapshots %s: every time must be within the run's duration, 0 to %g s (%s)" %
                 (",".join("%g" % t for t in late), duration, source))
    return a


def runFolders(a):
    """(row name, output folder) of each run: SDEM, then one per level-set spacing."""
    return [("SDEM", os.path.join(a.out, "sdem"))] + [
        ("LevelSet h %g mm" % (1e3 * h), os.path.join(a.out, "levelset_%gmm" % (1e3 * h))) for h in a.ls_spacing]


def runOne(a, out, extra):
    """One run of the example in its own process, into ``out``; returns its summary.json."""
    name = os.path.basename(out)
    cmd = [sys.executable, EXAMPLE, "--dx", repr(a.dx), "--ppc", str(a.ppc), "--duration", repr(a.duration),
           "--out", out] + extra + ([] if a.flip_viscosity is None else ["--flip-viscosity", repr(a.flip_viscosity)])
    print("running %s: %s" % (name, " ".join(cmd[1:])), flush=True)
    t0 = time.time()
    subprocess.run(cmd, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    s["process_seconds"] = time.time() - t0
    s["command"] = " ".join(["examples/liu2018_blocks.py"] + cmd[2:])
    return s


def row(name, s):
    b, m, t = s["blocks"]["bottom"], s["blocks"]["middle"], s["blocks"]["top"]
    wall = s["wall_seconds"]["coupled"]
    return {"run": name, "middle_travel": m["travel"], "top_travel": t["travel"], "middle_fall": m["fall_time"],
            "top_fall": t["fall_time"], "middle_dz": m["dz"], "top_dz": t["dz"], "bottom_peak": b["peak_force"],
            "bottom_peak_time": b["peak_time"], "bottom_after": b["mean_force_after"], "steps": s["steps"],
            "dt_min": s["dt_min"], "coupled_wall": wall, "ms_per_step": 1e3 * wall / s["steps"],
            "masses": s["block_mass"], "level_set": s["level_set"], "command": s["command"]}


def fmt(x, f="%.3f"):
    return "never" if x is None else f % x


def table(rows, a, meta):
    ref = rows[0]
    lines = ["| run | middle travel [m] | top travel [m] | middle falls [s] | top falls [s] | bottom peak, 10 ms "
             "[N] (at [s]) | coupled steps (smallest O.dt [s]) | coupled wall [s] | wall per step [ms] |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append("| %s | %.4f | %.4f | %s | %s | %.2f (%.3f) | %d (%.2g) | %.0f | %.2f |" % (
            r["run"], r["middle_travel"], r["top_travel"], fmt(r["middle_fall"]), fmt(r["top_fall"]),
            r["bottom_peak"], r["bottom_peak_time"], r["steps"], r["dt_min"], r["coupled_wall"], r["ms_per_step"]))
    lines += ["", "| LevelSet run − SDEM run | middle travel | top travel | middle falls | top falls | bottom peak | "
              "wall per step |", "|---|---:|---:|---:|---:|---:|---:|"]

    def rel(x, y):
        return "%+.4f m (%+.1f %%)" % (x - y, 100 * (x - y) / abs(y)) if y else "%+.4f m" % (x - y)

    def dt(x, y):
        return "–" if x is None or y is None else "%+.3f s" % (x - y)
    for r in rows[1:]:
        lines.append("| %s | %s | %s | %s | %s | %+.2f N (%+.1f %%) | × %.2f |" % (
            r["run"], rel(r["middle_travel"], ref["middle_travel"]), rel(r["top_travel"], ref["top_travel"]),
            dt(r["middle_fall"], ref["middle_fall"]), dt(r["top_fall"], ref["top_fall"]),
            r["bottom_peak"] - ref["bottom_peak"], 100 * (r["bottom_peak"] / ref["bottom_peak"] - 1),
            r["ms_per_step"] / ref["ms_per_step"]))
    lines += ["", "Paper §4.1 (its numbers, against the experiment; the measured travel is not given): top block "
              "%.1f %% (SDEM) / %.1f %% (LSDEM) off, middle block %.1f %% / %.1f %% off; LSDEM − SDEM therefore "
              "%.1f or %.1f %% (top), %.1f or %.1f %% (middle) of the measured travel, signs not given." % (
                  PAPER["top"]["sdem"], PAPER["top"]["lsdem"], PAPER["middle"]["sdem"], PAPER["middle"]["lsdem"],
                  PAPER["top"]["lsdem"] - PAPER["top"]["sdem"], PAPER["top"]["lsdem"] + PAPER["top"]["sdem"],
                  PAPER["middle"]["lsdem"] - PAPER["middle"]["sdem"], PAPER["middle"]["lsdem"] + PAPER["middle"]["sdem"]),
              "", "Δx %g m, %d point(s) per cell, %s, %g s coupled; commit %s at the start; %s; %s" % (
                  a.dx, a.ppc, meta["flip_blend"], a.duration, meta["commit"], meta["machine"], meta["threads"])]
    return "\n".join(lines)


def recordAt(times, t):
    """Index of the record at ``t`` [s]: the nearest one, if within half the record interval (the
    median spacing of ``times``); a ValueError naming ``t`` and the nearest record otherwise, as a
    state between records would have to be made up."""
    times = np.asarray(times, dtype=float)
    if times.size == 0:
        raise ValueError("t = %g s: there are no records" % t)
    k = int(np.argmin(np.abs(times - t)))
    half = 0.5 * float(np.median(np.diff(times))) if times.size > 1 else 0.0
    if abs(times[k] - t) > half * (1 + 1e-9):
        raise ValueError("t = %g s: no record within half a record interval (%g s) of it; the nearest is at %.4f s"
                         % (t, half, times[k]))
    return k


def rotation(rv):
    """The rotation matrix of a rotation vector (Rodrigues)."""
    angle = np.linalg.norm(rv)
    if angle == 0:
        return np.eye(3)
    k = np.asarray(rv) / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def outline(pos, rv, half):
    """The x–z outline of a box's side view: the convex hull (counter-clockwise) of its 8 corners projected,
    the box axis-aligned at the first record (coupled.h5's rotation counts from there)."""
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)
    p = sorted(set(map(tuple, np.round((pos + (signs * half) @ rotation(rv).T)[:, [0, 2]], 12))))
    hull = []
    for pts in (p, p[::-1]):  # monotone chain: lower, then upper half
        part = []
        for q in pts:
            while len(part) >= 2 and np.cross(np.subtract(part[-1], part[-2]), np.subtract(q, part[-2])) <= 0:
                part.pop()
            part.append(q)
        hull += part[:-1]
    return np.array(hull)


def runStates(folder, times):
    """A run's recorded state at each of ``times`` [s]: (record time, points' x and z, their speeds, the
    blocks' outlines from the bottom one up: the bodies and sizes its summary.json names)."""
    import h5py
    with open(os.path.join(folder, "summary.json")) as f:
        run = json.load(f)
    if "block_ids" not in run:
        raise ValueError("%s: summary.json names no blocks (a run of an older example: run it again)" % folder)
    half = np.asarray(run["block_half"], dtype=float)
    flow = []
    with h5py.File(os.path.join(folder, "mpm", "mpm.h5"), "r") as f:
        snaps = [f["snapshots"][n] for n in sorted(f["snapshots"])]
        recorded = [float(g.attrs["time"]) for g in snaps]
        for t in times:
            try:
                snap = snaps[recordAt(recorded, t)]
            except ValueError as e:
                raise ValueError("%s, the flow's snapshots: %s" % (folder, e))
            flow.append((float(snap.attrs["time"]), int(snap.attrs["step"]), snap["x"][:], snap["v"][:]))
    states = []
    with h5py.File(os.path.join(folder, "coupled.h5"), "r") as f:
        g = f["series"]
        steps = g["step"][:]
        n = g["pos"].shape[1] // 3
        ids = json.loads(f.attrs["ids"])  # the columns' YADE ids, LevelSet bodies among them
        columns = [ids.index(i) for i in run["block_ids"]]  # bottom, middle, top
        for tRec, step, x, v in flow:
            same = np.nonzero(steps == step)[0]
            if not same.size:  # the blocks must be drawn as they were at the flow's snapshot, not near it
                raise ValueError("%s: coupled.h5 has no record of step %d, the flow's snapshot at %.4f s"
                                 % (folder, step, tRec))
            pos, rv = g["pos"][same[0]].reshape(n, 3), g["rotation"][same[0]].reshape(n, 3)
            states.append((tRec, x[:, [0, 2]], np.linalg.norm(v, axis=1),
                           [outline(pos[b], rv[b], half) for b in columns]))
    return states


def figure(a, folders):
    """OUT/fig12.png: the paper's Fig 12 for our runs, a row per run, a column per --snapshots time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection
    try:
        states = [runStates(folder, a.snapshots) for _, folder in folders]
    except ValueError as e:  # a time with no record: say which, without a traceback
        sys.exit("%s: %s" % (os.path.basename(__file__), e))
    for (name, _), row in zip(folders, states):
        for t, st in zip(a.snapshots, row):
            if abs(st[0] - t) > 1e-3:  # the flow is recorded every few hundredths of a second only
                print("%s, t = %g s: the nearest record, at %.3f s, is shown" % (name, t, st[0]))
    with open(os.path.join(folders[0][1], "summary.json")) as f:
        run = json.load(f)
    spacing = run["dx"] / round(run["ppc"] ** (1.0 / 3.0))  # the points' initial spacing: their drawn diameter
    corners = np.vstack([o for row in states for st in row for o in st[3]])
    # the blocks' neighbourhood: from upstream of the stack to past where the blocks went, bed to above them
    x0, x1 = corners[:, 0].min() - 0.06, corners[:, 0].max() + 0.06
    z0, z1 = -0.01, max(corners[:, 1].max() + 0.03, 0.08)
    inView = [sp[(p[:, 0] >= x0) & (p[:, 0] <= x1)] for row in states for _, p, sp, _ in row]
    vmax = max(0.1, np.ceil(10 * max(sp.max() for sp in inView if sp.size)) / 10)
    nr, nc, pw = len(folders), len(a.snapshots), 3.6  # panel width [in]
    fig, ax = plt.subplots(nr, nc, sharex=True, sharey=True, squeeze=False, layout="constrained",
                           figsize=(nc * pw + 1.4, nr * (0.8 * pw * (z1 - z0) / (x1 - x0) + 0.35) + 0.75))
    colours = ("0.35", "tab:red", "tab:orange")
    for r, (name, _) in enumerate(folders):
        for c, (tRec, p, speed, boxes) in enumerate(states[r]):
            axc = ax[r, c]
            discs = EllipseCollection(spacing, spacing, 0.0, units="xy", offsets=p, offset_transform=axc.transData,
                                      cmap="viridis", clim=(0, vmax), linewidths=0)
            discs.set_array(speed)
            axc.add_collection(discs)
            axc.axhline(0.0, color="k", lw=1)  # the bed's surface
            for o, colour, which in zip(boxes, colours, ("bottom (glued)", "middle", "top")):
                axc.fill(o[:, 0], o[:, 1], facecolor="none", edgecolor=colour, lw=1.5, label="%s block" % which)
            if abs(tRec - states[0][c][0]) > 1e-3:  # the column title is the first row's record time
                axc.text(0.02, 0.9, "t = %.3f s" % tRec, transform=axc.transAxes, fontsize=8)
            axc.set_xlim(x0, x1)
            axc.set_ylim(z0, z1)
            axc.set_aspect("equal")
            if r == 0:
                axc.set_title("t = %.2f s" % tRec)
            if r == nr - 1:
                axc.set_xlabel("x along the flume [m]")
            if c == 0:
                axc.set_ylabel("%s\nz [m]" % name)
    ax[0, 0].legend(loc="upper right", fontsize=7, frameon=False)
    fig.colorbar(discs, ax=ax, shrink=0.8, label="point speed [m/s], 0 to %.1f" % vmax)
    fig.suptitle("Paper §4.1, Fig 12: side views of the material points (coloured by speed) and the blocks; "
                 "Δx %g m, %d point(s) per cell" % (run["dx"], run["ppc"]))
    path = os.path.join(a.out, "fig12.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print("side views in %s" % path)
    return path


def main(argv):
    a = parse(argv)
    os.makedirs(a.out, exist_ok=True)
    meta = {"commit": commit(), "machine": "%s, %s, %d cores" % (platform.machine(), platform.processor() or
                                                                  platform.system(), os.cpu_count() or 0),
            "threads": "OMP_NUM_THREADS=%s" % os.environ.get("OMP_NUM_THREADS", "unset")}
    folders = runFolders(a)
    if a.snapshots_only:
        figure(a, folders)
        return None
    runs = [("SDEM", runOne(a, folders[0][1], []))]
    for h, (name, out) in zip(a.ls_spacing, folders[1:]):
        runs.append((name, runOne(a, out, ["--blocks", "levelset", "--ls-spacing", repr(h),
                                           "--ls-nodes", str(a.ls_nodes)])))
    meta["flip_blend"] = runs[0][1]["flip_blend"]
    rows = [row(name, s) for name, s in runs]
    text = table(rows, a, meta)
    print(text)
    with open(os.path.join(a.out, "compare.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(a.out, "compare.json"), "w") as f:
        json.dump({"meta": meta, "rows": rows}, f, indent=1)
    figure(a, folders)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
