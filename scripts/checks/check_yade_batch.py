#!/usr/bin/env python3
"""Check: the yade-batch workflow with the installed plugin. Runs examples/sliding_block.py
through `yade-batch` on a two-line table (theta 20 and 40 deg, mu 0.1, 0.5 s), each job in
its own YADE process, and requires both results within 1.5 % of Eq 19 (the tangential-spring
stick stage makes SDEM up to ~1 % longer at small theta; see check_sliding_block.py).

    /usr/bin/python3 scripts/checks/check_yade_batch.py
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def main():
    batch = shutil.which("yade-batch")
    if batch is None:
        sys.exit("FAILED: yade-batch not found (make deps installs yade)")
    with tempfile.TemporaryDirectory() as work:
        shutil.copy(os.path.join(ROOT, "examples", "sliding_block.py"), work)
        with open(os.path.join(work, "sweep.table"), "w") as f:
            f.write("theta mu duration dt\n20 0.1 0.5 5e-5\n40 0.1 0.5 5e-5\n")
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # the installed package, as users run it
        env["OMP_NUM_THREADS"] = "1"
        proc = subprocess.run([batch, "-j", "2", "--job-threads=1", "sweep.table", "sliding_block.py"], cwd=work,
                              env=env, capture_output=True, text=True, timeout=600)
        failures = []
        if proc.returncode != 0:
            failures.append("yade-batch exited %d:\n%s" % (proc.returncode, proc.stdout[-2000:]))
        for theta in (20, 40):
            path = os.path.join(work, "results", "sliding_theta=%g_mu=0.1.json" % theta)
            if not os.path.exists(path):
                failures.append("theta %g: no result file (job log in %s)" % (theta, work))
                continue
            r = json.load(open(path))
            print("theta %g, mu 0.1, t = %.2f s: S = %.5f m, Eq 19 %.5f m (%+.2f %%)"
                  % (theta, r["time"], r["distance"], r["eq19"], 100 * r["relative_error"]))
            if abs(r["relative_error"]) > 0.015:
                failures.append("theta %g: %+.2f %% from Eq 19" % (theta, 100 * r["relative_error"]))
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("OK: yade-batch sweep ran both jobs and matches Eq 19")


if __name__ == "__main__":
    main()
