#!/usr/bin/env python3
"""Paper §5: a glass-bead column released in the inclined flume hits a 0.05 m copper cube;
20 runs over the column's aspect ratio AR = H_i/L_i (1.3 to 4.0) and the block-to-column
distance L0 (4 to 74 h_b). Each run is the paper's pair of simulations: a free flow without
the cube (flow depth h_f and velocity v_f at the cube's station when the front arrives,
Fr = v_f/√(g h_f), Fr1 = v_f/√(g L0)), then the coupled run (travel S_b, peak and static
flow force on the cube).

One case (defaults AR = 1.3, L0/h_b = 4):
    yade -n -x examples/parametric_study.py            (or /usr/bin/python3 ...)
The 20 cases with yade-batch, one YADE process per table line, 2 at a time:
    yade-batch -j 2 --job-threads=1 examples/parametric_study.table examples/parametric_study.py
The 20 cases through mpmsdem.sweep (resumable store, retries, progress; local processes or a
Dask cluster):
    python3 examples/parametric_study.py --sweep --workers 2
    python3 examples/parametric_study.py --sweep --scheduler tcp://HOST:8786
Then: python3 examples/parametric_study_summary.py     (Figs 14, 16b, 19a, 19b)
Through the plain C++ driver (a machine without YADE, e.g. a GPU machine; the same scenes,
probe and results):
    python3 examples/parametric_study.py --prepare DIR --full         (here, with YADE)
    python3 examples/parametric_study.py --run-prepared DIR [--backend cuda] [--workers N]   (needs only mpmsdem-run)
    python3 examples/parametric_study.py --collect DIR                (h5py; then the summary on DIR)
The coupled runs last until the front's arrival + 1.5 s; ``--until 4.5`` runs them to the
paper's 4.5 s (§5.4: "when the system approaches quasi-steady state") in every mode, and with
--run-prepared continues cases that ended earlier from their last snapshot. --run-prepared also
resumes a case that was stopped part-way (killed): its finished free flow is kept and its
coupled run goes on from its last snapshot. Its coupled runs start from the free flow's state
when the front is AHEAD cells short of the cube (mpmsdem-run --flow-from): the run from the
release to the last bit, without the flow's way to the cube.

Resolution: coarse by default (dx = 0.02 m, 8 points per cell); table column ``full = 1`` or
``--full``: the paper's (dx = 0.01 m). A coarse case takes from 6 minutes on one core (AR 1.3,
L0/h_b 4, 24,000 material points) to about an hour (AR 4, L0/h_b 74: 72,000 points in a 5 m
flume); the paper's resolution about 16 times more.

Set-up (our reading of §5 and §3.2): the §3.2 flume (width 0.2 m, incline 10°, glass beads
of Table 1, basal friction 0.21, no gate: the column starts free) with a column of length
L_i = 0.3 m and height H_i = AR · L_i (rounded to the grid: the coarse grid makes AR = 1.3 a
column of 0.40 m, AR 1.33; the reported AR is the one simulated), the cube's upstream face at
L_i + L0, and a flume long enough for the flow to carry the cube without reaching its end
wall: L_i + L0 + h_b + ``margin`` (3 m by default: at the paper's blend a cube slid 1.2 m). Runs
to the paper's 4.5 s need more: at the paper's resolution and blend the fronts are then about
4.5, 6.75, 11.0 and 15 m from the column's back wall at AR 1.3, 2.0, 3.0 and 4.0 (docs/studies.md;
``FRONT_AT_END``); --prepare says when a flume is shorter, with the margin that gives room. A cube
still carried when the front reaches the end wall is flagged ``cube_at_end``.
"""
import argparse
import json
import os
import sys
import time

HB = 0.05          # cube side h_b [m] (paper §5)
COLUMN = 0.3       # column length L_i [m] (the §3.2 storage container)
RHO = 1600.0       # bulk density of the glass beads [kg/m³] (Table 1)
K_STATIC = 1.6     # static pressure coefficient of the paper's Eq 21 fit
MARGIN = 3.0       # flume length downstream of the cube [m]
# (AR, the front's distance from the column's back wall at the paper's 4.5 s [m]) at the paper's
# resolution and blend: AR 2.0 and 3.0 measured (docs/studies.md, flumes long enough), AR 1.3 about,
# AR 4.0 from its front's slowing (its runs reached the end wall)
FRONT_AT_END = ((1.3, 4.5), (2.0, 6.75), (3.0, 11.0), (4.0, 15.0))
END_ROOM = 1.0     # flume length kept beyond that front [m]
PROBE_EVERY = 0.005   # free flow: the station is read every this much simulated time [s]
PROBE_WINDOW = 0.05   # h_f, v_f: means over this long after the front's arrival [s]
FRONT_STILL = 0.3     # free flow: a front that has not advanced dx/2 for this long has stopped [s]
SAMPLE_EVERY = 0.002  # coupled run: the cube's record interval [s]
ENERGY_EVERY = 0.01   # coupled run: the energies kept in the results (Fig 17) every this long [s]
MOVING = 0.01         # a cube faster than this [m/s] is still carried
STATIC_FLOOR = 0.01   # a static force below this fraction of the peak: nothing rests against the cube (no ratio)
AHEAD = 8             # driver: the free flow saves its state when its front is this many cells short of the cube,
                      # and the coupled run starts there (mpmsdem-run --flow-from) instead of at the release
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from driver_runs import (STOPPED_EXIT, DriverStopped, eachCase, recordSteps, runDriver,  # noqa: E402
                         stepsOf, stopDriversOnSignals)  # (standard library only)


def resolution(full, dx=None, ppc=None):
    """(dx [m], points per cell) of a run: coarse (0.02, 8) or, with ``full``, the paper's (0.01, 8)."""
    dx = dx or (0.01 if full else 0.02)
    if not dx > 0:
        raise ValueError("dx = %r m: must be > 0" % (dx,))
    return dx, ppc or 8


def runCase(AR, L0_hb, full=0, dx=None, ppc=None, settle=1.5, margin=MARGIN, maxFreeTime=5.0, output=None,
            backend="cpu", precision="double", verbose=False, until=None):
    """One case of the study: free flow, then the coupled run. Returns a dict of the results.

    :param AR: aspect ratio H_i / L_i of the column [-], > 0 (paper: 1.3 to 4.0).
    :param L0_hb: block-to-column distance L0 in cube heights [-], > 0 (paper: 4 to 74).
    :param full: 0 (default): coarse grid; 1: the paper's resolution.
    :param dx: grid spacing [m] (default 0.02, full 0.01); :param ppc: points per cell (8).
    :param settle: coupled run lasts until the front's arrival + settle [s] (default 1.5),
        rounded up to whole record intervals (2 ms); the static force is the mean flow force
        on the cube over its last 0.1 s.
    :param until: None (default), or the coupled run lasts at least until this time [s] (the
        paper's runs end at 4.5 s, "when the system approaches quasi-steady state", §5.4).
    :param margin: flume length downstream of the cube [m] (default 3).
    :param maxFreeTime: the free flow gives up after this [s] (default 5).
    :param output: folder for the coupled run's HDF5 and ParaView files (default none).
    :param backend, precision: MPM backend ("cpu"/"cuda") and precision ("double"/"float").
    """
    import mpmsdem  # before yade: it finds YADE's folder in a plain python3
    from yade import O
    from mpmsdem import analysis
    from mpmsdem.flume import Flume
    common, out = _setup(AR, L0_hb, full, dx, ppc, margin, backend, precision, verbose)
    station = COLUMN + out["L0"]

    t0 = time.time()
    scene = Flume(**common)
    out["particles"] = scene.mpm.numParticles
    out["flip_blend"] = scene.flipBlend()
    probe = analysis.FlowProbe(station, halfWidth=out["dx"], bedZ=0.0, L0=out["L0"], window=PROBE_WINDOW)
    front, frontAt = 0.0, 0.0
    while True:
        mpmsdem.run(stepsOf(PROBE_EVERY, O.dt), scene.coupled)
        p = scene.mpm.particles()
        probe.sample(O.time, p)
        if probe.arrival is not None and O.time > probe.arrival + probe.window:
            break
        x = float(p["x"][:, 0].max())
        if x > front + 0.5 * out["dx"]:
            front, frontAt = x, O.time
        if O.time - frontAt > FRONT_STILL or O.time > maxFreeTime:  # the flow stopped short of the station
            out.update(reached=False, front=front, stopped_at=O.time, wall_seconds={"free_flow": time.time() - t0})
            return out
    ff = probe.result()
    tFree = time.time() - t0

    t1 = time.time()
    scene = Flume(blocks=[_cube(station)], output=output, outputEvery=0.01, vtkEvery=0.05 if output else None,
                  **common)
    potential0 = scene.mpm.diagnostics()["potential_energy"]
    steps, every = coupledSteps(ff["arrival"], settle, until, O.dt)
    scene.run(steps * O.dt, sampleEvery=every * O.dt)
    _coupledResults(out, ff, scene.series(0), steps * O.dt, potential0)
    out["wall_seconds"] = {"free_flow": tFree, "coupled": time.time() - t1}
    return out


def coupledSteps(arrival, settle, until, dt):
    """(steps, record interval in steps) of a case's coupled run of step ``dt`` [s]: to the
    front's arrival + settle, or to ``until`` [s] if later (None: no such end), in whole record
    intervals."""
    if until is not None and not until > 0:
        raise ValueError("until = %r s: must be > 0 (or None)" % (until,))
    return recordSteps(max(arrival + settle, until or 0.0), dt, SAMPLE_EVERY)


def _setup(AR, L0_hb, full, dx, ppc, margin, backend, precision, verbose):
    """A case's geometry: (the Flume arguments its two runs share, the start of its result
    dict)."""
    from mpmsdem.mpm import PAPER_VISCOSITY
    if not (AR > 0 and L0_hb > 0):
        raise ValueError("AR = %r, L0_hb = %r: both must be > 0" % (AR, L0_hb))
    if not margin > 0:
        raise ValueError("margin = %r m: must be > 0" % (margin,))
    dx, ppc = resolution(full, dx, ppc)
    H = round(max(1, round(AR * COLUMN / dx)) * dx, 12)  # the column's top on a grid line
    L0 = L0_hb * HB
    length = COLUMN + L0 + HB + margin
    # the paper's blend (α 0.99 per 5e-6 s, 2010 /s) at the paper's resolution (docs/physics.md)
    common = dict(length=length, columnLength=COLUMN, columnHeight=H, dx=dx, ppc=ppc, backend=backend,
                  precision=precision, verbose=verbose, flipViscosity=PAPER_VISCOSITY if full else None)
    result = {"AR": round(H / COLUMN, 6), "AR_nominal": AR, "L0_hb": L0_hb, "L0": L0, "h_b": HB, "H_i": H,
              "L_i": COLUMN, "dx": dx, "ppc": ppc, "flume_length": length, "margin": margin}
    return common, result


def _cube(station):
    from mpmsdem.flume import Block
    return Block(half=(HB / 2,) * 3, x=station, density=8900, friction=0.67, flowFriction=0.21)


def _coupledResults(out, ff, s, duration, potential0, before=None):
    """The coupled run's results into ``out`` from the cube's series ``s`` (the keys of
    Flume.series, the flow's front among them), the free flow ``ff`` (FlowProbe.result) and the
    flow's potential energy at the start, ``potential0`` [J] (zero at the bed under the column's
    upstream end): the energies of the paper's Figs 17 and 18 (the flow's kinetic peak and its
    time; the cube's largest kinetic energy E_k,max^b and its ratio to E_p,0^f). ``before``: the
    flow's energies before the first record of ``s`` (t, flow_kinetic, flow_potential,
    block_kinetic), for a run that started later than the release."""
    from mpmsdem import analysis
    peak, tPeak = analysis.peakMeanForce(s, 0.01)
    # the same over 50 ms: past the first 10-20 ms of a blow, whose size the flow's E sets
    peakLong, _ = analysis.peakMeanForce(s, 0.05)
    static = analysis.meanForceBetween(s, max(s["t"][0], s["t"][-1] - 0.1), s["t"][-1])  # its last 0.1 s
    A = min(ff["h_f"], HB) * HB  # impact area: the flow's depth on the cube's face, at most its height
    travel = float(s["travel"][-1])
    # A cube carried to the flume's end, pushed back by the flow the end wall turned (a
    # negative force at the end once the front has reached the wall), or still carried when the
    # front reached the wall (the flow piles against it instead of running on), has a travel
    # cut short by the end wall: flagged, and left out of the travel fits by the summary (give
    # such a case a larger margin). A negative force while the front is still short of the
    # wall is the flow holding back a cube that runs ahead of it: its travel stands.
    atWall = s["flow_front"] > out["flume_length"] - 0.1
    wallTime = float(s["t"][atWall.argmax()]) if atWall.any() else None
    carriedPastWall = wallTime is not None and bool((abs(s["vx"][s["t"] >= wallTime]) > MOVING).any())
    atEnd = (out["L_i"] + out["L0"] + travel + HB > out["flume_length"] - 0.1 or (static < 0 and wallTime is not None)
             or carriedPastWall)
    out.update(reached=True, free_flow=ff, submersion=analysis.submersion(ff["h_f"], HB), travel=travel,
               travel_L0=travel / out["L0"], cube_at_end=atEnd, front_at_wall_time=wallTime,
               carried_past_wall=carriedPastWall, duration=duration, peak_force=peak, peak_time=tPeak,
               peak_force_50ms=peakLong,
               static_force=static, force_ratio=peak / static if static > STATIC_FLOOR * peak else None,
               static_force_model=analysis.staticImpactForce(RHO, ff["h_f"], A, k=K_STATIC),
               eq20_force=analysis.hydrodynamicForce(RHO, ff["v_f"], ff["h_f"], A),
               rotation_deg=float(s["rotation"][-1]), speed_end=float(abs(s["vx"][-1])),
               flow_potential_0=potential0)
    early = before if before is not None and len(before["t"]) else None
    for key in ("flow_kinetic", "block_kinetic"):
        t, e = s["t"], s[key]
        if early:
            t, e = list(early["t"]) + list(t), list(early[key]) + list(e)
        i = max(range(len(e)), key=lambda k: e[k])
        out.update({key + "_max": float(e[i]), key + "_max_time": float(t[i])})
    out["block_kinetic_ratio"] = out["block_kinetic_max"] / potential0
    out["energy"] = energySeries(s, potential0)
    if early:
        head = energySeries(early, potential0)
        out["energy"] = {k: head[k] + out["energy"][k] for k in head}
    out["flow_dissipated_end"] = out["energy"]["dissipated"][-1]
    touch = analysis.touchTime(s)
    if touch is not None and analysis.forceSource(s) == "impulse":  # the blow by parts after the touch
        out.update(first_touch=touch, blow_parts=analysis.blowParts(s),
                   blow_line_of_action=analysis.blowLineOfAction(s))


def energySeries(s, potential0):
    """Fig 17's energies over the flow's initial potential energy E_p,0^f, every ENERGY_EVERY
    and at the run's end, from the coupled run's records ``s`` (t, flow_potential, flow_kinetic,
    block_kinetic): E_p^f, E_k^f, E_k^b and the energy dissipated, E_d = E_p,0^f - E_p^f - E_k^f
    - E_k^b, the mechanical energy the flow and the cube have lost (the cube's own potential
    energy, about 1 J against the flow's hundreds, is left out). E_p^f is zero at the bed under
    the column's upstream end, so a flow that runs far down the 10° flume dissipates more than
    E_p,0^f."""
    t = [float(x) for x in s["t"]]
    every = max(1, int(round(ENERGY_EVERY / (t[1] - t[0])))) if len(t) > 1 else 1
    keep = list(range(0, len(t), every))
    if keep[-1] != len(t) - 1:
        keep.append(len(t) - 1)
    out = {"t": [t[i] for i in keep]}
    for key, name in (("flow_potential", "flow_potential"), ("flow_kinetic", "flow_kinetic"),
                      ("block_kinetic", "block_kinetic")):
        out[name] = [float(s[key][i]) / potential0 for i in keep]
    out["dissipated"] = [1.0 - p - k - b for p, k, b in zip(out["flow_potential"], out["flow_kinetic"],
                                                                out["block_kinetic"])]
    return out


# ---------------------------------------------------------------- through the C++ driver
# A case folder holds case.json, free.json (the free flow with its probe at the station) and
# coupled.json (the flow with the cube); --run-prepared writes free/ and coupled/ (the driver's
# outputs) and run.json (wall times, backend) there; --collect turns them into the result dict
# of runCase, one CASE.json beside the case folders.

def prepareCase(AR, L0_hb, folder, full=0, dx=None, ppc=None, settle=1.5, margin=MARGIN, maxFreeTime=5.0,
                backend="cpu", precision="double", startAhead=True):
    """Write one case's two driver scenes and case.json into ``folder`` (created). The scenes
    are the ones runCase runs (the same O.dt, records at the same steps): the driver's results
    are runCase's to round-off. With ``startAhead`` (default) the free flow saves its state
    when its front is AHEAD cells short of the cube, and --run-prepared starts the coupled run
    there: the same run, bit for bit, without its flow's way to the cube (the energies before
    that state come from the free flow's records, every PROBE_EVERY). Returns the folder."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade import O
    from mpmsdem import driver
    from mpmsdem.flume import Flume
    common, result = _setup(AR, L0_hb, full, dx, ppc, margin, backend, precision, False)
    station = COLUMN + result["L0"]
    os.makedirs(folder, exist_ok=True)
    scene = Flume(**common)
    result["particles"] = scene.mpm.numParticles
    result["flip_blend"] = scene.flipBlend()
    probe = {"x": station, "halfWidth": result["dx"], "bedZ": 0.0, "window": PROBE_WINDOW}
    ahead = {"snapshotWhenFrontAt": station - AHEAD * result["dx"]} if startAhead else {}
    driver.writeScene(os.path.join(folder, "free.json"), scene.coupled, duration=maxFreeTime, dt=O.dt,
                      flowProbes=[probe], seriesEvery=stepsOf(PROBE_EVERY, O.dt) * O.dt, outputEvery=maxFreeTime,
                      vtk="none", stopWhenProbed=True, stopWhenFrontStill=FRONT_STILL, **ahead)
    dt = O.dt
    scene = Flume(blocks=[_cube(station)], **common)
    if O.dt != dt:
        raise RuntimeError("the free flow and the coupled run chose different steps (%r, %r s)" % (dt, O.dt))
    # run.duration bounds the run; --run-prepared runs the steps that runCase would (--steps)
    driver.writeScene(os.path.join(folder, "coupled.json"), scene.coupled, duration=maxFreeTime + settle, dt=O.dt,
                      seriesEvery=stepsOf(SAMPLE_EVERY, O.dt) * O.dt, outputEvery=0.5, vtk="none")
    with open(os.path.join(folder, "case.json"), "w") as f:
        json.dump({"name": caseName(AR, L0_hb, full, dx), "settle": settle, "dt": O.dt, "result": result}, f,
                  indent=1)
    return folder


def runPrepared(folder, exe="mpmsdem-run", backend=None, precision=None, threads=None, rerun=False, until=None,
                workers=1):
    """Run the prepared cases under ``folder`` through the driver, ``workers`` at a time (each
    its own mpmsdem-run; on a GPU, small cases leave room for several): the free flow, then
    (if its front reached the station) the coupled run to the arrival + settle, or to
    ``until`` [s] if later (see runCase), from the free flow's state ahead of the cube where it
    saved one (prepareCase's ``startAhead``). Standard library only (no YADE, numpy or h5py): it
    runs where only mpmsdem-run is built. A case with run.json is done and skipped unless
    ``rerun``, or unless its coupled run ended before ``until``: that run then goes on from
    its last snapshot (mpmsdem-run --restart, the same run as one to ``until``). A case
    stopped part-way (killed, or the machine went away) resumes: its finished free flow is
    kept (run.partial.json) and its coupled run goes on from its last snapshot (every 0.5 s, and
    where a signal stopped it: the command line passes SIGINT and SIGTERM on to the drivers, which
    save their state; DriverStopped is then raised). Returns the case folders run, in name order."""
    cases = [os.path.join(folder, name) for name in sorted(os.listdir(folder))
             if os.path.isfile(os.path.join(folder, name, "case.json"))]

    def runOne(case):
        with open(os.path.join(case, "case.json")) as f:
            meta = json.load(f)

        def drive(scene, out, extra=()):
            return runDriver(exe, os.path.join(case, scene), os.path.join(case, out), os.path.join(case, out + ".log"),
                             extra, backend, precision, threads)

        if os.path.exists(os.path.join(case, "run.json")) and not rerun:
            if _extend(case, meta, until, drive):
                return True
            print("%s: done before (run.json), skipped" % os.path.basename(case))
            return False
        how = {"backend": backend or "scene's", "precision": precision or "scene's", "exe": exe}
        _runCaseFolder(case, meta, until, drive, how, restart=not rerun)
        return True

    return [case for case, ran in zip(cases, eachCase(runOne, cases, workers)) if ran]


def _runCaseFolder(case, meta, until, drive, how, restart):
    """The free flow and the coupled run of one prepared case (``how``: backend, precision and
    driver, recorded); writes run.json at the end. What has finished is kept in run.partial.json
    as it finishes; with ``restart`` a case stopped part-way goes on from there (the coupled run
    from coupled/coupled.checkpoint.json; its wall seconds add up the legs, the stopped ones
    kept in run.partial.json as coupled_seconds_before)."""
    partialPath = os.path.join(case, "run.partial.json")
    record = {}
    if restart and os.path.exists(partialPath):
        with open(partialPath) as f:
            record = json.load(f)

    def keep():
        with open(partialPath, "w") as f:
            json.dump(record, f, indent=1)

    name = os.path.basename(case)
    if "free_flow_seconds" not in record:
        record = dict(how, free_flow_seconds=drive("free.json", "free"))
        keep()
    elif restart:
        print("%s: free flow done before (run.partial.json), kept" % name)
    probe = _freeFlow(case)["probes"][0]
    if probe["complete"]:
        steps, _ = coupledSteps(probe["arrival"], meta["settle"], until, meta["dt"])
        start = 0
        if record.get("coupled_started") and os.path.exists(_checkpointPath(case)):
            start = min(_checkpointStep(case), steps)
        record.update(coupled_steps=steps, coupled_started=True)
        keep()
        seconds = 0.0
        if start == 0:
            record.pop("coupled_seconds_before", None)  # a run from its start: earlier legs do not count
        front = _frontSnapshot(case)
        legStart = time.time()
        try:
            if start == 0 and front is not None and front["step"] < steps:
                record["coupled_from_step"] = front["step"]
                keep()
                seconds = drive("coupled.json", "coupled",
                                ["--flow-from", os.path.join(case, "free"), "--steps", str(steps - front["step"])])
            elif start == 0:
                record.pop("coupled_from_step", None)
                seconds = drive("coupled.json", "coupled", ["--steps", str(steps)])
            elif start < steps:
                print("%s: coupled run resumed from step %d of %d" % (name, start, steps))
                record.setdefault("resumed_from_steps", []).append(start)
                seconds = drive("coupled.json", "coupled", ["--restart", "--steps", str(steps - start)])
        except BaseException:
            record["coupled_seconds_before"] = record.get("coupled_seconds_before", 0.0) + time.time() - legStart
            keep()
            raise
        record["coupled_seconds"] = seconds + record.pop("coupled_seconds_before", 0.0)
    record.pop("coupled_started", None)
    with open(os.path.join(case, "run.json"), "w") as f:
        json.dump(record, f, indent=1)
    os.remove(partialPath)
    print("%s: free flow %.0f s%s" % (name, record["free_flow_seconds"],
                                      ", coupled %.0f s" % record["coupled_seconds"] if probe["complete"]
                                      else ", the front did not reach the station"))


def _extend(case, meta, until, drive):
    """Continue a case's finished coupled run to ``until`` [s] if it ended before: from its last
    snapshot (coupled/coupled.checkpoint.json) to the step runCase(until=...) would end on.
    Updates run.json. Returns whether it ran."""
    with open(os.path.join(case, "run.json")) as f:
        record = json.load(f)
    if until is None or "coupled_steps" not in record:
        return False
    steps, _ = coupledSteps(_freeFlow(case)["probes"][0]["arrival"], meta["settle"], until, meta["dt"])
    if steps <= record["coupled_steps"]:
        return False
    start = _checkpointStep(case)
    seconds = drive("coupled.json", "coupled", ["--restart", "--steps", str(steps - start)])
    record.update(coupled_steps=steps, coupled_seconds=record["coupled_seconds"] + seconds, until=until)
    with open(os.path.join(case, "run.json"), "w") as f:
        json.dump(record, f, indent=1)
    print("%s: coupled run continued from step %d to %d (until %g s), %.0f s" % (os.path.basename(case), start, steps,
                                                                                until, seconds))
    return True


def _checkpointPath(case):
    return os.path.join(case, "coupled", "coupled.checkpoint.json")


def _checkpointStep(case):
    """The step of the coupled run's last snapshot, the one mpmsdem-run --restart goes on from."""
    with open(_checkpointPath(case)) as f:
        return json.load(f)["step"]


def _frontSnapshot(case):
    """The state the free flow saved ahead of the cube (free/front_snapshot.json), or None (a
    case prepared without it, or a flow that never came so far)."""
    path = os.path.join(case, "free", "front_snapshot.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def _flowBefore(case, t):
    """The free flow's records before ``t`` [s] (t, flow_kinetic, flow_potential, block_kinetic
    0: the cube at rest before the flow comes) and its potential energy at the release, from
    free/coupled.h5: what a coupled run started from the free flow's state does not record."""
    import h5py
    with h5py.File(os.path.join(case, "free", "coupled.h5"), "r") as f:
        g = f["series"]
        times = g["time"][:]
        keep = (times > 0) & (times < t * (1 - 1e-12))  # (no record at the release: as runCase's series)
        out = {"t": times[keep], "flow_kinetic": g["flow_kinetic"][:][keep],
               "flow_potential": g["flow_potential"][:][keep]}
        potential0 = float(g["flow_potential"][0])
    out["block_kinetic"] = 0.0 * out["t"]
    return out, potential0


def _freeFlow(case):
    """What the driver's free flow of a case folder reported (free/flow_probes.json)."""
    with open(os.path.join(case, "free", "flow_probes.json")) as f:
        return json.load(f)


def collectCase(case):
    """The result dict of runCase from a case folder that --run-prepared ran."""
    from mpmsdem import analysis
    with open(os.path.join(case, "case.json")) as f:
        meta = json.load(f)
    with open(os.path.join(case, "run.json")) as f:
        record = json.load(f)
    run = _freeFlow(case)
    out = dict(meta["result"], driver=record)
    probe = run["probes"][0]
    out["wall_seconds"] = {"free_flow": record["free_flow_seconds"]}
    if not probe["complete"]:
        out.update(reached=False, front=run["front_x"], stopped_at=run["time"])
        return out
    h, v = probe["h_f"], probe["v_f"]
    ff = {"arrival": probe["arrival"], "h_f": h, "v_f": v, "Fr": analysis.froude(v, h),
          "Fr1": analysis.froudeDistance(v, out["L0"])}
    s, _ = analysis.driverBlockSeries(os.path.join(case, "coupled"))
    if "flow_front" not in s:
        raise ValueError("%s: no mpm.h5 beside coupled.h5 (the flow's front series)" % os.path.join(case, "coupled"))
    before = None
    if record.get("coupled_from_step"):  # started from the free flow's state: its records before
        before, potential0 = _flowBefore(case, float(s["t"][0]))
    else:
        potential0 = float(s["flow_potential"][0])  # the driver's record at the start
    _coupledResults(out, ff, {k: v[1:] for k, v in s.items()}, record["coupled_steps"] * meta["dt"], potential0,
                    before)
    out["wall_seconds"]["coupled"] = record["coupled_seconds"]
    return out


def caseName(AR, L0_hb, full=0, dx=None):
    """A case's name: AR, L0/h_b, the paper's resolution, and a spacing given apart from it (a
    refinement's runs of one case side by side in one folder)."""
    return "AR=%g_L0hb=%g%s%s" % (AR, L0_hb, "_full" if full else "", "_dx%g" % dx if dx else "")


def readTable(path):
    """The table's lines as parameter dicts (read as yade-batch reads them)."""
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade.utils import TableParamReader
    rows = []
    for _, row in sorted(TableParamReader(path).paramDict().items()):
        case = {}
        for k, v in row.items():
            if k == "description":
                continue
            try:
                f = float(v)
            except ValueError:
                raise ValueError("%s: %s = %r is not a number" % (path, k, v)) from None
            case[k] = int(f) if f.is_integer() and "." not in v else f
        rows.append(case)
    return rows


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sweep", action="store_true", help="run the table's cases through mpmsdem.sweep")
    ap.add_argument("--table", default=os.path.join(HERE, "parametric_study.table"),
                    help="cases, one per line (default: the 20 of examples/parametric_study.table)")
    ap.add_argument("--full", action="store_true", help="the paper's resolution (dx 0.01 m) for every case")
    ap.add_argument("--workers", type=int, default=1,
                    help="local runs at a time, also of --run-prepared's cases (default 1)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask scheduler address (tcp://host:8786): run the cases on its workers instead")
    ap.add_argument("--retries", type=int, default=2, help="extra attempts of a failed case (default 2)")
    ap.add_argument("--timeout", type=float, default=None, help="limit of one case [s] (default none)")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each case (default 1)")
    ap.add_argument("--out", default="results/parametric_study",
                    help="results folder: the sweep's store runs.jsonl, or one JSON file per case")
    ap.add_argument("--AR", type=float, default=None, help="one case: aspect ratio (default 1.3)")
    ap.add_argument("--L0-hb", type=float, default=None, help="one case: L0 / h_b (default 4)")
    ap.add_argument("--margin", type=float, default=None,
                    help="flume length beyond the cube [m] where the table gives none (default %g; to 4.5 s at "
                         "AR 3.0 and 4.0 the flows need about 11 and 15 m from the column)" % MARGIN)
    ap.add_argument("--prepare", metavar="DIR", default=None,
                    help="write the driver scenes of the table's cases (or of --AR/--L0-hb) into DIR/CASE")
    ap.add_argument("--run-prepared", metavar="DIR", default=None,
                    help="run the prepared cases in DIR through mpmsdem-run (no YADE needed)")
    ap.add_argument("--collect", metavar="DIR", default=None,
                    help="results of the cases run in DIR as DIR/CASE.json, for parametric_study_summary.py")
    ap.add_argument("--exe", default="mpmsdem-run",
                    help="--run-prepared: the driver (default: mpmsdem-run on the PATH)")
    ap.add_argument("--backend", choices=("cpu", "cuda"), default=None,
                    help="--run-prepared: the backend (default: the scenes', cpu)")
    ap.add_argument("--precision", choices=("double", "float"), default=None,
                    help="--run-prepared: the precision (default: the scenes', double)")
    ap.add_argument("--rerun", action="store_true", help="--run-prepared: run the cases done before again")
    ap.add_argument("--until", type=float, default=None,
                    help="the coupled runs last at least until this time [s] (the paper's: 4.5); with "
                         "--run-prepared, cases done before that ended earlier go on from their last snapshot")
    return ap.parse_known_args(argv)[0]


def sweepMain(a):
    from mpmsdem import sweep
    cases = readTable(a.table)
    if a.full:
        cases = [dict(c, full=1) for c in cases]
    if a.until:
        cases = [dict(c, until=a.until) for c in cases]
    store = os.path.join(a.out, "runs.jsonl")
    records = sweep.runAll("%s:runCase" % os.path.abspath(__file__), cases, store, workers=a.workers,
                           scheduler=a.scheduler, retries=a.retries, timeout=a.timeout, threads=a.threads,
                           describe=lambda r: _describe(r["result"]))
    bad = sweep.failed(records)
    print("summary: python3 %s --results %s" % (os.path.join(HERE, "parametric_study_summary.py"), a.out))
    if bad:
        sys.exit("%d case(s) failed every attempt (errors above and in %s); re-run to retry them" % (len(bad), store))


def _describe(r):
    if not r.get("reached"):
        return "-> the flow stopped at x = %.2f m, short of the cube" % r["front"]
    ff = r["free_flow"]
    ratio = "%.2f" % r["force_ratio"] if r["force_ratio"] is not None else "- (no static force left on the cube)"
    cut = ""
    if r.get("carried_past_wall"):
        cut = " (cut short: still carried when the front reached the end wall at %.2f s)" % r["front_at_wall_time"]
    elif r["cube_at_end"]:
        cut = " (at the flume's end)"
    return ("-> h_f %.3f m (%s), Fr %.2f, Fr1 %.2f, S_b %.3f m%s, F_peak/F_static %s"
            % (ff["h_f"], r["submersion"], ff["Fr"], ff["Fr1"], r["travel"], cut, ratio))


def frontAtEnd(AR):
    """Where the flow's front is at 4.5 s, from the column's back wall [m] (FRONT_AT_END, linear
    between its aspect ratios and beyond them)."""
    pts = FRONT_AT_END
    i = max(1, min(len(pts) - 1, sum(1 for a, _ in pts if a < AR)))
    (a0, x0), (a1, x1) = pts[i - 1], pts[i]
    return x0 + (x1 - x0) * (AR - a0) / (a1 - a0)


def marginToEnd(AR, L0_hb):
    """The smallest whole ``margin`` [m] whose flume holds the flow's front at 4.5 s with END_ROOM
    to spare at the paper's resolution and blend."""
    import math
    return max(1.0, math.ceil(frontAtEnd(AR) + END_ROOM - (COLUMN + L0_hb * HB + HB)))


def prepareMain(a):
    if a.AR or a.L0_hb:
        cases = [{"AR": a.AR or 1.3, "L0_hb": a.L0_hb or 4}]
    else:
        cases = readTable(a.table)
    for c in cases:
        c = dict(c, full=1 if a.full else c.get("full", 0))
        if a.margin and "margin" not in c:
            c["margin"] = a.margin
        name = caseName(c["AR"], c["L0_hb"], c["full"], c.get("dx"))
        folder = prepareCase(folder=os.path.join(a.prepare, name), **c)
        print("prepared %s" % folder)
        with open(os.path.join(folder, "case.json")) as f:
            length = json.load(f)["result"]["flume_length"]
        if length < frontAtEnd(c["AR"]) + END_ROOM:
            print("  note: its flume ends %.2f m from the column; at the paper's resolution and blend the front is "
                  "about %.1f m from it at 4.5 s, so a run --until 4.5 would be cut short by the end wall "
                  "(cube_at_end): --margin %g gives room" % (length, frontAtEnd(c["AR"]), marginToEnd(c["AR"],
                                                                                                     c["L0_hb"])))
    print("next: python3 %s --run-prepared %s [--backend cuda] [--exe PATH/mpmsdem-run]" % (__file__, a.prepare))


def collectMain(a):
    n = 0
    for name in sorted(os.listdir(a.collect)):
        case = os.path.join(a.collect, name)
        if not os.path.isfile(os.path.join(case, "run.json")):
            continue
        r = collectCase(case)
        with open(case + ".json", "w") as f:
            json.dump(r, f, indent=1)
        print("%s %s" % (name, _describe(r)))
        n += 1
    if not n:
        sys.exit("--collect %s: no case folder there has been run (run.json); --run-prepared first" % a.collect)
    print("summary: python3 %s --results %s" % (os.path.join(HERE, "parametric_study_summary.py"), a.collect))


def main(argv):
    a = parse(argv)
    if a.sweep:
        return sweepMain(a)
    if a.prepare:
        return prepareMain(a)
    if a.run_prepared:
        try:
            with stopDriversOnSignals():
                ran = runPrepared(a.run_prepared, a.exe, a.backend, a.precision, a.threads, a.rerun, a.until,
                                  a.workers)
        except DriverStopped as e:
            print("--run-prepared %s: stopped by a signal (%s); the same command goes on from where each case "
                  "stopped" % (a.run_prepared, e))
            return STOPPED_EXIT
        if not ran:
            print("--run-prepared %s: nothing to run (no case folder without run.json; --rerun runs them again)"
                  % a.run_prepared)
        return
    if a.collect:
        return collectMain(a)
    import mpmsdem  # noqa: F401  (finds YADE's folder in a plain python3)
    from yade import utils
    # Table columns beyond AR, L0_hb and full are optional; 0 means runCase's default.
    utils.readParamsFromTable(AR=a.AR or 1.3, L0_hb=a.L0_hb or 4, full=1 if a.full else 0, dx=0, ppc=0, settle=1.5,
                              margin=a.margin or MARGIN, until=a.until or 0, noTableOk=True)
    from yade.params import table
    r = runCase(table.AR, table.L0_hb, full=table.full, dx=table.dx or None, ppc=table.ppc or None,
                settle=table.settle, margin=table.margin, until=table.until or None, verbose=True)
    os.makedirs(a.out, exist_ok=True)
    name = caseName(table.AR, table.L0_hb, table.full, table.dx or None)
    path = os.path.join(a.out, name + ".json")
    with open(path, "w") as f:
        json.dump(r, f, indent=1)
    print("%s %s; %s" % (name, _describe(r), path))


if __name__ == "__main__":  # also under `yade -x` and yade-batch, which run scripts as __main__
    status = main(sys.argv[1:])
    if status:  # --run-prepared stopped by a signal
        sys.exit(status)
