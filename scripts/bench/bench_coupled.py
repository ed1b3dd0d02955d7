#!/usr/bin/env python3
"""Cost of the MPM–SDEM coupled step on the paper's §3.2 scene (copper cube in the inclined
glass-bead flume, the settings of examples/flume_block.py).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/bench/bench_coupled.py [--full] [--dx DX]
                                                 [--steps N] [--start T]

Two runs in one command, each a window of N steps timed around the impact:

1. the coupled scene with the cube: the run goes untimed until the flow front is one cell
   upstream of the cube's face (or to ``--start`` seconds), then N steps are timed;
2. the same scene without the cube (flow and SDEM bed only), untimed for the same number of
   steps (same O.dt: the flume fixes it at the start, the cube does not change it), then the
   same N steps timed: the reference for the wall time per step.

Prints per run the share of the window's wall time in the MPM step (``coupled.timings()["mpm"]``),
the MP–block contacts (``["coupling"]``, the bed included: the bed is an SDEM block), the SDEM
bridge (``sdem.timings()``: read, compute, write) and the rest (YADE's ForceResetter and
NewtonIntegrator, the Python runner); the ratio coupling/MPM (the project's goal: coupling adds
≤ 25 % to the MPM step for one block) and the ratio of wall time per step with the cube to
without it. Also the commit, the machine (nproc, CPU model, load average) and the command.

Default dx = 0.02 m (12,000 material points); ``--full`` is the paper's dx = 0.01 m, 8 points per
cell (96,000 material points).
"""
import argparse
import os
import platform
import subprocess
import sys
import time

import mpmsdem
from mpmsdem.flume import Block, Flume
from yade import O

HB, L0, COLUMN = 0.02, 0.21, 0.3   # examples/flume_block.py


def parse():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--full", action="store_true", help="paper resolution: dx 0.01 m, 96,000 material points")
    ap.add_argument("--dx", type=float, default=None, help="grid spacing [m] (default 0.02, --full 0.01)")
    ap.add_argument("--steps", type=int, default=None, help="timed steps (default: 0.1 s of flow)")
    ap.add_argument("--start", type=float, default=None,
                    help="untimed run before the window [s] (default: until the front is one cell upstream of the cube)")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    a = ap.parse_args()
    a.dx = a.dx or (0.01 if a.full else 0.02)
    if not a.dx > 0:
        ap.error("--dx = %r m: must be > 0" % a.dx)
    if a.steps is not None and a.steps < 1:
        ap.error("--steps = %r: must be >= 1" % a.steps)
    if a.start is not None and a.start < 0:
        ap.error("--start = %r s: must be >= 0" % a.start)
    return a


def build(dx, withCube, backend):
    blocks = [Block(half=(HB / 2,) * 3, x=COLUMN + L0, density=8900, friction=0.67, flowFriction=0.21)] if withCube \
        else []
    return Flume(dx=dx, blocks=blocks, backend=backend, verbose=False)


def untimedToImpact(scene, dx, start):
    """Run until ``start`` [s] or, by default, until the front is one cell upstream of the
    cube's upstream face; return the number of steps."""
    chunk = max(1, int(round(0.005 / O.dt)))
    while True:
        if start is not None:
            if O.time >= start - 0.5 * O.dt:
                break
            mpmsdem.run(max(1, min(chunk, int(round((start - O.time) / O.dt)))), scene.coupled)
            continue
        if scene.mpm.front(0) >= COLUMN + L0 - dx:
            break
        if O.time > 3.0:
            raise RuntimeError("the front did not reach x = %g m within 3 s" % (COLUMN + L0 - dx))
        mpmsdem.run(chunk, scene.coupled)
    return O.iter


def window(scene, steps):
    scene.coupled.resetTimings()
    contacts = cubeMax = 0
    cube = scene.blockIds[0] if scene.blockIds else None
    t0 = time.perf_counter()
    done = 0
    while done < steps:  # chunks only to sample the contact count; the timers run throughout
        k = min(50, steps - done)
        mpmsdem.run(k, scene.coupled)
        done += k
        contacts = max(contacts, scene.coupled.totalContacts)
        if cube is not None:
            cubeMax = max(cubeMax, scene.coupled.contactCount(cube))
    wall = time.perf_counter() - t0
    c, s = scene.coupled.timings(), scene.sdem.timings()
    sd = s["read"] + s["compute"] + s["write"]
    return {"wall": wall, "mpm": c["mpm"], "coupling": c["coupling"], "sdem": sd,
            "rest": wall - c["mpm"] - c["coupling"] - sd, "steps": c["steps"], "maxContacts": contacts,
            "cubeContacts": cubeMax, "travel": scene.travel(0) if cube is not None else 0.0}


def machine():
    model = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = "%.2f %.2f %.2f" % os.getloadavg()
    return "nproc %d, %s, %s; load average %s" % (os.cpu_count(), model, platform.machine(), load)


def commit():
    try:
        here = os.path.dirname(os.path.abspath(__file__))
        return subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=here, text=True).strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def report(name, r):
    w = r["wall"]
    print("%-22s %8.3f ms/step | MPM %5.1f %% | MP-block coupling %5.1f %% | SDEM bridge %5.1f %% | YADE + Python "
          "%5.1f %% | coupling/MPM %.3f | max MP-block contacts %d"
          % (name, 1e3 * w / r["steps"], 100 * r["mpm"] / w, 100 * r["coupling"] / w, 100 * r["sdem"] / w,
             100 * r["rest"] / w, r["coupling"] / r["mpm"], r["maxContacts"]))


def main():
    a = parse()
    print("command: OMP_NUM_THREADS=%s %s" % (os.environ.get("OMP_NUM_THREADS", "(unset)"),
                                              " ".join(["python3"] + sys.argv)))
    print("commit %s; machine: %s" % (commit(), machine()))
    scene = build(a.dx, True, a.backend)
    n = scene.mpm.numParticles
    dt = O.dt
    steps = a.steps or max(1, int(round(0.1 / dt)))
    t0 = time.perf_counter()
    pre = untimedToImpact(scene, a.dx, a.start)
    tPre = time.perf_counter() - t0
    tStart = O.time
    cube = window(scene, steps)
    print("§3.2 scene, dx = %g m, %d material points, O.dt = %.3g s; window: steps %d-%d (t = %.3f-%.3f s), the front "
          "at the cube's face at its start; up to %d material points on the cube (sampled every 50 steps), cube travel %.4f m at the end "
          "(untimed part: %.0f s)" % (a.dx, n, dt, pre, pre + steps, tStart, O.time, cube["cubeContacts"], cube["travel"],
                                      tPre))
    ref = build(a.dx, False, a.backend)
    if abs(O.dt - dt) > 1e-12 * dt:
        raise RuntimeError("O.dt differs without the cube (%g s against %g s): the runs are not comparable" % (O.dt, dt))
    mpmsdem.run(pre, ref.coupled)
    free = window(ref, steps)
    report("with the cube", cube)
    report("without the cube", free)
    print("wall time per step with the cube / without: %.3f; MP-cube contacts alone cost %.3f of the MPM step "
          "((coupling with - coupling without) / MPM without)"
          % ((cube["wall"] / cube["steps"]) / (free["wall"] / free["steps"]),
             (cube["coupling"] - free["coupling"]) / free["mpm"]))
    print("load average after the runs: %.2f %.2f %.2f (on a shared machine compare the ratios, not the absolute "
          "times)" % os.getloadavg())


main()
