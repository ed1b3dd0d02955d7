#!/usr/bin/env python3
"""Peak memory of a whole driver run with outputs: seeding, stepping, HDF5 snapshots and VTK.

Runs ``mpmsdem-run SCENE --out DIR --steps N`` on bench_mpm.py's dam-break block (8 points per
cell) for each particle count, with one or two copies of the particle state
(``keep_last_good_state``) and with VTK off or in the default binary encoding, and prints the
peak resident size of the process (``ru_maxrss`` of that child) in MB and per particle, that of
the same run continued with ``--restart`` for as many steps again, and the solver's own
``memoryBytes()`` per particle (``--bench`` of the same scene). With
``--baseline-exe`` an older build runs each case in the same command, and the last column is
the new peak over the old one. ``--yade`` adds the same scene run through YADE (MpmEngine with
outputs; its module from ``--yade-pythonpath``, an older one from ``--baseline-yade-pythonpath``).

    python3 scripts/bench/bench_output_memory.py --exe build/mpmsdem-run [--baseline-exe OLD/mpmsdem-run]
        [--sizes 1e6] [--precisions double,float] [--copies 1,2] [--vtk none,binary] [--steps 20]
        [--threads 2] [--markdown FILE]

Uses only the standard library. Exit status 1 when a run fails.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_mpm  # noqa: E402  (the dam-break scene, machine description and table helpers)

YADE_RUN = os.path.join(os.path.dirname(os.path.abspath(__file__)), "yade_output_run.py")


def peak_rss(cmd, env):
    """Exit status and peak resident size [bytes] of one child process."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError("%s failed (exit %d):\n%s" % (" ".join(cmd), proc.returncode, out.decode()[-2000:]))
    return usage.ru_maxrss * 1024


def parse_list(text, allowed, what):
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items or any(i not in allowed for i in items):
        raise argparse.ArgumentTypeError("%s: comma-separated values from %s" % (what, ", ".join(allowed)))
    return items


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default=os.path.join(bench_mpm.REPO, "build", "mpmsdem-run"), help="mpmsdem-run to measure")
    ap.add_argument("--baseline-exe", help="an older mpmsdem-run run on the same cases for the ratio")
    ap.add_argument("--sizes", type=bench_mpm.parse_sizes, default=[1000000], help="particle counts (default 1e6)")
    ap.add_argument("--copies", type=lambda t: [int(c) for c in parse_list(t, ("1", "2"), "--copies")],
                    default=[1, 2], help="copies of the particle state: 1 and/or 2 (default both)")
    ap.add_argument("--vtk", type=lambda t: parse_list(t, ("none", "binary"), "--vtk"), default=["none", "binary"],
                    help="VTK output: none and/or binary (default both)")
    ap.add_argument("--precisions", type=lambda t: parse_list(t, ("double", "float"), "--precisions"),
                    default=["double"], help="double and/or float (default double)")
    ap.add_argument("--steps", type=int, default=20, help="steps per run (default 20; a snapshot at the start and end)")
    ap.add_argument("--threads", type=int, default=2, help="OMP_NUM_THREADS (default 2)")
    ap.add_argument("--yade", action="store_true",
                    help="also the same scene through YADE (MpmEngine with outputs, yade_output_run.py; "
                         "no restart), with the mpmsdem module of --yade-pythonpath and --baseline-yade-pythonpath")
    ap.add_argument("--yade-pythonpath", default=os.path.join(bench_mpm.REPO, "build", "python"),
                    help="PYTHONPATH entry holding the mpmsdem package to measure (default build/python)")
    ap.add_argument("--baseline-yade-pythonpath", help="the same for the older build")
    ap.add_argument("--markdown", help="append the table, the commit, the machine and the command to FILE")
    args = ap.parse_args()
    if args.steps < 1:
        ap.error("--steps must be >= 1")
    if args.threads < 1:
        ap.error("--threads must be >= 1")
    exes = bench_mpm.builds(ap, args.exe, args.baseline_exe)
    env = dict(os.environ, OMP_NUM_THREADS=str(args.threads))
    head = ["particles", "precision", "copies", "vtk", "build", "peak RSS [MB]", "B/particle",
            "restart B/particle", "solver B/particle"]
    if args.baseline_exe:
        head.append("new / old peak")
    body = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
          for precision in args.precisions:
            for copies in args.copies:
                scene, n = bench_mpm.dam_break_scene(size)
                scene["keep_last_good_state"] = copies == 2
                path = os.path.join(tmp, "scene.json")
                solverBytes = None
                for vtk in args.vtk:
                    if vtk == "binary":
                        scene["run"].pop("vtk", None)  # the default: binary VTK with every snapshot
                    else:
                        scene["run"]["vtk"] = "none"
                    with open(path, "w") as f:
                        json.dump(scene, f)
                    if solverBytes is None:
                        solverBytes = bench_mpm.run_one(args.exe, path, "cpu", precision, 2, args.threads,
                                                        None)["bytes_per_particle"]
                    peaks, restarts = {}, {}
                    if args.yade and vtk == "binary":
                        yadeRuns = [("yade new", args.yade_pythonpath)]
                        if args.baseline_yade_pythonpath:
                            yadeRuns.append(("yade old", args.baseline_yade_pythonpath))
                        for name, path_ in yadeRuns:
                            out = os.path.join(tmp, "out")
                            shutil.rmtree(out, ignore_errors=True)
                            yenv = dict(env, PYTHONPATH=os.pathsep.join([path_] + [p for p in sys.path if "yade" in p]))
                            scene["run"]["precision"] = precision
                            with open(path, "w") as f:
                                json.dump(scene, f)
                            peak = peak_rss([sys.executable, YADE_RUN, path, out, str(args.steps)], yenv)
                            print("%d particles, %s, %d copies, %s: peak %.0f MB (%.0f B/particle)"
                                  % (n, precision, copies, name, peak / 1e6, peak / n), flush=True)
                            body.append([str(n), precision, str(copies), "binary", name, "%.0f" % (peak / 1e6),
                                         "%.0f" % (peak / n), "", "%.0f" % solverBytes]
                                        + ([""] if args.baseline_exe else []))
                        scene["run"].pop("precision", None)
                    for name, exe in exes:
                        out = os.path.join(tmp, "out")
                        shutil.rmtree(out, ignore_errors=True)
                        cmd = [exe, path, "--out", out, "--precision", precision]
                        peaks[name] = peak_rss(cmd + ["--steps", str(args.steps)], env)
                        restarts[name] = peak_rss(cmd + ["--steps", str(args.steps), "--restart"], env)
                        print("%d particles, %s, %d copies, vtk %s, %s: peak %.0f MB (%.0f B/particle), restarted "
                              "%.0f MB" % (n, precision, copies, vtk, name, peaks[name] / 1e6, peaks[name] / n,
                                           restarts[name] / 1e6), flush=True)
                    for name, _ in exes:
                        row = [str(n), precision, str(copies), vtk, name, "%.0f" % (peaks[name] / 1e6),
                               "%.0f" % (peaks[name] / n), "%.0f" % (restarts[name] / n), "%.0f" % solverBytes]
                        if args.baseline_exe:
                            row.append("%.2f" % (peaks["new"] / peaks["old"]) if name == "new" else "")
                        body.append(row)
    bench_mpm.report(head, body, "dam-break block, 8 points per cell, %d steps, OMP_NUM_THREADS=%d"
                     % (args.steps, args.threads), args.markdown, "Peak memory of an output run")
    return 0


if __name__ == "__main__":
    bench_mpm.run_main(main, "bench_output_memory")
