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
  travel: an arrow up from its point (a fixed share of the panel's height), and a note in the
  table (fits.json: still_moving). A travel the flume's end wall cut short (cube_at_end) is a
  grey triangle with an arrow, in no fit.
- Fig 18: the cube's largest kinetic energy over the flow's initial potential energy,
  E_k,max^b / E_p,0^f, against L0/h_b for each AR (paper: below 0.4 % in every case; our E_p,0^f
  is zero at the bed under the column's upstream end), and beside it the time of the flow's
  kinetic-energy peak in the coupled run (Fig 17: about 0.38 s for AR 3.0 at L0/h_b 4 and 24).
  Runs recorded before these energies were kept are left out of both.
- Fig 17: the energies of each case over time, over the flow's initial potential energy E_p,0^f:
  E_p^f, E_k^f, the energy dissipated E_d^f (the balance E_p,0^f - E_p^f - E_k^f - E_k^b) and the
  cube's E_k^b (paper, AR 3.0 at 4.5 s: E_d^f 77 % at L0/h_b 4, 73 % at 24; E_p^f is zero at the
  bed under the column's upstream end, a datum the paper does not give) ->
  parametric_study_energy.png.
- Fig 15 (``--views CASE_FOLDER``, a case the driver ran, `examples/parametric_study.py
  --run-prepared`): top and side views of the coupled run's particle snapshots around the cube,
  coloured by speed, the cube's outline drawn from its position and rotation, and the flow's
  height over the cube against h_b (paper, Fig 15a: 2.31 for AR 1.3, L0/h_b 4 at 0.5 s; Fig 15c:
  0.31 for AR 1.3, L0/h_b 54) -> views_CASE.png beside the folder.

    python3 examples/parametric_study_summary.py [--results results/parametric_study]
    python3 examples/parametric_study_summary.py --views DIR/AR=3_L0hb=4_full [--times 0.5,1,4.5]

Reads the sweep's store (runs.jsonl) and the per-case JSON files of yade-batch jobs in the
folder; writes parametric_study.png, parametric_study_energy.png, fits.json and cases.md (every
case's flow, travel and forces in one markdown table, with the fits beside the paper's) there.
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


# Fig 19's Pearson r of S_b/L0 against Fr and against Fr1, by submersion group (§5.4)
PAPER_R = {"Fr": {"complete": 0.02, "partial": -0.11}, "Fr1": {"complete": 0.91, "partial": 0.83}}
# Fig 17's dissipated energy at 4.5 s, by (AR, L0/h_b) (§5.3)
PAPER_DISSIPATED = {(3.0, 4): 0.77, (3.0, 24): 0.73}
HALF_WINDOW = 8  # Fig 15's views reach this many h_b up- and downstream of the cube
# Fig 15's flow height over the cube against h_b, by (AR, L0/h_b): (value, time [s] or None: the largest)
PAPER_HEIGHT = {(1.3, 4): (2.31, 0.5), (1.3, 54): (0.31, None)}
# the study's flume and flow (examples/parametric_study.py): width [m], incline [deg], bulk density
FLUME_WIDTH, INCLINE_DEG, FLOW_DENSITY = 0.2, 10.0, 1600.0


def potentialPerMetre(r):
    """What E_p,0^f of run r gains [J] for each metre down the bed its zero of potential energy
    moves: the flow's weight times the bed's drop per metre."""
    return r["L_i"] * r["H_i"] * FLUME_WIDTH * FLOW_DENSITY * 9.81 * math.sin(math.radians(INCLINE_DEG))


def paperDatum(runs):
    """Where the paper's zero of potential energy would lie for its Fig 17 shares: E_d^f/E_p,0^f
    of 77 % and 73 % at 4.5 s (AR 3.0 at L0/h_b 4 and 24), with E_p^f zero on the bed that far
    downstream of the cube's upstream face [m] (ours is zero under the column's upstream end; a
    lower zero adds M g H to E_p,0^f and leaves E_d^f as it is). One distance per case run to
    4.5 s, or {} without them."""
    out = {}
    for r in runs:
        share = PAPER_DISSIPATED.get((round(r["AR"], 2), r["L0_hb"]))
        if not share or "flow_potential_0" not in r or r["energy"]["t"][-1] < 4.5 - 0.01:
            continue
        gained = r["flow_dissipated_end"] * r["flow_potential_0"] / share - r["flow_potential_0"]
        out[(round(r["AR"], 2), r["L0_hb"])] = gained / potentialPerMetre(r) - (r["L_i"] + r["L0"])
    return out


def blockShareAgainst(r, beyond):
    """E_k,max^b over E_p,0^f with the zero of potential energy on the bed `beyond` [m] past the
    cube's upstream face."""
    return r["block_kinetic_max"] / (r["flow_potential_0"] + potentialPerMetre(r) * (r["L_i"] + r["L0"] + beyond))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--results", default="results/parametric_study", help="folder of the study's results")
    ap.add_argument("--views", metavar="CASE_FOLDER", default=None,
                    help="Fig 15: top and side views of one case the driver ran (its coupled/mpm.h5 snapshots)")
    ap.add_argument("--times", default="0.5,1,2,4.5",
                    help="--views: the snapshot times to show [s], comma-separated (the nearest snapshot each; "
                         "default 0.5,1,2,4.5)")
    a = ap.parse_args()
    if a.views:
        path, heights = views(a.views, [float(t) for t in a.times.split(",")])
        for t, h in heights:
            print("t = %.3f s: the flow's height over the cube %.2f h_b" % (t, h))
        print("views: %s" % path)
        return
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
                 " (travel cut short by the end wall: not in the travel fits)" if not travelled(r) else
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
    # the peak over 50 ms (results collected since it was recorded): past the blow's first
    # 10-20 ms, whose size the flow's Young's modulus sets
    longer = [r for r in forced if "peak_force_50ms" in r]
    if longer:
        eq21Long = analysis.fitImpactForceRatio([r["free_flow"]["Fr"] for r in longer],
                                                [r["peak_force_50ms"] / r["static_force"] for r in longer], k=K_STATIC)
        fits["eq21_peak_50ms"] = eq21Long
        print("Eq 21 fit with the 50 ms peak: alpha_f = %.3f at k = %.1f (%d runs; F_peak over 50 ms / F_peak over "
              "10 ms: %s)" % (eq21Long["alphaF"], eq21Long["k"], eq21Long["n"],
                              ", ".join("%.2f" % (r["peak_force_50ms"] / r["peak_force"]) for r in longer)))
    for xname in ("Fr", "Fr1"):
        text = ", ".join("%s: %s" % (g, "r = %.2f (n %d)" % (f["r"], f["n"]) if f else "too few runs")
                         for g, f in fits[xname].items())
        print("S_b/L0 against %s: %s (paper, complete / partial: r = %s)"
              % (xname, text, " / ".join("%g" % PAPER_R[xname][g] for g, *_ in GROUPS)))

    withEnergy = sorted((r for r in runs if "energy" in r), key=lambda r: (r["AR"], r["L0_hb"]))
    for r in withEnergy:
        paper = PAPER_DISSIPATED.get((round(r["AR"], 2), r["L0_hb"]))
        print("%5.2f %6g   E_d^f/E_p,0^f %.1f %% at %.2f s%s" % (
            r["AR"], r["L0_hb"], 100 * r["flow_dissipated_end"], r["energy"]["t"][-1],
            " (paper: %.0f %% at 4.5 s)" % (100 * paper) if paper else ""))
    datum = paperDatum(withEnergy)
    if datum:
        beyond = sum(datum.values()) / len(datum)
        fits["paper_datum_beyond_cube"] = {"%g/%g" % k: v for k, v in datum.items()}
        print("Fig 17's shares hold with E_p^f zero on the bed %s m beyond the cube's upstream face (AR/L0_hb: %s); "
              "E_k,max^b/E_p,0^f against that zero (mean %.2f m): %s (paper: < 0.4 %%)" % (
                  " and ".join("%.2f" % v for v in datum.values()), ", ".join("%g/%g" % k for k in datum), beyond,
                  ", ".join("%g/%g %.2f %%" % (r["AR"], r["L0_hb"], 100 * blockShareAgainst(r, beyond))
                            for r in runs if "block_kinetic_max" in r and "flow_potential_0" in r)))
    png, js = os.path.join(a.results, "parametric_study.png"), os.path.join(a.results, "fits.json")
    plot(runs, fits, png)
    if withEnergy:
        energyPlot(withEnergy, os.path.join(a.results, "parametric_study_energy.png"))
    with open(js, "w") as f:
        json.dump(fits, f, indent=1)
    md = os.path.join(a.results, "cases.md")
    with open(md, "w") as f:
        f.write(casesTable(runs, fits))
    print("plot: %s; fits: %s; table: %s" % (png, js, md))


def cell(r, key, form):
    """A run's value in a table cell, or a dash where the run has none."""
    v = r.get(key)
    return form % v if v is not None and finite(v) else "–"


def casesTable(runs, fits):
    """Every case of ``runs`` in one markdown table (AR, then L0/h_b), the way its travel counts
    in the fits (cut short by the end wall; still carried at the run's end: a lower bound), and
    the fits of ``fits`` beside the paper's."""
    head = ("| AR | L0/h_b | h_f [m] (h_f/h_b) | v_f [m/s] | Fr | Fr1 | S_b/L0 (S_b [m]) | rotation [°] | "
            "speed at the end [m/s] | F_peak [N] | F_static: force over the last 0.1 s [N] | "
            "F_peak/F_static (the paper's Eq 21 fit) | "
            "submersion | travel |")
    lines = [head, "|" + "---:|" * 12 + "---|---|"]
    for r in sorted(runs, key=lambda r: (r["AR"], r["L0_hb"])):
        ff = r["free_flow"]
        ratio = cell(r, "force_ratio", "%.1f")
        paper = analysis.impactForceRatio(ff["Fr"], k=K_STATIC)
        how = ("cut short by the end wall (in no fit)" if not travelled(r) else
               "still carried: a lower bound" if moving(r) else "at rest")
        lines.append("| %.1f | %g | %.4f (%.2f) | %.2f | %.2f | %.2f | %.2f (%.2f) | %s | %s | %.1f | %s | %s (%.2f) | %s | %s |"
                     % (r["AR"], r["L0_hb"], ff["h_f"], ff["h_f"] / r["h_b"], ff["v_f"], ff["Fr"], ff["Fr1"],
                        r["travel_L0"], r["travel"], cell(r, "rotation_deg", "%.0f"), cell(r, "speed_end", "%.2f"),
                        r["peak_force"], cell(r, "static_force", "%.2f"), ratio, paper, r["submersion"], how))
    lines.append("")
    eq21 = fits.get("eq21")
    if eq21:
        lines.append("Eq 21 fit: α_f %.2f at k %.1f over %d cases with a static force (the paper: 0.18)."
                     % (eq21["alphaF"], eq21["k"], eq21["n"]))
    for xname in ("Fr1", "Fr"):
        text = "; ".join("%s: %s (the paper: %g)" % (g, "r = %.2f, n %d" % (f["r"], f["n"]) if f else "too few cases",
                                                    PAPER_R[xname][g])
                         for g, f in fits[xname].items())
        lines.append("S_b/L0 against %s: %s." % (xname, text))
    return "\n".join(lines).replace(" -", " −") + "\n"


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

    # A lower bound's arrow rises by a share of the panel's height, not of its own travel: a short
    # travel's arrow would be too small to see beside a long one.
    highest = max([r["travel_L0"] for r in runs if finite(r.get("travel_L0", float("nan")))] + [1e-9])
    rise = 0.08 * highest
    for a, xname, title in ((ax[1, 0], "Fr", "Fig 19a"), (ax[1, 1], "Fr1", "Fig 19b")):
        for (group, marker, face, label), color in zip(GROUPS, ("C1", "C2")):
            sel = [r for r in runs if r["submersion"] == group and travelled(r)]
            x = [r["free_flow"][xname] for r in sel]
            a.plot(x, [r["travel_L0"] for r in sel], marker, mfc=face or color, color=color, ls="none")
            for r in sel:
                if moving(r):  # a lower bound: the cube was still carried when the run ended
                    a.annotate("", xy=(r["free_flow"][xname], r["travel_L0"] + rise),
                               xytext=(r["free_flow"][xname], r["travel_L0"]),
                               arrowprops=dict(arrowstyle="->", color=color))
            f = fits[xname][group]
            if f:
                xs = np.linspace(min(x), max(x), 2)
                a.plot(xs, f["slope"] * xs + f["intercept"], "-", color=color,
                       label="%s: r = %.2f" % (label.split(" (")[0], f["r"]))
        # travels the end wall cut short: shown as lower bounds, in no fit
        cut = [r for r in runs if r.get("reached", True) and not travelled(r)]
        for r in cut:
            a.annotate("", xy=(r["free_flow"][xname], r["travel_L0"] + rise), xytext=(r["free_flow"][xname], r["travel_L0"]),
                       arrowprops=dict(arrowstyle="->", color="0.6"))
        a.set_ylim(top=max(a.get_ylim()[1], highest + 1.5 * rise))  # the highest arrow in view
        if cut:
            a.plot([r["free_flow"][xname] for r in cut], [r["travel_L0"] for r in cut], "^", color="0.6", mfc="none",
                   ls="none", label="cut short by the end wall (not fitted)")
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


def energyPlot(runs, path):
    """Fig 17 for every case with its energy series: one panel a case."""
    cols = min(4, len(runs))
    rows = (len(runs) + cols - 1) // cols
    fig, ax = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    for a, r in zip(ax.flat, runs):
        e = r["energy"]
        for key, label, color in (("flow_potential", "E_p^f", "C0"), ("flow_kinetic", "E_k^f", "C1"),
                                  ("dissipated", "E_d^f", "C3")):
            a.plot(e["t"], e[key], color=color, label=label)
        a.plot(e["t"], [100 * b for b in e["block_kinetic"]], color="C2", label="E_k^b × 100")
        paper = PAPER_DISSIPATED.get((round(r["AR"], 2), r["L0_hb"]))
        if paper:
            a.plot([4.5], [paper], "k*", ms=10, label="paper's E_d^f at 4.5 s")
        a.axvline(0.38, color="k", ls=":", lw=0.8)
        a.set_title("AR %.2f, L0/h_b %g (%s)" % (r["AR"], r["L0_hb"], r["submersion"]), fontsize=9)
        a.set_xlabel("t [s]")
        a.set_ylabel("E / E_p,0^f")
    for a in ax.flat[len(runs):]:
        a.axis("off")
    ax.flat[0].legend(fontsize=7)
    fig.suptitle("Energies over the flow's initial potential energy (Fig 17; dotted: the paper's kinetic peak, "
                 "0.38 s)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def flowHeightOver(x, cube, hb):
    """The flow's height over the cube: the highest point z [m] within h_b/2 of the cube's
    centre in x and y (the flume frame, z up from the bed), or 0 when none is there."""
    near = (np.abs(x[:, 0] - cube[0]) < hb / 2) & (np.abs(x[:, 1] - cube[1]) < hb / 2)
    return float(x[near, 2].max()) if near.any() else 0.0


def cubeOutline(centre, rotation, hb, axes):
    """The outline of the cube (side hb, turned by the rotation vector) projected on two axes:
    the convex hull of its corners' projections, closed."""
    from scipy.spatial import ConvexHull
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float) * hb / 2
    angle = np.linalg.norm(rotation)
    if angle > 0:
        u = np.asarray(rotation) / angle
        K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        corners = corners @ (np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K).T
    p = (corners + centre)[:, axes]
    hull = ConvexHull(p).vertices
    return np.vstack([p[hull], p[hull[:1]]])


def views(case, times):
    """Fig 15 for one case folder the driver ran: top (x, y) and side (x, z) views of the
    coupled run's snapshots nearest ``times`` [s], the points coloured by speed; writes
    views_CASE.png beside the folder. Returns its path and, per snapshot shown, (time [s], the
    flow's height over the cube / h_b)."""
    import h5py
    case = os.path.normpath(case)
    folder = os.path.join(case, "coupled")
    with open(os.path.join(case, "case.json")) as f:
        meta = json.load(f)["result"]
    hb = meta["h_b"]
    with h5py.File(os.path.join(folder, "coupled.h5"), "r", locking=False) as f:
        t = f["series/time"][:]
        pos, rot = f["series/pos"][:], f["series/rotation"][:]
    block = next(k for k in range(pos.shape[1] // 3) if np.ptp(pos[:, 3 * k:3 * k + 3], axis=0).max() > 0)
    pos, rot = pos[:, 3 * block:3 * block + 3], rot[:, 3 * block:3 * block + 3]
    snaps = []
    with h5py.File(os.path.join(folder, "mpm.h5"), "r", locking=False) as f:
        stored = [(float(f["snapshots"][k].attrs["time"]), k) for k in f["snapshots"]]
        if not stored:
            raise SystemExit("%s: no particle snapshots in coupled/mpm.h5" % case)
        for want in times:
            tt, key = min(stored, key=lambda s: abs(s[0] - want))
            if any(key == k for k, *_ in snaps):
                continue
            g = f["snapshots"][key]
            snaps.append((key, tt, g["x"][:], np.linalg.norm(g["v"][:], axis=1)))
    # Each panel follows the cube, HALF_WINDOW h_b up- and downstream of it, drawn to scale: its
    # height follows the flume's width and the flow's height there.
    window = []
    for key, tt, x, v in snaps:
        c = pos[int(np.abs(t - tt).argmin()), 0]
        window.append((c - HALF_WINDOW * hb, c + HALF_WINDOW * hb))
    width = max(float(np.ptp(x[:, 1])) for _, _, x, _ in snaps) + hb
    top = 1.05 * max(float(x[(x[:, 0] > lo) & (x[:, 0] < hi), 2].max(initial=hb))
                     for (_, _, x, _), (lo, hi) in zip(snaps, window))
    inch = 4.8 / (2 * HALF_WINDOW * hb)
    fig, ax = plt.subplots(2, len(snaps), figsize=(4.8 * len(snaps) + 1.5, inch * (width + top) + 2.0),
                           squeeze=False, gridspec_kw={"height_ratios": [width, top]}, constrained_layout=True)
    vmax = max(float(np.percentile(v, 99)) for *_, v in snaps) or 1.0
    heights = []
    for c, (key, tt, x, v) in enumerate(snaps):
        i = int(np.abs(t - tt).argmin())
        lo, hi = window[c]
        sel = (x[:, 0] > lo) & (x[:, 0] < hi)
        height = flowHeightOver(x, pos[i], hb) / hb
        heights.append((tt, height))
        for r, (axes, ylabel) in enumerate((((0, 1), "y [m]"), ((0, 2), "z [m]"))):
            a = ax[r, c]
            im = a.scatter(x[sel, axes[0]], x[sel, axes[1]], c=v[sel], s=0.2, cmap="viridis", vmin=0, vmax=vmax,
                           rasterized=True)
            a.plot(*cubeOutline(pos[i], rot[i], hb, list(axes)).T, color="#e6b800", lw=1.5, ls="--")
            a.set_xlim(lo, hi)
            if axes[1] == 2:
                a.set_ylim(0, top)
            a.set_aspect("equal")
            a.set_xlabel("x [m]")
            a.set_ylabel(ylabel)
        ax[0, c].set_title("t = %.2f s: height over the cube %.2f h_b" % (tt, height), fontsize=9)
    fig.colorbar(im, ax=ax, label="speed [m/s]", shrink=0.8)
    paper = PAPER_HEIGHT.get((round(meta["AR"], 2), meta["L0_hb"]))
    fig.suptitle("AR %.2f, L0/h_b %g: top and side views (Fig 15%s)" % (
        meta["AR"], meta["L0_hb"], "; paper: %.2f h_b%s" % (paper[0], " at %.1f s" % paper[1] if paper[1] else
                                                           ", largest") if paper else ""), fontsize=10)
    path = os.path.join(os.path.dirname(case), "views_%s.png" % os.path.basename(case))
    fig.savefig(path, dpi=100)
    return path, heights


if __name__ == "__main__":
    main()
