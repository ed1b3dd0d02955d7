"""Terrain under the flow: a raster height field for ``MpmEngine(terrain=...)``.

A :class:`Terrain` is heights ``z[i, j]`` [m] at ``(x0 + i·spacing, y0 + j·spacing)`` in the
grid frame (i along x, west to east; j along y, south to north), read between nodes linearly on
the two triangles of each raster cell (split along the diagonal from node (i+1, j) to node
(i, j+1)) and continued flat beyond the raster (``pkg/common/Terrain.hpp``, the same formula on
CPU and CUDA). The flow cannot enter it: grid nodes at or below the surface lose their velocity
into it, with Coulomb friction on the rest (the walls' law of Appendix A, along the surface's
normal), and material points carried below it are lifted back onto it. Use it with vertical
gravity (a real slope, not the flumes' rotated one).

Rasters come from files (:meth:`Terrain.read`: ESRI ASCII grids with the driver's own reader,
GeoTIFF and whatever else GDAL reads through Debian's ``python3-gdal``) or are made
(:meth:`Terrain.plane`, :meth:`Terrain.valley`). A georeferenced raster is moved into the grid
frame by ``origin`` (the world point that becomes the grid frame's zero), which keeps float runs
accurate far from the map's origin; :attr:`Terrain.georeference` keeps what maps written back on
the raster's own grid need.
"""
import math
import os

import numpy as np

from . import _mpmsdem


def _friction(value):
    """A friction as the scene takes it: "free", "noslip" or a Coulomb coefficient >= 0."""
    if value in ("free", "noslip"):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (0 <= value < math.inf):
        raise ValueError("friction = %r: must be 'free', 'noslip' or a Coulomb coefficient >= 0" % (value,))
    return float(value)


class Terrain:
    """A height field in the grid frame.

    :param heights: array (nx, ny) of heights [m], nx, ny >= 2, finite (fill a raster's no-data
        cells first).
    :param spacing: raster spacing [m] > 0.
    :param x0, y0: position of node (0, 0) in the grid frame [m].
    :param friction: flow–terrain friction: ``"free"`` (default), ``"noslip"`` or a Coulomb
        coefficient >= 0 (the basal friction of the flow on the ground).
    :param georeference: for rasters read from a file: ``{"x0", "y0"}`` of node (0, 0) in the
        file's coordinates, ``"origin"`` (the world point at the grid frame's zero), ``"crs"``
        (the file's coordinate reference system as WKT, or None), ``"path"``.
    """

    def __init__(self, heights, spacing, x0=0.0, y0=0.0, friction="free", georeference=None):
        z = np.array(heights, dtype=float)
        if z.ndim != 2 or z.shape[0] < 2 or z.shape[1] < 2:
            raise ValueError("heights: must be a 2-D array of at least 2 x 2 nodes, got shape %s" % (z.shape,))
        bad = np.argwhere(~np.isfinite(z))
        if len(bad):
            raise ValueError("heights: %d values are not finite, the first at node i %d, j %d (fill the raster's "
                             "no-data cells first)" % (len(bad), bad[0][0], bad[0][1]))
        if not (spacing > 0 and math.isfinite(spacing)):
            raise ValueError("spacing = %r m: must be > 0 and finite" % (spacing,))
        for name, v in (("x0", x0), ("y0", y0)):
            if not math.isfinite(v):
                raise ValueError("%s = %r m: must be finite" % (name, v))
        self.heights = z
        self.spacing = float(spacing)
        self.x0, self.y0 = float(x0), float(y0)
        self.friction = _friction(friction)
        self.georeference = georeference

    @property
    def shape(self):
        return self.heights.shape

    @property
    def extent(self):
        """(x_min, x_max, y_min, y_max) of the raster's nodes in the grid frame [m]."""
        nx, ny = self.heights.shape
        return (self.x0, self.x0 + (nx - 1) * self.spacing, self.y0, self.y0 + (ny - 1) * self.spacing)

    @classmethod
    def read(cls, path, origin=(0.0, 0.0, 0.0), friction="free"):
        """A terrain from a raster file: ``.asc`` (ESRI ASCII grid, read as the driver reads it)
        or any raster GDAL reads (GeoTIFF, …; band 1). Heights at the cell centres; the world
        point ``origin`` (x, y, z) [m] goes to the grid frame's zero. ValueError naming the file
        for unreadable or incomplete rasters and no-data cells."""
        origin = [float(v) for v in origin]
        if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
            raise ValueError("origin = %r: must be three finite coordinates [m]" % (origin,))
        if str(path).lower().endswith(".asc"):
            r = _mpmsdem.readEsriAscii(str(path))
            z, x0, y0, spacing, crs = r["heights"], r["x0"], r["y0"], r["spacing"], None
        else:
            z, x0, y0, spacing, crs = _readGdal(str(path))
        geo = {"x0": x0, "y0": y0, "origin": tuple(origin), "crs": crs, "path": os.path.abspath(str(path))}
        return cls(np.asarray(z) - origin[2], spacing, x0 - origin[0], y0 - origin[1], friction, geo)

    @classmethod
    def plane(cls, lo, hi, spacing, z0=0.0, slope_x_deg=0.0, slope_y_deg=0.0, friction="free"):
        """A plane over [lo, hi] (x, y) [m]: height z0 at lo, falling along +x at slope_x_deg and
        along +y at slope_y_deg (negative: rising)."""
        nx = int(round((hi[0] - lo[0]) / spacing)) + 1
        ny = int(round((hi[1] - lo[1]) / spacing)) + 1
        x = lo[0] + spacing * np.arange(nx)
        y = lo[1] + spacing * np.arange(ny)
        z = (z0 - math.tan(math.radians(slope_x_deg)) * (x - lo[0])[:, None]
             - math.tan(math.radians(slope_y_deg)) * (y - lo[1])[None, :])
        return cls(z, spacing, lo[0], lo[1], friction)

    @classmethod
    def valley(cls, length, width, spacing, slope_deg=15.0, side_slope_deg=25.0, floor_width=None, runout=0.0,
               z_low=0.0, friction="free"):
        """A synthetic valley along +x: a V-shaped (or flat-floored) cross-section whose flanks
        rise at side_slope_deg from a floor ``floor_width`` wide (default a fifth of the width)
        on the centre line y = width/2, the floor falling at slope_deg along +x and levelling
        out over the last ``runout`` metres (a run-out plain at height z_low)."""
        if not (0 <= runout < length):
            raise ValueError("runout = %r m: must be in [0, length)" % (runout,))
        floor = width / 5.0 if floor_width is None else floor_width
        nx = int(round(length / spacing)) + 1
        ny = int(round(width / spacing)) + 1
        x = spacing * np.arange(nx)
        y = spacing * np.arange(ny)
        slope_end = length - runout
        along = z_low + math.tan(math.radians(slope_deg)) * np.maximum(slope_end - x, 0.0)
        across = math.tan(math.radians(side_slope_deg)) * np.maximum(np.abs(y - width / 2.0) - floor / 2.0, 0.0)
        return cls(along[:, None] + across[None, :], spacing, 0.0, 0.0, friction)

    def height(self, x, y):
        """Surface height [m] at (x, y) in the grid frame (arrays broadcast): linear on the two
        triangles of each raster cell, flat beyond the raster, as the solver reads it."""
        nx, ny = self.heights.shape

        def axis(u, n):
            uc = np.clip(u, 0.0, n - 1.0)
            c = np.minimum(uc.astype(int), n - 2)
            return c, uc - c

        i, fx = axis((np.asarray(x, dtype=float) - self.x0) / self.spacing, nx)
        j, fy = axis((np.asarray(y, dtype=float) - self.y0) / self.spacing, ny)
        z = self.heights
        z00, z01, z10, z11 = z[i, j], z[i, j + 1], z[i + 1, j], z[i + 1, j + 1]
        lower = fx + fy <= 1.0
        return np.where(lower, z00 + fx * (z10 - z00) + fy * (z01 - z00),
                        z11 - (1.0 - fx) * (z11 - z01) - (1.0 - fy) * (z11 - z10))

    def scene(self):
        """The scene's ``"terrain"`` entry (heights inline, i-major)."""
        nx, ny = self.heights.shape
        return {"nx": nx, "ny": ny, "x0": self.x0, "y0": self.y0, "spacing": self.spacing,
                "heights": self.heights.ravel().tolist(), "friction": self.friction}

    def writeVtk(self, path):
        """The surface for ParaView: a legacy VTK structured grid of the raster's nodes in the
        grid frame (the flow's frame), heights as a point field."""
        nx, ny = self.heights.shape
        x = self.x0 + self.spacing * np.arange(nx)
        y = self.y0 + self.spacing * np.arange(ny)
        with open(path, "w") as f:
            f.write("# vtk DataFile Version 3.0\nmpmsdem terrain\nASCII\nDATASET STRUCTURED_GRID\n")
            f.write("DIMENSIONS %d %d 1\nPOINTS %d double\n" % (nx, ny, nx * ny))
            for j in range(ny):  # VTK: x fastest
                f.write("".join("%.10g %.10g %.10g\n" % (x[i], y[j], self.heights[i, j]) for i in range(nx)))
            f.write("POINT_DATA %d\nSCALARS height double 1\nLOOKUP_TABLE default\n" % (nx * ny))
            f.write("".join("%.10g\n" % self.heights[i, j] for j in range(ny) for i in range(nx)))
        return path

    def writeAsc(self, path, values=None, nodata=-9999.0):
        """Write ``values`` (default: the heights; an array of the raster's shape, NaN for no
        data) as an ESRI ASCII grid on this raster's nodes, in the file's own coordinates for a
        read raster (cell centres, north row first)."""
        v = self.heights if values is None else np.asarray(values, dtype=float)
        if v.shape != self.heights.shape:
            raise ValueError("values: shape %s, must be the raster's %s" % (v.shape, self.heights.shape))
        x0, y0 = self.x0, self.y0
        if self.georeference:
            x0, y0 = self.georeference["x0"], self.georeference["y0"]
        nx, ny = v.shape
        with open(path, "w") as f:
            f.write("ncols %d\nnrows %d\nxllcenter %.10g\nyllcenter %.10g\ncellsize %.10g\nNODATA_value %g\n"
                    % (nx, ny, x0, y0, self.spacing, nodata))
            rows = np.where(np.isfinite(v), v, nodata).T[::-1]  # north row first
            for row in rows:
                f.write(" ".join("%.9g" % z for z in row) + "\n")


def _readGdal(path):
    try:
        from osgeo import gdal
    except ImportError as e:
        raise ValueError("terrain file '%s': reading this format needs GDAL's Python bindings (Debian: "
                         "python3-gdal, installed by `make`); ESRI ASCII grids (.asc) need nothing more" % path) from e
    gdal.UseExceptions()
    try:
        ds = gdal.Open(path)
    except RuntimeError as e:
        raise ValueError("terrain file '%s': GDAL cannot read it (%s)" % (path, e)) from e
    gt = ds.GetGeoTransform()
    if gt[2] != 0 or gt[4] != 0 or abs(abs(gt[5]) - gt[1]) > 1e-9 * gt[1]:
        raise ValueError("terrain file '%s': cells must be square and the raster north-up (geotransform %s)"
                         % (path, gt))
    band = ds.GetRasterBand(1)
    rows = band.ReadAsArray().astype(float)  # (rows, cols), row 0 at the top
    nodata = band.GetNoDataValue()
    spacing = gt[1]
    north_up = gt[5] < 0
    z = (rows[::-1] if north_up else rows).T  # (cols, rows), j from the south
    if nodata is not None:
        z[z == nodata] = np.nan
    missing = np.argwhere(~np.isfinite(z))
    if len(missing):
        raise ValueError("terrain file '%s': %d no-data values, the first at column %d, row %d from the south: fill "
                         "them before using the raster as a terrain" % (path, len(missing), missing[0][0],
                                                                         missing[0][1]))
    x0 = gt[0] + 0.5 * spacing
    y0 = (gt[3] - rows.shape[0] * spacing if north_up else gt[3]) + 0.5 * spacing
    return z, x0, y0, spacing, ds.GetProjection() or None


def mapOffset(terrain):
    """(x, y, z) [m] that take a point of the grid frame into the map's own coordinates (those of
    the raster file the terrain was read from): the world point ``origin`` the raster was moved
    by (:meth:`Terrain.read`), so that map = grid + offset; (0, 0, 0) for a terrain made in the
    grid frame (:meth:`Terrain.plane`, :meth:`Terrain.valley`: its grid frame is its map's) or
    None."""
    geo = getattr(terrain, "georeference", None) if terrain is not None else None
    if geo and geo.get("origin") is not None:
        return tuple(float(v) for v in geo["origin"])
    return (0.0, 0.0, 0.0)


class FlowMaps:
    """Maps of a flow over a terrain on the terrain's raster. Call :meth:`sample` with the
    engine's particles at the times to take (the last sample is the deposit); :meth:`write`
    writes them as ESRI ASCII grids (and GeoTIFF where GDAL is installed) on the raster's own
    georeference, and as a PNG.

    Each sample puts the material points on the raster's nodes: a point's initial volume
    V₀ = m/ρ₀, its mass m and its momentum m·v are shared among the four raster nodes around it
    with linear weights (summing to one). At a node, over its square of side ``spacing`` (s):

    - the thickness h = ΣV₀/s² [m]: the material's volume at its initial bulk density per unit
      area (points spread thin by the flow, whose current volume J·V₀ is far larger, count as the
      material they carry, not as the space they fill);
    - the depth-averaged speed v = |Σm·v|/Σm [m/s]: the column's momentum over its mass;
    - the column's density ρ = Σm/ΣV₀ [kg/m³]: its mass over its volume at the initial density
      (the material's ρ₀ for a flow of one material);
    - the momentum flux ρ·h·v² [N/m] (= Σm/s²·v²: the momentum carried across a metre of width
      per second; a field comparison of run-out models at Montecito found its peak the best
      predictor of damaged buildings, Barnhart et al. 2024, NHESS 24:1459);
    - the dynamic pressure ρ·v² [Pa].

    The maps: ``deposit_thickness`` (h of the last sample), ``max_thickness``, ``max_speed`` and
    ``max_momentum_flux`` (the largest over the samples; 0 where no material ever came), and,
    only where the flow is at least ``minThickness`` thick (h >= minThickness and h > 0: a node
    holding material), so that a few stray fast points do not paint them:
    ``max_dynamic_pressure`` (the largest ρ·v² over the samples at which the node was that
    thick) and ``arrival_time`` (the time of the first sample at which it was); NaN (no data in
    the files) where never reached.

    :param terrain: the :class:`Terrain` the flow runs on.
    :param minThickness: the thickness [m] >= 0 at which the flow reaches a node for the
        pressure and arrival maps (default 0.1 m: at the field example's Δx 0.5 m and 8 points
        per cell one point alone spreads at most 0.0625 m onto a node of its 0.5 m raster, so
        it takes two points).
    """

    NAMES = ("deposit_thickness", "max_thickness", "max_speed", "max_momentum_flux", "max_dynamic_pressure",
             "arrival_time")
    UNITS = {"deposit_thickness": "m", "max_thickness": "m", "max_speed": "m/s", "max_momentum_flux": "N/m",
             "max_dynamic_pressure": "Pa", "arrival_time": "s"}

    def __init__(self, terrain, minThickness=0.1):
        if isinstance(minThickness, bool) or not isinstance(minThickness, (int, float, np.floating, np.integer)) \
                or not (0 <= minThickness < math.inf):
            raise ValueError("minThickness = %r m: must be a thickness >= 0 and finite" % (minThickness,))
        self.terrain = terrain
        self.minThickness = float(minThickness)
        shape = terrain.heights.shape
        self.deposit_thickness = np.zeros(shape)
        self.max_thickness = np.zeros(shape)
        self.max_speed = np.zeros(shape)
        self.max_momentum_flux = np.zeros(shape)
        self.max_dynamic_pressure = np.full(shape, np.nan)
        self.arrival_time = np.full(shape, np.nan)
        self.samples = 0
        self.time = None  # the last sample's time [s], when given
        self.outside = 0  # points of the last sample beyond the raster (not mapped)

    def _weights(self, x):
        """The four raster nodes around each point and their linear weights (summing to one),
        and which points lie on the raster (within half a spacing of its outer nodes)."""
        t = self.terrain
        nx, ny = t.heights.shape
        u = (x[:, 0] - t.x0) / t.spacing
        w = (x[:, 1] - t.y0) / t.spacing
        on = (u >= -0.5) & (u <= nx - 0.5) & (w >= -0.5) & (w <= ny - 0.5)
        u, w = np.clip(u, 0.0, nx - 1.0), np.clip(w, 0.0, ny - 1.0)
        i, j = np.minimum(u.astype(np.int64), nx - 2), np.minimum(w.astype(np.int64), ny - 2)
        fx, fy = u - i, w - j
        nodes = [i * ny + j, (i + 1) * ny + j, i * ny + j + 1, (i + 1) * ny + j + 1]
        weights = [(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy]
        return nodes, weights, on

    def sample(self, particles, time=None):
        """Add one sample of ``particles`` (the dict of ``MpmEngine.particles()``: x, v, mass,
        volume0) taken at ``time`` [s] (e.g. ``O.time``; finite, not before the previous
        sample's). Without a time (callers written before the arrival map) the sample adds
        to every map but ``arrival_time``."""
        if time is not None:
            if isinstance(time, bool) or not math.isfinite(time):
                raise ValueError("time = %r s: must be finite" % (time,))
            time = float(time)
            if self.time is not None and time < self.time:
                raise ValueError("time = %r s: before the previous sample's %r s (samples in time order)"
                                 % (time, self.time))
        x = np.asarray(particles["x"], dtype=float).reshape(-1, 3)
        v = np.asarray(particles["v"], dtype=float).reshape(-1, 3)
        m = np.asarray(particles["mass"], dtype=float)
        vol = np.asarray(particles["volume0"], dtype=float)
        nodes, weights, on = self._weights(x)
        self.outside = int((~on).sum())
        n = self.deposit_thickness.size
        shape = self.deposit_thickness.shape

        def spread(values):
            return sum(np.bincount(k[on], (w * values)[on], n) for k, w in zip(nodes, weights))
        volume = spread(vol)
        thickness = (volume / self.terrain.spacing ** 2).reshape(shape)
        mass = spread(m)
        momentum = np.stack([spread(m * v[:, d]) for d in range(3)])
        speed = (np.sqrt((momentum ** 2).sum(axis=0)) / np.where(mass > 0, mass, 1.0)).reshape(shape)
        density = (mass / np.where(volume > 0, volume, 1.0)).reshape(shape)  # 0 where no material
        reached = (thickness >= self.minThickness) & (thickness > 0)
        self.deposit_thickness = thickness
        self.max_thickness = np.maximum(self.max_thickness, thickness)
        self.max_speed = np.maximum(self.max_speed, speed)
        self.max_momentum_flux = np.maximum(self.max_momentum_flux, density * thickness * speed ** 2)
        self.max_dynamic_pressure = np.where(reached, np.fmax(self.max_dynamic_pressure, density * speed ** 2),
                                             self.max_dynamic_pressure)
        if time is not None:
            self.arrival_time[reached & np.isnan(self.arrival_time)] = time
            self.time = time
        self.samples += 1

    def write(self, folder, blocks=None, title=None):
        """Write the maps of :attr:`NAMES` (deposit and largest thickness, largest speed,
        momentum flux and dynamic pressure, arrival time) as ``.asc`` (and ``.tif`` with GDAL;
        NaN as no data, -9999) into ``folder``, and ``flow_maps.png`` (the maps over the
        terrain's contours; ``blocks``: optional (x, y) positions [m] in the grid frame to draw).
        Returns the paths written."""
        os.makedirs(folder, exist_ok=True)
        paths = []
        for name in self.NAMES:
            path = os.path.join(folder, name + ".asc")
            self.terrain.writeAsc(path, getattr(self, name))
            paths.append(path)
            tif = _writeGeoTiff(self.terrain, os.path.join(folder, name + ".tif"), getattr(self, name))
            if tif:
                paths.append(tif)
        paths.append(self._plot(os.path.join(folder, "flow_maps.png"), blocks, title))
        return paths

    def _plot(self, path, blocks, title):
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        t = self.terrain
        x0, x1, y0, y1 = t.extent
        half = 0.5 * t.spacing
        box = (x0 - half, x1 + half, y0 - half, y1 + half)
        fig, axes = plt.subplots(3, 2, figsize=(18, 10), sharex=True, sharey=True)
        for ax, name in zip(axes.T.ravel(), self.NAMES):  # the first three down the left column
            values = getattr(self, name)
            hidden = ~np.isfinite(values) if name == "arrival_time" else ~(values > 0)
            shown = np.ma.masked_where(hidden, values)
            cmap = "plasma_r" if name == "arrival_time" else "viridis"
            im = ax.imshow(shown.T, origin="lower", extent=box, cmap=cmap, aspect="equal")
            if np.ptp(t.heights) > 0:
                ax.contour(x0 + t.spacing * np.arange(t.shape[0]), y0 + t.spacing * np.arange(t.shape[1]),
                           t.heights.T, levels=12, colors="0.5", linewidths=0.5)
            if blocks is not None and len(blocks):
                b = np.asarray(blocks)
                ax.plot(b[:, 0], b[:, 1], "s", mfc="none", mec="r", ms=4)
            label = "%s [%s]" % (name.replace("_", " "), self.UNITS[name])
            if name in ("max_dynamic_pressure", "arrival_time"):
                label += "\nwhere ≥ %g m thick" % self.minThickness
            fig.colorbar(im, ax=ax, label=label)
            ax.set_ylabel("y [m]")
        for ax in axes[-1]:
            ax.set_xlabel("x [m] (grid frame; contours: the terrain)")
        if title:
            fig.suptitle(title)
        fig.tight_layout()
        fig.savefig(path, dpi=90)
        plt.close(fig)
        return path


def _writeGeoTiff(terrain, path, values, nodata=-9999.0):
    """The map as a GeoTIFF on the raster's own georeference (NaN written as ``nodata``), or
    None without GDAL."""
    try:
        from osgeo import gdal
    except ImportError:
        return None
    gdal.UseExceptions()
    nx, ny = values.shape
    x0, y0 = terrain.x0, terrain.y0
    crs = None
    if terrain.georeference:
        x0, y0, crs = terrain.georeference["x0"], terrain.georeference["y0"], terrain.georeference.get("crs")
    s = terrain.spacing
    ds = gdal.GetDriverByName("GTiff").Create(path, nx, ny, 1, gdal.GDT_Float64)
    ds.SetGeoTransform((x0 - 0.5 * s, s, 0.0, y0 + (ny - 0.5) * s, 0.0, -s))
    if crs:
        ds.SetProjection(crs)
    band = ds.GetRasterBand(1)
    v = np.asarray(values, dtype=float)
    band.WriteArray(np.where(np.isfinite(v), v, nodata).T[::-1])
    band.SetNoDataValue(nodata)
    ds.FlushCache()
    return path
