"""Runs of prepared scenes through the plain C++ driver ``mpmsdem-run``, with the standard
library only: the examples' ``--run-prepared`` steps use it where neither YADE nor numpy is
installed (a GPU machine). ``mpmsdem.driver`` writes the scenes (that side needs YADE); both
sides size the runs with :func:`stepsOf` and :func:`recordSteps`."""
import contextlib
import os
import signal
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor

# mpmsdem-run's exit status when SIGINT or SIGTERM stopped it after saving its state
STOPPED_EXIT = 4


class DriverStopped(RuntimeError):
    """mpmsdem-run was stopped by SIGINT or SIGTERM (exit 4) after saving its state as a snapshot:
    the same run goes on with --restart (a prepared case: the same --run-prepared command)."""


_drivers = set()  # the driver processes running now, for stopDriversOnSignals
_drivers_lock = threading.Lock()
_stopping = threading.Event()


def runDriver(exe, scene, out, log, extra=(), backend=None, precision=None, threads=None):
    """``exe scene --out out [--backend B] [--precision P] [extra...]`` with its output in the
    file ``log`` and OMP_NUM_THREADS = ``threads`` (None: as set). Returns the wall time [s];
    RuntimeError naming the scene and the log when the driver fails."""
    cmd = [exe, scene, "--out", out] + (["--backend", backend] if backend else []) + \
        (["--precision", precision] if precision else []) + list(extra)
    env = dict(os.environ, **({"OMP_NUM_THREADS": str(threads)} if threads else {}))
    if _stopping.is_set():
        raise DriverStopped("mpmsdem-run %s not started: the runs are being stopped" % scene)
    start = time.time()
    with open(log, "w") as f:
        proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
        with _drivers_lock:
            _drivers.add(proc)
        try:
            if _stopping.is_set():  # a signal came while it started
                proc.send_signal(signal.SIGTERM)
            returncode = proc.wait()
        finally:
            with _drivers_lock:
                _drivers.discard(proc)
    if returncode == STOPPED_EXIT:
        raise DriverStopped("mpmsdem-run %s was stopped by a signal, its state saved (its output: %s)" % (scene, log))
    if returncode == -signal.SIGTERM and _stopping.is_set():  # before its step loop: nothing to save
        raise DriverStopped("mpmsdem-run %s was stopped by a signal before its first step (its output: %s)"
                            % (scene, log))
    if returncode != 0:
        raise RuntimeError("mpmsdem-run %s exited %d (its output: %s)" % (scene, returncode, log))
    return time.time() - start


@contextlib.contextmanager
def stopDriversOnSignals():
    """While inside: SIGINT or SIGTERM to this process is passed on to the drivers that
    :func:`runDriver` is running, as SIGTERM (each saves its state and exits 4: DriverStopped
    is raised in its runner), and no other driver starts; a second SIGINT ends this process as
    usual. Main thread only (Python's rule for signal handlers)."""
    def stop(sig, frame):
        if sig == signal.SIGINT:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        _stopping.set()
        with _drivers_lock:
            running = list(_drivers)
        for proc in running:
            with contextlib.suppress(OSError):
                proc.send_signal(signal.SIGTERM)

    old = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        _stopping.clear()


def stepsOf(interval, dt):
    """Whole steps of ``dt`` [s] nearest to ``interval`` [s], at least one."""
    return max(1, int(round(interval / dt)))


def recordSteps(duration, dt, interval):
    """(steps, record interval in steps) of a run of about ``duration`` [s] recorded every
    ``interval`` [s]: rounded up to whole record intervals, so that the last record is the run's
    end (the YADE run and the driver then record the same steps)."""
    every = stepsOf(interval, dt)
    steps = stepsOf(duration, dt)
    return -(-steps // every) * every, every


def eachCase(run, cases, workers=1):
    """``[run(case) for case in cases]``, ``workers`` at a time (an integer >= 1: each run
    waits on its own driver process, so threads suffice). At the first exception the cases not
    yet started are dropped and it is raised once those running have ended."""
    if not (isinstance(workers, int) and workers >= 1):
        raise ValueError("workers = %r: must be an integer >= 1" % (workers,))
    if workers == 1:
        return [run(case) for case in cases]
    pool = ThreadPoolExecutor(workers)
    try:
        return list(pool.map(run, cases))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
