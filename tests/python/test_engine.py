"""What the engines share (mpmsdem.engine): the runner command saved scenes hold, the O.engines
check and its error, and the scene's one progress line per interval with the run's ETA."""
import re

import pytest

import mpmsdem
from mpmsdem import engine
from mpmsdem.field import BlockTracker
from yade import O
from yade.wrapper import ForceResetter, NewtonIntegrator

GLASS = {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65}
GRID = {"dx": 0.01, "cells": [12, 8, 8], "origin": [0, 0, 0]}
BLOB = [{"lo": [0.02, 0.02, 0.02], "hi": [0.04, 0.04, 0.04], "ppc": 1}]  # 8 points


def engines(sdemVerbose=False, mpmVerbose=False, coupledVerbose=None):
    """An SDEM engine with a cube, an MPM engine with 8 points and, unless coupledVerbose is
    None, a CoupledEngine of the two."""
    sdem = mpmsdem.SdemEngine(verbose=sdemVerbose)
    mat = mpmsdem.material(density=2000, friction=0.3)
    sdem.box((0.01,) * 3, 0.002, mat, pos=(0.09, 0.04, 0.04))
    mpm = mpmsdem.MpmEngine(grid=GRID, material=GLASS, particles=BLOB, gravity=(0, 0, 0), verbose=mpmVerbose)
    coupled = None
    if coupledVerbose is not None:
        coupled = mpmsdem.CoupledEngine(sdem, mpm, pairs={mat: 0.3}, verbose=coupledVerbose)
    O.dt = 1e-5
    return sdem, mpm, coupled


@pytest.fixture
def progress(monkeypatch):
    """A fresh scene progress whose wall clock reads 4 s a step (O.iter): a line every third step."""
    p = engine._SceneProgress()
    p.clock = lambda: 4.0 * O.iter
    monkeypatch.setattr(engine, "_PROGRESS", p)
    return p


def lines(text):
    return [line for line in text.splitlines() if line.startswith("mpmsdem")]


def test_every_runner_is_a_dispatch_command_that_saved_scenes_hold():
    sdem, mpm, coupled = engines(coupledVerbose=False)
    tracker = BlockTracker(coupled, sdem.ids)
    assert mpmsdem._dispatch is engine._dispatch
    for kind, e in (("sdem", sdem), ("mpm", mpm), ("coupled", coupled), ("field", tracker)):
        assert e.runner.command == "__import__('mpmsdem')._dispatch('%s_%d')" % (kind, id(e))
        assert e.runner.iterPeriod == 1 and not e.runner.updateGlobals
        assert engine._REGISTRY["%s_%d" % (kind, id(e))].__self__ is e
    assert tracker.runner.initRun is False and sdem.runner.initRun is True


@pytest.mark.parametrize("kind", ["sdem", "coupled"])
def test_the_engines_check_stops_a_plain_run_with_the_same_message_from_every_engine(kind):
    sdem, mpm, coupled = engines(coupledVerbose=False)
    e = {"sdem": sdem, "coupled": coupled}[kind]
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, 0), damping=0), e.runner]
    with pytest.raises(RuntimeError, match=r"must be \[ForceResetter\(\), %s.runner" % kind):
        O.run(1, True)
    assert O.iter == 0
    expected = ("mpmsdem.%s stopped the run at step 0 (t = 0 s): O.engines = [ForceResetter, NewtonIntegrator, "
                "PyRunner]: must be [ForceResetter(), %s.runner, NewtonIntegrator(...)] (in this order; other engines "
                "may come before or after): " % (type(e).__name__, kind))
    with pytest.raises(RuntimeError) as err:
        e.check()
    assert str(err.value).startswith(expected), str(err.value)
    # once the list is right, the engine steps
    e.error = None
    O.engines = [ForceResetter(), e.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    start = O.iter
    O.run(2, True)
    e.check()
    assert O.iter == start + 2


def test_the_mpm_runner_missing_is_refused_before_the_run():
    sdem, mpm, coupled = engines()
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    with pytest.raises(ValueError, match=r"^O.engines does not hold this MpmEngine's runner: put it there"):
        mpmsdem.run(1, sdem, mpm)
    assert O.iter == 0 and mpm.error is None


def test_two_engines_in_one_scene_print_one_line_per_interval_with_the_eta_of_the_run(progress, capsys):
    sdem, mpm, coupled = engines(sdemVerbose=True, mpmVerbose=True)
    O.engines = [ForceResetter(), sdem.runner, mpm.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    mpmsdem.run(30, sdem, mpm)
    out = lines(capsys.readouterr().err)
    # the clock passes 10 s every third step; the first step of a run sets the start
    assert [int(re.search(r", step (\d+) ", line).group(1)) for line in out] == list(range(3, 30, 3))
    for line in out:
        s = int(re.search(r", step (\d+) ", line).group(1))
        assert line.startswith("mpmsdem: t = %.6g s, step %d (%.1f %% of 30 steps, ETA %s), O.dt 1e-05 s, "
                               "4000.0 ms/step; SdemEngine: " % (s * 1e-5, s, 100 * s / 30.0,
                                                                 engine._duration(4.0 * (30 - s)))), line
        assert line.count("SdemEngine: ") == 1 and line.count("MpmEngine: ") == 1
        assert re.search(r"; SdemEngine: \d+ contacts, critical step \S+ s; MpmEngine: the flow's CFL step \S+ s, "
                         r"2 particle-updates/s$", line), line  # 8 points in 4 s a step
    assert "ETA 1 min 48 s" in out[0] and "ETA 12 s" in out[-1]
    # a plain O.run: the same lines, without a length to count down
    O.run(12, True)
    out = lines(capsys.readouterr().err)
    assert [int(re.search(r", step (\d+),", line).group(1)) for line in out] == [30, 33, 36, 39]
    assert not any("ETA" in line or "%" in line for line in out)


def test_a_run_in_chunks_to_an_end_time_counts_down_the_whole_run(progress, capsys):
    # three chunks of 10 steps to t = 30 steps: one countdown over the three (4 s a step, so at
    # t the ETA is 4 s for each step left), not one per chunk
    sdem, mpm, coupled = engines(sdemVerbose=True)
    O.engines = [ForceResetter(), sdem.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    O.dt = 1e-5
    t0, end = O.time, O.time + 30e-5
    first = O.iter
    for _ in range(3):
        mpmsdem.run(10, sdem, endTime=end)
    out = lines(capsys.readouterr().err)
    assert len(out) == 9, out
    for line in out:
        k = int(re.search(r", step (\d+) ", line).group(1)) - first
        t = float(re.search(r"t = (\S+) s", line).group(1))
        assert t == pytest.approx(t0 + k * 1e-5, abs=1e-12)
        expect = " (%.1f %% of the run to t = %.6g s, ETA %s), " % (100.0 * k / 30, end, engine._duration(4.0 * (30 - k)))
        assert expect in line, line
    # a run that stops on an event with endTime as its limit: the same numbers, as bounds
    t0, end = O.time, O.time + 40e-5
    first = O.iter
    mpmsdem.run(20, sdem, endTime=end, endIsBound=True)
    out = lines(capsys.readouterr().err)
    assert len(out) == 7, out   # a line every 3 steps of 4 s: the first at the run's start, without a share
    assert "%" not in out[0] and "at most" not in out[0]
    for line in out[1:]:
        k = int(re.search(r", step (\d+) ", line).group(1)) - first
        expect = " (at least %.1f %% of the run to t = %.6g s at most, ETA at most %s), " % (
            100.0 * k / 40, end, engine._duration(4.0 * (40 - k)))
        assert expect in line, line
    # the end must lie ahead
    with pytest.raises(ValueError, match=r"endTime = .*: must be finite and > O.time"):
        mpmsdem.run(1, sdem, endTime=O.time)
    with pytest.raises(ValueError, match=r"endTime = nan s"):
        mpmsdem.run(1, sdem, endTime=float("nan"))

def test_a_coupled_scene_prints_one_line_with_the_fields_of_its_verbose_engines(progress, capsys):
    sdem, mpm, coupled = engines(sdemVerbose=True, mpmVerbose=True, coupledVerbose=True)
    O.engines = [ForceResetter(), coupled.runner, NewtonIntegrator(gravity=(0, 0, 0), damping=0)]
    mpmsdem.run(7, coupled)
    out = lines(capsys.readouterr().err)
    assert len(out) == 2 and all(" of 7 steps, ETA " in line for line in out)
    for line in out:
        parts = line.split("; ")
        assert [p.split(":")[0] for p in parts] == ["mpmsdem", "SdemEngine", "MpmEngine", "CoupledEngine"], line
        assert re.fullmatch(r"CoupledEngine: \d+ MP-block contacts, critical step \S+ s, O.dt: set by the script",
                            parts[-1]), line
    sdem.verbose = mpm.verbose = False     # the coupling's own fields only
    mpmsdem.run(6, coupled)
    out = lines(capsys.readouterr().err)
    assert len(out) == 2 and all(line.split("; ")[1].startswith("CoupledEngine: ") for line in out)
    assert all(len(line.split("; ")) == 2 for line in out)
    coupled.verbose = False                # no engine verbose: no line
    mpmsdem.run(6, coupled)
    assert lines(capsys.readouterr().err) == []


def test_a_flow_stepped_from_python_prints_its_line_by_its_own_steps(progress, capsys):
    sdem, mpm, coupled = engines(mpmVerbose=True)
    progress.clock = lambda: 4.0 * mpm.solver.steps
    for _ in range(7):
        mpm.step(1e-5)
    out = lines(capsys.readouterr().err)
    assert [re.search(r"step (\d+), O.dt 1e-05 s, 4000.0 ms/step; MpmEngine: ", line).group(1) for line in out] \
        == ["3", "6"]


def test_durations_read_in_seconds_minutes_and_hours():
    assert [engine._duration(s) for s in (0.2, 59.0, 59.5, 61.0, 3599.0, 3725.0)] == \
        ["1 s", "59 s", "1 min 00 s", "1 min 01 s", "59 min 59 s", "1 h 02 min"]
