#!/usr/bin/env python3
"""One MpmEngine run in YADE with outputs, for bench_output_memory.py's --yade rows: the driver
scene SCENE (its grid, material, particles, gravity, walls and keep_last_good_state) stepped
STEPS times by O.dt = 1e-5 s with a snapshot at the start and every 5 steps into OUT.

    /usr/bin/python3 scripts/bench/yade_output_run.py SCENE OUT STEPS
"""
import json
import sys

import mpmsdem
from yade import O


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        scene = json.load(f)
    steps = int(sys.argv[3])
    dt = 1e-5
    eng = mpmsdem.MpmEngine(grid=scene["grid"], material=scene["material"], particles=scene["particles"],
                            gravity=scene.get("gravity", (0, 0, -9.81)),
                            walls=scene.get("walls"), keepLastGoodState=scene.get("keep_last_good_state", True),
                            precision=scene.get("run", {}).get("precision", "double"),
                            output=sys.argv[2], outputEvery=5 * dt, verbose=False)
    O.engines = [eng.runner]
    O.dt = dt
    mpmsdem.run(steps, eng)


if __name__ == "__main__":
    main()
