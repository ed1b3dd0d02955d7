#!/usr/bin/env python3
"""MPM throughput benchmark: CPU (OpenMP) and CUDA, each in double and float.

Runs `mpmsdem-run --bench` on generated dam-break scenes (a block of glass beads, 8 material
points per cell, twice as long as high and as wide as high, released in a box four block
lengths long) at several particle counts and prints particle-updates per second
(particles x steps / wall time of the step loop), bytes per particle (solver memory /
particles), the float/double ratio of each backend and the GPU/CPU ratio (against
cpu-double) at the same size.

    scripts/bench/bench_mpm.py                       # CPU 1e5, 1e6; CUDA 1e5..1e7 if a GPU is found
    scripts/bench/bench_mpm.py --threads 1 --cpu-precisions double,float
    scripts/bench/bench_mpm.py --cuda --markdown docs/benchmarks.md
    scripts/bench/bench_mpm.py --cpu-sizes 1e5,1e6,1e7 --threads 2
    scripts/bench/bench_mpm.py --no-cuda --cpu-copies 2,1   # keep_last_good_state on and off

--cpu-copies 2,1 runs each CPU case with the solver's second copy of the particles (the
default, "keep_last_good_state": true) and with one copy, and prints the speed ratio
one/two copies.

--baseline-exe OLD/mpmsdem-run runs each CUDA case also with that older build, right after the
new one, and prints the speed ratio new/old (build "old" rows; the other ratios are the new
build's).

Uses only the standard library. Exit status 1 when a run fails.
"""
import argparse
import datetime
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def parse_sizes(text):
    """'1e5,1e6' -> [100000, 1000000]"""
    try:
        sizes = [int(float(s)) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("sizes must be comma-separated numbers, e.g. 1e5,1e6")
    if not sizes or min(sizes) < 64:
        raise argparse.ArgumentTypeError("each size must be >= 64 particles")
    return sizes


def dam_break_scene(particles, dx=0.01):
    """Scene dict for a dam-break block of about `particles` material points (8 per cell)."""
    cells = particles / 8.0
    h = max(2, int(round((cells / 2.0) ** (1.0 / 3.0))))  # block: 2h x h x h cells
    block = (2 * h, h, h)
    region = (4 * block[0], block[1], block[2] + 2)  # cells open to material (inside the walls)
    margin = 2  # wall layers of the solver (kWallLayer)
    return {
        "description": "benchmark dam break, %d x %d x %d cells x 8 ppc" % block,
        "grid": {"dx": dx, "cells": [r + 2 * margin for r in region],
                 "origin": [-margin * dx] * 3},
        "gravity": [0, 0, -9.81],
        "walls": {"-z": 0.21},
        "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3,
                     "mu_s": 0.24, "mu_2": 0.65},
        "particles": [{"lo": [0, 0, 0], "hi": [b * dx for b in block], "ppc": 8}],
        "run": {"duration": 10.0, "dt": "auto", "vtk": "none"},
    }, 8 * block[0] * block[1] * block[2]


def machine():
    """'<CPU model>, <n> cores (nproc), <arch>' for the benchmark records."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return "%s, %d cores (nproc), %s" % (model, os.cpu_count() or 0, platform.machine())


def find_exe(args):
    if args.exe:
        return args.exe
    exe = os.path.join(args.build, "mpmsdem-run")
    if not os.path.isabs(exe):
        exe = os.path.join(REPO, exe)
    return exe


def gpu_present():
    if not shutil.which("nvidia-smi"):
        return False
    try:
        out = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return out.returncode == 0 and "GPU" in out.stdout


def gpu_name():
    try:
        out = subprocess.run(["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=30)
        return out.stdout.strip().splitlines()[0] if out.returncode == 0 and out.stdout.strip() else ""
    except (OSError, subprocess.TimeoutExpired, IndexError):
        return ""


def copy_bandwidth_cpu(megabytes=512, repeats=5):
    """This machine's memory bandwidth as one thread's copy of a large buffer (a memcpy) moves it:
    bytes read plus written per second, the best of `repeats`."""
    src = bytearray(b"\x01") * (megabytes * 1024 * 1024)
    dst = bytearray(len(src))
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        dst[:] = src
        best = min(best, time.perf_counter() - t0)
    return 2 * len(src) / best


def copy_bandwidth_gpu(megabytes=2048, repeats=10):
    """The GPU's memory bandwidth as a device-to-device copy moves it (bytes read plus written per
    second, CuPy with CUDA events), or None where CuPy is missing."""
    try:
        import cupy as cp
    except ImportError:
        return None
    n = megabytes * 1024 * 1024 // 8
    src, dst = cp.ones(n), cp.empty(n)
    start, end = cp.cuda.Event(), cp.cuda.Event()
    cp.copyto(dst, src)
    start.record()
    for _ in range(repeats):
        cp.copyto(dst, src)
    end.record()
    end.synchronize()
    seconds = cp.cuda.get_elapsed_time(start, end) / 1e3 / repeats
    return 2 * src.nbytes / seconds


def parse_copies(text):
    """'2,1' -> [2, 1]"""
    try:
        copies = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        copies = []
    if not copies or any(c not in (1, 2) for c in copies):
        raise argparse.ArgumentTypeError("copies must be 2 and/or 1, comma-separated")
    return copies


def run_one(exe, scene_path, backend, precision, steps, threads, timeout):
    env = dict(os.environ)
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
    cmd = [exe, scene_path, "--bench", "--backend", backend, "--precision", precision,
           "--steps", str(steps)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError("%s failed (exit %d):\n%s" % (" ".join(cmd), proc.returncode,
                                                        proc.stderr.strip()[-2000:]))
    lines = [l for l in proc.stdout.splitlines() if l.startswith("{")]
    if not lines:
        raise RuntimeError("%s printed no JSON result:\n%s" % (" ".join(cmd), proc.stdout[-2000:]))
    return json.loads(lines[-1])


def parse_precisions(text):
    """'double,float' -> ['double', 'float']"""
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names or any(n not in ("double", "float") for n in names):
        raise argparse.ArgumentTypeError("precisions must be double and/or float, comma-separated")
    return names


def steps_for(particles, target_updates, min_steps, max_steps):
    return int(min(max_steps, max(min_steps, math.ceil(target_updates / particles))))


def format_table(rows):
    head = ["size", "build", "backend", "precision", "copies", "particles", "steps", "seconds",
            "updates/s", "bytes/particle", "state GB/s", "of copy", "float/double", "1/2 copies", "GPU/CPU",
            "new/old"]
    body = []
    for r in rows:
        body.append([
            "%.0e" % r["size"], r["build"], r["backend"], r["precision"], str(r["copies"]), str(r["particles"]),
            str(r["steps"]),
            "%.3g" % r["seconds"], "%.3e" % r["particle_updates_per_s"],
            "%.0f" % r["bytes_per_particle"],
            "%.1f" % (r["state_bytes_per_s"] / 1e9),
            ("%.0f %%" % (100 * r["of_copy"])) if r.get("of_copy") is not None else "",
            ("%.2f" % r["float_ratio"]) if r.get("float_ratio") is not None else "",
            ("%.2f" % r["copies_ratio"]) if r.get("copies_ratio") is not None else "",
            ("%.1f" % r["ratio"]) if r.get("ratio") is not None else "n/a",
            ("%.2f" % r["new_old"]) if r.get("new_old") is not None else ""])
    return render_table(head, body)


def append_markdown(path, title, settings, table):
    """Append `table` (markdown) to the file at `path` under a heading with `title`, the date and
    the commit, then a line with the machine, `settings` and the command that made it."""
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    with open(path, "a") as f:
        f.write("\n### %s, %s (commit %s)\n\n" % (title, datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
                                                    commit or "unknown"))
        f.write("Machine: %s. %s. Command: `%s`\n\n" % (machine(), settings, " ".join(sys.argv)))
        f.write(table)


def report(head, body, caption, markdown=None, title=None):
    """Print the table (header, rows of strings) and its caption in parentheses; with
    `markdown` (a path), also append it there under `title` (append_markdown)."""
    text, md = render_table(head, body)
    print()
    print(text, end="")
    print("(%s)" % caption)
    if markdown:
        append_markdown(markdown, title, caption, md)


def builds(ap, exe, baselineExe):
    """[("new", exe)], and ("old", baselineExe) when one is given, for a benchmark that compares
    two builds of mpmsdem-run; an error of the parser `ap` names one that is not an executable."""
    exes = [("new", exe)] + ([("old", baselineExe)] if baselineExe else [])
    for name, path in exes:
        if not os.access(path, os.X_OK):
            ap.error("%s build: %s is not an executable mpmsdem-run" % (name, path))
    return exes


def run_main(main, name):
    """Exit with main()'s status; a RuntimeError (a run that failed) is printed as 'name:
    message' and exits with status 1."""
    try:
        sys.exit(main())
    except RuntimeError as e:
        print("%s: %s" % (name, e), file=sys.stderr)
        sys.exit(1)


def render_table(head, body, mdRule="---|"):
    """(aligned text, markdown) of a table given its header and rows of strings."""
    widths = [max(len(h), *(len(b[i]) for b in body)) if body else len(h) for i, h in enumerate(head)]
    text = "  ".join(h.rjust(w) for h, w in zip(head, widths)) + "\n"
    for b in body:
        text += "  ".join(c.rjust(w) for c, w in zip(b, widths)) + "\n"
    md = "| " + " | ".join(head) + " |\n|" + mdRule * len(head) + "\n"
    for b in body:
        md += "| " + " | ".join(b) + " |\n"
    return text, md


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build", help="build folder holding mpmsdem-run (default: build)")
    ap.add_argument("--exe", help="path of mpmsdem-run (overrides --build)")
    ap.add_argument("--sizes", type=parse_sizes, default=parse_sizes("1e5,1e6,1e7"),
                    help="particle counts for CUDA runs (default 1e5,1e6,1e7)")
    ap.add_argument("--cpu-sizes", type=parse_sizes, default=parse_sizes("1e5,1e6"),
                    help="particle counts for CPU runs (default 1e5,1e6; add 1e7 for the full set)")
    gpu = ap.add_mutually_exclusive_group()
    gpu.add_argument("--cuda", action="store_true", help="run the CUDA backend (default: when nvidia-smi finds a GPU)")
    gpu.add_argument("--no-cuda", action="store_true", help="never run the CUDA backend")
    ap.add_argument("--no-cpu", action="store_true", help="skip the CPU runs (no GPU/CPU ratio then)")
    ap.add_argument("--cpu-precisions", type=parse_precisions, default=parse_precisions("double,float"),
                    help="precisions of the CPU runs (default double,float; the GPU/CPU ratio needs double)")
    ap.add_argument("--cpu-copies", type=parse_copies, default=parse_copies("2"),
                    help="copies of the particle state in CPU runs: 2 (keep_last_good_state, the default) "
                         "and/or 1 (default 2)")
    ap.add_argument("--threads", type=int, default=2, help="OMP_NUM_THREADS for CPU runs (default 2)")
    ap.add_argument("--cpu-updates", type=float, default=3e7,
                    help="particle updates per CPU run; steps = this / particles (default 3e7)")
    ap.add_argument("--gpu-updates", type=float, default=2e9,
                    help="particle updates per CUDA run (default 2e9)")
    ap.add_argument("--min-steps", type=int, default=20, help="fewest steps per run (default 20)")
    ap.add_argument("--max-steps", type=int, default=2000, help="most steps per run (default 2000)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds allowed per run (default 1800)")
    ap.add_argument("--markdown", help="append the results as a markdown table to this file")
    ap.add_argument("--json", help="write all results as a JSON list to this file")
    ap.add_argument("--baseline-exe", help="an older mpmsdem-run: each CUDA case runs with it too (new/old column)")
    args = ap.parse_args()
    if args.threads < 1:
        ap.error("--threads must be >= 1")
    if args.min_steps < 1 or args.max_steps < args.min_steps:
        ap.error("need 1 <= --min-steps <= --max-steps")

    exe = find_exe(args)
    if not os.access(exe, os.X_OK):
        sys.exit("bench_mpm: no executable mpmsdem-run at %s (build it, or pass --build/--exe)" % exe)
    exes = dict(builds(ap, exe, args.baseline_exe))
    use_cuda = args.cuda or (not args.no_cuda and gpu_present())

    plan = []  # (size, backend, precision, copies, build)
    if not args.no_cpu:
        plan += [(n, "cpu", p, c, "new") for n in args.cpu_sizes for p in args.cpu_precisions for c in args.cpu_copies]
    if use_cuda:
        for n in args.sizes:
            for p in ("float", "double"):
                plan += [(n, "cuda", p, 2, b) for b in exes]
    if not plan:
        sys.exit("bench_mpm: nothing to run (no CPU runs and no GPU)")

    rows = []
    failed = False
    with tempfile.TemporaryDirectory(prefix="bench_mpm_") as tmp:
        for size, backend, precision, copies, build in plan:
            scene, particles = dam_break_scene(size)
            scene["keep_last_good_state"] = copies == 2
            path = os.path.join(tmp, "dam_break_%d_%d.json" % (size, copies))
            with open(path, "w") as f:
                json.dump(scene, f)
            if backend == "cpu":
                steps = steps_for(particles, args.cpu_updates, args.min_steps, args.max_steps)
            else:
                steps = steps_for(particles, args.gpu_updates, args.min_steps, args.max_steps)
            print("running %s-%s, %d particles, %d steps, %d cop%s, %s build ..."
                  % (backend, precision, particles, steps, copies, "y" if copies == 1 else "ies", build), flush=True)
            try:
                r = run_one(exes[build], path, backend, precision, steps,
                            args.threads if backend == "cpu" else None, args.timeout)
            except (RuntimeError, subprocess.TimeoutExpired) as e:
                print("bench_mpm: %s" % e, file=sys.stderr)
                failed = True
                continue
            r["size"] = size
            r["copies"] = copies
            r["build"] = build
            rows.append(r)

    old = {(r["size"], r["backend"], r["precision"]): r["particle_updates_per_s"] for r in rows if r["build"] == "old"}
    for r in rows:
        base = old.get((r["size"], r["backend"], r["precision"]))
        r["new_old"] = r["particle_updates_per_s"] / base if r["build"] == "new" and base else None
    rows_old = [r for r in rows if r["build"] == "old"]
    rows = [r for r in rows if r["build"] == "new"]
    rate = {(r["size"], r["backend"], r["precision"], r["copies"]): r["particle_updates_per_s"] for r in rows}
    for r in rows:
        double = rate.get((r["size"], r["backend"], "double", r["copies"]))
        r["float_ratio"] = r["particle_updates_per_s"] / double if r["precision"] == "float" and double else None
        two = rate.get((r["size"], r["backend"], r["precision"], 2))
        r["copies_ratio"] = r["particle_updates_per_s"] / two if r["copies"] == 1 and two else None
        cpu = rate.get((r["size"], "cpu", "double", 2))
        r["ratio"] = r["particle_updates_per_s"] / cpu if r["backend"] == "cuda" and cpu else None
    rows += rows_old
    # What a step moves at least: the solver's bytes per particle, its state read from one copy
    # and written to the other once a step (the grid and the stencils' re-reads not counted),
    # against the copy bandwidth of the memory that holds it.
    bandwidth = {"cpu": copy_bandwidth_cpu() if any(r["backend"] == "cpu" for r in rows) else None,
                 "cuda": copy_bandwidth_gpu() if any(r["backend"] == "cuda" for r in rows) else None}
    for r in rows:
        r["state_bytes_per_s"] = r["particle_updates_per_s"] * r["bytes_per_particle"]
        bw = bandwidth[r["backend"]]
        r["of_copy"] = r["state_bytes_per_s"] / bw if bw else None
    text, md = format_table(rows)
    print()
    print(text, end="")
    print("(CPU runs: OMP_NUM_THREADS=%d; float/double: against the same backend and copies in double; "
          "1/2 copies: one copy of the particles against two; GPU/CPU: against cpu-double at the same size; "
          "new/old: against the baseline build's run of the same case; state GB/s: updates/s times the "
          "solver's bytes per particle, a lower bound of a step's memory traffic; of copy: that against the "
          "memory's copy bandwidth, read plus written: %s)" % (args.threads, ", ".join(
              "%s %.1f GB/s (%s)" % (k, v / 1e9, "a one-thread memcpy" if k == "cpu" else "device-to-device copy")
              for k, v in bandwidth.items() if v) or "not measured"))

    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    if args.markdown:
        try:
            commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                                    capture_output=True, text=True).stdout.strip()
        except OSError:
            commit = ""
        machine_text = machine()
        if use_cuda:
            machine_text += ", GPU: %s" % (gpu_name() or "unknown")
        os.makedirs(os.path.dirname(os.path.abspath(args.markdown)), exist_ok=True)
        with open(args.markdown, "a") as f:
            f.write("\n### MPM throughput, %s (commit %s)\n\n" %
                    (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), commit or "unknown"))
            f.write("Machine: %s. CPU runs with OMP_NUM_THREADS=%d. Dam-break block, 8 MPs/cell, "
                    "dt auto. updates/s = particles x steps / wall time of the step loop.\n\n"
                    % (machine_text, args.threads))
            f.write(md)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
