#!/usr/bin/env python3
"""Paper §3.1 as a parametric study with yade-batch: a 0.1 m sphero-cube (R 5 mm, rho 3000,
k_c 1e4) sliding down a fixed bed inclined by theta, basal friction mu.

One case (defaults theta = 30, mu = 0.1, 2 s):
    yade -n -x examples/sliding_block.py
The paper's 8 cases, one YADE process each, 2 at a time:
    yade-batch -j 2 examples/sliding_block.table examples/sliding_block.py
Each job writes results/sliding_theta=<theta>_mu=<mu>.json (travel distance at the end vs
Eq 19, and the time series) and, with output=1 in the table, sdem.h5 / bodies.pvd in a
folder of the same name. Summarise with: python3 examples/sliding_block_summary.py
"""
import json
import math
import os

import mpmsdem  # first: it finds YADE's Python folder when run by a plain python3
from mpmsdem import analysis
from yade import O, utils
from yade.minieigenHP import Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator

utils.readParamsFromTable(theta=30.0, mu=0.1, duration=2.0, dt=5e-5, output=0, noTableOk=True)
from yade.params import table  # noqa: E402

H, R, RHO, KC = 0.1, 0.005, 3000.0, 1e4
name = "sliding_theta=%g_mu=%g" % (table.theta, table.mu)
os.makedirs("results", exist_ok=True)

sdem = mpmsdem.SdemEngine(dtCheck="raise", output=os.path.join("results", name) if table.output else None,
                          outputEvery=0.01 if table.output else None)
mat = mpmsdem.material(density=RHO, friction=table.mu, barrierStiffness=KC)
sdem.box((12.0, 0.5, 0.05), R, mat, pos=(10.0, 0, -0.05), fixed=True)  # 24 m bed, top face z = 0
mass = RHO * mpmsdem.SpheroPolyhedron.box((H / 2,) * 3, R).volume
load = mass * 9.81 * math.cos(math.radians(table.theta))
z0 = H / 2 - analysis.equilibriumOverlap(load, 2 * R, KC, contacts=4)  # resting on its 4 corners
cube = sdem.box((H / 2,) * 3, R, mat, pos=(0, 0, z0))
th = math.radians(table.theta)
O.engines = [ForceResetter(), sdem.runner,
             NewtonIntegrator(gravity=Vector3(9.81 * math.sin(th), 0, -9.81 * math.cos(th)), damping=0)]
O.dt = table.dt

trace = []
for _ in range(20):
    mpmsdem.run(round(table.duration / O.dt / 20), sdem)
    trace.append((O.time, O.bodies[cube].state.pos[0], analysis.slidingDistance(O.time, table.theta, table.mu)))
s, ref = trace[-1][1], trace[-1][2]
result = {"theta": table.theta, "mu": table.mu, "time": O.time, "distance": s, "eq19": ref,
          "relative_error": (s - ref) / ref if ref else None, "series": trace}
with open(os.path.join("results", name + ".json"), "w") as f:
    json.dump(result, f, indent=1)
print("%s: S = %.5f m after %.2f s, Eq 19 %.5f m (%+.2f %%)" % (name, s, O.time, ref, 100 * (s - ref) / ref))
