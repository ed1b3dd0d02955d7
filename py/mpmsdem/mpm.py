"""The MPM granular-flow solver inside YADE's loop (or stepped directly from Python).

The scene uses the same schema as the plain C++ driver ``mpmsdem-run`` (see
``examples/scenes/README.md``): a grid box with six walls, a μ(I) granular material, boxes of
material points. Example, an MPM-only YADE script::

    import mpmsdem
    from yade import O
    mpm = mpmsdem.MpmEngine(
        grid={"dx": 0.01, "cells": [54, 9, 34], "origin": [-0.02, -0.02, -0.02]},
        material={"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.38, "mu_2": 0.64},
        particles=[{"lo": [0, 0, 0], "hi": [0.1, 0.05, 0.2], "ppc": 8}],
        walls={"-z": 0.4}, output="out/collapse", outputEvery=0.02)
    O.engines = [mpm.runner]
    O.dt = 0.9 * mpm.stableTimeStep()
    O.run(int(0.6 / O.dt), True)
    mpm.check()
"""
import json
import math

from yade import O

from . import _mpmsdem
from .engine import Engine
from .parameters import pythonNames

# The scene's top-level keys by their keywords here (mpmsdem.parameters): "flip_viscosity" for
# flipViscosity, ...
_SCENE_KEYS = pythonNames("")


# The step of the paper's coupled runs (§3.1, Appendix D) [s]: with flipReferenceDt=PAPER_STEP the
# flow is blended as the paper blends it, alpha 0.99 once per 5e-6 s (2010 /s of PIC damping).
PAPER_STEP = 5e-6
# The paper's blend as a PIC viscosity [m²/s]: the share 1 − 0.99 = 0.01 handed to PIC per 5e-6 s
# at its dx 0.01 m, times dx²/(4 Δt): 0.05. With flipViscosity=PAPER_VISCOSITY a scene at any dx
# and step has the flow of the paper's numerics (docs/physics.md, "The blend as a viscosity").
PAPER_VISCOSITY = 0.01 * 0.01 ** 2 / (4.0 * PAPER_STEP)


def flipReferenceArg(text):
    """argparse type of a ``--flip-reference-dt`` option: a reference step [s] > 0, or ``step``
    (the blend per step, Eq 4 as written)."""
    if text == "step":
        return "step"
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (v > 0 and math.isfinite(v)):
        raise ValueError("--flip-reference-dt %r: must be a step [s] > 0 or 'step'" % text)
    return v


class MpmEngine(Engine):
    """Explicit MPM with the μ(I) granular model (paper §2.1, Appendices A–B).

    :param grid: ``{"dx": [m], "cells": [nx, ny, nz], "origin": [x, y, z] [m]}``.
    :param material: ``{"density", "young_modulus", "poisson_ratio", "mu_s", "mu_2", "I0",
        "grain_diameter", "solid_density", "critical_density"}`` (SI; see the schema).
    :param particles: list of ``{"lo", "hi", "ppc", "velocity"}`` boxes of material points; an
        empty list is a scene without flow (a coupled scene whose blocks move alone, at no MPM
        cost).
    :param gravity: ``[gx, gy, gz]`` [m/s²] or ``{"g": 9.81, "incline_deg": θ}`` (flume
        inclined about y, flowing toward +x: gravity is rotated, not the grid).
    :param walls: per wall ``"-x"``…``"+z"``: ``"free"``, ``"noslip"`` or a friction μ_w ≥ 0.
    :param gate: a release gate (``pkg/mpm/Gate.hpp``), a plane normal to x holding the material
        upstream of it above its lower edge, which is lifted along z (the bed normal in a flume):
        ``{"x": plane [m] (required, inside the wall layers), "bottom": edge height z_0 until
        open_at [m] (default 0), "speed": lift speed [m/s] ≥ 0 (default 0; 0 or ``math.inf``:
        removed at once at open_at), "open_at": t_open [s] ≥ 0 (default 0), "friction":
        material–gate Coulomb μ ≥ 0 (default 0)}``; edge height z_0 + speed·max(0, t − t_open).
        It acts on the grid before the walls; ``solver.gateImpulse()`` is the impulse it has
        given the flow [N s]. None (default): no gate.
    :param flipViscosity: PIC viscosity ν of the FLIP/PIC blend of Eq 4 [m²/s] > 0: a step of
        length Δt hands PIC the share 4 ν Δt/Δx² and keeps the rest of FLIP (the stable step is
        at most Δx²/(4ν)). The PIC part smooths the velocity by (Δx²/4) ∇²v, so a blend per unit
        time acts as a viscosity that grows with Δx²; ν keeps the flow when the step or the grid
        changes. None (default, with no ``flipReferenceDt``):
        the scene default, 0.005 m²/s (200 /s at Δx 0.01 m; ``mpm::FlipBlend::kDefaultViscosity``, chosen
        against the column collapse of Lube et al.); :data:`PAPER_VISCOSITY` (0.05 m²/s): the
        paper's blend, α 0.99 once per its 5e-6 s step at its Δx 0.01 m (§3.1, Appendix D).
    :param flipAlpha, flipReferenceDt: instead of ``flipViscosity``: α in [0, 1] (Table 1: 0.99;
        default 0.99) kept per Δt_ref [s] > 0 of simulated time (the same damping per second at
        any step, not at any Δx; :data:`PAPER_STEP`, 5e-6 s: the paper's blend), or
        ``flipReferenceDt="step"``: α per step, Eq 4 as written (the damping per second then
        grows as the step shrinks). ``flipAlpha`` needs ``flipReferenceDt``.
        ``solver.flipBlend`` names the blend in force, ``solver.flipViscosity(dt)`` and
        ``solver.flipDampingRate(dt)`` give it as numbers; docs/physics.md.
    :param terrain: a :class:`mpmsdem.terrain.Terrain` (a raster height field in the grid frame,
        with its flow–terrain friction) the flow cannot enter, or its scene entry as a dict
        (``{"file", "origin", "friction"}`` or ``{"nx", "ny", "x0", "y0", "spacing", "heights",
        "friction"}``); the boxes of ``particles`` are seeded only above its surface. None
        (default): no terrain.
    :param cfl: CFL number of :meth:`stableTimeStep`, in (0, 1].
    :param keepLastGoodState: True (default): the solver keeps a second copy of the particles,
        so that a step that fails (NaN, blow-up) leaves them as they were at its start, and they
        are saved as the last snapshot. False: one copy, 125 B per particle less in double and 65
        in float (CPU; CUDA keeps the copy), the same results to the last bit; a failed step
        then leaves the particles partly advanced, and the last good state is the last snapshot
        written before it.
    :param backend: ``"cpu"`` (OpenMP) or ``"cuda"``; :param precision: ``"double"``
        or ``"float"``, on either backend.
    :param output: folder for ``mpm.h5`` (append-only HDF5 series + snapshots) and VTK
        files (``particles.pvd`` for ParaView); None: no files.
    :param outputEvery: snapshot interval [s] (with ``output``).
    :param label: label of the PyRunner for ``O.engines``.
    :param verbose: add the flow's fields (its CFL step, particle-updates/s) to the scene's
        progress line on stderr, every 10 s of wall time (with time, step, ``O.dt`` and wall time
        per step; :mod:`mpmsdem.engine`).
    """

    def __init__(self, grid, material, particles, gravity=(0, 0, -9.81), walls=None, flipAlpha=None, cfl=0.3,
                 backend="cpu", precision="double", output=None, outputEvery=None, label="mpm", verbose=True,
                 gate=None, flipReferenceDt=None, keepLastGoodState=True, flipViscosity=None, terrain=None):
        scene = {"grid": grid, "material": material, "particles": list(particles),
                 "gravity": list(gravity) if not isinstance(gravity, dict) else gravity,
                 "cfl": cfl, "keep_last_good_state": keepLastGoodState,
                 "run": {"duration": 1.0, "backend": backend, "precision": precision}}
        for name, value in (("flipViscosity", flipViscosity), ("flipAlpha", flipAlpha),
                            ("flipReferenceDt", flipReferenceDt)):
            if value is not None:
                scene[_SCENE_KEYS[name]] = value
        if walls:
            scene["walls"] = walls
        if gate is not None:
            if not isinstance(gate, dict):
                raise ValueError("gate = %r: must be a dict {x, bottom, speed, open_at, friction}" % (gate,))
            scene["gate"] = dict(gate)
            if scene["gate"].get("speed") == math.inf:  # JSON has no infinity; 0 means the same
                scene["gate"]["speed"] = 0
        if terrain is not None:
            if hasattr(terrain, "scene"):
                scene["terrain"] = terrain.scene()
            elif isinstance(terrain, dict):
                scene["terrain"] = dict(terrain)
            else:
                raise ValueError("terrain = %r: must be an mpmsdem.terrain.Terrain or a scene entry dict" % (terrain,))
        self._setup(json.dumps(_plain(scene, ""), allow_nan=False), output, outputEvery, label, verbose)

    def _setup(self, sceneJson, output, outputEvery, label, verbose):
        self.solver = _mpmsdem.MpmSolver(sceneJson)
        self.output = None
        self._lastSeriesStep = self._lastSnapshotStep = None
        self.verbose = verbose
        self.seriesPeriod = 10  # steps between time-series records (time, kinetic energy, front)
        self.error = None
        if output is not None:
            self._openOutput(output, outputEvery, append=False)
        self._bindRunner("mpm", label)

    def _openOutput(self, output, outputEvery, append):
        if not (outputEvery and outputEvery > 0):
            raise ValueError("outputEvery = %r s: must be > 0 when output is set" % (outputEvery,))
        import os
        t = self.solver.time
        h5 = os.path.join(str(output), "mpm.h5")
        append = append and os.path.exists(h5)
        if append:
            # records and snapshots after t were written by a run that went on past the
            # checkpoint we restart from: dropped, so the files never repeat or go back in time
            _mpmsdem.truncateOutputsAfter(h5, os.path.join(str(output), "particles.pvd"), t)
        self.solver.openOutput(str(output), bool(append))
        self.output, self.outputEvery = output, outputEvery
        self._lastSeriesStep = self._lastSnapshotStep = None
        if append:  # the state at t is the checkpoint's, already in the file
            self._lastSeriesStep = self._lastSnapshotStep = self.solver.steps
            self._nextOutput = (int(t / outputEvery + 1e-9) + 1) * outputEvery
        else:  # snapshot 0 and the first record hold the initial state, before step 1
            self._recordSeries(0.0)
            self._writeSnapshot()
            self._nextOutput = t + outputEvery

    def _recordSeries(self, dt):
        d = self.solver.diagnostics()
        self.solver.appendSeries("time", self.solver.time)
        self.solver.appendSeries("step", float(self.solver.steps))
        self.solver.appendSeries("dt", float(dt))
        for name in SERIES[3:]:
            if name == "centre_of_mass":
                self.solver.appendVector(name, d[name])
            else:
                self.solver.appendSeries(name, d[name])
        self._lastSeriesStep = self.solver.steps

    def _writeSnapshot(self):
        self.solver.writeSnapshot()
        self._lastSnapshotStep = self.solver.steps

    # ------------------------------------------------------------------ stepping
    def stableTimeStep(self):
        """cfl · dx / (elastic wave speed + max particle speed) [s]."""
        return self.solver.stableTimeStep()

    def step(self, dt):
        """One MPM step of ``dt`` seconds, then outputs if due."""
        self._stepping(self.solver.time, self.solver.steps, float(dt))
        self._advance(float(dt))

    def _advance(self, dt):
        self.solver.step(dt)
        self._afterStep(dt)

    def _step(self):
        self._stepping(O.time, O.iter, O.dt)
        try:
            self._advance(float(O.dt))
        except Exception as e:
            self._fail(e)
            raise

    def _lastGoodState(self, e):
        """Save the last good state after a failed step, if the solver kept it, and say where it is."""
        if self.output is None:
            return ""
        if not self.solver.holdsLastGoodState:
            return " [last good state: the last snapshot in %s]" % self.output
        if self._lastSnapshotStep != self.solver.steps:  # not written already by the last step's outputs
            self._writeSnapshot()
        return " [last good state saved as the last snapshot in %s]" % self.output

    def _afterStep(self, dt):
        t = self.solver.time
        if self.output is not None:
            if self.solver.steps % self.seriesPeriod == 0 and self._lastSeriesStep != self.solver.steps:
                self._recordSeries(dt)
            # half a step of slack: t is a sum of steps and may fall a rounding error short
            if t >= self._nextOutput - 0.5 * dt:
                if self._lastSnapshotStep != self.solver.steps:
                    self._writeSnapshot()
                while self._nextOutput <= t + 0.5 * dt:
                    self._nextOutput += self.outputEvery

    # the flow needs no other engine and no order
    _name, _runnerName = "MpmEngine", "mpm.runner"
    _missing = ("O.engines does not hold this MpmEngine's runner: put it there (O.engines = [mpm.runner], or next "
                "to other engines), else the flow does not move")

    def _progressFields(self, perStep):
        return "the flow's CFL step %.3g s, %.3g particle-updates/s" % (self.solver.stableTimeStep(),
                                                                       self.solver.numParticles / max(perStep, 1e-12))

    def finish(self, snapshot=True):
        """Record the current state in the series of ``mpm.h5`` and, with ``snapshot``, as a
        snapshot (and ParaView file), unless this step has them: the outputs of a run then end
        with its final state. :func:`mpmsdem.run` calls ``finish(snapshot=False)`` after each
        run; call it after a plain ``O.run`` yourself."""
        if self.output is None:
            return
        if self._lastSeriesStep != self.solver.steps:
            self._recordSeries(O.dt if O.dt > 0 else 0.0)
        if snapshot and self._lastSnapshotStep != self.solver.steps:
            self._writeSnapshot()

    # ------------------------------------------------------------------ checkpoint
    def save(self, path):
        """Write a checkpoint (HDF5: the scene and every particle's state at this time), to go
        alongside ``O.save()``; continue with :meth:`MpmEngine.restore`. Written to a temporary
        name and renamed, so a killed run never leaves a half-written checkpoint."""
        self.solver.saveCheckpoint(str(path))

    @classmethod
    def restore(cls, path, output=None, outputEvery=None, label="mpm", verbose=True, appendOutput=True):
        """An engine continuing from a checkpoint of :meth:`save` (or from the last snapshot of
        an ``mpm.h5``): same scene, particles, time and step count. With ``output``, outputs
        are appended to the files already in that folder (``appendOutput``). Put its
        ``runner`` into ``O.engines``."""
        eng = cls.__new__(cls)
        eng._setup(_mpmsdem.sceneOf(str(path)), None, None, label, verbose)
        eng.solver.loadSnapshot(str(path), -1)
        if output is not None:
            eng._openOutput(output, outputEvery, append=appendOutput)
        return eng

    # ------------------------------------------------------------------ read-out
    def particles(self):
        """Particle arrays (numpy): x, v (n×3), stress (n×6: xx yy zz yz xz xy, tension > 0)
        [Pa], mass [kg], volume0 [m³], J, density [kg/m³], gammaDotP [1/s], phase
        (0 elastic, 1 flowing, 2 gasified)."""
        return self.solver.particles()

    def kineticEnergy(self):
        """Total kinetic energy of the material points [J]."""
        return self.solver.diagnostics()["kinetic_energy"]

    def diagnostics(self):
        """Whole-system diagnostics of the current state, a dict: kinetic_energy and
        potential_energy [J] (zero height at the origin), front_x and height_z [m] (NaN without
        particles), centre_of_mass [m], max_speed [m/s], flowing_fraction and gasified_fraction
        (the series of mpm.h5 record these)."""
        return self.solver.diagnostics()

    @property
    def time(self):
        return self.solver.time

    @property
    def gravity(self):
        """Gravity acting on the flow [m/s²], as a tuple (an inclined flume's resolved)."""
        return tuple(self.solver.gravity)

    @property
    def numParticles(self):
        return self.solver.numParticles

    def front(self, axis=0):
        """Position of the flow front: the largest particle coordinate along ``axis`` [m]; NaN
        without particles."""
        x = self.solver.particles()["x"]
        return float(x[:, axis].max()) if len(x) else float("nan")


# The /series of mpm.h5, the same as the driver mpmsdem-run writes (docs/outputs.md).
SERIES = ("time", "step", "dt", "kinetic_energy", "front_x", "height_z", "centre_of_mass", "max_speed",
          "flowing_fraction", "gasified_fraction")


def _plain(obj, path):
    """The scene as plain JSON values: numpy arrays and scalars (and YADE vectors) become lists
    and numbers; a NaN or infinite number is a ValueError naming its key path (JSON has no
    such numbers: the C++ parser would report only a column)."""
    if isinstance(obj, dict):
        return {k: _plain(v, "%s.%s" % (path, k) if path else str(k)) for k, v in obj.items()}
    if isinstance(obj, (str, bool)) or obj is None:
        return obj
    if hasattr(obj, "tolist") and not isinstance(obj, (int, float)):  # numpy array or scalar
        return _plain(obj.tolist(), path)
    if isinstance(obj, (list, tuple)) or (hasattr(obj, "__len__") and hasattr(obj, "__getitem__")):
        return [_plain(obj[i], "%s[%d]" % (path, i)) for i in range(len(obj))]
    if isinstance(obj, int):
        return obj
    try:
        x = float(obj)
    except (TypeError, ValueError):
        raise ValueError("%s = %r: must be a number, a list, a string or a dict (the scene schema of "
                         "examples/scenes/README.md)" % (path, obj)) from None
    if not math.isfinite(x):
        raise ValueError("%s = %r: must be a finite number" % (path, obj))
    return x
