"""The paper's studies through the plain C++ driver, as a GPU machine (no YADE) runs them:
- §5 (examples/parametric_study.py --prepare, --run-prepared, --collect): a case's free flow,
  read by the driver's flow probe, and its coupled run give runCase's results in YADE to
  round-off; a coupled run started from the free flow's state ahead of the cube is the run
  from the release, to the bit; a flow that never reaches the station is reported as such by both; the driver's
  probe and stop rules are refused or recorded as documented.
- §3.2 (examples/calibrate_flume.py prepareFlume / flumeResultOfDriver, used by
  scripts/validation/paper_flume_design.py): a candidate through the driver gives flumeRun's
  targets in YADE to round-off."""
import importlib.util
import json
import math
import os
import subprocess
import sys

import pytest

from mpmsdem import driver

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
pytest.importorskip("h5py")


def summary():
    spec = importlib.util.spec_from_file_location("parametric_study_summary",
                                                  os.path.join(ROOT, "examples", "parametric_study_summary.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def study():
    spec = importlib.util.spec_from_file_location("parametric_study", os.path.join(ROOT, "examples",
                                                                                    "parametric_study.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# A coarse case (dx 0.05 m: 1,536 points, the cube one cell): what is compared is the path, not
# the physics, so the same numbers must come out of both.
CASE = dict(AR=1.3, L0_hb=4, dx=0.05, settle=0.3, margin=1.0)


def test_a_case_through_the_driver_gives_the_yade_case(tmp_path):
    ps = study()
    ref = ps.runCase(**CASE)
    folder = ps.prepareCase(folder=str(tmp_path / "AR=1.3_L0hb=4"), **CASE)
    assert ps.runPrepared(str(tmp_path), exe=driver.executable()) == [folder]
    assert ps.runPrepared(str(tmp_path), exe=driver.executable()) == []  # done: run.json
    got = ps.collectCase(folder)
    assert ref["reached"] and got["reached"]
    assertSameCase(got, ref)
    # a 50 ms mean is a mean of 10 ms means: its largest is no larger, and positive once hit
    assert 0 < ref["peak_force_50ms"] <= ref["peak_force"] * (1 + 1e-12)
    # Fig 15's views of the run's first and last snapshots: nothing over the cube before the flow
    # comes; at the end at most the cube's height and the free flow's depth (at this grid the
    # flow passes the one-cell cube by its sides)
    path, heights = summary().views(folder, [0.0, 10.0])
    assert os.path.getsize(path) > 10000
    assert [t for t, _ in heights] == [0.0, pytest.approx(ref["duration"], abs=1e-9)]
    assert heights[0][1] == 0.0 and 0 <= heights[1][1] < 1.0 + ref["free_flow"]["h_f"] / 0.05
    # E_p,0 is the column's weight times its centroid's height against gravity, zero at the bed
    # under its upstream end (10° flume; the lowest points R_p0 - dx/4 above the bed, Eq 13)
    dx, th = CASE["dx"], math.radians(10)
    zLow = (3 * dx ** 3 / 8 / (4 * math.pi)) ** (1 / 3) - dx / 4
    mass = 1600 * 0.3 * 0.2 * ref["H_i"]
    assert ref["flow_potential_0"] == pytest.approx(
        mass * 9.81 * (math.cos(th) * (zLow + ref["H_i"] / 2) - math.sin(th) * 0.15), rel=1e-9)
    # the flow's kinetic energy peaks after the release, the cube's after the front's arrival
    assert 0 < ref["flow_kinetic_max_time"] < ref["duration"]
    assert ref["free_flow"]["arrival"] < ref["block_kinetic_max_time"] <= ref["duration"] + 1e-9
    assert 0.001 < ref["block_kinetic_ratio"] < 0.2
    # Fig 17's balance: no energy is made, so the flow and cube lose mechanical energy from the
    # release on, and by the end have lost a good part of it (two-sided: the flow has not stopped)
    e = ref["energy"]
    assert e["t"][0] == pytest.approx(0.002, abs=1e-3) and e["t"][-1] == pytest.approx(ref["duration"], abs=1e-3)
    assert e["t"][1] - e["t"][0] == pytest.approx(ps.ENERGY_EVERY, rel=0.3)
    assert e["dissipated"][0] == pytest.approx(0.0, abs=1e-3)
    assert min(e["dissipated"]) > -1e-3
    assert min(b - a for a, b in zip(e["dissipated"], e["dissipated"][1:])) > -1e-3  # nothing given back
    assert 0.1 < ref["flow_dissipated_end"] < 1.0
    # the front arrives at the station (x 0.5 m) in 0.2 s and the cube is pushed downstream
    assert 0.1 < ref["free_flow"]["arrival"] < 0.3
    assert 0.05 < ref["travel"] < 1.0
    # the run is sized from the free flow's arrival, rounded up to whole 2 ms records
    steps = json.load(open(os.path.join(folder, "run.json")))["coupled_steps"]
    dt = json.load(open(os.path.join(folder, "case.json")))["dt"]
    every = round(0.002 / dt)
    assert steps % every == 0 and -dt / 2 <= steps * dt - (ref["free_flow"]["arrival"] + CASE["settle"]) < every * dt
    # a later end (--until) continues the finished coupled run from its last snapshot: the
    # results of one run to that end
    until = ref["duration"] + 0.1
    longer = ps.runCase(**CASE, until=until)
    assert ps.runPrepared(str(tmp_path), exe=driver.executable(), until=until) == [folder]
    assert ps.runPrepared(str(tmp_path), exe=driver.executable(), until=until) == []  # already there
    extended = ps.collectCase(folder)
    assertSameCase(extended, longer)
    assert until - dt / 2 <= longer["duration"] < until + every * dt
    assert extended["travel"] != pytest.approx(got["travel"], rel=1e-6)  # the cube was still moving: it went on


def assertSameCase(got, ref):
    for k in ("arrival", "h_f", "v_f", "Fr", "Fr1"):
        assert got["free_flow"][k] == pytest.approx(ref["free_flow"][k], rel=1e-12, abs=1e-15), k
    for k in ("travel", "peak_force", "peak_force_50ms", "static_force", "rotation_deg", "speed_end", "eq20_force", "static_force_model",
              "flow_potential_0", "flow_kinetic_max", "block_kinetic_max", "block_kinetic_ratio", "flow_dissipated_end"):
        assert got[k] == pytest.approx(ref[k], rel=1e-9, abs=1e-12), k
    assert got["energy"]["t"] == ref["energy"]["t"]
    for k in ("flow_potential", "flow_kinetic", "block_kinetic", "dissipated"):
        assert got["energy"][k] == pytest.approx(ref["energy"][k], rel=1e-9, abs=1e-12), k
    for k in ("peak_time", "flow_kinetic_max_time", "block_kinetic_max_time", "duration", "particles", "cube_at_end", "submersion", "flume_length", "flip_blend"):
        assert got[k] == ref[k], k


def test_a_refinement_table_names_each_spacing_s_case_apart():
    # examples/parametric_study_refinement.table: two cases at the paper's resolution and at half
    # of it, four names; a case without a spacing of its own keeps its name
    ps = study()
    rows = ps.readTable(os.path.join(ROOT, "examples", "parametric_study_refinement.table"))
    names = [ps.caseName(r["AR"], r["L0_hb"], r["full"], r.get("dx")) for r in rows]
    assert names == ["AR=1.3_L0hb=4_full_dx0.01", "AR=1.3_L0hb=4_full_dx0.005", "AR=1.3_L0hb=14_full_dx0.01",
                     "AR=1.3_L0hb=14_full_dx0.005"]
    assert all(r["settle"] == 0.3 for r in rows)
    assert ps.caseName(1.3, 4, 1) == "AR=1.3_L0hb=4_full" and ps.caseName(2, 54) == "AR=2_L0hb=54"


def test_a_case_stopped_part_way_resumes_where_it_stopped(tmp_path):
    """A machine that goes away mid-case: --run-prepared keeps the finished free flow and goes on
    with the coupled run from its last snapshot; the results are those of one unbroken run."""
    ps = study()
    until = 0.8
    ref = ps.runCase(**CASE, until=until)
    folder = ps.prepareCase(folder=str(tmp_path / "study" / "case"), **CASE)
    dt = json.load(open(os.path.join(folder, "case.json")))["dt"]
    steps, _ = ps.coupledSteps(ref["free_flow"]["arrival"], CASE["settle"], until, dt)
    stop = steps // 2
    # a driver whose coupled run stops after `stop` steps and reports a kill (SIGKILL's 137)
    real = driver.executable()
    wrapper = tmp_path / "killed-driver"
    wrapper.write_text("#!%s\nimport subprocess, sys\nargs = sys.argv[1:]\n"
                       "if args[0].endswith('coupled.json') and '--restart' not in args:\n"
                       "    args[args.index('--steps') + 1] = '%d'\n"
                       "    subprocess.run([%r] + args)\n"
                       "    sys.exit(137)\n"
                       "sys.exit(subprocess.run([%r] + args).returncode)\n" % (sys.executable, stop, real, real))
    wrapper.chmod(0o755)
    with pytest.raises(RuntimeError, match="exited 137"):
        ps.runPrepared(str(tmp_path / "study"), exe=str(wrapper), until=until)
    assert not os.path.exists(os.path.join(folder, "run.json"))
    partial = json.load(open(os.path.join(folder, "run.partial.json")))
    assert partial["coupled_steps"] == steps and partial["free_flow_seconds"] > 0
    assert partial["coupled_seconds_before"] > 0  # the killed leg's wall time, kept for the total
    freeLog = os.path.join(folder, "free.log")
    freeWritten = os.stat(freeLog).st_mtime_ns
    assert ps.runPrepared(str(tmp_path / "study"), exe=real, until=until) == [folder]
    assert os.stat(freeLog).st_mtime_ns == freeWritten  # the free flow was not run again
    record = json.load(open(os.path.join(folder, "run.json")))
    assert record["resumed_from_steps"] == [stop] and record["coupled_steps"] == steps
    assert record["coupled_seconds"] > partial["coupled_seconds_before"] and "coupled_seconds_before" not in record
    assert not os.path.exists(os.path.join(folder, "run.partial.json"))
    assertSameCase(ps.collectCase(folder), ref)
    # --rerun starts the case afresh: the same results again
    assert ps.runPrepared(str(tmp_path / "study"), exe=real, until=until, rerun=True) == [folder]
    assert "resumed_from_steps" not in json.load(open(os.path.join(folder, "run.json")))
    assertSameCase(ps.collectCase(folder), ref)


def test_a_coupled_run_started_ahead_of_the_cube_is_the_run_from_the_release(tmp_path):
    """--prepare's free flow saves its state when its front is AHEAD cells short of the cube and
    the coupled run starts there (mpmsdem-run --flow-from): the cube's series, the flow's state
    and every result are those of the coupled run from the release, to the last bit; the energies
    before that state come from the free flow's records. Scenes that are not the same flow, or
    whose cube the flow already reaches, are refused by name."""
    import h5py
    import numpy as np
    ps = study()
    case = dict(CASE, L0_hb=14)  # the cube 0.7 m downstream: the front saved at x 0.6 m
    runs = {}
    for name, ahead in (("ahead", True), ("release", False)):
        folder = ps.prepareCase(folder=str(tmp_path / name / "case"), startAhead=ahead, **case)
        assert ps.runPrepared(str(tmp_path / name), exe=driver.executable()) == [folder]
        runs[name] = folder
    record = json.load(open(os.path.join(runs["ahead"], "run.json")))
    front = json.load(open(os.path.join(runs["ahead"], "free", "front_snapshot.json")))
    assert 0 < record["coupled_from_step"] == front["step"] < record["coupled_steps"] / 2
    assert 0.6 <= front["front_x"] < 0.6 + 0.05 and front["x"] == pytest.approx(0.6, abs=1e-12)
    assert "coupled_from_step" not in json.load(open(os.path.join(runs["release"], "run.json")))
    got, ref = ps.collectCase(runs["ahead"]), ps.collectCase(runs["release"])
    for k in ref:
        if k not in ("driver", "wall_seconds", "energy"):
            assert got[k] == ref[k], k
    assert got["travel"] > 0.05  # the cube was carried
    tk = front["time"]
    for k in ref["energy"]:  # after the start: the same records; before it, the free flow's
        after = [e for t, e in zip(ref["energy"]["t"], ref["energy"][k]) if t > tk + 0.01]
        assert after == got["energy"][k][-len(after):], k
    early = [t for t in got["energy"]["t"] if t < tk]
    assert early[0] == pytest.approx(0.01, abs=0.006) and len(early) == pytest.approx(tk / ps.ENERGY_EVERY, abs=1.5)
    with h5py.File(os.path.join(runs["ahead"], "coupled", "coupled.h5"), "r") as a, \
            h5py.File(os.path.join(runs["release"], "coupled", "coupled.h5"), "r") as b:
        t = a["series/time"][:]
        assert t[0] == tk
        at = np.searchsorted(b["series/time"][:], t[1:])
        for k in a["series"]:  # (flow_first_contact: NaN until the flow touches a block)
            assert np.array_equal(a["series"][k][1:], b["series"][k][:][at], equal_nan=True), k

    exe, free = driver.executable(), os.path.join(runs["ahead"], "free")
    scene = json.load(open(os.path.join(runs["ahead"], "coupled.json")))
    # a list of x: a state for each, front_snapshot_<k>.json; the one at 0.6 m is the state above
    flow = json.load(open(os.path.join(runs["ahead"], "free.json")))
    flow["run"]["snapshot_when_front_at"] = [0.5, 0.6]
    json.dump(flow, open(str(tmp_path / "several.json"), "w"))
    r = subprocess.run([exe, str(tmp_path / "several.json"), "--out", str(tmp_path / "several")], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    states = [json.load(open(tmp_path / "several" / ("front_snapshot_%d.json" % k))) for k in (0, 1)]
    assert [s["x"] for s in states] == [0.5, 0.6] and states[0]["step"] < states[1]["step"] == front["step"]
    assert not os.path.exists(tmp_path / "several" / "front_snapshot.json")
    r = subprocess.run([exe, os.path.join(runs["ahead"], "coupled.json"), "--out", str(tmp_path / "from1"),
                        "--flow-from", str(tmp_path / "several" / "front_snapshot_1.json"), "--steps", "200"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "from1" / "coupled.h5", "r") as a, \
            h5py.File(os.path.join(runs["ahead"], "coupled", "coupled.h5"), "r") as b:
        n = len(a["series/time"])
        assert n > 10
        assert all(np.array_equal(a["series"][k][:], b["series"][k][:n], equal_nan=True) for k in a["series"])

    def refused(changed, expect, extra=(), source=free):
        path = str(tmp_path / "changed.json")
        json.dump(changed, open(path, "w"))
        r = subprocess.run([exe, path, "--out", str(tmp_path / "refused"), "--flow-from", source] + list(extra),
                           capture_output=True, text=True)
        assert r.returncode == 2 and expect in r.stderr, r.stderr

    import copy
    other = copy.deepcopy(scene)
    other["material"]["mu_2"] = 0.7
    refused(other, "material.mu_2")
    other = copy.deepcopy(scene)
    other["grid"]["cells"][1] += 2  # the +y side is a wall
    refused(other, "grid.cells[1]")
    other = copy.deepcopy(scene)
    other["blocks"][1]["position"][0] = 0.55  # the cube where the front already is
    refused(other, "the flow had reached it")
    other = copy.deepcopy(scene)
    other["run"]["dt"] = "auto"
    refused(other, "run.dt")
    refused(scene, "--restart and --flow-from", ["--restart"])
    refused(scene, "front_snapshot.json is missing", source=str(tmp_path))


def test_a_flow_that_stops_short_of_the_station_has_no_coupled_run(tmp_path):
    ps = study()
    kw = dict(CASE, maxFreeTime=0.1)  # stopped before the front reaches x 0.5 m
    ref = ps.runCase(**kw)
    folder = ps.prepareCase(folder=str(tmp_path / "short"), **kw)
    ps.runPrepared(str(tmp_path), exe=driver.executable())
    got = ps.collectCase(folder)
    assert not ref["reached"] and not got["reached"]
    assert not os.path.exists(os.path.join(folder, "coupled"))
    assert got["front"] == pytest.approx(ref["front"], abs=CASE["dx"])
    probes = json.load(open(os.path.join(folder, "free", "flow_probes.json")))
    assert probes["stopped"] == "duration" and probes["probes"][0]["arrival"] is None


def test_stop_rules_and_a_restart_of_a_probed_run(tmp_path):
    ps = study()
    folder = ps.prepareCase(folder=str(tmp_path / "case"), **CASE)
    exe = driver.executable()
    scene = json.load(open(os.path.join(folder, "free.json")))
    # the flow piles up at the flume's end wall (x 1.6 m): the front-still rule ends the run
    # long before run.duration, with the probe near the wall read and complete
    scene["flow_probes"] = [{"x": 1.5}]
    scene["run"]["duration"] = 20.0
    scene["run"]["stop_when_probed"] = False
    path = str(tmp_path / "still.json")
    json.dump(scene, open(path, "w"))
    r = subprocess.run([exe, path, "--out", str(tmp_path / "still")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    res = json.load(open(tmp_path / "still" / "flow_probes.json"))
    assert res["stopped"] == "front_still"
    assert 0.3 < res["time"] - res["front_still_since"] < 0.3 + 0.006
    assert res["time"] < 3.0 and res["front_x"] < 1.6
    assert res["probes"][0]["complete"] and res["probes"][0]["arrival"] < res["front_still_since"]
    # a restart of the finished run takes its probe and front records again from mpm.h5: the
    # front-still rule ends it after one step (a record at most), with the same probe result
    r = subprocess.run([exe, path, "--out", str(tmp_path / "still"), "--restart"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    again = json.load(open(tmp_path / "still" / "flow_probes.json"))
    assert again["stopped"] == "front_still" and again["front_still_since"] == res["front_still_since"]
    assert again["probes"][0]["records"] - res["probes"][0]["records"] in (0, 1)
    assert [dict(p, records=0) for p in again["probes"]] == [dict(p, records=0) for p in res["probes"]]
    # stop_when_probed without probes is a parameter error naming the key
    del scene["flow_probes"]
    scene["run"]["stop_when_probed"] = True
    json.dump(scene, open(path, "w"))
    r = subprocess.run([exe, path, "--out", str(tmp_path / "bad")], capture_output=True, text=True)
    assert r.returncode == 2 and "run.stop_when_probed" in r.stderr, r.stderr


def test_a_flume_candidate_through_the_driver_gives_flumerun(tmp_path):
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import calibrate_flume
    from driver_runs import runDriver
    kw = dict(duration=0.3, flowFriction=0.4)  # coarse (dx 0.02 m): the front touches the cube at 0.22 s
    ref = calibrate_flume.flumeRun(**kw)
    folder = calibrate_flume.prepareFlume(str(tmp_path / "c"), **kw)
    steps = json.load(open(os.path.join(folder, "case.json")))["steps"]
    runDriver(driver.executable(), os.path.join(folder, "scene.json"), os.path.join(folder, "out"),
              os.path.join(folder, "out.log"), ["--steps", str(steps)])
    got = calibrate_flume.flumeResultOfDriver(folder)
    assert set(got) == set(ref)
    assert 0.1 < ref["first_touch"] < 0.3 and ref["peak_force"] > 0.1 and ref["travel"] > 1e-3  # the cube was hit
    for k, v in ref.items():
        if isinstance(v, float):
            assert got[k] == pytest.approx(v, rel=1e-9, abs=1e-12), k
        else:
            assert got[k] == v, k


def test_a_cube_at_the_end_wall_is_told_from_one_held_back_by_the_flow():
    # Travel is cut short (left out of the fits) when the cube reached the flume's end, when the
    # flow turned back by the end wall pushes it upstream, or when it was still carried as the
    # front reached the wall (the flow piles there instead of running on); a negative force while
    # the front is still short of the wall is the flow holding back a cube that runs ahead of it.
    import numpy as np
    ps = study()
    t = np.linspace(0, 2, 201)
    ff = {"arrival": 0.5, "h_f": 0.02, "v_f": 2.0, "Fr": 4.5, "Fr1": 0.6}

    def case(travel, force, frontEnd, stops=1.0):
        # the front runs at frontEnd / 1.5 m/s to frontEnd; the cube moves at 1 m/s until `stops` [s]
        s = {"t": t, "Ft": np.where(t > 1.9, force, 5.0), "travel": travel * t / 2, "vx": np.where(t < stops, 1.0, 0.0),
             "rotation": np.zeros_like(t), "flow_kinetic": np.ones_like(t), "block_kinetic": np.ones_like(t),
             "flow_potential": np.full_like(t, 150.0), "flow_front": np.minimum(frontEnd, frontEnd * t / 1.5)}
        out = {"L_i": 0.3, "L0": 2.7, "flume_length": 9.05, "dx": 0.01}
        ps._coupledResults(out, ff, s, 2.0, 150.0)
        return out["cube_at_end"], out["front_at_wall_time"]

    assert case(1.9, -1.3, 5.4) == (False, None)   # held back, the front 3.6 m short of the wall
    assert case(1.9, -1.3, 9.0) == (True, 1.5)     # pushed back by the flow the wall turned (8.95 m at 1.4917 s)
    assert case(5.95, 2.0, 9.0)[0]                 # at the wall itself
    assert not case(1.9, 2.0, 9.0)[0]              # at rest from 1 s, pushed downstream, away from the wall
    assert not case(1.9, 2.0, 9.0, stops=1.49)[0]  # at rest just before the front reached the wall
    assert case(1.9, 2.0, 9.0, stops=1.51)[0]      # still carried when it did
    assert not case(1.9, 2.0, 8.9, stops=3.0)[0]   # carried to the end, the front 0.15 m short of the wall


def test_the_energies_of_fig_17_are_a_balance_over_the_initial_potential_energy():
    # A flow that turns 150 J of potential energy into 20 J of kinetic energy, hands 0.6 J to the
    # cube and dissipates the rest, recorded every 2 ms for 1.001 s: kept every 10 ms and at the end.
    import numpy as np
    ps = study()
    t = np.arange(501) * 0.002 + 0.002
    s = {"t": t, "flow_potential": 150.0 - 120.0 * t / t[-1], "flow_kinetic": 20.0 * np.sin(np.pi * t / t[-1]),
         "block_kinetic": np.full_like(t, 0.6)}
    e = ps.energySeries(s, 150.0)
    assert len(e["t"]) == 101 and e["t"][:2] == [0.002, 0.012] and e["t"][-1] == t[-1]
    assert e["flow_potential"][-1] == pytest.approx(30.0 / 150.0, rel=1e-12)
    assert e["block_kinetic"][0] == pytest.approx(0.004, rel=1e-12)
    assert e["dissipated"][-1] == pytest.approx(1 - 0.2 - 0.004, abs=1e-12)  # E_k^f back to 0 at the end
    mid = e["t"].index(t[250])
    assert e["dissipated"][mid] == pytest.approx(1 - (150 - 120 * t[250] / t[-1] + 20 * np.sin(np.pi * t[250] / t[-1])
                                                     + 0.6) / 150, rel=1e-12)


def test_fig_15_views_measure_the_flow_over_the_cube_and_draw_it_turned():
    import numpy as np
    sm = summary()
    hb = 0.05

    def area(p):  # shoelace, of a closed outline
        return 0.5 * abs(np.dot(p[:-1, 0], p[1:, 1]) - np.dot(p[1:, 0], p[:-1, 1]))

    centre = np.array([1.0, 0.1, 0.025])
    flat = sm.cubeOutline(centre, [0, 0, 0], hb, [0, 1])
    assert area(flat) == pytest.approx(hb * hb, rel=1e-12) and np.ptp(flat[:, 0]) == pytest.approx(hb, rel=1e-12)
    yawed = sm.cubeOutline(centre, [0, 0, math.pi / 4], hb, [0, 1])  # from above: the same square, corner first
    assert area(yawed) == pytest.approx(hb * hb, rel=1e-12)
    assert np.ptp(yawed[:, 0]) == pytest.approx(hb * math.sqrt(2), rel=1e-12)
    side = sm.cubeOutline(centre, [0, 0, math.pi / 4], hb, [0, 2])  # from the side: its diagonal by its height
    assert area(side) == pytest.approx(hb * hb * math.sqrt(2), rel=1e-12)
    assert side[:, 1].min() == pytest.approx(0.0, abs=1e-15) and side[:, 1].max() == pytest.approx(hb, rel=1e-12)
    # the highest point within h_b/2 of the cube's centre in x and y; one just outside does not count
    x = np.array([[1.0, 0.1, 0.07], [1.02, 0.08, 0.09], [1.03, 0.1, 0.5], [0.9, 0.1, 0.3]])
    assert sm.flowHeightOver(x, centre, hb) == 0.09
    assert sm.flowHeightOver(x[2:], centre, hb) == 0.0


def test_prepared_cases_run_workers_at_a_time_in_order_and_stop_at_a_failure():
    import threading
    import time
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    from driver_runs import eachCase
    # two workers: two cases are inside run() together (else the barrier times out)
    together = threading.Barrier(2, timeout=10)
    assert eachCase(lambda c: (together.wait(), c * c)[1], [3, 1, 2, 5], workers=2) == [9, 1, 4, 25]
    # one worker: never two at once
    inside, most = [0], [0]
    lock = threading.Lock()

    def counted(c):
        with lock:
            inside[0] += 1
            most[0] = max(most[0], inside[0])
        time.sleep(0.01)
        with lock:
            inside[0] -= 1
        return c

    assert eachCase(counted, list(range(5)), workers=1) == list(range(5)) and most[0] == 1
    # a failure: raised, and the cases not yet started are dropped
    ran = []

    def failFirst(c):
        if c == 0:
            raise RuntimeError("mpmsdem-run case0 exited 1")
        time.sleep(0.1)
        ran.append(c)

    with pytest.raises(RuntimeError, match="case0 exited 1"):
        eachCase(failFirst, list(range(12)), workers=2)
    assert 1 <= len(ran) <= 4, ran
    for bad in (0, 1.5, "2"):
        with pytest.raises(ValueError, match=r"workers = .*: must be an integer >= 1"):
            eachCase(abs, [1], workers=bad)


def test_the_design_table_scores_the_cases_and_shows_an_unreached_45_degrees_as_a_bound():
    spec = importlib.util.spec_from_file_location("paper_flume_design", os.path.join(
        ROOT, "scripts", "validation", "paper_flume_design.py"))
    design = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(design)
    a = design.parse(["--cases", "paper"])
    base = {"first_touch": 0.25, "force_04": 0.32, "force_mean": 0.20, "rotation_07": 45.0, "max_rotation_deg": 60.0}
    records = [{"status": "ok", "result": dict(base, t45=0.72)},                      # the paper's numbers
               {"status": "ok", "result": dict(base, t45=a.duration, first_touch=0.30)},  # never turned 45°
               {"status": "ok", "result": dict(base, t45=0.5, max_rotation_deg=180.0)}]   # tumbled: not ranked
    params = {n: {"dx": 0.01, "duration": a.duration} for n in ("exact", "unturned", "tumbled")}
    text = design.table(["exact", "unturned", "tumbled"], records, a, params)
    rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| ")}
    assert rows["exact"].rstrip().endswith("| 0.00 |")
    # 45° not reached by the end: a bound, and its misfit a lower bound (0.8 against 0.72 s)
    assert "> %.2f" % a.duration in rows["unturned"] and "≥ +11 %" in rows["unturned"]
    assert "+20 % / +0 % / +0 % / ≥ +11 % / +0 %" in rows["unturned"]
    assert "> " not in rows["tumbled"] and "-31 %" in rows["tumbled"]
    assert "Lowest loss" in text and ": exact (" in text  # the tumbled case is not ranked however it scores
    m, loss = design.misfits(dict(base, t45=0.72))
    assert loss == 0 and set(m) == {k for k, _ in design.LOSS_TARGETS}


def test_a_signal_to_the_runner_stops_its_drivers_which_save_and_no_other_case_starts(tmp_path):
    """SIGTERM to a --run-prepared runner (stopDriversOnSignals) is passed on to the drivers it is
    running, as SIGTERM; each saves and exits 4 (here a stand-in for mpmsdem-run that does only
    that), the runner raises DriverStopped and exits 4, and the third case never starts."""
    import signal
    import time
    fake = tmp_path / "fake-mpmsdem-run"
    fake.write_text("#!%s\n" % sys.executable + "\n".join([
        "import signal, sys, time",
        "out = sys.argv[sys.argv.index('--out') + 1]",
        "def stop(sig, frame):",
        "    open(out + '.stopped', 'w').write(str(sig))",
        "    sys.exit(4)",
        "signal.signal(signal.SIGTERM, stop)",
        "open(out + '.started', 'w').close()",
        "time.sleep(60)",
        "sys.exit(9)"]) + "\n")
    fake.chmod(0o755)
    runner = "\n".join([
        "import os, sys",
        "sys.path.insert(0, %r)" % os.path.join(ROOT, "examples"),
        "from driver_runs import STOPPED_EXIT, DriverStopped, eachCase, runDriver, stopDriversOnSignals",
        "work = %r" % str(tmp_path),
        "def one(c):",
        "    runDriver(%r, c + '.json', os.path.join(work, c), os.path.join(work, c + '.log'))" % str(fake),
        "try:",
        "    with stopDriversOnSignals():",
        "        eachCase(one, ['a', 'b', 'c'], workers=2)",
        "except DriverStopped as e:",
        "    print('stopped:', e)",
        "    sys.exit(STOPPED_EXIT)"])
    proc = subprocess.Popen([sys.executable, "-c", runner], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.time() + 30
    while not all((tmp_path / (c + ".started")).exists() for c in "ab") and time.time() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 4, out
    assert "was stopped by a signal, its state saved" in out
    for c in "ab":
        assert (tmp_path / (c + ".stopped")).read_text() == str(int(signal.SIGTERM))
    assert not (tmp_path / "c.started").exists()


def test_the_margin_that_holds_the_front_at_the_papers_end():
    # FRONT_AT_END at its aspect ratios, linear between and beyond them; the margin is the whole
    # metres that put the flume's end END_ROOM (1 m) past that front, counted from the cube's far
    # face at L_i + L0 + h_b (hand-computed: AR 3.0 at L0/h_b 14, 11.0 + 1 - 1.05 = 10.95 -> 11 m).
    ps = study()
    assert ps.frontAtEnd(3.0) == pytest.approx(11.0)
    assert ps.frontAtEnd(2.5) == pytest.approx((6.75 + 11.0) / 2)
    assert ps.frontAtEnd(4.5) == pytest.approx(15.0 + 0.5 * 4.0)  # the last slope, 4 m per unit AR
    assert ps.marginToEnd(3.0, 14) == 11
    assert ps.marginToEnd(2.0, 24) == 7   # 6.75 + 1 - 1.55 = 6.2 -> 7
    assert ps.marginToEnd(1.3, 74) == 2   # 4.5 + 1 - 4.05 = 1.45 -> 2
    assert ps.marginToEnd(1.3, 200) == 1  # the front short of the cube: at least 1 m
    for AR, L0_hb in ((1.3, 4), (2.0, 54), (4.0, 74)):
        length = ps.COLUMN + L0_hb * ps.HB + ps.HB + ps.marginToEnd(AR, L0_hb)
        assert ps.frontAtEnd(AR) + ps.END_ROOM <= length < ps.frontAtEnd(AR) + ps.END_ROOM + 1
