#!/usr/bin/env python3
"""The field example's cost per step on the CPU against its points and its blocks: each grid
spacing runs the flow alone and the flow with the 200 blocks in the same command, so the blocks'
share is a ratio between two runs of one machine minute.

Scenes: ``examples/field_valley.py --dx DX --blocks 0|200 --driver-scene`` (the valley, 378 m³ of
debris, the example's PIC viscosity), run with ``mpmsdem-run SCENE --bench --steps N`` (no
outputs; the first N steps, where the debris accelerates down the valley). Printed per run:
points, grid cells, steps, ms per step, particle-updates per second, and with blocks the step's
split (MPM, MP–block coupling, blocks) and the ratio of its cost per step to the flow alone's.

    /usr/bin/python3 scripts/bench/bench_field.py [--exe build/mpmsdem-run] [--dx 1.0,0.5,0.25] [--steps 400]

(Debian's python, where YADE is: the scenes are written by the YADE example; the package is
taken from build/python when there is one, else from where it is installed.)
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default=os.path.join(REPO, "build", "mpmsdem-run"))
    ap.add_argument("--dx", default="1.0,0.5,0.25")
    ap.add_argument("--steps", type=int, default=400)
    a = ap.parse_args(argv)
    rows = []
    env = dict(os.environ)
    built = os.path.join(REPO, "build", "python")
    if os.path.isdir(built):
        env["PYTHONPATH"] = os.pathsep.join([built] + [v for v in env.get("PYTHONPATH", "").split(os.pathsep) if v])
    with tempfile.TemporaryDirectory() as tmp:
        for dx in a.dx.split(","):
            alone = None
            for blocks in (0, 200):
                scene = os.path.join(tmp, "field_%s_%d.json" % (dx, blocks))
                p = subprocess.run([sys.executable, os.path.join(REPO, "examples", "field_valley.py"), "--dx", dx,
                                    "--blocks", str(blocks), "--driver-scene", scene, "--out", os.path.join(tmp, "o")],
                                   capture_output=True, text=True, env=env)
                if p.returncode != 0:
                    sys.exit("field_valley.py --driver-scene failed:\n" + p.stderr[-3000:])
                r = subprocess.run([a.exe, scene, "--bench", "--steps", str(a.steps)], capture_output=True, text=True)
                if r.returncode != 0:
                    sys.exit("mpmsdem-run failed on %s:\n%s" % (scene, r.stderr[-3000:]))
                b = json.loads(r.stdout.strip().splitlines()[-1])
                cells = json.load(open(scene))["grid"]["cells"]
                per = b["seconds"] / b["steps"] * 1e3
                if blocks == 0:
                    alone = per
                st = b.get("stage_seconds")
                split = ("%.2f / %.2f / %.2f" % tuple(st[k] / b["seconds"] for k in ("mpm", "coupling", "blocks"))
                         if st and blocks else "–")
                rows.append((dx, blocks, b["particles"], cells, b["steps"], per, b["particle_updates_per_s"], split,
                             per / alone, b["threads"]))
    print("| dx [m] | blocks | points | grid cells | steps | ms per step | particle-updates/s | MPM / coupling / "
          "blocks | against the flow alone |")
    print("|---:|---:|---:|---|---:|---:|---:|---|---:|")
    for dx, blocks, n, cells, steps, per, ups, split, ratio, threads in rows:
        print("| %s | %d | %d | %s | %d | %.2f | %.3g | %s | %.2f |" % (dx, blocks, n, " × ".join(map(str, cells)), steps,
                                                                       per, ups, split, ratio))
    print("threads %d, commit %s, load average %.1f" % (rows[0][-1], subprocess.run(
        ["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
        os.getloadavg()[0]))


if __name__ == "__main__":
    main(sys.argv[1:])
