"""The scene's parameter tables through the binding: the committed reference page is the one they
generate, a value out of a table's range is refused naming the key and that range, and the Python
API's names and defaults are the tables'."""
import inspect
import json
import os

import pytest

import mpmsdem
from mpmsdem import driver, parameters
from mpmsdem.coupling import PAIR_KEYS

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PAGE = os.path.join(ROOT, "docs", "parameters.md")


def scene(**changes):
    """A small MPM scene (grid 40 x 10 x 20 cells of 0.01 m); ``changes`` by key path."""
    s = {"grid": {"dx": 0.01, "cells": [40, 10, 20]},
         "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
         "particles": [{"lo": [0.02, 0.02, 0.02], "hi": [0.1, 0.08, 0.1], "ppc": 1}],
         "run": {"duration": 0.1}}
    for key, value in changes.items():
        *path, leaf = key.split(".")
        d = s
        for part in path:
            d = d.setdefault(part, {})
        d[leaf] = value
    return json.dumps(s)


def test_committed_page_is_the_generated_one():
    with open(PAGE, encoding="utf-8") as f:
        committed = f.read()
    assert committed == parameters.markdown(), (
        "docs/parameters.md differs from the tables: regenerate it with "
        "`PYTHONPATH=build/python python3 scripts/gen_parameters.py`")


def test_page_has_a_row_per_parameter_and_is_linked():
    page = parameters.markdown()
    for p in parameters.parameters():
        assert "| `%s` |" % p["leaf"] in page, p["key"]
    for index in ("README.md", os.path.join("docs", "README.md")):
        with open(os.path.join(ROOT, index), encoding="utf-8") as f:
            assert "parameters.md" in f.read(), index


@pytest.mark.parametrize("key, value", [("material.poisson_ratio", 0.5), ("material.mu_s", -0.1),
                                        ("cfl", 1.5), ("run.dt_factor", 0), ("grid.dx", -0.01)])
def test_range_violation_names_the_key_and_the_tables_range(key, value):
    p = parameters.parameter(key)
    with pytest.raises(ValueError) as e:
        mpmsdem._mpmsdem.MpmSolver(scene(**{key: value}))
    assert "%s = %g" % (key, value) in str(e.value)
    assert "must be " + p["range"] in str(e.value)


def test_hand_checked_rows():
    mu2 = parameters.parameter("material.mu_2")
    assert (mu2["required"], mu2["range"], mu2["equation"]) == (True, "[mu_s, inf)", "Eq B.2")
    poisson = parameters.parameter("material.poisson_ratio")
    assert (poisson["lo"], poisson["hi"], poisson["loInclusive"], poisson["hiInclusive"]) == (0, 0.5, True, False)
    assert poisson["range"] == "in [0, 0.5)"
    cfl = parameters.parameter("cfl")
    assert (cfl["default"], cfl["range"], cfl["python"]) == (0.3, "in (0, 1]", "cfl")
    viscosity = parameters.parameter("flip_viscosity")
    assert (viscosity["default"], viscosity["unit"], viscosity["python"]) == (0.005, "m^2/s", "flipViscosity")
    assert parameters.parameter("material.I0")["default"] == 0.279
    assert parameters.parameter("run.vtk")["choices"] == ["raw", "ascii", "none"]
    assert parameters.parameter("grid.cells")["range"] == "an integer in [4, 2^30]"
    kc = parameters.parameter("block_materials.<name>.barrier_stiffness")
    assert (kc["default"], kc["unit"], kc["python"], kc["equation"]) == (1e4, "N/m", "barrierStiffness", "Eq 10")
    with pytest.raises(KeyError):
        parameters.parameter("material.mu_3")


def test_python_defaults_are_the_tables():
    engine = inspect.signature(mpmsdem.MpmEngine).parameters
    assert engine["cfl"].default == parameters.parameter("cfl")["default"]
    assert engine["keepLastGoodState"].default is (parameters.parameter("keep_last_good_state")["defaultText"] == "true")
    material = inspect.signature(mpmsdem.material).parameters
    for p in parameters.parameters("block_materials.<name>"):
        if p["python"] in material and p["default"] is not None:
            assert material[p["python"]].default == p["default"], p["key"]


def test_python_names_come_from_the_tables():
    assert driver.RUN_KEYS["outputEvery"] == "output_every"
    assert driver.RUN_KEYS["snapshotWhenFrontAt"] == "snapshot_when_front_at"
    assert "duration" not in driver.RUN_KEYS and "dt" not in driver.RUN_KEYS
    assert driver.PROBE_KEYS == {"x": "x", "halfWidth": "half_width", "bedZ": "bed_z", "minPoints": "min_points",
                                 "window": "window"}
    assert PAIR_KEYS == ("friction", "barrierStiffness", "poisson", "normalDamping", "tangentialDamping")
    for section in {parameters.sectionOf(p["key"]) for p in parameters.parameters()}:
        names = [p["python"] for p in parameters.parameters(section) if p["python"]]
        assert len(names) == len(set(names)), section
