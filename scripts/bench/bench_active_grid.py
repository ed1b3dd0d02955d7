#!/usr/bin/env python3
"""Cost follows the particles, not the box: the same flow in grids it fills less and less.

Runs `mpmsdem-run --bench` on bench_mpm.py's dam-break block (the same particles, 8 per
cell) in its own box and in boxes enlarged along x and z until the particles fill the given
fractions of the grid's cells, and prints particle-updates/s and the cost of each box relative
to the snug one (1.0: empty space is free). With --baseline-exe, an older build runs the same
scenes in the same command (interleaved, so machine load hits both alike) and the last column
is new/old speed, e.g. the gain of the active grid over a dense grid sweep.

With one CPU thread (--threads 1, the default) the speeds are particle updates per CPU second
of the run (user + system time of the process, set-up included), which other work on the
machine disturbs much less than wall time; otherwise per wall second of the step loop.

    scripts/bench/bench_active_grid.py --build build --fills 0.05,0.01
    scripts/bench/bench_active_grid.py --exe build/mpmsdem-run --baseline-exe old/mpmsdem-run --markdown FILE

Uses only the standard library. Exit status 1 when a run fails.
"""
import argparse
import datetime
import json
import os
import resource
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_mpm  # noqa: E402  (the dam-break scene, running and table helpers)


def parse_fills(text):
    try:
        fills = [float(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("fills must be comma-separated fractions, e.g. 0.05,0.01")
    if not fills or not all(0 < f < 1 for f in fills):
        raise argparse.ArgumentTypeError("each fill must be in (0, 1): the fraction of grid cells holding particles")
    return fills


def sparse_scene(size, fill):
    """bench_mpm's dam-break scene with its grid stretched along x and z to `fill`.

    The block keeps its place at the origin and the walls stay at the grid faces, so the flow
    is the same until it would have reached the snug box's far wall.
    """
    scene, particles = bench_mpm.dam_break_scene(size)
    dx = scene["grid"]["dx"]
    block = [round(h / dx) for h in scene["particles"][0]["hi"]]
    cells = list(scene["grid"]["cells"])
    snugFill = float(block[0] * block[1] * block[2]) / (cells[0] * cells[1] * cells[2])
    if fill is None:
        return scene, particles, snugFill
    if fill >= snugFill:
        raise ValueError("fill %g: must be below the snug box's %.3g" % (fill, snugFill))
    stretch = (snugFill / fill) ** 0.5
    cells[0] = int(round(cells[0] * stretch))
    cells[2] = int(round(cells[2] * stretch))
    scene["grid"]["cells"] = cells
    scene["description"] += ", grid stretched to %d x %d x %d cells" % tuple(cells)
    return scene, particles, float(block[0] * block[1] * block[2]) / (cells[0] * cells[1] * cells[2])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build", help="build folder holding mpmsdem-run (default: build)")
    ap.add_argument("--exe", help="path of mpmsdem-run (overrides --build)")
    ap.add_argument("--baseline-exe", help="an older mpmsdem-run to run on the same scenes (new/old speed column)")
    ap.add_argument("--size", type=float, default=1e5, help="particles (default 1e5)")
    ap.add_argument("--fills", type=parse_fills, default=parse_fills("0.05,0.01"),
                    help="fractions of the grid cells the particles fill (default 0.05,0.01)")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    ap.add_argument("--precision", default="double", choices=("double", "float"))
    ap.add_argument("--threads", type=int, default=1,
                    help="OMP_NUM_THREADS for CPU runs (default 1: speeds per CPU second)")
    ap.add_argument("--steps", type=int, default=100, help="steps per run (default 100)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per scene and build; the fastest counts (default 3)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds allowed per run (default 1800)")
    ap.add_argument("--markdown", help="append the results as a markdown table to this file")
    args = ap.parse_args()
    if args.threads < 1:
        ap.error("--threads must be >= 1")
    if args.steps < 1 or args.repeat < 1:
        ap.error("--steps and --repeat must be >= 1")
    if args.size < 64:
        ap.error("--size must be >= 64 particles")

    exes = {"new": bench_mpm.find_exe(args)}
    if args.baseline_exe:
        exes["old"] = args.baseline_exe
    for name, exe in exes.items():
        if not os.access(exe, os.X_OK):
            sys.exit("bench_active_grid: no executable mpmsdem-run at %s" % exe)

    threads = args.threads if args.backend == "cpu" else None
    cpuClock = threads == 1
    best = {}  # (fill index, build) -> updates/s
    fills = [None] + args.fills
    failed = False
    with tempfile.TemporaryDirectory(prefix="bench_active_grid_") as tmp:
        scenes = []
        for i, fill in enumerate(fills):
            try:
                scene, particles, actual = sparse_scene(args.size, fill)
            except ValueError as e:
                sys.exit("bench_active_grid: --fills: %s" % e)
            path = os.path.join(tmp, "scene_%d.json" % i)
            with open(path, "w") as f:
                json.dump(scene, f)
            scenes.append((path, particles, actual, scene["grid"]["cells"]))
        for rep in range(args.repeat):
            for i, (path, particles, actual, cells) in enumerate(scenes):
                for name, exe in exes.items():
                    print("[%d/%d] %s build, fill %.3g (%d x %d x %d cells), %d particles ..."
                          % (rep + 1, args.repeat, name, actual, cells[0], cells[1], cells[2], particles), flush=True)
                    before = resource.getrusage(resource.RUSAGE_CHILDREN)
                    try:
                        r = bench_mpm.run_one(exe, path, args.backend, args.precision, args.steps, threads,
                                              args.timeout)
                    except (RuntimeError, subprocess.TimeoutExpired) as e:
                        print("bench_active_grid: %s" % e, file=sys.stderr)
                        failed = True
                        continue
                    after = resource.getrusage(resource.RUSAGE_CHILDREN)
                    rate = r["particle_updates_per_s"]
                    if cpuClock:
                        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                        rate = r["particles"] * r["steps"] / cpu
                    key = (i, name)
                    best[key] = max(best.get(key, 0.0), rate)

    head = ["fill", "cells", "build", "updates/s", "cost / snug box"] + (["new/old speed"] if "old" in exes else [])
    body = []
    for i, (path, particles, actual, cells) in enumerate(scenes):
        for name in exes:
            rate = best.get((i, name))
            snug = best.get((0, name))
            if rate is None:
                continue
            row = ["%.3g" % actual, "%d x %d x %d" % tuple(cells), name, "%.3e" % rate,
                   "%.2f" % (snug / rate) if snug else "n/a"]
            if "old" in exes:
                old = best.get((i, "old"))
                row.append("%.2f" % (rate / old) if name == "new" and old else "")
            body.append(row)
    text, md = bench_mpm.render_table(head, body)
    print()
    print(text, end="")
    clock = "updates per CPU second" if cpuClock else "updates per wall second of the step loop"
    print("(%s-%s, %d steps, fastest of %d; %s; %s)" % (args.backend, args.precision, args.steps, args.repeat,
                                                        "OMP_NUM_THREADS=%d" % args.threads if threads else "GPU",
                                                        clock))
    if args.markdown:
        commit = subprocess.run(["git", "-C", bench_mpm.REPO, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        machine = bench_mpm.machine()
        with open(args.markdown, "a") as f:
            f.write("\n### Cost against grid fill, %s (commit %s)\n\n" %
                    (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), commit or "unknown"))
            f.write("Machine: %s. %s-%s, OMP_NUM_THREADS=%d, %d steps, fastest of %d, %s.\n\n"
                    % (machine, args.backend, args.precision, args.threads, args.steps, args.repeat, clock))
            f.write(md)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
