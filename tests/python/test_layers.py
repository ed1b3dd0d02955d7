"""The folders of pkg/ stack: each includes only the folders below it, and the two solvers not
each other, so that the blocks (pkg/sdem) build and read without the flow (pkg/mpm) and the
shared math and geometry (pkg/common) without either. Read from the source tree; no build."""
import os
import re

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PKG = os.path.join(ROOT, "pkg")

# Lowest first. Folders on one rank may not include each other.
LAYERS = [
    ("common",),          # types, errors, JSON helpers, host/device math, the terrain surface
    ("input",),           # readers of input formats: meshes, rasters
    ("sdem", "mpm"),      # the two solvers
    ("scene",),           # the MPM scene's parser, above the solver it configures
    ("io",),              # writers and the stored scenes read back for restarts
    ("coupling",),        # the coupled step, its scene, outputs and checkpoints
    ("run",),             # the run layer the driver calls
]
RANK = {folder: rank for rank, group in enumerate(LAYERS) for folder in group}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"/]+)/', re.M)


def includes():
    """(file relative to pkg/, its folder, the folder it includes) for every quoted include."""
    for dirpath, _, files in os.walk(PKG):
        for name in files:
            if not name.endswith((".hpp", ".cpp", ".cu", ".cuh")):
                continue
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, PKG)
            with open(path, encoding="utf-8") as f:
                text = f.read()
            for target in INCLUDE.findall(text):
                yield rel, rel.split(os.sep)[0], target


def test_every_folder_has_a_layer():
    folders = {d for d in os.listdir(PKG) if os.path.isdir(os.path.join(PKG, d))}
    assert folders == set(RANK), "pkg/ folders without a layer here (or layers without a folder): %s" % sorted(
        folders ^ set(RANK))


def violations(found):
    """The includes of ``found`` that go to a folder of the same rank or above."""
    return ["%s includes %s/ (rank %d, not below %d)" % (rel, target, RANK[target], RANK[folder])
            for rel, folder, target in found
            if target in RANK and target != folder and RANK[target] >= RANK[folder]]


def test_no_include_reaches_up_or_across():
    found = list(includes())
    assert len(found) > 100  # the walk saw the tree
    assert not violations(found), "\n".join(violations(found))


def test_the_rule_refuses_up_and_across_and_allows_down():
    assert len(violations([("sdem/A.hpp", "sdem", "mpm")])) == 1      # across: solver to solver
    assert len(violations([("mpm/B.cpp", "mpm", "scene")])) == 1      # up: solver to its parser
    assert len(violations([("common/C.hpp", "common", "input")])) == 1
    assert violations([("run/D.cpp", "run", "common"), ("scene/E.cpp", "scene", "mpm"),
                       ("mpm/F.hpp", "mpm", "mpm"), ("io/G.cpp", "io", "hdf5")]) == []


# The Python package stacks the same way, lowest first: the C++ module; what every engine uses
# (the runner base, the parameter tables, the terrain, analytic references); the two solvers'
# engines; the coupled engine; the package's own entry points (__init__: run, material); the
# scenes, drivers and studies built on them; the calibration over sweeps.
PACKAGE = os.path.join(ROOT, "py", "mpmsdem")
MODULE_LAYERS = [
    ("_mpmsdem",),
    ("_util", "engine", "parameters", "terrain", "analysis"),
    ("sdem", "mpm"),
    ("coupling",),
    ("__init__",),
    ("flume", "driver", "field", "sweep", "tradeoffs"),
    ("calibrate",),
]
MODULE_RANK = {m: rank for rank, group in enumerate(MODULE_LAYERS) for m in group}


def imports():
    """(module, the package module it imports) for every import of the package's own modules,
    at any depth of the file (an import inside a function is an arrow too); `from . import x`
    of a name that is no module (`run`, `material`) is an import of __init__."""
    import ast
    modules = {name[:-3] for name in os.listdir(PACKAGE) if name.endswith(".py")} | {"_mpmsdem"}
    for name in sorted(os.listdir(PACKAGE)):
        if not name.endswith(".py"):
            continue
        module = name[:-3]
        with open(os.path.join(PACKAGE, name), encoding="utf-8") as f:
            tree = ast.parse(f.read())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.level == 1 or node.module == "mpmsdem"):
                if node.module and node.module != "mpmsdem":
                    yield module, node.module.split(".")[0]
                else:
                    for alias in node.names:
                        yield module, alias.name if alias.name in modules else "__init__"
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name == "mpmsdem":
                        yield module, "__init__"


def module_violations(found):
    return ["%s.py imports %s (rank %d, not below %d)" % (module, target, MODULE_RANK[target], MODULE_RANK[module])
            for module, target in found
            if target != module and MODULE_RANK[target] >= MODULE_RANK[module]]


def test_every_module_has_a_layer():
    modules = {name[:-3] for name in os.listdir(PACKAGE) if name.endswith(".py")} | {"_mpmsdem"}
    assert modules == set(MODULE_RANK), "modules without a layer here (or layers without a module): %s" % sorted(
        modules ^ set(MODULE_RANK))


def test_no_import_reaches_up_or_across():
    found = list(imports())
    assert len(found) > 30  # the walk saw the package
    assert ("coupling", "mpm") in found and ("flume", "__init__") in found  # imports in functions, names of __init__
    assert not module_violations(found), "\n".join(module_violations(found))


def test_the_module_rule_refuses_up_and_across():
    assert len(module_violations([("sdem", "mpm")])) == 1          # across
    assert len(module_violations([("engine", "coupling")])) == 1   # up
    assert len(module_violations([("coupling", "__init__")])) == 1
    assert module_violations([("calibrate", "sweep"), ("flume", "__init__"), ("mpm", "engine")]) == []
