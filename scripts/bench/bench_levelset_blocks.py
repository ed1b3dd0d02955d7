#!/usr/bin/env python3
"""Cost of the coupled flume with N free blocks as YADE LevelSet bodies against the same blocks
as SDEM sphero-boxes (paper §4.2, Fig 13 style), in one command.

The §3.3 flume (examples/liu2018_blocks.py: horizontal, 0.6 × 0.2 m, column 0.1 × 0.2 m at the
upstream end, Table 2's flow, flow–block friction 0.13) with N free wooden cubes (20 mm, 500
kg/m³, friction 0.60, barrier stiffness 1e4 N/m) in rows of five across the flume, 50 mm apart
along it, the first row's upstream faces at x = 0.2 m: the first 30 on the bed (six rows), the next
ones stacked on them in layers of 30, up to four high (N ≤ 120; each cube of a layer dropped from
0.5 mm above the one under it, at rest long before the front arrives). SDEM: sweep radius 1 mm
(h/20). LevelSet: grid spacing ``--ls-spacing`` (2 mm), ``--ls-nodes`` boundary nodes (602),
YADE's contacts with k_n ``--ls-kn`` (1e4 N/m, Flume's ``levelSetContact`` default). Each case runs
``--duration`` seconds of the coupled scene (the flow reaches the first row at about 0.18 s)
with the example's step control (``dtAuto`` 0.5); prints wall time, steps, wall time per step
and per simulated second, the ratios LevelSet / SDEM at each N, and the fastest block of each
case (how hard the front throws them: the two kinds do not move alike). The cases run one after the
other in this process; on a shared machine their ratio is what to read, not the absolute times.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/bench/bench_levelset_blocks.py [--n 1,3,10,30,100]
        [--dx 0.01] [--ppc 1] [--duration 0.3] [--ls-spacing 0.002] [--ls-nodes 602] [--ls-kn 1e4]
        [--json PATH]

docs/benchmarks.md quotes its output.
"""
import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HALF = (0.01, 0.01, 0.01)
ROW, ACROSS, X0, PITCH = 5, (0.03, 0.065, 0.1, 0.135, 0.17), 0.2, 0.05
ROWS, LAYERS, LAYER_GAP = 6, 4, 5e-4  # rows along the flume, layers stacked, drop onto the layer below [m]
GRANULAR = {"density": 1300.0, "young_modulus": 5e4, "poisson_ratio": 0.40,
            "mu_s": math.tan(math.radians(22.0)), "mu_2": 0.60}


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", default="1,3,10,30,100", help="numbers of blocks, comma-separated, 1 to %d" % (
        ROW * ROWS * LAYERS))
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing [m] > 0 (0.01)")
    ap.add_argument("--ppc", type=int, default=1, help="material points per cell (1)")
    ap.add_argument("--duration", type=float, default=0.3, help="coupled run per case [s] > 0 (0.3)")
    ap.add_argument("--ls-spacing", type=float, default=0.002, help="level-set grid spacing [m] > 0 (0.002)")
    ap.add_argument("--ls-nodes", type=int, default=602, help="boundary nodes per LevelSet block >= 8 (602)")
    ap.add_argument("--ls-kn", type=float, default=1e4, help="YADE's k_n of the LevelSet cubes [N/m] > 0 (1e4)")
    ap.add_argument("--json", default=None, help="also write the rows to this file")
    a = ap.parse_args(argv)
    try:
        a.n = [int(k) for k in a.n.split(",")]
    except ValueError:
        ap.error("--n %r: must be comma-separated integers" % a.n)
    if not all(1 <= k <= ROW * ROWS * LAYERS for k in a.n):
        ap.error("--n %r: each must be in 1..%d (%d rows of %d, %d layers)" % (a.n, ROW * ROWS * LAYERS, ROWS, ROW,
                                                                              LAYERS))
    if not (a.dx > 0 and a.duration > 0 and a.ls_spacing > 0 and a.ls_kn > 0 and a.ls_nodes >= 8):
        ap.error("--dx, --duration, --ls-spacing, --ls-kn must be > 0 and --ls-nodes >= 8")
    return a


def blocks(n, levelSet):
    from mpmsdem.flume import Block
    out = []
    for k in range(n):
        layer, k = divmod(k, ROW * ROWS)
        row, col = divmod(k, ROW)
        out.append(Block(half=HALF, x=X0 + PITCH * row, y=ACROSS[col], z=layer * (2 * HALF[2] + LAYER_GAP),
                         density=500.0, friction=0.60, flowFriction=0.13, barrierStiffness=1e4, levelSet=levelSet))
    return out


def case(a, n, kind):
    import mpmsdem
    from mpmsdem.flume import Flume
    from yade import O
    ls = {"spacing": a.ls_spacing, "nSurfNodes": a.ls_nodes} if kind == "levelset" else None
    s = Flume(inclineDeg=0.0, length=0.6, width=0.2, columnLength=0.1, columnHeight=0.2, dx=a.dx, ppc=a.ppc,
              granular=GRANULAR, basalFriction=0.13, blocks=blocks(n, ls), verbose=False,
              levelSetContact={"kn": a.ls_kn, "ks": a.ls_kn / 2.6})
    O.dt = min(O.dt, 4e-5)
    s.coupled.dtAuto = 0.5
    t0 = time.time()
    fastest = (0.0, None, None)  # the fastest block's speed [m/s], when [s], its velocity
    while O.time < a.duration - 1e-12:
        mpmsdem.run(10, s.coupled)
        for i in s.blockIds:
            v = O.bodies[i].state.vel
            if v.norm() > fastest[0]:
                fastest = (v.norm(), O.time, tuple(v))
    wall = time.time() - t0
    moved = max(abs(O.bodies[i].state.pos[0] - x0) for i, x0 in zip(s.blockIds, s.x0))
    return {"n": n, "kind": kind, "steps": O.iter, "wall": wall, "ms_per_step": 1e3 * wall / O.iter,
            "wall_per_sim_second": wall / O.time, "largest_travel": moved, "points": s.mpm.numParticles,
            "fastest": fastest}


def main(argv):
    a = parse(argv)
    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    print("commit %s; %s, %d cores; OMP_NUM_THREADS=%s; dx %g m, %d per cell, %g s per case"
          % (commit, platform.machine(), os.cpu_count() or 0, os.environ.get("OMP_NUM_THREADS", "unset"), a.dx,
             a.ppc, a.duration))
    rows = []
    print("| N | SDEM steps | SDEM ms/step | LevelSet steps | LevelSet ms/step | LS/SDEM per step | LS/SDEM per "
          "simulated s | largest travel SDEM / LS [m] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---|")
    for n in a.n:
        sd, ls = case(a, n, "sdem"), case(a, n, "levelset")
        rows += [sd, ls]
        print("| %d | %d | %.2f | %d | %.2f | %.2f | %.2f | %.3f / %.3f |" % (
            n, sd["steps"], sd["ms_per_step"], ls["steps"], ls["ms_per_step"], ls["ms_per_step"] / sd["ms_per_step"],
            ls["wall_per_sim_second"] / sd["wall_per_sim_second"], sd["largest_travel"], ls["largest_travel"]),
            flush=True)
    for r in rows:
        print("%s, N = %d: fastest block %.2f m/s at %.3f s, velocity (%.2f, %.2f, %.2f) m/s (sampled every 10 steps)"
              % ((r["kind"], r["n"], r["fastest"][0], r["fastest"][1]) + r["fastest"][2]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"commit": commit, "rows": rows}, f, indent=1)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
