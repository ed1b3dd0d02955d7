"""Inclined-flume scenes of the paper (§3.2, §3.3, §5): a granular column released in a flume
with an SDEM bed and blocks downstream, coupled every step.

Coordinates follow the flume: x downstream along the bed, y across, z normal to the bed (the
bed surface is z = 0); gravity is rotated by the incline, not the grid. The column occupies
0 ≤ x ≤ columnLength, full width, with the grid's −x wall behind it. By default it starts free
at t = 0; with ``gate`` a release gate at x = columnLength holds it until ``open_at`` and is
then lifted, as in the experiments. Side walls are grid walls; the bed is a fixed SDEM slab, so
the flow–bed friction is the coupling pair of the bed material and blocks rest on it through
SDEM contacts.

    scene = mpmsdem.flume.Flume(dx=0.02, blocks=[mpmsdem.flume.Block(half=(0.01,) * 3, x=0.51)])
    scene.run(1.5)
    print(scene.travel(0), scene.peakForce(0, smooth=0.01))
"""
import math
import os

from yade import O
from yade.minieigenHP import Vector3
from yade import utils
from yade.wrapper import (Bo1_LevelSet_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_LevelSet_LevelSet_ScGeom,
                          Ig2_Wall_LevelSet_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                          Law2_ScGeom_FrictPhys_CundallStrack, MatchMaker, NewtonIntegrator)

from . import analysis
from .analysis import tiltAndYaw
from .coupling import CoupledEngine
from .mpm import MpmEngine
from .sdem import SdemEngine
from . import material as _material

# Glass beads of Table 1 (paper §3.2).
GLASS_BEADS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65,
               "I0": 0.279, "grain_diameter": 0.002, "solid_density": 2500}

# The §3.2 flow and friction settings by name, keyed as examples/flume_block.py's options:
# basal (flow–bed) friction, the flow's μ₂, flow–cube friction, flow–side wall friction, and the
# PIC viscosity of the FLIP/PIC blend [m²/s] (None: the paper's, α 0.99 per its 5e-6 s step).
# - "table1": Table 1 (basal 0.21, μ₂ 0.65); flow–cube 0.21 and smooth side walls are our reading.
# - "joint": lhs02 of the joint design at the paper's resolution (dx 0.01 m;
#   scripts/validation/paper_flume_design.py --lhs 20, docs/coupled-results.md "Joint
#   calibration"): PIC viscosity 0.0347 m²/s (1388 /s at dx 0.01 m; the fit ran with a blend
#   that kept exp(−4νΔt/Δx²) of FLIP, 0.0360 m²/s at the flume's step 5.17e-5 s, the same share
#   per step), basal 0.28, μ₂ 0.72, flow–cube 0.39, side walls 0.11. The cube is pushed and turns through 45° near the paper's 0.72 s without
#   tumbling; its force plateau stays above the paper's.
FLUME_SETTINGS = {
    "table1": {"basal_friction": 0.21, "mu_2": 0.65, "flow_friction": 0.21, "side_wall_friction": 0.0,
               "flip_viscosity": None},
    "joint": {"basal_friction": 0.2778, "mu_2": 0.7221, "flow_friction": 0.3938, "side_wall_friction": 0.111,
              "flip_viscosity": 0.0347053},
}


class Block:
    """A box-shaped block standing on the bed.

    :param half: outer half-extents (along the flume, across, normal to the bed) [m].
    :param x: position of its upstream face along the flume [m]; :param y: centre across the
        flume [m] (None: the centre line); :param z: height of its bottom face above the bed
        [m] (0: resting on it; stacked blocks give the top of the one below).
    :param sweepRadius: R [m] (None: h/20 of the smallest side, the paper's ratio).
    :param density: [kg/m³]; :param friction: block–bed and block–block friction;
        :param flowFriction: flow–block friction (coupling pair).
    :param blockedDOFs: YADE's blockedDOFs string, e.g. ``"xyzXYZ"`` for a glued block.
    :param levelSet: None (default): an SDEM sphero-box; or ``{"spacing": h [m] > 0,
        "nSurfNodes": n ≥ 8}``: a YADE ``LevelSet`` box of the outer size ``half``
        (``yade.utils.levelSetBody("box", ...)``, grid spacing h, default a fifth of the
        smallest half-extent, n boundary nodes, default 602; sweepRadius unused), in the flow through ``CoupledEngine(levelSets=...)`` with ``flowFriction`` and
        ``barrierStiffness``, and against the other LevelSet blocks and the bed through YADE's
        own contacts (:class:`Flume`'s ``levelSetContact``). On a CUDA flow not yet run on a GPU
        (docs/coupling.md).
    """

    def __init__(self, half, x, y=None, z=0.0, sweepRadius=None, density=8900, friction=0.67, flowFriction=0.21,
                 blockedDOFs="", barrierStiffness=1e4, levelSet=None):
        self.half = tuple(float(h) for h in half)
        if len(self.half) != 3 or min(self.half) <= 0:
            raise ValueError("half = %r: must be three half-extents > 0 [m]" % (half,))
        self.x, self.y, self.z = float(x), y, float(z)
        self.sweepRadius = sweepRadius if sweepRadius is not None else min(self.half) / 10.0
        self.density, self.friction, self.flowFriction = density, friction, flowFriction
        self.blockedDOFs, self.barrierStiffness = blockedDOFs, barrierStiffness
        if levelSet is not None:
            if not isinstance(levelSet, dict) or set(levelSet) - {"spacing", "nSurfNodes"}:
                raise ValueError("levelSet = %r: must be None or a dict with keys among spacing [m], nSurfNodes"
                                 % (levelSet,))
            levelSet = {"spacing": float(levelSet.get("spacing", min(self.half) / 5.0)),
                        "nSurfNodes": int(levelSet.get("nSurfNodes", 602))}
            if not levelSet["spacing"] > 0:
                raise ValueError("levelSet spacing = %r m: must be > 0" % (levelSet["spacing"],))
            if levelSet["nSurfNodes"] < 8:
                raise ValueError("levelSet nSurfNodes = %r: must be >= 8" % (levelSet["nSurfNodes"],))
        self.levelSet = levelSet


class Flume:
    """Build the coupled scene in YADE (O.reset() first) and run it.

    :param length: flume length [m] (paper §3.2: 1.8); :param width: [m] (0.2);
    :param inclineDeg: incline [deg] (10); :param columnLength, columnHeight: L_i, H_i [m];
    :param dx: grid spacing [m] (paper 0.01); :param ppc: material points per cell (8);
    :param granular: MPM material dict (default: the glass beads of Table 1);
    :param basalFriction: flow–bed friction (0.21, Table 1); :param sideWallFriction: flow–wall
        friction of the grid side walls (0: smooth);
    :param blocks: list of :class:`Block`; :param bedSweep: R of the bed slab [m];
    :param dtFactor: O.dt = dtFactor × the MPM CFL step at the start (the contact step is
        checked every step by the coupled engine);
    :param dtAuto: None (default: O.dt stays as set), or f in (0, 1]: the coupled engine sets
        O.dt every step (see :class:`CoupledEngine`'s ``dtAuto``);
    :param dtCheck: ``"raise"`` (default) or ``"warn"``: what a step above the critical step
        of the contacts does, in the SDEM and the coupled engine;
    :param gate: release gate on the column's downstream face (x = columnLength), its lower
        edge on the bed until ``open_at`` and then lifted normal to the bed:
        ``{"speed": lift speed [m/s] ≥ 0 (0 or math.inf: removed at once; default 0),
        "open_at": t_open [s] ≥ 0 (default 0), "friction": material–gate Coulomb μ ≥ 0
        (default 0: smooth)}``. The column settles behind it until t_open; no material above
        the edge passes it (the grid resolves the edge: the opening the flow sees lags the
        edge by about 1.5 dx). None (default): no gate, the column starts free at t = 0.
    :param flipViscosity: PIC viscosity of the flow's FLIP/PIC blend [m²/s] > 0, None (the
        scene default, 0.005 m²/s: 200 /s at dx 0.01 m) or ``mpmsdem.mpm.PAPER_VISCOSITY`` (the
        paper's blend, 0.05 m²/s: the paper's examples use it); :param flipAlpha,
        flipReferenceDt: instead, α per Δt_ref [s] (``mpmsdem.mpm.PAPER_STEP``: the paper's
        α 0.99 per 5e-6 s) or per ``"step"``; see :class:`MpmEngine`. ``flipBlend()`` names the
        blend a run used;
    :param levelSetContact: YADE's contacts of the LevelSet blocks (:class:`Block`'s
        ``levelSet``) with each other and with the bed, a YADE ``Wall`` at z = 0 (the flow still
        meets the SDEM bed): ``{"kn": k_n [N/m] > 0, "ks": k_s [N/m] ≥ 0}`` of
        ``Ip2_FrictMat_FrictMat_FrictPhys`` (one linear spring per contact, one contact per pair
        of bodies: ``Ig2_LevelSet_LevelSet_ScGeom``, ``Ig2_Wall_LevelSet_ScGeom``) with
        ``Law2_ScGeom_FrictPhys_CundallStrack``; friction the smaller of the two bodies'
        (the bed's: the LevelSet blocks'). Default k_n 1e4 N/m (the blocks' barrier stiffness
        scale), k_s = k_n/(2(1 + 0.3)) (the SDEM K_t at ν 0.3). The coupled engine's step
        control does not see these contacts: O.dt and the coupled engine's ``dtMax`` are set to
        ``levelSetStep`` = 0.3 sqrt(m/k_n) of the lightest moving LevelSet block;
    :param backend, precision: MPM backend; :param output: folder for all outputs (None: none),
        :param outputEvery: record interval [s]; :param vtkEvery: ParaView interval [s].
    """

    def __init__(self, length=1.8, width=0.2, inclineDeg=10.0, columnLength=0.3, columnHeight=0.2, dx=0.01, ppc=8,
                 granular=None, basalFriction=0.21, sideWallFriction=0.0, blocks=(), bedSweep=0.005,
                 bedBarrierStiffness=1e4, dtFactor=0.5, backend="cpu", precision="double", output=None,
                 outputEvery=0.01, vtkEvery=None, plot=False, verbose=True, gate=None, flipReferenceDt=None,
                 dtAuto=None, dtCheck="raise", flipAlpha=None, flipViscosity=None, levelSetContact=None):
        if gate is not None and (not isinstance(gate, dict) or set(gate) - {"speed", "open_at", "friction"}):
            raise ValueError("gate = %r: must be None or a dict with keys among speed [m/s], open_at [s], friction"
                             % (gate,))
        levelSetBlocks = [b for b in blocks if b.levelSet is not None]
        if levelSetBlocks and backend != "cpu":
            raise ValueError("backend = %r: LevelSet blocks need the flow's CPU backend" % (backend,))
        contact = {"kn": 1e4, "ks": 1e4 / 2.6}
        if levelSetContact is not None:
            if not isinstance(levelSetContact, dict) or set(levelSetContact) - set(contact):
                raise ValueError("levelSetContact = %r: must be None or a dict with keys among kn, ks [N/m]"
                                 % (levelSetContact,))
            contact.update({k: float(v) for k, v in levelSetContact.items()})
            if not (contact["kn"] > 0 and contact["ks"] >= 0):
                raise ValueError("levelSetContact = %r: kn must be > 0 and ks >= 0 [N/m]" % (levelSetContact,))
        self.levelSetContact = contact
        O.reset()
        self.inclineDeg, self.dx, self.length, self.width = inclineDeg, dx, length, width
        self.columnLength, self.columnHeight = columnLength, columnHeight
        th = math.radians(inclineDeg)
        self.gravity = (9.81 * math.sin(th), 0.0, -9.81 * math.cos(th))
        granular = dict(GLASS_BEADS if granular is None else granular)
        if not dx > 0:
            raise ValueError("dx = %r m: must be > 0" % (dx,))
        cellsAcross = width / dx
        if not (round(cellsAcross) >= 1 and abs(cellsAcross - round(cellsAcross)) < 1e-6 * cellsAcross):
            raise ValueError("dx = %r m: must divide the flume width %r m into whole cells (the side walls lie on "
                             "grid planes), e.g. %r or %r m" % (dx, width, width / max(1, math.floor(cellsAcross)),
                                                                 width / math.ceil(cellsAcross)))
        n = round(ppc ** (1.0 / 3.0))
        if n ** 3 != ppc:
            raise ValueError("ppc = %r: must be a perfect cube (1, 8, 27, ...)" % (ppc,))
        rp = analysis.pointRadius(dx, ppc)
        # The bed's outer surface is z = 0 (its core top at -bedSweep). Grid aligned so that the
        # lowest material points, at zLow + dx/(2n), touch it (centre R_p0 above it); the
        # grid's own bottom wall lies two cells lower, under the bed, so that only the SDEM bed
        # (through the coupling pair) holds the flow and gives it its basal friction.
        zLow = rp - dx / (2.0 * n)
        height = columnHeight + max(b.z + 2 * b.half[2] for b in blocks) if blocks else columnHeight
        cells = [int(math.ceil(length / dx)) + 4, int(round(width / dx)) + 4,
                 int(math.ceil((max(height, columnHeight) + 0.05) / dx)) + 6]
        self.sdem = SdemEngine(dtCheck=dtCheck, verbose=verbose,
                               output=output, outputEvery=outputEvery if output else None)
        bedMat = _material(density=2500, friction=1.0, barrierStiffness=bedBarrierStiffness)
        self.bedId = self.sdem.box((length / 2 + 2 * dx, width / 2 + 2 * dx, 0.02), bedSweep, bedMat,
                                   pos=(length / 2 - dx, width / 2, -0.02), fixed=True)
        pairs = {bedMat: {"friction": basalFriction}}
        self.blockIds = []
        self.levelSetIds = []
        if levelSetBlocks:
            lsBed = O.materials.append(FrictMat(density=2500, frictionAngle=math.atan(max(b.friction for b in
                                                                                      levelSetBlocks))))
            self.levelSetBedId = O.bodies.append(utils.wall(0.0, axis=2, material=lsBed))
        for b in blocks:
            if b.levelSet is not None:
                self.blockIds.append(self._levelSetBlock(b, th))
                continue
            mat = _material(density=b.density, friction=b.friction, barrierStiffness=b.barrierStiffness)
            y = width / 2 if b.y is None else b.y
            zc = b.z + b.half[2]
            if b.z == 0.0:  # resting on the bed: at the overlap that carries its weight
                R = b.sweepRadius + bedSweep
                mass = b.density * 8 * b.half[0] * b.half[1] * b.half[2]
                zc -= analysis.equilibriumOverlap(mass * 9.81 * math.cos(th), R, b.barrierStiffness, contacts=4)
            i = self.sdem.box(b.half, b.sweepRadius, mat, pos=(b.x + b.half[0], y, zc))
            if b.blockedDOFs:
                O.bodies[i].state.blockedDOFs = b.blockedDOFs
            pairs[mat] = {"friction": b.flowFriction}
            self.blockIds.append(i)
        self.mpm = MpmEngine(
            grid={"dx": dx, "cells": cells, "origin": [-2 * dx, -2 * dx, zLow - 4 * dx]},
            material=granular,
            particles=[{"lo": [0, 0, zLow], "hi": [columnLength, width, zLow + columnHeight], "ppc": ppc}],
            gravity={"g": 9.81, "incline_deg": inclineDeg},
            walls={"-x": "free", "+x": "free", "-y": sideWallFriction, "+y": sideWallFriction, "-z": "free",
                   "+z": "free"},
            backend=backend, precision=precision, verbose=verbose, flipAlpha=flipAlpha, flipReferenceDt=flipReferenceDt,
            flipViscosity=flipViscosity,
            gate=None if gate is None else dict(gate, x=columnLength, bottom=0.0),
            output=os.path.join(output, "mpm") if output else None, outputEvery=vtkEvery or outputEvery)
        levelSets = {i: {"friction": b.flowFriction, "barrierStiffness": b.barrierStiffness}
                     for i, b in zip(self.blockIds, blocks) if b.levelSet is not None}
        self.coupled = CoupledEngine(self.sdem, self.mpm, pairs=pairs, output=output, outputEvery=outputEvery,
                                     vtkEvery=vtkEvery, plot=plot, verbose=verbose, dtAuto=dtAuto,
                                     dtCheck=dtCheck, levelSets=levelSets or None)
        yadeContacts = []
        if levelSetBlocks:
            ip2 = Ip2_FrictMat_FrictMat_FrictPhys(kn=MatchMaker(algo="val", val=contact["kn"]),
                                                  ks=MatchMaker(algo="val", val=contact["ks"]))
            yadeContacts = [InsertionSortCollider([Bo1_LevelSet_Aabb(), Bo1_Wall_Aabb()], verletDist=0.1 * dx),
                            InteractionLoop([Ig2_LevelSet_LevelSet_ScGeom(), Ig2_Wall_LevelSet_ScGeom()], [ip2],
                                            [Law2_ScGeom_FrictPhys_CundallStrack()])]
        O.engines = [ForceResetter()] + yadeContacts + [self.coupled.runner,
                                                        NewtonIntegrator(gravity=Vector3(*self.gravity), damping=0)]
        O.dt = dtFactor * self.mpm.stableTimeStep()
        self.levelSetStep = math.inf
        moving = [O.bodies[i].state.mass for i in self.levelSetIds if O.bodies[i].state.blockedDOFs != "xyzXYZ"]
        if moving:
            # The coupled engine's step control does not see YADE's own contacts of the LevelSet
            # blocks. One linear spring k_n on a body of mass m: central differences are stable
            # below 2 sqrt(m/k_n) in translation; a box turning about its centre on an edge
            # contact has m r^2 / I = 3, so sqrt(3) times the frequency. O.dt is held below
            # 0.3 sqrt(m/k_n) (0.52 rad a step in the fastest mode).
            self.levelSetStep = 0.3 * math.sqrt(min(moving) / contact["kn"])
            self.coupled.dtMax = self.levelSetStep
            O.dt = min(O.dt, self.levelSetStep)
        self.x0 = [O.bodies[i].state.pos[0] for i in self.blockIds]
        # per sample: (t, [x], [vx], [Fx], [Ffx], [Fex], [rotation], [tilt], [yaw] deg, (flow
        # kinetic, flow potential, blocks' kinetic energy [J], the flow's front [m]))
        self.history = []

    def _levelSetBlock(self, b, th):
        """A YADE LevelSet box for :class:`Block` ``b``; returns its id."""
        mat = O.materials.append(FrictMat(density=b.density, frictionAngle=math.atan(b.friction)))
        y = self.width / 2 if b.y is None else b.y
        zc = b.z + b.half[2]
        if b.z == 0.0:  # resting on the bed: at the overlap of the linear spring that carries its weight
            mass = b.density * 8 * b.half[0] * b.half[1] * b.half[2]
            zc -= mass * 9.81 * math.cos(th) / self.levelSetContact["kn"]
        i = O.bodies.append(utils.levelSetBody("box", center=(b.x + b.half[0], y, zc), extents=b.half,
                                               spacing=b.levelSet["spacing"], nSurfNodes=b.levelSet["nSurfNodes"],
                                               material=mat))
        if b.blockedDOFs:
            O.bodies[i].state.blockedDOFs = b.blockedDOFs
        self.levelSetIds.append(i)
        return i

    def sample(self):
        """Append the blocks' state and flow forces (downstream components) to ``history``."""
        row = [O.time]
        bodies = [O.bodies[i] for i in self.blockIds]
        row.append([b.state.pos[0] for b in bodies])
        row.append([b.state.vel[0] for b in bodies])
        row.append([self.coupled.force(i)[0] for i in self.blockIds])
        # a LevelSet body has no faces and edges to tell apart: nan
        row.append([math.nan if i in self.levelSetIds else self.coupled.faceForce(i)[0] for i in self.blockIds])
        row.append([math.nan if i in self.levelSetIds else self.coupled.edgeForce(i)[0] for i in self.blockIds])
        turns = [b.state.ori.toAngleAxis() for b in bodies]
        row.append([math.degrees(angle) for angle, _ in turns])
        split = [tiltAndYaw(angle, axis) for angle, axis in turns]
        row.append([tilt for tilt, _ in split])
        row.append([yaw for _, yaw in split])
        d = self.mpm.diagnostics()
        row.append((d["kinetic_energy"], d["potential_energy"], self.coupled.blockKineticEnergy(), d["front_x"]))
        # the CUDA backend keeps its contacts on the device: no split by face there
        row.append([None if i in self.levelSetIds else
                    analysis.boxFaceLoads(self.coupled.contacts(i), b.state.ori.toRotationMatrix())
                    for i, b in zip(self.blockIds, bodies)] if self.mpm.solver.name.startswith("cpu") else None)
        row.append([b.state.vel.norm() for b in bodies])
        row.append([self.coupled.impulse(i)[0] for i in self.blockIds])
        row.append([self.coupled.firstContact(i) for i in self.blockIds])
        row.append([self.coupled.angularImpulse(i)[1] for i in self.blockIds])
        self.history.append(row)

    def run(self, duration, sampleEvery=None):
        """Run ``duration`` seconds, sampling every ``sampleEvery`` s (default: ~5 steps)."""
        from . import run as _run
        every = max(1, int(round((sampleEvery or 5 * O.dt) / O.dt)))
        steps = int(round(duration / O.dt))
        end = O.time + steps * O.dt  # the progress line's end at this O.dt (each chunk starts a step or more before it)
        done = 0
        while done < steps:
            k = min(every, steps - done)
            # a step the scene changes (dtAuto) can pass that end early: the count-down then stops
            _run(k, self.coupled, endTime=end if O.time < end else None)
            done += k
            self.sample()

    # ------------------------------------------------------------------ results
    def gateImpulse(self):
        """Impulse the gate has given the flow so far [N s], (x, y, z) in the flume frame (x < 0
        while it holds the column); ValueError without a gate."""
        return self.mpm.solver.gateImpulse()

    def gateEdgeHeight(self, t=None):
        """Height of the gate's lower edge above the bed at time t (default: now) [m], inf once
        removed; ValueError without a gate."""
        return self.mpm.solver.gateEdgeHeight(self.mpm.time if t is None else t)

    def flipBlend(self):
        """The flow's FLIP/PIC blend in words (e.g. 'alpha 0.99 per 5e-06 s (PIC damping 2010 /s)'):
        the damping per second is a model quantity, stated with every result."""
        return self.mpm.solver.flipBlend

    def travel(self, k):
        """Travel distance of block k along the flume so far, S_b [m]."""
        return O.bodies[self.blockIds[k]].state.pos[0] - self.x0[k]

    def series(self, k):
        """numpy arrays of block k: t, travel S_b, v_x, speed (of its centre) [m/s], F_t, F_f, F_e
        (downstream, of the step before each sample, N), J (the downstream impulse since the
        start, N s), Ly (the angular impulse about its centroid and the cross-slope axis y since
        the start, N m s; :func:`analysis.blowLineOfAction`) and Fmean (the mean downstream force
        since the sample before, :func:`analysis.intervalMean`, N), first_contact (when the flow first touched it, as
        known at each sample, NaN before: :meth:`CoupledEngine.firstContact`, s), rotation
        (the whole angle turned since the start), tilt and yaw (deg; :func:`tiltAndYaw`; F_f and
        F_e are nan for a LevelSet block); and
        of the scene: flow_kinetic, flow_potential (zero at the origin: the bed under the
        column's upstream end) and block_kinetic (all SDEM blocks, translation and rotation;
        not the LevelSet ones) [J], and
        flow_front, the flow's most downstream point [m].
        On the CPU backend also ``faces``: the flow's normal load on each face of the block in
        its own frame, a dict of arrays [N] keyed as :func:`analysis.boxFaceLoads` ("-x" the
        upstream face of a block placed square, "+z" its top, "edges")."""
        import numpy as np
        t = np.array([r[0] for r in self.history])
        cols = [np.array([r[j][k] for r in self.history]) for j in range(1, 9)]
        scene = np.array([r[9] for r in self.history]).reshape(-1, 4)
        out = {"t": t, "travel": cols[0] - self.x0[k], "vx": cols[1], "speed": np.array([r[11][k] for r in self.history]),
               "Ft": cols[2], "Ff": cols[3], "Fe": cols[4], "J": np.array([r[12][k] for r in self.history]),
               "first_contact": np.array([r[13][k] for r in self.history]),
               "Ly": np.array([r[14][k] for r in self.history]),
               "rotation": cols[5], "tilt": cols[6], "yaw": cols[7], "flow_kinetic": scene[:, 0],
               "flow_potential": scene[:, 1], "block_kinetic": scene[:, 2], "flow_front": scene[:, 3]}
        out["Fmean"] = analysis.intervalMean(t, out["J"])
        if self.history and self.history[0][10] is not None and self.history[0][10][k] is not None:
            out["faces"] = {f: np.array([r[10][k][f] for r in self.history]) for f in self.history[0][10][k]}
        return out

    def peakForce(self, k, smooth=None):
        """Peak downstream flow force on block k [N] and its time [s]: with ``smooth`` [s] the
        largest mean force over a window that long, from the impulse (every step's force:
        :func:`mpmsdem.analysis.peakMeanForce`); without, the largest force of one recorded step."""
        s = self.series(k)
        if smooth:
            return analysis.peakMeanForce(s, smooth)
        return analysis.smoothedPeak(s["t"], s["Ft"])
