"""Runs of prepared scenes through the plain C++ driver ``mpmsdem-run``, with the standard
library only: the examples' ``--run-prepared`` steps use it where neither YADE nor numpy is
installed (a GPU machine). ``mpmsdem.driver`` writes the scenes (that side needs YADE)."""
import os
import subprocess
import time


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
