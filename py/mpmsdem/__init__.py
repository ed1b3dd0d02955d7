"""mpmsdem — coupled MPM–SDEM for flow-type landslides carrying rigid objects, as a YADE plugin.

Import it from a YADE script (``yade -n -x script.py``) or from Debian's ``/usr/bin/python3``
with YADE's Python path set; YADE is imported first so that its Vector3/Quaternion
converters are registered for our C++ module.

Main entry points (all SI units):

* :class:`SdemMat` — contact material of blocks (density, friction, Poisson ratio, barrier
  stiffness k_c, dampings), paper Eqs 9–11.
* :class:`SpheroPolyhedron` — the shape: eroded core + sweep sphere R (paper §2.2).
* :class:`SdemEngine` — creates YADE bodies with sphero-polyhedral shapes and computes their
  contact forces every step (put ``engine.runner`` between ``ForceResetter`` and
  ``NewtonIntegrator`` in ``O.engines``).
* :class:`MpmEngine` — the MPM granular-flow solver (CPU or CUDA, float or double).
* :class:`CoupledEngine` — the two coupled every step (paper §2.3): material points push the
  blocks and the blocks push back; ``coupled.runner`` goes between ``ForceResetter`` and
  ``NewtonIntegrator``.
* :mod:`mpmsdem.analysis` — analytic references (paper Eq 19, runout fits, Froude numbers).
* :mod:`mpmsdem.tradeoffs` — measured settings against error and cost; ``propose(error)``.
* :mod:`mpmsdem.parameters` — every scene key's Python name, unit, default and range.
"""
import math
import os
import sys


def _import_yade():
    try:
        import yade  # noqa: F401
        return
    except ImportError:
        pass
    for cand in ("/usr/lib/x86_64-linux-gnu/yade-double/py", "/usr/lib/aarch64-linux-gnu/yade-double/py"):
        if os.path.isdir(cand) and cand not in sys.path:
            sys.path.insert(0, cand)
    try:
        import yade  # noqa: F401
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise ImportError("mpmsdem needs YADE: install the Debian packages yade and python3-yade "
                          "(`make deps`), and run with /usr/bin/python3 or `yade`") from e


def _import_core():
    """Import the C++ module, or raise an ImportError that says which copy of the package lacks it."""
    try:
        from . import _mpmsdem  # noqa: F401
    except ImportError as e:
        here = os.path.dirname(os.path.abspath(__file__))
        built = [f for f in os.listdir(here) if f.startswith("_mpmsdem") and f.endswith(".so")]
        if built:  # the file is there but does not load: a library or the Python version
            why = "its C++ module %s is there but does not load (%s)" % (built[0], e)
        else:
            why = ("it has no C++ module _mpmsdem*.so: it is a source copy, not a built one. A folder named "
                   "mpmsdem in the current directory, or on sys.path before the installed package, shadows "
                   "the installed one")
        raise ImportError("mpmsdem was imported from %s, and %s. Build and install it (`make install`), or put "
                          "the build's python folder first on PYTHONPATH" % (here, why)) from e


_import_yade()
_import_core()

from ._mpmsdem import SpheroPolyhedron, SdemMat, cudaAvailable  # noqa: E402
from .engine import _dispatch  # noqa: E402,F401  (the engines' PyRunner commands, saved scenes' too)
from .sdem import SdemEngine  # noqa: E402
from .mpm import MpmEngine  # noqa: E402
from .coupling import CoupledEngine  # noqa: E402
from . import analysis  # noqa: E402

__all__ = ["SpheroPolyhedron", "SdemMat", "SdemEngine", "MpmEngine", "CoupledEngine", "analysis", "cudaAvailable", "material", "run",
           "saveCheckpoint", "lastCheckpoint", "loadCheckpoint"]


def material(density, friction=0.5, poisson=0.3, barrierStiffness=1e4, normalDamping=0.0,
             tangentialDamping=0.1):
    """A validated :class:`SdemMat`.

    :param density: mass density [kg/m^3], > 0
    :param friction: Coulomb coefficient mu [-], >= 0 (Eq 9)
    :param poisson: Poisson ratio nu [-], in (-1, 0.5); K_t = k_n / (2 (1 + nu)) (Eq 11)
    :param barrierStiffness: k_c [N/m], > 0 (Eq 10 read as a force; paper: 1e4)
    :param normalDamping: fraction of critical [-], >= 0 (0: elastic barrier, as the paper)
    :param tangentialDamping: fraction of critical [-], >= 0 (c_t of Eq 9)
    """
    from ._util import _material
    return _material(dict(density=density, friction=friction, poisson=poisson, barrierStiffness=barrierStiffness,
                          normalDamping=normalDamping, tangentialDamping=tangentialDamping))


def run(steps, *engines, endTime=None, endIsBound=False):
    """Run YADE for ``steps`` steps and raise RuntimeError if one of ``engines`` (SdemEngine,
    MpmEngine, CoupledEngine) stopped the run, with the engine's message (YADE reports an error
    raised inside a PyRunner on its log and stops, but does not always raise it from ``O.run``).

    The steps are taken in the calling thread, one ``O.step()`` each: ``O.run(n, True)`` hands
    them to YADE's worker thread and waits for it in 40 ms polls, which cost more than the steps
    when a script runs in short chunks to sample its scene (docs/benchmarks.md). An
    ``O.pause()`` from an engine therefore does not end this call early; use ``O.run`` for that.

    The scene's progress line (every 10 s of wall time, when an engine is verbose) says how much
    of the ``steps`` is done and when they will be. A script that runs in chunks (to sample its
    scene, or with a step that changes) gives each chunk the run's ``endTime`` [s, simulated,
    > O.time]: the line then counts down the simulated time to it over all the chunks. A run that
    stops on an event (a front passing a station) with a time limit gives the limit as
    ``endTime`` and ``endIsBound=True``: the line then gives the share and the ETA as bounds
    ("at most")."""
    from yade import O
    from yade.wrapper import PyRunner
    from .engine import _PROGRESS
    for e in engines:  # a misplaced or missing runner, a block state no scene has: say so now
        e._beforeRun()
    # Before each command of a PyRunner whose updateGlobals is on (YADE's default), YADE copies
    # the local names of the Python function that called O.step() -- this one -- into the
    # script's globals: a script's own `steps` or `engines` would be overwritten. Our runners
    # have it off; a script's own runners are switched off for this call and back after (their
    # commands still run in the script's globals, which is what they read).
    userRunners = [r for r in O.engines if isinstance(r, PyRunner) and r.updateGlobals]
    for r in userRunners:
        r.updateGlobals = False
    if endTime is not None:
        endTime = float(endTime)
        if not (math.isfinite(endTime) and endTime > O.time):
            raise ValueError("endTime = %r s: must be finite and > O.time = %.9g s (the run's end, simulated)"
                             % (endTime, O.time))
    _PROGRESS.running(int(steps), endTime, bool(endIsBound))
    try:
        for _ in range(int(steps)):
            O.step()
    except Exception:
        for e in engines:
            e.check()
        raise
    finally:
        _PROGRESS.running(None)
        for r in userRunners:
            r.updateGlobals = True
    for e in engines:
        e.check()
    for e in engines:  # the series end with the state the run reached (files at their own cadence)
        e.finish(False)


# What each engine kind writes into a checkpoint folder, and how it is rebuilt.
_CHECKPOINT_FILES = (("coupled", "coupled"), ("sdem", "sdem.json"), ("mpm", "mpm.h5"))


def saveCheckpoint(folder, engine, keep=2):
    """Save the YADE scene (``O.save``) and ``engine`` (an SdemEngine, MpmEngine or
    CoupledEngine) as one checkpoint, ``folder/ck_<O.iter>/``, and keep the newest ``keep``
    (>= 1). The files are written into a temporary folder that is renamed when complete, so a
    run killed at any instant leaves only whole checkpoints (:func:`lastCheckpoint` finds the
    newest). Returns the checkpoint's path."""
    import shutil
    from yade import O
    if not (isinstance(keep, int) and keep >= 1):
        raise ValueError("keep = %r: must be an integer >= 1" % (keep,))
    kind = _engineKind(engine)
    os.makedirs(folder, exist_ok=True)
    name = "ck_%012d" % O.iter
    final, tmp = os.path.join(folder, name), os.path.join(folder, name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    O.save(os.path.join(tmp, "scene.yade.gz"))
    if kind == "coupled":
        engine.save(os.path.join(tmp, "coupled"))
    else:
        engine.save(os.path.join(tmp, dict(_CHECKPOINT_FILES)[kind]))
    shutil.rmtree(final, ignore_errors=True)
    os.rename(tmp, final)
    done = sorted(d for d in os.listdir(folder) if d.startswith("ck_") and not d.endswith(".tmp"))
    for d in done[:-keep]:
        shutil.rmtree(os.path.join(folder, d), ignore_errors=True)
    return final


def lastCheckpoint(folder):
    """The newest complete checkpoint of :func:`saveCheckpoint` in ``folder`` (a path), or
    None when there is none; a half-written one left by a killed run is removed."""
    import shutil
    if not os.path.isdir(folder):
        return None
    names = sorted(os.listdir(folder))
    for d in names:
        if d.startswith("ck_") and d.endswith(".tmp"):
            shutil.rmtree(os.path.join(folder, d), ignore_errors=True)
    done = [d for d in names if d.startswith("ck_") and not d.endswith(".tmp")]
    return os.path.join(folder, done[-1]) if done else None


def loadCheckpoint(path, **restoreKw):
    """Continue from a checkpoint of :func:`saveCheckpoint`: ``O.load`` its scene, rebuild the
    engine with its ``restore`` (``restoreKw``: outputs and other arguments of that method)
    and put the new runner in ``O.engines`` where the saved one was. Returns the engine; run
    on with ``mpmsdem.run(n, engine)``."""
    from yade import O
    from yade.wrapper import PyRunner
    files = os.listdir(path) if os.path.isdir(path) else []
    if "scene.yade.gz" not in files:
        raise ValueError("path = %r: not a checkpoint of mpmsdem.saveCheckpoint (no scene.yade.gz)" % (path,))
    O.load(os.path.join(path, "scene.yade.gz"))
    if "coupled.coupled.json" in files:
        engine = CoupledEngine.restore(os.path.join(path, "coupled"), **restoreKw)
    elif "sdem.json" in files:
        engine = SdemEngine.restore(os.path.join(path, "sdem.json"), **restoreKw)
    elif "mpm.h5" in files:
        engine = MpmEngine.restore(os.path.join(path, "mpm.h5"), **restoreKw)
    else:
        raise ValueError("path = %r: no engine state (sdem.json, mpm.h5 or coupled.*) beside scene.yade.gz" % (path,))
    engines = list(O.engines)
    slots = [i for i, e in enumerate(engines) if isinstance(e, PyRunner) and "mpmsdem')._dispatch(" in e.command]
    if len(slots) != 1:
        raise ValueError("path = %r: the saved O.engines hold %d mpmsdem runners, expected 1: set O.engines "
                         "yourself with the returned engine's runner" % (path, len(slots)))
    engines[slots[0]] = engine.runner
    O.engines = engines
    return engine


def _engineKind(engine):
    for kind, cls in (("coupled", CoupledEngine), ("sdem", SdemEngine), ("mpm", MpmEngine)):
        if isinstance(engine, cls):
            return kind
    raise ValueError("engine = %r: must be an mpmsdem SdemEngine, MpmEngine or CoupledEngine" % (engine,))
