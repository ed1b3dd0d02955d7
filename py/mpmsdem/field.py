"""Blocks by the hundred on a terrain, and what a user reads of each after the flow.

- :func:`readBlockTable` / :func:`writeBlockTable`: the blocks of a scene as a CSV table, one row
  per block: ``id, shape, x, y, heading_deg, mass`` (shape ``box:LxWxH``, outer lengths [m] along
  the block's own x, y, z, or a mesh file, ``.obj``/``.stl``, with an optional ``*scale``
  suffix); (x, y) [m] in the grid frame, the heading about the vertical [deg], the mass [kg].
- :func:`placeBlocks`: each block resting on the terrain, its base along the ground's slope under
  it, turned by its heading.
- :class:`BlockTracker`: every step, each block's largest flow force and its time, its 10 ms
  means (a time series) and its first contact with the flow; then :meth:`BlockTracker.report`
  (final position in the grid frame and the map's own coordinates, travel, rotation, the force,
  the first contact, and the burial: the depth of debris above the block's top at its centre,
  the fraction of its plan covered, buried or partly buried) and :func:`writeReport` as CSV and
  HDF5.
- :func:`rescueList` / :func:`writeRescue`: the blocks a search must find (buried, partly
  buried or moved), where they are in map coordinates and how deep, deepest first.
"""
import csv
import json
import math
import os

import numpy as np
from yade import O
from yade.minieigenHP import Quaternion, Vector3

from . import _mpmsdem
from .engine import _stepRunner
from .terrain import mapOffset

WALL_LAYER = _mpmsdem.wallLayer  # cells inside each face of the grid box where its walls act

COLUMNS = ("id", "shape", "x", "y", "heading_deg", "mass")


def readBlockTable(path):
    """The rows of a block table (CSV with the header ``id,shape,x,y,heading_deg,mass``) as
    dicts; ValueError naming the file, the row and the column for a missing, malformed or
    out-of-range value (a mass not > 0, a repeated id, a box without three lengths > 0)."""
    rows, ids = [], set()
    try:
        with open(path, newline="", encoding="utf-8") as f:
            text = f.read()
    except UnicodeDecodeError as e:
        raise ValueError("block table %s: not UTF-8 text (byte %d): %s" % (path, e.start, e.reason)) from None
    try:
        table = list(csv.reader(text.splitlines()))
    except csv.Error as e:
        raise ValueError("block table %s: not CSV: %s" % (path, e)) from None
    header = [h.strip() for h in table[0]] if table else []
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise ValueError("block table %s: missing column(s) %s (header: %s)" % (path, ", ".join(missing),
                                                                               ",".join(COLUMNS)))
    column = {c: header.index(c) for c in COLUMNS}
    for n, values in enumerate(table[1:], start=2):
        where = "block table %s, line %d" % (path, n)
        if not any(v.strip() for v in values):
            continue  # a blank line
        if len(values) != len(header):
            raise ValueError("%s: %d values for the %d columns of the header" % (where, len(values), len(header)))
        r = {c: values[column[c]] for c in COLUMNS}
        row = {"shape": r["shape"].strip()}
        for c, kind in (("id", int), ("x", float), ("y", float), ("heading_deg", float), ("mass", float)):
            try:
                row[c] = kind(r[c])
            except ValueError:
                raise ValueError("%s: %s = %r: not %s" % (where, c, r[c], "an integer" if kind is int else "a number")
                                 ) from None
        if not all(math.isfinite(row[k]) for k in ("x", "y", "heading_deg", "mass")):
            raise ValueError("%s: x, y, heading_deg and mass must be finite" % where)
        if not row["mass"] > 0:
            raise ValueError("%s: mass = %r kg: must be > 0" % (where, row["mass"]))
        if row["id"] in ids:
            raise ValueError("%s: id %d given twice" % (where, row["id"]))
        _shapeSpec(row["shape"], where)
        ids.add(row["id"])
        rows.append(row)
    if not rows:
        raise ValueError("block table %s: no blocks" % path)
    return rows


def writeBlockTable(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([r["id"], r["shape"], "%.6f" % r["x"], "%.6f" % r["y"], "%.3f" % r["heading_deg"],
                        "%.3f" % r["mass"]])


def _shapeSpec(shape, where):
    """("box", (L, W, H)) or ("mesh", path, scale)."""
    if shape.startswith("box:"):
        try:
            dims = tuple(float(v) for v in shape[4:].split("x"))
        except ValueError:
            dims = ()
        if len(dims) != 3 or not all(d > 0 and math.isfinite(d) for d in dims):
            raise ValueError("%s: shape %r: a box is 'box:LxWxH' with three lengths > 0 [m]" % (where, shape))
        return ("box", dims)
    path, star, scale = shape.partition("*")
    if not path.lower().endswith((".obj", ".stl")):
        raise ValueError("%s: shape %r: must be 'box:LxWxH' or a mesh file (.obj, .stl), optionally '*scale'"
                         % (where, shape))
    try:
        factor = float(scale) if star else 1.0
    except ValueError:
        factor = float("nan")
    if not (factor > 0 and math.isfinite(factor)):
        raise ValueError("%s: shape %r: the scale after '*' must be a number > 0" % (where, shape))
    return ("mesh", path, factor)


def placeBlocks(sdem, terrain, rows, material, sweepFraction=0.05, folder="."):
    """Add the blocks of ``rows`` (:func:`readBlockTable`) to ``sdem`` resting on ``terrain``:
    each turned by its heading about the vertical, then tilted so that its base lies along the
    ground's slope under its centre; its sweep radius ``sweepFraction`` of its smallest side (a
    twentieth, the paper's R/h_b), its rounded base a tenth of that radius above the ground (it
    settles within its first tenths of a second). ``material``: a function
    ``mass_density -> SdemMat`` (each block's density is its mass over its rounded volume).
    Mesh paths are relative to ``folder``. Returns the YADE ids, in the table's order."""
    ids = []
    for r in rows:
        spec = _shapeSpec(r["shape"], "block %d" % r["id"])
        if spec[0] == "box":
            half = tuple(0.5 * d for d in spec[1])
            R = sweepFraction * 2 * min(half)
            volume = _mpmsdem.SpheroPolyhedron.box(half, R).volume
            low = half[2]
        else:
            path = spec[1] if os.path.isabs(spec[1]) else os.path.join(folder, spec[1])
            verts, tris = _mpmsdem.readMeshFile(path, spec[2])
            v = np.array([list(p) for p in verts])
            ext = v.max(axis=0) - v.min(axis=0)
            R = sweepFraction * float(ext.min())
            shape = _mpmsdem.SpheroPolyhedron.mesh(verts, tris, R)
            volume = shape.volume
            low = 0.5 * float(ext[2])
        x, y = r["x"], r["y"]
        z = float(terrain.height(x, y))
        e = 1e-3 * terrain.spacing
        gx = float(terrain.height(x + e, y) - terrain.height(x - e, y)) / (2 * e)
        gy = float(terrain.height(x, y + e) - terrain.height(x, y - e)) / (2 * e)
        n = Vector3(-gx, -gy, 1.0)
        n.normalize()
        tilt = Quaternion(Quaternion.Identity)
        tilt.setFromTwoVectors(Vector3(0, 0, 1), n)
        ori = tilt * Quaternion(Vector3(0, 0, 1), math.radians(r["heading_deg"]))
        pos = Vector3(x, y, z) + n * (low + 0.1 * R)
        mat = material(r["mass"] / volume)
        if spec[0] == "box":
            ids.append(sdem.box(half, R, mat, pos=pos, ori=ori))
        else:
            ids.append(sdem.mesh(path, R, mat, scale=spec[2], pos=pos, ori=ori))
    return ids


class BlockTracker:
    """Each step, for every block of ``ids``: the largest flow force |F| on it [N] and its time,
    the mean of |F| over consecutive windows of ``window`` seconds (the impulse of the window over
    its length: an impact's force without the single steps' spikes of the barrier, as the flume
    results' 10 ms means), kept as a time series (:meth:`series`) and its largest value with the
    window's end, and the time of its first contact with the flow. Put :attr:`runner` into
    ``O.engines`` after the coupled engine's runner; :meth:`report` tells what became of each
    block.

    :param coupled: the ``CoupledEngine`` of the flow and the blocks.
    :param ids: the blocks' YADE ids (:func:`placeBlocks`).
    :param window: the force means' window [s] > 0 (default 0.01).
    :param terrain: the :class:`~mpmsdem.terrain.Terrain` the blocks stand on, for positions in
        the map's own coordinates (a raster read with an ``origin``: map = grid frame + origin;
        default None: the grid frame's).
    :param depthRadius: the radius [m] of the disc around a block's centre whose debris counts as
        "at its centre" for ``cover_depth`` (default: the flow grid's spacing dx, at most the
        distance from the centre to the edge of the block's plan, so the disc stays on the block;
        a disc of radius dx holds about 4π ≈ 12.6 of the flow's points per layer at 8 per cell).
    :param coverRadius: a sample of a block's plan is covered when a point of the flow above the
        block's top lies within this horizontal distance [m] of it (default dx/2, the spacing of
        the flow's points at 8 per cell: a continuous layer of them leaves no place farther than
        0.71 of it from a point).
    :param planSamples: the plan is sampled on ``planSamples`` × ``planSamples`` points
        (default 10, an integer >= 1; see :meth:`report`).
    """

    def __init__(self, coupled, ids, window=0.01, label="blockTracker", terrain=None, depthRadius=None,
                 coverRadius=None, planSamples=10):
        if not (window > 0 and math.isfinite(window)):
            raise ValueError("window = %r s: must be > 0 and finite" % (window,))
        for name, r in (("depthRadius", depthRadius), ("coverRadius", coverRadius)):
            if r is not None and not (r > 0 and math.isfinite(r)):
                raise ValueError("%s = %r m: must be > 0 and finite (or None: from the flow grid's spacing)"
                                 % (name, r))
        if isinstance(planSamples, bool) or not isinstance(planSamples, (int, np.integer)) or planSamples < 1:
            raise ValueError("planSamples = %r: must be an integer >= 1 (samples along each side of a plan)"
                             % (planSamples,))
        self.coupled, self.ids, self.window = coupled, list(ids), float(window)
        n = len(self.ids)
        self.start = [(Vector3(O.bodies[i].state.pos), Quaternion(O.bodies[i].state.ori)) for i in self.ids]
        self.peak = np.zeros(n)
        self.peakTime = np.full(n, np.nan)
        self.peakMean = np.zeros(n)
        self.peakMeanTime = np.full(n, np.nan)
        self._impulse = np.zeros(n)
        self._elapsed = 0.0
        self._seriesTime, self._seriesMean = [], []
        self.firstContact = np.full(n, np.nan)
        self.runner = _stepRunner("field", id(self), self._step, label, initRun=False)
        g = json.loads(coupled.mpm.solver.sceneJson)["grid"]
        self.gridLo = np.array(g["origin"], dtype=float)
        self.gridHi = self.gridLo + g["dx"] * np.array(g["cells"], dtype=float)
        self.dx = float(g["dx"])
        self.terrain = terrain
        self.mapOffset = np.array(mapOffset(terrain))
        self.depthRadius = None if depthRadius is None else float(depthRadius)
        self.coverRadius = 0.5 * self.dx if coverRadius is None else float(coverRadius)
        self.planSamples = int(planSamples)

    def _step(self):
        t, dt = O.time, O.dt
        for k, i in enumerate(self.ids):
            f = self.coupled.force(i).norm()
            if f > self.peak[k]:
                self.peak[k], self.peakTime[k] = f, t
            if f > 0 and np.isnan(self.firstContact[k]):
                self.firstContact[k] = t
            self._impulse[k] += f * dt
        self._elapsed += dt
        if self._elapsed >= self.window * (1 - 1e-9):
            mean = self._impulse / self._elapsed
            higher = mean > self.peakMean
            self.peakMean[higher] = mean[higher]
            self.peakMeanTime[higher] = t
            self._seriesTime.append(t)
            self._seriesMean.append(mean.copy())
            self._impulse[:] = 0
            self._elapsed = 0.0

    def series(self):
        """The blocks' flow-force time series: ``{"id": the blocks' ids (n,), "time": each
        window's end [s] (w,), "mean_force": the mean of |F| over each window [N] (n, w), one row
        per block in the order of ``ids``, "window": its length [s]}``; complete windows only
        (a last one cut short by the run's end is left out)."""
        n = len(self.ids)
        mean = np.array(self._seriesMean, dtype=float).reshape(-1, n).T
        return {"id": np.array(self.ids, dtype=np.int64), "time": np.array(self._seriesTime, dtype=float),
                "mean_force": mean, "window": self.window}

    def report(self, particles):
        """One dict per block (in the order of ``ids``), from the flow's ``particles`` (x,
        volume0) at the end:

        - id; start and end position of its centre (x0, y0, z0, x, y, z) [m] in the grid frame,
          and the same in the map's own coordinates (x0_map … z_map) [m] (the grid frame moved by
          the terrain's ``origin``: :func:`mpmsdem.terrain.mapOffset`);
        - travel (horizontal) and travel_3d [m], rotation_deg [deg];
        - peak_force [N] and its time peak_force_time [s]; peak_force_mean [N], the largest
          window mean, and its window's end peak_force_mean_time [s]; first_contact [s] (NaN:
          never touched);
        - top [m]: the highest point of its rounded shape. "Above its top" below means above the
          horizontal plane through it: a point of the flow counts when its centre is higher;
        - cover_depth [m]: the depth of debris above its top at its centre: the volume (at the
          material's initial density, V₀ = m/ρ₀) of the points above the top within the
          horizontal disc of radius ``depthRadius`` around its centre (its centre of mass), over
          the disc's area π·r²;
        - cover_fraction [1]: the fraction of its plan covered by debris above its top. The plan
          is the convex hull of its rounded shape's outer vertices seen from above; its
          bounding box (along the grid frame's x and y) is cut into ``planSamples`` ×
          ``planSamples`` equal cells, and the cells' centres inside the plan are its samples; a
          sample is covered when a point above the top lies within ``coverRadius`` of it
          (horizontally; a point just beyond the plan's edge covers the edge's samples). The
          fraction is the covered samples over the samples;
        - buried: covered over its whole plan (cover_fraction 1); partly_buried: debris above
          its top on its plan, but not all over it: not buried, and cover_fraction > 0 or
          cover_depth > 0 (debris at its centre that no sample reaches: samples farther apart
          than ``coverRadius``);
        - cover [m]: the volume of the points above its top within the circle around its plan
          (centred on its centre, through its farthest outer vertex), over the circle's area: the
          mean thickness over that circle, debris beside the block included;
        - outside_grid: its centre left the flow's grid box (the flow can no longer reach it;
          reported, not dropped)."""
        x = np.asarray(particles["x"], dtype=float).reshape(-1, 3)
        vol = np.asarray(particles["volume0"], dtype=float)
        ox, oy, oz = self.mapOffset
        rows = []
        for k, i in enumerate(self.ids):
            b = O.bodies[i]
            p, q = b.state.pos, b.state.ori
            p0, q0 = self.start[k]
            verts = self.coupled.sdem.shape(i).outerVertices()
            world = np.array([list(p + q * Vector3(v)) for v in verts])
            top = float(world[:, 2].max())
            c = np.array([p[0], p[1]])
            radius = float(np.linalg.norm(world[:, :2] - c, axis=1).max())
            hull = _convexHull(world[:, :2])
            edge = _distanceToEdge(hull, c)
            rc = self.depthRadius if self.depthRadius is not None else (min(self.dx, edge) if edge > 0 else self.dx)
            above = x[:, 2] > top
            xa, va = x[above, :2], vol[above]
            d = np.hypot(xa[:, 0] - c[0], xa[:, 1] - c[1])
            cover = float(va[d <= radius].sum() / (math.pi * radius * radius))
            depth = float(va[d <= rc].sum() / (math.pi * rc * rc))
            samples = _planSamples(hull, self.planSamples)
            lo, hi = hull.min(axis=0) - self.coverRadius, hull.max(axis=0) + self.coverRadius
            near = xa[np.all((xa >= lo) & (xa <= hi), axis=1)]
            r2 = self.coverRadius ** 2
            covered = sum(1 for s in samples if len(near) and bool(np.any(((near - s) ** 2).sum(axis=1) <= r2)))
            fraction = covered / len(samples)
            turn = (q0.conjugate() * q).toAxisAngle()[1]
            rows.append({"id": i, "x0": p0[0], "y0": p0[1], "z0": p0[2], "x": p[0], "y": p[1], "z": p[2],
                         "x0_map": p0[0] + ox, "y0_map": p0[1] + oy, "z0_map": p0[2] + oz,
                         "x_map": p[0] + ox, "y_map": p[1] + oy, "z_map": p[2] + oz,
                         "travel": math.hypot(p[0] - p0[0], p[1] - p0[1]), "travel_3d": (p - p0).norm(),
                         "rotation_deg": math.degrees(min(turn, 2 * math.pi - turn)),
                         "peak_force": float(self.peak[k]), "peak_force_time": float(self.peakTime[k]),
                         "peak_force_mean": float(self.peakMean[k]),
                         "peak_force_mean_time": float(self.peakMeanTime[k]),
                         "first_contact": float(self.firstContact[k]), "top": top, "cover": cover,
                         "cover_depth": depth, "cover_fraction": float(fraction),
                         "buried": bool(covered == len(samples)),
                         "partly_buried": bool(covered < len(samples) and (covered > 0 or depth > 0)),
                         "outside_grid": bool(np.any(np.array(list(p)) < self.gridLo) or
                                              np.any(np.array(list(p)) > self.gridHi))})
        return rows


def _convexHull(points):
    """The convex hull of 2-D points, counter-clockwise, without repeated or collinear points
    (Andrew's monotone chain)."""
    pts = sorted(set((float(a), float(b)) for a, b in points))
    if len(pts) < 3:
        return np.array(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    lower, upper = [], []
    for pt in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], pt) <= 0:
            lower.pop()
        lower.append(pt)
    for pt in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], pt) <= 0:
            upper.pop()
        upper.append(pt)
    return np.array(lower[:-1] + upper[:-1])


def _distanceToEdge(hull, c):
    """The distance [m] from c to the nearest edge of the convex polygon ``hull`` (CCW); <= 0
    outside it (or for a polygon without area)."""
    if len(hull) < 3:
        return 0.0
    a, b = hull, np.roll(hull, -1, axis=0)
    e = b - a
    return float(np.min((e[:, 0] * (c[1] - a[:, 1]) - e[:, 1] * (c[0] - a[:, 0])) / np.hypot(e[:, 0], e[:, 1])))


def _planSamples(hull, n):
    """The centres of the n × n equal cells of the hull's bounding box that lie inside the hull
    (its edges included, to a relative 1e-12 of its size); the hull's centroid of vertices alone
    for a hull without area."""
    lo, hi = hull.min(axis=0), hull.max(axis=0)
    f = (np.arange(n) + 0.5) / n
    gx, gy = np.meshgrid(lo[0] + f * (hi[0] - lo[0]), lo[1] + f * (hi[1] - lo[1]), indexing="ij")
    s = np.column_stack([gx.ravel(), gy.ravel()])
    if len(hull) >= 3:
        a, b = hull, np.roll(hull, -1, axis=0)
        e = b - a
        side = e[None, :, 0] * (s[:, None, 1] - a[None, :, 1]) - e[None, :, 1] * (s[:, None, 0] - a[None, :, 0])
        tol = 1e-12 * float(np.max(hi - lo)) * np.hypot(e[:, 0], e[:, 1])
        s = s[np.all(side >= -tol[None, :], axis=1)]
    return s if len(s) else hull.mean(axis=0)[None, :]


def pointsAtGridWalls(particles, grid, layers=WALL_LAYER + 1):
    """The material points held by the flow grid's side walls or its top: the points within
    ``layers`` cells of the faces x lo/hi, y lo/hi and z hi of the grid box (its walls act
    ``WALL_LAYER`` cells inside each face, and points are kept inside them). ``grid``: the
    scene's grid (``origin`` [m], ``dx`` [m], ``cells``). A field scene whose points reach them
    was too small for its flow: the flow would have gone on. Returns (count, mass [kg]); the
    floor is left out (the terrain holds the flow there)."""
    if not (layers > 0):
        raise ValueError("layers = %r cells: must be > 0" % (layers,))
    x = np.asarray(particles["x"], dtype=float)
    mass = np.asarray(particles["mass"], dtype=float)
    lo = np.asarray(grid["origin"], dtype=float)
    hi = lo + float(grid["dx"]) * np.asarray(grid["cells"], dtype=float)
    reach = layers * float(grid["dx"])
    held = ((x[:, 0] < lo[0] + reach) | (x[:, 0] > hi[0] - reach) | (x[:, 1] < lo[1] + reach) |
            (x[:, 1] > hi[1] - reach) | (x[:, 2] > hi[2] - reach))
    return int(held.sum()), float(mass[held].sum())


REPORT_UNITS = {"id": "", "x0": "m", "y0": "m", "z0": "m", "x": "m", "y": "m", "z": "m",
                "x0_map": "m", "y0_map": "m", "z0_map": "m", "x_map": "m", "y_map": "m", "z_map": "m",
                "travel": "m", "travel_3d": "m", "rotation_deg": "deg", "peak_force": "N", "peak_force_time": "s",
                "peak_force_mean": "N", "peak_force_mean_time": "s",
                "first_contact": "s", "top": "m", "cover": "m", "cover_depth": "m", "cover_fraction": "1",
                "buried": "", "partly_buried": "", "outside_grid": ""}


def _csvValue(key, value):
    """A report value as written to CSV: map coordinates to 0.1 mm (``%.4f``: their millions of
    metres kept), other reals to 6 significant digits, flags and ids as integers, text as it
    is."""
    if isinstance(value, str):
        return value
    if isinstance(value, float):
        return ("%.4f" if key.endswith("_map") else "%.6g") % value
    return int(value)


def writeReport(folder, rows, series=None, attrs=None):
    """``blocks.csv`` and ``blocks.h5`` in ``folder`` (the columns of :data:`REPORT_UNITS`, as
    :meth:`BlockTracker.report` gives them; CSV: units in the header; HDF5: one dataset per
    column, its unit as an attribute); returns their paths.

    :param series: :meth:`BlockTracker.series`: written to ``blocks.h5`` as the group
        ``force_series`` (``id``, ``time`` [s], ``mean_force`` [N], one row per block in the
        rows' order, and the ``window`` [s] as an attribute).
    :param attrs: attributes of ``blocks.h5``'s root (e.g. ``crs``, the map's coordinate system
        as WKT, and ``map_offset``); None values are left out."""
    os.makedirs(folder, exist_ok=True)
    keys = list(REPORT_UNITS)
    if series is not None:
        ids = [int(v) for v in series["id"]]
        if ids != [int(r["id"]) for r in rows]:
            raise ValueError("series: its blocks %s are not the rows' %s (in that order)"
                             % (ids[:8], [int(r["id"]) for r in rows][:8]))
    csvPath = os.path.join(folder, "blocks.csv")
    with open(csvPath, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["%s [%s]" % (k, REPORT_UNITS[k]) if REPORT_UNITS[k] else k for k in keys])
        for r in rows:
            w.writerow([_csvValue(k, r[k]) for k in keys])
    h5Path = os.path.join(folder, "blocks.h5")
    import h5py
    with h5py.File(h5Path, "w") as f:
        for k in keys:
            d = f.create_dataset(k, data=np.array([r[k] for r in rows]))
            d.attrs["unit"] = REPORT_UNITS[k]
        for k, v in (attrs or {}).items():
            if v is not None:
                f.attrs[k] = v
        if series is not None:
            g = f.create_group("force_series")
            g.attrs["window"] = float(series["window"])
            g.attrs["window_unit"] = "s"
            g.attrs["description"] = ("mean of the flow force |F| on each block over consecutive windows; row k: "
                                      "the block id[k], column w: the window ending at time[w]")
            for k, v, unit in (("id", series["id"], ""), ("time", series["time"], "s"),
                               ("mean_force", series["mean_force"], "N")):
                d = g.create_dataset(k, data=np.asarray(v))
                d.attrs["unit"] = unit
    return csvPath, h5Path


RESCUE_COLUMNS = ("id", "status", "x_map", "y_map", "z_map", "cover_depth", "cover_fraction", "travel", "x", "y")
RESCUE_UNITS = {"id": "", "status": "", "x_map": "m", "y_map": "m", "z_map": "m", "cover_depth": "m",
                "cover_fraction": "1", "travel": "m", "x": "m", "y": "m"}


def rescueList(rows, minTravel=1.0):
    """The blocks a search must find, from :meth:`BlockTracker.report`'s rows: those buried,
    partly buried, or moved more than ``minTravel`` [m] >= 0 horizontally (``travel``), each row
    with a ``status`` (``"buried"``, ``"partly buried"`` or ``"moved"``, the first that holds),
    sorted by the depth of debris at their centre (``cover_depth``), deepest first, then by the
    fraction of their plan covered and their travel, largest first, then by id."""
    if isinstance(minTravel, bool) or not (0 <= minTravel < math.inf):
        raise ValueError("minTravel = %r m: must be >= 0 and finite" % (minTravel,))
    found = []
    for r in rows:
        status = ("buried" if r["buried"] else "partly buried" if r["partly_buried"] else
                  "moved" if r["travel"] > minTravel else None)
        if status:
            found.append(dict(r, status=status))
    return sorted(found, key=lambda r: (-r["cover_depth"], -r["cover_fraction"], -r["travel"], r["id"]))


def writeRescue(path, rows):
    """:func:`rescueList`'s rows as CSV (the columns of :data:`RESCUE_COLUMNS`, units in the
    header); returns the path."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["%s [%s]" % (k, RESCUE_UNITS[k]) if RESCUE_UNITS[k] else k for k in RESCUE_COLUMNS])
        for r in rows:
            w.writerow([_csvValue(k, r[k]) for k in RESCUE_COLUMNS])
    return path
