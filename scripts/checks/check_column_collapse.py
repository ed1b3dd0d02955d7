#!/usr/bin/env python3
"""Check: granular column collapse with the plain C++ driver (no YADE), the scene
examples/scenes/column_collapse.json: quasi-2D column, L_i = 0.1 m, H_i = 0.2 m (a = 2),
free-slip side walls, basal friction 0.4, mu_s 0.38, mu_2 0.64, dx 0.01 m, 8 per cell.

Asserts, from the HDF5 output read with h5py:
- runout Delta L / L_i within the experimental band at a = 2 (Lube et al. 2005: 1.9 a^(2/3)
  = 3.02; Lajeunesse et al. 2005 report 1.2a-2a^(2/3) type fits with ~+-20 % scatter between
  materials): [0.8, 1.2] x 1.9 a^(2/3);
- the front stops after a few sqrt(H_i/g): over the last 0.05 s (t >= 3.9 sqrt(H_i/g)) its
  speed is below 2 % of its peak speed;
- total mass exactly conserved in every snapshot; kinetic energy at the end < 1e-3 of its peak.

    /usr/bin/python3 scripts/checks/check_column_collapse.py [--build build] [--plot FILE]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build folder with mpmsdem-run")
    ap.add_argument("--plot", help="write the final deposit profile to this PNG")
    args = ap.parse_args()
    exe = os.path.join(args.build, "mpmsdem-run")
    scene_path = os.path.join(ROOT, "examples", "scenes", "column_collapse.json")
    scene = json.load(open(scene_path))
    L, H = 0.1, 0.2
    a = H / L
    with tempfile.TemporaryDirectory() as out:
        env = dict(os.environ, OMP_NUM_THREADS=str(os.cpu_count() or 1))
        subprocess.run([exe, scene_path, "--out", out], check=True, stdout=subprocess.DEVNULL, env=env)
        with h5py.File(os.path.join(out, "mpm.h5"), "r") as f:
            t = f["series/time"][:]
            front = f["series/front_x"][:]
            ke = f["series/kinetic_energy"][:]
            names = sorted(f["snapshots"].keys())
            masses = [f["snapshots"][n]["mass"][:].sum() for n in names]
            x_end = f["snapshots"][names[-1]]["x"][:]
    failures = []
    runout = (front[-1] - L) / L
    fit = 1.9 * a ** (2.0 / 3.0)
    print("runout dL/L_i = %.3f (Lube fit 1.9 a^(2/3) = %.3f, band [%.2f, %.2f])" % (runout, fit, 0.8 * fit, 1.2 * fit))
    if not 0.8 * fit <= runout <= 1.2 * fit:
        failures.append("runout %.3f outside [%.3f, %.3f]" % (runout, 0.8 * fit, 1.2 * fit))
    t_last = t[-1] - 0.05
    v_end = (front[-1] - np.interp(t_last, t, front)) / 0.05
    v_peak = np.max(np.diff(front) / np.diff(t))
    tau = math.sqrt(H / 9.81)
    print("front speed %.3f m/s at peak, %.2e m/s over t = %.2f..%.2f s (%.1f..%.1f sqrt(H/g))"
          % (v_peak, v_end, t_last, t[-1], t_last / tau, t[-1] / tau))
    if not 0 <= v_end <= 0.02 * v_peak:
        failures.append("front not stopped: %.2e m/s at the end, peak %.3f m/s" % (v_end, v_peak))
    m0 = scene["material"]["density"] * L * H * 0.05
    drift = max(abs(m - m0) for m in masses) / m0
    print("mass: %d snapshots, max relative deviation from rho0 V = %.1e" % (len(masses), drift))
    if drift > 1e-12:
        failures.append("mass not conserved: %.2e" % drift)
    print("kinetic energy: end/peak = %.2e" % (ke[-1] / ke.max()))
    if ke[-1] > 1e-3 * ke.max():
        failures.append("flow not at rest: KE end/peak = %.2e" % (ke[-1] / ke.max()))
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(8, 3))
        ax.scatter(x_end[:, 0], x_end[:, 2], s=1)
        ax.axvline(L + fit * L, color="k", ls="--", label="Lube et al. 2005 fit")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
        ax.set_aspect("equal")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=100)
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("OK: column collapse within the experimental runout band, at rest, mass conserved")


if __name__ == "__main__":
    main()
