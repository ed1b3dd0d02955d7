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
* :class:`MpmEngine` — the MPM granular-flow solver (CPU double, or CUDA float/double).
* :class:`CoupledEngine` — the two coupled every step (paper §2.3): material points push the
  blocks and the blocks push back; ``coupled.runner`` goes between ``ForceResetter`` and
  ``NewtonIntegrator``.
* :mod:`mpmsdem.analysis` — analytic references (paper Eq 19, runout fits, Froude numbers).
"""
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


_import_yade()

from ._mpmsdem import SpheroPolyhedron, SdemMat, cudaAvailable  # noqa: E402
from .sdem import SdemEngine, _dispatch  # noqa: E402,F401  (_dispatch: the engines' PyRunner commands)
from .mpm import MpmEngine  # noqa: E402
from .coupling import CoupledEngine  # noqa: E402
from . import analysis  # noqa: E402

__all__ = ["SpheroPolyhedron", "SdemMat", "SdemEngine", "MpmEngine", "CoupledEngine", "analysis", "cudaAvailable", "material", "run"]


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
    from .sdem import _material
    return _material(dict(density=density, friction=friction, poisson=poisson, barrierStiffness=barrierStiffness,
                          normalDamping=normalDamping, tangentialDamping=tangentialDamping))


def run(steps, *engines):
    """Run YADE for ``steps`` steps (``O.run(steps, True)``) and raise RuntimeError if one of
    ``engines`` (SdemEngine, MpmEngine) stopped the run. YADE reports an error raised inside a
    PyRunner on its log and stops, but does not always raise it from ``O.run``."""
    from yade import O
    for e in engines:  # a misplaced or missing runner: say so now, not after a silent run
        if isinstance(e, (SdemEngine, MpmEngine)):
            e._checkEngines()
    try:
        O.run(int(steps), True)
    except RuntimeError:
        for e in engines:
            e.check()
        raise
    for e in engines:
        e.check()
