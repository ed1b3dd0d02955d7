"""The tests and scripts run as a user's would: no dependence on a PYTHONPATH that make sets.

On a fresh machine make computed YADE's folder before installing YADE, so the children of four
tests got a PYTHONPATH without it and failed to ``import yade``; a second run passed. A user's
script finds YADE through ``import mpmsdem`` (``mpmsdem._import_yade``), so every file that
may run in a plain python3 must import mpmsdem before yade, in every function that imports
yade. The children the tests start get YADE's folder taken out of their PYTHONPATH
(tests/python/children.py), so a file that breaks the rule fails its test wherever pytest runs;
the rule is also checked here for the scripts no test starts."""
import ast
import os
import subprocess
import sys

import children

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SOURCES = ("tests", "scripts", "examples")


def _imports(node):
    if isinstance(node, ast.Import):
        return [a.name.split(".")[0] for a in node.names]
    if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
        return [node.module.split(".")[0]]
    return []


def _ownStatements(scope):
    """Nodes of one module or function body in source order, without nested functions/classes."""
    out, stack = [], list(scope.body)
    while stack:
        n = stack.pop()
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        out.append(n)
        stack.extend(ast.iter_child_nodes(n))
    return sorted((n for n in out if hasattr(n, "lineno")), key=lambda n: (n.lineno, n.col_offset))


def yadeBeforeMpmsdem(source):
    """Lines where ``yade`` is imported with no ``mpmsdem`` import before it in the same body
    (or anywhere at module level, for a function: functions run after the module's imports)."""
    tree = ast.parse(source)
    moduleLevel = [n.lineno for n in _ownStatements(tree) if "mpmsdem" in _imports(n)]
    bad = []
    for scope in ast.walk(tree):
        if not isinstance(scope, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        seen = bool(moduleLevel) and not isinstance(scope, ast.Module)
        for n in _ownStatements(scope):
            names = _imports(n)
            seen = seen or "mpmsdem" in names
            if "yade" in names and not seen:
                bad.append(n.lineno)
                break
    return sorted(bad)


def test_the_rule_catches_what_failed_on_a_fresh_machine():
    # the child of test_determinism.py before the fix, and two variants the rule must allow
    assert yadeBeforeMpmsdem("def child():\n    from yade import O\n") == [2]
    assert yadeBeforeMpmsdem("def f():\n    from yade import O\n    import mpmsdem.driver\n") == [2]
    assert yadeBeforeMpmsdem("def f():\n    import mpmsdem.driver\n    from yade import O\n") == []
    assert yadeBeforeMpmsdem("def f():\n    from yade import O\nimport mpmsdem\n") == []
    assert yadeBeforeMpmsdem("from yade import O\nimport mpmsdem\n") == [1]


def test_every_script_imports_mpmsdem_before_yade():
    bad = []
    for top in SOURCES:
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            for name in sorted(files):
                if name.endswith(".py"):
                    path = os.path.join(folder, name)
                    with open(path) as f:
                        bad += ["%s:%d" % (os.path.relpath(path, ROOT), line) for line in yadeBeforeMpmsdem(f.read())]
    assert not bad, ("these import yade before mpmsdem, which fails in a plain python3 without YADE's folder on "
                     "PYTHONPATH (import mpmsdem first: it finds YADE): %s" % ", ".join(bad))


def test_a_child_without_yade_on_its_path_finds_it_through_mpmsdem():
    env = children.env()
    assert not any(children.isYadeFolder(p) for p in env["PYTHONPATH"].split(os.pathsep))
    bare = subprocess.run([sys.executable, "-c", "import yade"], env=env, capture_output=True, text=True)
    assert bare.returncode != 0 and "No module named 'yade'" in bare.stderr, (
        "YADE is importable without mpmsdem here (a .pth file or site setting?): the children would not test "
        "how a user's script finds it: " + bare.stderr[-500:])
    r = subprocess.run([sys.executable, "-c", "import mpmsdem, yade; print(yade.__file__); print(mpmsdem.__file__)"],
                       env=env, capture_output=True, text=True, check=True)
    yadeFile, pkgFile = r.stdout.split("\n")[-3:-1]  # YADE prints its banner first
    import mpmsdem
    import yade
    assert yadeFile == yade.__file__ and pkgFile == mpmsdem.__file__


def test_a_source_copy_of_the_package_is_named_when_it_shadows_the_built_one(tmp_path):
    # A user who runs a script from the repository's py/ folder (or any folder holding an
    # unbuilt mpmsdem) imports that copy first: the error must say which copy and why.
    source = os.path.join(ROOT, "py", "mpmsdem")
    shadow = tmp_path / "mpmsdem"
    shadow.mkdir()
    for name in os.listdir(source):
        if name.endswith(".py"):
            (shadow / name).write_text(open(os.path.join(source, name)).read())
    r = subprocess.run([sys.executable, "-c", "import mpmsdem"], cwd=str(tmp_path), capture_output=True, text=True,
                       env=children.env(), timeout=120)
    assert r.returncode != 0
    last = r.stderr.strip().splitlines()[-1]
    assert "mpmsdem was imported from %s" % shadow in last, r.stderr
    assert "no C++ module _mpmsdem" in last and "make install" in last, r.stderr
