#!/usr/bin/env python3
"""Validation study (opt-in, minutes): quasi-2D granular column collapse runout against the
aspect ratio a = H_i/L_i, with the plain C++ driver, against the experimental fits of
Lube et al. (2005): dL/L_i = 1.2 a for a < 1.8 and 1.9 a^(2/3) above.

Every column is the scene of examples/scenes/column_collapse.json (glass-bead mu(I)
parameters mu_s 0.38, mu_2 0.64, I0 0.279; basal friction 0.4; free-slip side walls; dx 1 cm,
8 points per cell; slot 5 cm wide) with its length, height and domain changed, run for
max(0.5 s, 5 sqrt(H_i/g)). Prints a table (runout, final height, deviation from the fit,
kinetic energy left) and, with --plot, a figure. It reports; it does not pass or fail.

    /usr/bin/python3 scripts/validation/runout_vs_aspect.py [--aspects 0.5,1,2,4] [--plot FILE]
"""
import argparse
import json
import math
import os
import subprocess
import tempfile

import h5py

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def lube(a):
    return 1.2 * a if a < 1.8 else 1.9 * a ** (2.0 / 3.0)


def scene_for(a, base, dx=0.01):
    H = 0.2 if a >= 1 else 0.1
    L = round(H / a / dx) * dx
    s = json.loads(json.dumps(base))
    room = L * (1 + 1.6 * lube(a)) + 4 * dx  # 60 % beyond the fitted runout
    s["grid"]["cells"] = [int(room / dx) + 2, s["grid"]["cells"][1], int(H / dx) + 6]
    s["particles"] = [{"lo": [0, 0, 0], "hi": [L, base["particles"][0]["hi"][1], H], "ppc": 8}]
    s["run"].update(duration=max(0.5, 5 * math.sqrt(H / 9.81)), vtk="none")
    return s, L, H


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--aspects", default="0.5,1,2,4", help="comma-separated aspect ratios a = H_i/L_i")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="build folder with mpmsdem-run")
    ap.add_argument("--plot", help="write runout against a to this PNG")
    args = ap.parse_args()
    base = json.load(open(os.path.join(ROOT, "examples", "scenes", "column_collapse.json")))
    rows = []
    print("%5s %6s %6s %9s %9s %8s %9s %10s" % ("a", "L_i", "H_i", "dL/L_i", "Lube fit", "dev", "H_end/L_i", "KE end/pk"))
    with tempfile.TemporaryDirectory() as work:
        for a in (float(x) for x in args.aspects.split(",")):
            s, L, H = scene_for(a, base)
            path = os.path.join(work, "a%g.json" % a)
            s["run"]["output_dir"] = os.path.join(work, "a%g" % a)
            json.dump(s, open(path, "w"))
            subprocess.run([os.path.join(args.build, "mpmsdem-run"), path], check=True, stdout=subprocess.DEVNULL)
            with h5py.File(os.path.join(s["run"]["output_dir"], "mpm.h5"), "r") as f:
                front, height = f["series/front_x"][-1], f["series/height_z"][-1]
                ke = f["series/kinetic_energy"][:]
            r = (front - L) / L
            rows.append((a, r, lube(a), height / L))
            print("%5g %6.2f %6.2f %9.3f %9.3f %+7.0f%% %9.3f %10.1e"
                  % (a, L, H, r, lube(a), 100 * (r / lube(a) - 1), height / L, ke[-1] / ke.max()))
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import numpy as np
        fig, ax = plt.subplots(figsize=(5, 4))
        aa = np.linspace(0.3, max(r[0] for r in rows) * 1.1, 100)
        ax.plot(aa, [lube(x) for x in aa], "k--", label="Lube et al. 2005 fits")
        ax.plot([r[0] for r in rows], [r[1] for r in rows], "o", label="mpmsdem MPM")
        ax.set_xlabel("a = H_i / L_i")
        ax.set_ylabel("ΔL / L_i")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=100)
        print("plot written to", args.plot)


if __name__ == "__main__":
    main()
