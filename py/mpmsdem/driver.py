"""Scene files for the plain C++ driver ``mpmsdem-run``, written from a YADE coupled set-up.

The driver runs a coupled scene without YADE or Python (machines without YADE, such as GPU
machines, and long batch runs). ``writeScene`` takes a :class:`mpmsdem.CoupledEngine` as set
up in a YADE script, before its first step, and writes the flow (the MPM scene it was built
from) and its blocks (shape tables, materials with their flow pairs, poses, velocities,
``fixed``/``blockedDOFs`` from ``O.bodies``) as one JSON file::

    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={copper: {"friction": 0.21}})
    mpmsdem.driver.writeScene("flume.json", coupled, duration=2.0, dt=O.dt, outputDir="out")
    # then, anywhere:  mpmsdem-run flume.json [--backend cuda]

Blocks are written as core tables (vertices, faces, sweep radius) in their body frame, so a
driver built without CGAL runs convex hulls and meshes too. The driver moves blocks as YADE's
``NewtonIntegrator`` (damping 0) does: the same scene gives the same trajectories (test:
tests/python/test_driver_blocks.py). Schema: pkg/coupling/CoupledScene.hpp.
"""
import json
import math
import os
import shutil

from yade import O

from .parameters import pythonNames

# writeScene's keywords and the scene keys they set (mpmsdem.parameters): the run settings but
# duration and dt, its own arguments; a flow probe's.
RUN_KEYS = {k: v for k, v in pythonNames("run").items() if v not in ("duration", "dt")}
PROBE_KEYS = pythonNames("flow_probes[]")
_MATERIAL_KEYS = pythonNames("block_materials.<name>")
_PAIR_KEYS = pythonNames("block_materials.<name>.flow")


def sceneDict(coupled, duration, dt="auto", flowProbes=(), **run):
    """The driver scene of ``coupled`` as a dict (see :func:`writeScene`)."""
    from .coupling import CoupledEngine
    if not isinstance(coupled, CoupledEngine):
        raise ValueError("coupled = %r: must be an mpmsdem.CoupledEngine" % (coupled,))
    if coupled.mpm.time > 0 or coupled._started:
        raise ValueError("coupled: already stepped (t = %g s); write the scene before the first step: the driver "
                         "seeds the particles from the scene, not from the current state" % coupled.mpm.time)
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0):
        raise ValueError("duration = %r s: must be a finite number > 0" % (duration,))
    if dt != "auto" and not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise ValueError("dt = %r s: must be > 0 or \"auto\"" % (dt,))
    unknown = set(run) - set(RUN_KEYS)
    if unknown:
        raise ValueError("unknown run setting(s) %s: allowed %s" % (", ".join(sorted(unknown)), ", ".join(sorted(RUN_KEYS))))
    scene = json.loads(coupled.mpm.solver.sceneJson)
    settings = {"duration": float(duration), "dt": dt if dt == "auto" else float(dt)}
    for k, v in run.items():
        settings[RUN_KEYS[k]] = v
    backend = scene.get("run", {})
    for k in ("backend", "precision"):
        if k in backend and k not in settings:
            settings[k] = backend[k]
    scene["run"] = settings
    probes = []
    for k, p in enumerate(flowProbes):
        if not isinstance(p, dict) or "x" not in p or set(p) - set(PROBE_KEYS):
            raise ValueError("flowProbes[%d] = %r: must be a dict with x and optionally %s"
                             % (k, p, ", ".join(sorted(set(PROBE_KEYS) - {"x"}))))
        probes.append({PROBE_KEYS[key]: v for key, v in p.items()})
    if probes:
        scene["flow_probes"] = probes
    sdem = coupled.sdem
    materials, names = {}, {}
    for mat, k in sdem._materials:
        if k not in coupled._pairs:
            continue
        name = "material_%d" % k
        names[k] = name
        pair = coupled._pairs[k]
        materials[name] = {key: getattr(mat, attr) for attr, key in _MATERIAL_KEYS.items()}
        materials[name]["flow"] = {key: pair[attr] for attr, key in _PAIR_KEYS.items()}
    blocks = []
    for i in sdem.ids:
        k = _materialIndex(coupled, i)
        if k not in names:
            raise ValueError("body %d: its material has no flow pair in coupled (pairs=...): every block needs one" % i)
        shape = sdem.shape(i)
        b = O.bodies[i]
        s = b.state
        blocks.append({
            "id": i, "material": names[k],
            "core": {"vertices": [list(v) for v in shape.coreVertices()],
                     "faces": [list(f) for f in shape.coreFaces()], "convex": bool(shape.convex)},
            "outer": {"vertices": [list(v) for v in shape.outerVertices()],
                      "triangles": [list(t) for t in shape.outerTriangles()]},
            "sweep_radius": shape.sweepRadius,
            "position": list(s.pos), "orientation": [s.ori[3], s.ori[0], s.ori[1], s.ori[2]],
            "velocity": list(s.vel), "angular_velocity": list(s.angVel),
            "fixed": not b.dynamic, **_dofs(b)})
    scene["block_materials"] = materials
    scene["blocks"] = blocks
    if sdem._terrain is not None:  # the blocks' ground: the flow's terrain, with the SDEM material set on it
        t, flow = sdem._terrain, scene.get("terrain")
        if flow is None or [flow.get(k) for k in ("x0", "y0", "spacing")] != [t["x0"], t["y0"], t["spacing"]] or \
                flow.get("heights") != [z for row in t["heights"] for z in row]:
            raise ValueError("the SDEM engine's terrain is not the flow's (MpmEngine(terrain=...)): a driver scene has "
                             "one ground for both; give them the same Terrain")
        m = t["material"]  # the ground does not move: no density
        scene["terrain_material"] = {key: m[attr] for attr, key in _MATERIAL_KEYS.items() if key != "density"}
    return scene


def writeScene(path, coupled, duration, dt="auto", flowProbes=(), **run):
    """Write the coupled scene of ``coupled`` (an :class:`mpmsdem.CoupledEngine` before its
    first step) as a JSON scene for ``mpmsdem-run``.

    :param duration: simulated time [s], > 0.
    :param dt: fixed step [s] (e.g. ``O.dt``, to compare with the YADE run) or ``"auto"``.
    :param flowProbes: stations where the driver records the flow's depth and velocity (the
        free-flow tests of the paper's §3.2.3 and §5), dicts with ``x`` [m] and optionally
        ``halfWidth`` [m], ``bedZ`` [m], ``minPoints``, ``window`` [s] (the scene's
        ``flow_probes``: pkg/scene/MpmScene.hpp); results in the output's flow_probes.json.
    :param run: other run settings of the scene, by the names of :data:`RUN_KEYS`
        (``outputEvery``, ``seriesEvery`` [s], ``outputDir``, ``vtk``, ``backend``, ``precision``,
        ``dtFactor``, ``minStepFraction``, ``maxBlockSpeed`` [m/s], ``progressEvery`` [s],
        ``stopWhenProbed``, ``stopWhenFrontStill`` [s], ``snapshotWhenFrontAt`` [m]: the state
        where another scene of the same flow starts, ``mpmsdem-run --flow-from``); units, defaults
        and ranges: docs/parameters.md.
    :returns: the path written.
    """
    scene = sceneDict(coupled, duration, dt, flowProbes, **run)
    with open(path, "w") as f:
        json.dump(scene, f, allow_nan=False)
    return path


def executable():
    """Path of the ``mpmsdem-run`` that belongs to this package: ``$MPMSDEM_RUN`` if set, else
    the one beside the package in a build folder (``build/mpmsdem-run`` for
    ``build/python/mpmsdem``), else the one on the PATH (``make install`` puts it in
    /usr/local/bin). FileNotFoundError when there is none."""
    env = os.environ.get("MPMSDEM_RUN")
    if env:
        if not (os.path.isfile(env) and os.access(env, os.X_OK)):
            raise FileNotFoundError("MPMSDEM_RUN = %s: not an executable file (the mpmsdem-run driver)" % env)
        return os.path.abspath(env)
    beside = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "mpmsdem-run"))
    if os.path.isfile(beside) and os.access(beside, os.X_OK):
        return beside
    found = shutil.which("mpmsdem-run")
    if found:
        return os.path.abspath(found)
    raise FileNotFoundError("mpmsdem-run: not beside this package (%s) nor on the PATH; build and install it "
                            "(`make install`) or set MPMSDEM_RUN" % beside)


def _materialIndex(coupled, yadeId):
    # The engine keeps a body's material values, not the object: equal values are one material
    # unless their flow pairs differ, which the file could not tell apart.
    from ._util import _matDict
    sdem = coupled.sdem
    values = sdem._recipes[sdem._index[yadeId]]["material"]
    ks = [k for mat, k in sdem._materials if _matDict(mat) == values]
    pairs = {json.dumps(coupled._pairs.get(k), sort_keys=True) for k in ks}
    if len(pairs) > 1:
        raise ValueError("body %d: several block materials with the same values but different flow pairs; give "
                         "them different values (e.g. density) so that the scene file can tell them apart" % yadeId)
    return ks[0]


def _dofs(body):
    # YADE's fixed bodies are non-dynamic (all DOFs blocked); the driver says that with "fixed"
    if not body.dynamic:
        return {"blocked_dofs": ""}
    return {"blocked_dofs": body.state.blockedDOFs}
