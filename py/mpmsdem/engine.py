"""What the mpmsdem engines share: their YADE runner, the ``O.engines`` check, failure handling
and the scene's progress line.

An engine (:class:`~mpmsdem.SdemEngine`, :class:`~mpmsdem.MpmEngine`,
:class:`~mpmsdem.CoupledEngine`) is stepped by a ``PyRunner`` that it puts into ``O.engines``
(:attr:`Engine.runner`). A step that fails stops the run with the error recorded on the engine,
which :meth:`Engine.check` (and :func:`mpmsdem.run`) raises again: YADE reports an error raised
inside a ``PyRunner`` on its log and stops, but ``O.run`` does not always raise it.
"""
import math
import sys
import time
import warnings
import weakref

from yade import O
from yade.wrapper import PyRunner

DT_CHECKS = ("raise", "warn")


# Step functions of the engines of this process, by the name their PyRunner command calls.
_REGISTRY = {}


def _stepRunner(kind, key, step, label, initRun=True):
    """Register ``step`` and return the PyRunner (every step) that calls it, for ``O.engines``.
    The command goes through :func:`_dispatch` rather than naming a function in ``__main__``: a
    scene saved with ``O.save`` and loaded in another process keeps the command but not the
    function, and YADE would then report only a ``NameError`` on a generated name. The runner's
    ``updateGlobals`` is off: YADE's default copies the local names of the Python function that
    called ``O.step()`` into the script's globals before each command (``mpmsdem.run``'s
    ``steps`` would overwrite a script's own ``steps``), and the command needs none of them."""
    name = "%s_%d" % (kind, key)
    _REGISTRY[name] = step
    return PyRunner(command="__import__('mpmsdem')._dispatch(%r)" % name, iterPeriod=1, initRun=initRun, label=label,
                    updateGlobals=False)


def _dispatch(name):
    """Run the step registered as ``name`` (the PyRunner commands of mpmsdem engines; saved
    scenes hold ``mpmsdem._dispatch``, so it stays there)."""
    try:
        step = _REGISTRY[name]
    except KeyError:
        raise RuntimeError(
            "this mpmsdem engine (%r) is not registered in this process: after O.load(), rebuild it with "
            "mpmsdem.SdemEngine.restore(...) or mpmsdem.MpmEngine.restore(...) and put its runner in O.engines in "
            "place of the loaded one (e.g. O.engines = [ForceResetter(), engine.runner, NewtonIntegrator(...)])"
            % name) from None
    step()


class Engine:
    """The part of an mpmsdem engine that is the same for all: the runner that YADE calls
    (:attr:`runner`, registered for :func:`_dispatch`), the check of ``O.engines``, the error of
    a failed step (:attr:`error`, :meth:`check`) and its share of the scene's progress line.

    A subclass sets ``_name`` (its class as messages name it), ``_runnerName`` (its runner as a
    script names it) and ``_between`` (why its runner goes between ``ForceResetter`` and
    ``NewtonIntegrator``) or ``_missing`` (the error when its runner, which needs no order, is
    not in ``O.engines``); it defines ``_step`` (one step of the runner), ``_lastGoodState``
    (keep the last good state after a failed step, say where) and ``_progressFields`` (its
    fields of the progress line), and calls :meth:`_bindRunner` in its constructor."""

    _between = None
    error = None      # "step N (t = ... s): what failed [...]" once a step failed
    verbose = False   # whether the engine has fields in the progress line
    _checkedOrder = False  # O.engines passed the check at a step (a plain O.run has no other check)

    def _bindRunner(self, kind, label):
        self.runner = _stepRunner(kind, id(self), self._step, label)

    def _checkEngines(self):
        """ValueError unless ``O.engines`` holds the runner where it must be; returns the
        NewtonIntegrator that follows it, or None for a runner without an order."""
        from yade.wrapper import ForceResetter, NewtonIntegrator
        engines = list(O.engines)
        me = engines.index(self.runner) if self.runner in engines else -1
        if self._between is None:
            if me < 0:
                raise ValueError(self._missing)
            return None
        resetters = [i for i, e in enumerate(engines) if isinstance(e, ForceResetter)]
        newtons = [i for i, e in enumerate(engines) if isinstance(e, NewtonIntegrator)]
        if me < 0 or not resetters or not newtons or not (resetters[0] < me < newtons[0]):
            raise ValueError("O.engines = [%s]: must be [ForceResetter(), %s, NewtonIntegrator(...)] (in this order; "
                             "other engines may come before or after): %s"
                             % (", ".join(type(e).__name__ for e in engines), self._runnerName, self._between))
        return engines[newtons[0]]

    def _checkEnginesOnce(self):
        """:meth:`_checkEngines` at the runner's first step (a plain ``O.run`` has no check
        before it), its error recorded for :meth:`check`; again at the next step until it
        passes."""
        if self._checkedOrder:
            return
        try:
            self._checkEngines()
        except ValueError as e:
            self._recordError(e)
            raise
        self._checkedOrder = True

    def _beforeRun(self):
        """What :func:`mpmsdem.run` checks before its first step."""
        self._checkEngines()

    def _recordError(self, e):
        self.error = "step %d (t = %.6g s): %s" % (O.iter, O.time, e)

    def _fail(self, e):
        """Record the error of a failed step and keep the last good state (``_lastGoodState``
        says where it is)."""
        self._recordError(e)
        self.error += self._lastGoodState(e)

    def check(self):
        """Raise RuntimeError if a step failed (YADE stops the run but O.run does not raise)."""
        if self.error:
            raise RuntimeError("mpmsdem.%s stopped the run at %s" % (self._name, self.error))

    def _stepping(self, t, steps, dt):
        """Called as a step starts, before it changes anything (see :class:`_SceneProgress`)."""
        _PROGRESS.stepping(self, t, steps, dt)

    def _progressParts(self, perStep):
        """(name, fields) of the engine's share of the progress line, ``perStep`` the wall time
        of a step [s]: none unless verbose."""
        return [(self._name, self._progressFields(perStep))] if self.verbose else []


class _StepControl:
    """``dtAuto`` and ``dtMax`` of an engine whose bridge has ``checkFactor``,
    ``autoStep(bodies, factor, critical, lastDt)`` and ``timeStepWarnings`` (SdemEngine,
    CoupledEngine), and the warning of ``dtCheck="warn"``."""

    @property
    def dtAuto(self):
        """None, or the factor f of the step set every step (``dtAuto`` of the constructor)."""
        return self._dtAuto

    @dtAuto.setter
    def dtAuto(self, value):
        if value is not None and not (isinstance(value, (int, float)) and 0 < value <= 1):
            raise ValueError("dtAuto = %r: must be None or a factor in (0, 1] of the critical step" % (value,))
        self._bridge.checkFactor = 1.0 if value is None else 2.0
        self._dtAuto = value

    @property
    def dtMax(self):
        """None, or the largest ``O.dt`` that ``dtAuto`` sets [s]."""
        return self._dtMax

    @dtMax.setter
    def dtMax(self, value):
        if value is not None and not (isinstance(value, (int, float)) and value > 0):
            raise ValueError("dtMax = %r s: must be None or > 0" % (value,))
        self._dtMax = value

    def _setAutoStep(self, critical, contactsKnown):
        """With dtAuto, set O.dt for the step about to run; critical: a bound on the critical
        step besides the bridge's own [s] (inf: none). Before the contacts are known (first
        step) O.dt is only capped."""
        if self._dtAuto is None:
            return
        step = self._bridge.autoStep(O.bodies, self._dtAuto, critical, O.dt if contactsKnown else 0.0)
        if self._dtMax is not None:
            step = min(step, self._dtMax)
        O.dt = step if contactsKnown else min(O.dt, step)

    def _warnTimeStep(self, what, critical):
        """With ``dtCheck="warn"``, a RuntimeWarning at the first step whose O.dt exceeded
        ``what``, the critical step ``critical`` [s]; the later ones are only counted."""
        if self.dtCheck == "warn" and self._bridge.timeStepWarnings > self._warned:
            if self._warned == 0:
                warnings.warn("mpmsdem.%s: O.dt = %g s exceeds the %s %g s at step %d"
                              % (self._name, O.dt, what, critical, O.iter), RuntimeWarning)
            self._warned = self._bridge.timeStepWarnings


class _SceneProgress:
    """The progress line of the scene on stderr: one every :attr:`interval` seconds of wall time
    however many mpmsdem engines step in it, each verbose one adding its fields. The first
    engine to step in a YADE step writes the line, before it changes anything: every engine's
    state is then the one the steps so far have left. Within :func:`mpmsdem.run` the line also
    says how much of the run is done and when it will end: of its ``steps``, or, where a script
    runs in chunks and gives the run's ``endTime``, of the simulated time to it, counted from the
    first chunk with that end."""

    interval = 10.0

    def __init__(self):
        self.clock = time.monotonic
        self._steps = None     # the steps done when the current step started
        self._engines = []     # weak references to the engines that started a step since then, in their order
        self._last = None      # (wall time, steps) of the last line, or of the first step seen
        self._run = None       # (steps done, steps at the end, wall time) of mpmsdem.run's steps
        self._span = None      # (O.time, wall time, endTime, endTime a bound) when chunks run to endTime began

    def stepping(self, engine, t, steps, dt):
        """``engine`` starts a step with ``steps`` steps done, at time ``t`` [s] after a step
        ``dt`` [s] (O.time, O.iter and O.dt in YADE)."""
        if steps != self._steps:
            if self._steps is None or steps != self._steps + 1:
                self._last = (self.clock(), steps)  # a new scene, or stepping again: no rate across the gap
            else:
                self._report(t, steps, dt)
            self._steps, self._engines = steps, []
        if not any(r() is engine for r in self._engines):
            # weak: a scene's engines are freed with it (their files closed) whatever is printed
            self._engines.append(weakref.ref(engine))

    def _report(self, t, steps, dt):
        now = self.clock()
        wall, before = self._last
        if now - wall <= self.interval:
            return
        self._last = (now, steps)
        perStep = (now - wall) / max(steps - before, 1)
        parts = [p for r in self._engines if r() is not None for p in r()._progressParts(perStep)]
        if not parts:
            return
        line = "mpmsdem: t = %.6g s, step %d" % (t, steps)
        if self._run is not None and self._span is not None and t > self._span[0]:
            t0, start, end, bound = self._span
            line += (" (at least %.1f %% of the run to t = %.6g s at most, ETA at most %s)" if bound else
                     " (%.1f %% of the run to t = %.6g s, ETA %s)") % (
                100.0 * (t - t0) / (end - t0), end, _duration((now - start) / (t - t0) * max(end - t, 0.0)))
        elif self._run is not None and self._run[0] < steps <= self._run[1]:
            first, end, start = self._run
            line += " (%.1f %% of %d steps, ETA %s)" % (100.0 * (steps - first) / (end - first), end - first,
                                                          _duration((now - start) / (steps - first) * (end - steps)))
        line += ", O.dt %.3g s, %s" % (dt, _perStep(perStep))
        print("; ".join([line] + ["%s: %s" % p for p in parts]), file=sys.stderr, flush=True)

    def running(self, steps, endTime=None, endIsBound=False):
        """:func:`mpmsdem.run` is about to take ``steps`` steps from O.iter (None: it is done), as
        a chunk of a run to ``endTime`` [s] (at the latest, with ``endIsBound``) where one is
        given: the span (and its rate) goes on from the chunk before while the end is the same and
        O.time has not gone back."""
        if steps is None:
            self._run = None
            return
        self._run = (O.iter, O.iter + steps, self.clock())
        if endTime is None:
            self._span = None
        elif self._span is None or self._span[2:] != (endTime, endIsBound) or not self._span[0] <= O.time < endTime:
            self._span = (O.time, self.clock(), endTime, endIsBound)


_PROGRESS = _SceneProgress()


def _perStep(seconds):
    return "%.1f us/step" % (1e6 * seconds) if seconds < 1e-3 else "%.1f ms/step" % (1e3 * seconds)


def _duration(seconds):
    """A wall time to the second, in h, min and s."""
    s = int(math.ceil(seconds))
    if s < 60:
        return "%d s" % s
    if s < 3600:
        return "%d min %02d s" % divmod(s, 60)
    return "%d h %02d min" % (s // 3600, s % 3600 // 60)
