#!/usr/bin/env python3
"""MPM CPU throughput against a peer: our C++ solver and a Taichi implementation of the same scheme.

Both run the granular column collapse of examples/scenes/column_collapse.json, scaled to
each requested particle count (the column and the box grow, dx, the material, the walls and
8 points per cell stay), with the same fixed dt and the same number of steps, in double
precision on the same number of CPU threads. The runs are interleaved (ours, peer, ours,
peer, ...) so that a machine shared with other work slows both alike; the best of the repeats
is reported. The peer (scripts/bench/peers/taichi_mpm.py) is written from our C++ scheme.

Before the timings count, the script checks that both solvers computed the same flow: the
front position (largest particle x) and the kinetic energy after the benchmarked steps must
agree (ours from a second, non-benchmark run that prints them). A mismatch is an error.

    scripts/bench/bench_mpm_peers.py                          # 5e3, 1e5, 1e6 particles
    scripts/bench/bench_mpm_peers.py --sizes 5e3 --steps 2000 --threads 2

The peer runs in a virtual environment (.venv-peers/ at the repository root, created with
--peer-python and given the pinned Taichi from PyPI when missing). Both rates are particles x
steps / wall time over the steps after the first two, which are timed apart: the peer's compile
its kernels, ours sort the seeded particles from scratch (mpmsdem-run --bench). Exit status 1
when a run fails or the solvers disagree.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import threading

from bench_mpm import machine, render_table  # same folder: shared with the other benchmarks

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PEER = os.path.join(REPO, "scripts", "bench", "peers", "taichi_mpm.py")
BASE_SCENE = os.path.join(REPO, "examples", "scenes", "column_collapse.json")
WALL_LAYER = 2  # kWallLayer of the solver: wall cells on each face of the grid box


def parse_sizes(text):
    try:
        sizes = [int(float(s)) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("sizes must be comma-separated numbers, e.g. 5e3,1e5")
    if not sizes or min(sizes) < 100:
        raise argparse.ArgumentTypeError("each size must be >= 100 particles")
    return sizes


def parse_steps(text):
    try:
        steps = [int(float(s)) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("steps: one integer, or one per size, e.g. 2000,100,20")
    if not steps or min(steps) < 2:
        raise argparse.ArgumentTypeError("each step count must be >= 2")
    return steps


def column_scene(particles, dt):
    """The base column-collapse scene scaled to about `particles` points; returns (scene, n)."""
    with open(BASE_SCENE) as f:
        s = json.load(f)
    g = s["grid"]
    dx = g["dx"]
    (box,) = s["particles"]
    ppc = box.get("ppc", 8)
    ppc_n = ppc if isinstance(ppc, int) else ppc[0] * ppc[1] * ppc[2]
    col = [round((box["hi"][d] - box["lo"][d]) / dx) for d in range(3)]
    region = [g["cells"][d] - 2 * WALL_LAYER for d in range(3)]  # cells open to material
    f = (particles / (ppc_n * col[0] * col[1] * col[2])) ** (1.0 / 3.0)
    new_col = [max(1, round(c * f)) for c in col]
    new_region = [max(nc, round(nc * r / c)) for nc, r, c in zip(new_col, region, col)]
    g["cells"] = [r + 2 * WALL_LAYER for r in new_region]
    box["hi"] = [box["lo"][d] + new_col[d] * dx for d in range(3)]
    s["description"] = "column collapse scaled for bench_mpm_peers: column %d x %d x %d cells" % tuple(new_col)
    s["run"].update({"dt": dt, "vtk": "none", "backend": "cpu", "precision": "double",
                     "output_every": 1e9, "series_every": 1e9})
    return s, ppc_n * new_col[0] * new_col[1] * new_col[2]


def run_measured(cmd, env, timeout):
    """Run cmd; return (exit status, stdout, stderr, peak RSS in bytes of the child)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, env=env)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return proc.returncode, out.read(), err.read(), usage.ru_maxrss * 1024


def last_json(text):
    lines = [l for l in text.splitlines() if l.startswith("{")]
    return json.loads(lines[-1]) if lines else None


def run_ours(exe, scene, steps, threads, timeout):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    rc, out, err, rss = run_measured([exe, scene, "--bench", "--steps", str(steps)], env, timeout)
    r = last_json(out)
    if rc != 0 or r is None:
        raise RuntimeError("mpmsdem-run --bench failed (exit %d):\n%s" % (rc, err[-2000:]))
    r["max_rss_bytes"] = rss
    return r


def check_ours(exe, scene, steps, threads, outdir, timeout):
    """Front position and kinetic energy of our solver after `steps` steps (a run with outputs)."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    rc, out, err, _ = run_measured([exe, scene, "--steps", str(steps), "--out", outdir], env, timeout)
    if rc == 2 and "--bench only" in err:
        return None  # a driver built without HDF5 prints no diagnostics
    if rc != 0:
        raise RuntimeError("mpmsdem-run failed (exit %d):\n%s" % (rc, err[-2000:]))
    last = [l for l in out.splitlines() if l.startswith("[100.0%]")]
    if not last:
        raise RuntimeError("mpmsdem-run printed no final progress line:\n%s" % out[-2000:])
    fields = dict(tok.split("=", 1) for tok in last[-1].split() if "=" in tok)
    return {"front_x": float(fields["front"]), "kinetic_energy": float(fields["KE"])}


def run_peer(python, scene, steps, threads, timeout):
    rc, out, err, rss = run_measured([python, PEER, scene, "--steps", str(steps), "--threads", str(threads)],
                                     dict(os.environ), timeout)
    r = last_json(out)
    if rc != 0 or r is None:
        raise RuntimeError("taichi peer failed (exit %d):\n%s" % (rc, err[-2000:]))
    r["max_rss_bytes"] = rss
    return r


def ensure_peer_env(venv, python, spec):
    """Path of the venv's interpreter, with Taichi importable (installed from PyPI when missing)."""
    py = os.path.join(venv, "bin", "python")
    if not os.path.exists(py):
        print("creating %s with %s ..." % (venv, python), flush=True)
        subprocess.run([python, "-m", "venv", venv], check=True)
    if subprocess.run([py, "-c", "import taichi"], capture_output=True).returncode != 0:
        print("installing %s into %s ..." % (spec, venv), flush=True)
        subprocess.run([py, "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True)
        subprocess.run([py, "-m", "pip", "install", "-q", spec], check=True)
    return py


def table(rows):
    head = ["particles", "steps", "ours upd/s", "peer upd/s", "ours/peer", "ours B/p", "ours RSS MB",
            "peer B/p", "peer RSS MB", "front ours", "front peer", "KE rel diff"]
    body = []
    for r in rows:
        o, p, c = r["ours"], r["peer"], r.get("check")
        body.append([
            str(o["particles"]), str(o["steps"]),
            "%.3e" % o["particle_updates_per_s"], "%.3e" % p["particle_updates_per_s"],
            "%.2f" % (o["particle_updates_per_s"] / p["particle_updates_per_s"]),
            "%.0f" % o["bytes_per_particle"], "%.0f" % (o["max_rss_bytes"] / 2**20),
            "%.0f" % p["bytes_per_particle"], "%.0f" % (p["max_rss_bytes"] / 2**20),
            "%.6f" % c["front_x"] if c else "n/a", "%.6f" % p["front_x"],
            ("%.1e" % (abs(c["kinetic_energy"] - p["kinetic_energy"]) / max(abs(c["kinetic_energy"]), 1e-300)))
            if c else "n/a"])
    return render_table(head, body, mdRule="---:|")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build", help="build folder holding mpmsdem-run (default: build)")
    ap.add_argument("--exe", help="path of mpmsdem-run (overrides --build)")
    ap.add_argument("--sizes", type=parse_sizes, default=parse_sizes("5e3,1e5,1e6"),
                    help="particle counts, about (default 5e3,1e5,1e6)")
    ap.add_argument("--steps", type=parse_steps,
                    help="steps per run: one count, or one per size (default: 1e7 particle updates per run, "
                         "20 to 2000 steps)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                    help="CPU threads for both solvers (default: all cores)")
    ap.add_argument("--dt", type=float, default=8e-5,
                    help="fixed time step [s] (default 8e-5, below the stable step of the scene's dx)")
    ap.add_argument("--repeats", type=int, default=2, help="interleaved timed runs per solver and size (default 2)")
    ap.add_argument("--no-check", action="store_true", help="skip the agreement check (our run with outputs)")
    ap.add_argument("--front-tol", type=float, default=1e-3,
                    help="allowed front difference, in cells dx (default 1e-3)")
    ap.add_argument("--ke-tol", type=float, default=1e-3, help="allowed relative kinetic-energy difference (default 1e-3)")
    ap.add_argument("--venv", default=os.path.join(REPO, ".venv-peers"), help="the peer's virtual environment")
    ap.add_argument("--peer-python", default=sys.executable,
                    help="interpreter that creates the venv (Taichi 1.7 has wheels for Python 3.8-3.12)")
    ap.add_argument("--taichi", default="taichi==1.7.4", help="pip requirement for the peer (default taichi==1.7.4)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds allowed per run (default 1800)")
    ap.add_argument("--markdown", help="write the table as markdown to this file")
    ap.add_argument("--json", help="write all results as JSON to this file")
    args = ap.parse_args()
    if args.threads < 1 or args.repeats < 1:
        ap.error("--threads and --repeats must be >= 1")
    if args.steps and len(args.steps) not in (1, len(args.sizes)):
        ap.error("--steps: give one count or one per size")

    exe = args.exe or os.path.join(args.build if os.path.isabs(args.build) else os.path.join(REPO, args.build),
                                   "mpmsdem-run")
    if not os.access(exe, os.X_OK):
        sys.exit("bench_mpm_peers: no executable mpmsdem-run at %s (build it, or pass --build/--exe)" % exe)
    py = ensure_peer_env(args.venv, args.peer_python, args.taichi)

    load_before = os.getloadavg()[0]
    rows, failed = [], False
    with tempfile.TemporaryDirectory(prefix="bench_mpm_peers_") as tmp:
        for i, size in enumerate(args.sizes):
            scene, n = column_scene(size, args.dt)
            path = os.path.join(tmp, "column_%d.json" % n)
            with open(path, "w") as f:
                json.dump(scene, f)
            if args.steps:
                steps = args.steps[i] if len(args.steps) > 1 else args.steps[0]
            else:
                steps = int(min(2000, max(20, math.ceil(1e7 / n))))
            print("%d particles (grid %s cells), %d steps, dt %g s, %d threads ..."
                  % (n, "x".join(map(str, scene["grid"]["cells"])), steps, args.dt, args.threads), flush=True)
            try:
                ours, peer = [], []
                for _ in range(args.repeats):
                    ours.append(run_ours(exe, path, steps, args.threads, args.timeout))
                    peer.append(run_peer(py, path, steps, args.threads, args.timeout))
                    print("  ours %.3e upd/s, peer %.3e upd/s (peer compile %.1f s)"
                          % (ours[-1]["particle_updates_per_s"], peer[-1]["particle_updates_per_s"],
                             peer[-1]["warmup_seconds"]), flush=True)
                row = {"size": size,
                       "ours": max(ours, key=lambda r: r["particle_updates_per_s"]),
                       "peer": max(peer, key=lambda r: r["particle_updates_per_s"]),
                       "all_ours": ours, "all_peer": peer}
                if not args.no_check:
                    c = check_ours(exe, path, steps, args.threads, os.path.join(tmp, "out_%d" % n), args.timeout)
                    row["check"] = c
                    if c is None:
                        print("  agreement not checked: this mpmsdem-run has no HDF5 outputs", flush=True)
                    else:
                        # ours is printed with 5 significant digits: allow for that as well
                        dfront = abs(c["front_x"] - row["peer"]["front_x"])
                        dke = abs(c["kinetic_energy"] - row["peer"]["kinetic_energy"]) / abs(c["kinetic_energy"])
                        ok = (dfront <= args.front_tol * scene["grid"]["dx"] + 5e-6 * abs(c["front_x"])
                              and dke <= args.ke_tol + 5e-5)
                        print("  agreement: front %.6f m (ours) vs %.6f m (peer), KE rel diff %.1e: %s"
                              % (c["front_x"], row["peer"]["front_x"], dke, "ok" if ok else "MISMATCH"),
                              flush=True)
                        if not ok:
                            failed = True
                rows.append(row)
            except (RuntimeError, subprocess.CalledProcessError) as e:
                print("bench_mpm_peers: %s" % e, file=sys.stderr)
                failed = True

    load_after = os.getloadavg()[0]
    # Other work on the machine slows OpenMP's barriers more than it slows the peer's kernels:
    # say how busy the machine was.
    load = "1-min load average %.1f before, %.1f after" % (load_before, load_after)
    text, md = table(rows) if rows else ("", "")
    peer_name = rows[0]["peer"]["solver"] if rows else "taichi"
    print()
    print(text, end="")
    print("ours: mpmsdem-run --bench (cpu-double, OpenMP); peer: %s; %d threads each; best of %d "
          "interleaved runs; dt %g s; machine: %s; %s"
          % (peer_name, args.threads, args.repeats, args.dt, machine(), load))
    print("B/p: ours memoryBytes()/particles (both particle buffers, grid, bins); peer: its fields' bytes "
          "/ particles. RSS: peak resident size of the whole process (the peer's includes Python, Taichi and LLVM).")
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(md)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"machine": machine(), "load": load, "threads": args.threads, "dt": args.dt, "rows": rows},
                      f, indent=1)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
