#!/usr/bin/env python3
"""Where does the block end up, and what hits it, wherever it stands? One flow, many placements.

The §3.2 flume and copper cube (examples/flume_block.py's scene and settings options), the cube's
upstream face at each of ``--at`` positions along the flume, each placement its own run. Until
the flow reaches a cube, every run repeats the same flow; so the flow runs once, alone, through
the C++ driver: with a flow probe at every station (the free flow's arrival, depth h_f and
velocity v_f there, and Eq 20's force F = α_f ρ v_f² A from them), and saving its state when its
front is ``--ahead`` cells short of each station (``run.snapshot_when_front_at``, a list). Each
placement then starts from its station's state (``mpmsdem-run --flow-from``): its cube takes
its steps before it alone (it settles on the bed), and the run is the one from the release, to
the last bit. ``--check`` also runs the last placement from the release and compares the two.

    python3 examples/block_placements.py --at 0.6,0.8,1.0,1.2 [--duration 1.2] [--full]
                                          [--settings joint|table1] [--out DIR] [--exe PATH]
                                          [--threads N] [--workers N] [--check]

Needs YADE (the scenes are written from mpmsdem.flume) and h5py. Writes DIR/placements.csv and
placements.json (per placement: station, free-flow arrival, h_f, v_f, Eq 20, travel, rotation,
peak flow force over 10 ms and its time, speed at the end, and the steps and wall seconds of its
run), prints them, and the steps the shared flow saved. Every run's outputs stay in DIR (the
flow in flow/, placement k in at_k/; coupled.h5 and mpm.h5, h5py).
"""
import argparse
import csv
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from driver_runs import eachCase, recordSteps, runDriver, stepsOf  # noqa: E402

HB = 0.02             # cube side [m] (§3.2)
RHO = 1600.0          # glass beads' bulk density [kg/m³] (Table 1)
PROBE_EVERY = 0.005   # the flow's records: the probes read every this long [s]
SAMPLE_EVERY = 0.002  # a placement's records [s]


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--at", required=True,
                    help="the cube's upstream face along the flume [m], comma-separated, each beyond the column "
                         "(0.3 m) and a cube short of the flume's end (1.8 m)")
    ap.add_argument("--ahead", type=int, default=8,
                    help="the flow's state is saved when its front is this many cells short of each station "
                         "(>= 3: a point within two cells of a cube is refused)")
    ap.add_argument("--out", default="results/block_placements", help="output folder")
    ap.add_argument("--exe", default=None, help="mpmsdem-run (default: the one of this build)")
    ap.add_argument("--threads", type=int, default=None, help="OpenMP threads of each run")
    ap.add_argument("--workers", type=int, default=1, help="placements run at a time")
    ap.add_argument("--check", action="store_true",
                    help="also run the last placement from the release and check it equals the started one")
    a, _ = ap.parse_known_args(argv)
    try:
        a.at = sorted(float(x) for x in a.at.split(","))
    except ValueError:
        raise SystemExit("--at = %r: must be positions [m] separated by commas" % a.at)
    if len(set(a.at)) < len(a.at):
        raise SystemExit("--at = %r: the positions must differ" % (a.at,))
    if a.at[0] <= 0.3 or a.at[-1] >= 1.8 - 2 * HB:
        raise SystemExit("--at = %r: each must lie in (0.3, %g) m (beyond the column, a cube short of the end)"
                         % (a.at, 1.8 - 2 * HB))
    if a.ahead < 3:
        raise SystemExit("--ahead = %r cells: must be >= 3" % a.ahead)
    import flume_block
    a.flume = flume_block.parse(argv)  # the flow's settings, --dx, --full, --duration, --backend
    return a


def prepare(a):
    """The flow's scene and one scene per placement, written to a.out; returns (dx, dt, steps)."""
    import mpmsdem  # noqa: F401  (before yade: it finds YADE's folder in a plain python3)
    from yade import O
    from mpmsdem import driver
    from mpmsdem.flume import Block, Flume
    import flume_block
    dx, duration = flume_block.settings(a.flume)
    kw = dict(dx=dx, width=a.flume.width, backend=a.flume.backend, precision=a.flume.precision, verbose=False,
              **flume_block.flumeKeywords(a.flume))
    os.makedirs(a.out, exist_ok=True)
    flow = Flume(**kw)
    dt = O.dt
    # (it stops once every station has its free-flow reading, or at the placements' duration)
    driver.writeScene(os.path.join(a.out, "flow.json"), flow.coupled, duration=duration, dt=dt,
                      flowProbes=[{"x": x, "halfWidth": dx, "window": 0.05} for x in a.at],
                      seriesEvery=stepsOf(PROBE_EVERY, dt) * dt, outputEvery=duration, vtk="none",
                      stopWhenProbed=True, snapshotWhenFrontAt=[x - a.ahead * dx for x in a.at])
    steps, every = recordSteps(duration, dt, SAMPLE_EVERY)
    for k, x in enumerate(a.at):
        cube = Block(half=(HB / 2,) * 3, x=x, density=8900, friction=0.67, flowFriction=a.flume.flow_friction)
        scene = Flume(blocks=[cube], **kw)
        if O.dt != dt:
            raise RuntimeError("the placement at x %g m chose another step (%r s) than the flow (%r s)" % (x, O.dt, dt))
        driver.writeScene(os.path.join(a.out, "at_%d.json" % k), scene.coupled, duration=duration + 1.0, dt=dt,
                          seriesEvery=every * dt, outputEvery=duration / 4, vtk="none")
    return dx, dt, steps


def run(a, steps):
    """The flow, then every placement from its station's saved state (and with --check the last
    one from the release); returns (wall seconds per run name, the step each placement starts
    from)."""
    from mpmsdem import driver
    exe = a.exe or driver.executable()

    def drive(name, extra):
        return runDriver(exe, os.path.join(a.out, name + ".json"), os.path.join(a.out, name),
                         os.path.join(a.out, name + ".log"), extra, threads=a.threads)

    seconds = {"flow": drive("flow", [])}
    states = [os.path.join(a.out, "flow", "front_snapshot_%d.json" % k) for k in range(len(a.at))]
    start = []
    for k, path in enumerate(states):
        if not os.path.exists(path):
            raise RuntimeError("the flow's front never came %d cells short of x %g m in its run (%s): no placement "
                               "there" % (a.ahead, a.at[k], os.path.join(a.out, "flow.log")))
        with open(path) as f:
            start.append(json.load(f)["step"])
    names = ["at_%d" % k for k in range(len(a.at))]
    walls = eachCase(lambda k: drive(names[k], ["--flow-from", states[k], "--steps", str(steps - start[k])]),
                     list(range(len(a.at))), a.workers)
    seconds.update(zip(names, walls))
    if a.check:
        with open(os.path.join(a.out, names[-1] + ".json")) as f:
            scene = json.load(f)
        with open(os.path.join(a.out, "release.json"), "w") as f:
            json.dump(scene, f)
        seconds["release"] = drive("release", ["--steps", str(steps)])
    return seconds, start


def sameRun(started, release):
    """Whether the records of a placement started from the flow's state are those of the run
    from the release at the same times, to the last bit (coupled.h5's series; the particles at
    the end)."""
    import h5py
    import numpy as np
    with h5py.File(os.path.join(started, "coupled.h5"), "r") as a, \
            h5py.File(os.path.join(release, "coupled.h5"), "r") as b:
        t = a["series/time"][1:]  # (the first record is the start)
        at = np.searchsorted(b["series/time"][:], t)
        if not np.array_equal(b["series/time"][:][at], t):
            return False
        # (equal_nan: a block's flow_first_contact is NaN until the flow touches it)
        if not all(np.array_equal(a["series"][k][1:], b["series"][k][:][at], equal_nan=True) for k in a["series"]):
            return False
    with h5py.File(os.path.join(started, "mpm.h5"), "r") as a, h5py.File(os.path.join(release, "mpm.h5"), "r") as b:
        sa, sb = a["snapshots"][sorted(a["snapshots"])[-1]], b["snapshots"][sorted(b["snapshots"])[-1]]
        return sa.attrs["time"] == sb.attrs["time"] and all(np.array_equal(sa[k][:], sb[k][:]) for k in sa)


def collect(a, dx, dt, steps, seconds, start):
    from mpmsdem import analysis
    with open(os.path.join(a.out, "flow", "flow_probes.json")) as f:
        probes = json.load(f)["probes"]
    rows = []
    for k, (x, p) in enumerate(zip(a.at, probes)):
        s, _ = analysis.driverBlockSeries(os.path.join(a.out, "at_%d" % k), initial=False)
        peak, tPeak = analysis.peakMeanForce(s, 0.01)
        row = {"x": x, "arrival": p["arrival"], "h_f": p["h_f"], "v_f": p["v_f"], "eq20_force": None,
               "travel": float(s["travel"][-1]), "rotation_deg": float(s["rotation"][-1]),
               "peak_force": peak, "peak_time": tPeak, "speed_end": float(abs(s["vx"][-1])),
               "start_time": start[k] * dt, "steps": steps - start[k], "wall_seconds": seconds["at_%d" % k]}
        if p["arrival"] is not None and p["h_f"] > 0:
            row["eq20_force"] = analysis.hydrodynamicForce(RHO, p["v_f"], p["h_f"], min(p["h_f"], HB) * HB)
        rows.append(row)
    with open(os.path.join(a.out, "placements.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    summary = {"dx": dx, "dt": dt, "steps_from_release": steps, "placements": rows, "wall_seconds": seconds}
    if a.check:
        summary["release_equal"] = sameRun(os.path.join(a.out, "at_%d" % (len(a.at) - 1)),
                                           os.path.join(a.out, "release"))
    with open(os.path.join(a.out, "placements.json"), "w") as f:
        json.dump(summary, f, indent=1)
    return summary


def report(s, duration):
    rows = s["placements"]
    print("dx %g m, step %.3g s, %g s a placement (%d steps from the release); the placements ran %.0f %% of those "
          "steps, each from the flow's state ahead of its station"
          % (s["dx"], s["dt"], duration, s["steps_from_release"],
             100.0 * sum(r["steps"] for r in rows) / (len(rows) * s["steps_from_release"])))
    print("%7s %7s %8s %8s %6s %8s %8s %8s %14s %7s %7s" % ("x [m]", "from [s]", "arrival", "h_f [m]", "v_f",
                                                          "Eq20 [N]", "travel", "rot [deg]", "peak [N] (t)", "v_end",
                                                          "wall [s]"))
    for r in rows:
        eq20 = "%8.3f" % r["eq20_force"] if r["eq20_force"] is not None else "%8s" % "-"
        arrival = "%8.3f" % r["arrival"] if r["arrival"] is not None else "%8s" % "-"
        print("%7.3f %8.3f %s %8.4f %6.3f %s %8.4f %8.1f %6.3f (%.3f) %7.4f %7.0f"
              % (r["x"], r["start_time"], arrival, r["h_f"] or 0.0, r["v_f"] or 0.0, eq20, r["travel"],
                 r["rotation_deg"], r["peak_force"], r["peak_time"], r["speed_end"], r["wall_seconds"]))
    if "release_equal" in s:
        print("the last placement from the release (%.0f s) %s the one started from the flow's state (%.0f s)"
              % (s["wall_seconds"]["release"], "equals, to the last bit," if s["release_equal"] else "DIFFERS FROM",
                 s["wall_seconds"]["at_%d" % (len(rows) - 1)]))


def main(argv):
    a = parse(argv)
    dx, dt, steps = prepare(a)
    started = time.time()
    seconds, start = run(a, steps)
    s = collect(a, dx, dt, steps, seconds, start)
    report(s, steps * dt)
    print("wall %.0f s in all; outputs in %s (placements.csv, placements.json)" % (time.time() - started, a.out))
    if a.check and not s["release_equal"]:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
