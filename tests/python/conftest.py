"""Shared fixtures of the YADE-level tests: a clean YADE scene and yade.plot per test (both are
process-wide: a test that leaves data in either changes what the next one in its worker reads)."""
import pytest

import mpmsdem  # noqa: F401  (imports yade first, registers converters)
from yade import O, plot

@pytest.fixture(autouse=True)
def clean_scene():
    O.reset()
    plot.reset()
    yield
    O.reset()
    plot.reset()

