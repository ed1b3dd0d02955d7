#!/usr/bin/env python3
"""A debris avalanche down a synthetic valley onto a run-out plain with 200 blocks on it (field
scale, MPM–SDEM).

    yade -n -x examples/field_valley.py [--dx 0.5] [--duration 20] [--out DIR]
                                        [--backend cpu|cuda] [--precision double|float]
                                        [--blocks N | --block-table CSV]
                                        [--terrain FILE --origin X Y Z]
                                        [--min-thickness M] [--rescue-distance D]
    /usr/bin/python3 examples/field_valley.py ...          (same, without YADE's GUI shell)

The valley (``mpmsdem.terrain.Terrain.valley``) is 60 m long and 16 m wide: its floor, 4 m wide,
falls at 28° over 26 m and levels out into a 34 m run-out plain; its flanks rise at 30°. A source
volume of granular debris, 6 × 8 m in plan and up to 4 m above the ground, is released at rest
near the top and runs down under gravity (vertical: the slope is the terrain's), with Coulomb
basal friction 0.45 on the ground (24°, above the plain's slope and below the valley's), and
comes to rest on the plain. ``--blocks N`` (default 200) 1 m blocks of 2 t (sheds, boulders)
stand on a jittered grid over the plain and the lower flanks, turned at random, resting on the
ground (block–ground friction 0.7); ``--block-table`` places your own (CSV ``id, shape, x, y,
heading_deg, mass``, shape ``box:LxWxH`` or a mesh file: ``mpmsdem.field``); ``--blocks 0`` runs
the flow alone. Its FLIP/PIC blend is a PIC viscosity of 0.3125 m²/s (5 /s of damping at
dx 0.5 m, chosen against AvaFrame; ``--flip-viscosity``): at field scale the run-out depends on it
(docs/field.md). ``--terrain`` runs the same source on a raster of your own (ESRI ASCII
or GeoTIFF, moved by ``--origin``, the world point that becomes the grid's zero), the source box
then at ``--source X0 Y0 X1 Y1`` in the grid frame.

Outputs (``--out``, default ``results/field_valley``): ``blocks.csv`` and ``blocks.h5`` (per block:
final position in the grid frame and in the map's own coordinates (the raster's: the grid frame
moved back by ``--origin``), travel, rotation, peak flow force and its time, first contact, the
depth of debris above its top at its centre, the fraction of its plan covered, buried or partly
buried; ``blocks.h5`` also each block's 10 ms mean flow force against time), ``rescue.csv`` (the
blocks a search must find: buried, partly buried or moved more than ``--rescue-distance``, default
1 m; where they are in map coordinates and how deep, deepest first; also printed),
``blocks_input.csv`` (the table placed), ``coupled.h5``, ``scene.pvd`` (ParaView: flow and
blocks), ``mpm.h5`` (h5py) and ``particles.pvd`` (ParaView) of the flow, ``terrain.vtk`` (the
ground, for ParaView), ``maps/`` (deposit thickness, largest thickness, largest depth-averaged
speed, largest momentum flux ρhv², largest dynamic pressure ρv² and first arrival time, the last
two where the flow is at least ``--min-thickness`` thick, default 0.1 m: ESRI ASCII grids and
GeoTIFF on the terrain's own georeference, and ``flow_maps.png``), ``field_valley.png`` (the
flow's front and kinetic energy against time) and ``summary.json``. Default: dx 0.5 m, about
12,000 material points, a minute or two on 2 cores; ``--dx 0.25`` has eight times the points.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import mpmsdem
import mpmsdem.driver
from mpmsdem import field
from mpmsdem.terrain import FlowMaps, Terrain, mapOffset

DEBRIS = {"density": 1800, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64, "I0": 0.279,
          "grain_diameter": 0.005, "solid_density": 2650}
BASAL_FRICTION = 0.45
# The example's PIC viscosity [m²/s]: 0.3125, a PIC damping of 5 /s at dx 0.5 m, chosen against
# AvaFrame's depth-averaged runs on this valley and two standard slopes (docs/field.md, "Against
# AvaFrame"): at 20 /s (1.25 m²/s) our fronts stopped 9-23 % short of AvaFrame's at the debris's
# mu_s, at 5 /s 6-14 %, at the price of a thin fringe spreading further on open ground. Nothing
# calibrates it against an event; at the scenes' default, 0.005 m²/s (0.08 /s here), 0.8 % of the
# points spray to the valley's end and the debris still moves after 20 s.
FIELD_VISCOSITY = 0.3125
# Contacts at field scale: the barrier stiffness of Eq 10 that lets a 1 m, 2 t block rest on its
# corners at a tenth of its sweep radius (5 mm: k_c = F R / (3 delta^2) with F a quarter of its
# weight), for the blocks, the ground and the flow's points alike.
FIELD_STIFFNESS = 3e6
BLOCK_GROUND_FRICTION = 0.7  # blocks and ground (a pair takes the smaller): above the flanks' 30 deg (0.577)


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
    ap.add_argument("--source", type=float, nargs=4, default=None, metavar=("X0", "Y0", "X1", "Y1"),
                    help="the source volume's plan [m] in the grid frame (default: the valley's, near its top: "
                         "2 4 8 12 times --scale)")
    ap.add_argument("--source-depth", type=float, default=None,
                    help="the source's depth above the ground [m] (default 4 times --scale)")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="the synthetic valley, its source and its village this many times larger (default 1; the "
                         "blocks stay 1 m): 2 with --dx 0.1 is the GPU version, about 2e7 points and room for 900 "
                         "blocks")
    ap.add_argument("--flip-viscosity", type=float, default=FIELD_VISCOSITY,
                    help="PIC viscosity of the FLIP/PIC blend [m²/s] > 0 (default %g: 5 /s of PIC damping at dx "
                         "0.5 m, chosen against AvaFrame; docs/field.md)" % FIELD_VISCOSITY)
    ap.add_argument("--blocks", type=int, default=None,
                    help="1 m blocks on the valley's plain (default 200; 0: the flow alone; with --terrain only 0)")
    ap.add_argument("--block-table", default=None, help="CSV of the blocks to place instead (mpmsdem.field)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the blocks' headings")
    ap.add_argument("--min-thickness", type=float, default=0.1,
                    help="the flow's thickness [m] at which a map node counts as reached, for the dynamic pressure "
                         "and arrival time maps (default 0.1)")
    ap.add_argument("--rescue-distance", type=float, default=1.0,
                    help="rescue.csv lists the blocks buried, partly buried or moved more than this [m] (default 1)")
    ap.add_argument("--driver-scene", metavar="JSON", default=None,
                    help="write the scene (flow, terrain, blocks) for the C++ driver mpmsdem-run to JSON and exit: "
                         "e.g. to run it on a GPU machine without YADE (mpmsdem-run JSON --backend cuda)")
    ap.add_argument("--no-plots", action="store_true")
    a = ap.parse_args(argv)
    if not (a.dx > 0 and math.isfinite(a.dx)):
        raise ValueError("--dx = %r m: must be > 0 and finite" % (a.dx,))
    if not (a.duration > 0 and math.isfinite(a.duration)):
        raise ValueError("--duration = %r s: must be > 0 and finite" % (a.duration,))
    if not (a.scale > 0 and math.isfinite(a.scale)):
        raise ValueError("--scale = %r: must be > 0 and finite" % (a.scale,))
    if a.terrain and a.scale != 1.0:
        raise ValueError("--scale = %r: the synthetic valley's; a --terrain keeps its own size" % (a.scale,))
    a.source = tuple(a.source) if a.source else tuple(a.scale * v for v in (2.0, 4.0, 8.0, 12.0))
    a.source_depth = a.source_depth if a.source_depth is not None else 4.0 * a.scale
    if not (a.source[2] > a.source[0] and a.source[3] > a.source[1]):
        raise ValueError("--source = %r: must be X0 Y0 X1 Y1 with X1 > X0 and Y1 > Y0" % (a.source,))
    if not (a.flip_viscosity > 0 and math.isfinite(a.flip_viscosity)):
        raise ValueError("--flip-viscosity = %r m²/s: must be > 0 and finite" % (a.flip_viscosity,))
    if a.blocks is None:
        a.blocks = 0 if a.terrain else 200
    if a.blocks < 0:
        raise ValueError("--blocks = %d: must be >= 0" % a.blocks)
    if a.terrain and a.blocks:
        raise ValueError("--blocks = %d: the generated blocks stand on the valley's plain; on your own --terrain "
                         "place them with --block-table" % a.blocks)
    if not (0 <= a.min_thickness < math.inf):
        raise ValueError("--min-thickness = %r m: must be >= 0 and finite" % (a.min_thickness,))
    if not (0 <= a.rescue_distance < math.inf):
        raise ValueError("--rescue-distance = %r m: must be >= 0 and finite" % (a.rescue_distance,))
    if not (a.source_depth > 0):
        raise ValueError("--source-depth = %r m: must be > 0" % (a.source_depth,))
    return a


def snap(v, dx, up):
    """v [m] on the grid's lines (the grid's origin is 0 on x and y)."""
    return (math.ceil if up else math.floor)(v / dx - 1e-9) * dx


def scene(a, dx):
    """The terrain, the grid of spacing dx around it and the source box."""
    k = a.scale
    if a.terrain:
        ground = Terrain.read(a.terrain, origin=a.origin, friction=BASAL_FRICTION)
    else:
        ground = Terrain.valley(60.0 * k, 16.0 * k, 0.5, slope_deg=28.0, side_slope_deg=30.0, floor_width=4.0 * k,
                                runout=34.0 * k, friction=BASAL_FRICTION)
    x0, x1, y0, y1 = ground.extent
    # the grid covers the raster, with the two wall layers outside it, and the relief plus room
    # for the source above its highest point
    lo = [snap(x0, dx, False) - 2 * dx, snap(y0, dx, False) - 2 * dx, snap(ground.heights.min(), dx, False) - 2 * dx]
    top = ground.heights.max() + a.source_depth + 2.0
    cells = [int(round((snap(x1, dx, True) - lo[0]) / dx)) + 2, int(round((snap(y1, dx, True) - lo[1]) / dx)) + 2,
             int(math.ceil((top - lo[2]) / dx)) + 2]
    sx0, sy0, sx1, sy1 = (snap(a.source[0], dx, False), snap(a.source[1], dx, False), snap(a.source[2], dx, True),
                          snap(a.source[3], dx, True))
    # the source: a box from the ground up to source_depth above the ground's highest point under it
    xs, ys = np.meshgrid(np.linspace(sx0, sx1, 9), np.linspace(sy0, sy1, 9))
    floor = float(ground.height(xs, ys).min())
    ceiling = float(ground.height(xs, ys).max()) + a.source_depth
    box = {"lo": [sx0, sy0, snap(max(floor, lo[2] + 2 * dx), dx, False)],
           "hi": [sx1, sy1, snap(ceiling, dx, True)], "ppc": 8}
    return ground, {"dx": dx, "cells": cells, "origin": lo}, box


def village(n, seed, scale=1.0):
    """n blocks of 1 m and 2 t on a regular grid over the plain and its flanks (x 28-59 m, y
    0.5-15.5 m, times the valley's scale), turned by up to 10 deg either way, at least 1.45 m
    apart: their corners stay clear of each other, also where one stands on the floor and its
    neighbour on a 30 deg flank."""
    rng = np.random.default_rng(seed)
    x0, x1, y0, y1 = 28.0 * scale, 59.0 * scale, 0.5 * scale, 15.5 * scale
    nx = max(1, int(math.ceil(math.sqrt(n * (x1 - x0) / (y1 - y0)))))
    ny = int(math.ceil(n / nx))
    xs = np.linspace(x0, x1, nx) if nx > 1 else np.array([0.5 * (x0 + x1)])
    ys = np.linspace(y0, y1, ny) if ny > 1 else np.array([0.5 * (y0 + y1)])
    if n > 1 and min((x1 - x0) / max(nx - 1, 1), (y1 - y0) / max(ny - 1, 1)) < 1.45:
        raise ValueError("--blocks = %d: too many for the plain (1 m blocks need 1.45 m spacing there; at most "
                         "about %d)" % (n, int((x1 - x0) / 1.45 + 1) * int((y1 - y0) / 1.45 + 1)))
    rows = []
    for k in range(n):
        rows.append({"id": k, "shape": "box:1.0x1.0x1.0", "x": float(xs[k % nx]), "y": float(ys[k // nx]),
                     "heading_deg": float(rng.uniform(-10.0, 10.0)), "mass": 2000.0})
    return rows


def main(argv):
    a = parse(argv)
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    # A driver scene for a fine grid is written from engines built on a coarse one (the flow is
    # seeded by the driver from the scene's box, and nothing else depends on dx): the host need not
    # hold the fine grid.
    buildDx = max(a.dx, 0.5) if a.driver_scene else a.dx
    ground, grid, box = scene(a, buildDx)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    # a driver scene's outputs are the driver's (at a.out as the user wrote it, for the machine that
    # runs it); the engines built here to write it write none
    outputs = {} if a.driver_scene else {"output": out, "outputEvery": 1.0}
    O.reset()
    rows = field.readBlockTable(a.block_table) if a.block_table else village(a.blocks, a.seed, a.scale)
    coupled = tracker = None
    mpm = mpmsdem.MpmEngine(grid=grid, material=DEBRIS, particles=[box], gravity=(0, 0, -9.81), terrain=ground,
                            flipViscosity=a.flip_viscosity, backend=a.backend, precision=a.precision,
                            verbose=False, **outputs)
    if rows:
        field.writeBlockTable(os.path.join(out, "blocks_input.csv"), rows)
        sdem = mpmsdem.SdemEngine(verbose=False)
        sdem.terrain(ground, mpmsdem.material(density=2500, friction=BLOCK_GROUND_FRICTION,
                                              barrierStiffness=FIELD_STIFFNESS))
        materials = {}

        def blockMaterial(density):
            key = round(density, 6)
            if key not in materials:
                materials[key] = mpmsdem.material(density=density, friction=BLOCK_GROUND_FRICTION,
                                                  barrierStiffness=FIELD_STIFFNESS,
                                                  normalDamping=0.3)
            return materials[key]
        ids = field.placeBlocks(sdem, ground, rows, blockMaterial,
                                folder=os.path.dirname(os.path.abspath(a.block_table)) if a.block_table else ".")
        pairs = {m: {"friction": BASAL_FRICTION, "barrierStiffness": FIELD_STIFFNESS} for m in materials.values()}
        coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs=pairs, dtAuto=0.5, verbose=False,
                                        **dict(outputs, vtkEvery=1.0) if outputs else {})
        tracker = field.BlockTracker(coupled, ids, terrain=ground)
        O.engines = [ForceResetter(), coupled.runner, tracker.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
        O.dt = 0.5 * mpm.stableTimeStep()
    else:
        O.engines = [mpm.runner]
    if a.driver_scene:
        if coupled:
            s = mpmsdem.driver.sceneDict(coupled, duration=a.duration, dt="auto", outputEvery=1.0, outputDir=a.out)
        else:
            s = json.loads(mpm.solver.sceneJson)
            s["run"] = {"duration": a.duration, "dt": "auto", "output_every": 1.0, "output_dir": a.out}
        _, s["grid"], fine = scene(a, a.dx)
        s["particles"] = [fine]
        with open(a.driver_scene, "w") as f:
            json.dump(s, f, allow_nan=False)
        cells = s["grid"]["cells"]
        print("driver scene of the field valley (%d blocks, dx %g m, grid %s cells, at most %.3g points) written to %s: "
              "mpmsdem-run %s" % (len(rows), a.dx, "x".join(map(str, cells)),
                                  8 * np.prod([(fine["hi"][d] - fine["lo"][d]) / a.dx for d in range(3)]),
                                  a.driver_scene, a.driver_scene))
        return None
    ground.writeVtk(os.path.join(out, "terrain.vtk"))
    maps = FlowMaps(ground, minThickness=a.min_thickness)
    p0 = mpm.particles()
    mass0 = float(p0["mass"].sum())
    maps.sample(p0, O.time)
    print("field valley: %d material points (%.0f m³ of debris, %.0f t), %d blocks, grid %s cells of %g m, terrain "
          "%d x %d nodes of %g m, %s, %s" % (len(p0["mass"]), (p0["volume0"]).sum(), mass0 / 1000.0, len(rows),
                                             "x".join(map(str, grid["cells"])), a.dx, ground.shape[0],
                                             ground.shape[1], ground.spacing, mpm.solver.flipBlend, mpm.solver.name))
    sample = 0.1  # [s] between map samples
    t0 = time.time()
    series = []
    steps = 0
    while O.time < a.duration - 1e-9:
        target = min(O.time + sample, a.duration)
        if coupled:
            while O.time < target - 1e-9:  # dtAuto sets each step
                mpmsdem.run(5, coupled, endTime=a.duration)
                steps += 5
        else:
            O.dt = 0.5 * mpm.stableTimeStep()  # the bound falls as the flow speeds up
            n = max(1, int(round((target - O.time) / O.dt)))
            mpmsdem.run(n, mpm, endTime=a.duration)
            steps += n
        p = mpm.particles()
        maps.sample(p, O.time)
        speed = (p["v"] ** 2).sum(axis=1) ** 0.5
        series.append((O.time, float(p["x"][:, 0].max()), mpm.kineticEnergy(), float(speed.max())))
        if len(series) % 20 == 0 or O.time >= a.duration - 1e-9:
            wall = time.time() - t0
            touched = int((~np.isnan(tracker.firstContact)).sum()) if tracker else 0
            print("  t %5.1f s: front x %.1f m, kinetic energy %.3g J, largest speed %.1f m/s%s; %.0f s so far, about "
                  "%.0f s left" % (O.time, series[-1][1], series[-1][2], series[-1][3],
                                   ", %d blocks reached" % touched if tracker else "", wall,
                                   wall * max(0.0, a.duration - O.time) / O.time))
    (coupled or mpm).finish(True)
    wall = time.time() - t0
    p = mpm.particles()
    blocks = tracker.report(p) if tracker else []
    written = maps.write(os.path.join(out, "maps"), blocks=[(b["x"], b["y"]) for b in blocks],
                         title="Debris in the valley after %g s, dx %g m" % (O.time, a.dx))
    offset = mapOffset(ground)
    rescue = field.rescueList(blocks, a.rescue_distance)
    if blocks:
        written += list(field.writeReport(out, blocks, series=tracker.series(), attrs={
            "map_offset": offset, "crs": (ground.georeference or {}).get("crs")}))
        written.append(field.writeRescue(os.path.join(out, "rescue.csv"), rescue))
    deposited = maps.deposit_thickness > 0.05
    wallPoints, wallMass = field.pointsAtGridWalls(p, json.loads(mpm.solver.sceneJson)["grid"])
    summary = {"dx": a.dx, "duration": O.time, "steps": steps, "points": int(len(p["mass"])),
               "mass": float(p["mass"].sum()), "mass_seeded": mass0, "flip_blend": mpm.solver.flipBlend,
               "flip_damping_rate": mpm.solver.flipDampingRate(O.dt), "basal_friction": BASAL_FRICTION,
               "front_x": float(p["x"][:, 0].max()), "kinetic_energy": mpm.kineticEnergy(),
               "below_ground": int((p["x"][:, 2] < ground.height(p["x"][:, 0], p["x"][:, 1]) - 1e-9).sum()),
               "deposit_area": float(deposited.sum() * ground.spacing ** 2),
               "max_deposit_thickness": float(maps.deposit_thickness.max()),
               "max_speed": float(maps.max_speed.max()), "max_momentum_flux": float(maps.max_momentum_flux.max()),
               "max_dynamic_pressure": float(np.nanmax(maps.max_dynamic_pressure, initial=0.0)),
               "map_min_thickness": maps.minThickness,
               "reached_area": float(np.isfinite(maps.arrival_time).sum() * ground.spacing ** 2),
               "last_arrival": float(np.nanmax(maps.arrival_time, initial=0.0)),
               "map_offset": list(offset), "unmapped_points": maps.outside,
               "blocks": len(blocks), "blocks_reached": sum(1 for b in blocks if b["first_contact"] == b["first_contact"]),
               "blocks_buried": sum(1 for b in blocks if b["buried"]),
               "blocks_partly_buried": sum(1 for b in blocks if b["partly_buried"]),
               "blocks_to_find": len(rescue), "rescue_distance": a.rescue_distance,
               "blocks_below_ground": sum(1 for b in blocks if b["z"] < float(ground.height(b["x"], b["y"]))),
               "blocks_outside_grid": sum(1 for b in blocks if b["outside_grid"]),
               "points_at_grid_walls": wallPoints, "mass_at_grid_walls": wallMass,
               "largest_block_travel": max((b["travel"] for b in blocks), default=0.0),
               "largest_block_force": max((b["peak_force"] for b in blocks), default=0.0),
               "largest_block_force_10ms": max((b["peak_force_mean"] for b in blocks), default=0.0),
               "wall_seconds": wall, "maps": written}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    if not a.no_plots:
        plotSeries(series, os.path.join(out, "field_valley.png"), a.dx)
    print("after %.1f s: front at x %.1f m, kinetic energy %.3g J (at rest below ~1e3 J); deposit over %.0f m² (>5 cm), "
          "%.2f m thick at most; fastest depth-averaged flow %.1f m/s; largest momentum flux %.3g N/m, dynamic "
          "pressure %.3g Pa (where >= %g m thick); mass %s; %d points below the ground; "
          "wall time %.0f s; outputs in %s" % (O.time, summary["front_x"], summary["kinetic_energy"],
                                               summary["deposit_area"], summary["max_deposit_thickness"],
                                               summary["max_speed"], summary["max_momentum_flux"],
                                               summary["max_dynamic_pressure"], maps.minThickness,
                                               "conserved" if summary["mass"] == mass0 else "CHANGED",
                                               summary["below_ground"], wall, out))
    if wallPoints:
        print("WARNING: %d material points (%.3g t) reached the grid's side walls or top and are held there: the domain "
              "is too small for this flow, which would have gone on (a larger terrain or grid)"
              % (wallPoints, wallMass / 1000.0))
    if blocks:
        print("blocks: %d reached by the flow, %d buried, %d partly buried, %d below the ground, %d outside the grid; "
              "the most displaced (blocks.csv):" % (summary["blocks_reached"], summary["blocks_buried"],
                                                    summary["blocks_partly_buried"], summary["blocks_below_ground"],
                                                    summary["blocks_outside_grid"]))
        for b in sorted(blocks, key=lambda b: -b["travel"])[:5]:
            print("  block %3d: from (%.1f, %.1f) to (%.1f, %.1f) m, %.1f m, turned %.0f deg, peak force %.3g N (10 ms "
                  "mean) at %.2f s, debris %.2f m deep over it" % (b["id"], b["x0"], b["y0"], b["x"], b["y"],
                                                                  b["travel"], b["rotation_deg"], b["peak_force_mean"],
                                                                  b["peak_force_mean_time"], b["cover_depth"]))
        printRescue(rescue, a.rescue_distance)
    return summary


def printRescue(rescue, distance, shown=20):
    """The search's table (rescue.csv): the blocks buried, partly buried or moved more than
    ``distance`` [m], deepest first, the first ``shown`` of them."""
    print("search and rescue (rescue.csv): %d blocks buried, partly buried or moved more than %g m, deepest first; "
          "positions in the map's coordinates" % (len(rescue), distance))
    if not rescue:
        return
    print("  %5s  %-13s  %14s  %14s  %9s  %9s  %8s  %8s" % ("id", "status", "x_map [m]", "y_map [m]", "z_map [m]",
                                                            "depth [m]", "covered", "moved [m]"))
    for r in rescue[:shown]:
        print("  %5d  %-13s  %14.2f  %14.2f  %9.2f  %9.2f  %7.0f%%  %8.2f" % (
            r["id"], r["status"], r["x_map"], r["y_map"], r["z_map"], r["cover_depth"], 100 * r["cover_fraction"],
            r["travel"]))
    if len(rescue) > shown:
        print("  ... %d more in rescue.csv" % (len(rescue) - shown))


def plotSeries(series, path, dx):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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
