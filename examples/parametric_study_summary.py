#!/usr/bin/env python3
"""Post-processing of the §5 parametric study (examples/parametric_study.py), as the paper's
Figs 14, 16b and 19:

- Fig 14: the cases over (L0/h_b, AR), coloured by h_f/h_b; open circles: the cube is
  completely submerged (h_f > h_b), filled: partially (h_f < h_b).
- Fig 16b: F_peak/F_static against Fr with the least-squares fit of Eq 21,
  F_peak/F_static = 1 + 2 α_f Fr²/k (α_f for the paper's k = 1.6), the paper's fit
  (k = 1.6, α_f = 0.18) and its bound (k = α_f = 1).
- Fig 19a, 19b: S_b/L0 against Fr and against Fr1 = v_f/√(g L0), with a line and Pearson's
  r for each submersion group (paper: r = 0.02 and −0.11 against Fr; 0.91 and 0.83 against Fr1).
  A cube still carried at the end of its run (faster than 0.05 m/s) has a lower bound for its
  travel: an arrow up from its point, and a note in the table (fits.json: still_moving).
- Fig 18: the cube's largest kinetic energy over the flow's initial potential energy,
  E_k,max^b / E_p,0^f, against L0/h_b for each AR (paper: below 0.4 % in every case; our E_p,0^f
  is zero at the bed under the column's upstream end), and beside it the time of the flow's
  kinetic-energy peak in the coupled run (Fig 17: about 0.38 s for AR 3.0 at L0/h_b 4 and 24).
  Runs recorded before these energies were kept are left out of both.

    python3 examples/parametric_study_summary.py [--results results/parametric_study]

Reads the sweep's store (runs.jsonl) and the per-case JSON files of yade-batch jobs in the
folder; writes parametric_study.png and fits.json there.
"""
import argparse
import glob
import json
import math
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mpmsdem import analysis, sweep  # noqa: E402

K_STATIC = 1.6  # the paper's static pressure coefficient: data fix only 2 α_f/k, α_f is quoted at this k
MOVING = 0.05     # a cube faster than this at the end of its run [m/s] is still carried: its travel a lower bound
GROUPS = (("complete", "o", "none", "completely submerged (h_f > h_b)"),
          ("partial", "s", None, "partially submerged (h_f < h_b)"))


def finite(v):
    """A usable force ratio: runs whose cube kept no static force have none (None, or NaN in
    older records)."""
    return v is not None and math.isfinite(v)


def load(folder):
    """The finished cases in ``folder``: the store's ok records, then the job files not
    already there (one per (AR, L0/h_b, dx))."""
    runs, seen = [], set()
    rows = [r["result"] for r in sweep.readStore(os.path.join(folder, "runs.jsonl")) if r["status"] == "ok"]
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        if os.path.basename(path) != "fits.json":
            with open(path) as f:
                rows.append(json.load(f))
    for r in rows:
        key = (r["AR"], r["L0_hb"], r.get("dx"))
        if key not in seen:
            seen.add(key)
            runs.append(r)
    return runs


def travelled(r):
    """Whether a run's travel counts: not cut short at the flume's end."""
    return not r.get("cube_at_end", False)


def moving(r):
    """Whether a run's cube was still carried at its end (its travel a lower bound)."""
    return r.get("speed_end") is not None and r["speed_end"] > MOVING


def fitGroups(runs, x):
    """Line and Pearson r of S_b/L0 against ``x`` (a function of a run) per submersion group;
    None for a group with fewer than two runs or no spread."""
    fits = {}
    for group, *_ in GROUPS:
        sel = [r for r in runs if r["submersion"] == group and travelled(r)]
        try:
            fits[group] = analysis.linearFit([x(r) for r in sel], [r["travel_L0"] for r in sel])
        except ValueError:
            fits[group] = None
    return fits


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--results", default="results/parametric_study", help="folder of the study's results")
    a = ap.parse_args()
    allRuns = load(a.results)
    if not allRuns:
        raise SystemExit("no results in %s: run the study first (see examples/parametric_study.py)" % a.results)
    runs = [r for r in allRuns if r.get("reached", True)]
    short = [r for r in allRuns if not r.get("reached", True)]
    print("%5s %6s %7s %7s %6s %6s %9s %8s %9s %s" % ("AR", "L0/hb", "h_f[m]", "v_f", "Fr", "Fr1", "S_b/L0",
                                                     "F_pk/F_st", "F_pk[N]", "submersion"))
    for r in sorted(runs, key=lambda r: (r["AR"], r["L0_hb"])):
        ff = r["free_flow"]
        ratio = "%8.2f" % r["force_ratio"] if finite(r["force_ratio"]) else "%8s" % "-"
        print("%5.2f %6g %7.4f %7.3f %6.2f %6.2f %9.4f %s %9.3f %s%s"
              % (r["AR"], r["L0_hb"], ff["h_f"], ff["v_f"], ff["Fr"], ff["Fr1"], r["travel_L0"], ratio,
                 r["peak_force"], r["submersion"],
                 " (cube at the flume's end: not in the travel fits)" if not travelled(r) else
                 " (still carried at %.2f m/s at the run's end: the travel a lower bound)" % r["speed_end"]
                 if moving(r) else ""))
    for r in sorted((r for r in runs if "block_kinetic_ratio" in r), key=lambda r: (r["AR"], r["L0_hb"])):
        print("%5.2f %6g   E_k,max^b/E_p,0^f %.2f %% (paper: < 0.4 %%) at %.3f s; flow kinetic peak %.1f J at %.3f s "
              "(paper, AR 3.0: ~0.38 s)" % (r["AR"], r["L0_hb"], 100 * r["block_kinetic_ratio"],
                                            r["block_kinetic_max_time"], r["flow_kinetic_max"],
                                            r["flow_kinetic_max_time"]))
    for r in short:
        print("%5.2f %6g   the flow stopped at x = %.2f m, short of the cube (not in the fits)"
              % (r["AR"], r["L0_hb"], r["front"]))

    forced = [r for r in runs if finite(r["force_ratio"])]
    eq21 = analysis.fitImpactForceRatio([r["free_flow"]["Fr"] for r in forced], [r["force_ratio"] for r in forced],
                                        k=K_STATIC) if forced else None
    fits = {"runs": len(allRuns), "stopped_short": len(short),
            "cube_at_end": sum(not travelled(r) for r in runs),
            "still_moving": sum(travelled(r) and moving(r) for r in runs), "eq21": eq21,
            "Fr": fitGroups(runs, lambda r: r["free_flow"]["Fr"]),
            "Fr1": fitGroups(runs, lambda r: r["free_flow"]["Fr1"])}
    if eq21:
        print("Eq 21 fit: alpha_f = %.3f at k = %.1f (2 alpha_f/k = %.4f, rms %.3f, %d runs; paper: alpha_f 0.18, "
              "k 1.6)" % (eq21["alphaF"], eq21["k"], eq21["slope"], eq21["rms"], eq21["n"]))
    for xname, paper in (("Fr", "0.02 / -0.11"), ("Fr1", "0.91 / 0.83")):
        text = ", ".join("%s: %s" % (g, "r = %.2f (n %d)" % (f["r"], f["n"]) if f else "too few runs")
                         for g, f in fits[xname].items())
        print("S_b/L0 against %s: %s (paper, complete / partial: r = %s)" % (xname, text, paper))

    png, js = os.path.join(a.results, "parametric_study.png"), os.path.join(a.results, "fits.json")
    plot(runs, fits, png)
    with open(js, "w") as f:
        json.dump(fits, f, indent=1)
    print("plot: %s; fits: %s" % (png, js))


def plot(runs, fits, path):
    fig, ax = plt.subplots(2, 3, figsize=(16, 8.5))
    a = ax[0, 0]
    hf = np.array([r["free_flow"]["h_f"] / r["h_b"] for r in runs])
    norm = matplotlib.colors.Normalize(hf.min(), hf.max())
    cmap = plt.get_cmap("viridis")
    for group, marker, face, label in GROUPS:
        sel = [(r, h) for r, h in zip(runs, hf) if r["submersion"] == group]
        colors = [cmap(norm(h)) for _, h in sel]
        a.scatter([r["L0_hb"] for r, _ in sel], [r["AR"] for r, _ in sel], s=80, linewidths=1.5, edgecolors=colors,
                  facecolors="none" if face else colors, label=label)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=a, label="h_f / h_b")
    a.set_xlabel("L0 / h_b")
    a.set_ylabel("AR = H_i / L_i")
    a.set_title("Cases (Fig 14)")
    a.legend(fontsize=8)

    a = ax[0, 1]
    Fr = np.linspace(0, max(r["free_flow"]["Fr"] for r in runs) * 1.1, 200)
    for group, marker, face, label in GROUPS:
        sel = [r for r in runs if r["submersion"] == group and finite(r["force_ratio"])]
        a.plot([r["free_flow"]["Fr"] for r in sel], [r["force_ratio"] for r in sel], marker, mfc=face or "C0",
               color="C0", ls="none", label=label)
    if fits["eq21"]:
        e = fits["eq21"]
        a.plot(Fr, analysis.impactForceRatio(Fr, k=e["k"], alphaF=e["alphaF"]), "C0-",
               label="Eq 21 fit: k = %.1f, α_f = %.3f" % (e["k"], e["alphaF"]))
    a.plot(Fr, analysis.impactForceRatio(Fr, k=1.6, alphaF=0.18), "k--", label="paper's fit: k = 1.6, α_f = 0.18")
    a.plot(Fr, analysis.impactForceRatio(Fr, k=1.0, alphaF=1.0), "k:", label="bound: k = 1, α_f = 1")
    ratios = [r["force_ratio"] for r in runs if finite(r["force_ratio"])]
    a.set_ylim(0, 1.2 * max(ratios + [analysis.impactForceRatio(Fr[-1])]))
    a.set_xlabel("Fr = v_f / √(g h_f)")
    a.set_ylabel("F_peak / F_static")
    a.set_title("Impact force (Fig 16b, Eq 21)")
    a.legend(fontsize=8)

    for a, xname, title in ((ax[1, 0], "Fr", "Fig 19a"), (ax[1, 1], "Fr1", "Fig 19b")):
        for (group, marker, face, label), color in zip(GROUPS, ("C1", "C2")):
            sel = [r for r in runs if r["submersion"] == group and travelled(r)]
            x = [r["free_flow"][xname] for r in sel]
            a.plot(x, [r["travel_L0"] for r in sel], marker, mfc=face or color, color=color, ls="none")
            for r in sel:
                if moving(r):  # a lower bound: the cube was still carried when the run ended
                    a.annotate("", xy=(r["free_flow"][xname], r["travel_L0"] * 1.12),
                               xytext=(r["free_flow"][xname], r["travel_L0"]),
                               arrowprops=dict(arrowstyle="->", color=color))
            f = fits[xname][group]
            if f:
                xs = np.linspace(min(x), max(x), 2)
                a.plot(xs, f["slope"] * xs + f["intercept"], "-", color=color,
                       label="%s: r = %.2f" % (label.split(" (")[0], f["r"]))
        a.set_xlabel("Fr = v_f / √(g h_f)" if xname == "Fr" else "Fr1 = v_f / √(g L0)")
        a.set_ylabel("S_b / L0")
        a.set_title("Travel distance (%s)" % title)
        a.legend(fontsize=8)
    energies = [r for r in runs if "block_kinetic_ratio" in r]
    for a, key, scale, ylabel, title in (
            (ax[0, 2], "block_kinetic_ratio", 100.0, "E_k,max^b / E_p,0^f [%]", "Cube's largest kinetic energy (Fig 18)"),
            (ax[1, 2], "flow_kinetic_max_time", 1.0, "t [s]", "Flow's kinetic-energy peak (Fig 17)")):
        for k, AR in enumerate(sorted({r["AR"] for r in energies})):
            sel = sorted((r for r in energies if r["AR"] == AR), key=lambda r: r["L0_hb"])
            a.plot([r["L0_hb"] for r in sel], [scale * r[key] for r in sel], "o-", color="C%d" % k, label="AR %.2f" % AR)
        a.set_xlabel("L0 / h_b")
        a.set_ylabel(ylabel)
        a.set_title(title)
    ax[0, 2].axhline(0.4, color="k", ls="--", label="paper: below 0.4 %")
    ax[1, 2].axhline(0.38, color="k", ls="--", label="paper: ~0.38 s (AR 3.0)")
    for a in ax[:, 2]:
        a.legend(fontsize=8)
    fig.suptitle("Parametric study (paper §5): %d runs" % len(runs))
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
