"""examples/block_placements.py on the coarse §3.2 flume: the flow once, two placements of the
cube each from the flow's state ahead of its station, and the last one from the release: the
two runs are the same to the last bit, each placement starts before the front comes and is hit
after it, and the farther station is reached later by a shallower front."""
import json
import os
import subprocess
import sys

import pytest

import children

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
pytest.importorskip("h5py")


def test_each_placement_from_the_flow_ahead_of_it_is_the_run_from_the_release(tmp_path):
    out = str(tmp_path / "placements")
    proc = subprocess.run([sys.executable, os.path.join(REPO, "examples", "block_placements.py"), "--at", "0.8,0.6",
                           "--duration", "0.5", "--check", "--out", out],
                          capture_output=True, text=True, env=children.env(OMP_NUM_THREADS=1), timeout=900)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    s = json.load(open(os.path.join(out, "placements.json")))
    assert s["release_equal"] is True
    near, far = s["placements"]
    assert (near["x"], far["x"]) == (0.6, 0.8)  # sorted
    steps = s["steps_from_release"]
    assert abs(steps * s["dt"] - 0.5) < 0.002 + s["dt"]
    for p in (near, far):
        # the state 8 cells (0.16 m) short of the station, before the front's arrival there; the cube is
        # hit after it and pushed downstream
        assert 0 < p["start_time"] < p["arrival"] < p["peak_time"] < 0.5
        assert p["steps"] == steps - round(p["start_time"] / s["dt"])
        assert p["travel"] > 0.01 and p["peak_force"] > 0
        assert p["eq20_force"] > 0
    assert near["start_time"] < far["start_time"] and near["arrival"] < far["arrival"]
    assert far["h_f"] < near["h_f"]  # the front thins as it runs out
    for name in ("flow", "at_0", "at_1", "release"):
        assert os.path.exists(os.path.join(out, name, "mpm.h5")), name
    assert sorted(f for f in os.listdir(os.path.join(out, "flow")) if f.startswith("front_snapshot_")) == [
        "front_snapshot_0.checkpoint.json", "front_snapshot_0.json", "front_snapshot_1.checkpoint.json",
        "front_snapshot_1.json"]
