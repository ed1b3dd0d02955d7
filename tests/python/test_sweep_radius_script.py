"""scripts/bench/tradeoff_sweep_radius.py run in two places: scenes prepared here, run by their
run_driver.sh (as on a GPU machine without YADE), collected here, must give the results of the
same runs made by the script's own driver path, and a run that never ran is reported as such."""
import json
import os
import subprocess
import sys

import pytest

import mpmsdem
import mpmsdem.driver
import mpmsdem.flume

import children

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "bench", "tradeoff_sweep_radius.py")
COMMON = ["--engine", "driver", "--sizes", "20", "--ratios", "1/20,1/8", "--duration", "0.3", "--window", "0.27",
          "0.29"]


def driverExe():
    return mpmsdem.driver.executable()


def script(*args, **env):
    p = subprocess.run([sys.executable, SCRIPT] + list(args), capture_output=True, text=True,
                       env=children.env(OMP_NUM_THREADS=1, **env))
    return p.returncode, p.stdout + p.stderr


def results(out):
    with open(os.path.join(out, "results.json")) as f:
        return {r["ratio_label"]: r for r in json.load(f)}


def test_prepared_runs_collected_equal_the_direct_driver_runs(tmp_path):
    exe = driverExe()
    direct, remote = str(tmp_path / "direct"), str(tmp_path / "remote")
    rc, log = script(*COMMON, "--exe", exe, "--out", direct)
    assert rc == 0, log
    rc, log = script(*COMMON, "--prepare", "--out", remote)
    assert rc == 0, log
    run = subprocess.run([os.path.join(remote, "run_driver.sh")], capture_output=True, text=True,
                         env=dict(os.environ, MPMSDEM_RUN=exe, JOBS="2", OMP_NUM_THREADS="1"))
    assert run.returncode == 0 and run.stdout.count(" done") == 2, run.stdout + run.stderr
    rc, log = script(*COMMON, "--collect", "--out", remote, "--markdown", str(tmp_path / "t.md"))
    assert rc == 0, log
    a, b = results(direct), results(remote)
    assert sorted(a) == sorted(b) == ["1/20", "1/8"]
    for k in a:
        # the cube is hit at 0.230 s (coarse flume, the default PIC viscosity: 50 /s at dx 0.02 m): the runs
        # carry a peak force and a travel to compare
        assert a[k]["peak_force"] > 1.0 and a[k]["first_touch"] == pytest.approx(0.230, abs=0.01)
        # the touch is the contact's first step (coupled.h5's), within the 2 ms record interval
        # (and one step) before the first record with a force, which holds the step before it
        assert 0 < a[k]["first_touch_sampled"] - a[k]["first_touch"] <= 0.002 + a[k]["dt_flume"]
        assert a[k]["flip_blend"] == b[k]["flip_blend"] == "PIC viscosity 0.005 m^2/s, share 4 nu dt/dx^2 (PIC damping 50 /s at dx 0.02 m)"
        for field in ("travel", "peak_force", "peak_time", "max_rotation_deg", "max_rise", "first_touch",
                      "first_touch_sampled",
                      "contact_step_min", "steps"):
            assert b[k][field] == a[k][field], (k, field)  # same driver, same scene: same bits
    with open(str(tmp_path / "t.md")) as f:
        text = f.read()
    assert "MPM cpu-double" in text and "dx 0.02 m" in text


def test_the_yade_engine_and_the_driver_find_the_same_first_contact(tmp_path):
    # the YADE path sums the cube's impulse every step and takes the first step it grew in; the
    # driver records that step in coupled.h5: one scene, one first contact, to the bit (each
    # within a record interval and a step before its first record with a force, the same record)
    one = [v if v != "1/20,1/8" else "1/20" for v in COMMON]
    rc, log = script(*one, "--exe", driverExe(), "--out", str(tmp_path / "driver"))
    assert rc == 0, log
    rc, log = script(*[v if v != "driver" else "yade" for v in one], "--out", str(tmp_path / "yade"))
    assert rc == 0, log
    d, y = results(str(tmp_path / "driver"))["1/20"], results(str(tmp_path / "yade"))["1/20"]
    assert y["first_touch"] == d["first_touch"] == pytest.approx(0.2286, abs=1e-4)
    assert y["first_touch_sampled"] == d["first_touch_sampled"]
    assert 0 < d["first_touch_sampled"] - d["first_touch"] <= 0.002 + d["dt_flume"]


def test_a_run_that_never_ran_is_reported_not_invented_nor_relabelled(tmp_path):
    exe = driverExe()
    out = str(tmp_path / "remote")
    rc, log = script(*COMMON, "--prepare", "--out", out)
    assert rc == 0, log
    subprocess.run([os.path.join(out, "run_driver.sh")], capture_output=True, text=True,
                   env=dict(os.environ, MPMSDEM_RUN=exe, OMP_NUM_THREADS="1"), check=True)
    other = [v if v != "0.3" else "0.35" for v in COMMON]
    rc, log = script(*other, "--collect", "--out", out)
    assert rc == 1 and "--collect: --duration = 0.35, but" in log and "prepared with 0.3" in log, log
    os.remove(os.path.join(out, "h20_r1-8", "driver.log"))
    rc, log = script(*COMMON, "--collect", "--out", out, "--markdown", str(tmp_path / "t.md"))
    assert rc == 1, log  # a failed run fails the sweep
    assert list(results(out)) == ["1/20"]
    with open(str(tmp_path / "t.md")) as f:
        assert "R/h_b 1/8: **failed**: not run (no driver.log)" in f.read()


def test_prepare_refuses_the_yade_engine_and_a_grid_out_of_range(tmp_path):
    rc, log = script("--prepare", "--out", str(tmp_path))
    assert rc == 2 and "--prepare and --collect are for --engine driver" in log
    rc, log = script("--engine", "driver", "--prepare", "--dx", "0.04", "--out", str(tmp_path))
    assert rc == 2 and "--dx = 0.04 m: must be in [0.005, 0.02]" in log


def test_joint_settings_reach_the_scene_and_are_not_mixed_with_others(tmp_path):
    """--settings joint: the set examples/flume_block.py --full runs (mpmsdem.flume.FLUME_SETTINGS)
    is what the prepared scene holds; the sweep's other flags cannot contradict it, and a
    collect with another set is refused rather than labelled with the wrong one."""
    out = str(tmp_path / "joint")
    rc, log = script(*COMMON, "--settings", "joint", "--ratios", "1/20", "--prepare", "--out", out)
    assert rc == 0, log
    with open(os.path.join(out, "h20_r1-20", "scene.json")) as f:
        scene = json.load(f)
    with open(os.path.join(out, "h20_r1-20", "prepared.json")) as f:
        prepared = json.load(f)
    joint = mpmsdem.flume.FLUME_SETTINGS["joint"]
    assert scene["flip_viscosity"] == joint["flip_viscosity"] == 0.0347053
    assert scene["material"]["mu_2"] == joint["mu_2"]
    assert scene["walls"]["-y"] == scene["walls"]["+y"] == joint["side_wall_friction"]
    bed, cube = (scene["block_materials"][scene["blocks"][i]["material"]] for i in (0, 1))
    assert bed["flow"]["friction"] == joint["basal_friction"] and cube["flow"]["friction"] == joint["flow_friction"]
    assert scene["blocks"][1]["sweep_radius"] == pytest.approx(0.001, rel=1e-12)  # R = h_b / 20 of the 20 mm cube
    # nu / dx^2 scaled as at dx 0.01 m (1388 /s): a quarter at the coarse dx 0.02 m
    assert prepared["flip_blend"] == "PIC viscosity 0.0347053 m^2/s, share 4 nu dt/dx^2 (PIC damping 347 /s at dx 0.02 m)"
    subprocess.run([os.path.join(out, "run_driver.sh")], capture_output=True, text=True,
                   env=dict(os.environ, MPMSDEM_RUN=driverExe(), OMP_NUM_THREADS="1"), check=True)
    rc, log = script(*COMMON, "--ratios", "1/20", "--collect", "--out", out)
    assert rc == 1 and "--collect: --settings table1, but" in log and "prepared with joint" in log, log
    rc, log = script(*COMMON, "--settings", "joint", "--flip-reference-dt", "5e-6", "--prepare", "--out", out)
    assert rc == 2 and "--flip-reference-dt is for --settings table1" in log, log
