#!/usr/bin/env python3
"""Calibration of the §3.2 flume (paper Appendix C): fit the flow's basal friction and its
maximum dynamic friction μ₂ — or any of the scene parameters listed below — so that the
simulated copper cube travels as far as measured (or the flow runs out as far).

    python3 examples/calibrate_flume.py --target travel=0.085
    python3 examples/calibrate_flume.py --target travel=0.085 --param basalFriction=0.1:0.3 \\
        --param mu_2=0.5:0.8 --fix dx=0.01 --workers 2
    python3 examples/calibrate_flume.py --target travel=0.085 --scheduler tcp://HOST:8786

Every candidate is one coupled run of examples/flume_block.py's scene (coarse: dx 0.02 m,
12,000 material points, a few minutes on one core), run as its own process by
mpmsdem.sweep; finished candidates are stored in ``--out``/runs.jsonl at once, so running
the same command again after an interruption goes on where it stopped. Writes
``calibration.png`` (loss per candidate and over the parameter plane) and
``calibration.json`` (the best parameters and the search's record) to ``--out``.

Parameters that can be fitted (``--param NAME=LOW:HIGH``) or fixed (``--fix NAME=VALUE``):
see :func:`flumeRun`. Measured quantities (``--target NAME=VALUE``): ``travel`` (the cube's
travel distance at the end of the run [m]) and ``runout`` (the flow front's distance
beyond the column's initial front at the end [m]).
"""
import argparse
import inspect
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from driver_runs import recordSteps  # noqa: E402  (standard library only)


def flumeRun(basalFriction=0.21, mu_2=0.65, mu_s=0.24, I0=0.279, sideWallFriction=0.0, blockFriction=0.67,
             flowFriction=0.21, inclineDeg=10.0, dx=0.02, ppc=8, duration=1.2, backend="cpu", precision="double",
             flipDampingRate=None, flipViscosity=None):
    """One coupled run of the §3.2 flume with the copper cube; returns the measured quantities.

    :param basalFriction: flow–bed friction [-] (Table 1: 0.21; Appendix C range 0.01–0.5).
    :param mu_2: maximum dynamic friction μ₂ of the μ(I) model [-] (Table 1: 0.65; Appendix C
        range 0.3–0.8; > mu_s).
    :param mu_s: static friction μ_s of the flow [-] (Table 1: 0.24).
    :param I0: inertial number scale I₀ of the μ(I) model [-] (0.279).
    :param sideWallFriction: flow–side wall friction [-] (0: smooth walls).
    :param blockFriction: cube–bed friction [-] (measured: 0.67).
    :param flowFriction: flow–cube friction [-] (0.21).
    :param inclineDeg: flume incline [deg] (10).
    :param dx: grid spacing [m] (coarse 0.02; the paper 0.01); :param ppc: points per cell (8).
    :param duration: simulated time [s] (1.2; the cube has stopped by then in the coarse scene).
    :param backend, precision: MPM backend and precision.
    :param flipViscosity: PIC viscosity of the flow's FLIP/PIC blend [m²/s] > 0 (the paper's,
        mpmsdem.mpm.PAPER_VISCOSITY: 0.05, α 0.99 per its 5e-6 s step at dx 0.01 m); None:
        the scene default (0.005). docs/physics.md.
    :param flipDampingRate: instead, the PIC damping per second [1/s] > 0 at this dx (α 0.99 per
        −ln(0.99)/rate of simulated time; the paper's: 2010 /s at dx 0.01 m).
    :returns: dict(travel [m], runout [m], rotation_deg (at the end), peak_force [N] (10 ms
        mean), first_touch [s] (first flow force on the cube; the duration if never),
        force_04 [N] (F_t, 10 ms mean, at 0.4 s), force_mean [N] (mean F_t over 0.4–0.7 s),
        rotation_04, rotation_05, rotation_07 [deg], t45 [s] (first time the cube has turned
        45°; the duration if never), max_rotation_deg, tilt_04, tilt_05, tilt_07, max_tilt_deg
        (tipping: the lean of the cube's up axis) and max_yaw_deg (turning on the bed, largest
        |yaw|) [deg] (mpmsdem.analysis.tiltAndYaw), speed_end [m/s] (the cube's downstream
        speed at the end), centre_speed_end [m/s] (its centre's), rest_time [s] (from when it stays
        at rest: mpmsdem.analysis.restTime; None if it moves at the end), flip_blend, particles);
        the quantities at times past the duration are left out.
    """
    import mpmsdem  # noqa: F401  (before yade: it finds YADE's folder in a plain python3)
    from yade import O
    scene = _flumeScene(basalFriction, mu_2, mu_s, I0, sideWallFriction, blockFriction, flowFriction, inclineDeg, dx,
                        ppc, backend, precision, flipDampingRate, flipViscosity)
    steps, every = recordSteps(duration, O.dt, RECORD_EVERY)
    scene.run(steps * O.dt, sampleEvery=every * O.dt)
    front = float(scene.mpm.particles()["x"][:, 0].max())
    return _flumeResults(scene.series(0), front, steps * O.dt, scene.mpm.numParticles, scene.flipBlend())


RECORD_EVERY = 0.002  # the cube's record interval [s]


def _flumeScene(basalFriction, mu_2, mu_s, I0, sideWallFriction, blockFriction, flowFriction, inclineDeg, dx, ppc,
                backend, precision, flipDampingRate, flipViscosity):
    """The Flume of flumeRun's parameters (see there), before its first step."""
    if not mu_2 > mu_s:
        raise ValueError("mu_2 = %r: must be > mu_s = %r (the mu(I) model's friction rises from mu_s to mu_2)"
                         % (mu_2, mu_s))
    from mpmsdem.flume import GLASS_BEADS, Flume
    from flume_block import copperCube
    granular = dict(GLASS_BEADS, mu_s=mu_s, mu_2=mu_2, I0=I0)
    cube = copperCube(friction=blockFriction, flowFriction=flowFriction)
    if flipDampingRate is not None and not (flipDampingRate > 0 and math.isfinite(flipDampingRate)):
        raise ValueError("flipDampingRate = %r /s: must be > 0 and finite (the paper's: 2010)" % (flipDampingRate,))
    if flipViscosity is not None and flipDampingRate is not None:
        raise ValueError("flipViscosity = %r and flipDampingRate = %r: give one (both set the blend)"
                         % (flipViscosity, flipDampingRate))
    ref = None if flipDampingRate is None else -math.log(0.99) / flipDampingRate
    return Flume(dx=dx, ppc=ppc, inclineDeg=inclineDeg, granular=granular, basalFriction=basalFriction,
                 sideWallFriction=sideWallFriction, blocks=[cube], backend=backend, precision=precision,
                 verbose=False, flipReferenceDt=ref, flipViscosity=flipViscosity)


def _flumeResults(s, front, duration, particles, blend):
    """flumeRun's dict from the cube's series ``s`` (keys of Flume.series) and the flow's front
    [m] at the end of a run of ``duration`` [s]."""
    from mpmsdem import analysis
    from flume_block import COLUMN, blockEvents
    peak, _ = analysis.peakMeanForce(s, 0.01)
    out = {"travel": float(s["travel"][-1]), "runout": front - COLUMN, "peak_force": peak, "particles": particles,
           "flip_blend": blend}
    out.update(blockEvents(s, duration))
    return out


def prepareFlume(folder, duration=1.2, **params):
    """Write flumeRun(duration=duration, **params) as a driver scene, ``folder``/scene.json, with
    ``folder``/case.json (the parameters, the steps to run, O.dt): run it with mpmsdem-run
    ``--steps`` (anywhere, a GPU machine included) and read it back with :func:`flumeResultOfDriver`;
    the driver gives flumeRun's results to round-off."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade import O
    from mpmsdem import driver
    # flumeRun's own parameters and defaults
    names = [n for n in inspect.signature(flumeRun).parameters if n != "duration"]
    unknown = set(params) - set(names)
    if unknown:
        raise ValueError("unknown parameter(s) %s: allowed %s" % (", ".join(sorted(unknown)), ", ".join(names)))
    bound = inspect.signature(flumeRun).bind(duration=duration, **params)
    bound.apply_defaults()
    scene = _flumeScene(**{n: bound.arguments[n] for n in names})
    steps, every = recordSteps(duration, O.dt, RECORD_EVERY)
    os.makedirs(folder, exist_ok=True)
    driver.writeScene(os.path.join(folder, "scene.json"), scene.coupled, duration=steps * O.dt, dt=O.dt,
                      seriesEvery=every * O.dt, outputEvery=steps * O.dt, vtk="none")
    with open(os.path.join(folder, "case.json"), "w") as f:
        json.dump({"params": dict(params, duration=duration), "steps": steps, "dt": O.dt,
                   "particles": scene.mpm.numParticles, "flip_blend": scene.flipBlend()}, f, indent=1)
    return folder


def flumeResultOfDriver(folder):
    """flumeRun's dict from a case that :func:`prepareFlume` wrote and mpmsdem-run ran into
    ``folder``/out (h5py, no YADE)."""
    import h5py
    from mpmsdem import analysis
    with open(os.path.join(folder, "case.json")) as f:
        meta = json.load(f)
    s, _ = analysis.driverBlockSeries(os.path.join(folder, "out"), initial=False)
    with h5py.File(os.path.join(folder, "out", "mpm.h5"), "r") as f:
        front = float(f["series/front_x"][-1])
    return _flumeResults(s, front, meta["steps"] * meta["dt"], meta["particles"], meta["flip_blend"])


def _pairs(items, what, form, convert):
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        try:
            if not (sep and name):
                raise ValueError
            out[name] = convert(value)
        except ValueError:
            raise SystemExit("%s %r: must be %s" % (what, item, form)) from None
    return out


def _range(text):
    lo, sep, hi = text.partition(":")
    if not sep:
        raise ValueError
    return float(lo), float(hi)


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--target", action="append", metavar="NAME=VALUE",
                    help="measured value to fit: travel=S [m] or runout=L [m] (one or both; required)")
    ap.add_argument("--param", action="append", metavar="NAME=LOW:HIGH",
                    help="a fitted parameter and its range (default: basalFriction=0.01:0.5 and mu_2=0.3:0.8, "
                         "Appendix C)")
    ap.add_argument("--fix", action="append", metavar="NAME=VALUE", help="a parameter held at a value, e.g. dx=0.01")
    ap.add_argument("--full", action="store_true",
                    help="the paper's resolution (dx 0.01 m) and blend (flipViscosity 0.05 m^2/s) for every candidate")
    ap.add_argument("--popsize", type=int, default=8, help="candidates per generation per fitted parameter (8)")
    ap.add_argument("--maxiter", type=int, default=20, help="generations after the first (20)")
    ap.add_argument("--threshold", type=float, default=1e-4,
                    help="stop at this loss, the sum of squared relative misfits (1e-4: 1 %%)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the search; keep it to resume (1)")
    ap.add_argument("--workers", type=int, default=1, help="local candidates at a time (1)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask scheduler address (tcp://host:8786): run the candidates on its workers instead")
    ap.add_argument("--retries", type=int, default=2, help="extra attempts of a failed candidate (2)")
    ap.add_argument("--timeout", type=float, default=None, help="limit of one candidate [s] (none)")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each candidate (1)")
    ap.add_argument("--out", default="results/calibrate_flume", help="results folder")
    a = ap.parse_args(argv)
    if not a.target:
        ap.error("--target is required: the measured value to fit, e.g. --target travel=0.085 [m]")
    a.targets = _pairs(a.target, "--target", "NAME=VALUE, e.g. travel=0.085", float)
    from mpmsdem.calibrate import APPENDIX_C_BOUNDS
    from mpmsdem.mpm import PAPER_VISCOSITY
    a.bounds = _pairs(a.param, "--param", "NAME=LOW:HIGH, e.g. mu_2=0.3:0.8", _range) or dict(APPENDIX_C_BOUNDS)
    a.fixed = _pairs(a.fix, "--fix", "NAME=VALUE, e.g. dx=0.01", float)
    blends = sorted({"flipDampingRate", "flipViscosity"} & (set(a.fixed) | set(a.bounds)))
    if len(blends) > 1:
        raise SystemExit("--fix/--param %s: give one (both set the flow's FLIP/PIC blend)" % " and ".join(blends))
    if a.full:
        a.fixed["dx"] = 0.01
        if not {"flipDampingRate", "flipViscosity"} & (set(a.fixed) | set(a.bounds)):
            a.fixed["flipViscosity"] = PAPER_VISCOSITY  # the paper's blend
    if "ppc" in a.fixed:
        a.fixed["ppc"] = int(a.fixed["ppc"])
    if "mu_2" in a.bounds and not a.bounds["mu_2"][0] > a.fixed.get("mu_s", 0.24):
        raise SystemExit("--param mu_2=%g:%g: the lower bound must be > mu_s = %g" % (
            a.bounds["mu_2"] + (a.fixed.get("mu_s", 0.24),)))
    return a


def main(argv):
    a = parse(argv)
    from mpmsdem import calibrate
    os.makedirs(a.out, exist_ok=True)
    try:
        fit = calibrate.calibrate("%s:flumeRun" % os.path.abspath(__file__), bounds=a.bounds, targets=a.targets,
                                  store=os.path.join(a.out, "runs.jsonl"), fixed=a.fixed, popsize=a.popsize,
                                  maxiter=a.maxiter, threshold=a.threshold, seed=a.seed, workers=a.workers,
                                  scheduler=a.scheduler, retries=a.retries, timeout=a.timeout, threads=a.threads,
                                  plot=os.path.join(a.out, "calibration.png"))
    except (ValueError, ConnectionError) as e:  # bad arguments: the message names them, a traceback adds nothing
        raise SystemExit("calibrate_flume.py: %s" % e) from None
    with open(os.path.join(a.out, "calibration.json"), "w") as f:
        json.dump(dict(fit, targets=a.targets, bounds=a.bounds, fixed=a.fixed), f, indent=1)
    print("best: %s; outputs in %s (calibration.png, calibration.json, runs.jsonl)"
          % (", ".join("%s = %.4g" % kv for kv in fit["params"].items()), a.out))
    return fit


if __name__ == "__main__":
    main(sys.argv[1:])
