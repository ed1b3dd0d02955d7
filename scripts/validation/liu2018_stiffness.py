#!/usr/bin/env python3
"""Validation probe (opt-in, about a minute a modulus on one core): the §3.3 glued bottom block's
force against the flow's Young's modulus. Runs examples/liu2018_blocks.py --full (Δx 0.01 m,
8 points per cell, the paper's blend) for each modulus and prints, from each run's coupled.h5,
the bottom block's downstream flow force: the script's own peak (10 ms mean), the largest running
means over 2, 10, 20 and 50 ms (analysis.smoothedPeak), its mean over 20-40 ms and 40-80 ms after the flow first
touches it and over 0.40-0.45 s, and the impulse of the first 20 ms; with the free flow's v_f,
h_f and Eq 20, and the flow's p-wave speed c = sqrt((K + 4G/3)/rho).

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/liu2018_stiffness.py
        [--young 3.125e3,1.25e4,5e4,2e5,8e5] [--duration 0.45] [--out results/liu2018_stiffness]

A run whose folder already holds summary.json for the same modulus and duration is read, not run
again. docs/coupled-results.md quotes its output.
"""
import argparse
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RHO, NU = 1300.0, 0.40  # Table 2's flow


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--young", default="3.125e3,1.25e4,5e4,2e5,8e5", help="moduli [Pa], comma-separated")
    ap.add_argument("--duration", type=float, default=0.45, help="coupled run [s] (0.45; > 0.4)")
    ap.add_argument("--out", default=os.path.join("results", "liu2018_stiffness"), help="output folder")
    a = ap.parse_args(argv)
    try:
        a.young = [float(e) for e in a.young.split(",")]
    except ValueError:
        ap.error("--young %r: must be comma-separated moduli [Pa]" % a.young)
    if not all(e > 0 for e in a.young):
        ap.error("--young %r: every modulus must be > 0" % a.young)
    if not a.duration > 0.4:
        ap.error("--duration %r: must be > 0.4 s (the last window is 0.40-0.45 s)" % a.duration)
    return a


def waveSpeed(E):
    K, G = E / (3 * (1 - 2 * NU)), E / (2 * (1 + NU))
    return math.sqrt((K + 4 * G / 3) / RHO)


def forceWindows(t, f):
    """From a force series f(t) (the bottom block's downstream force): first touch, the largest
    means over 2/10/20/50 ms, the means 20-40 and 40-80 ms after the touch and over 0.40-0.45 s,
    and the impulse of the first 20 ms."""
    import numpy as np
    from mpmsdem.analysis import smoothedPeak
    touch = t[np.argmax(f > 0)]

    def mean(a, b):
        m = (t >= a) & (t < b)
        return float(f[m].mean()) if m.any() else float("nan")

    m = (t >= touch) & (t < touch + 0.02)
    return {"touch": float(touch), "peaks": [smoothedPeak(t, f, w)[0] for w in (0.002, 0.01, 0.02, 0.05)],
            "after_20_40": mean(touch + 0.02, touch + 0.04), "after_40_80": mean(touch + 0.04, touch + 0.08),
            "late": mean(0.40, 0.45), "impulse_20ms": float(np.trapz(f[m], t[m]))}


def main(argv):
    a = parse(argv)
    import h5py
    rows = []
    for E in a.young:
        folder = os.path.abspath(os.path.join(a.out, "E%g" % E))
        summaryPath = os.path.join(folder, "summary.json")
        summary = None
        if os.path.exists(summaryPath):
            with open(summaryPath) as fh:
                summary = json.load(fh)
            if summary.get("young_modulus") != E or summary.get("duration") != a.duration:
                summary = None
        if summary is None:
            print("E %g Pa: running liu2018_blocks.py --full --duration %g ..." % (E, a.duration), flush=True)
            cmd = [sys.executable, os.path.join(ROOT, "examples", "liu2018_blocks.py"), "--full", "--no-plots",
                   "--duration", repr(a.duration), "--young", repr(E), "--out", folder]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit("liu2018_blocks.py failed for E %g Pa:\n%s" % (E, (r.stdout + r.stderr)[-3000:]))
            with open(summaryPath) as fh:
                summary = json.load(fh)
        with h5py.File(os.path.join(folder, "coupled.h5"), "r", locking=False) as h:
            ids = json.loads(h.attrs["ids"])
            t = h["series/time"][:]
            f = h["series/flow_force"][:, 3 * ids.index(1)]  # body 1: the glued bottom block
        rows.append((E, summary, forceWindows(t, f)))
    print("| E [kPa] | c [m/s] | free flow v_f, h_f; Eq 20 | first touch [s] | peak, 10 ms (the script's) [N] | "
          "largest 2 / 10 / 20 / 50 ms means [N] | 20-40 ms after the touch [N] | 40-80 ms after [N] | "
          "0.40-0.45 s [N] | impulse of the first 20 ms [N s] |")
    print("|---:|---:|---|---:|---:|---|---:|---:|---:|---:|")
    for E, s, w in rows:
        ff = s["free_flow"]
        print("| %g | %.1f | %.3f m/s, %.1f mm; %.1f N | %.4f | %.2f | %s | %.1f | %.1f | %.1f | %.3f |" % (
            E / 1e3, waveSpeed(E), ff["v_f"], 1e3 * ff["h_f"], s["eq20_bottom"], w["touch"],
            s["blocks"]["bottom"]["peak_force"], " / ".join("%.1f" % p for p in w["peaks"]), w["after_20_40"],
            w["after_40_80"], w["late"], w["impulse_20ms"]))


if __name__ == "__main__":
    main(sys.argv[1:])
