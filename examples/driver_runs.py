"""Runs of prepared scenes through the plain C++ driver ``mpmsdem-run``, with the standard
library only: the examples' ``--run-prepared`` steps use it where neither YADE nor numpy is
installed (a GPU machine). ``mpmsdem.driver`` writes the scenes (that side needs YADE); both
sides size the runs with :func:`stepsOf` and :func:`recordSteps`."""
import os
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor


def runDriver(exe, scene, out, log, extra=(), backend=None, precision=None, threads=None):
    """``exe scene --out out [--backend B] [--precision P] [extra...]`` with its output in the
    file ``log`` and OMP_NUM_THREADS = ``threads`` (None: as set). Returns the wall time [s];
    RuntimeError naming the scene and the log when the driver fails."""
    cmd = [exe, scene, "--out", out] + (["--backend", backend] if backend else []) + \
        (["--precision", precision] if precision else []) + list(extra)
    env = dict(os.environ, **({"OMP_NUM_THREADS": str(threads)} if threads else {}))
    start = time.time()
    with open(log, "w") as f:
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
    if r.returncode != 0:
        raise RuntimeError("mpmsdem-run %s exited %d (its output: %s)" % (scene, r.returncode, log))
    return time.time() - start


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
