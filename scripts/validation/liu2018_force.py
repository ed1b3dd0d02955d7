#!/usr/bin/env python3
"""Validation probe (opt-in): the §3.3 glued bottom block's force against the flow's Young's
modulus and the grid spacing. Runs examples/liu2018_blocks.py (three stacked wooden blocks in
the Liu et al. 2018 flume, Table 2's flow) for each modulus and spacing, 8 points per cell, with
the paper's FLIP/PIC blend at Δx 0.01 m (2000 /s, a PIC viscosity of 0.05 m²/s) held
(``--hold``) as that viscosity (``viscosity``, the default: the damping rate 4ν/Δx² grows as Δx
shrinks, the model a viscous flow) or as that rate (``rate``: ν scales with Δx², towards the
inviscid μ(I) flow), and prints from each run's
coupled.h5 the bottom block's downstream flow force, every figure read from the impulse the file
records (every step's force, not a record's own one-step sample): the largest means over 2, 10,
20 and 50 ms, the means 20-40 ms and 40-80 ms after the flow first touches the block and over
0.40-0.45 s, and the impulse of the first 20 ms; with the free flow's v_f, h_f and Eq 20, the
flow's p-wave speed c = sqrt((K + 4G/3)/rho), the cells per block height (h_b 18 mm) and the push
the flow gave the middle and top blocks by the end (their travel).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/liu2018_force.py
        [--young 5e4[,...]] [--dx 0.01[,...]] [--hold viscosity|rate] [--duration 0.45] [--extrapolate]
        [--out results/liu2018_force]

Two to three minutes a run at Δx 0.01 m on one core, about nine times that at 0.005 m. A run whose folder
(OUT/E<modulus>_dx<spacing>) already holds the summary of the same command is read, not run
again (with the rate held: OUT/E<modulus>_dx<spacing>_rate). With --extrapolate and three spacings or more, each modulus's figures at the three finest
also get the observed order p and the value at Δx 0 of f = f0 + C Δx^p where the differences keep
their sign and shrink (and say so where they do not). The table goes to OUT/force.md, the numbers
to OUT/force.json; docs/coupled-results.md quotes it.
"""
import argparse
import json
import math
import os
import platform
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flume_convergence import commit, limitOf  # noqa: E402  (same folder)

RHO, NU = 1300.0, 0.40  # Table 2's flow
BLOCK_HEIGHT = 0.018    # h_b of the §3.3 blocks [m] (examples/liu2018_blocks.py HALF)
WINDOWS = (0.002, 0.01, 0.02, 0.05)  # the peaks' averaging windows [s]
QUANTITIES = ("touch", "peak_10ms", "peak_20ms", "after_20_40", "after_40_80", "late", "impulse_20ms", "push_middle",
              "push_top")


def numbers(text, name, ap):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        ap.error("%s %r: must be comma-separated numbers" % (name, text))
    if not all(v > 0 for v in values):
        ap.error("%s %r: every value must be > 0" % (name, text))
    return values


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--young", default="5e4", help="moduli [Pa] > 0, comma-separated (default Table 2's 5e4)")
    ap.add_argument("--dx", default="0.01", help="grid spacings [m] > 0, comma-separated (default 0.01)")
    ap.add_argument("--hold", default="viscosity", choices=("viscosity", "rate"),
                    help="what of the paper's blend at dx 0.01 m is held at other spacings (default viscosity)")
    ap.add_argument("--duration", type=float, default=0.45, help="coupled run [s] > 0.45 (the last window is "
                    "0.40-0.45 s; default 0.45)")
    ap.add_argument("--extrapolate", action="store_true", help="the limit Δx -> 0 through the three finest spacings")
    ap.add_argument("--out", default=os.path.join("results", "liu2018_force"), help="output folder")
    a = ap.parse_args(argv)
    a.young, a.dx = numbers(a.young, "--young", ap), numbers(a.dx, "--dx", ap)
    if not a.duration >= 0.45:
        ap.error("--duration %r: must be >= 0.45 s (the last window is 0.40-0.45 s)" % a.duration)
    return a


def waveSpeed(E):
    K, G = E / (3 * (1 - 2 * NU)), E / (2 * (1 + NU))
    return math.sqrt((K + 4 * G / 3) / RHO)


def forceWindows(series):
    """From the bottom block's series (t, its downstream impulse J since the start [N s], its
    records' own forces Ft and, where coupled.h5 records it, first_contact): the touch
    (:func:`mpmsdem.analysis.touchTime`: the contact's first step, or the first record with a
    force in older files), the largest means over WINDOWS, the means 20-40 and 40-80 ms after the
    touch and over 0.40-0.45 s, and the impulse of the first 20 ms: from the touch's step, or in
    older files from the record before the first record with a force (a record's force is the
    step's before it, so the contact began after that record)."""
    import numpy as np
    from mpmsdem.analysis import firstContact, impulseMean, peakWindowMean, touchImpulse
    touch, t, J = touchImpulse(series)
    if touch is None:  # the flow never reached the block (a flow too viscous to arrive)
        nan = float("nan")
        return {"touch": None, "peaks": [nan] * len(WINDOWS), "after_20_40": nan, "after_40_80": nan, "late": nan,
                "impulse_20ms": nan}
    start = touch if firstContact(series) is not None else float(t[max(int(np.searchsorted(t, touch)) - 1, 0)])
    return {"touch": touch, "peaks": [peakWindowMean(t, J, w)[0] for w in WINDOWS],
            "after_20_40": impulseMean(t, J, touch + 0.02, touch + 0.04),
            "after_40_80": impulseMean(t, J, touch + 0.04, touch + 0.08), "late": impulseMean(t, J, 0.40, 0.45),
            "impulse_20ms": 0.02 * impulseMean(t, J, start, start + 0.02)}


def viscosity(hold, dx):
    """The PIC viscosity [m²/s] at spacing dx [m] that holds the paper's blend at Δx 0.01 m as a
    viscosity or as a damping rate 4ν/Δx²."""
    from mpmsdem.mpm import PAPER_VISCOSITY
    return PAPER_VISCOSITY if hold == "viscosity" else PAPER_VISCOSITY * (dx / 0.01) ** 2


def runOne(a, E, dx):
    """One run of the example (or the one already in its folder); its row."""
    hold = getattr(a, "hold", "viscosity")
    folder = os.path.abspath(os.path.join(a.out, "E%g_dx%g%s" % (E, dx, "" if hold == "viscosity" else "_rate")))
    cmd = [os.path.join(ROOT, "examples", "liu2018_blocks.py"), "--dx", repr(dx), "--ppc", "8",
           "--flip-viscosity", repr(viscosity(hold, dx)), "--young", repr(E), "--duration", repr(a.duration),
           "--no-plots", "--out", folder]
    summaryPath, commandPath = os.path.join(folder, "summary.json"), os.path.join(folder, "command.json")
    summary = record = None
    if os.path.exists(summaryPath) and os.path.exists(commandPath):
        with open(commandPath) as fh:
            record = json.load(fh)
        if record["args"] == cmd[1:]:
            with open(summaryPath) as fh:
                summary = json.load(fh)
    if summary is None:
        print("E %g Pa, Δx %g m: running liu2018_blocks.py %s ..." % (E, dx, " ".join(cmd[1:-1])), flush=True)
        started = commit()  # the code the run starts with (the checkout may move on while it runs)
        os.makedirs(folder, exist_ok=True)
        if os.path.exists(summaryPath):
            os.remove(summaryPath)
        with open(os.path.join(folder, "log.txt"), "w") as log:
            r = subprocess.run([sys.executable] + cmd, stdout=log, stderr=subprocess.STDOUT)
        if r.returncode != 0:
            sys.exit("liu2018_blocks.py failed for E %g Pa, Δx %g m: see %s" % (E, dx, os.path.join(folder, "log.txt")))
        record = {"args": cmd[1:], "commit": started}
        with open(commandPath, "w") as fh:
            json.dump(record, fh)
        with open(summaryPath) as fh:
            summary = json.load(fh)
    import h5py
    from mpmsdem.analysis import driverBlockSeries
    with h5py.File(os.path.join(folder, "coupled.h5"), "r", locking=False) as h:
        block = json.loads(h.attrs["ids"]).index(1)  # body 1: the glued bottom block
    w = forceWindows(driverBlockSeries(folder, block=block)[0])
    b = summary["blocks"]
    return dict(w, young=E, dx=dx, hold=hold, viscosity=viscosity(hold, dx), cells=BLOCK_HEIGHT / dx,
                peak_10ms=w["peaks"][1], peak_20ms=w["peaks"][2],
                free_flow=summary["free_flow"], eq20=summary["eq20_bottom"], push_middle=b["middle"]["travel"],
                push_top=b["top"]["travel"], middle_fall=b["middle"]["fall_time"], dt_min=summary["dt_min"],
                steps=summary["steps"], particles=summary["particles"], flip_blend=summary["flip_blend"],
                wall=summary["wall_seconds"], commit=record["commit"])


def table(rows):
    lines = ["| E [kPa] | c [m/s] | Δx [m] | cells per h_b | free flow v_f, h_f; Eq 20 | first touch [s] | "
             "largest 2 / 10 / 20 / 50 ms means [N] | 20-40 ms after the touch [N] | 40-80 ms after [N] | "
             "0.40-0.45 s [N] | impulse of the first 20 ms [N s] | push, middle / top [mm] | steps (smallest O.dt) "
             "| wall, free + coupled [s] |",
             "|---:|---:|---:|---:|---|---:|---|---:|---:|---:|---:|---|---:|---:|"]
    for r in rows:
        ff = r["free_flow"]
        lines.append("| %g | %.1f | %g | %.1f | %.3f m/s, %.1f mm; %.1f N | %s | %s | %.2f | %.2f | %.2f | %.4f | "
                     "%.1f / %.1f | %d (%.2g s) | %.0f + %.0f |" % (
                         r["young"] / 1e3, waveSpeed(r["young"]), r["dx"], r["cells"], ff["v_f"], 1e3 * ff["h_f"],
                         r["eq20"], "never" if r["touch"] is None else "%.4f" % r["touch"], " / ".join("%.2f" % p for p in r["peaks"]), r["after_20_40"],
                         r["after_40_80"], r["late"], r["impulse_20ms"], 1e3 * r["push_middle"], 1e3 * r["push_top"],
                         r["steps"], r["dt_min"], r["wall"]["free_flow"], r["wall"]["coupled"]))
    return "\n".join(lines)


def extrapolations(rows):
    """Per modulus, the limit of each quantity through its three finest spacings (:func:`limitOf`)."""
    lines = []
    for E in sorted({r["young"] for r in rows}):
        rs = sorted((r for r in rows if r["young"] == E), key=lambda r: -r["dx"])[-3:]
        if len(rs) < 3:
            continue
        h = [r["dx"] for r in rs]
        for q in QUANTITIES:
            f = [r[q] for r in rs]
            if any(v is None or v != v for v in f):  # a run the flow never reached
                lines.append("- E %g kPa, %s: not reached at every spacing" % (E / 1e3, q))
                continue
            p, f0, why = limitOf(f, h, positive=not q.startswith("push_"))  # the blocks' travels may tend to zero
            lines.append("- E %g kPa, %s at Δx %s: %s -> %s" % (
                E / 1e3, q, ", ".join("%g" % x for x in h), ", ".join("%.4g" % v for v in f),
                "no limit to trust (%s)" % why if why else
                "order %.2f, limit %.4g (%+.1f %% from the finest)" % (p, f0, 100 * (f[-1] / f0 - 1)
                                                                       if f0 else float("nan"))))
    return lines


def main(argv):
    a = parse(argv)
    os.makedirs(a.out, exist_ok=True)
    rows = [runOne(a, E, dx) for E in a.young for dx in sorted(a.dx, reverse=True)]
    text = table(rows)
    text += "\n\nThe paper's blend at Δx 0.01 m held at every Δx as %s; 8 points per cell; coupled run to %g s; " \
            "runs at commit(s) %s; %s, %d cores, OMP_NUM_THREADS=%s" % (
                "a PIC viscosity of %.4g m²/s" % viscosity(a.hold, 0.01) if a.hold == "viscosity" else
                "a PIC damping rate of %.0f /s (viscosity 4 x rate / dx²)" % (4 * viscosity(a.hold, 0.01) / 0.01 ** 2),
                a.duration,
                ", ".join(sorted({r["commit"] for r in rows})), platform.machine(), os.cpu_count() or 0,
                os.environ.get("OMP_NUM_THREADS", "unset"))
    if a.extrapolate:
        text += "\n\n" + "\n".join(extrapolations(rows) or ["(fewer than three spacings for every modulus)"])
    print(text)
    with open(os.path.join(a.out, "force.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(a.out, "force.json"), "w") as f:
        json.dump(rows, f, indent=1)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
