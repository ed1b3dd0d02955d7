"""Scene builders shared by the YADE-level tests and the checks in scripts/checks."""
import math
import os

import mpmsdem
from mpmsdem import analysis
from yade import O
from yade.minieigenHP import Quaternion, Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")

H = 0.1          # cube side [m] (paper §3.1)
R = 0.005        # sweep radius [m]
RHO = 3000.0     # block density [kg/m^3]
KC = 1e4         # barrier stiffness [N/m]


def forget(*engines):
    """What a killed process leaves: the engines gone, with their open output files closed. The
    registry of runner commands keeps a reference (see mpmsdem.engine._stepRunner): drop it too."""
    import gc
    from mpmsdem.engine import _REGISTRY
    for name in [n for n, f in _REGISTRY.items() if getattr(f, "__self__", None) in engines]:
        del _REGISTRY[name]
    O.reset()
    gc.collect()


def readVtp(path):
    """The arrays of a .vtp the writers of pkg/io wrote with appended raw data (header UInt64), by
    name (points: "Points"; cells: "connectivity", "offsets"), each shaped (values, components),
    and the piece's counts ("NumberOfPoints", "NumberOfPolys", ...) as ints."""
    import xml.etree.ElementTree as ET
    import numpy as np
    raw = open(path, "rb").read()
    start = raw.index(b"<AppendedData")
    data = raw.index(b"_", start) + 1
    header = ET.fromstring(raw[:start].decode() + "</VTKFile>")
    types = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}
    out = {k: int(v) for k, v in header.find("PolyData/Piece").attrib.items()}
    for a in header.iter("DataArray"):
        at = data + int(a.get("offset"))
        n = int(np.frombuffer(raw[at:at + 8], "<u8")[0])
        values = np.frombuffer(raw[at + 8:at + 8 + n], types[a.get("type")])
        out[a.get("Name")] = values.reshape(-1, int(a.get("NumberOfComponents")))
    return out


def run(engine, steps):
    """Run YADE for ``steps`` steps and re-raise an error that stopped the run."""
    mpmsdem.run(steps, engine)


def momentum(mpm, body):
    """The momentum of the flow's points and of YADE body ``body`` [kg m/s]."""
    import numpy as np
    p = mpm.particles()
    s = O.bodies[body].state
    return (p["mass"][:, None] * p["v"]).sum(axis=0) + s.mass * np.array(s.vel)


def pushFreeBody(coupled, mpm, body, chunks=30, steps=100):
    """Run ``coupled`` under YADE's NewtonIntegrator without gravity or damping at O.dt 1e-5 s, in
    ``chunks`` runs of ``steps`` steps: the flow's momentum and the body's before and after, and
    the most contacts the body had at the end of a chunk."""
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    p0 = momentum(mpm, body)
    hit = 0
    for _ in range(chunks):
        mpmsdem.run(steps, coupled)
        hit = max(hit, coupled.contactCount(body))
    return p0, momentum(mpm, body), hit


def gravity(thetaDeg, g=9.81):
    """Gravity of a flume inclined by theta about y, flowing toward +x (rotate gravity, not the bed)."""
    th = math.radians(thetaDeg)
    return Vector3(g * math.sin(th), 0, -g * math.cos(th))


def cubeOnSlab(thetaDeg=0.0, mu=0.0, yawDeg=0.0, normalDamping=0.0, gap=None, **engineKw):
    """The §3.1 scene: a 0.1 m cube (R 5 mm, rho 3000, k_c 1e4) on a fixed slab whose top face is
    z = 0, gravity inclined by theta. With gap=None the cube starts at the overlap at which its
    4 face contacts carry its weight component normal to the bed (no bouncing).
    Returns (engine, cube id, slab id, cube mass)."""
    eng = mpmsdem.SdemEngine(**engineKw)
    mat = mpmsdem.material(density=RHO, friction=mu, barrierStiffness=KC, normalDamping=normalDamping)
    slab = eng.box((12.0, 0.5, 0.05), R, mat, pos=(10.0, 0, -0.05), fixed=True)  # 24 m bed (paper: 20 m)
    mass = RHO * mpmsdem.SpheroPolyhedron.box((H / 2,) * 3, R).volume
    if gap is None:
        load = mass * 9.81 * math.cos(math.radians(thetaDeg))
        z = H / 2 - analysis.equilibriumOverlap(load, 2 * R, KC, contacts=4)
    else:
        z = H / 2 + gap
    ori = Quaternion(Vector3(0, 0, 1), math.radians(yawDeg))
    cube = eng.box((H / 2,) * 3, R, mat, pos=(0, 0, z), ori=ori)
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=gravity(thetaDeg), damping=0)]
    return eng, cube, slab, mass
