#!/usr/bin/env python3
"""Validation probe (opt-in, minutes on one thread): where the bed acts on the flow. The §3.2
material (the glass beads of Table 1 with the joint set's μ₂ 0.7221: the set of
examples/flume_block.py --full and of the convergence study) on a flat bed at each grid spacing,
with the bed given four ways:

- ``wall``: the grid's −z box wall, whose node layer is the geometric bed (z = 0);
- ``terrain``: a flat terrain (the field scenes' boundary) at z = 0, on that node layer;
- ``terrain-half``: the same terrain half a cell higher, at z = Δx/2, between node layers;
- ``sdem``: the flume's own bed, a fixed SDEM slab whose outer surface is z = 0, holding the
  material points through the coupling contacts (points seeded R_p0 above it, as the flume does).

1. A layer at rest: a --layer thick layer on a square footprint --side-cells wide between
   frictionless side walls, settled under gravity with pure PIC transfer (α 0 each step: the
   strongest damping the blend has) until no point moves faster than --still at three readings
   5 ms apart. Read off: the top surface (the mean height of the top point layer plus half the
   spacing of the two top point layers), the thickness the mass implies (M / (ρ A) with the settled density ρ = M / V, i.e. the settled
   volume over the footprint), and so the effective bed, top − thickness; the lithostatic line,
   −σ_zz = a + b z fitted to the points more than three cells above the lowest and a cell below
   the top (its slope against ρ g), the height where it reaches the full column weight M g / A,
   and how far up the point layers' mean stress stays more than 5 % off it; and the bed that the
   whole stress field implies, z̄ + Σ σ_zz V / (M g) (for a column at rest,
   ∫ σ_zz dV = −g ∫ ρ (z − z_bed) dV exactly: where the bed's reaction enters; tension > 0).
2. A steady flow down a --incline slope (grid along it, gravity rotated as in the flume), a
   --depth thick layer, --length long, on a no-slip bed (at 25°, tan θ 0.47, a Coulomb bed of
   0.21, Table 1's, or 0.28, the joint set's, cannot hold a layer: it accelerates for ever as a
   plug, with no basal boundary layer to measure), the PIC viscosity of the joint set held
   (0.0360 m²/s, as the convergence study holds it). Read every --every s over the points within
   --window of the layer's median x (its uniform middle, which the disturbances from the two free
   ends reach last); steady when the mean speed there changes by less than --steady of itself
   over each of the last two intervals. Then: u(z) in the point layers (Δx/2 thick); the speed of
   the lowest point layer (the slip the points see; the bed nodes themselves hold u = 0); the
   basal boundary layer's thickness, the height above the geometric bed where u reaches the
   lowest layer's speed + 90 % of the rise to the surface layer's; the effective bed where the
   parabola through the layers above the lowest cell reaches u = 0; the mass and stress-field
   beds of part 1 (bed-normal gravity g cos θ); and beside them the steady film of the continuum
   model (μ(I) plus the PIC viscosity as a Newtonian one, no slip on the geometric bed, the
   measured depth): its surface speed and boundary layer.

    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/bed_height.py --out DIR
        [--dx 0.02,0.01,0.005] [--beds wall,terrain,terrain-half,sdem] [--flow-beds wall,terrain-half]
    OMP_NUM_THREADS=1 /usr/bin/python3 scripts/validation/bed_height.py --out DIR --dx 0.0025 \
        --beds wall,terrain-half,sdem --no-flow --max-time 5

The second adds Δx 0.0025 m at rest (pure PIC damps less as Δx shrinks: the layer takes 3 s to
come to rest there). The flow is not run at 0.0025 m: about 16 times the 95 s of one at 0.005 m.

Each case's numbers go to OUT/<part>_<bed>_<dx>.json when it ends and a finished case is not
run again; the Markdown tables of all cases in OUT are printed and written to OUT/bed_height.md.
Heights are in mm above the geometric bed (the box wall's node layer, the terrain's plane, the
slab's surface), offsets also in units of Δx.
"""
import argparse
import glob
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flume_convergence import commit, fmt  # noqa: E402

BEDS = ("wall", "terrain", "terrain-half", "sdem")
FLOW_BEDS = ("wall", "terrain", "terrain-half")
G = 9.81
STRESS_BAND = 0.05  # a point layer's mean -σ_zz off the lithostatic line by more than this is disturbed
HEIGHTS = ("top", "mass_bed", "line_surface", "line_bed", "virial_bed", "lowest_point", "stress_disturbed")
ROOM_SPEED = 0.5  # [m/s]: the flow's grid reaches this far ahead of the layer per second of --max-time
BED_FRICTION = 0.21  # the slab's coupling pair (Table 1's basal friction): at rest it carries no shear


def material():
    from mpmsdem.flume import FLUME_SETTINGS, GLASS_BEADS
    return dict(GLASS_BEADS, mu_2=FLUME_SETTINGS["joint"]["mu_2"])


def listArg(text, kind, allowed=None):
    items = [s.strip() for s in text.split(",") if s.strip()]
    out = []
    for s in items:
        try:
            v = kind(s)
        except ValueError:
            raise argparse.ArgumentTypeError("%r: not a %s" % (s, kind.__name__)) from None
        if allowed is not None and v not in allowed:
            raise argparse.ArgumentTypeError("%r: must be among %s" % (s, ", ".join(allowed)))
        out.append(v)
    if not out:
        raise argparse.ArgumentTypeError("%r: an empty list" % text)
    return out


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="folder for the per-case JSON files and bed_height.md")
    ap.add_argument("--dx", type=lambda s: listArg(s, float), default=[0.02, 0.01, 0.005],
                    help="grid spacings [m], each dividing --layer (and --depth for the flow) (0.02,0.01,0.005)")
    ap.add_argument("--flow-dx", type=lambda s: listArg(s, float), default=None,
                    help="grid spacings of the steady flow [m] (those of --dx)")
    ap.add_argument("--beds", type=lambda s: listArg(s, str, BEDS), default=list(BEDS),
                    help="beds of the layer at rest, among %s (all)" % ", ".join(BEDS))
    ap.add_argument("--flow-beds", type=lambda s: listArg(s, str, FLOW_BEDS), default=["wall", "terrain-half"],
                    help="beds of the steady flow, among %s (wall,terrain-half); 'none' via --no-flow"
                    % ", ".join(FLOW_BEDS))
    ap.add_argument("--no-flow", action="store_true", help="the layer at rest only")
    ap.add_argument("--layer", type=float, default=0.16,
                    help="thickness of the layer at rest as seeded [m] (0.16: the line is fitted above 3 cells)")
    ap.add_argument("--side-cells", type=int, default=2,
                    help="side of its square footprint [cells] (2: the layer is uniform across, between frictionless "
                    "walls)")
    ap.add_argument("--still", type=float, default=1e-6, help="at rest: every point slower than this [m/s] (1e-6)")
    ap.add_argument("--incline", type=float, default=25.0, help="slope of the flow [deg] (25)")
    ap.add_argument("--depth", type=float, default=0.06, help="thickness of the flowing layer as seeded [m] (0.06)")
    ap.add_argument("--length", type=float, default=0.8, help="length of the flowing layer [m] (0.8)")
    ap.add_argument("--viscosity", type=float, default=None,
                    help="PIC viscosity of the flow [m²/s] (the joint set's, 0.0360, as the convergence study holds)")
    ap.add_argument("--window", type=float, default=0.1,
                    help="the flow is read over the points within this of its median x [m] (0.1)")
    ap.add_argument("--every", type=float, default=0.05, help="interval of the flow's readings [s] (0.05)")
    ap.add_argument("--steady", type=float, default=0.01,
                    help="steady: the mean speed changes by less than this fraction over --every (0.01)")
    ap.add_argument("--max-time", type=float, default=2.0, help="give up on rest or steadiness after this [s] (2)")
    a = ap.parse_args(argv)
    a.flow_dx = a.dx if a.flow_dx is None else a.flow_dx
    for dx, name, v in [(d, "--layer", a.layer) for d in a.dx] + [(d, "--depth", a.depth) for d in a.flow_dx]:
        if not (dx > 0 and abs(v / dx - round(v / dx)) < 1e-6 and round(v / dx) >= 2):
            ap.error("--dx %g m: must divide %s %g m into at least two whole cells" % (dx, name, v))
    if a.side_cells < 1:
        ap.error("--side-cells %d: must be >= 1" % a.side_cells)
    if not 0 < a.incline < 45:
        ap.error("--incline %g deg: must be in (0, 45)" % a.incline)
    if not 0 < 2 * a.window < a.length:
        ap.error("--window %g m: must be > 0 and under half of --length %g m" % (a.window, a.length))
    for name in ("still", "every", "steady", "max_time", "viscosity"):
        if getattr(a, name) is not None and not getattr(a, name) > 0:
            ap.error("--%s %g: must be > 0" % (name.replace("_", "-"), getattr(a, name)))
    return a


# ----------------------------------------------------------------------------------- analysis
def pointLayers(z0, dx):
    """Index of each point's seeded layer (2 per cell: z0 = (k + 1/2) dx/2 above the lowest)."""
    return np.round((z0 - z0.min()) / (0.5 * dx)).astype(int)


def columnBeds(z, layer, szz, mass, volume, area, gn, dx):
    """The bed heights a column of points implies [m]: top surface, mass-implied thickness and
    the bed below it, the lithostatic line's fit and where it reaches the column weight, and the
    stress field's own bed; z, szz (tension > 0), mass, volume: the column's points, area its
    footprint [m²], gn the bed-normal gravity [m/s²]."""
    top_k = layer.max()
    zt, zn = z[layer == top_k].mean(), z[layer == top_k - 1].mean()
    top = zt + 0.5 * (zt - zn)
    M, V = mass.sum(), volume.sum()
    rho = M / V
    thickness = V / area
    # the stress of the lowest three cells and of the top cell departs from the line (their
    # points carry the boundaries' load unevenly: the disturbance tabled as "stress disturbed")
    inner = (z > z.min() + 3 * dx) & (z < zt - dx)
    ks = np.unique(layer)
    zl = np.array([z[layer == k].mean() for k in ks])
    sl = np.array([-szz[layer == k].mean() for k in ks])
    out = {"top": top, "thickness": thickness, "rho": rho, "mass_bed": top - thickness, "slope_ratio": None,
           "line_surface": None, "line_bed": None, "stress_disturbed": None, "lowest_stress_ratio": None,
           "stress_layers": [[float(u), float(v)] for u, v in zip(zl, sl)]}
    if len(np.unique(layer[inner])) >= 3:  # a line through fewer point layers says nothing
        b, a = np.polyfit(z[inner], -szz[inner], 1)  # -σ_zz = a + b z, b < 0
        line = a + b * zl
        off = (np.abs(sl - line) > STRESS_BAND * line) & (zl < zt - dx)
        out.update(slope_ratio=-b / (rho * gn), line_surface=-a / b, line_bed=(M * gn / area - a) / b,
                   stress_disturbed=float(zl[off].max()) if off.any() else float(zl.min()),
                   lowest_stress_ratio=float(sl[0] / line[0]),
                   stress_layers=[[float(u), float(v), float(w)] for u, v, w in zip(zl, sl, line)])
    out.update({
            "virial_bed": float((mass * z).sum() / M + (szz * volume).sum() / (M * gn)),
            "lowest_point": float(z.min()), "points": int(len(z))})
    return out


def filmProfile(depth, incline, viscosity, n=400):
    """The steady film the continuum model gives: μ(I) plus the PIC viscosity as a Newtonian one,
    no slip at z = 0, a free surface at `depth` [m]. At height z the shear stress
    ρ g sinθ (h − z) = μ(I) p + ρ ν γ̇ with p = ρ g cosθ (h − z) and I = γ̇ d / sqrt(p / ρ_s) (the
    μ(I) stress has no normal deviator in simple shear, so p is the overburden); γ̇ found by
    bisection (the right side grows with γ̇), u = ∫ γ̇ dz. Returns heights and speeds [m, m/s]."""
    m = material()
    th = math.radians(incline)
    z = np.linspace(0.0, depth, n + 1)

    def rate(zz):
        load = G * (depth - zz)  # per unit bulk density
        if load <= 0:
            return 0.0
        p = m["density"] * G * math.cos(th) * (depth - zz)
        lo, hi = 0.0, load * math.sin(th) / viscosity
        for _ in range(100):
            gd = 0.5 * (lo + hi)
            i = gd * m["grain_diameter"] / math.sqrt(p / m["solid_density"])
            mu = m["mu_s"] + (m["mu_2"] - m["mu_s"]) * i / (m["I0"] + i)
            if mu * G * math.cos(th) * (depth - zz) + viscosity * gd > load * math.sin(th):
                hi = gd
            else:
                lo = gd
        return 0.5 * (lo + hi)
    gd = np.array([rate(zz) for zz in z])
    return z, np.concatenate(([0.0], np.cumsum(0.5 * (gd[1:] + gd[:-1]) * np.diff(z))))


def riseHeight(z, u):
    """Height where u first reaches its lowest value + 90 % of the rise to its top value
    (linear between the samples)."""
    rise = u[0] + 0.9 * (u[-1] - u[0])
    j = int(np.argmax(u >= rise))
    return float(z[j - 1] + (rise - u[j - 1]) * (z[j] - z[j - 1]) / (u[j] - u[j - 1]))


def isSteady(history, steady):
    """The mean speed (history: (t, u) readings) changed by less than `steady` of itself over each
    of the last two intervals."""
    u = [v for _, v in history[-3:]]
    return len(u) == 3 and all(abs(b - a) < steady * abs(u[-1]) for a, b in zip(u, u[1:]))


def profileBed(zl, ul, dx):
    """Where the flow's interior puts its bed: the root nearest the lowest point layer of the
    parabola fitted to the point layers' speeds above the lowest cell (the layers the bed nodes
    reach directly are left out; a viscous film's profile is exactly such a parabola); None
    with fewer than three layers there or no root."""
    up = zl > zl[0] + dx
    if up.sum() < 3:
        return None
    roots = np.roots(np.polyfit(zl[up], ul[up], 2))
    roots = roots[np.isreal(roots)].real
    return float(roots[np.argmin(np.abs(roots - zl[0]))]) if len(roots) else None


# ----------------------------------------------------------------------------------- scenes
def grid(dx, side_cells, height, below):
    """Grid of a slice: side_cells cells across each horizontal extent (inside the 2-cell wall
    layers), the bed plane z = 0 at `below` cells above the grid's origin, room above."""
    nz = below + int(math.ceil(height / dx)) + 4
    return {"dx": dx, "cells": [side_cells[0] + 4, side_cells[1] + 4, nz], "origin": [-2 * dx, -2 * dx, -below * dx]}


def terrainAt(g, z0, friction):
    from mpmsdem.terrain import Terrain
    span = max(g["cells"][:2]) * g["dx"]
    return Terrain(np.full((2, 2), z0), span, g["origin"][0], g["origin"][1], friction=friction)


def bedSetup(bed, dx, friction):
    """Grid cells below z = 0, the -z wall, the terrain height (None: no terrain) and the
    geometric bed height of a bed kind."""
    if bed == "wall":
        return 2, friction, None, 0.0
    if bed == "terrain":
        return 4, "free", 0.0, 0.0
    if bed == "terrain-half":
        return 4, "free", 0.5 * dx, 0.5 * dx
    raise ValueError("bed %r: must be one of %s" % (bed, ", ".join(FLOW_BEDS)))


def mpmOnly(bed, dx, cells, height, particles, gravity, friction, ends, **blend):
    from mpmsdem.mpm import MpmEngine
    below, zwall, zterrain, zbed = bedSetup(bed, dx, friction)
    g = grid(dx, cells, height, below)
    mpm = MpmEngine(grid=g, material=material(), particles=particles, gravity=gravity,
                    walls={"-x": ends, "+x": ends, "-y": 0.0, "+y": 0.0, "-z": zwall, "+z": "free"},
                    terrain=None if zterrain is None else terrainAt(g, zterrain, friction), verbose=False, **blend)
    return mpm, zbed


def restLayer(dx, bed, layer=0.16, sideCells=2, still=1e-6, maxTime=2.0):
    """Settle the layer at rest on a bed and measure it; a dict of the numbers (heights [m])."""
    from mpmsdem import analysis
    n = sideCells
    side = n * dx
    rp = analysis.pointRadius(dx, 8)
    pure = {"flipAlpha": 0.0, "flipReferenceDt": "step"}
    started = time.time()
    if bed == "sdem":
        mpmsdem, O, mpm, step = sdemSlab(dx, n, layer, rp, pure)
        zbed = 0.0
    else:
        mpm, zbed = mpmOnly(bed, dx, (n, n), layer, [{"lo": [0, 0, 0], "hi": [side, side, layer], "ppc": 8}],
                            (0, 0, -G), 0.0, 0.0, **pure)
        dt = 0.9 * mpm.stableTimeStep()

        def step(duration):
            mpm.solver.run(max(1, int(round(duration / dt))), dt)
    z0 = mpm.particles()["x"][:, 2].copy()
    # at rest after three readings in a row below `still`: a standing wave is still everywhere at
    # once twice a period (its stress at an extreme), and 5 ms apart no three readings catch that
    chunk = 0.005
    speeds = []
    while mpm.time < maxTime:
        step(chunk)
        speeds.append(float(np.abs(mpm.particles()["v"]).max()))
        if mpm.time > 0.05 and max(speeds[-3:]) < still and len(speeds) >= 3:
            break
    speed = max(speeds[-3:])
    p = mpm.particles()
    res = columnBeds(p["x"][:, 2], pointLayers(z0, dx), p["stress"][:, 2], p["mass"], p["volume0"] * p["J"],
                     side * side, G, dx)
    res = {k: v - zbed if k in HEIGHTS and v is not None else v for k, v in res.items()}
    res["stress_layers"] = [[u[0] - zbed] + u[1:] for u in res["stress_layers"]]
    res.update(part="rest", bed=bed, dx=dx, layer=layer, side=side, time=mpm.time, max_speed=speed,
               settled=speed < still, still=still, rp=rp, seeded_mass=float(p["mass"].sum()),
               wall=time.time() - started, commit=commit())
    return res


def sdemSlab(dx, n, layer, rp, blend):
    """The layer on the flume's bed: a fixed SDEM slab (outer surface z = 0, sweep 5 mm, the
    flume's barrier stiffness) under grid walls that are free below; points seeded from R_p0 − Δx/4
    so that the lowest ones rest on it, as in mpmsdem.flume."""
    import mpmsdem
    from mpmsdem.coupling import CoupledEngine
    from mpmsdem.mpm import MpmEngine
    from mpmsdem.sdem import SdemEngine
    from yade import O
    from yade.minieigenHP import Vector3
    from yade.wrapper import ForceResetter, NewtonIntegrator
    O.reset()
    side = n * dx
    zLow = rp - dx / 4
    sdem = SdemEngine(verbose=False)
    bedMat = mpmsdem.material(density=2500, friction=1.0, barrierStiffness=1e4)
    sdem.box((side / 2 + 2 * dx, side / 2 + 2 * dx, 0.02), 0.005, bedMat, pos=(side / 2, side / 2, -0.02), fixed=True)
    g = grid(dx, (n, n), layer + zLow, 4)
    g["origin"][2] = zLow - 4 * dx
    mpm = MpmEngine(grid=g, material=material(), particles=[{"lo": [0, 0, zLow], "hi": [side, side, zLow + layer],
                                                             "ppc": 8}],
                    gravity=(0, 0, -G), walls={"-x": 0.0, "+x": 0.0, "-y": 0.0, "+y": 0.0, "-z": "free", "+z": "free"},
                    verbose=False, **blend)
    coupled = CoupledEngine(sdem, mpm, pairs={bedMat: {"friction": BED_FRICTION}}, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=Vector3(0, 0, -G), damping=0)]
    O.dt = 0.5 * mpm.stableTimeStep()

    def step(duration):
        mpmsdem.run(max(1, int(round(duration / O.dt))), coupled)
    return mpmsdem, O, mpm, step


def flowLayer(dx, bed, incline=25.0, depth=0.06, length=0.8, window=0.1, every=0.05, steady=0.01, maxTime=2.0,
              viscosity=None):
    """A layer flowing down a slope on a no-slip bed until its middle is steady; a dict."""
    from mpmsdem.flume import FLUME_SETTINGS
    viscosity = FLUME_SETTINGS["joint"]["flip_viscosity"] if viscosity is None else viscosity
    th = math.radians(incline)
    gn = G * math.cos(th)
    # room ahead for the layer's front at up to ROOM_SPEED over maxTime (checked as it runs)
    cells = (int(math.ceil((length + ROOM_SPEED * maxTime) / dx)), 2)
    started = time.time()
    mpm, zbed = mpmOnly(bed, dx, cells, depth, [{"lo": [0, 0, 0], "hi": [length, 2 * dx, depth], "ppc": 8}],
                        {"g": G, "incline_deg": incline}, "noslip", "free",
                        flipViscosity=viscosity)
    dt = 0.9 * mpm.stableTimeStep()
    x0 = mpm.particles()["x"]
    layer = pointLayers(x0[:, 2], dx)
    history = []
    while mpm.time < maxTime:
        mpm.solver.run(max(1, int(round(every / dt))), dt)
        p = mpm.particles()
        if p["x"][:, 0].max() > cells[0] * dx - dx:
            raise RuntimeError("flow, %s bed, dx %g m: the front reached the grid's end at %.3f s (faster than %g m/s "
                               "on average): not a slow steady film" % (bed, dx, mpm.time, ROOM_SPEED))
        at = np.abs(p["x"][:, 0] - np.median(p["x"][:, 0])) < window
        history.append((mpm.time, float(p["v"][at, 0].mean())))
        if isSteady(history, steady):
            break
    z, u = p["x"][at, 2] - zbed, p["v"][at, 0]
    ks = np.unique(layer[at])
    zl = np.array([z[layer[at] == k].mean() for k in ks])
    ul = np.array([u[layer[at] == k].mean() for k in ks])
    res = columnBeds(z, layer[at], p["stress"][at, 2], p["mass"][at], (p["volume0"] * p["J"])[at],
                     2 * window * 2 * dx, gn, dx)
    fz, fu = filmProfile(res["top"], incline, viscosity)
    res.update(part="flow", bed=bed, dx=dx, incline=incline, depth=depth, length=length, time=mpm.time,
               steady=isSteady(history, steady),
               history=history, layers_z=zl.tolist(), layers_u=ul.tolist(), slip=float(ul[0]), surface=float(ul[-1]),
               boundary_layer=riseHeight(zl, ul), film_surface=float(fu[-1]), film_boundary_layer=riseHeight(fz, fu),
               profile_bed=profileBed(zl, ul, dx), dt=dt,
               viscosity=viscosity, wall=time.time() - started, commit=commit())
    return res


# ----------------------------------------------------------------------------------- report
def mm(v):
    return "%.2f" % (1000 * v)


def offset(v, dx):
    return "–" if v is None else "%.2f (%+.3f Δx)" % (1000 * v, v / dx)


def restTable(runs):
    cols = ("bed", "Δx [m]", "points", "settled at [s] (max speed [m/s])", "top [mm]", "thickness M/(ρA) [mm]",
            "ρ settled [kg/m³]", "bed from the mass [mm] (Δx)", "lithostatic slope / ρg",
            "bed from the lithostatic line [mm] (Δx)", "bed from the stress field [mm] (Δx)", "lowest point [mm]",
            "lowest layer's −σ_zz / line", "stress disturbed up to [mm] (Δx)", "wall [s]")
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in runs:
        lines.append("| " + " | ".join((
            r["bed"], "%g" % r["dx"], "%d" % r["points"], "%.3f (%.1e)%s" % (r["time"], r["max_speed"],
                                                                              "" if r["settled"] else " NOT AT REST"),
            mm(r["top"]), mm(r["thickness"]), "%.2f" % r["rho"], offset(r["mass_bed"], r["dx"]),
            fmt(r["slope_ratio"], "%.4f"), offset(r["line_bed"], r["dx"]), offset(r["virial_bed"], r["dx"]),
            mm(r["lowest_point"]), fmt(r["lowest_stress_ratio"], "%.2f"), offset(r["stress_disturbed"], r["dx"]),
            "%.0f" % r["wall"])) + " |")
    return "\n".join(lines)


def effectiveFilm(r):
    """(x = 4νΔt/Δx², ν_eff/ν, the surface speed of the film of the blend's effective viscosity
    on the run's depth above its profile bed) of a flow run: what the flow should show when its
    only departures from the viscous film are the blend's share per step and where the no-slip
    acts (docs/coupled-results.md, "Why the held viscosity does not hold")."""
    from mpmsdem import analysis
    nu = analysis.effectivePicViscosity(r["viscosity"], r["dt"], r["dx"])
    bed = r["profile_bed"] if r["profile_bed"] is not None else 0.0
    _, u = filmProfile(r["top"] - bed, r["incline"], nu)
    return 4 * r["viscosity"] * r["dt"] / r["dx"] ** 2, nu / r["viscosity"], float(u[-1])


def flowTable(runs):
    cols = ("bed", "Δx [m]", "read at [s] (steady)", "surface u [m/s] (film)",
            "x = 4νΔt/Δx², ν_eff/ν, film of ν_eff on the profile bed [m/s] (surface / it)",
            "lowest layer u [m/s] (at [mm])",
            "boundary layer [mm] (/ depth) (film)", "bed from the profile, u = 0 [mm] (Δx)",
            "bed from the mass [mm] (Δx)", "bed from the stress field [mm] (Δx)", "lithostatic slope / ρg cosθ",
            "wall [s]")
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in runs:
        depth = r["top"] - r["mass_bed"]
        x, share, film = effectiveFilm(r)
        lines.append("| " + " | ".join((
            r["bed"], "%g" % r["dx"], "%.2f (%s)" % (r["time"], "yes" if r["steady"] else "NO"),
            "%.4f (%.4f)" % (r["surface"], r["film_surface"]),
            "%.3f, %.3f, %.4f (%.3f)" % (x, share, film, r["surface"] / film),
            "%.4f (%s)" % (r["slip"], mm(r["layers_z"][0])),
            "%s (%.2f) (%s)" % (mm(r["boundary_layer"]), (r["boundary_layer"] - r["mass_bed"]) / depth,
                                mm(r["film_boundary_layer"])),
            offset(r["profile_bed"], r["dx"]), offset(r["mass_bed"], r["dx"]), offset(r["virial_bed"], r["dx"]),
            fmt(r["slope_ratio"], "%.4f"), "%.0f" % r["wall"])) + " |")
    return "\n".join(lines)


def profiles(runs):
    return "\n".join("%s, Δx %g m, u [m/s] at height [mm]: %s" % (
        r["bed"], r["dx"], " ".join("%.1f:%.4f" % (1000 * z, u) for z, u in zip(r["layers_z"], r["layers_u"])))
        for r in runs)


def main(argv):
    a = parse(argv)
    os.makedirs(a.out, exist_ok=True)
    cases = [("rest", b, dx) for dx in a.dx for b in a.beds]
    if not a.no_flow:
        cases += [("flow", b, dx) for dx in a.flow_dx for b in a.flow_beds]
    for part, bed, dx in cases:
        path = os.path.join(a.out, "%s_%s_%g.json" % (part, bed, dx))
        if os.path.exists(path):
            continue
        print("%s, %s bed, dx %g m ..." % (part, bed, dx), file=sys.stderr, flush=True)
        if part == "rest":
            r = restLayer(dx, bed, a.layer, a.side_cells, a.still, a.max_time)
        else:
            r = flowLayer(dx, bed, a.incline, a.depth, a.length, a.window, a.every, a.steady, a.max_time, a.viscosity)
        with open(path + ".tmp", "w") as f:
            json.dump(r, f, indent=1)
        os.replace(path + ".tmp", path)
    runs = []
    for path in sorted(glob.glob(os.path.join(a.out, "*.json"))):
        with open(path) as f:
            runs.append(json.load(f))
    order = {b: i for i, b in enumerate(BEDS)}
    runs.sort(key=lambda r: (order[r["bed"]], -r["dx"]))
    rest = [r for r in runs if r["part"] == "rest"]
    flow = [r for r in runs if r["part"] == "flow"]
    text = []
    if rest:
        r0 = rest[0]
        text += ["Layer at rest (%g m seeded on a square %d cells wide, pure PIC until every point is slower than "
                 "%g m/s; heights above the geometric bed; commit %s):" % (
                     r0["layer"], round(r0["side"] / r0["dx"]), r0["still"], r0["commit"]),
                 "", restTable(rest), ""]
    if flow:
        r0 = flow[0]
        text += ["Steady flow (%g° no-slip bed, %g m seeded, PIC viscosity %.4g m²/s; commit %s):" % (
            r0["incline"], r0["depth"], r0["viscosity"], r0["commit"]), "", flowTable(flow), "", profiles(flow), ""]
    text = "\n".join(text)
    print(text)
    with open(os.path.join(a.out, "bed_height.md"), "w") as f:
        f.write(text)
    bad = [r for r in runs if not r.get("settled", r.get("steady"))]
    for r in bad:
        print("%s, %s bed, dx %g m: not %s by %.2f s" % (r["part"], r["bed"], r["dx"],
                                                          "at rest" if r["part"] == "rest" else "steady", r["time"]),
              file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
