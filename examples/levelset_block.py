#!/usr/bin/env python3
"""A YADE LevelSet boulder in a granular flow (docs/coupling.md, "YADE LevelSet bodies in the
flow"), beside the same boulder as an SDEM block.

A 0.04 m cube of glass beads (512 material points, dx 0.01 m) slides at 1 m/s, without
gravity, into a free 0.04 m cube of density 2000 kg/m³, once as a YADE ``LevelSet`` box
(``levelSetBody("box", ...)``, grid spacing 2.5 mm, moved by YADE's NewtonIntegrator, its
contacts with other LevelSet bodies left to YADE's own functors) and once as an SDEM
sphero-cube of the same outer size (sweep radius 3 mm). Prints, for each, the peak force of
the flow on the body and how far the body has travelled after 0.03 s, and the momentum of flow
and body together before and after (conserved to round-off).

Run: ``yade -n -x examples/levelset_block.py`` or ``/usr/bin/python3 examples/levelset_block.py``
(about 20 s).
"""
import numpy as np

import mpmsdem
from yade import O
from yade.utils import levelSetBody
from yade.wrapper import (Bo1_LevelSet_Aabb, ForceResetter, FrictMat, Ig2_LevelSet_LevelSet_ScGeom,
                          InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                          Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
HALF, DENSITY, FRICTION, KC = 0.02, 2000.0, 0.3, 1e4
CENTRE = (0.125, 0.07, 0.07)
DT, STEPS = 1e-5, 3000


def flow():
    return mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                             particles=[{"lo": [0.04, 0.05, 0.05], "hi": [0.08, 0.09, 0.09], "ppc": 8,
                                         "velocity": [1, 0, 0]}], gravity=(0, 0, 0), verbose=False)


def momentum(mpm, body):
    p = mpm.particles()
    s = O.bodies[body].state
    return (p["mass"][:, None] * p["v"]).sum(axis=0) + s.mass * np.array(s.vel)


def run(kind):
    O.reset()
    mpm = flow()
    sdem = mpmsdem.SdemEngine(verbose=False)
    if kind == "levelset":
        rock = FrictMat(density=DENSITY, frictionAngle=np.arctan(FRICTION))
        body = O.bodies.append(levelSetBody("box", center=CENTRE, extents=(HALF,) * 3, spacing=0.0025,
                                            material=O.materials.append(rock)))
        coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={}, levelSets={body: {"friction": FRICTION,
                                                                               "barrierStiffness": KC}},
                                        verbose=False)
        yadeContacts = [InsertionSortCollider([Bo1_LevelSet_Aabb()], verletDist=0.001),
                        InteractionLoop([Ig2_LevelSet_LevelSet_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                        [Law2_ScGeom_FrictPhys_CundallStrack()])]
    else:
        mat = mpmsdem.material(density=DENSITY, friction=FRICTION, barrierStiffness=KC)
        body = sdem.box((HALF,) * 3, 0.003, mat, pos=CENTRE)
        coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: FRICTION}, verbose=False)
        yadeContacts = []
    O.engines = [ForceResetter()] + yadeContacts + [coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = DT
    p0 = momentum(mpm, body)
    fx = []
    for _ in range(STEPS):
        mpmsdem.run(1, coupled)
        fx.append(coupled.force(body)[0])
    s = O.bodies[body].state
    # the force's peak over 0.5 ms windows: a single step's peak follows which points touch then
    peak = max(np.convolve(fx, np.ones(50) / 50, mode="valid"))
    drift = np.linalg.norm(momentum(mpm, body) - p0) / np.linalg.norm(p0)
    return {"peak": peak, "travel": s.pos[0] - CENTRE[0], "impulse": s.mass * s.vel[0], "mass": s.mass,
            "drift": drift}


if __name__ == "__main__":
    rows = {kind: run(kind) for kind in ("levelset", "sdem")}
    for kind, r in rows.items():
        print("%-8s body %.4f kg: peak flow force (0.5 ms mean) %.2f N, after %.2f s travel %.3f mm and momentum "
              "%.5f N s; momentum of flow and body conserved to %.1e" % (kind, r["mass"], r["peak"], STEPS * DT,
                                                                         1e3 * r["travel"], r["impulse"], r["drift"]))
