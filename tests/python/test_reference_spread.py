"""tools/reference_spread.py: the checks' tolerances read from their scripts, and the spread of two
builds' references against them."""
import json
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
import reference_spread as rs  # noqa: E402


def test_every_reference_check_declares_its_tolerances():
    # each stored reference belongs to a check whose TOL names keys the reference holds
    refs = sorted(os.listdir(os.path.join(rs.CHECKS, "reference")))
    assert refs
    for ref in refs:
        tol = rs.tolerances(os.path.join(rs.CHECKS, "check_" + ref[:-len(".json")] + ".py"))
        assert tol and all(0 < t < 1 for t in tol.values()), ref
        assert set(tol) <= set(rs.readJson(os.path.join(rs.CHECKS, "reference", ref))), ref


def test_spread_of_two_builds_against_the_tolerances(tmp_path):
    checks, ours, other = (tmp_path / d for d in ("checks", "ours", "other"))
    for d in (checks, ours, other):
        d.mkdir()
    (checks / "check_wall.py").write_text('TOL = {"F": 0.03, "h": 0.02}\nmain()\n')  # never run
    (checks / "check_plain.py").write_text("main()\n")  # no TOL: not compared
    (ours / "wall.json").write_text(json.dumps({"F": 10.0, "h": 0.05, "t": 1.0}))
    (other / "wall.json").write_text(json.dumps({"F": 10.1, "h": 0.05, "t": 2.0}))
    rows = rs.spread(str(ours), str(other), str(checks))
    assert [r[:2] for r in rows] == [("wall", "F"), ("wall", "h")]
    assert rows[0][4] == pytest.approx(0.01, rel=1e-12) and rows[1][4] == 0.0
    assert rs.margin(rows[0][4], 0.03) == "3" and rs.margin(0.0, 0.02) == "exact"
    # a difference past its tolerance (what makes main's exit status 1)
    (other / "wall.json").write_text(json.dumps({"F": 10.5, "h": 0.05}))
    rows = rs.spread(str(ours), str(other), str(checks))
    assert rows[0][4] == pytest.approx(0.05, rel=1e-12) and abs(rows[0][4]) > rows[0][5]


def test_main_prints_each_key_and_fails_past_a_tolerance(tmp_path, capsys):
    checks, ours, other = (tmp_path / d for d in ("checks", "ours", "other"))
    for d in (checks, ours, other):
        d.mkdir()
    (checks / "check_wall.py").write_text('TOL = {"F": 0.03}\nmain()\n')
    (ours / "wall.json").write_text(json.dumps({"F": 10.0}))
    args = [str(other), "--ref", str(ours), "--checks", str(checks)]
    # no reference in the other folder: an error naming both folders
    with pytest.raises(SystemExit):
        rs.main(args)
    assert "no check has a reference in both %s and %s" % (ours, other) in capsys.readouterr().err
    # 1 % apart against 3 %: status 0, the row with its margin 3; 5 % apart: status 1
    (other / "wall.json").write_text(json.dumps({"F": 10.1}))
    assert rs.main(args + ["--markdown"]) == 0
    assert "| wall | F | 10 | 10.1 | +1.0e-02 | 3 % | 3 |" in capsys.readouterr().out.splitlines()
    (other / "wall.json").write_text(json.dumps({"F": 10.5}))
    assert rs.main(args) == 1
    line = capsys.readouterr().out.strip()
    assert line.split()[:4] == ["wall", "F", "10", "10.5"] and line.endswith("margin 0.6")
