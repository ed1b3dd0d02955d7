"""Shared fixtures of the YADE-level tests: a clean YADE scene per test."""
import pytest

import mpmsdem  # noqa: F401  (imports yade first, registers converters)
from yade import O

@pytest.fixture(autouse=True)
def clean_scene():
    O.reset()
    yield
    O.reset()

