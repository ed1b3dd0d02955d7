#!/usr/bin/env python3
"""Our field flow against a depth-averaged peer, AvaFrame's com1DFA (opt-in, minutes a case).

One terrain (an ESRI ASCII or GeoTIFF DEM) and one release, run twice: by our MPM flow through
the field example's own machinery (``examples/field_valley.py --terrain DEM --blocks 0``: the
same material, basal friction, FLIP/PIC blend, seeding, time step and maps) and by AvaFrame 2.1's
dense-flow model com1DFA (SPH, depth-averaged, Coulomb friction), then compared on the DEM's
raster: runout along a path and the travel angle, deposit area, the deposit's thickness profile
along the path, its centroid and the centre-of-mass travel angle, the largest speed and the
arrival time at stations along the path. Writes ``comparison.md`` (the table), ``comparison.json``
and ``comparison.png`` (both deposits on one map, the thickness profiles and the front's arrival)
into ``--out``.

    /usr/bin/python3 scripts/validation/avaframe_peer.py --case valley|hockey|parabola|hockey-small
    /usr/bin/python3 scripts/validation/avaframe_peer.py --dem dem.asc --release X0 Y0 X1 Y1 \\
        --release-depth D [--path X Y X Y ...] [--dx 0.5] [--duration 30] [--out DIR]

(``PYTHONPATH=build/python`` before ``make install``.) AvaFrame runs in the virtual environment
``.venv-peers/`` at the repository root (made by ``tools/install-deps.sh``, which ``make test``
runs), as a subprocess of this script: our own code runs under the system Python with YADE,
which that environment does not have.

**The release** is the field example's source: a box over the plan X0..X1 × Y0..Y1 (map
coordinates, snapped outwards to our grid) from the ground up to ``--release-depth`` above the
highest ground under it (``--release-volume`` instead finds that depth for a volume). Our flow
seeds it with 8 points a cell; AvaFrame gets the same body as a release-thickness raster: at each
raster node the box's height above the ground times the share of the node's cell inside the
plan, scaled to the volume our seeding holds, and turned into AvaFrame's thickness normal to the
slope (times cos θ, θ the DEM's slope there), so both start from the same volume and shape.

**Friction.** AvaFrame's Coulomb coefficient (``--mu``) stands for our material's μ(I) at a stated
inertial number: μ(I) = μ_s + (μ_2 − μ_s)/(I_0/I + 1), I = γ̇ d/√(p/ρ_s). The default is the
quasi-static limit, μ_s (0.38 for the example's debris: 20.8°), because the field flows' inertial
numbers are small (d = 5 mm, p of 10–30 kPa, shear rates under 10 /s: I < 0.03, μ(I) < 0.40;
the script prints μ(I) at I = 1e-3, 1e-2, 3e-2). Our flow also has the ground's basal friction
(the example's 0.45, 24.2°, above μ_s, so the debris shears inside itself first); pass
``--mu 0.38 0.45`` to bracket. AvaFrame has no FLIP/PIC damping (its artificial viscosity, which
pulls each particle towards the grid's velocity, is the nearest relative of it); ours is stated with each run.

**Definitions** (h: thickness as volume per unit plan area, at the material's initial density
for ours, AvaFrame's slope-normal thickness divided by cos θ; thr = ``--threshold``):
runout = the farthest raster node along the path (arc length of its nearest point on the path)
with a final h ≥ thr; travel angle α = atan(drop / reach) from the release's highest ground node
to that node, reach along the path (farthest reach, in comparison.json: the same for the largest
h over time);
deposit area = the nodes with final h ≥ thr times the cell area; the profile = final h along the
path, read between nodes bilinearly; centroid = the h-weighted mean of the nodes (its height the
ground's plus h/2), the centre-of-mass travel angle atan(its drop / its travel along the path)
from the release's centroid (its tangent is the mean resistance along the way, an effective
friction: a Coulomb block on a plane gives μ, the load of the terrain's curvature and any other
dissipation add to it); the largest speed = the largest depth-averaged speed |Σmv|/Σm at a node
with h ≥ thr over the samples (every 0.1 s for both); the arrival at station s = the first sample at which
the flow is at least thr thick at a node at or beyond s along the path.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
EXAMPLE = os.path.join(ROOT, "examples", "field_valley.py")
VENV = os.path.join(ROOT, ".venv-peers")
AVAFRAME = "2.1"
SAMPLE = 0.1  # [s] between map samples: the field example's, and AvaFrame's saved steps here

# The cases. The valley is the field example's (examples/field_valley.py: Terrain.valley with its
# slope of 28 deg, flanks of 30 deg, 4 m floor and 34 m plain, raster 0.5 m, and its source, 6 x 8 m
# and 4 m above the highest ground under it, 18 m above the slope's foot), with 10 m more slope above
# the source, 10 m more plain and 4 m more flank on either side: the depth-averaged peer spreads the
# source sideways over the flanks and back up the slope, and its particles that leave the raster are
# lost. The others are AvaFrame's standard idealised topographies (in3Utils/generateTopo) made
# small and left without their channel: HS, an inclined plane at meanAlpha with a circular
# transition of radius rCirc into a flat run-out, and PF, a parabolic slope falling C metres over
# C/tan(meanAlpha) into a flat run-out; 100 x 60 m, 20 m high, a source 6 x 8 m and 2 m above the
# highest ground under it, 6 m below the top.
VALLEY = {"length": 80.0, "width": 24.0, "spacing": 0.5, "slope_deg": 28.0, "side_slope_deg": 30.0,
          "floor_width": 4.0, "runout": 44.0}
CASES = {
    "valley": {"dem": {"kind": "valley"}, "dx": 0.5, "duration": 20.0, "threshold": 0.1,
               "release": (12.0, 8.0, 18.0, 16.0), "depth": 4.0, "path": [(0.0, 12.0), (80.0, 12.0)],
               "stations": (20, 30, 40, 50, 60)},
    "hockey": {"dem": {"kind": "avaframe", "demType": "HS", "dx": 0.5, "xEnd": 100.0, "yEnd": 60.0,
                       "meanAlpha": 34.0, "z0": 20.0, "rCirc": 4.0},
               "dx": 0.5, "duration": 20.0, "threshold": 0.1, "release": (6.0, 26.0, 12.0, 34.0), "depth": 2.0,
               "path": [(0.0, 30.0), (100.0, 30.0)], "stations": (20, 25, 30, 35, 40, 45)},
    "parabola": {"dem": {"kind": "avaframe", "demType": "PF", "dx": 0.5, "xEnd": 100.0, "yEnd": 60.0,
                         "meanAlpha": 34.0, "C": 20.0},
                 "dx": 0.5, "duration": 20.0, "threshold": 0.1, "release": (6.0, 26.0, 12.0, 34.0), "depth": 2.0,
                 "path": [(0.0, 30.0), (100.0, 30.0)], "stations": (20, 25, 30, 35, 40, 45)},
    # the smallest: the hockey stick at half height on a 1 m raster and grid (tests/python/test_avaframe_peer.py)
    "hockey-small": {"dem": {"kind": "avaframe", "demType": "HS", "dx": 1.0, "xEnd": 50.0, "yEnd": 40.0,
                             "meanAlpha": 34.0, "z0": 10.0, "rCirc": 2.0},
                     "dx": 1.0, "duration": 12.0, "threshold": 0.25, "release": (4.0, 17.0, 8.0, 23.0),
                     "depth": 1.5, "path": [(0.0, 20.0), (50.0, 20.0)], "stations": (10, 15, 20, 25, 30)},
}


class PeerMissing(RuntimeError):
    pass


# ---------------------------------------------------------------------------------------------
# Analysis on rasters: node values v[i, j] at (x0 + i s, y0 + j s), i along x, j along y.

def nodes(shape, x0, y0, s):
    """The nodes' x and y [m], arrays of ``shape``."""
    return np.meshgrid(x0 + s * np.arange(shape[0]), y0 + s * np.arange(shape[1]), indexing="ij")


def pathLength(path):
    p = np.asarray(path, dtype=float)
    return float(np.hypot(*(p[1:] - p[:-1]).T).sum())


def projectOnPath(x, y, path):
    """Arc length s [m] along the polyline ``path`` ((n, 2), n >= 2) of the nearest point of the
    path to each point (x, y), and the distance to it. Points before its start or beyond its end
    get s = 0 or its length."""
    p = np.asarray(path, dtype=float)
    if p.ndim != 2 or p.shape[0] < 2 or p.shape[1] != 2:
        raise ValueError("path: needs at least two (x, y) points, got %r" % (path,))
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    seg = p[1:] - p[:-1]
    length = np.hypot(seg[:, 0], seg[:, 1])
    if (length <= 0).any():
        raise ValueError("path: two consecutive points coincide: %r" % (path,))
    start = np.concatenate([[0.0], np.cumsum(length)])
    best = np.full(np.broadcast(x, y).shape, np.inf)
    s = np.zeros_like(best)
    for k in range(len(seg)):
        t = np.clip(((x - p[k, 0]) * seg[k, 0] + (y - p[k, 1]) * seg[k, 1]) / length[k] ** 2, 0.0, 1.0)
        d = np.hypot(x - p[k, 0] - t * seg[k, 0], y - p[k, 1] - t * seg[k, 1])
        closer = d < best
        s = np.where(closer, start[k] + t * length[k], s)
        best = np.where(closer, d, best)
    return s, best


def pointsOnPath(path, step):
    """Points every ``step`` metres along the path from its start (its end included): (s, x, y)."""
    p = np.asarray(path, dtype=float)
    seg = p[1:] - p[:-1]
    length = np.hypot(seg[:, 0], seg[:, 1])
    start = np.concatenate([[0.0], np.cumsum(length)])
    s = np.arange(0.0, start[-1] + 1e-9 * step, step)
    if start[-1] - s[-1] > 1e-9 * step:
        s = np.append(s, start[-1])
    k = np.clip(np.searchsorted(start, s, side="right") - 1, 0, len(seg) - 1)
    t = (s - start[k]) / length[k]
    return s, p[k, 0] + t * seg[k, 0], p[k, 1] + t * seg[k, 1]


def bilinear(values, x0, y0, s, x, y):
    """``values`` on the nodes read at (x, y) between nodes bilinearly (clamped to the raster)."""
    nx, ny = values.shape
    u = np.clip((np.asarray(x, dtype=float) - x0) / s, 0.0, nx - 1.0)
    w = np.clip((np.asarray(y, dtype=float) - y0) / s, 0.0, ny - 1.0)
    i, j = np.minimum(u.astype(int), nx - 2), np.minimum(w.astype(int), ny - 2)
    fx, fy = u - i, w - j
    return ((1 - fx) * (1 - fy) * values[i, j] + fx * (1 - fy) * values[i + 1, j]
            + (1 - fx) * fy * values[i, j + 1] + fx * fy * values[i + 1, j + 1])


def profile(h, x0, y0, s, path, step=None):
    """The thickness along the path: (path coordinate [m], h [m]) every ``step`` (default the
    raster's spacing)."""
    sp, x, y = pointsOnPath(path, step or s)
    return sp, bilinear(h, x0, y0, s, x, y)


def farthest(h, heights, x0, y0, s, path, threshold):
    """The node with h >= threshold farthest along the path: {"s", "x", "y", "z"} (z the ground's),
    or None where no node is that thick."""
    X, Y = nodes(h.shape, x0, y0, s)
    m = h >= threshold
    if not m.any():
        return None
    sp, _ = projectOnPath(X[m], Y[m], path)
    k = int(np.argmax(sp))
    return {"s": float(sp[k]), "x": float(X[m][k]), "y": float(Y[m][k]), "z": float(heights[m][k])}


def releaseTop(release, heights, x0, y0, s, path):
    """The release's highest ground node (where the release thickness is > 0): {"s", "x", "y", "z"}."""
    X, Y = nodes(release.shape, x0, y0, s)
    m = release > 0
    if not m.any():
        raise ValueError("release: no node with a thickness > 0")
    k = int(np.argmax(np.where(m, heights, -np.inf)))
    i, j = np.unravel_index(k, release.shape)
    sp, _ = projectOnPath(X[i, j], Y[i, j], path)
    return {"s": float(sp), "x": float(X[i, j]), "y": float(Y[i, j]), "z": float(heights[i, j])}


def travelAngle(top, end):
    """atan(drop / reach) [deg] from ``top`` to ``end`` (dicts with "s", the path coordinate [m],
    and "z", the height [m]); NaN without an end or a reach."""
    if end is None or not end["s"] > top["s"]:
        return float("nan")
    return math.degrees(math.atan2(top["z"] - end["z"], end["s"] - top["s"]))


def depositArea(h, s, threshold):
    """Plan area [m²] of the nodes with h >= threshold (each a cell of s × s)."""
    return float((h >= threshold).sum() * s * s)


def centroid(h, heights, x0, y0, s, path):
    """The h-weighted centre of a deposit: {"x", "y", "z", "s"}: the mean of the nodes weighted
    by h, z the mean of ground + h/2 (the columns' centres), s its path coordinate."""
    X, Y = nodes(h.shape, x0, y0, s)
    w = np.where(h > 0, h, 0.0)
    total = w.sum()
    if not total > 0:
        return None
    c = {"x": float((w * X).sum() / total), "y": float((w * Y).sum() / total),
         "z": float((w * (heights + 0.5 * w)).sum() / total)}
    c["s"] = float(projectOnPath(c["x"], c["y"], path)[0])
    return c


def arrivalMap(times, series, threshold):
    """Per node, the first time at which series[k] (thickness at times[k]) is >= threshold and
    > 0; NaN where never."""
    reached = (series >= threshold) & (series > 0)
    first = np.argmax(reached, axis=0)
    return np.where(reached.any(axis=0), np.asarray(times, dtype=float)[first], np.nan)


def stationArrivals(arrival, sNodes, stations):
    """For each station s, the first arrival at a node at or beyond it along the path (NaN: never)."""
    out = []
    for st in stations:
        m = (sNodes >= st) & np.isfinite(arrival)
        out.append(float(arrival[m].min()) if m.any() else float("nan"))
    return out


def slopeCosine(heights, s):
    """cos θ of the DEM's slope at each node (central differences, one-sided at the edges)."""
    gx, gy = np.gradient(heights, s)
    return 1.0 / np.sqrt(1.0 + gx ** 2 + gy ** 2)


def muOfI(I, muS, mu2, I0):
    return muS + (mu2 - muS) / (I0 / I + 1.0)


def readAsc(path):
    """An ESRI ASCII grid: (values (nx, ny) with i along x and j from the south, NaN for no data,
    x0 and y0 of the first node (cell centre), spacing)."""
    header = {}
    with open(path) as f:
        while True:
            pos = f.tell()
            line = f.readline()
            parts = line.split()
            if len(parts) == 2 and re.match(r"^[A-Za-z_]+$", parts[0]):
                header[parts[0].lower()] = float(parts[1])
            else:
                f.seek(pos)
                break
        rows = np.loadtxt(f, ndmin=2)
    s = header["cellsize"]
    x0 = header["xllcenter"] if "xllcenter" in header else header["xllcorner"] + 0.5 * s
    y0 = header["yllcenter"] if "yllcenter" in header else header["yllcorner"] + 0.5 * s
    v = rows[::-1].T.astype(float)
    if "nodata_value" in header:
        v[v == header["nodata_value"]] = np.nan
    if v.shape != (int(header["ncols"]), int(header["nrows"])):
        raise ValueError("%s: %s values, the header says %d x %d" % (path, v.shape, header["ncols"], header["nrows"]))
    return v, x0, y0, s


# ---------------------------------------------------------------------------------------------
# AvaFrame, inside .venv-peers (this file run by the venv's Python with --peer-job JOB.json).

def peerMain(jobPath):
    with open(jobPath) as f:
        job = json.load(f)
    if job["action"] == "topo":
        return peerTopo(job)
    return peerRun(job)


def peerTopo(job):
    """A standard topography by AvaFrame's in3Utils/generateTopo, written to job["out"]."""
    import pathlib
    from avaframe.in3Utils import cfgUtils, generateTopo
    ava = pathlib.Path(job["work"])
    (ava / "Inputs").mkdir(parents=True, exist_ok=True)
    d = job["dem"]
    ini = ava / "generateTopo_peer.ini"
    ini.write_text("[TOPO]\ndemType = %s\ndx = %r\nxEnd = %r\nyEnd = %r\nmeanAlpha = %r\nz0 = %r\nrCirc = %r\nC = %r\n"
                   "channel = False\nnarrowing = False\ndam = False\ndrop = False\ncurvedSlope = False\n"
                   "[DEMDATA]\nxl = 0.0\nyl = 0.0\ndemName = DEM\n"
                   % (d["demType"], d["dx"], d["xEnd"], d["yEnd"], d["meanAlpha"], d.get("z0", 20.0),
                      d.get("rCirc", 4.0), d.get("C", 20.0)))
    cfg = cfgUtils.getModuleConfig(generateTopo, fileOverride=ini, toPrint=False)
    generateTopo.generateTopo(cfg, ava)
    made = list((ava / "Inputs").glob("DEM_%s_Topo.*" % d["demType"]))
    shutil.copy(made[0], job["out"])
    return 0


def peerRun(job):
    """com1DFA on job["work"] (Inputs/ with the DEM and REL/ with the release raster, as AvaFrame
    expects an avalanche folder), Coulomb friction job["mu"]; the thickness and speed every
    job["save"] s, the peaks and the mass over time, to job["out"] (.npz)."""
    import importlib.metadata
    import pathlib
    from avaframe.com1DFA import com1DFA
    from avaframe.in2Trans import rasterUtils
    from avaframe.in3Utils import cfgUtils, logUtils
    ava = pathlib.Path(job["work"])
    shutil.rmtree(ava / "Outputs", ignore_errors=True)
    shutil.rmtree(ava / "Work", ignore_errors=True)
    logUtils.initiateLogger(ava, "com1DFA_peer")
    cfgMain = cfgUtils.getGeneralConfig()
    cfgMain["MAIN"]["avalancheDir"] = str(ava)
    cfgMain["MAIN"]["nCPU"] = "1"
    for flag in ("showPlot", "savePlot", "createReport", "ReportDir", "reportOneFile"):
        cfgMain["FLAGS"][flag] = "False"
    ini = ava / "com1DFA_peer.ini"
    ini.write_text("[GENERAL]\n" + "".join("%s = %s\n" % kv for kv in job["cfg"].items()))
    cfg = cfgUtils.getModuleConfig(com1DFA, fileOverride=ini, toPrint=False)
    t0 = time.time()
    com1DFA.com1DFAMain(cfgMain, cfgInfo=cfg)
    wall = time.time() - t0
    out = ava / "Outputs" / "com1DFA"
    peak = out / "peakFiles"

    def read(path):
        r = rasterUtils.readRaster(path)
        return r["rasterData"].T, r["header"]  # (x, y), j from the south

    series = {"FT": {}, "FV": {}}
    for path in (peak / "timeSteps").glob("*.asc"):
        m = re.search(r"_(FT|FV)_t([0-9.]+)\.asc$", path.name)
        if m:
            series[m.group(1)][float(m.group(2))] = read(path)[0]
    times = sorted(set(series["FT"]) & set(series["FV"]))
    final, header = read(next(peak.glob("*_FT.asc")))
    massFile = next(out.glob("mass_*.txt"))
    mass = np.loadtxt(massFile, delimiter=",", skiprows=1, ndmin=2)
    logs = sorted(ava.glob("com1DFA_peer*.log"))
    text = logs[-1].read_text() if logs else ""
    parts = re.findall(r"MTot = ([0-9.eE+-]+) kg, (\d+) particles", text)
    np.savez_compressed(
        job["out"], times=np.array(times), FT=np.array([series["FT"][t] for t in times], dtype=np.float32),
        FV=np.array([series["FV"][t] for t in times], dtype=np.float32), final=final,
        pft=read(next(peak.glob("*_pft.asc")))[0], pfv=read(next(peak.glob("*_pfv.asc")))[0],
        x0=header["xllcenter"], y0=header["yllcenter"], spacing=header["cellsize"],
        massTime=mass[:, 0], mass=mass[:, 1], wall=wall, particles=int(parts[0][1]) if parts else -1,
        version=importlib.metadata.version("avaframe"))
    return 0


# ---------------------------------------------------------------------------------------------
# Ours and theirs, from the system Python.

def peerPython(venv):
    """The venv's interpreter with AvaFrame AVAFRAME importable, or PeerMissing saying how to get it."""
    py = os.path.join(venv, "bin", "python")
    how = ("run `make test` or `bash tools/install-deps.sh` (they create .venv-peers/ at the repository root with "
           "avaframe==%s from PyPI)" % AVAFRAME)
    if not os.path.exists(py):
        raise PeerMissing("AvaFrame's virtual environment is missing (%s has no bin/python): %s" % (venv, how))
    r = subprocess.run([py, "-c", "import importlib.metadata as m; import avaframe.com1DFA.com1DFA; "
                                  "print(m.version('avaframe'))"], capture_output=True, text=True)
    if r.returncode != 0:
        raise PeerMissing("AvaFrame does not import in %s (%s): %s"
                          % (venv, (r.stderr.strip().splitlines() or ["?"])[-1], how))
    if r.stdout.strip() != AVAFRAME:
        raise PeerMissing("%s has AvaFrame %s, this comparison was written for %s: %s"
                          % (venv, r.stdout.strip(), AVAFRAME, how))
    return py


def runPeerJob(py, job, work, log):
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, "job.json")
    with open(path, "w") as f:
        json.dump(job, f, indent=1)
    with open(log, "w") as f:
        r = subprocess.run([py, os.path.abspath(__file__), "--peer-job", path], stdout=f, stderr=subprocess.STDOUT,
                           cwd=work, env=dict(os.environ, PYTHONPATH=""))
    if r.returncode != 0:
        with open(log, errors="replace") as f:
            tail = f.read()[-3000:]
        raise RuntimeError("AvaFrame (%s) failed with exit %d; the end of %s:\n%s" % (job["action"], r.returncode,
                                                                                     log, tail))


def loadExample():
    import importlib.util
    spec = importlib.util.spec_from_file_location("field_valley", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def writeValleyDem(path):
    """The field example's valley (its generator, Terrain.valley, with its parameters), larger (VALLEY)."""
    from mpmsdem.terrain import Terrain
    Terrain.valley(**VALLEY).writeAsc(path)


def setup(a, out, py):
    """The DEM (made or given, copied into out/), origin, release, path, stations and settings."""
    fv = loadExample()
    from mpmsdem.terrain import Terrain
    case = CASES.get(a.case, {})
    ext = os.path.splitext(a.dem)[1].lower() if a.dem else ".asc"
    dem = os.path.join(out, "dem" + ext)
    if a.dem:
        if ext not in (".asc", ".tif", ".tiff"):
            raise ValueError("--dem %s: AvaFrame reads ESRI ASCII (.asc) and GeoTIFF (.tif)" % a.dem)
        shutil.copy(a.dem, dem)
    elif not (a.reuse and os.path.exists(dem)):
        d = case["dem"]
        if d["kind"] == "valley":
            writeValleyDem(dem)
        else:
            runPeerJob(py, {"action": "topo", "dem": d, "work": os.path.join(out, "topo"), "out": dem},
                       os.path.join(out, "topo"), os.path.join(out, "topo.log"))
    ground = Terrain.read(dem)  # map coordinates
    if a.origin is None:
        a.origin = (ground.x0, ground.y0, math.floor(float(ground.heights.min())))
    pick = lambda name: getattr(a, name) if getattr(a, name) is not None else case.get(name)  # noqa: E731
    s = {"dem": dem, "origin": tuple(a.origin), "dx": pick("dx"), "duration": pick("duration"),
         "threshold": pick("threshold"), "release": tuple(pick("release")), "stations": pick("stations"),
         "label": a.case or os.path.basename(a.dem)}
    if a.path:
        if len(a.path) < 4 or len(a.path) % 2:
            raise ValueError("--path: x y pairs, at least two points (got %d numbers)" % len(a.path))
        s["path"] = [(a.path[k], a.path[k + 1]) for k in range(0, len(a.path), 2)]
    elif case:
        s["path"] = case["path"]
    else:  # along +x through the release's centre, over the whole raster
        yc = 0.5 * (s["release"][1] + s["release"][3])
        x0, x1, _, _ = ground.extent
        s["path"] = [(x0, yc), (x1, yc)]
    if s["stations"] is None:
        length = pathLength(s["path"])
        s["stations"] = tuple(float(v) for v in np.arange(10.0, length, 10.0))
    s["depth"] = a.release_depth if a.release_depth is not None else case.get("depth")
    if a.release_volume is not None:
        s["depth"] = depthForVolume(fv, s, a.release_volume)
    if s["depth"] is None:
        raise ValueError("the release needs --release-depth or --release-volume")
    return fv, s


def exampleArgs(s, depth=None):
    o = s["origin"]
    r = s["release"]
    return ["--terrain", s["dem"], "--origin", repr(o[0]), repr(o[1]), repr(o[2]), "--source", repr(r[0] - o[0]),
            repr(r[1] - o[1]), repr(r[2] - o[0]), repr(r[3] - o[1]), "--source-depth",
            repr(s["depth"] if depth is None else depth), "--blocks", "0", "--dx", repr(s["dx"])]


def releaseField(fv, s, depth=None):
    """The release as the field example seeds it, on the DEM's nodes: the box's height above the
    ground [m] times the share of each node's cell inside its plan (vertical: volume per plan
    area), and the terrain (grid frame) it stands on."""
    a = fv.parse(exampleArgs(s, depth))
    ground, _, box = fv.scene(a, s["dx"])
    sp = ground.spacing
    X, Y = nodes(ground.shape, ground.x0, ground.y0, sp)

    def share(c, lo, hi):
        return np.clip((np.minimum(c + 0.5 * sp, hi) - np.maximum(c - 0.5 * sp, lo)) / sp, 0.0, 1.0)
    h = np.maximum(box["hi"][2] - ground.heights, 0.0) * share(X, box["lo"][0], box["hi"][0]) \
        * share(Y, box["lo"][1], box["hi"][1])
    return h, ground


def depthForVolume(fv, s, volume):
    """The release depth whose box holds ``volume`` m³ above the ground (bisection)."""
    lo, hi = 1e-3, 1.0

    def vol(depth):
        h, ground = releaseField(fv, s, depth)
        return h.sum() * ground.spacing ** 2
    while vol(hi) < volume:
        hi *= 2.0
        if hi > 1e4:
            raise ValueError("--release-volume %g m³: no depth up to 10 km holds it" % volume)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if vol(mid) < volume else (lo, mid)
    return 0.5 * (lo + hi)


def runOurs(s, nu, a, out, fv):
    """The field example on the DEM without blocks: its maps and summary."""
    folder = os.path.join(out, "ours_nu%g" % nu)
    summaryPath = os.path.join(folder, "summary.json")
    if not (a.reuse and os.path.exists(summaryPath)):
        cmd = [sys.executable, EXAMPLE] + exampleArgs(s) + ["--duration", repr(s["duration"]), "--flip-viscosity",
                                                             repr(nu), "--min-thickness", repr(s["threshold"]),
                                                             "--out", folder, "--no-plots"]
        env = dict(os.environ, OMP_NUM_THREADS=str(a.threads))
        env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
        os.makedirs(folder, exist_ok=True)
        print("ours (PIC viscosity %g m²/s): %s" % (nu, " ".join(cmd[1:])), flush=True)
        t0 = time.time()
        with open(os.path.join(folder, "run.log"), "w") as f:
            r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
        if r.returncode != 0:
            with open(os.path.join(folder, "run.log"), errors="replace") as f:
                raise RuntimeError("our run failed (exit %d):\n%s" % (r.returncode, f.read()[-3000:]))
        with open(summaryPath) as f:
            summary = json.load(f)
        summary["script_wall_seconds"] = time.time() - t0
        with open(summaryPath, "w") as f:
            json.dump(summary, f, indent=1)
    with open(summaryPath) as f:
        summary = json.load(f)
    maps = {}
    for name in ("deposit_thickness", "max_thickness", "max_speed", "max_dynamic_pressure", "arrival_time"):
        maps[name], x0, y0, sp = readAsc(os.path.join(folder, "maps", name + ".asc"))
    density = fv.DEBRIS["density"]
    return {"label": "ours, PIC viscosity %g m²/s" % nu, "kind": "ours", "nu": nu, "summary": summary,
            "deposit": maps["deposit_thickness"], "max_thickness": maps["max_thickness"],
            "arrival": maps["arrival_time"],
            "speed_thick": float(np.sqrt(np.nanmax(maps["max_dynamic_pressure"], initial=0.0) / density)),
            "speed_any": float(maps["max_speed"].max()), "volume0": summary["mass_seeded"] / density,
            "volume_end": float(maps["deposit_thickness"].sum() * sp * sp), "t_end": summary["duration"],
            "wall": summary.get("script_wall_seconds", summary["wall_seconds"]),
            "grid": (x0, y0, sp)}


def runPeer(s, mu, a, out, py, release, cosine):
    """AvaFrame's com1DFA on the same DEM and release (Coulomb ``mu``)."""
    work = os.path.join(out, "avaframe_mu%g" % mu)
    npz = os.path.join(work, "result.npz")
    rho = 1800.0
    if not (a.reuse and os.path.exists(npz)):
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(os.path.join(work, "Inputs", "REL"))
        shutil.copy(s["dem"], os.path.join(work, "Inputs", "DEM" + os.path.splitext(s["dem"])[1]))
        from mpmsdem.terrain import Terrain
        Terrain.read(s["dem"]).writeAsc(os.path.join(work, "Inputs", "REL", "release.asc"), release * cosine)
        sp = Terrain.read(s["dem"]).spacing
        cfg = {"frictModel": "Coulomb", "mucoulomb": repr(mu), "rho": repr(rho), "meshCellSize": repr(sp),
               "sphKernelRadius": "meshCellSize", "sphKernelRadiusTimeStepping": "True", "cMax": "0.02",
               "tEnd": repr(a.peer_t_end), "tSteps": "0:%g" % SAMPLE, "resType": "pft|pfv|FT|FV",
               "secRelArea": "False", "relThFromFile": "True"}
        print("AvaFrame com1DFA (Coulomb mu %g) in %s" % (mu, work), flush=True)
        t0 = time.time()
        runPeerJob(py, {"action": "run", "work": work, "cfg": cfg, "out": npz}, work, os.path.join(work, "run.log"))
        with open(os.path.join(work, "script_wall.json"), "w") as f:
            json.dump({"wall": time.time() - t0}, f)
        shutil.rmtree(os.path.join(work, "Outputs", "com1DFA", "peakFiles", "timeSteps"), ignore_errors=True)
    r = np.load(npz)
    sp = float(r["spacing"])
    up = 1.0 / cosine  # slope-normal thickness -> volume per plan area
    ft = r["FT"].astype(float) * up[None]
    speedThick = float(np.where(ft >= s["threshold"], r["FV"], 0.0).max())
    final = np.nan_to_num(r["final"]) * up
    with open(os.path.join(work, "script_wall.json")) as f:
        wall = json.load(f)["wall"]
    return {"label": "AvaFrame com1DFA, Coulomb μ %g" % mu, "kind": "avaframe", "mu": mu, "deposit": final,
            "max_thickness": np.nan_to_num(ft).max(axis=0), "arrival": arrivalMap(r["times"], np.nan_to_num(ft),
                                                                                   s["threshold"]),
            "speed_thick": speedThick, "speed_any": float(np.nanmax(r["pfv"])),
            "volume0": float(r["mass"][0]) / rho, "volume_end": float(final.sum() * sp * sp),
            "mass_end": float(r["mass"][-1]), "mass0": float(r["mass"][0]), "t_end": float(r["massTime"][-1]),
            "wall": wall, "avaframe_wall": float(r["wall"]), "particles": int(r["particles"]),
            "version": str(r["version"]), "grid": (float(r["x0"]), float(r["y0"]), sp)}


def analyse(run, s, heights, grid, top, releaseCentroid, sNodes):
    x0, y0, sp = grid
    h = np.nan_to_num(run["deposit"])
    end = farthest(h, heights, x0, y0, sp, s["path"], s["threshold"])
    reach = farthest(np.nan_to_num(run["max_thickness"]), heights, x0, y0, sp, s["path"], s["threshold"])
    c = centroid(h, heights, x0, y0, sp, s["path"])
    prof = profile(h, x0, y0, sp, s["path"])
    comAngle = float("nan")
    if c is not None and c["s"] > releaseCentroid["s"]:
        comAngle = math.degrees(math.atan2(releaseCentroid["z"] - c["z"], c["s"] - releaseCentroid["s"]))
    return {"runout": end["s"] if end else float("nan"), "runout_point": end, "alpha": travelAngle(top, end),
            "reach": reach["s"] if reach else float("nan"), "reach_alpha": travelAngle(top, reach),
            "area": depositArea(h, sp, s["threshold"]), "centroid": c, "com_angle": comAngle,
            "effective_mu": math.tan(math.radians(comAngle)) if comAngle == comAngle else float("nan"),
            "max_deposit": float(h.max()), "profile": prof,
            "arrivals": stationArrivals(run["arrival"], sNodes, s["stations"])}


ROWS = [  # key, quantity, unit, deviation: "rel" (percent) or "abs" (in the unit); comparison.json has more
    ("volume0", "release volume", "m³", "rel"),
    ("runout", "runout: deposit front along the path (h ≥ thr)", "m", "rel"),
    ("alpha", "travel angle α (release top to the deposit front)", "°", "abs"),
    ("area", "deposit area (h ≥ thr)", "m²", "rel"),
    ("centroid_s", "deposit centroid along the path", "m", "rel"),
    ("com_angle", "centre-of-mass travel angle", "°", "abs"),
    ("effective_mu", "its tangent (an effective friction)", "", "rel"),
    ("max_deposit", "thickest deposit", "m", "rel"),
    ("speed_thick", "largest depth-averaged speed where h ≥ thr", "m/s", "rel"),
    ("volume_end", "volume on the raster at the end", "m³", "rel"),
    ("t_end", "simulated time (ours: fixed; AvaFrame: its stop, kinetic energy < 1 % of its peak)", "s", None),
    ("wall", "wall time of the run", "s", None),
]


def fmt(v, unit):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if unit in ("°",):
        return "%.1f" % v
    if unit == "":
        return "%.3f" % v
    a = abs(v)
    return "%.0f" % v if a >= 100 else "%.1f" % v if a >= 10 else "%.2f" % v


def deviation(o, p, how, unit):
    if how is None or not (isinstance(o, float) and isinstance(p, float)) or not (math.isfinite(o)
                                                                                   and math.isfinite(p)):
        return "—"
    d = 100.0 * (o - p) / p if how == "rel" and p else o - p
    if how == "rel":
        return ("%+.0f %%" % d if round(d) else "0 %") if p else "—"
    return "%+.1f %s" % (d, unit) if round(d, 1) else "0 %s" % unit


def table(s, runs):
    ours = [r for r in runs if r["kind"] == "ours"]
    peer = [r for r in runs if r["kind"] == "avaframe"]
    head = ["quantity", "unit"] + [r["label"] for r in runs] + ["deviation: %s" % r["label"].replace("ours, ", "")
                                                                 for r in ours]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 2 + "---:|" * (len(runs) + len(ours))]
    thr = "%g m" % s["threshold"]
    rows = list(ROWS)
    for k, st in enumerate(s["stations"]):
        rows.insert(len(rows) - 3, ("arrival%d" % k, "arrival at s = %g m" % st, "s", "abs"))
    for key, name, unit, how in rows:
        vals = [r["values"].get(key) for r in runs]
        cells = [name.replace("thr", thr), unit] + [fmt(v, unit) for v in vals]
        cells += [deviation(o["values"].get(key), peer[0]["values"].get(key), how, unit) for o in ours]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def figure(path, s, runs, heights, grid, releaseBox):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    x0, y0, sp = grid
    nx, ny = heights.shape
    X, Y = nodes(heights.shape, x0, y0, sp)
    fig = plt.figure(figsize=(12, 8.5))
    gs = fig.add_gridspec(2, 2, height_ratios=[1.15, 1])
    ax = fig.add_subplot(gs[0, :])
    first = runs[0]
    h = np.ma.masked_less(np.nan_to_num(first["deposit"]), s["threshold"])
    im = ax.imshow(h.T, origin="lower", extent=(x0 - sp / 2, x0 + (nx - 0.5) * sp, y0 - sp / 2, y0 + (ny - 0.5) * sp),
                   cmap="viridis", aspect="equal")
    fig.colorbar(im, ax=ax, label="deposit thickness [m], %s" % first["label"], shrink=0.8)
    if np.ptp(heights) > 0:
        ax.contour(X, Y, heights, levels=15, colors="0.6", linewidths=0.5)
    colours = ["C0", "C2", "C1", "C3", "C4", "C5"]
    handles = []
    for k, r in enumerate(runs):
        ax.contour(X, Y, np.nan_to_num(r["deposit"]), levels=[s["threshold"]], colors=colours[k % 6],
                        linewidths=1.6, linestyles="-" if r["kind"] == "avaframe" else "--")
        handles.append(plt.Line2D([], [], color=colours[k % 6], ls="-" if r["kind"] == "avaframe" else "--",
                                  label=r["label"]))
        p = r["values"]["runout_point"]
        if p:
            ax.plot(p["x"], p["y"], "x", color=colours[k % 6], ms=8)
    bx = releaseBox
    ax.plot([bx[0], bx[2], bx[2], bx[0], bx[0]], [bx[1], bx[1], bx[3], bx[3], bx[1]], "k:", lw=1)
    pth = np.asarray(s["path"])
    ax.plot(pth[:, 0], pth[:, 1], "k-", lw=0.6)
    ax.legend(handles=handles + [plt.Line2D([], [], color="k", ls=":", label="release")], fontsize=8,
              loc="upper right")
    seen = np.zeros(heights.shape, bool)
    for r in runs:
        seen |= np.nan_to_num(r["max_thickness"]) >= s["threshold"]
    if seen.any():  # the map around what the flows reached and the release, 3 m beyond
        xs, ys = X[seen], Y[seen]
        ax.set_xlim(max(x0, min(xs.min(), bx[0]) - 3.0), min(x0 + (nx - 1) * sp, max(xs.max(), bx[2]) + 3.0))
        ax.set_ylim(max(y0, min(ys.min(), bx[1]) - 3.0), min(y0 + (ny - 1) * sp, max(ys.max(), bx[3]) + 3.0))
    ax.set_title("%s: deposits (outlines at h = %g m; x: the fronts), terrain contours" % (s["label"], s["threshold"]))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax2 = fig.add_subplot(gs[1, 0])
    for k, r in enumerate(runs):
        sp_, hp = r["values"]["profile"]
        ax2.plot(sp_, hp, color=colours[k % 6], ls="-" if r["kind"] == "avaframe" else "--", label=r["label"])
    ax2.axhline(s["threshold"], color="0.5", lw=0.5)
    ax2.set_xlabel("s along the path [m]")
    ax2.set_ylabel("deposit thickness [m]")
    ax2.set_title("thickness profile along the path")
    ax2.legend(fontsize=7)
    ax3 = fig.add_subplot(gs[1, 1])
    for k, r in enumerate(runs):
        ax3.plot(r["values"]["arrivals"], s["stations"], marker="o", color=colours[k % 6],
                 ls="-" if r["kind"] == "avaframe" else "--", label=r["label"])
    ax3.set_xlabel("arrival time [s] (h ≥ %g m at or beyond s)" % s["threshold"])
    ax3.set_ylabel("station s [m]")
    ax3.set_title("the front's arrival")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--case", choices=sorted(CASES), help="a prepared case (its DEM is made)")
    ap.add_argument("--dem", help="your own DEM (ESRI ASCII or GeoTIFF, projected, metres, north-up, square cells)")
    ap.add_argument("--release", type=float, nargs=4, metavar=("X0", "Y0", "X1", "Y1"),
                    help="the release's plan [m], map coordinates")
    ap.add_argument("--release-depth", type=float, help="its depth above the highest ground under it [m]")
    ap.add_argument("--release-volume", type=float, help="or its volume [m³] (the depth that holds it)")
    ap.add_argument("--origin", type=float, nargs=3, metavar=("X", "Y", "Z"),
                    help="the map point that becomes our grid's zero (default: the raster's first node and its lowest "
                         "height, rounded down)")
    ap.add_argument("--path", type=float, nargs="+", metavar="X Y",
                    help="the path (polyline) along which runout, profile and stations are measured, map coordinates "
                         "(default: along +x through the release's centre)")
    ap.add_argument("--stations", type=float, nargs="+", help="path coordinates [m] of the arrival stations")
    ap.add_argument("--dx", type=float, help="our grid spacing [m] (default: the case's, else 0.5)")
    ap.add_argument("--duration", type=float, help="our simulated time [s] (default: the case's, else 30)")
    ap.add_argument("--threshold", type=float, help="thickness [m] of a deposit and of an arrival (default: the "
                                                    "case's, else 0.1)")
    ap.add_argument("--flip-viscosity", type=float, nargs="+",
                    help="our PIC viscosity [m²/s], one run each (default: the field example's)")
    ap.add_argument("--mu", type=float, nargs="+", help="AvaFrame's Coulomb friction, one run each "
                                                        "(default: our material's mu_s)")
    ap.add_argument("--peer-t-end", type=float, default=60.0, help="AvaFrame's end time [s] if its stop criterion "
                                                                   "has not stopped it (default 60)")
    ap.add_argument("--threads", type=int, default=2, help="OpenMP threads of our runs (default 2)")
    ap.add_argument("--venv", default=VENV, help="AvaFrame's virtual environment (default .venv-peers/)")
    ap.add_argument("--out", help="output folder (default results/avaframe_peer/CASE)")
    ap.add_argument("--reuse", action="store_true", help="keep the runs already in --out, only analyse again")
    ap.add_argument("--peer-job", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.peer_job:
        return a
    if bool(a.case) == bool(a.dem):
        ap.error("give either --case or --dem")
    if a.dem and not a.release:
        ap.error("--dem needs --release X0 Y0 X1 Y1 and --release-depth or --release-volume")
    if a.release_depth is not None and a.release_volume is not None:
        ap.error("give --release-depth or --release-volume, not both")
    if a.dem:
        a.dx = 0.5 if a.dx is None else a.dx
        a.duration = 30.0 if a.duration is None else a.duration
        a.threshold = 0.1 if a.threshold is None else a.threshold
    for name in ("dx", "duration", "threshold", "release_depth", "release_volume"):
        v = getattr(a, name)
        if v is not None and not (v > 0 and math.isfinite(v)):
            ap.error("--%s = %r: must be > 0 and finite" % (name.replace("_", "-"), v))
    return a


def main(argv):
    a = parse(argv)
    if a.peer_job:
        return peerMain(a.peer_job)
    try:
        py = peerPython(a.venv)
    except PeerMissing as e:
        print("avaframe_peer: %s" % e, file=sys.stderr)
        return 2
    out = os.path.abspath(a.out or os.path.join(ROOT, "results", "avaframe_peer", a.case or "dem"))
    os.makedirs(out, exist_ok=True)
    fv, s = setup(a, out, py)
    debris = fv.DEBRIS
    nus = a.flip_viscosity or [fv.FIELD_VISCOSITY]
    mus = a.mu or [debris["mu_s"]]
    print("case %s: DEM %s, our dx %g m, %g s, threshold %g m; AvaFrame Coulomb mu %s; our mu(I): %s" % (
        s["label"], s["dem"], s["dx"], s["duration"], s["threshold"], ", ".join("%g" % m for m in mus),
        ", ".join("%.3f at I = %g" % (muOfI(I, debris["mu_s"], debris["mu_2"], debris["I0"]), I)
                  for I in (1e-3, 1e-2, 3e-2))), flush=True)
    ours = [runOurs(s, nu, a, out, fv) for nu in nus]
    release, terrain = releaseField(fv, s)
    sp = terrain.spacing
    heights = terrain.heights + s["origin"][2]  # map heights
    grid = (terrain.x0 + s["origin"][0], terrain.y0 + s["origin"][1], sp)
    scale = ours[0]["volume0"] / (release.sum() * sp * sp)
    release = release * scale
    cosine = slopeCosine(heights, sp)
    peers = [runPeer(s, mu, a, out, py, release, cosine) for mu in mus]
    X, Y = nodes(heights.shape, *grid)
    sNodes, _ = projectOnPath(X, Y, s["path"])
    top = releaseTop(release, heights, *grid, s["path"])
    c0 = centroid(release, heights, *grid, s["path"])
    runs = ours + peers
    for r in runs:
        if r["grid"] != grid and not np.allclose(r["grid"], grid):
            raise RuntimeError("%s: its maps are on %s, the DEM's nodes on %s" % (r["label"], r["grid"], grid))
        v = analyse(r, s, heights, grid, top, c0, sNodes)
        v.update(volume0=r["volume0"], volume_end=r["volume_end"], speed_thick=r["speed_thick"],
                 speed_any=r["speed_any"], t_end=r["t_end"], wall=r["wall"],
                 centroid_s=v["centroid"]["s"] if v["centroid"] else float("nan"))
        for k, t in enumerate(v["arrivals"]):
            v["arrival%d" % k] = t
        r["values"] = v
    box = [s["release"][0], s["release"][1], s["release"][2], s["release"][3]]
    figure(os.path.join(out, "comparison.png"), s, runs, heights, grid, box)
    demName = os.path.relpath(s["dem"], ROOT) if s["dem"].startswith(ROOT + os.sep) else s["dem"]
    r0 = s["release"]
    notes = ["Case **%s**: DEM `%s` (%d × %d nodes of %g m), release over x %g–%g, y %g–%g m, %g m above the highest "
             "ground under it: %.1f m³ seeded by us (the AvaFrame release raster scaled by %.4f to it); path %s; "
             "threshold thr = %g m." % (s["label"], demName, heights.shape[0], heights.shape[1], sp, r0[0], r0[2],
                                        r0[1], r0[3], s["depth"], ours[0]["volume0"], scale,
                                        " → ".join("(%g, %g)" % tuple(p) for p in s["path"]), s["threshold"])]
    for r in ours:
        m = r["summary"]
        notes.append("%s: Δx %g m, %d points, %s, FLIP/PIC damping rate %g /s at the last step, %d steps over %.1f s "
                     "(mean step %.2f ms: half the stable step), kinetic energy at the end %.3g J, %d points held by "
                     "the grid's walls." % (r["label"], m["dx"], m["points"], m["flip_blend"], m["flip_damping_rate"],
                                             m["steps"], m["duration"], 1e3 * m["duration"] / max(m["steps"], 1),
                                             m["kinetic_energy"], m["points_at_grid_walls"]))
    for r in peers:
        notes.append("%s (AvaFrame %s): cells and SPH kernel radius %g m, time step %.3g s (cMax 0.02 × cell), %d "
                     "particles, mass at the start %.4g t, at the end %.4g t (%.1f %% left the DEM), stopped at %.2f s."
                     % (r["label"], r["version"], sp, 0.02 * sp, r["particles"], r["mass0"] / 1e3, r["mass_end"] / 1e3,
                        100.0 * (1.0 - r["mass_end"] / r["mass0"]), r["t_end"]))
    md = "\n\n".join(notes) + "\n\n" + table(s, runs) + "\n"
    with open(os.path.join(out, "comparison.md"), "w") as f:
        f.write(md)
    js = {"case": s["label"], "dem": s["dem"], "origin": s["origin"], "dx": s["dx"], "threshold": s["threshold"],
          "release": s["release"], "depth": s["depth"], "path": s["path"], "stations": list(s["stations"]),
          "release_scale": scale, "runs": []}
    for r in runs:
        v = dict(r["values"])
        v["profile"] = {"s": v["profile"][0].tolist(), "h": v["profile"][1].tolist()}
        entry = {"label": r["label"], "kind": r["kind"], "values": v}
        entry.update({k: r[k] for k in ("nu", "mu", "particles", "mass0", "mass_end", "version") if k in r})
        if r["kind"] == "ours":
            entry["summary"] = {k: r["summary"][k] for k in ("dx", "points", "steps", "duration", "flip_blend",
                                                             "flip_damping_rate", "kinetic_energy",
                                                             "points_at_grid_walls")}
        js["runs"].append(entry)
    with open(os.path.join(out, "comparison.json"), "w") as f:
        json.dump(js, f, indent=1, default=float)
    print(md)
    print("written: %s (comparison.md, comparison.json, comparison.png)" % out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
