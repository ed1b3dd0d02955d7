#!/usr/bin/env python3
"""Table and plot of the yade-batch sweep of examples/sliding_block.py (paper Fig 5):
reads results/sliding_*.json, prints S_b against Eq 19, writes results/sliding_block.png."""
import glob
import json

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

runs = sorted((json.load(open(p)) for p in glob.glob("results/sliding_*.json")), key=lambda r: (r["mu"], r["theta"]))
if not runs:
    raise SystemExit("no results/sliding_*.json: run the yade-batch sweep first (see examples/sliding_block.py)")
print("%6s %5s %10s %10s %8s" % ("theta", "mu", "S[m]", "Eq19[m]", "error"))
fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for r in runs:
    print("%6g %5g %10.5f %10.5f %+7.2f%%" % (r["theta"], r["mu"], r["distance"], r["eq19"], 100 * r["relative_error"]))
    ax = axes[0 if r["mu"] == 0 else 1]
    t, s, ref = zip(*r["series"])
    ax.plot(t, s, "o", ms=3, label="θ = %g°" % r["theta"])
    ax.plot(t, ref, "k-", lw=0.8)
for ax, mu in zip(axes, (0, 0.1)):
    ax.set_title("μ_b = %g (lines: Eq 19)" % mu)
    ax.set_xlabel("t [s]")
    ax.legend()
axes[0].set_ylabel("S_b [m]")
fig.tight_layout()
fig.savefig("results/sliding_block.png", dpi=100)
print("plot: results/sliding_block.png")
