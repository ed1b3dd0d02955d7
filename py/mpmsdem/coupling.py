"""MPM flow and SDEM blocks coupled every step inside YADE (paper §2.3, Eqs 12–18).

A material point is a sphere of radius R_p0 = (3 V0 / 4π)^(1/3) (Eq 13) that touches the
blocks' rounded shapes through the same barrier normal law and Coulomb tangential law as
block–block contacts (Eq 12); the force goes to the block at the contact point and,
opposite, to the grid through the particle's P2G weights (Eqs 14–16). Typical use::

    import mpmsdem
    from yade import O
    from yade.wrapper import ForceResetter, NewtonIntegrator
    sdem = mpmsdem.SdemEngine()
    copper = mpmsdem.material(density=8900, friction=0.67)
    bed = sdem.box((1.0, 0.15, 0.02), 0.005, copper, pos=(0.8, 0.1, -0.02), fixed=True)
    cube = sdem.box((0.01,) * 3, 0.001, copper, pos=(0.51, 0.1, 0.0101))
    mpm = mpmsdem.MpmEngine(grid=..., material=..., particles=..., gravity=...)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={copper: {"friction": 0.21}})
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=..., damping=0)]
    O.dt = 0.5 * coupled.criticalTimeStep()
    mpmsdem.run(10000, coupled)

``coupled.runner`` replaces ``sdem.runner`` and ``mpm.runner`` (it steps both).
"""
import math
import warnings

from yade import O
from yade.minieigenHP import Quaternion, Vector3

from . import _mpmsdem
from ._util import _material, _matDict, _nextOnGrid
from .engine import DT_CHECKS, Engine, _StepControl
from .parameters import parameters, pythonNames

# The keys of a flow-block pair (a block material's "flow" in a scene: mpmsdem.parameters).
PAIR_KEYS = tuple(pythonNames("block_materials.<name>.flow"))


def _timesOrNone(times):
    # first contacts for a checkpoint: JSON has no NaN or infinity (not yet, not kept)
    return [t if math.isfinite(t) else None for t in times]


def _timesOrNan(times):
    return [math.nan if t is None else t for t in times]


class CoupledEngine(Engine, _StepControl):
    """Couples an :class:`SdemEngine` (blocks) and an :class:`MpmEngine` (flow).

    :param sdem: the SDEM engine whose bodies are the blocks (all of them are coupled).
    :param mpm: the MPM engine of the flow (CPU or CUDA backend).
    :param pairs: contact physics between the flow and each block material, a dict
        ``{SdemMat: {"friction": μ, "barrierStiffness": k_c [N/m], "poisson": ν,
        "normalDamping": ζ_n, "tangentialDamping": ζ_t}}`` (a bare number is taken as μ);
        missing keys default to the block material's own values. Every material used by a
        block needs a pair: the flow–block friction is a property of the pair, not of the
        block (paper Table 1: basal friction of the flow 0.21 on the bed).
    :param dtCheck: ``"raise"`` stops the run when ``O.dt`` exceeds the critical step of the
        MP–block and block–block contacts (tangent barrier stiffness with the MP and block
        masses, :attr:`contactTimeStep`); ``"warn"`` warns once and counts
        (``timeStepWarnings``). May be changed between steps.
    :param dtAuto: time-step control, like YADE's time steppers: None (default) leaves
        ``O.dt`` to the script; a factor f in (0, 1] sets, at the start of every step,
        ``O.dt = min(f × criticalTimeStep(), 0.1 × approachTimeStep, particleApproachStep)``
        from the contacts of the step before and the blocks' current velocities, growing by at
        most 1 % a step (at the
        first step, when the contacts are not known yet, ``O.dt`` is only capped at that). No
        block then moves by more than a tenth of its sweep radius in a step, so a block about
        to land, which has no contact yet, enters the barrier gradually and none passes through
        another. ``O.dt`` is also at most :attr:`particleApproachStep`, so a material point
        that reaches a stiff barrier within a step does not start the next one beyond its
        contact step. Any other contact that starts within a step was not known when its
        ``O.dt`` was chosen: with ``dtAuto`` the step checks (``dtCheck``) allow up to twice
        the critical step, the leapfrog's own stability limit, and the next step shrinks. A changing step costs a
        little energy in elastic impacts (YADE's integrator kicks with the new step): -0.24 %
        for a cube landing face-down, -2.5 % edge-first while spinning; a fixed step keeps them
        to 1e-6. May be changed between steps.
    :param dtMax: with ``dtAuto``, the largest ``O.dt`` it may set [s] (None: no bound), e.g.
        to sample a fast transient finely.
    :param minStepFraction: with ``dtAuto``, a step below this fraction of the flow's CFL step
        stops the run (the last good state saved, as for a blow-up), naming what forces it (a
        block's speed, a contact): a run at such steps crawls. In [0, 1) (default 1e-4; 0: no
        floor). The progress line says what sets the step at any time (:attr:`stepLimit`).
    :param maxBlockSpeed: a block faster than this at the first step [m/s] (|v| + |ω| times its
        bounding radius) is refused with a ValueError naming it: no scene starts so. None
        (default): ten times the flow's P-wave speed (290 m/s for Table 1's glass beads), as the
        driver's ``run.max_block_speed``.
    :param historySlots: simultaneous block contacts per material point that keep their
        tangential history, in [1, 4] (default 2: a point between a block and the bed).
    :param output: folder for ``coupled.h5`` (per block every ``outputEvery`` s: ``pos``,
        ``vel``, ``rotation`` (rotation vector since the first record) [rad], ``flow_force``
        F_t, ``face_force`` F_f, ``edge_force`` F_e (paper §3.2.3), ``flow_torque`` (of the step
        before the record), ``flow_impulse`` [N s] and ``flow_angular_impulse`` [N m s] (summed
        over every step since the run's start: their change between two records over the
        interval is the mean force between them, :func:`mpmsdem.analysis.intervalMean`),
        ``contacts``; energies ``flow_kinetic``, ``flow_potential``, ``block_kinetic``,
        ``dissipated`` [J]) and, with ``vtkEvery``, ``scene.pvd`` (particles, blocks and the
        point–block contacts of the step in one ParaView time series; on CUDA it sets
        :attr:`recordContacts`). The SDEM and MPM engines keep their own outputs if given.
    :param plot: also feed ``yade.plot.addData`` every ``outputEvery`` s (``t``, and per
        block id ``Ft_<id>``, ``Ff_<id>``, ``Fe_<id>`` [N], ``x_<id>`` [m], ``vx_<id>``
        [m/s], ``rot_<id>`` [deg]; per LevelSet body the same without ``Ff``/``Fe``), so
        ``plot.plots``/``plot.saveDataTxt`` work as with any YADE engine. Needs ``outputEvery``.
    :param verbose: add the coupling's fields (MP–block contacts, the critical step, what sets
        ``O.dt``) to the scene's progress line on stderr, every 10 s of wall time (with time,
        step, ``O.dt`` and wall time per step, and the fields of the SDEM and MPM engines that are
        verbose themselves; :mod:`mpmsdem.engine`).
    :param levelSets: YADE ``LevelSet`` bodies in the flow, beside the SDEM blocks (on a CUDA
        flow not yet run on a GPU: docs/coupling.md): a dict ``{body id: {"friction": μ, "barrierStiffness": k_c [N/m],
        "poisson": ν, "normalDamping": ζ_n, "tangentialDamping": ζ_t}}`` of the flow–body contact
        physics (a bare number is taken as μ; missing keys default to those of
        :func:`mpmsdem.material`). A material point meets such a body through the body's own
        distance grid (``shape.lsGrid``, ``shape.distField``, trilinear; docs/coupling.md), with
        the barrier and Coulomb laws of the blocks; YADE moves the body (its NewtonIntegrator)
        and keeps its contacts with other bodies (``Ig2_LevelSet_LevelSet_ScGeom`` and a law in
        ``O.engines``). A body whose grid spacing exceeds the material points' contact radius
        R_p0 is refused with a ValueError. With LevelSet bodies ``pairs`` may be empty when the
        SDEM engine has no block.
    """

    def __init__(self, sdem, mpm, pairs, dtCheck="raise", historySlots=2, output=None, outputEvery=None,
                 vtkEvery=None, plot=False, label="coupled", verbose=True, dtAuto=None, dtMax=None,
                 minStepFraction=1e-4, maxBlockSpeed=None, levelSets=None):
        from .mpm import MpmEngine
        from .sdem import SdemEngine
        if not isinstance(sdem, SdemEngine):
            raise ValueError("sdem = %r: must be an mpmsdem.SdemEngine" % (sdem,))
        if not isinstance(mpm, MpmEngine):
            raise ValueError("mpm = %r: must be an mpmsdem.MpmEngine" % (mpm,))
        if (output is not None or plot) and not (outputEvery and outputEvery > 0):
            raise ValueError("outputEvery = %r s: must be > 0 when output or plot is set" % (outputEvery,))
        if vtkEvery is not None and not (output is not None and vtkEvery > 0):
            raise ValueError("vtkEvery = %r s: must be > 0, with output set" % (vtkEvery,))
        self.sdem, self.mpm = sdem, mpm
        self._bridge = _mpmsdem.CouplingBridge(sdem._bridge, mpm.solver)
        self._bridge.historySlots = int(historySlots)
        self._bridge.recordContacts = vtkEvery is not None
        self.dtCheck = dtCheck
        self.dtAuto = dtAuto
        self.dtMax = dtMax
        if not (isinstance(minStepFraction, (int, float)) and 0 <= minStepFraction < 1):
            raise ValueError("minStepFraction = %r: must be in [0, 1) (0: no floor on the automatic step)"
                             % (minStepFraction,))
        self.minStepFraction = float(minStepFraction)
        if maxBlockSpeed is not None and not (isinstance(maxBlockSpeed, (int, float)) and maxBlockSpeed > 0):
            raise ValueError("maxBlockSpeed = %r m/s: must be > 0 (None: ten times the flow's P-wave speed)"
                             % (maxBlockSpeed,))
        self.maxBlockSpeed = maxBlockSpeed
        self._pairs = {}
        if levelSets is not None and not (isinstance(levelSets, dict) and levelSets):
            raise ValueError("levelSets = %r: must be a non-empty dict {LevelSet body id: {...}} of flow-body "
                             "contact physics, or None" % (levelSets,))
        if not isinstance(pairs, dict) or not (pairs or levelSets):
            raise ValueError("pairs = %r: must be a non-empty dict {SdemMat: {...}} of flow-block contact "
                             "physics" % (pairs,))
        for mat, spec in pairs.items():
            self.setPair(mat, spec)
        self._levelSets = {}  # YADE id -> index in the bridge
        self._levelSetPairs = {}  # YADE id -> its flow-body contact physics (for checkpoints)
        for bid, spec in (levelSets or {}).items():
            self._addLevelSet(bid, spec)
        self.output, self.outputEvery, self.vtkEvery, self.plot = output, outputEvery, vtkEvery, plot
        self.verbose = verbose
        self.error = None
        self._started = False
        self._contactsKnown = False  # criticalTimeStep() holds the contact step only after a step
        self._restoredContactStep = None  # restore(): the contact step saved, until the first step
        self._warned = 0
        self._nextRecord = self._nextVtk = None
        self._lastRecord = self._lastVtk = -math.inf
        self._ori0 = {}
        self._appendOutput = False  # restore(): continue the files in `output`
        self._bindRunner("coupled", label)

    def setPair(self, material, spec):
        """Set the flow–block contact physics for blocks of ``material`` (see ``pairs``)."""
        if isinstance(spec, (int, float)):
            spec = {"friction": float(spec)}
        if not isinstance(spec, dict):
            raise ValueError("pairs[%r] = %r: must be a dict with keys among %s, or a friction number"
                             % (material, spec, ", ".join(PAIR_KEYS)))
        unknown = set(spec) - set(PAIR_KEYS)
        if unknown:
            raise ValueError("pairs: unknown key(s) %s: allowed %s" % (", ".join(sorted(unknown)), ", ".join(PAIR_KEYS)))
        k = self.sdem._materialIndex(material)
        p = {key: float(spec.get(key, getattr(material, key))) for key in PAIR_KEYS}
        self._bridge.setPair(k, p["barrierStiffness"], p["friction"], p["poisson"], p["normalDamping"],
                             p["tangentialDamping"])
        self._pairs[k] = p

    def _addLevelSet(self, bid, spec):
        import numpy as np
        from yade.wrapper import LevelSet
        if isinstance(spec, (int, float)):
            spec = {"friction": float(spec)}
        if not isinstance(spec, dict):
            raise ValueError("levelSets[%r] = %r: must be a dict with keys among %s, or a friction number"
                             % (bid, spec, ", ".join(PAIR_KEYS)))
        unknown = set(spec) - set(PAIR_KEYS)
        if unknown:
            raise ValueError("levelSets[%r]: unknown key(s) %s: allowed %s"
                             % (bid, ", ".join(sorted(unknown)), ", ".join(PAIR_KEYS)))
        if not isinstance(bid, int) or not 0 <= bid < len(O.bodies) or O.bodies[bid] is None:
            raise ValueError("levelSets: body id %r: must be the id of a body in O.bodies" % (bid,))
        shape = O.bodies[bid].shape
        if not isinstance(shape, LevelSet):
            raise ValueError("levelSets: body %d has a %s shape: must be a LevelSet" % (bid, type(shape).__name__))
        if bid in self.sdem._index:
            raise ValueError("levelSets: body %d is an SDEM block" % bid)
        if bid in self._levelSets:
            raise ValueError("levelSets: body %d given twice" % bid)
        defaults = {p["python"]: p["default"] for p in parameters("block_materials.<name>")}  # mpmsdem.material's
        p = {key: float(spec.get(key, defaults[key])) for key in PAIR_KEYS}
        g = shape.lsGrid
        dist = np.ascontiguousarray(np.asarray(shape.distField, dtype=np.float64))
        n = tuple(int(k) for k in g.nGP)
        if dist.shape != n:
            raise ValueError("levelSets: body %d: distField has shape %s, its grid %s points" % (bid, dist.shape, n))
        self._bridge.addLevelSet(bid, Vector3(g.min), float(g.spacing), n[0], n[1], n[2], dist.tobytes(),
                                 p["barrierStiffness"], p["friction"], p["poisson"], p["normalDamping"],
                                 p["tangentialDamping"])
        self._levelSets[bid] = len(self._levelSets)
        self._levelSetPairs[bid] = p

    @property
    def levelSetIds(self):
        """The YADE ids of the coupled LevelSet bodies, in the order given."""
        return list(self._levelSets)

    @property
    def dtCheck(self):
        """``"raise"`` or ``"warn"``: what a step above :attr:`contactTimeStep` does."""
        return self._dtCheck

    @dtCheck.setter
    def dtCheck(self, value):
        if value not in DT_CHECKS:
            raise ValueError("dtCheck = %r: must be one of %s" % (value, ", ".join(DT_CHECKS)))
        self._bridge.strict = value == "raise"
        self._dtCheck = value

    @property
    def contactTimeStep(self):
        """The contact part of :meth:`criticalTimeStep` [s], from the contacts of the last step:
        sqrt(m_p/k) per MP–block contact and sqrt(m/Σk) (and its rotational analogue) per moving
        block, k the tangent barrier stiffness, times the SDEM safety factor; ``inf`` before the
        first step and while nothing touches. A step above it is what ``dtCheck`` acts on."""
        return self._bridge.contactStep

    @property
    def particleApproachStep(self):
        """The longest next step [s] that stays within the contact step of the contacts the
        last step made: material points that did not touch a block at its start but reached its
        barrier within it, by δ = v_n dt − g (normal speed v_n, gap g). Those contacts act in the
        next step but are only known once it has begun, so ``dtAuto`` keeps ``O.dt`` under
        ``s sqrt(m_p R / (6 k_c δ))`` for each (R = R_p0 + R_b, s the SDEM time-step safety, 6 k_c
        δ/R the barrier's tangent stiffness at first touch, Eq 10; K_t instead when it is the
        larger). inf when no point reached a block.
        """
        return self._bridge.particleApproachStep

    @property
    def approachTimeStep(self):
        """The step in which a point of a moving block travels its own sweep radius [s]: min over
        moving blocks of R / (|v| + |ω| ρ), ρ the radius of a sphere about the centroid that
        holds the block, at the blocks' current velocities; ``inf`` when none moves.
        ``dtAuto`` keeps ``O.dt`` below a tenth of it."""
        return self._bridge.approachStep(O.bodies)

    # ------------------------------------------------------------------ stepping
    def criticalTimeStep(self):
        """The largest stable step of the coupled scene [s]: the MPM CFL step and the contact
        step sqrt(m/k) of MP–block (MP mass) and block–block/MP contacts (block mass), times
        the SDEM safety factor. Before the first step only the MPM part is known."""
        return self._bridge.criticalTimeStep()

    _name, _runnerName = "CoupledEngine", "coupled.runner"
    _between = "the coupled runner adds the block forces after they are reset and before YADE moves the blocks"

    def _checkEngines(self):
        engines = list(O.engines)
        if self.sdem.runner in engines or self.mpm.runner in engines:
            raise ValueError("O.engines holds sdem.runner or mpm.runner besides coupled.runner: the coupled runner "
                             "steps both; use O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(...)]")
        newton = super()._checkEngines()
        g = Vector3(newton.gravity)
        gm = self.mpm.gravity
        if (g - Vector3(*gm)).norm() > 1e-9 * max(g.norm(), 1.0):
            raise ValueError("NewtonIntegrator.gravity = %s differs from the MPM gravity %s: blocks and flow must "
                             "fall the same way" % (tuple(g), tuple(gm)))

    def _checkBlockSpeeds(self):
        """ValueError naming a block faster than maxBlockSpeed: no scene starts so."""
        self._bridge.checkBlockSpeeds(O.bodies, self.maxBlockSpeed or self._bridge.defaultMaxBlockSpeed)

    def _beforeRun(self):
        # O.engines is checked at the first step: a wrong list stops the run there (RuntimeError)
        if not self._started:
            self._checkBlockSpeeds()

    def _step(self):
        self._stepping(O.time, O.iter, O.dt)
        if not self._started:
            self._checkEnginesOnce()
            self._checkBlockSpeeds()
            self._started = True
            self.sdem._beforeFirstStep()
            self._nextRecord = self._nextVtk = O.time
            if self.output is not None:
                self._openOutput()
            for w in self._bridge.outsideGridWarnings(O.bodies):
                warnings.warn("mpmsdem.CoupledEngine: " + w, RuntimeWarning)
        if self._dtAuto is not None:
            # Set before this step's forces, so that the coupling, NewtonIntegrator and O.time
            # all advance by the same dt, and before the records, whose time slack is half of it.
            crit = self.criticalTimeStep()
            if self._restoredContactStep is not None:
                crit = min(crit, self._restoredContactStep)
            self._setAutoStep(crit, self._contactsKnown)
            cfl = self.mpm.solver.stableTimeStep()
            if self._contactsKnown and O.dt < self.minStepFraction * cfl:
                e = RuntimeError("the automatic step fell to %.4g s, below minStepFraction = %g of the flow's CFL step "
                                 "%.4g s: the run would crawl. It is set by %s. Check the scene (block velocities, "
                                 "barrier stiffness), or lower minStepFraction (0: no floor)"
                                 % (O.dt, self.minStepFraction, cfl, self.stepLimit))
                self._fail(e)
                raise e
        # Records are taken here, before the step: NewtonIntegrator has moved the blocks to the
        # flow's time, so blocks and particles are both at t (after the MPM step they would be a
        # step apart). The forces recorded are those of the step that led to t; finish() records
        # the state the run ends with.
        self._recordDue(self.mpm.time)
        try:
            self._bridge.step(O.bodies, O.forces, O.dt)
        except Exception as e:
            self._fail(e)
            raise
        self._contactsKnown = True
        self._restoredContactStep = None
        self.sdem._afterStep()
        self.mpm._afterStep(O.dt)
        self._warnTimeStep("contact critical step", self._bridge.contactStep)

    def _progressParts(self, perStep):
        return self.sdem._progressParts(perStep) + self.mpm._progressParts(perStep) + super()._progressParts(perStep)

    def _progressFields(self, perStep):
        return "%d MP-block contacts, critical step %.3g s, O.dt: %s" % (self._bridge.totalContacts,
                                                                       self._bridge.contactStep, self.stepLimit)

    @property
    def stepLimit(self):
        """What sets ``O.dt`` now, in words: with ``dtAuto`` the term of the automatic step (the
        flow's CFL step, the contacts' critical step, a block's approach naming the block and its
        speed, a material point closing on a barrier, the growth cap); otherwise "set by the
        script"."""
        return (self._bridge.stepLimit or "not chosen yet") if self._dtAuto is not None else "set by the script"

    def _recordDue(self, t, final=False, files=False):
        # t is a sum of steps: it may fall a rounding error short of a record time
        slack = 0.5 * O.dt
        if (self.output is not None or self.plot) and (t >= self._nextRecord - slack or
                                                        (final and t > self._lastRecord + slack)):
            self._record(t)
            self._lastRecord = t
            while self._nextRecord <= t + slack:
                self._nextRecord += self.outputEvery
        if self.vtkEvery and (t >= self._nextVtk - slack or (final and files and t > self._lastVtk + slack)):
            self._bridge.writeVtk(O.bodies, t)
            self._lastVtk = t
            while self._nextVtk <= t + slack:
                self._nextVtk += self.vtkEvery

    def _openOutput(self):
        import os
        t = O.time
        h5 = os.path.join(str(self.output), "coupled.h5")
        append = self._appendOutput and os.path.exists(h5)
        if append:
            # records after the checkpoint's time were written by a run that went on past it
            lastRecord, _, lastVtk = _mpmsdem.truncateOutputsAfter(
                h5, os.path.join(str(self.output), "scene.pvd"), t + 1e-9 * self.outputEvery)
            if not math.isnan(lastRecord):
                self._lastRecord = lastRecord
                self._nextRecord = max(t, _nextOnGrid(lastRecord, self.outputEvery))
            if self.vtkEvery and not math.isnan(lastVtk):
                self._lastVtk = lastVtk
                self._nextVtk = max(t, lastVtk + self.vtkEvery)
        self._bridge.openOutput(str(self.output), append)
        self.sdem._outputsOpen = self.sdem._outputsOpen or h5

    def _lastGoodState(self, e):
        note = ""
        self.sdem._fail(e)
        if self.sdem.error and "saved" in self.sdem.error:
            note += self.sdem.error[self.sdem.error.index(" [last good"):]
        if self.mpm.output is not None:
            if self.mpm.solver.holdsLastGoodState:
                self.mpm.solver.writeSnapshot()
                note += " [particles of the last good step: last snapshot in %s]" % self.mpm.output
            else:
                note += " [particles' last good state: the last snapshot in %s]" % self.mpm.output
        return note

    def _dissipated(self):
        e = self._bridge.energies()
        s = self.sdem.energies()
        return e["friction"] + e["damping"] + s["friction"] + s["damping"]

    def _record(self, t):
        ids = self.sdem.ids
        if self.output is not None:
            self._bridge.record(O.bodies, t, O.iter)
            d = self.mpm.diagnostics()
            self._bridge.appendSeries("flow_kinetic", d["kinetic_energy"])
            self._bridge.appendSeries("flow_potential", d["potential_energy"])
            self._bridge.appendSeries("block_kinetic", self.blockKineticEnergy())
            self._bridge.appendSeries("dissipated", self._dissipated())
        if self.plot:
            from yade import plot
            row = {"t": t}
            for k, i in enumerate(ids):
                b = O.bodies[i]
                row["Ft_%d" % i] = self.force(i).norm()
                row["Ff_%d" % i] = self.faceForce(i).norm()
                row["Fe_%d" % i] = self.edgeForce(i).norm()
                row["x_%d" % i] = b.state.pos[0]
                row["vx_%d" % i] = b.state.vel[0]
                q0 = self._ori0.setdefault(i, Quaternion(b.state.ori))
                row["rot_%d" % i] = math.degrees((b.state.ori * q0.conjugate()).toAngleAxis()[0])
            for i in self._levelSets:  # no F_f / F_e: a level set has no faces and edges to tell apart
                b = O.bodies[i]
                row["Ft_%d" % i] = self.force(i).norm()
                row["x_%d" % i] = b.state.pos[0]
                row["vx_%d" % i] = b.state.vel[0]
                q0 = self._ori0.setdefault(i, Quaternion(b.state.ori))
                row["rot_%d" % i] = math.degrees((b.state.ori * q0.conjugate()).toAngleAxis()[0])
            plot.addData(**row)

    def blockKineticEnergy(self):
        """Kinetic energy of the moving blocks (translation and rotation) [J]."""
        e = 0.0
        for i in self.sdem.ids:
            b = O.bodies[i]
            if not b.dynamic:
                continue
            s = b.state
            wb = s.ori.conjugate() * s.angVel
            e += 0.5 * s.mass * s.vel.squaredNorm() + 0.5 * sum(s.inertia[k] * wb[k] ** 2 for k in range(3))
        return e

    # ------------------------------------------------------------------ checkpoint
    def save(self, prefix):
        """Write a checkpoint of the coupled state, to go alongside ``O.save(prefix +
        ".yade.gz")``: ``prefix.sdem.json`` (:meth:`SdemEngine.save`), ``prefix.mpm.h5``
        (:meth:`MpmEngine.save`) and ``prefix.coupled.json`` (flow–block pairs, the MP–block
        tangential histories, dissipations, the flow's impulses on the blocks, each block's
        reference orientation; the same of the
        LevelSet bodies, whose shapes and states ``O.save`` keeps). Continue with
        :meth:`CoupledEngine.restore`; the restart is bit-for-bit (CPU backend). The
        ``.coupled.json`` is written last and names the time of the other two, so a set left
        half-written by a kill is refused at restore rather than mixed."""
        import base64
        import json
        import os
        keys, xi, slots = self._bridge.histories()
        lsKeys, lsXi, _ = self._bridge.levelSetHistories()
        self.sdem.save(prefix + ".sdem.json")
        self.mpm.save(prefix + ".mpm.h5")
        self._bridge.commitOutput()  # a restart from this checkpoint finds coupled.h5 as it is now
        mats = {k: m for m, k in self.sdem._materials}
        data = {"format": "mpmsdem-coupled-2", "time": O.time, "iter": O.iter, "mpmTime": self.mpm.time,
                "mpmSteps": self.mpm.solver.steps, "dtCheck": self.dtCheck, "historySlots": slots,
                "dtAuto": self.dtAuto, "dtMax": self.dtMax, "minStepFraction": self.minStepFraction,
                "maxBlockSpeed": self.maxBlockSpeed,
                # what dtAuto's next step reads (None: not known yet; a string keeps inf JSON-clean)
                "contactStep": repr(self._bridge.contactStep) if self._contactsKnown else None,
                "particleApproachStep": repr(self._bridge.particleApproachStep) if self._contactsKnown else None,
                "pairs": [{"material": _matDict(mats[k]), "pair": p} for k, p in sorted(self._pairs.items())],
                "historyKeys": base64.b64encode(keys).decode(), "historyXi": base64.b64encode(xi).decode(),
                "dissipation": list(self._bridge.blockDissipation()),
                "impulse": list(self._bridge.blockImpulses()),
                # when the flow first touched each body; None before it or where not kept (the
                # impulse tells the two apart at the restore)
                "firstContact": _timesOrNone(self._bridge.blockFirstContacts()),
                "levelSets": [{"id": bid, "pair": self._levelSetPairs[bid]} for bid in self._levelSets],
                "levelSetHistoryKeys": base64.b64encode(lsKeys).decode(),
                "levelSetHistoryXi": base64.b64encode(lsXi).decode(),
                "levelSetDissipation": list(self._bridge.levelSetDissipation()),
                "levelSetImpulse": list(self._bridge.levelSetImpulses()),
                "levelSetFirstContact": _timesOrNone(self._bridge.levelSetFirstContacts()),
                "referenceOrientations": [list(q) for q in self._bridge.referenceOrientations()],
                "plotOrientations": {str(i): [q[k] for k in range(4)] for i, q in self._ori0.items()},
                # before the first step coupled.h5 is not open yet (unless restored onto one): a
                # restore then starts it afresh, whatever a killed run left of it (none of it is
                # this checkpoint's)
                "outputOpen": self._started or self._appendOutput}
        tmp = prefix + ".coupled.json.tmp"
        with open(tmp, "w") as f:
            json.dump(data, f)
        os.replace(tmp, prefix + ".coupled.json")

    @classmethod
    def restore(cls, prefix, output=None, outputEvery=None, vtkEvery=None, plot=False, appendOutput=True,
                sdemKw=None, mpmKw=None, **kw):
        """A coupled engine continuing from :meth:`save` after ``O.load(prefix + ".yade.gz")``:
        the SDEM engine, the MPM engine and the coupling state are rebuilt; put its ``runner``
        in ``O.engines`` in place of the loaded one. ``output``/``outputEvery``/``vtkEvery``/
        ``plot`` as in the constructor; with ``output`` the files there are continued
        (``appendOutput``), records later than the checkpoint dropped first. ``sdemKw`` and
        ``mpmKw`` go to :meth:`SdemEngine.restore` and :meth:`MpmEngine.restore` (their own
        outputs, for instance). LevelSet bodies and their contact physics come from the
        checkpoint (the bodies themselves from ``O.load``)."""
        import base64
        import json
        from .mpm import MpmEngine
        from .sdem import SdemEngine
        if "levelSets" in kw:
            raise ValueError("restore(%r): levelSets come from the checkpoint (the run goes on with the bodies and "
                             "contact physics it was saved with)" % (prefix,))
        with open(prefix + ".coupled.json") as f:
            data = json.load(f)
        if data.get("format") == "mpmsdem-coupled-1":
            # Format 1 stored the tangential history as a displacement [m]; it is now the elastic
            # tangential force [N], so the old values cannot be reinterpreted.
            raise ValueError("prefix = %r: %s.coupled.json is an mpmsdem-coupled-1 checkpoint, whose tangential "
                             "histories are displacements; this version stores elastic tangential forces and "
                             "cannot restore it: run the scene again from the start" % (prefix, prefix))
        if data.get("format") != "mpmsdem-coupled-2":
            raise ValueError("prefix = %r: %s.coupled.json is not an mpmsdem coupled checkpoint" % (prefix, prefix))
        with open(prefix + ".sdem.json") as f:
            sdemTime = json.load(f).get("time")
        sdemKw = dict(sdemKw or {}, verbose=kw.get("verbose", True))
        sdem = SdemEngine.restore(prefix + ".sdem.json", **sdemKw)
        mpm = MpmEngine.restore(prefix + ".mpm.h5", **dict(mpmKw or {}, verbose=kw.get("verbose", True)))
        if sdemTime != data["time"] or mpm.solver.steps != data["mpmSteps"] or mpm.time != data["mpmTime"]:
            raise ValueError("prefix = %r: the checkpoint's files are from different times (sdem %r s, mpm %r s, "
                             "coupled %r s): a save was interrupted; restart from an earlier checkpoint"
                             % (prefix, sdemTime, mpm.time, data["time"]))
        if abs(O.time - data["time"]) > 1e-9 * max(abs(data["time"]), 1e-300) or O.iter != data["iter"]:
            raise ValueError("prefix = %r: O.time = %r s, O.iter = %d, but the checkpoint is at t = %r s, step %d: "
                             "O.load(%r) first" % (prefix, O.time, O.iter, data["time"], data["iter"],
                                                   prefix + ".yade.gz"))
        mats = {json.dumps(_matDict(m), sort_keys=True): m for m, k in sdem._materials}
        pairs = {}
        for entry in data["pairs"]:
            key = json.dumps(entry["material"], sort_keys=True)
            mat = mats.get(key) or mats.setdefault(key, _material(entry["material"]))
            pairs[mat] = entry["pair"]
        eng = cls(sdem, mpm, pairs, dtCheck=kw.pop("dtCheck", data["dtCheck"]),
                  dtAuto=kw.pop("dtAuto", data.get("dtAuto")), dtMax=kw.pop("dtMax", data.get("dtMax")),
                  minStepFraction=kw.pop("minStepFraction", data.get("minStepFraction", 1e-4)),
                  maxBlockSpeed=kw.pop("maxBlockSpeed", data.get("maxBlockSpeed")),
                  historySlots=data["historySlots"], output=output, outputEvery=outputEvery, vtkEvery=vtkEvery,
                  plot=plot, levelSets={e["id"]: e["pair"] for e in data.get("levelSets", [])} or None, **kw)
        if data.get("contactStep") is not None:  # the first step's dtAuto sees what it would have seen
            eng._contactsKnown = True
            eng._restoredContactStep = float(data["contactStep"])
            if data.get("particleApproachStep") is not None:
                eng._bridge.particleApproachStep = float(data["particleApproachStep"])
        eng._bridge.setHistories(base64.b64decode(data["historyKeys"]), base64.b64decode(data["historyXi"]))
        eng._bridge.setDissipation(*data["dissipation"])
        # (a checkpoint written before the impulses were kept has none: they count from here)
        eng._bridge.setImpulses(data.get("impulse", []))
        # (nor the first contacts: a body the impulse says was touched keeps none, and without the
        # impulses no body gets one)
        eng._bridge.setFirstContacts(_timesOrNan(data.get("firstContact", [])), "impulse" in data)
        if data.get("levelSets"):
            eng._bridge.setLevelSetHistories(base64.b64decode(data["levelSetHistoryKeys"]),
                                             base64.b64decode(data["levelSetHistoryXi"]))
            eng._bridge.setLevelSetDissipation(*data["levelSetDissipation"])
            eng._bridge.setLevelSetImpulses(data.get("levelSetImpulse", []))
            eng._bridge.setLevelSetFirstContacts(_timesOrNan(data.get("levelSetFirstContact", [])),
                                                 "levelSetImpulse" in data)
        eng._bridge.setReferenceOrientations(data["referenceOrientations"])
        eng._ori0 = {int(i): Quaternion(*q) for i, q in data["plotOrientations"].items()}
        eng._appendOutput = bool(appendOutput) and data.get("outputOpen", True)
        return eng

    def finish(self, files=True):
        """Record the state the run has reached: a ``coupled.h5`` record at the current time
        unless one was taken there, a ``scene.pvd`` entry when one is due (with ``files``: in
        any case), and the SDEM and
        MPM engines' final records (:meth:`SdemEngine.finish`, :meth:`MpmEngine.finish`).
        ``mpmsdem.run`` calls it after each run."""
        if self._started:
            self._recordDue(self.mpm.time, final=True, files=files)
        self.sdem.finish(vtk=files)
        self.mpm.finish(snapshot=files)

    # ------------------------------------------------------------------ read-out (last step)
    def _index(self, yadeId):
        self.sdem.shape(yadeId)  # ValueError for a non-SDEM id
        return self.sdem._index[yadeId]

    def force(self, yadeId):
        """Force of the flow on a block or LevelSet body in the last step, F_t [N] (world frame)."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetForce(self._levelSets[yadeId]) if self._contactsKnown else Vector3.Zero
        return self._bridge.force(self._index(yadeId))

    def torque(self, yadeId):
        """Torque of the flow on a block about its centroid, or on a LevelSet body about its
        ``state.pos`` [N m]."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetTorque(self._levelSets[yadeId]) if self._contactsKnown else Vector3.Zero
        return self._bridge.torque(self._index(yadeId))

    def impulse(self, yadeId):
        """Impulse of the flow on a block or LevelSet body since the run's start [N s] (world
        frame): every step's force times its dt, summed. Its change between two times over the
        interval is the mean force between them, which no single step's :meth:`force` gives."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetImpulse(self._levelSets[yadeId]) if self._contactsKnown else Vector3.Zero
        return self._bridge.impulse(self._index(yadeId))

    def firstContact(self, yadeId):
        """When the flow first touched a block or LevelSet body [s]: the start of the first step
        whose flow force on it was not zero, the state its contacts were found in; NaN before it,
        or where a restart from an older checkpoint did not keep it. A record holds one step's
        force at each record, so the first record with a force places the touch only within its
        interval; a first blow's windows start here."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetFirstContact(self._levelSets[yadeId]) if self._contactsKnown else math.nan
        return self._bridge.firstContact(self._index(yadeId))

    def angularImpulse(self, yadeId):
        """The same of the torque (:meth:`torque`) [N m s]."""
        if yadeId in self._levelSets:
            return (self._bridge.levelSetAngularImpulse(self._levelSets[yadeId]) if self._contactsKnown
                    else Vector3.Zero)
        return self._bridge.angularImpulse(self._index(yadeId))

    def faceForce(self, yadeId):
        """Share of F_t through the block's face interiors, F_f [N] (paper §3.2.3)."""
        return self._bridge.faceForce(self._index(yadeId))

    def edgeForce(self, yadeId):
        """Share of F_t through the block's edges and vertices, F_e [N]."""
        return self._bridge.edgeForce(self._index(yadeId))

    def contactCount(self, yadeId):
        """Number of material points touching the block or LevelSet body."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetContactCount(self._levelSets[yadeId]) if self._contactsKnown else 0
        return self._bridge.contactCount(self._index(yadeId))

    def contacts(self, yadeId=None):
        """The material point–block contacts of the last step (of block ``yadeId``, or of every
        block: None), one row per contact, as numpy
        arrays: ``particle`` (the point's number, its row in ``mpm.particles()``), ``block``
        (YADE body id), ``point`` (n×3, midway between the two sphere surfaces) [m], ``normal``
        (n×3, unit, from the block towards the point), ``force`` (n×3, the flow's force on the
        block through the contact; the point takes the opposite) [N], ``normalForce`` (F_n of
        Eq 10) [N], ``overlap`` (δ of Eq 12) [m], ``feature`` (list: 'face', 'edge' or 'vertex',
        the block's core feature nearest the point; 'face' rows make :meth:`faceForce`). Summed
        per block they give :meth:`force` and :meth:`torque`; where on a block the flow pressed
        is their ``point`` (paper §3.2.3). On CUDA a step's contacts stay on the device unless
        :attr:`recordContacts` was set before it (RuntimeError otherwise). Empty before the
        first step. For a LevelSet body's id: its contacts, without ``feature`` (``point`` midway
        between the body's surface and the point's sphere, ``normal`` the normalised gradient of
        the body's interpolated distance field)."""
        if yadeId in self._levelSets:
            return self._bridge.levelSetContacts(self._levelSets[yadeId])
        return self._bridge.contacts(-1 if yadeId is None else self._index(yadeId))

    @property
    def recordContacts(self):
        """CUDA backend: keep each step's point–block contacts on the device (120 B per
        contact) so that :meth:`contacts` and the ParaView contacts can read them (on from the
        next step; default: on with ``vtkEvery``, else off). The CPU backend always has them."""
        return self._bridge.recordContacts

    @recordContacts.setter
    def recordContacts(self, on):
        self._bridge.recordContacts = bool(on)

    @property
    def totalContacts(self):
        return self._bridge.totalContacts

    @property
    def timeStepWarnings(self):
        return self._bridge.timeStepWarnings

    @property
    def historyOverflow(self):
        """MP–block contacts that found no free history slot so far (see historySlots)."""
        return self._bridge.historyOverflow

    def energies(self):
        """MP–block contact energies [J]: current barrier and tangential potentials, cumulative
        slip and dashpot work."""
        return dict(self._bridge.energies())

    def timings(self):
        """Wall time since the last reset [s]: steps, coupling (MP–block contacts), mpm (the MPM
        step); the SDEM bridge's share is in ``sdem.timings()``."""
        return dict(self._bridge.timings())

    def resetTimings(self):
        self._bridge.resetTimings()
        self.sdem.resetTimings()
