#!/usr/bin/env python3
"""Paper §5: a glass-bead column released in the inclined flume hits a 0.05 m copper cube;
20 runs over the column's aspect ratio AR = H_i/L_i (1.3 to 4.0) and the block-to-column
distance L0 (4 to 74 h_b). Each run is the paper's pair of simulations: a free flow without
the cube (flow depth h_f and velocity v_f at the cube's station when the front arrives,
Fr = v_f/√(g h_f), Fr1 = v_f/√(g L0)), then the coupled run (travel S_b, peak and static
flow force on the cube).

One case (defaults AR = 1.3, L0/h_b = 4):
    yade -n -x examples/parametric_study.py            (or /usr/bin/python3 ...)
The 20 cases with yade-batch, one YADE process per table line, 2 at a time:
    yade-batch -j 2 --job-threads=1 examples/parametric_study.table examples/parametric_study.py
The 20 cases through mpmsdem.sweep (resumable store, retries, progress; local processes or a
Dask cluster):
    python3 examples/parametric_study.py --sweep --workers 2
    python3 examples/parametric_study.py --sweep --scheduler tcp://HOST:8786
Then: python3 examples/parametric_study_summary.py     (Figs 14, 16b, 19a, 19b)

Resolution: coarse by default (dx = 0.02 m, 8 points per cell); table column ``full = 1`` or
``--full``: the paper's (dx = 0.01 m). A coarse case takes from 6 minutes on one core (AR 1.3,
L0/h_b 4, 24,000 material points) to about an hour (AR 4, L0/h_b 74: 72,000 points in a 5 m
flume); the paper's resolution about 16 times more.

Set-up (our reading of §5 and §3.2): the §3.2 flume (width 0.2 m, incline 10°, glass beads
of Table 1, basal friction 0.21, no gate: the column starts free) with a column of length
L_i = 0.3 m and height H_i = AR · L_i (rounded to the grid: the coarse grid makes AR = 1.3 a
column of 0.40 m, AR 1.33; the reported AR is the one simulated), the cube's upstream face at
L_i + L0, and a flume long enough for the flow to pass it: L_i + L0 + h_b + ``margin``.
"""
import argparse
import json
import os
import sys
import time

HB = 0.05          # cube side h_b [m] (paper §5)
COLUMN = 0.3       # column length L_i [m] (the §3.2 storage container)
RHO = 1600.0       # bulk density of the glass beads [kg/m³] (Table 1)
K_STATIC = 1.6     # static pressure coefficient of the paper's Eq 21 fit
HERE = os.path.dirname(os.path.abspath(__file__))


def resolution(full, dx=None, ppc=None):
    """(dx [m], points per cell) of a run: coarse (0.02, 8) or, with ``full``, the paper's (0.01, 8)."""
    dx = dx or (0.01 if full else 0.02)
    if not dx > 0:
        raise ValueError("dx = %r m: must be > 0" % (dx,))
    return dx, ppc or 8


def runCase(AR, L0_hb, full=0, dx=None, ppc=None, settle=1.5, margin=1.0, maxFreeTime=5.0, output=None,
            backend="cpu", precision="double", verbose=False):
    """One case of the study: free flow, then the coupled run. Returns a dict of the results.

    :param AR: aspect ratio H_i / L_i of the column [-], > 0 (paper: 1.3 to 4.0).
    :param L0_hb: block-to-column distance L0 in cube heights [-], > 0 (paper: 4 to 74).
    :param full: 0 (default): coarse grid; 1: the paper's resolution.
    :param dx: grid spacing [m] (default 0.02, full 0.01); :param ppc: points per cell (8).
    :param settle: coupled run lasts until the front's arrival + settle [s] (default 1.5);
        the static force is the mean flow force on the cube over its last 0.1 s.
    :param margin: flume length downstream of the cube [m] (default 1.0).
    :param maxFreeTime: the free flow gives up after this [s] (default 5).
    :param output: folder for the coupled run's HDF5 and ParaView files (default none).
    :param backend, precision: MPM backend ("cpu"/"cuda") and precision ("double"/"float").
    """
    import mpmsdem  # before yade: it finds YADE's folder in a plain python3
    from yade import O
    from mpmsdem import analysis
    from mpmsdem.flume import Block, Flume
    from mpmsdem.mpm import PAPER_VISCOSITY
    if not (AR > 0 and L0_hb > 0):
        raise ValueError("AR = %r, L0_hb = %r: both must be > 0" % (AR, L0_hb))
    dx, ppc = resolution(full, dx, ppc)
    H = round(max(1, round(AR * COLUMN / dx)) * dx, 12)  # the column's top on a grid line
    L0 = L0_hb * HB
    station = COLUMN + L0
    length = COLUMN + L0 + HB + margin
    # the paper's blend (α 0.99 per 5e-6 s, 2010 /s) at the paper's resolution (docs/physics.md)
    common = dict(length=length, columnLength=COLUMN, columnHeight=H, dx=dx, ppc=ppc, backend=backend,
                  precision=precision, verbose=verbose, flipViscosity=PAPER_VISCOSITY if full else None)
    out = {"AR": round(H / COLUMN, 6), "AR_nominal": AR, "L0_hb": L0_hb, "L0": L0, "h_b": HB, "H_i": H, "L_i": COLUMN,
           "dx": dx, "ppc": ppc, "flume_length": length}

    t0 = time.time()
    scene = Flume(**common)
    out["particles"] = scene.mpm.numParticles
    out["flip_blend"] = scene.flipBlend()
    probe = analysis.FlowProbe(station, halfWidth=dx, bedZ=0.0, L0=L0, window=0.05)
    front, frontAt = 0.0, 0.0
    while True:
        mpmsdem.run(max(1, int(round(0.005 / O.dt))), scene.coupled)
        p = scene.mpm.particles()
        probe.sample(O.time, p)
        if probe.arrival is not None and O.time > probe.arrival + probe.window:
            break
        x = float(p["x"][:, 0].max())
        if x > front + 0.5 * dx:
            front, frontAt = x, O.time
        if O.time - frontAt > 0.3 or O.time > maxFreeTime:  # the flow stopped short of the station
            out.update(reached=False, front=front, stopped_at=O.time, wall_seconds={"free_flow": time.time() - t0})
            return out
    ff = probe.result()
    out.update(reached=True, free_flow=ff, submersion=analysis.submersion(ff["h_f"], HB))
    tFree = time.time() - t0

    t1 = time.time()
    cube = Block(half=(HB / 2,) * 3, x=station, density=8900, friction=0.67, flowFriction=0.21)
    scene = Flume(blocks=[cube], output=output, outputEvery=0.01, vtkEvery=0.05 if output else None, **common)
    duration = ff["arrival"] + settle
    scene.run(duration, sampleEvery=0.002)
    s = scene.series(0)
    peak, tPeak = scene.peakForce(0, smooth=0.01)
    late = s["t"] >= s["t"][-1] - 0.1
    static = float(s["Ft"][late].mean())
    A = min(ff["h_f"], HB) * HB  # impact area: the flow's depth on the cube's face, at most its height
    travel = scene.travel(0)
    # A cube carried to the flume's end has a travel cut short by the end wall: flagged, and
    # left out of the travel fits by the summary (give such a case a larger margin).
    atEnd = station + travel + HB > length - 0.1
    out.update(travel=travel, travel_L0=travel / L0, cube_at_end=atEnd, duration=duration, peak_force=peak,
               peak_time=tPeak,
               static_force=static, force_ratio=peak / static if static > 0 else None,
               static_force_model=analysis.staticImpactForce(RHO, ff["h_f"], A, k=K_STATIC),
               eq20_force=analysis.hydrodynamicForce(RHO, ff["v_f"], ff["h_f"], A),
               rotation_deg=float(s["rotation"][-1]),
               wall_seconds={"free_flow": tFree, "coupled": time.time() - t1})
    return out


def caseName(AR, L0_hb, full=0):
    return "AR=%g_L0hb=%g%s" % (AR, L0_hb, "_full" if full else "")


def readTable(path):
    """The table's lines as parameter dicts (read as yade-batch reads them)."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade.utils import TableParamReader
    rows = []
    for _, row in sorted(TableParamReader(path).paramDict().items()):
        case = {}
        for k, v in row.items():
            if k == "description":
                continue
            try:
                f = float(v)
            except ValueError:
                raise ValueError("%s: %s = %r is not a number" % (path, k, v)) from None
            case[k] = int(f) if f.is_integer() and "." not in v else f
        rows.append(case)
    return rows


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sweep", action="store_true", help="run the table's cases through mpmsdem.sweep")
    ap.add_argument("--table", default=os.path.join(HERE, "parametric_study.table"),
                    help="cases, one per line (default: the 20 of examples/parametric_study.table)")
    ap.add_argument("--full", action="store_true", help="the paper's resolution (dx 0.01 m) for every case")
    ap.add_argument("--workers", type=int, default=1, help="local runs at a time (default 1)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask scheduler address (tcp://host:8786): run the cases on its workers instead")
    ap.add_argument("--retries", type=int, default=2, help="extra attempts of a failed case (default 2)")
    ap.add_argument("--timeout", type=float, default=None, help="limit of one case [s] (default none)")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each case (default 1)")
    ap.add_argument("--out", default="results/parametric_study",
                    help="results folder: the sweep's store runs.jsonl, or one JSON file per case")
    ap.add_argument("--AR", type=float, default=None, help="one case: aspect ratio (default 1.3)")
    ap.add_argument("--L0-hb", type=float, default=None, help="one case: L0 / h_b (default 4)")
    return ap.parse_known_args(argv)[0]


def sweepMain(a):
    from mpmsdem import sweep
    cases = readTable(a.table)
    if a.full:
        cases = [dict(c, full=1) for c in cases]
    store = os.path.join(a.out, "runs.jsonl")
    records = sweep.runAll("%s:runCase" % os.path.abspath(__file__), cases, store, workers=a.workers,
                           scheduler=a.scheduler, retries=a.retries, timeout=a.timeout, threads=a.threads,
                           describe=lambda r: _describe(r["result"]))
    bad = sweep.failed(records)
    print("summary: python3 %s --results %s" % (os.path.join(HERE, "parametric_study_summary.py"), a.out))
    if bad:
        sys.exit("%d case(s) failed every attempt (errors above and in %s); re-run to retry them" % (len(bad), store))


def _describe(r):
    if not r.get("reached"):
        return "-> the flow stopped at x = %.2f m, short of the cube" % r["front"]
    ff = r["free_flow"]
    ratio = "%.2f" % r["force_ratio"] if r["force_ratio"] is not None else "- (no static force left on the cube)"
    return ("-> h_f %.3f m (%s), Fr %.2f, Fr1 %.2f, S_b %.3f m%s, F_peak/F_static %s"
            % (ff["h_f"], r["submersion"], ff["Fr"], ff["Fr1"], r["travel"],
               " (at the flume's end)" if r["cube_at_end"] else "", ratio))


def main(argv):
    a = parse(argv)
    if a.sweep:
        return sweepMain(a)
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade import utils
    # Table columns beyond AR, L0_hb and full are optional; 0 means runCase's default.
    utils.readParamsFromTable(AR=a.AR or 1.3, L0_hb=a.L0_hb or 4, full=1 if a.full else 0, dx=0, ppc=0, settle=1.5,
                              margin=1.0, noTableOk=True)
    from yade.params import table
    r = runCase(table.AR, table.L0_hb, full=table.full, dx=table.dx or None, ppc=table.ppc or None,
                settle=table.settle, margin=table.margin, verbose=True)
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, caseName(table.AR, table.L0_hb, table.full) + ".json")
    with open(path, "w") as f:
        json.dump(r, f, indent=1)
    print("%s %s; %s" % (caseName(table.AR, table.L0_hb, table.full), _describe(r), path))


if __name__ == "__main__":  # also under `yade -x` and yade-batch, which run scripts as __main__
    main(sys.argv[1:])
