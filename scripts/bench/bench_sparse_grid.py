#!/usr/bin/env python3
"""The grid's cost against the domain (issue: a grid that costs what the flow occupies): one
dam-break flow at Δx 1 m in a box around it and in a 1 km x 1 km x 200 m domain, through
mpmsdem-run --bench, each run in its own process. Prints the step loop's time, the solver's
memory (MpmSolver::memoryBytes) and the process's peak resident memory of each, the ratios of
the large domain to the tight box, and what a dense grid of the large domain would hold.

    python3 scripts/bench/bench_sparse_grid.py [--exe build/mpmsdem-run] [--baseline-exe OLD]
                                              [--points 5e5] [--steps 100] [--threads 2]
                                              [--backend cpu|cuda] [--precision double|float]

--baseline-exe runs an older mpmsdem-run on both scenes too (new/old time and memory); a run that
fails (a grid the device cannot hold) is reported as such. Goals: the large domain below 2 GB
and within 1.5 times the tight box's time.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_mpm  # noqa: E402  (the dam-break scene and the machine line)

NODE_BYTES = 8 * 8  # a node record: 8 values in double


def scenes(points, dx):
    tight, n = bench_mpm.dam_break_scene(points, dx)
    large = json.loads(json.dumps(tight))
    margin = 2
    large["grid"]["cells"] = [int(round(1000 / dx)) + 2 * margin, int(round(1000 / dx)) + 2 * margin,
                              int(round(200 / dx)) + 2 * margin]
    large["description"] = "the same dam break in a 1 km x 1 km x 200 m domain"
    return tight, large, n


def run(exe, scene, steps, threads, backend, precision):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(scene, f)
        path = f.name
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.time()
    # one process per run, so that its peak resident memory is its own (ru_maxrss of the children
    # is the largest so far: the runs go smallest first)
    p = subprocess.run([exe, path, "--bench", "--steps", str(steps), "--backend", backend, "--precision", precision],
                       env=env, capture_output=True, text=True)
    wall = time.time() - t0
    os.unlink(path)
    if p.returncode != 0:
        return {"failed": "%s failed (exit %d): %s" % (exe, p.returncode, p.stderr.strip()[-600:])}
    r = json.loads(p.stdout.strip().splitlines()[-1])
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
    r["peak_rss"] = peak if peak > before * 1024 else None
    r["wall"] = wall
    r["solver_bytes"] = r["bytes_per_particle"] * r["particles"]
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default=os.path.join("build", "mpmsdem-run"))
    ap.add_argument("--baseline-exe", default=None, help="an older mpmsdem-run, run on both scenes too")
    ap.add_argument("--points", type=float, default=5e5, help="material points of the flow (default 5e5)")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--dx", type=float, default=1.0, help="grid spacing [m] (default 1)")
    ap.add_argument("--backend", choices=("cpu", "cuda"), default="cpu")
    ap.add_argument("--precision", choices=("double", "float"), default="double")
    a = ap.parse_args(argv)
    tight, large, n = scenes(int(a.points), a.dx)
    dense = NODE_BYTES
    for c in large["grid"]["cells"]:
        dense *= c + 1
    print("machine: %s; %d material points, Δx %g m, %d steps, OMP_NUM_THREADS=%d, %s %s" % (
        bench_mpm.machine(), n, a.dx, a.steps, a.threads, a.backend, a.precision))
    print("tight box %s cells; large domain %s cells (a dense grid of it: %.1f GB of node records in double)" % (
        "x".join(map(str, tight["grid"]["cells"])), "x".join(map(str, large["grid"]["cells"])), dense / 1e9))
    builds = [("new", a.exe)] + ([("old", a.baseline_exe)] if a.baseline_exe else [])
    results = {}
    for name, exe in builds:
        for label, scene in (("tight", tight), ("large", large)):
            results[name, label] = run(exe, scene, a.steps, a.threads, a.backend, a.precision)
    print("| build | domain | step loop [s] | particle-updates/s | solver memory [MB] | peak RSS [MB] |")
    print("|---|---|---:|---:|---:|---:|")
    for (name, label), r in results.items():
        if "failed" in r:
            print("| %s | %s | refused | - | - | - |" % (name, label))
            continue
        print("| %s | %s | %.2f | %.3g | %.0f | %s |" % (
            name, label, r["seconds"], r["particle_updates_per_s"], r["solver_bytes"] / 1e6,
            "%.0f" % (r["peak_rss"] / 1e6) if r["peak_rss"] else "-"))
    for (name, label), r in results.items():
        if "failed" in r:
            print("%s, %s domain: %s" % (name, label, r["failed"]))
    ok = {k: r for k, r in results.items() if "failed" not in r}
    for name, _ in builds:
        if (name, "tight") not in ok or (name, "large") not in ok:
            continue
        t, l = ok[name, "tight"], ok[name, "large"]
        print("%s: large / tight time %.2f (goal <= 1.5), solver memory %.0f MB in the large domain (goal < 2000)" % (
            name, l["seconds"] / t["seconds"], l["solver_bytes"] / 1e6))
    if a.baseline_exe and ("new", "large") in ok and ("old", "large") in ok:
        print("new / old in the large domain: time %.2f, solver memory %.3f" % (
            results["new", "large"]["seconds"] / results["old", "large"]["seconds"],
            results["new", "large"]["solver_bytes"] / results["old", "large"]["solver_bytes"]))


if __name__ == "__main__":
    main()
