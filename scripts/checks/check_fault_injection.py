"""Fault injection: SDEM, MPM and coupled runs killed (SIGKILL) at random steps and restarted
from their last checkpoint, the way docs/outputs.md tells a user to (``mpmsdem.saveCheckpoint``
every few steps; on start, ``mpmsdem.lastCheckpoint`` + ``mpmsdem.loadCheckpoint``), must end
exactly where an unbroken run of the same scene ends:

- every output file (sdem.h5, mpm.h5, coupled.h5) opens with h5py;
- its /series/time is strictly increasing (no duplicate, no step back) and continuous (no
  gap: the same records as the unbroken run);
- every series and snapshot array, and the final YADE body states and particle arrays, are
  bit-identical to the unbroken run's (the restarts are documented as bit-for-bit on the CPU);
- the ParaView files (.pvd collections and their .vtp/.vtu pieces) are byte for byte those of
  the unbroken run, with nothing left over (no half-written piece, no entry twice).

Each run is a child process forked from this one (YADE imported once), killed by the parent
with SIGKILL once it reports the randomly drawn step; kills land anywhere, also while an
output record or a checkpoint is being written.

The "driver-writes" kind does the same to the C++ driver on a coupled scene (the coupled scene
below, written with ``mpmsdem.driver.writeScene``): ``mpmsdem-run`` is killed (SIGKILL, through
strace's fault injection) at write calls drawn from all those of an unbroken run (its n-th
pwrite64), so that kills land inside HDF5's own flushes too, then continued with ``mpmsdem-run
--restart`` (from the snapshot its coupled.checkpoint.json names), as a user would; a run killed
before its first checkpoint is started again. Its mpm.h5 and coupled.h5 (series and snapshots)
must equal those of an unbroken driver run to the last bit. A kill between two writes leaves
the files as a kill at the next write does, so these kills cover every instant of the run.

Every kill point is drawn from ``--seed`` (printed; by default from the clock), so a failing
run is replayed exactly with the seed it printed. The opt-in kinds sdem-writes, mpm-writes and
coupled-writes kill the YADE runs at write calls the same way; the opt-in "driver" kind kills
the driver after random wall times instead (not replayable: where a time lands depends on the
machine's speed).

The "driver-full" kind fills the disk instead of killing: from a drawn write call on, every
pwrite64 of the driver fails with ENOSPC (strace's fault injection). The driver must stop by
itself with a failure (exit status 3) whose message names the file and the reason; every file
it wrote before must then be whole: ``mpmsdem-run --restart`` (with room again) continues the
run to the unbroken run's end, bit for bit.

Exit status 0 when every check holds, 1 with the failures listed otherwise.

    python3 scripts/checks/check_fault_injection.py [--seed S] [--kills N] [--kinds sdem,mpm,coupled,driver-writes,driver-full]
    python3 scripts/checks/check_fault_injection.py --kinds sdem-writes,mpm-writes,coupled-writes,driver --kills 60
"""
import argparse
import os
import random
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

import mpmsdem
import mpmsdem.driver
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "..", "tests", "data")

# steps of a whole run, steps between checkpoints, output intervals
# (checkpoints off the record grid: a restart must find the record times of the unbroken run)
PLAN = {"sdem": (3000, 70), "mpm": (400, 25), "coupled": (400, 25), "driver": (4000, None)}
_progressFd = None


def _progress():
    if _progressFd is not None:
        os.write(_progressFd, struct.pack("q", O.iter))


def _progressRunner():
    return PyRunner(command="__import__('__main__')._progress()", iterPeriod=1, label="progress")


# ------------------------------------------------------------------ the three scenes
def buildSdem(out):
    eng = mpmsdem.SdemEngine(output=out, outputEvery=2.5e-3, vtkEvery=0.02, verbose=False)
    mat = mpmsdem.material(density=500.0, friction=0.4, barrierStiffness=1e4, normalDamping=0.3)
    eng.box((0.6, 0.6, 0.05), 0.005, mat, pos=(0, 0, -0.05), fixed=True)
    eng.mesh(os.path.join(DATA, "l_prism.obj"), 0.005, mat, pos=(0, 0, 0.0505))
    eng.polyhedron([(-0.04, -0.03, 0), (0.05, -0.04, 0.01), (0.03, 0.05, -0.01), (-0.05, 0.04, 0.0),
                    (0.0, 0.0, 0.06), (0.02, -0.01, 0.055)], 0.004, mat, pos=(0.02, 0.03, 0.14))
    O.engines = [ForceResetter(), eng.runner, NewtonIntegrator(gravity=(2.0, 0.5, -9.81), damping=0),
                 _progressRunner()]
    O.dt = 5e-5
    return eng


GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}


def buildMpm(out):
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.02, "cells": [12, 6, 10], "origin": [-0.04, -0.04, -0.04]},
                            material=GLASS, particles=[{"lo": [0, 0, 0], "hi": [0.08, 0.04, 0.08], "ppc": 8}],
                            walls={"-z": 0.4}, output=out, outputEvery=4e-3, verbose=False)
    O.engines = [mpm.runner, _progressRunner()]
    O.dt = 2e-4
    return mpm


def buildCoupled(out):
    sdem = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    sdem.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07))
    mpm = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                            particles=[{"lo": [0.08, 0.05, 0.05], "hi": [0.10, 0.09, 0.09], "ppc": 8,
                                        "velocity": [3, 0, 0]}],
                            gravity=(0, 0, -9.81), output=os.path.join(out, "mpm"), outputEvery=5e-4, verbose=False)
    coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, output=out, outputEvery=2e-4, verbose=False)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0),
                 _progressRunner()]
    O.dt = 1e-5
    return coupled


def driverExe():
    import mpmsdem.driver
    try:
        return mpmsdem.driver.executable()
    except FileNotFoundError as e:
        sys.exit("check_fault_injection: %s" % e)


def driverScene(root):
    """The coupled scene as a driver JSON scene: 4,000 steps of 1e-5 s, a series row every
    2e-4 s, a snapshot, a ParaView entry and a checkpoint every 5e-4 s. Written once: the driver
    kinds of one call share it (a second engine could not create the first one's open files)."""
    path = os.path.join(root, "driver_scene.json")
    if os.path.exists(path):
        return path
    O.reset()
    coupled = buildCoupled(os.path.join(root, "unused"))
    os.makedirs(root, exist_ok=True)
    return mpmsdem.driver.writeScene(path, coupled, duration=PLAN["driver"][0] * O.dt,
                                     dt=O.dt, seriesEvery=2e-4, outputEvery=5e-4, outputDir=os.path.join(root, "x"))


def runDriver(exe, scene, work, killAfter=None):
    """mpmsdem-run into work/out, with --restart when a run was there before; killed with
    SIGKILL after killAfter seconds. Returns (killed, restarted from scratch)."""
    out = os.path.join(work, "out")
    restart = os.path.exists(out)
    cmd = [exe, scene, "--out", out] + (["--restart"] if restart else [])
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        _, err = p.communicate(timeout=killAfter)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        return True, False
    if p.returncode == 2 and restart and "with a restart point" in err:
        # killed before its first checkpoint: nothing to continue, start again
        shutil.rmtree(out)
        return runDriver(exe, scene, work, killAfter)[0], True
    if p.returncode != 0:
        raise RuntimeError("driver run failed (exit %d): %s" % (p.returncode, err.strip()[-800:]))
    return False, False


def driverKills(root, rng, kills):
    """Kill the driver at random moments until `kills` kills landed, then let it finish.
    Returns (unbroken folder, killed folder, kill count, fresh starts)."""
    exe = driverExe()
    scene = driverScene(root)
    ref, broken = os.path.join(root, "driver_ref"), os.path.join(root, "driver_killed")
    t0 = time.time()
    runDriver(exe, scene, ref)
    whole = time.time() - t0
    done, fresh = 0, 0
    for _ in range(20 * kills):
        if done == kills:
            break
        killed, again = runDriver(exe, scene, broken, killAfter=rng.uniform(0.1, 1.0) * whole)
        fresh += again
        if not killed:  # the run got to its end: start it over to place the remaining kills
            shutil.rmtree(os.path.join(broken, "out"))
            continue
        done += 1
    runDriver(exe, scene, broken)
    return ref, broken, done, fresh


def writeKills(kind, root, rng, kills, full=False):
    """Kill a run of `kind` at `kills` write calls drawn from all those of an unbroken run
    (strace's fault injection sends SIGKILL at the n-th pwrite64, so kills land inside HDF5
    flushes too), then continue it to its end as a user would (the driver with --restart, a
    YADE script from its last checkpoint). With ``full`` (the driver only) the disk is full
    instead: the n-th pwrite64 and every one after it fail with ENOSPC, and the run must stop by
    itself with a failure that names the file, before it is continued with room again. Returns
    (unbroken folder, [(write number, folder, error or None)], fresh starts)."""
    if not shutil.which("strace"):
        sys.exit("check_fault_injection: the *-writes kinds need strace (apt install strace)")
    if kind == "driver":
        exe = driverExe()
        scene = driverScene(root)
        command = lambda work: [exe, scene, "--out", os.path.join(work, "out")]  # noqa: E731

        def finish(work):
            try:
                return None, runDriver(exe, scene, work)[1]
            except RuntimeError as e:
                return str(e), False
    else:
        command = lambda work: [sys.executable, os.path.abspath(__file__), "--child", kind, work]  # noqa: E731

        def finish(work):
            p = subprocess.run(command(work), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            return (None if p.returncode == 0 else "continued run failed: " + p.stderr.strip()[-600:]), False
    ref = os.path.join(root, kind + "_writes_ref")
    count = subprocess.run(["strace", "-f", "-c", "-e", "trace=pwrite64"] + command(ref), stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True, check=True).stderr
    writes = int(next(line.split()[3] for line in count.splitlines() if line.rstrip().endswith("pwrite64")))
    runs, fresh = [], 0
    for n in sorted(rng.sample(range(1, writes), min(kills, writes - 1))):
        work = os.path.join(root, "%s_write_%d" % (kind, n))
        fault = "error=ENOSPC:when=%d+" % n if full else "signal=KILL:when=%d" % n
        p = subprocess.run(["strace", "-f", "-o", "/dev/null", "-e", "trace=pwrite64", "-e",
                            "inject=pwrite64:" + fault] + command(work),
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if full:
            stopped = fullDiskStop(p, os.path.join(work, "out"))
            if stopped:
                runs.append((n, work, stopped))
                continue
        error, again = finish(work)
        fresh += again
        runs.append((n, work, error))
    return ref, runs, fresh


def fullDiskStop(p, out):
    """None when the driver, its writes failing with ENOSPC, stopped as a failure (exit 3)
    whose message names a file in its output folder ``out`` and the system's reason; otherwise
    what was wrong."""
    err = p.stderr.strip()
    if p.returncode != 3:
        return "with a full disk the driver ended with exit status %d, not 3 (a failure): %s" % (p.returncode, err[-600:])
    if "mpmsdem-run: failure:" not in err or out not in err:
        return "with a full disk the driver's message names no file in %s: %s" % (out, err[-600:])
    if "No space left on device" not in err:
        return "with a full disk the driver's message does not give the reason (No space left on device): %s" % err[-600:]
    return None


def restoreKw(kind, out):
    """The outputs a restarted run continues (as a user passes them to loadCheckpoint)."""
    if kind == "sdem":
        return {"output": out, "outputEvery": 2.5e-3, "vtkEvery": 0.02, "verbose": False}
    if kind == "mpm":
        return {"output": out, "outputEvery": 4e-3, "verbose": False}
    return {"output": out, "outputEvery": 2e-4, "verbose": False,
            "mpmKw": {"output": os.path.join(out, "mpm"), "outputEvery": 5e-4}}


def runChild(kind, work):
    """A run as a user script does it: continue from the last checkpoint if there is one,
    checkpoint every few steps, end with the final state in final.npz."""
    total, every = PLAN[kind]
    out, cks = os.path.join(work, "out"), os.path.join(work, "ck")
    ck = mpmsdem.lastCheckpoint(cks)
    if ck:
        engine = mpmsdem.loadCheckpoint(ck, **restoreKw(kind, out))
    else:
        engine = {"sdem": buildSdem, "mpm": buildMpm, "coupled": buildCoupled}[kind](out)
        mpmsdem.saveCheckpoint(cks, engine)
    while O.iter < total:
        mpmsdem.run(min(every, total - O.iter), engine)
        mpmsdem.saveCheckpoint(cks, engine)
    final = {}
    sdem = engine if kind == "sdem" else getattr(engine, "sdem", None)
    for i in (sdem.ids if sdem else []):
        s = O.bodies[i].state
        final["body%d" % i] = np.array([*s.pos, *s.ori, *s.vel, *s.angVel])
    mpm = engine if kind == "mpm" else getattr(engine, "mpm", None)
    if mpm:
        for k, v in mpm.particles().items():
            final["mp_" + k] = v
    final["clock"] = np.array([O.iter, O.time])
    np.savez(os.path.join(work, "final.npz"), **final)


def fork(kind, work, killAt=None):
    """Run runChild in a forked process; SIGKILL it once it reports step >= killAt. Returns
    (killed, last step reported)."""
    global _progressFd
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        os.close(r)
        _progressFd = w
        code = 0
        try:
            O.reset()
            runChild(kind, work)
        except BaseException as e:  # noqa: BLE001  (reported to the parent through the exit status)
            print("child %s failed: %r" % (kind, e), file=sys.stderr, flush=True)
            code = 1
        os._exit(code)
    os.close(w)
    last, killed, buf = -1, False, b""
    while True:
        chunk = os.read(r, 65536)
        if not chunk:
            break
        buf += chunk
        n = len(buf) // 8
        if n:
            last = struct.unpack("q", buf[8 * (n - 1):8 * n])[0]
            buf = buf[8 * n:]
        if killAt is not None and not killed and last >= killAt:
            os.kill(pid, signal.SIGKILL)
            killed = True
    os.close(r)
    _, status = os.waitpid(pid, 0)
    if killed:
        if not (os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL) and os.WEXITSTATUS(status) != 0:
            raise RuntimeError("%s child failed before the kill (status %d)" % (kind, status))
    elif not (os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0):
        raise RuntimeError("%s child failed (status %d)" % (kind, status))
    return killed, last


# ------------------------------------------------------------------ comparisons
def h5Arrays(path):
    import h5py
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
        for name, g in f.get("snapshots", {}).items():  # also those in files of their own (links)
            out["snapshots/%s@time" % name] = np.array(g.attrs["time"])
            for k, d in g.items():
                out["snapshots/%s/%s" % (name, k)] = d[()]
    return out


def paraviewFiles(out):
    """Every ParaView file under an output folder (.pvd collections, .vtp/.vtu pieces and what
    a killed writer may have left beside them), as {path relative to out: bytes}."""
    found = {}
    for folder, _, names in os.walk(out):
        for name in names:
            if name.endswith((".pvd", ".vtp", ".vtu")) or ".pvd." in name or ".vtp." in name or ".vtu." in name:
                with open(os.path.join(folder, name), "rb") as f:
                    found[os.path.relpath(os.path.join(folder, name), out)] = f.read()
    return found


def compare(kind, ref, broken, failures):
    files = {"sdem": ["sdem.h5"], "mpm": ["mpm.h5"], "coupled": ["coupled.h5", "mpm/mpm.h5"],
             "driver": ["coupled.h5", "mpm.h5"]}[kind]
    for name in files:
        try:
            a, b = h5Arrays(os.path.join(ref, "out", name)), h5Arrays(os.path.join(broken, "out", name))
        except Exception as e:  # noqa: BLE001
            failures.append("%s: %s unreadable: %r" % (kind, name, e))
            continue
        t = b.get("series/time")
        if t is None or len(t) < 2:
            failures.append("%s: %s has no time series" % (kind, name))
        elif not np.all(np.diff(t) > 0):
            failures.append("%s: %s time not strictly increasing (duplicates or steps back) at records %s"
                            % (kind, name, np.nonzero(np.diff(t) <= 0)[0][:5].tolist()))
        if a.keys() != b.keys():
            failures.append("%s: %s datasets differ: only unbroken %s, only restarted %s" % (
                kind, name, sorted(set(a) - set(b))[:5], sorted(set(b) - set(a))[:5]))
        for k in sorted(set(a) & set(b)):
            x, y = np.asarray(a[k]), np.asarray(b[k])
            if x.shape != y.shape:
                failures.append("%s: %s %s shape %s, unbroken %s (records lost or repeated)" % (
                    kind, name, k, y.shape, x.shape))
            elif x.tobytes() != y.tobytes():
                failures.append("%s: %s %s differs from the unbroken run (max |diff| %g)" % (
                    kind, name, k, float(np.max(np.abs(x.astype(float) - y.astype(float))))))
    a, b = paraviewFiles(os.path.join(ref, "out")), paraviewFiles(os.path.join(broken, "out"))
    if a.keys() != b.keys():
        failures.append("%s: ParaView files differ: only unbroken %s, only restarted %s" % (
            kind, sorted(set(a) - set(b))[:5], sorted(set(b) - set(a))[:5]))
    for name in sorted(set(a) & set(b)):
        if a[name] != b[name]:
            failures.append("%s: ParaView file %s differs from the unbroken run's" % (kind, name))
    if kind == "driver":  # its final state is the last snapshot and record, compared above
        return
    with np.load(os.path.join(ref, "final.npz")) as a, np.load(os.path.join(broken, "final.npz")) as b:
        for k in a.files:
            if k not in b.files or a[k].tobytes() != b[k].tobytes():
                failures.append("%s: final state %s differs from the unbroken run" % (kind, k))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=None,
                    help="seed of the kill points (default: from the clock); the run prints it, and the same seed "
                         "replays the same kills")
    ap.add_argument("--kills", type=int, default=20, help="kills per kind of run (>= 1, default 20)")
    ap.add_argument("--kinds", default="sdem,mpm,coupled,driver-writes,driver-full",
                    help="comma-separated, of sdem, mpm, coupled (YADE runs killed at drawn steps), any of them with "
                         "-writes (killed at drawn write calls, through strace), driver-writes (the C++ driver, so), "
                         "driver-full (the driver's disk full from a drawn write call on), driver (the driver killed "
                         "after random wall times: not replayable); default sdem,mpm,coupled,driver-writes,driver-full")
    ap.add_argument("--child", nargs=2, metavar=("KIND", "FOLDER"), help=argparse.SUPPRESS)
    ap.add_argument("--keep", action="store_true", help="keep the work folder (printed)")
    a = ap.parse_args()
    if a.child:  # one run of a *-writes kind, in its own process so that strace can kill it
        O.reset()
        runChild(*a.child)
        return 0
    if a.kills < 1:
        ap.error("--kills = %d: must be >= 1" % a.kills)
    seed = a.seed if a.seed is not None else int(time.time() * 1000) % 2 ** 31
    print("check_fault_injection: seed %d (rerun with --seed %d), %d kills per kind" % (seed, seed, a.kills))
    rng = random.Random(seed)
    root = tempfile.mkdtemp(prefix="fault_injection_")
    failures = []
    try:
        for kind in a.kinds.split(","):
            if kind not in PLAN and kind[:-len("-writes")] not in PLAN and kind != "driver-full":
                ap.error("--kinds: %r is not one of %s, one of them with -writes, or driver-full"
                         % (kind, ", ".join(PLAN)))
            t0 = time.time()
            if kind.endswith("-writes") or kind == "driver-full":
                base, full = kind.rsplit("-", 1)[0], kind == "driver-full"
                ref, runs, fresh = writeKills(base, root, rng, a.kills, full=full)
                for n, work, error in runs:
                    before = len(failures)
                    if error:
                        failures.append(error)
                    else:
                        compare(base, ref, work, failures)
                    failures[before:] = ["%s %s at write %d: %s" % (base, "full from" if full else "killed", n, f)
                                         for f in failures[before:]]
                    if len(failures) == before:
                        shutil.rmtree(work)
                print("  %-8s %d %s at write calls %s%s; %.1f s" % (
                    kind, len(runs), "full disks from" if full else "kills", [n for n, _, _ in runs],
                    " (%d before a first snapshot: started again)" % fresh if base == "driver" else "",
                    time.time() - t0))
                continue
            if kind == "driver":
                ref, broken, kills, fresh = driverKills(root, rng, a.kills)
                compare(kind, ref, broken, failures)
                print("  %-8s %d kills at random moments (%d before a first checkpoint: started again); %.1f s"
                      % (kind, kills, fresh, time.time() - t0))
                if kills < a.kills:
                    failures.append("driver: only %d kills landed" % kills)
                continue
            total, every = PLAN[kind]
            ref, broken = os.path.join(root, kind + "_ref"), os.path.join(root, kind + "_killed")
            fork(kind, ref)
            kills, steps = 0, []
            while kills < a.kills:
                ck = mpmsdem.lastCheckpoint(os.path.join(broken, "ck"))
                start = int(os.path.basename(ck)[3:]) if ck else 0
                # spread over the run: a kill within ~1.5 x an even share of it after the restart
                target = min(total - 1, start + rng.randint(0, max(1, int(1.5 * total / a.kills))))
                killed, last = fork(kind, broken, killAt=target)
                if not killed:
                    break
                kills += 1
                steps.append(last)
            if os.path.exists(os.path.join(broken, "final.npz")):
                failures.append("%s: a killed run wrote its final state" % kind)
            fork(kind, broken)
            compare(kind, ref, broken, failures)
            print("  %-8s %d kills at steps %s; %.1f s" % (kind, kills, steps, time.time() - t0))
            if kills < a.kills:
                failures.append("%s: only %d kills (the run ended first)" % (kind, kills))
    finally:
        if a.keep:
            print("work folder:", root)
        else:
            shutil.rmtree(root, ignore_errors=True)
    if failures:
        print("check_fault_injection: FAILED (seed %d)" % seed)
        for f in failures:
            print("  " + f)
        return 1
    print("check_fault_injection: OK — restarted runs bit-identical to unbroken ones, outputs readable, "
          "time series strictly increasing and complete")
    return 0


if __name__ == "__main__":
    sys.exit(main())
