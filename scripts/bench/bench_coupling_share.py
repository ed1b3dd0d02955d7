#!/usr/bin/env python3
"""What the MP–block coupling adds to the MPM step on the paper's §3.2 flume, in the C++ driver.

Writes the driver scene of examples/flume_block.py (coarse: dx 0.02 m, 12,000 material points;
``--full``: the paper's dx 0.01 m, 96,000), then runs ``mpmsdem-run SCENE --bench`` for
``--steps`` steps with each given build in turn, ``--repeat`` times, and prints per run the
seconds of the step loop spent in the MPM step and in the MP–block contacts (the SDEM bed is a
block, so every point of the bottom layer is a contact), the ratio coupling / MPM (the project's
goal: at most 0.25 for one block) and, with ``--baseline-exe``, the speed of the new build over
the old one from the same command (interleaved runs, so machine load hits both alike).

    OMP_NUM_THREADS=1 python3 scripts/bench/bench_coupling_share.py --exe build/mpmsdem-run \\
        [--baseline-exe OLD/mpmsdem-run] [--full] [--steps N] [--repeat 2] [--markdown FILE]

Needs YADE's Python (the scene is written by the example script). Exit status 1 when a run fails.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_mpm  # noqa: E402  (machine description and table helpers)

EXAMPLE = os.path.join(bench_mpm.REPO, "examples", "flume_block.py")


def write_scene(path, full):
    cmd = [sys.executable, EXAMPLE, "--driver-scene", path] + (["--full"] if full else [])
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0 or not os.path.exists(path):
        raise RuntimeError("%s failed:\n%s" % (" ".join(cmd), (proc.stdout + proc.stderr)[-2000:]))


def run(exe, scene, steps, threads):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    cmd = [exe, scene, "--bench", "--steps", str(steps)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("{")]
    if proc.returncode != 0 or not lines:
        raise RuntimeError("%s failed (exit %d):\n%s" % (" ".join(cmd), proc.returncode,
                                                        (proc.stdout + proc.stderr)[-2000:]))
    return json.loads(lines[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default=os.path.join(bench_mpm.REPO, "build", "mpmsdem-run"), help="mpmsdem-run to measure")
    ap.add_argument("--baseline-exe", help="an older mpmsdem-run run in the same command for the speed ratio")
    ap.add_argument("--full", action="store_true", help="the paper's resolution (96,000 points) instead of 12,000")
    ap.add_argument("--steps", type=int, default=None,
                    help="steps per run (default: the whole scene, 1.2 s coarse or 2 s full)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per build, interleaved (default 2)")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of the runs (default 1)")
    ap.add_argument("--markdown", help="append the table, the commit, the machine and the command to FILE")
    args = ap.parse_args()
    if args.steps is not None and args.steps < 1:
        ap.error("--steps must be >= 1")
    if args.repeat < 1:
        ap.error("--repeat must be >= 1")
    if args.threads < 1:
        ap.error("--threads must be >= 1")
    exes = bench_mpm.builds(ap, args.exe, args.baseline_exe)
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "flume.json")
        write_scene(scene, args.full)
        with open(scene) as f:
            s = json.load(f)
        steps = args.steps or int(round(s["run"]["duration"] / s["run"]["dt"]))
        results = {name: [] for name, _ in exes}
        for k in range(args.repeat):
            for name, exe in exes:
                r = run(exe, scene, steps, args.threads)
                results[name].append(r)
                st = r["stage_seconds"]
                print("run %d, %s: %.1f s, MPM %.1f s, coupling %.1f s, coupling / MPM %.3f"
                      % (k + 1, name, r["seconds"], st["mpm"], st["coupling"], st["coupling"] / st["mpm"]),
                      flush=True)
    head = ["build", "run", "steps", "step loop [s]", "MPM step [s]", "coupling [s]", "blocks [s]", "coupling / MPM"]
    if args.baseline_exe:
        head.append("new / old speed")
    body = []
    for k in range(args.repeat):
        for name, _ in exes:
            r = results[name][k]
            st = r["stage_seconds"]
            row = [name, str(k + 1), str(r["steps"]), "%.1f" % r["seconds"], "%.1f" % st["mpm"],
                   "%.1f" % st["coupling"], "%.2f" % st["blocks"], "%.3f" % (st["coupling"] / st["mpm"])]
            if args.baseline_exe:
                row.append("%.2f" % (results["old"][k]["seconds"] / r["seconds"]) if name == "new" else "")
            body.append(row)
    label = "full (dx 0.01 m, 96,000 points)" if args.full else "coarse (dx 0.02 m, 12,000 points)"
    bench_mpm.report(head, body, "§3.2 flume, %s, %d steps, OMP_NUM_THREADS=%d" % (label, steps, args.threads),
                     args.markdown, "Coupling share, §3.2 flume " + label)
    return 0


if __name__ == "__main__":
    bench_mpm.run_main(main, "bench_coupling_share")
