#!/usr/bin/env python3
"""Runs the scripts of scripts/checks/ (``make checks``), JOBS at a time.

Each check is a single-threaded YADE scene or a driver run of a few minutes, independent of the
others (each writes only into its own temporary folder), so on a machine of N cores N of them at
once take about 1/N of the time one after the other. Each check's output is kept whole and printed
when it ends, with its wall time; at the end a table of every check's time and result. All checks
run even after one fails (so one CI log shows every failure); the exit status is 1 if any failed.

    python3 tools/run_checks.py [--jobs N] [SCRIPT ...]     (default: scripts/checks/check_*.py)
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def runOne(script, lock, procs):
    """Run one check with its output in a file; returns (script, seconds, exit status, output)."""
    t0 = time.time()
    with tempfile.TemporaryFile(mode="w+") as log:
        p = subprocess.Popen([sys.executable, script], stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
        with lock:
            procs.add(p)
        rc = p.wait()
        with lock:
            procs.discard(p)
        log.seek(0)
        return script, time.time() - t0, rc, log.read()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                    help="checks at once (default: the machine's cores; >= 1)")
    ap.add_argument("scripts", nargs="*", help="check scripts (default: scripts/checks/check_*.py)")
    a = ap.parse_args()
    if a.jobs < 1:
        ap.error("--jobs = %d: must be >= 1" % a.jobs)
    scripts = a.scripts or sorted(glob.glob(os.path.join(ROOT, "scripts", "checks", "check_*.py")))
    if not scripts:
        ap.error("no check scripts found")
    lock, procs, results = threading.Lock(), set(), []
    t0 = time.time()
    try:
        with ThreadPoolExecutor(max_workers=a.jobs) as pool:
            for done in as_completed([pool.submit(runOne, s, lock, procs) for s in scripts]):
                script, seconds, rc, out = done.result()
                name = os.path.relpath(script, ROOT)
                print("== %s (%.0f s%s)" % (name, seconds, "" if rc == 0 else ", FAILED: exit status %d" % rc))
                print(out, end="" if out.endswith("\n") or not out else "\n", flush=True)
                results.append((name, seconds, rc))
    except KeyboardInterrupt:
        with lock:
            for p in procs:
                p.kill()
        raise
    failed = [r for r in results if r[2] != 0]
    print("\nchecks: %d run, %d at a time, %.0f s wall" % (len(results), a.jobs, time.time() - t0))
    for name, seconds, rc in sorted(results, key=lambda r: -r[1]):
        print("  %6.0f s  %-6s %s" % (seconds, "ok" if rc == 0 else "FAILED", name))
    if failed:
        print("checks: %d FAILED: %s" % (len(failed), ", ".join(r[0] for r in failed)))
        return 1
    print("checks: OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
