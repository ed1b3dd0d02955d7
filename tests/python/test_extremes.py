"""Stability at the extremes (paper Appendix D): sweep radius R/h_b = 1/200 and 1/8, time steps
at 0.9x and 2x the reported critical step, friction 0 and 1 (block-bed and flow-block), blocks
pressed to near core contact, a stress-free (gasified) cloud hitting a block, a block rotated 45
degrees at impact, a Froude-12 stream, single precision. Each scene has an answer known from
an analytic solution or a conservation law, asserted with two-sided tolerances; each extreme
either works within its tolerance or stops with an error that names the cause. The table of
outcomes is docs/extremes.md; the 10^6-step energy run is scripts/validation/long_run_energy.py.
"""
import math
import re
import warnings

import numpy as np
import pytest

import mpmsdem
from mpmsdem import analysis
from yade import O
from yade.minieigenHP import Quaternion, Vector3
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

from scenes import H, KC, RHO, gravity

NU = 0.3          # Poisson ratio of mpmsdem.material's default: K_t = k_n / (2 (1 + nu)) (Eq 11)
RATIOS = [pytest.param(1 / 200, id="R=h/200"), pytest.param(1 / 8, id="R=h/8")]
GRAIN = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def _finite(*vectors):
    return all(math.isfinite(v[k]) for v in vectors for k in range(3))


def _every_step(fn, period=1):
    """A PyRunner calling ``fn`` after NewtonIntegrator every ``period`` steps."""
    import __main__
    name = "_mpmsdem_extremes_%d" % id(fn)
    setattr(__main__, name, fn)
    return PyRunner(command=name + "()", iterPeriod=period)


def _cubeOnSlab(ratio, mu=0.0, theta=0.0, normalDamping=0.0, tangentialDamping=0.1, lift=0.0, dtCheck="raise"):
    """A cube of side H (rho 3000, k_c 1e4) with sweep radius R = ratio H on a fixed slab whose
    top face is z = 0, gravity inclined by theta about y. It starts at the overlap at which its
    4 face contacts carry the normal weight component (Eq 10 inverted), raised by ``lift`` [m].
    Returns (engine, cube id, mass, equilibrium overlap)."""
    R = ratio * H
    eng = mpmsdem.SdemEngine(dtCheck=dtCheck, verbose=False)
    mat = mpmsdem.material(density=RHO, friction=mu, barrierStiffness=KC, normalDamping=normalDamping,
                           tangentialDamping=tangentialDamping)
    eng.box((1.0, 0.5, 0.05), R, mat, pos=(0.8, 0, -0.05), fixed=True)
    m = RHO * mpmsdem.SpheroPolyhedron.box((H / 2,) * 3, R).volume
    delta = analysis.equilibriumOverlap(m * 9.81 * math.cos(math.radians(theta)), 2 * R, KC, contacts=4)
    cube = eng.box((H / 2,) * 3, R, mat, pos=(0, 0, H / 2 - delta + lift))
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=gravity(theta), damping=0)]
    return eng, cube, m, delta


def _omegaMax(m, inertia, kn, a, zc):
    """Highest angular frequency of the cube on its 4 contacts, linearised: contact points at
    (+-a, +-a, -zc) from the centroid, normal stiffness kn (Eq 10's tangent) along z, K_t =
    kn/(2(1+nu)) in the plane (Eq 11). The leapfrog step is stable below 2/omega_max."""
    kt = kn / (2 * (1 + NU))
    n = np.array([0.0, 0.0, 1.0])
    D = kn * np.outer(n, n) + kt * (np.eye(3) - np.outer(n, n))
    K = np.zeros((6, 6))
    for sx in (-1, 1):
        for sy in (-1, 1):
            r = np.array([sx * a, sy * a, -zc])
            cross = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
            G = np.hstack([np.eye(3), -cross])  # generalised velocity -> contact point velocity
            K += G.T @ D @ G
    s = np.diag([m ** -0.5] * 3 + [inertia[k] ** -0.5 for k in range(3)])
    return math.sqrt(np.linalg.eigvalsh(s @ K @ s).max())


# ====================================================================== sweep radius extremes
@pytest.mark.parametrize("ratio", RATIOS)
def test_resting_cube_carries_its_weight_and_reports_a_safe_step(ratio):
    # Settled with normal damping, the cube must rest on exactly 4 contacts carrying m g at the
    # overlap of Eq 10 inverted, whatever R. At R = h/200 that overlap is 0.41 (R_i + R_j),
    # far from the first-touch regime k_n ~ 6 k_c delta/R, so the stiffness is checked against
    # the exact tangent of Eq 10. The reported critical step must lie below 1/omega_max of the
    # linearised 6-DOF system (the leapfrog bound is 2/omega_max) and not far below it.
    R = ratio * H
    eng, cube, m, delta = _cubeOnSlab(ratio, mu=0.3, normalDamping=0.5, lift=2e-4)
    kn = analysis.barrierStiffness(delta, 2 * R, KC)
    wmax = _omegaMax(m, O.bodies[cube].state.inertia, kn, H / 2 - R, H / 2 - delta / 2)
    O.dt = 0.2 / wmax
    mpmsdem.run(int(0.3 / O.dt), eng)
    c = eng.contacts()
    w = m * 9.81
    assert len(c["normalForce"]) == 4
    assert c["normalForce"].sum() == pytest.approx(w, rel=1e-6)
    assert np.allclose(c["overlap"], delta, rtol=1e-6, atol=0)
    assert np.allclose(c["normalStiffness"], kn, rtol=1e-6, atol=0)
    assert 0.5 <= eng.criticalTimeStep * wmax <= 1.0, eng.criticalTimeStep * wmax
    st = O.bodies[cube].state
    assert _finite(st.pos, st.vel, st.angVel) and st.vel.norm() < 1e-6


@pytest.mark.parametrize("ratio", RATIOS)
def test_frictionless_cube_slides_as_eq19_at_extreme_radii(ratio):
    # mu = 0: the Coulomb cap is 0, so the tangential force must vanish exactly and the cube
    # follows Eq 19 (S = g sin(theta) t^2 / 2); the leapfrog start (x_1 = a dt^2) shifts it by a
    # relative dt/t = 2e-4.
    eng, cube, m, delta = _cubeOnSlab(ratio, mu=0.0, theta=30.0)
    O.dt = 1e-4
    mpmsdem.run(5000, eng)
    s = O.bodies[cube].state.pos[0]
    assert s == pytest.approx(analysis.slidingDistance(O.time, 30.0, 0.0), rel=1e-3)
    assert eng.force(cube)[0] == 0.0 and not eng.contacts()["tangentialForce"].any()
    assert len(eng.contacts()["normalForce"]) == 4


@pytest.mark.parametrize("ratio", RATIOS)
def test_cube_with_friction_one_sticks_on_a_30_degree_incline(ratio):
    # tan 30 = 0.58 < mu = 1 (Eq 19 gives S = 0): after the stick stage the cube must stand
    # still with every contact below its Coulomb cap, the springs carrying m g sin(theta). Its
    # displacement is the springs' stretch x_s = m g sin(theta) / sum K_t (Eq 11) plus the
    # tilt of the centroid above the base: between x_s and 3 x_s.
    eng, cube, m, delta = _cubeOnSlab(ratio, mu=1.0, theta=30.0, normalDamping=0.3, tangentialDamping=0.5)
    O.dt = 1e-4
    mpmsdem.run(6000, eng)
    x1 = O.bodies[cube].state.pos[0]
    mpmsdem.run(2000, eng)
    x2 = O.bodies[cube].state.pos[0]
    c = eng.contacts()
    ws = m * 9.81 * 0.5
    xs = ws / (c["normalStiffness"] / (2 * (1 + NU))).sum()
    assert len(c["normalForce"]) == 4 and not c["sliding"].any()
    assert -c["tangentialForce"][:, 0].sum() == pytest.approx(ws, rel=1e-4)
    assert abs(x2 - x1) < 1e-3 * xs
    assert xs <= x2 <= 3 * xs, (x2, xs)


def test_cube_with_friction_one_sticks_with_the_elastic_barrier_at_small_radius():
    # The physics is that of the test above without normal damping: the total energy
    # (kinetic + gravity + barrier + tangential springs) plus the friction and damping work
    # may only stay at or below its initial value, and the cube may not move beyond its
    # stick stage (1 mm is 4 x_s).
    eng, cube, m, delta = _cubeOnSlab(1 / 200, mu=1.0, theta=30.0, dtCheck="warn")
    g = gravity(30.0)
    log = []

    def sample():
        s = O.bodies[cube].state
        wb = s.ori.conjugate() * s.angVel
        en = eng.energies()
        log.append((0.5 * s.mass * s.vel.squaredNorm() + 0.5 * sum(s.inertia[k] * wb[k] ** 2 for k in range(3))
                    - s.mass * g.dot(s.pos) + en["barrier"] + en["tangential"] + en["friction"] + en["damping"],
                    s.pos[0]))

    O.engines = O.engines + [_every_step(sample, 20)]
    O.dt = 5e-5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        mpmsdem.run(7000, eng)  # 0.35 s
    e, x = np.array(log).T
    assert np.abs(x).max() < 1e-3
    assert e.max() - e[0] < 1e-3 * m * 9.81 * H


# ====================================================================== time step
def _headOn(ratio, v, dt, dtCheck="raise"):
    """Two frictionless cubes 0.2 mm apart closing at 2 v (elastic barrier). Returns the
    engine, the ids and the smallest critical step reported during the run."""
    R = ratio * H
    eng = mpmsdem.SdemEngine(dtCheck=dtCheck, verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.0, barrierStiffness=KC)
    a = eng.box((H / 2,) * 3, R, mat, pos=(-H / 2 - 1e-4, 0, 0))
    b = eng.box((H / 2,) * 3, R, mat, pos=(H / 2 + 1e-4, 0, 0))
    O.bodies[a].state.vel = (v, 0, 0)
    O.bodies[b].state.vel = (-v, 0, 0)
    seen = {"crit": math.inf, "overlap": 0.0}

    def watch():
        seen["crit"] = min(seen["crit"], eng.criticalTimeStep)
        ov = eng.contacts()["overlap"]
        if len(ov):
            seen["overlap"] = max(seen["overlap"], ov.max())

    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0), _every_step(watch)]
    O.dt = dt
    return eng, a, b, seen


@pytest.mark.parametrize("ratio,v", [pytest.param(1 / 200, 0.1, id="R=h/200"), pytest.param(1 / 8, 1.0, id="R=h/8")])
def test_time_step_at_0_9_and_2_times_the_reported_critical_step(ratio, v):
    # The smallest critical step reported during the collision (a run at a small step) sets
    # dt_c. At 0.9 dt_c the blocks must separate at +-v (elastic barrier: restitution 1) to
    # 0.2 %, cores apart. At 2 dt_c, dtCheck="raise" must stop the run with an error naming dt
    # and the critical step, and "warn" must warn and count; neither may leave NaN.
    duration = 0.12 if ratio < 0.01 else 0.04  # the contact lasts ~0.1 s and ~0.02 s

    def collide(dt, dtCheck="raise"):
        O.reset()
        eng, a, b, seen = _headOn(ratio, v, dt, dtCheck)
        mpmsdem.run(int(duration / dt), eng)
        return eng, a, b, seen

    eng, a, b, seen = collide(2e-5 if ratio < 0.01 else 1e-4)
    dtc = seen["crit"]
    assert O.bodies[b].state.vel[0] == pytest.approx(v, rel=1e-5)
    assert math.isfinite(dtc) and 0.05 < seen["overlap"] / (2 * ratio * H) < 1

    eng, a, b, seen = collide(0.9 * dtc)
    assert not len(eng.contacts()["overlap"])
    for i, sign in ((a, -1), (b, 1)):
        st = O.bodies[i].state
        assert _finite(st.pos, st.vel, st.angVel)
        assert sign * st.vel[0] == pytest.approx(v, rel=2e-3)
    assert seen["overlap"] < 2 * ratio * H

    O.reset()
    eng, a, b, seen = _headOn(ratio, v, 2 * dtc, "raise")
    with pytest.raises(RuntimeError, match="critical time step") as err:
        mpmsdem.run(int(duration / (2 * dtc)), eng)
    m = re.search(r"dt = ([0-9.e+-]+) s: must be <= the SDEM critical time step ([0-9.e+-]+) s", str(err.value))
    assert m, str(err.value)
    assert float(m.group(1)) == pytest.approx(2 * dtc, rel=1e-5) and float(m.group(2)) < float(m.group(1))
    assert all(_finite(O.bodies[i].state.pos, O.bodies[i].state.vel) for i in (a, b))

    O.reset()
    eng, a, b, seen = _headOn(ratio, v, 2 * dtc, "warn")
    with pytest.warns(RuntimeWarning, match="exceeds the critical step"):
        mpmsdem.run(int(duration / (2 * dtc)), eng)
    assert eng.timeStepWarnings >= 1
    assert all(_finite(O.bodies[i].state.pos, O.bodies[i].state.vel) for i in (a, b))


def test_coupled_contact_step_read_out_and_dt_check_switched_mid_run():
    # contactTimeStep is inf until a point touches the block and finite after, and
    # criticalTimeStep() is the smaller of it and the MPM CFL step. A step 1.5x above it, with
    # dtCheck switched to "warn" between steps, warns, counts and stays finite; switched to
    # "raise" instead, the same step stops the run with dt and the contact step named. (A
    # stiffer flow-block barrier, k_c 1e6, puts the contact step below the MPM one; the blob
    # rebounds within that step, so each switch gets its own approach.)
    def approach(dtCheck):
        O.reset()
        mpm, coupled, cube = _blobAndBlock(pairStiffness=1e6)
        O.dt = 1e-5
        mpmsdem.run(1, coupled)
        assert coupled.contactTimeStep == math.inf
        assert coupled.criticalTimeStep() == mpm.stableTimeStep()
        for _ in range(200):
            if coupled.contactCount(cube) >= 4:
                break
            mpmsdem.run(10, coupled)
        mpmsdem.run(20, coupled)
        dtc = coupled.contactTimeStep
        assert 0 < dtc < math.inf and 1.5 * dtc < 0.9 * mpm.stableTimeStep()
        assert coupled.criticalTimeStep() == min(mpm.stableTimeStep(), dtc)
        O.dt = 1.5 * dtc
        coupled.dtCheck = dtCheck
        return coupled, cube, dtc

    coupled, cube, dtc = approach("warn")
    with pytest.warns(RuntimeWarning, match="exceeds the contact critical step"):
        mpmsdem.run(1, coupled)
    assert coupled.timeStepWarnings == 1
    assert _finite(O.bodies[cube].state.pos, O.bodies[cube].state.vel, coupled.force(cube))

    coupled, cube, dtc = approach("raise")
    with pytest.raises(RuntimeError, match="must be <= the coupled contact critical step") as err:
        mpmsdem.run(1, coupled)
    m = re.search(r"dt = ([0-9.e+-]+) s: must be <= the coupled contact critical step ([0-9.e+-]+) s", str(err.value))
    assert m and float(m.group(1)) == pytest.approx(1.5 * dtc, rel=1e-5) and float(m.group(2)) < float(m.group(1))
    with pytest.raises(ValueError, match="^dtCheck = 'stop': must be one of raise, warn"):
        coupled.dtCheck = "stop"


def test_coupled_dt_auto_follows_the_critical_step_of_the_step_before():
    # dtAuto = f: each step runs with O.dt = min(f x criticalTimeStep(), 0.1 x approachTimeStep,
    # particleApproachStep) as they stood after the step before, grown by at most 1 % over that step's O.dt (the first
    # step only caps the script's O.dt); dtMax bounds it; through the impact the contact part
    # falls below the MPM step and O.dt follows it down; no step ever exceeds the check. Bad
    # values are refused by name.
    mpm, coupled, cube = _blobAndBlock(pairStiffness=1e6)
    coupled.dtAuto = 0.5
    O.dt = 1e-6
    mpmsdem.run(1, coupled)
    assert O.dt == 1e-6  # the first step: below 0.5 x the MPM step, kept
    seen = []  # (O.dt of the step, criticalTimeStep(), approachTimeStep, particleApproachStep after it)
    O.engines = O.engines + [_every_step(lambda: seen.append((O.dt, coupled.criticalTimeStep(),
                                                              coupled.approachTimeStep,
                                                              coupled.particleApproachStep)))]
    mpmsdem.run(1500, coupled)
    capped = byContacts = 0
    for (dt, _, _, _), (prev, crit, app, pa) in zip(seen[1:], seen[:-1]):
        assert dt == min(0.5 * crit, 0.1 * app, pa, 1.01 * prev)
        capped += dt == 1.01 * prev
        byContacts += dt == 0.5 * crit and crit < mpm.stableTimeStep()
    assert 300 < capped < 1499  # grew from 1e-6 at 1 % a step, then followed the contacts
    assert byContacts > 20  # the impact's contact step set it
    dts = [d for d, *_ in seen]
    assert max(dts) == pytest.approx(0.5 * mpm.stableTimeStep(), rel=0.05)
    assert min(dts[400:]) < 0.6 * max(dts)
    assert any(app < math.inf for _, _, app, _ in seen)
    coupled.dtMax = 2e-5
    mpmsdem.run(20, coupled)
    assert all(d <= 2e-5 for d, *_ in seen[-20:])
    for name, bad in (("dtAuto", 0.0), ("dtAuto", 1.5), ("dtAuto", "0.5")):
        with pytest.raises(ValueError, match="^%s = " % name):
            coupled.dtAuto = bad
    with pytest.raises(ValueError, match="^dtMax = "):
        coupled.dtMax = 0


def test_coupled_dt_auto_lands_a_falling_block_without_a_refused_step():
    # A 2 cm copper cube (R 1 mm) dropped 15 cm onto the bed of a coarse flume, dtAuto = 0.5 and
    # dtCheck "raise" passed through Flume. No contact announces the landing, so the step that
    # lands it is chosen without one: the approach step keeps the cube from moving more than a
    # tenth of its sweep radius in a step (it sets the step over the last part of the fall, at
    # 1.7 m/s), so it enters the barrier so gently that no step exceeds even the critical step
    # of the new contact. The cores never meet, and the elastic barrier sends the cube back up,
    # never above its start.
    from mpmsdem.flume import Block, Flume
    R = 0.001
    scene = Flume(length=0.6, width=0.1, columnLength=0.1, columnHeight=0.06, dx=0.02, ppc=1, inclineDeg=0.0,
                  blocks=[Block(half=(0.01, 0.01, 0.01), x=0.45, z=0.15, sweepRadius=R)], dtAuto=0.5,
                  verbose=False)
    cube = scene.blockIds[0]
    steps = []  # (O.dt, displacement of the step, contact step after it, cube-bed contacts, z)
    last = [Vector3(O.bodies[cube].state.pos)]

    def probe():
        p = Vector3(O.bodies[cube].state.pos)
        steps.append((O.dt, (p - last[0]).norm(), scene.coupled.contactTimeStep, len(scene.sdem.contacts()["id1"]),
                      p[2]))
        last[0] = p

    O.engines = O.engines + [_every_step(probe)]
    while O.time < 0.25:
        mpmsdem.run(50, scene.coupled)
    st = O.bodies[cube].state
    assert _finite(st.pos, st.vel, st.angVel)
    landed = [i for i, step in enumerate(steps) if step[3] > 0]
    assert landed, "the cube never touched the bed"
    free = steps[:landed[0]]
    g = 9.81
    assert all(d <= 0.1 * R * (1 + g * dt / 0.05) for dt, d, _, _, _ in free[10:])  # v > 0.05 m/s there
    assert max(d for _, d, _, _, _ in free) == pytest.approx(0.1 * R, rel=0.02)  # the approach step bound it
    assert all(dt <= c for dt, _, c, _, _ in steps)
    bedCoreTop = -0.005
    assert st.pos[2] - 0.01 > bedCoreTop  # the cores never met
    rebound = max(z for *_, z in steps[landed[0]:])
    assert 0.11 < rebound < 0.16  # back up on the elastic barrier, never above its start


# ====================================================================== near core contact
def test_blocks_pressed_to_near_core_contact():
    # A load on the cube drives the overlap to 0.9, 0.99 and 0.999 of R_i + R_j (R = h/20):
    # the barrier force grows without bound, so there is an equilibrium for any load, with the
    # core gap of Eq 10 inverted (1e-5 m at 0.999). The reported critical step stays a safe
    # fraction of 1/omega_max and falls as 1/sqrt(k_n) (k_n ~ k_c/(1 - delta/R)^2 near the
    # limit), by ~10 from one load to the next; the lever arms of the contacts shorten by
    # delta/2, hence 1 % on the ratio.
    ratio = 1 / 20
    Rs = 2 * ratio * H
    steps = []
    for x in (0.9, 0.99, 0.999):
        O.reset()
        eng, cube, m, _ = _cubeOnSlab(ratio, mu=0.3, normalDamping=0.5)
        load = 4 * analysis.barrierForce(x * Rs, Rs, KC)
        O.bodies[cube].state.pos = (0, 0, H / 2 - x * Rs + 0.05 * (1 - x) * Rs)  # 5 % of the final gap above it
        O.forces.setPermF(cube, Vector3(0, 0, -(load - m * 9.81)))
        kn = analysis.barrierStiffness(x * Rs, Rs, KC)
        wmax = _omegaMax(m, O.bodies[cube].state.inertia, kn, H / 2 - ratio * H, H / 2 - x * Rs / 2)
        O.dt = 0.2 / wmax
        mpmsdem.run(int(60 * 2 * math.pi * math.sqrt(m / (4 * kn)) / O.dt), eng)
        c = eng.contacts()
        gap = Rs - c["overlap"]
        assert len(gap) == 4 and gap.min() > 0
        assert c["normalForce"].sum() == pytest.approx(load, rel=1e-6)
        assert np.allclose(gap, (1 - x) * Rs, rtol=1e-6, atol=0)
        st = O.bodies[cube].state
        assert _finite(st.pos, st.vel, st.angVel)
        assert 0.5 <= eng.criticalTimeStep * wmax <= 1.0
        steps.append((eng.criticalTimeStep, kn))
    for (dt1, k1), (dt2, k2) in zip(steps, steps[1:]):
        assert dt1 / dt2 == pytest.approx(math.sqrt(k2 / k1), rel=0.01)


def test_sudden_load_beyond_the_barrier_capacity_stops_with_a_named_error():
    # The same 0.999 load applied at once to the cube resting under its weight: its work over
    # the first millimetres (~3e3 J) exceeds what the barrier stores before the core gap falls
    # below double precision (-ln(1 - delta/R) would have to reach ~850), so the cores must
    # meet. The run has to stop saying so, with the bodies put back to a finite state, even at
    # a step below the critical step of the loaded equilibrium.
    ratio = 1 / 20
    Rs = 2 * ratio * H
    eng, cube, m, _ = _cubeOnSlab(ratio, mu=0.3, normalDamping=0.5)
    O.forces.setPermF(cube, Vector3(0, 0, -(4 * analysis.barrierForce(0.999 * Rs, Rs, KC) - m * 9.81)))
    O.dt = 2e-6  # the loaded equilibrium's critical step is 4.4e-6 s
    with pytest.raises(RuntimeError, match="cores interpenetrate|barrier limit"):
        mpmsdem.run(2000, eng)
    st = O.bodies[cube].state
    assert O.iter < 2000 and _finite(st.pos, st.vel, st.angVel)
    assert st.pos[2] > H / 2 - Rs  # put back before the cores met


# ====================================================================== rotated 45 degrees
def test_cube_rotated_45_degrees_hits_a_cube_edge_first():
    # A frictionless cube turned 45 degrees about z hits the face of an equal resting cube with
    # its edge, centred: the contact normal passes through both centroids, so the collision is
    # a 1D elastic one between equal masses: the velocities are exchanged (1e-6: the barrier is
    # conservative, the contact short), no spin, no sideways motion, the momentum exact.
    R = H / 20
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=RHO, friction=0.0, barrierStiffness=KC)
    a = eng.box((H / 2,) * 3, R, mat, pos=(-H / 2 * math.sqrt(2) - 1e-3, 0, 0),
                ori=Quaternion(Vector3(0, 0, 1), math.pi / 4))
    b = eng.box((H / 2,) * 3, R, mat, pos=(H / 2, 0, 0))
    O.bodies[a].state.vel = (1, 0, 0)
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    mpmsdem.run(6000, eng)
    sa, sb = O.bodies[a].state, O.bodies[b].state
    assert not len(eng.contacts()["overlap"])
    assert sa.vel[0] == pytest.approx(0, abs=1e-6) and sb.vel[0] == pytest.approx(1, rel=1e-6)
    p = sa.mass * sa.vel + sb.mass * sb.vel
    assert (p - Vector3(sa.mass, 0, 0)).norm() < 1e-12 * sa.mass
    for s in (sa, sb):
        assert math.hypot(s.vel[1], s.vel[2]) < 1e-9 and s.angVel.norm() < 1e-9


def _blobAndBlock(yawDeg=0.0, criticalDensity=None, ppc=8, speed=2.0, precision="double", pairStiffness=None):
    """A 4 cm granular cube at `speed` toward a free 4 cm block (R 3 mm, rho 2000, mu 0.3),
    zero gravity, away from every wall; `pairStiffness`: the flow-block k_c [N/m] (None: the
    block's 1e4)."""
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    cube = sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07), ori=Quaternion(Vector3(0, 0, 1),
                                                                                         math.radians(yawDeg)))
    material = dict(GRAIN)
    if criticalDensity is not None:
        material["critical_density"] = criticalDensity
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=material,
                            particles=[{"lo": [0.04, 0.05, 0.05], "hi": [0.08, 0.09, 0.09], "ppc": ppc,
                                        "velocity": [speed, 0, 0]}], gravity=(0, 0, 0), verbose=False,
                            precision=precision, backend="cpu")
    pair = 0.3 if pairStiffness is None else {"friction": 0.3, "barrierStiffness": pairStiffness}
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: pair}, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    return mpm, coupled, cube


def _momentum(mpm, body):
    p = mpm.particles()
    s = O.bodies[body].state
    return (p["mass"][:, None] * p["v"]).sum(axis=0) + s.mass * np.array(s.vel)


def _kinetic(mpm, body):
    p = mpm.particles()
    s = O.bodies[body].state
    wb = s.ori.conjugate() * s.angVel
    return (0.5 * float((p["mass"] * (p["v"] ** 2).sum(axis=1)).sum()) + 0.5 * s.mass * s.vel.squaredNorm()
            + 0.5 * sum(s.inertia[k] * wb[k] ** 2 for k in range(3)))


def _impact(mpm, coupled, cube, chunks, chunk=50, watch=None):
    """Run `chunks` x `chunk` steps; returns the initial momentum and the largest kinetic +
    barrier energy seen over the initial kinetic energy, and the most contacts seen."""
    p0, e0 = _momentum(mpm, cube), _kinetic(mpm, cube)
    rise, contacts = 0.0, 0
    for _ in range(chunks):
        mpmsdem.run(chunk, coupled)
        rise = max(rise, (_kinetic(mpm, cube) + coupled.energies()["barrier"]) / e0 - 1)
        contacts = max(contacts, coupled.contactCount(cube))
        f = coupled.force(cube)
        assert _finite(f)
        if watch:
            watch()
    return p0, rise, contacts


def test_block_rotated_45_degrees_hit_edge_first_by_a_granular_blob():
    # The blob, centred on the block, meets a vertical edge first. Zero gravity, no wall
    # touched: particles + block conserve momentum (Eqs 17-18) to round-off; nothing can create
    # energy (kinetic + barrier never above the initial kinetic energy); the scene is mirror
    # symmetric about the block's y and z planes, so no sideways motion and no spin.
    mpm, coupled, cube = _blobAndBlock(yawDeg=45.0)
    O.dt = 2e-5
    p0, rise, contacts = _impact(mpm, coupled, cube, 25)  # 25 ms
    s = O.bodies[cube].state
    assert contacts >= 8 and s.vel[0] > 0.3
    assert np.linalg.norm(_momentum(mpm, cube) - p0) <= 1e-9 * np.linalg.norm(p0)
    assert rise <= 1e-9
    assert math.hypot(s.vel[1], s.vel[2]) < 1e-9 * s.vel[0] and s.angVel.norm() < 1e-9 * s.vel[0] / 0.02
    assert np.isfinite(mpm.particles()["x"]).all() and np.isfinite(mpm.particles()["v"]).all()


# ====================================================================== gasified particles
def test_gasified_cloud_hitting_a_block_conserves_momentum():
    # With the critical density at twice the bulk density every material point is stress-free
    # (Appendix B: gasified below rho_c): a cloud of 64 free points, one per cell. It must
    # push the free block through the coupling alone, with particles + block momentum exact to
    # round-off, no energy created, nothing non-finite. Every point is still gasified when the
    # cloud first touches the block (piling up against it, it later compacts past rho_c).
    mpm, coupled, cube = _blobAndBlock(criticalDensity=3200.0, ppc=1)
    atTouch = []

    def watch():
        if coupled.contactCount(cube) and not atTouch:
            atTouch.append(mpm.particles()["phase"])

    O.dt = 2e-5
    p0, rise, contacts = _impact(mpm, coupled, cube, 30, watch=watch)
    assert mpm.numParticles == 64 and atTouch and (atTouch[0] == 2).all()
    assert contacts >= 4 and O.bodies[cube].state.vel[0] > 0.5
    assert np.linalg.norm(_momentum(mpm, cube) - p0) <= 1e-9 * np.linalg.norm(p0)
    assert rise <= 1e-9
    p = mpm.particles()
    assert np.isfinite(p["x"]).all() and np.isfinite(p["v"]).all()


# ====================================================================== Froude number 12
def test_froude_12_stream_on_a_fixed_block():
    # A stream 2 cm deep, 4 cm wide, 20 cm long at v = 12 sqrt(g h) = 5.3 m/s on a free-slip
    # bed, under gravity, hits a fixed block spanning the channel. Only the block changes the
    # x momentum, so its impulse balances the stream's momentum change to round-off. The stream
    # is stopped (at most a 15 % rebound): impulse between M v and 1.15 M v; over the time L/v
    # the stream needs to arrive, the mean force is its momentum flux rho v^2 A (a stopped,
    # deflected stream) within -15 %/+10 %.
    dx, h, w, L = 0.01, 0.02, 0.04, 0.2
    v = 12 * math.sqrt(9.81 * h)
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.0)
    face = 0.02 + L + 0.03
    block = sdem.box((0.02, 0.04, 0.1), 0.003, mat, pos=(face + 0.02, 0.02 + w / 2, 0.12), fixed=True)
    mpm = mpmsdem.MpmEngine(grid={"dx": dx, "cells": [int(round((face + 0.06) / dx)) + 2, 8, 24], "origin": [0, 0, 0]},
                            material=dict(GRAIN, mu_s=0.38, mu_2=0.64),
                            particles=[{"lo": [0.02, 0.02, 0.02], "hi": [0.02 + L, 0.02 + w, 0.02 + h], "ppc": 8,
                                        "velocity": [v, 0, 0]}], gravity=(0, 0, -9.81), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.0}, verbose=False)
    forces = []
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0),
                 _every_step(lambda: forces.append((O.time, coupled.force(block)[0])))]
    O.dt = 0.5 * mpm.stableTimeStep()
    p = mpm.particles()
    M = p["mass"].sum()
    px0 = (p["mass"] * p["v"][:, 0]).sum()
    mpmsdem.run(int((0.03 / v + 1.6 * L / v) / O.dt), coupled)
    t, f = np.array(forces).T
    p = mpm.particles()
    impulse = f.sum() * O.dt
    assert np.isfinite(f).all() and np.isfinite(p["x"]).all() and np.isfinite(p["v"]).all()
    assert impulse == pytest.approx(px0 - (p["mass"] * p["v"][:, 0]).sum(), rel=1e-9)
    assert M * v <= impulse <= 1.15 * M * v
    hit = t[np.argmax(f > 0)] - O.dt
    window = (t > hit) & (t <= hit + L / v)
    mean = f[window].sum() * O.dt / (L / v)
    flux = GRAIN["density"] * v * v * h * w
    assert 0.85 * flux <= mean <= 1.1 * flux, mean / flux


# ====================================================================== flow-block friction
@pytest.mark.parametrize("mu", [0.0, 1.0])
def test_flow_block_friction_zero_and_one_on_a_30_degree_slope(mu):
    # A granular blob (mu_s 1.5, so it does not avalanche within itself) resting on the top
    # face of a fixed block, gravity tilted by 30 degrees. mu = 0: no tangential force at all,
    # so the blob's x momentum grows as M g sin(theta) t to round-off and its centre of mass
    # follows Eq 19 with mu = 0. mu = 1 > tan 30: the base sticks; the block carries the blob's
    # whole weight M g (both components, 1 %), the total flow force never leaves the Coulomb
    # cone, and the base layer moves less than 2 % of the frictionless slide.
    th = math.radians(30.0)
    g = Vector3(9.81 * math.sin(th), 0, -9.81 * math.cos(th))
    dx, ppc = 0.01, 8
    rp = (3 * dx ** 3 / ppc / (4 * math.pi)) ** (1 / 3)  # Eq 13
    lo, hi = [0.10, 0.06, 0.06], [0.14, 0.10, 0.08]
    top = lo[2] + dx / 4 - rp  # the block's top face where the lowest points just touch it
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.0)
    block = sdem.box((0.09, 0.09, 0.02), 0.004, mat, pos=(0.13, 0.09, top - 0.02), fixed=True)
    mpm = mpmsdem.MpmEngine(grid={"dx": dx, "cells": [26, 18, 14], "origin": [0, 0, 0]},
                            material=dict(GRAIN, mu_s=1.5, mu_2=1.9), particles=[{"lo": lo, "hi": hi, "ppc": ppc}],
                            gravity=tuple(g), verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: {"friction": mu, "normalDamping": 0.3}}, verbose=False)
    forces = []
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=g, damping=0),
                 _every_step(lambda: forces.append(tuple(coupled.force(block))))]
    O.dt = 0.5 * mpm.stableTimeStep()
    p = mpm.particles()
    M, x0 = p["mass"].sum(), p["x"].copy()
    base = x0[:, 2] < lo[2] + dx / 2
    mpmsdem.run(int(0.1 / O.dt), coupled)
    f = np.array(forces)
    p = mpm.particles()
    t = O.time
    slide = analysis.slidingDistance(t, 30.0, 0.0)
    assert np.isfinite(f).all() and np.isfinite(p["x"]).all()
    if mu == 0:
        assert not f[:, 0].any() and not f[:, 1].any()
        assert (p["mass"] * p["v"][:, 0]).sum() == pytest.approx(M * g[0] * t, rel=1e-9)
        assert ((p["x"] - x0)[:, 0] * p["mass"]).sum() / M == pytest.approx(slide, rel=2e-3)
    else:
        late = f[int(0.7 * len(f)):].mean(axis=0)
        W = M * 9.81
        assert late[0] == pytest.approx(W * math.sin(th), rel=0.01)
        assert late[2] == pytest.approx(-W * math.cos(th), rel=0.01)
        assert abs(late[1]) < 1e-9 * W
        assert (np.hypot(f[:, 0], f[:, 1]) <= mu * np.abs(f[:, 2]) * (1 + 1e-9)).all()  # Coulomb (Eq 9)
        assert np.abs((p["x"] - x0)[base, 0]).max() < 0.02 * slide


# ====================================================================== single precision
def test_single_precision_coupled_impact_agrees_with_double():
    # The 45-degree impact in float on the CPU: the coupling sums stay double, the particle
    # state is float, so momentum holds to float round-off (1e-5) and the block's final
    # velocity agrees with the double run to 1e-4 (positions drift by 1.2e-7 x per step at
    # most, docs/physics.md).
    mpm, coupled, cube = _blobAndBlock(yawDeg=45.0, precision="float")
    assert mpm.solver.name == "cpu-float"
    O.dt = 2e-5
    p0, rise, contacts = _impact(mpm, coupled, cube, 25)
    vf = O.bodies[cube].state.vel[0]
    assert contacts >= 8 and rise <= 1e-6
    assert np.linalg.norm(_momentum(mpm, cube) - p0) <= 1e-5 * np.linalg.norm(p0)
    assert np.isfinite(mpm.particles()["x"]).all() and np.isfinite(mpm.particles()["v"]).all()
    O.reset()
    mpm, coupled, cube = _blobAndBlock(yawDeg=45.0)
    O.dt = 2e-5
    _impact(mpm, coupled, cube, 25)
    assert vf == pytest.approx(O.bodies[cube].state.vel[0], rel=1e-4)
