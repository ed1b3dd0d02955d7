#!/usr/bin/env python3
"""A debris avalanche down a synthetic valley onto a run-out plain (field scale, MPM).

    yade -n -x examples/field_valley.py [--dx 0.5] [--duration 20] [--out DIR]
                                        [--backend cpu|cuda] [--precision double|float]
                                        [--terrain FILE --origin X Y Z]
    /usr/bin/python3 examples/field_valley.py ...          (same, without YADE's GUI shell)

The valley (``mpmsdem.terrain.Terrain.valley``) is 60 m long and 16 m wide: its floor, 4 m wide,
falls at 28° over 26 m and levels out into a 34 m run-out plain; its flanks rise at 30°. A source
volume of granular debris, 6 × 8 m in plan and up to 4 m above the ground, is released at rest
near the top and runs down under gravity (vertical: the slope is the terrain's), with Coulomb
basal friction 0.45 on the ground (24°, above the plain's slope and below the valley's), and
comes to rest on the plain. Its FLIP/PIC blend is a PIC viscosity of 1.25 m²/s (20 /s of damping at
dx 0.5 m; ``--flip-viscosity``): at field scale the run-out depends on it (docs/field.md). ``--terrain`` runs the same source on a raster of your own (ESRI ASCII
or GeoTIFF, moved by ``--origin``, the world point that becomes the grid's zero), the source box
then at ``--source X0 Y0 X1 Y1`` in the grid frame.

Outputs (``--out``, default ``results/field_valley``): ``mpm.h5`` (h5py) and ``particles.pvd``
(ParaView) of the flow, ``terrain.vtk`` (the ground, for ParaView), ``maps/`` (deposit thickness,
largest thickness and largest depth-averaged speed as ESRI ASCII grids and GeoTIFF on the
terrain's own georeference, and ``flow_maps.png``), ``field_valley.png`` (the flow's front and
kinetic energy against time) and ``summary.json``. Default: dx 0.5 m, about 12,000 material
points, a minute or two on 2 cores; ``--dx 0.25`` has eight times the points.
"""
import argparse
import json
import math
import os
import sys
import time

import mpmsdem
from mpmsdem.terrain import FlowMaps, Terrain

DEBRIS = {"density": 1800, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64, "I0": 0.279,
          "grain_diameter": 0.005, "solid_density": 2650}
BASAL_FRICTION = 0.45
# The example's PIC viscosity [m²/s]: 1.25, a PIC damping of 20 /s at dx 0.5 m. Nothing calibrates
# the damping at field scale, and the run-out depends on it (docs/field.md: the front stops at
# 34-44 m for 80-5 /s; at the scenes' default, 0.005 m²/s, 0.08 /s here, 0.8 % of the points spray
# to the valley's end and the debris still moves after 20 s).
FIELD_VISCOSITY = 1.25


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dx", type=float, default=0.5, help="grid spacing [m] (default 0.5)")
    ap.add_argument("--duration", type=float, default=20.0, help="simulated time [s] (default 20)")
    ap.add_argument("--out", default=os.path.join("results", "field_valley"), help="output folder")
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    ap.add_argument("--precision", default="double", choices=("double", "float"))
    ap.add_argument("--terrain", default=None, help="a raster of your own (.asc, GeoTIFF) instead of the valley")
    ap.add_argument("--origin", type=float, nargs=3, default=(0.0, 0.0, 0.0), metavar=("X", "Y", "Z"),
                    help="with --terrain: the file's point that becomes the grid's zero [m]")
    ap.add_argument("--source", type=float, nargs=4, default=(2.0, 4.0, 8.0, 12.0), metavar=("X0", "Y0", "X1", "Y1"),
                    help="the source volume's plan [m] in the grid frame (default: the valley's, near its top)")
    ap.add_argument("--source-depth", type=float, default=4.0, help="the source's depth above the ground [m]")
    ap.add_argument("--flip-viscosity", type=float, default=FIELD_VISCOSITY,
                    help="PIC viscosity of the FLIP/PIC blend [m²/s] > 0 (default %g: 20 /s of PIC damping at dx "
                         "0.5 m; docs/field.md)" % FIELD_VISCOSITY)
    ap.add_argument("--no-plots", action="store_true")
    a = ap.parse_args(argv)
    if not (a.dx > 0 and math.isfinite(a.dx)):
        raise ValueError("--dx = %r m: must be > 0 and finite" % (a.dx,))
    if not (a.duration > 0 and math.isfinite(a.duration)):
        raise ValueError("--duration = %r s: must be > 0 and finite" % (a.duration,))
    if not (a.source[2] > a.source[0] and a.source[3] > a.source[1]):
        raise ValueError("--source = %r: must be X0 Y0 X1 Y1 with X1 > X0 and Y1 > Y0" % (a.source,))
    if not (a.flip_viscosity > 0 and math.isfinite(a.flip_viscosity)):
        raise ValueError("--flip-viscosity = %r m²/s: must be > 0 and finite" % (a.flip_viscosity,))
    if not (a.source_depth > 0):
        raise ValueError("--source-depth = %r m: must be > 0" % (a.source_depth,))
    return a


def snap(v, dx, up):
    """v [m] on the grid's lines (the grid's origin is 0 on x and y)."""
    return (math.ceil if up else math.floor)(v / dx - 1e-9) * dx


def scene(a):
    """The terrain, the grid around it and the source box."""
    if a.terrain:
        ground = Terrain.read(a.terrain, origin=a.origin, friction=BASAL_FRICTION)
    else:
        ground = Terrain.valley(60.0, 16.0, 0.5, slope_deg=28.0, side_slope_deg=30.0, floor_width=4.0, runout=34.0,
                                friction=BASAL_FRICTION)
    x0, x1, y0, y1 = ground.extent
    dx = a.dx
    # the grid covers the raster, with the two wall layers outside it, and the relief plus room
    # for the source above its highest point
    lo = [snap(x0, dx, False) - 2 * dx, snap(y0, dx, False) - 2 * dx, snap(ground.heights.min(), dx, False) - 2 * dx]
    top = ground.heights.max() + a.source_depth + 2.0
    cells = [int(round((snap(x1, dx, True) - lo[0]) / dx)) + 2, int(round((snap(y1, dx, True) - lo[1]) / dx)) + 2,
             int(math.ceil((top - lo[2]) / dx)) + 2]
    sx0, sy0, sx1, sy1 = (snap(a.source[0], dx, False), snap(a.source[1], dx, False), snap(a.source[2], dx, True),
                          snap(a.source[3], dx, True))
    # the source: a box from the ground up to source_depth above the ground's highest point under it
    import numpy as np
    xs, ys = np.meshgrid(np.linspace(sx0, sx1, 9), np.linspace(sy0, sy1, 9))
    floor = float(ground.height(xs, ys).min())
    ceiling = float(ground.height(xs, ys).max()) + a.source_depth
    box = {"lo": [sx0, sy0, snap(max(floor, lo[2] + 2 * dx), dx, False)],
           "hi": [sx1, sy1, snap(ceiling, dx, True)], "ppc": 8}
    return ground, {"dx": dx, "cells": cells, "origin": lo}, box


def main(argv):
    a = parse(argv)
    from yade import O
    ground, grid, box = scene(a)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    O.reset()
    mpm = mpmsdem.MpmEngine(grid=grid, material=DEBRIS, particles=[box], gravity=(0, 0, -9.81), terrain=ground,
                            flipViscosity=a.flip_viscosity, backend=a.backend, precision=a.precision, output=out, outputEvery=1.0, verbose=False)
    O.engines = [mpm.runner]
    ground.writeVtk(os.path.join(out, "terrain.vtk"))
    maps = FlowMaps(ground)
    p0 = mpm.particles()
    mass0 = float(p0["mass"].sum())
    maps.sample(p0)
    print("field valley: %d material points (%.0f m³ of debris, %.0f t), grid %s cells of %g m, terrain %d x %d nodes of "
          "%g m, %s, %s" % (len(p0["mass"]), (p0["volume0"]).sum(), mass0 / 1000.0, "x".join(map(str, grid["cells"])),
                            a.dx, ground.shape[0], ground.shape[1], ground.spacing, mpm.solver.flipBlend,
                            mpm.solver.name))
    sample = 0.1  # [s] between map samples
    t0 = time.time()
    series = []
    while O.time < a.duration - 1e-9:
        O.dt = 0.5 * mpm.stableTimeStep()  # the bound falls as the flow speeds up
        mpmsdem.run(max(1, int(round(min(sample, a.duration - O.time) / O.dt))), mpm)
        p = mpm.particles()
        maps.sample(p)
        speed = (p["v"] ** 2).sum(axis=1) ** 0.5
        series.append((O.time, float(p["x"][:, 0].max()), mpm.kineticEnergy(), float(speed.max())))
        if len(series) % 20 == 0 or O.time >= a.duration - 1e-9:
            wall = time.time() - t0
            print("  t %5.1f s: front x %.1f m, kinetic energy %.3g J, largest speed %.1f m/s; %.0f s so far, about "
                  "%.0f s left" % (O.time, series[-1][1], series[-1][2], series[-1][3], wall,
                                   wall * max(0.0, a.duration - O.time) / O.time))
    mpm.finish(True)
    wall = time.time() - t0
    p = mpm.particles()
    written = maps.write(os.path.join(out, "maps"), title="Debris in the valley after %g s, dx %g m" % (O.time, a.dx))
    deposited = maps.deposit_thickness > 0.05
    summary = {"dx": a.dx, "duration": O.time, "points": int(len(p["mass"])), "mass": float(p["mass"].sum()),
               "mass_seeded": mass0, "flip_blend": mpm.solver.flipBlend,
               "flip_damping_rate": mpm.solver.flipDampingRate(O.dt), "basal_friction": BASAL_FRICTION,
               "front_x": float(p["x"][:, 0].max()), "kinetic_energy": mpm.kineticEnergy(),
               "below_ground": int((p["x"][:, 2] < ground.height(p["x"][:, 0], p["x"][:, 1]) - 1e-9).sum()),
               "deposit_area": float(deposited.sum() * ground.spacing ** 2),
               "max_deposit_thickness": float(maps.deposit_thickness.max()),
               "max_speed": float(maps.max_speed.max()), "unmapped_points": maps.outside,
               "wall_seconds": wall, "maps": written}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if not a.no_plots:
        plotSeries(series, os.path.join(out, "field_valley.png"), a.dx)
    print("after %.1f s: front at x %.1f m, kinetic energy %.3g J (at rest below ~1e3 J); deposit over %.0f m² (>5 cm), "
          "%.2f m thick at most; fastest depth-averaged flow %.1f m/s; mass %s; %d points below the ground; "
          "wall time %.0f s; outputs in %s" % (O.time, summary["front_x"], summary["kinetic_energy"],
                                               summary["deposit_area"], summary["max_deposit_thickness"],
                                               summary["max_speed"],
                                               "conserved" if summary["mass"] == mass0 else "CHANGED",
                                               summary["below_ground"], wall, out))
    return summary


def plotSeries(series, path, dx):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    s = np.array(series)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    ax[0].plot(s[:, 0], s[:, 1])
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("front x [m]")
    ax[1].semilogy(s[:, 0], np.maximum(s[:, 2], 1e-3))
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("kinetic energy [J]")
    fig.suptitle("Debris avalanche in the valley, dx %g m" % dx)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":  # also under `yade -x`, which runs scripts as __main__
    main(sys.argv[1:])
