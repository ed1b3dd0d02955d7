"""The environment of the Python processes the tests start: the user's, not the test runner's.

A user's script finds YADE through ``import mpmsdem`` (it adds YADE's Python folder when
``import yade`` alone fails), not through a PYTHONPATH that names YADE. The tests start their
children with YADE's folder taken out of PYTHONPATH, so a child that imports ``yade`` before
``mpmsdem`` fails here as it would on a user's machine, however pytest itself was started; the
folder of the package under test comes first, so the child imports the same ``mpmsdem``."""
import os

import mpmsdem

PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(mpmsdem.__file__)))


def isYadeFolder(folder):
    """True for a folder that holds YADE's Python package (``yade/__init__.py``)."""
    return os.path.isfile(os.path.join(folder, "yade", "__init__.py"))


def env(**extra):
    """os.environ for a child process: PYTHONPATH = this package's folder plus the caller's
    entries that are not YADE's, with ``extra`` set on top (values as strings)."""
    kept = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p and not isYadeFolder(p)]
    e = dict(os.environ, PYTHONPATH=os.pathsep.join([PACKAGE_PARENT] + [p for p in kept if p != PACKAGE_PARENT]))
    e.update({k: str(v) for k, v in extra.items()})
    return e
