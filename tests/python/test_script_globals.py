"""A run leaves the user's script alone: no entry point that steps YADE writes into the script's
globals. YADE copies the local names of the Python function that calls ``O.step()`` into
``__main__`` before each command of a PyRunner whose ``updateGlobals`` is on (its default);
``mpmsdem.run``'s ``steps``, ``engines``, ``e`` and ``_`` used to overwrite a script's own.

Each case is a script run as ``__main__`` in its own process (as a user runs it: plain python3,
or ``yade -n -x`` for YADE's own ``O.run``). It fills its globals with sentinels under every
name the entry points use locally, takes a snapshot of its whole globals (name -> object),
steps through the entry point, and reports every name added, removed or rebound."""
import json
import os
import shutil
import subprocess
import sys

import pytest

import children

PRELUDE = r'''
import json, os, sys
import mpmsdem
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
OUT = sys.argv[1]


def sdemScene():
    s = mpmsdem.SdemEngine(dtCheck="raise", verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    s.box((0.5, 0.5, 0.05), 0.005, mat, pos=(0, 0, -0.05), fixed=True)
    s.box((0.05,) * 3, 0.005, mat, pos=(0, 0, 0.06))
    O.engines = [ForceResetter(), s.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-4
    return s


def mpmScene():
    m = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [12, 8, 8], "origin": [0, 0, 0]}, material=GLASS,
                          particles=[{"lo": [0.03, 0.03, 0.02], "hi": [0.05, 0.05, 0.04], "ppc": 8}],
                          gravity=(0, 0, -9.81), verbose=False)
    O.engines = [ForceResetter(), m.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-5
    return m


def coupledScene():
    s = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    s.box((0.02,) * 3, 0.003, mat, pos=(0.125, 0.07, 0.07))
    m = mpmsdem.MpmEngine(grid={"dx": 0.01, "cells": [24, 14, 14], "origin": [0, 0, 0]}, material=GLASS,
                          particles=[{"lo": [0.08, 0.05, 0.05], "hi": [0.10, 0.09, 0.09], "ppc": 8,
                                      "velocity": [3, 0, 0]}], gravity=(0, 0, -9.81), verbose=False)
    c = mpmsdem.CoupledEngine(s, m, pairs={mat: 0.3}, verbose=False)
    O.engines = [ForceResetter(), c.runner, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-5
    return c


# every local name of mpmsdem.run, Flume.run and the checkpoint functions, as a script's own
for _name in ("steps", "engines", "e", "_", "r", "userRunners", "duration", "sampleEvery", "every", "done", "k",
              "self", "path", "files", "engine", "folder", "keep", "kind", "name", "final", "tmp", "restoreKw",
              "slots", "i", "n", "t", "f"):
    globals()[_name] = "script's own %s" % _name
del _name


def snapshot():
    return {k: v for k, v in globals().items()}


def report(before, assigned=()):
    """Names added, removed or rebound since ``before``, but those the case itself ``assigned``."""
    after = globals()
    changed = sorted(k for k in set(before) | set(after)
                     if k not in ("before",) + tuple(assigned)
                     and (k not in after or k not in before or after[k] is not before[k]))
    with open(os.path.join(OUT, "changed.json"), "w") as fh:
        json.dump(changed, fh)
'''

CASES = {
    "sdem_run": "engine = sdemScene()\nbefore = snapshot()\nmpmsdem.run(10, engine)\nreport(before)\n",
    "mpm_run": "engine = mpmScene()\nbefore = snapshot()\nmpmsdem.run(5, engine)\nreport(before)\n",
    "coupled_run": "engine = coupledScene()\nbefore = snapshot()\nmpmsdem.run(5, engine)\nreport(before)\n",
    # a script's own PyRunner (updateGlobals on, YADE's default) beside ours: off during the
    # call, on again after it
    "own_runner": ("engine = sdemScene()\nmine = PyRunner(command='pass', iterPeriod=1)\n"
                   "O.engines = O.engines + [mine]\nbefore = snapshot()\nmpmsdem.run(10, engine)\n"
                   "assert mine.updateGlobals is True\nreport(before)\n"),
    "flume_run": ("from mpmsdem.flume import Flume\nengine = Flume(dx=0.05, length=0.6, width=0.1, columnLength=0.1, "
                  "columnHeight=0.1, verbose=False)\nbefore = snapshot()\nengine.run(3 * O.dt, sampleEvery=O.dt)\n"
                  "report(before)\n"),
    "checkpoint": ("engine = coupledScene()\nmpmsdem.run(2, engine)\nbefore = snapshot()\n"
                   "mpmsdem.saveCheckpoint(os.path.join(OUT, 'ck'), engine)\n"
                   "again = mpmsdem.loadCheckpoint(mpmsdem.lastCheckpoint(os.path.join(OUT, 'ck')), verbose=False)\n"
                   "mpmsdem.run(3, again)\nreport(before, assigned=('again',))\n"),
    # YADE's own loop under `yade -x`: O.run in YADE's thread
    "yade_x_orun": "engine = sdemScene()\nbefore = snapshot()\nO.run(10, True)\nengine.check()\nreport(before)\n",
}


def runCase(tmp_path, case):
    script = tmp_path / ("%s.py" % case)
    script.write_text(PRELUDE + CASES[case])
    out = tmp_path / "out"
    out.mkdir()
    if case.startswith("yade_x"):
        yade = shutil.which("yade")
        if yade is None:
            pytest.fail("yade is not on the PATH (make test installs it)")
        cmd = [yade, "-n", "-x", str(script), str(out)]
    else:
        cmd = [sys.executable, str(script), str(out)]
    p = subprocess.run(cmd, env=children.env(OMP_NUM_THREADS=1), capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-3000:]
    with open(out / "changed.json") as f:
        return json.load(f)


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_scripts_globals_survive(tmp_path, case):
    assert runCase(tmp_path, case) == []


def test_the_check_sees_a_leak(tmp_path):
    """The same script through a function that steps YADE itself, with a runner whose
    updateGlobals is on: YADE's copying is seen (so the cases above can fail)."""
    CASES["leaky"] = ("engine = sdemScene()\nO.engines = O.engines + [PyRunner(command='pass', iterPeriod=1)]\n"
                      "def stepper(n):\n    steps = n\n    for _ in range(n):\n        O.step()\n"
                      "before = snapshot()\nstepper(3)\nreport(before, assigned=('stepper',))\n")
    try:
        assert runCase(tmp_path, "leaky") == ["_", "n", "steps"]
    finally:
        del CASES["leaky"]
