#!/usr/bin/env python3
"""Blocks by the hundred on a terrain: does the SDEM step's cost per block stay flat as the
blocks grow from a hundred to thousands? (the field-scale issue: "the block–block broad phase
scales, measure 1,000 blocks").

Scene, written as a driver scene and run by ``mpmsdem-run --bench`` (no YADE in the timed loop):
N sphero-cubes of 1 m and 2 t (R 5 cm, k_c 3e6 N/m, friction 0.7) resting on a planar terrain
at 5° (raster 0.5 m), on a square grid 1.6 m apart (neighbours 0.6 m apart: no block–block
contact, so the broad phase must reject every pair it is shown), turned by up to 10° so that the
boxes are not aligned; no flow ("particles": []); a fixed step of 1e-3 s. Each size runs in the
same command, smallest first, ``--repeats`` times, best kept. Printed: steps, the step loop's
wall time, the blocks' stage share, µs per block-step, the ratio of that cost to the smallest
size's (1.0: linear scaling), the block pairs the narrow phase computed per step (0 here is a
broad phase that lets none through) and the terrain contacts (4 per block at rest).

    python3 scripts/bench/bench_blocks_terrain.py [--exe build/mpmsdem-run] [--sizes 100,300,1000,3000]
                                                  [--steps 500] [--repeats 2] [--baseline-exe OLD]

With ``--baseline-exe`` an older mpmsdem-run runs each scene too, in turn with the new one, and
the table adds the new/old speed.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))


def scene(n, steps, seed=1):
    import random
    rng = random.Random(seed)
    side = int(math.ceil(math.sqrt(n)))
    pitch = 1.6
    length = side * pitch + 4.0
    spacing = 0.5
    nr = int(math.ceil(length / spacing)) + 1
    tan5 = math.tan(math.radians(5.0))
    heights = [-tan5 * (i * spacing) for i in range(nr) for _ in range(nr)]
    th = math.radians(5.0)
    nrm = (math.sin(th), 0.0, math.cos(th))
    blocks = []
    half, R = 0.5, 0.05
    for k in range(n):
        x, y = 2.0 + (k % side) * pitch, 2.0 + (k // side) * pitch
        z = -tan5 * x
        yaw = math.radians(rng.uniform(-10, 10))
        # tilt about y by the slope, then yaw about the slope's normal: q = q_tilt * q_yaw, (w, x, y, z)
        ct, st, cy, sy = math.cos(th / 2), math.sin(th / 2), math.cos(yaw / 2), math.sin(yaw / 2)
        q = (ct * cy, st * sy, st * cy, ct * sy)
        d = half + 0.1 * R
        blocks.append({"id": k, "material": "block", "box": [half, half, half], "sweep_radius": R,
                       "position": [x + d * nrm[0], y, z + d * nrm[2]], "orientation": list(q)})
    mat = {"density": 2000.0 / ((2 * half) ** 3), "friction": 0.7, "barrier_stiffness": 3e6, "normal_damping": 0.3,
           "tangential_damping": 0.5, "flow": {"friction": 0.45, "barrier_stiffness": 3e6}}
    dx = 1.0
    cells = [int(math.ceil(length / dx)) + 4, int(math.ceil(length / dx)) + 4, 8]
    return {"description": "bench_blocks_terrain: %d blocks at rest on a 5 deg terrain" % n,
            "grid": {"dx": dx, "cells": cells, "origin": [-2 * dx, -2 * dx, -tan5 * length - 2 * dx]},
            "material": {"density": 1800, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
            "particles": [],
            "terrain": {"nx": nr, "ny": nr, "x0": 0.0, "y0": 0.0, "spacing": spacing, "heights": heights,
                        "friction": 0.45},
            "terrain_material": {"friction": 0.7, "barrier_stiffness": 3e6, "normal_damping": 0.3,
                                 "tangential_damping": 0.5},
            "block_materials": {"block": mat}, "blocks": blocks,
            "run": {"duration": steps * 1e-3, "dt": 1e-3, "output_dir": "out"}}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default=os.path.join(REPO, "build", "mpmsdem-run"))
    ap.add_argument("--sizes", default="100,300,1000,3000")
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--baseline-exe", default=None, help="an older mpmsdem-run to compare with")
    a = ap.parse_args(argv)
    sizes = [int(v) for v in a.sizes.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            path = os.path.join(tmp, "blocks_%d.json" % n)
            with open(path, "w") as f:
                json.dump(scene(n, a.steps), f)
            best = {}
            for _ in range(a.repeats):
                for exe in [a.exe] + ([a.baseline_exe] if a.baseline_exe else []):
                    r = subprocess.run([exe, path, "--bench"], capture_output=True, text=True)
                    if r.returncode != 0:
                        sys.exit("%s failed for %d blocks:\n%s" % (exe, n, r.stderr[-3000:]))
                    res = json.loads(r.stdout.strip().splitlines()[-1])
                    if exe not in best or res["seconds"] < best[exe]["seconds"]:
                        best[exe] = res
            rows.append((n, best[a.exe], best.get(a.baseline_exe)))
    base = None
    print("| blocks | steps | step loop [s] | blocks' share | µs per block-step | / %d blocks' | narrow-phase pairs per step | "
          "terrain contacts |%s" % (sizes[0], " baseline µs per block-step | new / baseline speed |" if a.baseline_exe else ""))
    print("|---:|---:|---:|---:|---:|---:|---:|---:|%s" % ("---:|---:|" if a.baseline_exe else ""))
    for n, r, old in rows:
        per = r["seconds"] / (r["steps"] * n) * 1e6
        base = base or per
        stages = r.get("stage_seconds", {})
        share = stages.get("blocks", float("nan")) / r["seconds"] if stages else float("nan")
        extra = ""
        if old:
            perOld = old["seconds"] / (old["steps"] * n) * 1e6
            extra = " %.2f | %.2f |" % (perOld, perOld / per)
        print("| %d | %d | %.3f | %.2f | %.2f | %.2f | %s | %s |%s" % (
            n, r["steps"], r["seconds"], share, per, per / base, "%.1f" % (r["narrow_phase_pairs"] / r["steps"]),
            r["block_contacts"], extra))
    print("commit %s, %s, %s" % (subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                                                capture_output=True, text=True).stdout.strip(),
                                 os.uname().machine, "load average %.1f" % os.getloadavg()[0]))


if __name__ == "__main__":
    main(sys.argv[1:])
