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
