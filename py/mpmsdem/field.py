"""Blocks by the hundred on a terrain, and what a user reads of each after the flow.

- :func:`readBlockTable` / :func:`writeBlockTable`: the blocks of a scene as a CSV table, one row
  per block: ``id, shape, x, y, heading_deg, mass`` (shape ``box:LxWxH``, outer lengths [m] along
  the block's own x, y, z, or a mesh file, ``.obj``/``.stl``, with an optional ``*scale``
  suffix); (x, y) [m] in the grid frame, the heading about the vertical [deg], the mass [kg].
- :func:`placeBlocks`: each block resting on the terrain, its base along the ground's slope under
  it, turned by its heading.
- :class:`BlockTracker`: every step, each block's largest flow force and its time and its first
  contact with the flow; then :meth:`BlockTracker.report` (final position, travel, rotation, the
  force, the first contact, and the burial: the thickness of the flow's material above the
  block's top at the end) as CSV and HDF5.
"""
import csv
import json
import math
import os

import numpy as np
from yade import O
from yade.minieigenHP import Quaternion, Vector3

from . import _mpmsdem
from .sdem import _stepRunner

WALL_LAYER = _mpmsdem.wallLayer  # cells inside each face of the grid box where its walls act

COLUMNS = ("id", "shape", "x", "y", "heading_deg", "mass")


def readBlockTable(path):
    """The rows of a block table (CSV with the header ``id,shape,x,y,heading_deg,mass``) as
    dicts; ValueError naming the file, the row and the column for a missing, malformed or
    out-of-range value (a mass not > 0, a repeated id, a box without three lengths > 0)."""
    rows, ids = [], set()
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError("block table %s: missing column(s) %s (header: %s)" % (path, ", ".join(missing),
                                                                                   ",".join(COLUMNS)))
        for n, r in enumerate(reader, start=2):
            where = "block table %s, line %d" % (path, n)
            try:
                row = {"id": int(r["id"]), "shape": r["shape"].strip(), "x": float(r["x"]), "y": float(r["y"]),
                       "heading_deg": float(r["heading_deg"]), "mass": float(r["mass"])}
            except (TypeError, ValueError) as e:
                raise ValueError("%s: %s" % (where, e)) from e
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
    path, _, scale = shape.partition("*")
    if not path.lower().endswith((".obj", ".stl")):
        raise ValueError("%s: shape %r: must be 'box:LxWxH' or a mesh file (.obj, .stl), optionally '*scale'"
                         % (where, shape))
    return ("mesh", path, float(scale) if scale else 1.0)


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
    the largest mean of |F| over consecutive windows of ``window`` seconds (the impulse of the
    window over its length: an impact's force without the single steps' spikes of the barrier,
    as the flume results' 10 ms means) and the window's end, and the time of its first contact with
    the flow. Put :attr:`runner` into ``O.engines`` after the coupled engine's runner."""

    def __init__(self, coupled, ids, window=0.01, label="blockTracker"):
        if not (window > 0 and math.isfinite(window)):
            raise ValueError("window = %r s: must be > 0 and finite" % (window,))
        self.coupled, self.ids, self.window = coupled, list(ids), float(window)
        n = len(self.ids)
        self.start = [(Vector3(O.bodies[i].state.pos), Quaternion(O.bodies[i].state.ori)) for i in self.ids]
        self.peak = np.zeros(n)
        self.peakTime = np.full(n, np.nan)
        self.peakMean = np.zeros(n)
        self.peakMeanTime = np.full(n, np.nan)
        self._impulse = np.zeros(n)
        self._elapsed = 0.0
        self.firstContact = np.full(n, np.nan)
        self.runner = _stepRunner("field", id(self), self._step, label, initRun=False)
        g = json.loads(coupled.mpm.solver.sceneJson)["grid"]
        self.gridLo = np.array(g["origin"], dtype=float)
        self.gridHi = self.gridLo + g["dx"] * np.array(g["cells"], dtype=float)

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
            self._impulse[:] = 0
            self._elapsed = 0.0

    def report(self, particles):
        """One dict per block: id, start and end position [m], travel (horizontal and 3-D) [m],
        rotation [deg], peak flow force [N] and its time [s], its largest window mean [N] and the
        window's end [s], first contact [s] (NaN: never
        touched), top [m] (the highest point of its rounded shape), cover [m] (the thickness of
        the flow's material above its top within its plan's circle: the volume at the
        material's initial density of the points above the top, over the circle's area), buried
        (cover > 0) and outside_grid (its centre left the flow's grid box: the flow can no
        longer reach it; reported, not dropped)."""
        x = np.asarray(particles["x"])
        vol = np.asarray(particles["volume0"])
        rows = []
        for k, i in enumerate(self.ids):
            b = O.bodies[i]
            p, q = b.state.pos, b.state.ori
            p0, q0 = self.start[k]
            verts = self.coupled.sdem.shape(i).outerVertices()
            world = np.array([list(p + q * Vector3(v)) for v in verts])
            top = float(world[:, 2].max())
            radius = float(np.linalg.norm(world[:, :2] - np.array([p[0], p[1]]), axis=1).max())
            over = (np.hypot(x[:, 0] - p[0], x[:, 1] - p[1]) <= radius) & (x[:, 2] > top)
            cover = float(vol[over].sum() / (math.pi * radius * radius))
            turn = (q0.conjugate() * q).toAxisAngle()[1]
            rows.append({"id": i, "x0": p0[0], "y0": p0[1], "z0": p0[2], "x": p[0], "y": p[1], "z": p[2],
                         "travel": math.hypot(p[0] - p0[0], p[1] - p0[1]), "travel_3d": (p - p0).norm(),
                         "rotation_deg": math.degrees(min(turn, 2 * math.pi - turn)),
                         "peak_force": float(self.peak[k]), "peak_force_time": float(self.peakTime[k]),
                         "peak_force_mean": float(self.peakMean[k]),
                         "peak_force_mean_time": float(self.peakMeanTime[k]),
                         "first_contact": float(self.firstContact[k]), "top": top, "cover": cover,
                         "buried": bool(cover > 0),
                         "outside_grid": bool(np.any(np.array(list(p)) < self.gridLo) or
                                              np.any(np.array(list(p)) > self.gridHi))})
        return rows


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


REPORT_UNITS = {"id": "", "x0": "m", "y0": "m", "z0": "m", "x": "m", "y": "m", "z": "m", "travel": "m",
                "travel_3d": "m", "rotation_deg": "deg", "peak_force": "N", "peak_force_time": "s",
                "peak_force_mean": "N", "peak_force_mean_time": "s",
                "first_contact": "s", "top": "m", "cover": "m", "buried": "", "outside_grid": ""}


def writeReport(folder, rows):
    """``blocks.csv`` and ``blocks.h5`` (one dataset per column, its unit as an attribute) in
    ``folder``; returns their paths."""
    os.makedirs(folder, exist_ok=True)
    keys = list(REPORT_UNITS)
    csvPath = os.path.join(folder, "blocks.csv")
    with open(csvPath, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["%s [%s]" % (k, REPORT_UNITS[k]) if REPORT_UNITS[k] else k for k in keys])
        for r in rows:
            w.writerow([("%.6g" % r[k]) if isinstance(r[k], float) else int(r[k]) for k in keys])
    h5Path = os.path.join(folder, "blocks.h5")
    import h5py
    with h5py.File(h5Path, "w") as f:
        for k in keys:
            d = f.create_dataset(k, data=np.array([r[k] for r in rows]))
            d.attrs["unit"] = REPORT_UNITS[k]
    return csvPath, h5Path
