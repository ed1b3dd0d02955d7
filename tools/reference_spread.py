#!/usr/bin/env python3
"""How far the checks' reference numbers move between two builds, beside each check's tolerance.

The checks of scripts/checks/ that hold numbers against a stored reference
(scripts/checks/reference/<name>.json for check_<name>.py, relative tolerances in the script's
``TOL``) give the same digits every run of one binary, whatever the thread count (every parallel
sum is reduced in a fixed order: tests/python/test_determinism.py). What moves them is rounding:
another compiler, other flags, another CPU's vector width and FMA. So a tolerance is measured as
the spread between two builds of one commit that round differently, e.g. this tree's
``-march=native`` build and one configured with ``-DMPMSDEM_NATIVE=OFF`` (no FMA, SSE2), each
check run with ``--regenerate`` in its own tree; a band no wider than a few times that spread
still lets a deliberate change of the model fail.

    python3 tools/reference_spread.py OTHER_TREE/scripts/checks/reference [--ref DIR] [--checks DIR] [--markdown]

Prints, per compared key, this tree's value, the other's, their relative difference (a fraction)
and the tolerance over it (the margin); the exit status is 1 where a difference exceeds its tolerance.
"""
import argparse
import ast
import glob
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHECKS = os.path.join(ROOT, "scripts", "checks")


def tolerances(script):
    """The ``TOL = {key: relative tolerance}`` of a check script (read, not run: a check runs when
    imported), or None where it has none."""
    with open(script) as f:
        tree = ast.parse(f.read(), script)
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "TOL" for t in node.targets):
            return ast.literal_eval(node.value)
    return None


def readJson(path):
    with open(path) as f:
        return json.load(f)


def margin(difference, tolerance):
    """The tolerance over the difference, as printed ("exact" where the builds agree)."""
    return "%.2g" % (tolerance / abs(difference)) if difference else "exact"


def spread(ref, other, checks=CHECKS):
    """Rows (check, key, ours, other's, relative difference, tolerance) of every check with a TOL
    and a reference in both folders."""
    rows = []
    for script in sorted(glob.glob(os.path.join(checks, "check_*.py"))):
        name = os.path.basename(script)[len("check_"):-len(".py")]
        tol = tolerances(script)
        paths = [os.path.join(d, name + ".json") for d in (ref, other)]
        if not tol or not all(os.path.exists(p) for p in paths):
            continue
        ours, theirs = (readJson(p) for p in paths)
        for key, t in tol.items():
            rows.append((name, key, ours[key], theirs[key], theirs[key] / ours[key] - 1, t))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("other", help="the other build's reference folder (its checks run with --regenerate)")
    ap.add_argument("--ref", default=os.path.join(CHECKS, "reference"), help="this tree's reference folder")
    ap.add_argument("--checks", default=CHECKS, help="the folder of the check scripts whose TOL are read")
    ap.add_argument("--markdown", action="store_true", help="a markdown table")
    a = ap.parse_args(argv)
    rows = spread(a.ref, a.other, a.checks)
    if not rows:
        ap.error("no check has a reference in both %s and %s" % (a.ref, a.other))
    if a.markdown:
        print("| check | key | this build | other build | difference | tolerance | tolerance / difference |")
        print("|---|---|---:|---:|---:|---:|---:|")
        for name, key, x, y, d, t in rows:
            print("| %s | %s | %.6g | %.6g | %+.1e | %g %% | %s |" % (name, key, x, y, d, 100 * t, margin(d, t)))
    else:
        for name, key, x, y, d, t in rows:
            print("%-24s %-20s %12.6g %12.6g %+9.1e  tolerance %5g %%  margin %s"
                  % (name, key, x, y, d, 100 * t, margin(d, t)))
    return 1 if any(abs(d) > t for *_, d, t in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
