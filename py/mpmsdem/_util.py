"""Helpers of the mpmsdem engines that belong to none of them: checked vectors and
orientations, SDEM materials from and to plain values, the output cadence of a restart."""
import math

from yade.minieigenHP import Quaternion, Vector3

from . import _mpmsdem


def _nextOnGrid(last, every):
    """The first multiple of ``every`` after ``last``: a restarted run keeps the record times of
    the unbroken one, also when its last record was an extra one (finish()) between them."""
    return (math.floor(last / every * (1 + 1e-12) + 1e-9) + 1) * every


def _vec(v, name):
    # NaN/inf caught here, where the caller can be named: later they surface as a blow-up
    # blamed on the time step.
    try:
        if len(v) != 3:
            raise TypeError
        out = Vector3(float(v[0]), float(v[1]), float(v[2]))
    except (TypeError, ValueError):
        raise ValueError("%s = %r: must be a 3-vector of finite numbers [m]" % (name, v)) from None
    if not all(math.isfinite(out[k]) for k in range(3)):
        raise ValueError("%s = %r: must be a 3-vector of finite numbers [m]" % (name, v))
    return out


def _quat(q):
    try:
        if not isinstance(q, Quaternion):
            if len(q) != 4:
                raise TypeError
            q = Quaternion(*[float(c) for c in q])
        c = [q[k] for k in range(4)]
    except (TypeError, ValueError):
        raise ValueError("ori = %r: must be a Quaternion (or 4 finite numbers w, x, y, z)" % (q,)) from None
    n = math.sqrt(sum(x * x for x in c))
    if not (math.isfinite(n) and n > 0):
        raise ValueError("ori = %r: must be a Quaternion of finite, not all zero components" % (q,))
    return q


def _material(d):
    m = _mpmsdem.SdemMat()
    for k, v in d.items():
        try:
            setattr(m, k, float(v))
        except (TypeError, ValueError):
            raise ValueError("%s = %r: must be a number (see mpmsdem.material for its range)" % (k, v)) from None
    m.validate()
    return m


def _matDict(m):
    return {"density": m.density, "friction": m.friction, "poisson": m.poisson,
            "barrierStiffness": m.barrierStiffness, "normalDamping": m.normalDamping,
            "tangentialDamping": m.tangentialDamping}
