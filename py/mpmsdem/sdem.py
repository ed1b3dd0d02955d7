"""SDEM in YADE: sphero-polyhedral blocks as real YADE bodies, contact forces from C++.

Typical use::

    import mpmsdem
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    sdem = mpmsdem.SdemEngine()
    steel = mpmsdem.material(density=7800, friction=0.3)
    slab = sdem.box(halfExtents=(1, 1, .05), sweepRadius=.005, material=steel, pos=(0, 0, -.05), fixed=True)
    cube = sdem.box(halfExtents=(.05,) * 3, sweepRadius=.005, material=steel, pos=(0, 0, .06))
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 1e-5
    O.run(10000, True)
    sdem.check()   # re-raises an error that stopped the run, if any

The YADE body is the source of truth for motion (mass, inertia, pos, ori, vel, angVel,
``dynamic``, ``blockedDOFs``); the engine only adds forces and torques through ``O.forces``.
"""
import json
import math
import os
import warnings

from yade import O
from yade.wrapper import Body, FrictMat, Polyhedra
from yade.minieigenHP import Quaternion, Vector3

from . import _mpmsdem
from ._util import _material, _matDict, _nextOnGrid, _quat, _vec
from .engine import DT_CHECKS, Engine, _StepControl


class SdemEngine(Engine, _StepControl):
    """Contact forces between sphero-polyhedral blocks, run inside YADE's loop.

    :param dtCheck: ``"raise"`` (default): stop the run with an error when ``O.dt`` exceeds
        the critical step of the current contacts; ``"warn"``: print a warning instead.
    :param dtAuto: time-step control, like YADE's time steppers: None (default) leaves
        ``O.dt`` to the script; a factor f in (0, 1] sets, at the start of every step,
        ``O.dt = min(f × criticalTimeStep, 0.1 × R/(|v| + |ω| ρ))`` from the contacts of the
        step before and the bodies' current velocities (R the sweep radius, ρ the radius about
        the centroid that holds the body, min over moving bodies), growing by at most 1 % a step (at the
        first step, when the contacts are not known yet, ``O.dt`` is only capped at that). A
        body then moves by at most a tenth of its sweep radius in a step, so a body about to
        land enters the barrier gradually. A contact that starts within a step was not known
        when its ``O.dt`` was chosen: with ``dtAuto`` the step check (``dtCheck``) allows up to
        twice the critical step, the leapfrog's own limit, and the next step shrinks. A changing
        step costs a little energy in elastic impacts (YADE's integrator kicks with the new
        step): -0.24 % for a cube landing face-down, -2.5 % edge-first while spinning; a fixed
        step keeps them to 1e-6. May be changed between steps.
    :param dtMax: with ``dtAuto``, the largest ``O.dt`` it may set [s] (None: no bound).
    :param timeStepSafety: c in dt_crit = c · min sqrt(m / Σk) over bodies [-], > 0
        (c = 1 is half the leapfrog stability limit 2/ω; default 1).
    :param maxSpeed: a body faster than this [m/s] (> 0), or with a non-finite state, stops the
        run as a blow-up (default 1000 m/s).
    :param saveOnFailure: path prefix; when a step fails, the last good state is saved as
        ``<prefix>.yade.gz`` (``O.save``) and ``<prefix>.sdem.json`` (:meth:`save`) before the
        run stops. None: nothing saved (the state in memory is still the last good one).
    :param output: folder for ``sdem.h5`` — append-only HDF5 series of every body's pos, ori,
        vel, angVel, contact force and torque (``/series/<name>``, shape (records, 3·bodies),
        bodies in the order of the root attribute ``ids``) — and, with ``vtkEvery``,
        ``bodies.pvd`` + ``vtk/bodies_*.vtp`` (outer shapes, for ParaView). None: no files.
    :param outputEvery: interval of the HDF5 records [s], > 0 (with ``output``).
    :param vtkEvery: interval of the VTK files [s], > 0, or None for none.
    :param verbose: add the engine's fields (contacts, critical step) to the scene's progress
        line on stderr, every 10 s of wall time on long runs (with time, step, ``O.dt`` and wall
        time per step; :mod:`mpmsdem.engine`).
    :param label: label of the PyRunner put into ``O.engines``.
    """

    def __init__(self, dtCheck="raise", timeStepSafety=1.0, maxSpeed=1e3, saveOnFailure=None, output=None,
                 outputEvery=None, vtkEvery=None, verbose=True, label="sdem", dtAuto=None, dtMax=None):
        if dtCheck not in DT_CHECKS:
            raise ValueError("dtCheck = %r: must be one of %s" % (dtCheck, ", ".join(DT_CHECKS)))
        self._bridge = _mpmsdem.SdemBridge()
        self._bridge.strict = dtCheck == "raise"
        self._bridge.timeStepSafety = float(timeStepSafety)
        self._bridge.maxSpeed = float(maxSpeed)
        self.dtCheck = dtCheck
        self.dtAuto, self.dtMax = dtAuto, dtMax
        self._contactsKnown = False  # criticalTimeStep holds the contacts' step only after a step
        self._restoredCritical = math.inf  # restore(): the critical step saved, until the first step
        self.saveOnFailure = saveOnFailure
        if output is not None and not (outputEvery and outputEvery > 0):
            raise ValueError("outputEvery = %r s: must be > 0 when output is set" % (outputEvery,))
        if vtkEvery is not None and not (output is not None and vtkEvery > 0):
            raise ValueError("vtkEvery = %r s: must be > 0, with output set" % (vtkEvery,))
        self.output, self.outputEvery, self.vtkEvery = output, outputEvery, vtkEvery
        self._nextRecord = self._nextVtk = None  # set when the outputs open, at the first step
        self._lastRecordIter = self._lastVtkIter = None
        self._outputsOpen = None  # the per-body output file being written (no bodies may be added then)
        self._materials = []      # (SdemMat, index)
        self._recipes = []        # how each body was made, for save()/restore()
        self._terrain = None      # the ground under the blocks (terrain()), for save()/restore()
        self._index = {}          # YADE id -> engine index
        self._shapes = {}         # YADE id -> SpheroPolyhedron
        self._warned = 0
        self.verbose = verbose
        self._checkedEngines = False
        self._appendOutput = False  # restore(): continue the files in `output`
        self._rolledBackAt = None   # O.iter of a failure whose bodies were put back (save() time)
        self._bindRunner("sdem", label)

    # ------------------------------------------------------------------ bodies
    def box(self, halfExtents, sweepRadius, material, pos=(0, 0, 0), ori=None, fixed=False, color=None):
        """Add a rounded box; returns the YADE body id.

        :param halfExtents: OUTER half-extents of the box [m]; the core is shrunk by R.
        :param sweepRadius: R [m], 0 < R < min(halfExtents) (paper recommends R = h/20).
        :param material: an :class:`SdemMat`.
        :param pos: centroid position [m]. :param ori: orientation (Quaternion), default identity.
        :param fixed: a fixed body (YADE ``dynamic = False``): a slab, a flume bed, a wall.
            A body given ``blockedDOFs = "xyzXYZ"`` before the first step or while at rest
            counts as fixed too, until released.
        """
        shape = _mpmsdem.SpheroPolyhedron.box(_vec(halfExtents, "halfExtents"), float(sweepRadius))
        recipe = {"kind": "box", "halfExtents": list(_vec(halfExtents, "halfExtents")), "sweepRadius": sweepRadius}
        return self._add(shape, recipe, material, pos, ori, fixed, color, centroidPlacement=True)

    def polyhedron(self, points, sweepRadius, material, pos=None, ori=None, fixed=False, color=None):
        """Add the rounded convex hull of ``points`` [m] (the outer shape); returns the YADE id.

        With ``pos=None`` the body stays where the points describe it; otherwise its centroid
        is put at ``pos`` and ``ori`` rotates the shape as described.
        """
        pts = [_vec(p, "points") for p in points]
        shape = _mpmsdem.SpheroPolyhedron.convexHull(pts, float(sweepRadius))
        recipe = {"kind": "hull", "points": [list(p) for p in pts], "sweepRadius": sweepRadius}
        return self._add(shape, recipe, material, pos, ori, fixed, color, centroidPlacement=pos is not None)

    def mesh(self, path, sweepRadius, material, scale=1.0, pos=None, ori=None, fixed=False, color=None):
        """Add a closed triangle mesh (STL or OBJ, non-convex allowed) as the outer shape.

        Coordinates are multiplied by ``scale``. Placement as in :meth:`polyhedron`.
        """
        # The file's triangles go into the recipe: a checkpoint then restores the shape from
        # any working folder, with the file moved or gone.
        verts, tris = _mpmsdem.readMeshFile(str(path), float(scale))
        shape = _mpmsdem.SpheroPolyhedron.mesh(verts, tris, float(sweepRadius))
        recipe = {"kind": "mesh", "vertices": [list(v) for v in verts], "triangles": [list(t) for t in tris],
                  "sweepRadius": sweepRadius, "source": str(path), "scale": scale}
        return self._add(shape, recipe, material, pos, ori, fixed, color, centroidPlacement=pos is not None)

    def terrain(self, terrain, material):
        """The ground under the blocks: an :class:`mpmsdem.terrain.Terrain` (the flow's, so that
        flow and blocks stand on one surface: linear on the two triangles of each raster cell)
        with the blocks' SDEM material against it (its friction, stiffness and damping mix with
        each block's as for a block pair). Each core vertex of a moving block closer than its
        sweep radius to the plane of the terrain triangle under it is a contact (vertex–face; the
        terrain's own radius is 0): a cube face-down rests on its 4 corners, at any yaw. The cost
        is the blocks' core vertices, whatever the raster's size; relief finer than a block's
        core edges is not felt between its corners. Set it before the first step."""
        if self._outputsOpen:
            raise ValueError("terrain(): set the terrain before the first step")
        z = terrain.heights
        k = self._materialIndex(material)
        self._bridge.setTerrain(z.ravel().tolist(), z.shape[0], z.shape[1], terrain.x0, terrain.y0, terrain.spacing, k)
        self._terrain = {"heights": z.tolist(), "x0": terrain.x0, "y0": terrain.y0, "spacing": terrain.spacing,
                         "material": _matDict(material)}

    def _materialIndex(self, mat):
        if not isinstance(mat, _mpmsdem.SdemMat):
            raise ValueError("material = %r: must be an mpmsdem.SdemMat (see mpmsdem.material())" % (mat,))
        for m, k in self._materials:
            if m is mat:
                return k
        mat.validate()
        k = self._bridge.addMaterial(mat)
        self._materials.append((mat, k))
        return k

    def _add(self, shape, recipe, material, pos, ori, fixed, color, centroidPlacement, yadeId=None):
        if yadeId is None and self._outputsOpen:
            # each per-body series has one column block per body, its width fixed when the file
            # was opened: a new body has no place there
            raise ValueError(
                "%s(): adding a body after the run started writing %s is not supported (its per-body series have "
                "their width fixed at the first step). Add every body before the first step, or continue in a new "
                "output folder: checkpoint (mpmsdem.saveCheckpoint, or engine.save + O.save), restore it with "
                "output=<new folder>, then add the body before the restored engine's first step"
                % (recipe["kind"] if recipe["kind"] != "hull" else "polyhedron", self._outputsOpen))
        k = self._materialIndex(material)
        q = _quat(ori) if ori is not None else Quaternion.Identity
        if centroidPlacement:
            p = _vec(pos, "pos")
            o = q * shape.frameOrientation
        else:
            p = q * shape.framePosition
            o = q * shape.frameOrientation
        mass = material.density * shape.volume
        inertia = shape.inertiaPerDensity * material.density
        if yadeId is None:
            b = Body()
            b.shape = Polyhedra(v=shape.outerVertices())
            if color is not None:
                b.shape.color = _vec(color, "color")
            b.material = FrictMat(density=material.density, frictionAngle=math.atan(material.friction),
                                  poisson=material.poisson)
            b.state.mass = mass
            b.state.inertia = inertia
            b.state.pos = p
            b.state.ori = o
            b.aspherical = True
            if fixed:
                b.dynamic = False
            yadeId = O.bodies.append(b)
        self._bridge.addBody(shape, k, mass, inertia, yadeId, bool(fixed))
        self._index[yadeId] = len(self._recipes)
        self._shapes[yadeId] = shape
        recipe = dict(recipe, yadeId=yadeId, fixed=bool(fixed), material=_matDict(material))
        self._recipes.append(recipe)
        return yadeId

    def shape(self, yadeId):
        """The :class:`SpheroPolyhedron` of a body (ValueError if it is not an SDEM body)."""
        try:
            return self._shapes[yadeId]
        except KeyError:
            raise ValueError("yadeId = %r: not an SDEM body of this engine (ids: %s)"
                             % (yadeId, sorted(self._shapes))) from None

    @property
    def ids(self):
        """YADE ids of the SDEM bodies, in engine order."""
        return [r["yadeId"] for r in self._recipes]

    # ------------------------------------------------------------------ stepping
    # Forces reset before the contacts add theirs, bodies moved after. Any other order fails
    # later with a misleading time-step error (forces added twice or lost), and without the
    # runner blocks fall through each other silently.
    _name, _runnerName = "SdemEngine", "sdem.runner"
    _between = ("the SDEM runner adds the contact forces after ForceResetter clears them and before "
                "NewtonIntegrator moves the bodies")

    def _step(self):
        self._stepping(O.time, O.iter, O.dt)
        self._checkEnginesOnce()
        self._beforeFirstStep()
        try:
            # set before this step's forces, so that NewtonIntegrator and O.time advance by it
            self._setAutoStep(self._restoredCritical, self._contactsKnown)
            self._bridge.setStepClock(O.iter, O.time)
            self._bridge.step(O.bodies, O.forces, O.dt)
        except Exception as e:
            self._fail(e)
            raise
        self._contactsKnown = True
        self._restoredCritical = math.inf
        self._afterStep()

    def _beforeFirstStep(self):
        if not self._checkedEngines:
            self._checkedEngines = True
            _warnDamping()
            if self.output is not None:  # opened here: every body has been added by now
                t = O.time
                # records after t were written by a run that went on past the checkpoint we
                # restart from: dropped, so the series never repeat or go back in time
                lastRecord, lastVtk = self._bridge.openOutput(str(self.output), self._appendOutput,
                                                              t + 1e-9 * self.outputEvery)
                self._outputsOpen = os.path.join(str(self.output), "sdem.h5")
                self._nextRecord = t if math.isnan(lastRecord) else max(t, _nextOnGrid(lastRecord, self.outputEvery))
                self._nextVtk = t if (math.isnan(lastVtk) or not self.vtkEvery) else max(t, lastVtk + self.vtkEvery)

    def _lastGoodState(self, e):
        """Put the SDEM bodies back to the last good state after a failed step and save it
        (saveOnFailure); returns what the error adds about it.

        The last good state is the one at the start of the last step that completed: when the
        blow-up guard fires, the state YADE holds was produced by NewtonIntegrator from the
        previous step's forces and is already bad, so the failed step's own start cannot be
        trusted. YADE has no setter for O.iter and O.time: they stay at the failed step, one
        step after the state (the checkpoint records the state's own time)."""
        note = ""
        it = self._bridge.rollBack(O.bodies)
        if it >= 0:
            self._rolledBackAt = O.iter
            note += " [bodies put back to their state at the start of step %d (t = %.6g s)]" % (it, self._bridge.goodTime)
        if self.saveOnFailure:
            O.save(self.saveOnFailure + ".yade.gz")
            self.save(self.saveOnFailure + ".sdem.json")
            note += (" [last good state saved: %s.yade.gz, %s.sdem.json; to resume: O.load(%r), "
                     "engine = mpmsdem.SdemEngine.restore(%r), O.engines = [ForceResetter(), engine.runner, "
                     "NewtonIntegrator(...)], and a smaller O.dt (now %g s; the critical step is "
                     "engine.criticalTimeStep after a step)]"
                     % (self.saveOnFailure, self.saveOnFailure, self.saveOnFailure + ".yade.gz",
                        self.saveOnFailure + ".sdem.json", O.dt))
        return note

    def _afterStep(self):
        if self.output is not None:
            t = O.time
            # half a step of slack: O.time is a sum of steps and may fall a rounding error short
            # of the record time it reaches
            slack = 0.5 * O.dt
            if t >= self._nextRecord - slack:
                if self._lastRecordIter != O.iter:  # finish() may have recorded this state
                    self._bridge.record(t, O.iter)
                    self._lastRecordIter = O.iter
                while self._nextRecord <= t + slack:
                    self._nextRecord += self.outputEvery
            if self.vtkEvery and t >= self._nextVtk - slack:
                if self._lastVtkIter != O.iter:
                    self._bridge.writeVtk(t)
                    self._lastVtkIter = O.iter
                while self._nextVtk <= t + slack:
                    self._nextVtk += self.vtkEvery
        self._warnTimeStep("critical step", self._bridge.criticalTimeStep)

    def _progressFields(self, perStep):
        return "%d contacts, critical step %.3g s" % (self._bridge.numContacts, self._bridge.criticalTimeStep)

    def finish(self, vtk=True):
        """Record the state YADE holds now (the bodies as the last step moved them, at O.time)
        in ``sdem.h5`` and, with ``vtk`` and ``vtkEvery``, as a ParaView file, unless this step
        has them: the outputs of a run then end with its final state (a 1 s run ends with a
        record at t = 1 s). :func:`mpmsdem.run` calls ``finish(vtk=False)`` after each run;
        call it after a plain ``O.run`` yourself. The record's forces are those the next step
        will compute; the run continues exactly as without the call."""
        if self.output is None or self._nextRecord is None or self.error:
            return
        if self._lastRecordIter != O.iter:
            self._bridge.recordCurrent(O.bodies, O.time, O.iter, O.dt)
            self._lastRecordIter = O.iter
        if vtk and self.vtkEvery and self._lastVtkIter != O.iter:
            self._bridge.writeVtk(O.time)
            self._lastVtkIter = O.iter

    def refresh(self):
        """Re-read YADE's body state objects (after replacing O.bodies or O.load())."""
        self._bridge.refresh()

    # ------------------------------------------------------------------ read-out
    @property
    def criticalTimeStep(self):
        """c · min sqrt(m / Σ k_n) over bodies for the current contacts [s] (inf: no contact)."""
        return self._bridge.criticalTimeStep

    @property
    def narrowPhasePairs(self):
        """Body pairs whose contact geometry the narrow phase computed, summed over the steps
        so far. Pairs of two fixed bodies never are; a body whose six DOFs are blocked counts
        as fixed."""
        return self._bridge.narrowPhasePairs

    @property
    def timeStepWarnings(self):
        """Number of steps whose O.dt exceeded the critical step (dtCheck = "warn")."""
        return self._bridge.timeStepWarnings

    def contacts(self):
        """Contact points of the last step as numpy arrays: id1, id2, point (n×3), normal (n×3,
        from id1 to id2), normalForce (n) [N], tangentialForce (n×3) [N, on id2], overlap [m],
        normalStiffness [N/m], sliding (0/1), feature1/feature2 ('vertex'|'edge'|'face')."""
        return self._bridge.contacts()

    def force(self, yadeId):
        """Contact force of the last step on a body [N] (world frame)."""
        return self._bridge.force(self._engineIndex(yadeId))

    def torque(self, yadeId):
        """Contact torque of the last step about the body centroid [N m]."""
        return self._bridge.torque(self._engineIndex(yadeId))

    def _engineIndex(self, yadeId):
        if yadeId not in self._index:
            self.shape(yadeId)
        return self._index[yadeId]

    def energies(self):
        """Contact energies [J]: barrier potential, tangential springs, cumulative friction and
        damping dissipation."""
        b = self._bridge
        return {"barrier": b.barrierEnergy, "tangential": b.tangentialEnergy,
                "friction": b.frictionDissipation, "damping": b.dampingDissipation}

    def timings(self):
        """Wall time spent in the bridge since the last reset: steps, read (YADE → C++ state),
        compute (contacts and laws), write (forces → O.forces) [s]."""
        return dict(self._bridge.timings())

    def resetTimings(self):
        self._bridge.resetTimings()

    # ------------------------------------------------------------------ checkpoint
    def save(self, path):
        """Write the engine's state (shapes' recipes, materials, contact histories) as JSON,
        to go alongside ``O.save()``; restore with :meth:`SdemEngine.restore`."""
        self._bridge.commitOutput()  # a restart from this checkpoint finds sdem.h5 as it is now
        hist = [[a, b, ka, kb, ia, ib, list(xi)] for (a, b, ka, kb, ia, ib, xi) in self._bridge.histories()]
        rolledBack = self._rolledBackAt is not None and self._rolledBackAt == O.iter
        data = {"format": "mpmsdem-sdem-2", "dtCheck": self.dtCheck,
                "timeStepSafety": self._bridge.timeStepSafety, "maxSpeed": self._bridge.maxSpeed,
                "dtAuto": self.dtAuto, "dtMax": self.dtMax,
                # what dtAuto's next step reads (None: not known yet; a string keeps inf JSON-clean)
                "criticalStep": repr(self._bridge.criticalTimeStep) if self._contactsKnown else None,
                "time": self._bridge.goodTime if rolledBack else O.time,
                "frictionDissipation": self._bridge.frictionDissipation,
                "dampingDissipation": self._bridge.dampingDissipation,
                "bodies": self._recipes, "histories": hist, "terrain": self._terrain,
                # before the first step no output is open yet (unless restored onto one): a restore
                # then starts it afresh, whatever a killed run left of it (none of it is this
                # checkpoint's)
                "outputOpen": self._checkedEngines or self._appendOutput}
        tmp = str(path) + ".tmp"
        with open(tmp, "w") as f:
            json.dump(data, f)
        os.replace(tmp, str(path))

    @classmethod
    def restore(cls, path, appendOutput=True, **engineKw):
        """Rebuild an engine from :meth:`save` for bodies already in ``O.bodies`` (after
        ``O.load()``); returns it. Put its ``runner`` back into ``O.engines``. The saved
        dtCheck, timeStepSafety and maxSpeed are used unless given in ``engineKw``, which takes
        the other constructor arguments too (output, saveOnFailure, label, ...).

        The checkpoint is self-contained (shapes stored with their geometry): it restores from
        any working folder. With ``output``, ``sdem.h5`` and ``bodies.pvd`` are continued
        (``appendOutput``): records later than the checkpoint, left by a run that went on past
        it, are dropped first. The friction and damping dissipations continue from their saved
        values.

        A file that is not such a checkpoint, or is damaged, gets a ValueError naming it and what
        is wrong."""
        try:
            with open(path) as f:
                data = json.load(f)
            return cls._restoreFrom(path, data, appendOutput, engineKw)
        except ValueError as e:
            if repr(path) in str(e):
                raise
            raise ValueError("path = %r: %s" % (path, e)) from None
        except (KeyError, TypeError, IndexError, AttributeError) as e:
            # a key missing, a value of the wrong kind: a damaged or foreign file
            raise ValueError("path = %r: not a whole mpmsdem SDEM checkpoint (%s: %s)"
                             % (path, type(e).__name__, e)) from None

    @classmethod
    def _restoreFrom(cls, path, data, appendOutput, engineKw):
        if not isinstance(data, dict):
            raise ValueError("path = %r: not an mpmsdem SDEM checkpoint (a JSON %s, not an object)"
                             % (path, type(data).__name__))
        if data.get("format") == "mpmsdem-sdem-1":
            # Format 1 stored the tangential history as a displacement [m]; it is now the elastic
            # tangential force [N], so the old values cannot be reinterpreted.
            raise ValueError("path = %r: an mpmsdem-sdem-1 checkpoint, whose contact histories are tangential "
                             "displacements; this version stores elastic tangential forces and cannot restore it: "
                             "run the scene again from the start" % (path,))
        if data.get("format") != "mpmsdem-sdem-2":
            raise ValueError("path = %r: not an mpmsdem SDEM checkpoint" % (path,))
        kw = {k: data[k] for k in ("dtCheck", "timeStepSafety", "maxSpeed", "dtAuto", "dtMax") if k in data}
        kw.update(engineKw)
        eng = cls(**kw)
        eng._appendOutput = bool(appendOutput) and data.get("outputOpen", True)
        if data.get("criticalStep") is not None:  # the first step's dtAuto sees what it would have seen
            eng._contactsKnown = True
            eng._restoredCritical = float(data["criticalStep"])
        mats = {}
        for r in data["bodies"]:
            key = json.dumps(r["material"], sort_keys=True)
            if key not in mats:
                mats[key] = _material(r["material"])
            if r["kind"] == "box":
                shape = _mpmsdem.SpheroPolyhedron.box(r["halfExtents"], r["sweepRadius"])
            elif r["kind"] == "hull":
                shape = _mpmsdem.SpheroPolyhedron.convexHull(r["points"], r["sweepRadius"])
            elif r["kind"] == "mesh":
                shape = _mpmsdem.SpheroPolyhedron.mesh(r["vertices"], r["triangles"], r["sweepRadius"])
            else:  # "meshFile": checkpoints written before shapes were stored with their geometry
                shape = _mpmsdem.SpheroPolyhedron.meshFile(r["path"], r["sweepRadius"], r["scale"])
            rec = {k: v for k, v in r.items() if k not in ("yadeId", "fixed", "material")}
            eng._add(shape, rec, mats[key], None, None, r["fixed"], None, centroidPlacement=False,
                     yadeId=r["yadeId"])
        if data.get("terrain"):
            from .terrain import Terrain
            t = data["terrain"]
            key = json.dumps(t["material"], sort_keys=True)
            eng.terrain(Terrain(t["heights"], t["spacing"], t["x0"], t["y0"]), mats.get(key) or _material(t["material"]))
        eng._bridge.setHistories([tuple(h[:6]) + (Vector3(*h[6]),) for h in data["histories"]])
        eng._bridge.setDissipation(float(data.get("frictionDissipation", 0.0)),
                                   float(data.get("dampingDissipation", 0.0)))
        return eng


def _warnDamping():
    from yade.wrapper import NewtonIntegrator
    for e in O.engines:
        if isinstance(e, NewtonIntegrator) and e.damping != 0:
            warnings.warn("NewtonIntegrator.damping = %g: YADE's numerical damping removes energy the contact law "
                          "would conserve (restitution < 1 with an elastic barrier); use damping=0 and the "
                          "materials' normalDamping/tangentialDamping instead" % e.damping, RuntimeWarning)
