"""mpmsdem.sweep: runs in their own processes, locally and on a Dask LocalCluster (bit-identical
results), the append-only store (finished runs never run again, a half-written record is
dropped, one writer at a time), failed runs retried and reported, named errors; the §5
post-processing fits of mpmsdem.analysis and the study's summary script.

The runs' child processes load this file for the task functions below, so it imports only
the standard library at the top (pytest, numpy and mpmsdem, which brings YADE, would add
0.2 to 1.3 s to every run)."""
import json
import math
import os
import signal
import subprocess
import sys
import time

HERE = os.path.abspath(__file__)
ROOT = os.path.join(os.path.dirname(HERE), "..", "..")


# ------------------------------------------------------------------ tasks (run in child processes)
def slide(mu, theta=30.0, duration=0.3, dt=2e-4):
    """The §3.1 cube sliding on the SDEM bed (tests/python/scenes.py): travel after ``duration``."""
    import mpmsdem
    import scenes
    from yade import O
    eng, cube, _, _ = scenes.cubeOnSlab(theta, mu)
    O.dt = dt
    mpmsdem.run(round(duration / dt), eng)
    return {"travel": O.bodies[cube].state.pos[0], "vx": O.bodies[cube].state.vel[0], "t": O.time}


def flaky(x, marker):
    """Fails on its first call for a given marker file, then doubles x."""
    if not os.path.exists(marker):
        open(marker, "w").close()
        raise RuntimeError("injected failure of x = %g" % x)
    return {"y": 2.0 * x}


def crash(x):
    os.kill(os.getpid(), signal.SIGSEGV)


def sleepy(seconds):
    time.sleep(seconds)
    return seconds


def square(x):
    return {"y": x * x}


def task(name):
    return "%s:%s" % (HERE, name)


# ------------------------------------------------------------------ executor and store
def test_local_and_dask_runs_are_bit_identical_and_never_rerun(tmp_path):
    """The same three sliding-block runs through local processes and through a Dask
    LocalCluster give identical results to the last bit; a second Dask session on the same
    store runs nothing."""
    from distributed import LocalCluster
    from mpmsdem import analysis, sweep
    cases = [{"mu": mu} for mu in (0.1, 0.2, 0.3)]
    local = sweep.runAll(task("slide"), cases, str(tmp_path / "local.jsonl"), workers=2, progress=False)
    assert [r["status"] for r in local] == ["ok"] * 3
    # physics of the tiny scene: slower with more friction, and near Eq 19 (the stick stage of
    # the tangential spring makes SDEM up to ~6 % longer at 0.3 s, test_sdem_scenes)
    travel = [r["result"]["travel"] for r in local]
    assert travel[0] > travel[1] > travel[2]
    for c, s in zip(cases, travel):
        ref = analysis.slidingDistance(0.3, 30.0, c["mu"])
        assert 0.99 * ref < s < 1.07 * ref, (c, s, ref)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None) as cluster:
        with sweep.Executor(task("slide"), str(tmp_path / "dask.jsonl"), scheduler=cluster.scheduler_address,
                            progress=False) as ex:
            remote = ex.map(cases)
            assert ex.started == 3 and ex.reused == 0
        assert [r["result"] for r in remote] == [r["result"] for r in local]
        with sweep.Executor(task("slide"), str(tmp_path / "dask.jsonl"), scheduler=cluster.scheduler_address,
                            progress=False) as ex:
            again = ex.map(cases)
            assert ex.started == 0 and ex.reused == 3
        assert [r["result"] for r in again] == [r["result"] for r in local]
    stored = sweep.readStore(str(tmp_path / "dask.jsonl"))
    assert len(stored) == 3 and all(r["status"] == "ok" and r["attempt"] == 1 for r in stored)


def test_failed_run_is_retried_and_reported(tmp_path):
    """A run that fails once is retried and succeeds; the failure is in the store and on the
    progress lines. Without retries it is returned as failed, and the next session retries it."""
    from mpmsdem import sweep
    lines = []
    store = str(tmp_path / "runs.jsonl")
    with sweep.Executor(task("flaky"), store, retries=1, progress=lines.append) as ex:
        rec, = ex.map([{"x": 1.5, "marker": str(tmp_path / "m1")}])
        assert (ex.started, ex.failures) == (2, 1)
    assert rec["status"] == "ok" and rec["attempt"] == 2 and rec["result"] == {"y": 3.0}
    first = sweep.readStore(store)[0]
    assert first["status"] == "failed" and "injected failure of x = 1.5" in first["error"]
    assert any("failed, retrying (attempt 1 of 2)" in ln and "injected failure" in ln for ln in lines)

    case = {"x": 2.0, "marker": str(tmp_path / "m2")}
    rec, = sweep.runAll(task("flaky"), [case], store, retries=0, progress=False)
    assert rec["status"] == "failed" and sweep.failed([rec]) == [rec]
    rec, = sweep.runAll(task("flaky"), [case], store, retries=0, progress=False)
    assert rec["status"] == "ok" and rec["result"] == {"y": 4.0}
    assert [r["status"] for r in sweep.readStore(store)] == ["failed", "ok", "failed", "ok"]


def test_crash_and_timeout_fail_only_their_run(tmp_path):
    from mpmsdem import sweep
    t0 = time.time()
    recs = sweep.runAll(task("crash"), [{"x": 1}], str(tmp_path / "a.jsonl"), retries=0, progress=False)
    assert recs[0]["status"] == "failed" and recs[0]["error"].startswith("killed by signal %d" % signal.SIGSEGV)
    recs = sweep.runAll(task("sleepy"), [{"seconds": 0.01}, {"seconds": 30}], str(tmp_path / "b.jsonl"), workers=2,
                        retries=0, timeout=1.0, progress=False)
    assert recs[0]["status"] == "ok" and recs[0]["result"] == {"value": 0.01}
    assert recs[1]["status"] == "failed" and recs[1]["error"].startswith("timed out after 1 s")
    assert time.time() - t0 < 10


def test_store_drops_half_written_record_and_refuses_a_second_writer(tmp_path):
    import pytest
    from mpmsdem import sweep
    path = str(tmp_path / "runs.jsonl")
    sweep.runAll(task("square"), [{"x": 2}, {"x": 3.5}], path, progress=False)
    with open(path, "a") as f:  # what a process killed in the middle of a write leaves
        f.write('{"key": "{\\"x\\":4}", "status": "o')
    assert [r["params"] for r in sweep.readStore(path)] == [{"x": 2}, {"x": 3.5}]
    with sweep.Executor(task("square"), path, progress=False) as ex:
        recs = ex.map([{"x": 3.5}, {"x": 4}, {"x": 2}])
        assert (ex.started, ex.reused) == (1, 2)
        assert [r["result"]["y"] for r in recs] == [12.25, 16, 4]
        with pytest.raises(RuntimeError, match="in use by another sweep"):
            sweep.Store(path)
    with open(path) as f:
        assert [json.loads(ln)["params"] for ln in f] == [{"x": 2}, {"x": 3.5}, {"x": 4}]
    with pytest.raises(ValueError, match="holds runs of task test_sweep.py:square, not test_sweep.py:flaky"):
        sweep.Executor(task("flaky"), path, progress=False)
    # floats are keyed by their exact value: a different last bit is another run
    assert sweep.runKey({"x": 0.1 + 0.2}) != sweep.runKey({"x": 0.3})
    assert sweep.runKey({"b": 1, "a": 0.5}) == sweep.runKey({"a": 0.5, "b": 1})


def test_bad_input_named(tmp_path):
    import pytest
    from mpmsdem import sweep
    store = str(tmp_path / "s.jsonl")
    with pytest.raises(ValueError, match=r"workers = 0: must be an integer >= 1"):
        sweep.Executor(task("square"), store, workers=0)
    with pytest.raises(ValueError, match=r"retries = -1"):
        sweep.Executor(task("square"), store, retries=-1)
    with pytest.raises(ValueError, match=r"timeout = 0 s: must be > 0"):
        sweep.Executor(task("square"), store, timeout=0)
    with pytest.raises(ValueError, match=r"scheduler = 'host:8786': must be a Dask scheduler address"):
        sweep.Executor(task("square"), store, scheduler="host:8786")
    with pytest.raises(ValueError, match=r"task = 'square': must be"):
        sweep.Executor("square", store)
    with pytest.raises(ValueError, match=r"no such file"):
        sweep.Executor("nowhere/tasks.py:square", store)
    with pytest.raises(ValueError, match=r"has no function nothing"):
        sweep.loadTask(task("nothing"))
    with pytest.raises(ValueError, match=r"params\['x'\] = nan: must be finite"):
        sweep.runAll(task("square"), [{"x": math.nan}], store, progress=False)
    import socket
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.time()
    with pytest.raises(ConnectionError, match=r"scheduler = 'tcp://127.0.0.1:%d': no Dask scheduler answered" % port):
        sweep.Executor(task("square"), store, scheduler="tcp://127.0.0.1:%d" % port, connectTimeout=1)
    assert time.time() - t0 < 8


# ------------------------------------------------------------------ §5 post-processing
def test_eq21_and_pearson_fits():
    import numpy as np
    import pytest
    from mpmsdem import analysis
    Fr = np.array([1.04, 2.0, 3.5, 5.0, 8.0, 11.82])
    ratio = analysis.impactForceRatio(Fr, k=1.6, alphaF=0.18)
    assert ratio[0] == pytest.approx(1 + 2 * 0.18 * 1.04 ** 2 / 1.6, rel=1e-15)
    fit = analysis.fitImpactForceRatio(Fr, ratio, k=1.6)
    assert fit["alphaF"] == pytest.approx(0.18, rel=1e-12) and fit["rms"] < 1e-12
    assert fit["slope"] == pytest.approx(2 * 0.18 / 1.6, rel=1e-12)
    # noisy data: the least-squares slope through the model's intercept 1
    noisy = ratio * (1 + 0.05 * np.sin(np.arange(6)))
    x, y = Fr ** 2, noisy - 1
    assert analysis.fitImpactForceRatio(Fr, noisy)["slope"] == pytest.approx((x * y).sum() / (x * x).sum(), rel=1e-12)
    F = analysis.staticImpactForce(1600.0, 0.04, 0.04 * 0.05, k=1.6)
    assert F == pytest.approx(0.5 * 1.6 * 1600 * 9.81 * 0.04 * 0.002, rel=1e-15)

    xs = np.array([0.2, 0.5, 0.9, 1.4, 2.0])
    line = analysis.linearFit(xs, 0.7 * xs - 0.1)
    assert line["slope"] == pytest.approx(0.7, rel=1e-12) and line["intercept"] == pytest.approx(-0.1, abs=1e-12)
    assert line["r"] == pytest.approx(1.0, abs=1e-12)
    ys = np.array([0.3, 0.1, 0.5, 0.2, 0.6])
    assert analysis.linearFit(xs, ys)["r"] == pytest.approx(np.corrcoef(xs, ys)[0, 1], rel=1e-12)
    assert analysis.linearFit(xs, -2 * xs)["r"] == pytest.approx(-1.0, abs=1e-12)
    with pytest.raises(ValueError, match="x: all values equal"):
        analysis.linearFit([1, 1, 1], [1, 2, 3])
    with pytest.raises(ValueError, match="two or more finite pairs"):
        analysis.linearFit([1], [2])
    assert analysis.submersion(0.06, 0.05) == "complete" and analysis.submersion(0.02, 0.05) == "partial"


def test_parametric_study_summary_on_known_data(tmp_path):
    """The summary script reads a sweep store and per-job JSON files (yade-batch), splits the
    cases by submersion, leaves a cube stopped by the flume's end out of the travel fits and
    reproduces the fits of runs made up from known laws."""
    import children
    import numpy as np
    import pytest
    from mpmsdem import analysis, sweep
    rng = np.random.default_rng(3)
    runs = []
    for i, (AR, L0hb) in enumerate([(a, l) for a in (1.3, 2.0, 3.0, 4.0) for l in (4, 14, 24, 54, 74)]):
        hb, L0 = 0.05, 0.05 * L0hb
        hf = 0.12 * AR / (1 + 0.1 * L0hb)
        vf = 1.0 + 0.05 * L0hb + 0.2 * AR
        Fr, Fr1 = analysis.froude(vf, hf), analysis.froudeDistance(vf, L0)
        ratio = float(analysis.impactForceRatio(Fr, k=1.6, alphaF=0.18)) * (1 + 0.1 * rng.standard_normal())
        travel = L0 * (0.8 * Fr1 + 0.05 + 0.02 * rng.standard_normal())
        runs.append({"AR": AR, "L0_hb": L0hb, "h_b": hb, "L0": L0, "free_flow": {"h_f": hf, "v_f": vf, "Fr": Fr,
                     "Fr1": Fr1}, "submersion": analysis.submersion(hf, hb), "travel": travel,
                     "travel_L0": travel / L0, "peak_force": ratio * 0.5, "static_force": 0.5,
                     "force_ratio": ratio, "cube_at_end": i == 7,
                     "speed_end": {3: 0.4, 7: 0.9, 9: 0.05}.get(i, 0.0)})  # 3 still carried; 7 at the end; 9 at the bound
    for r in (runs[10], runs[16]):  # AR 3.0 and 4.0 at L0/h_b 4 and 14 with their energy series (Fig 17)
        t = np.linspace(0, 4.5, 451)
        e = {"t": list(t), "flow_potential": list(1 - 0.7 * t / 4.5), "flow_kinetic": list(0.1 * np.sin(t / 1.5)),
             "block_kinetic": list(np.full_like(t, 1e-4))}
        e["dissipated"] = [1 - p - q - b for p, q, b in zip(e["flow_potential"], e["flow_kinetic"], e["block_kinetic"])]
        r.update(energy=e, flow_dissipated_end=e["dissipated"][-1])
    out = tmp_path / "results"
    os.makedirs(out)
    with sweep.Store(str(out / "runs.jsonl")) as st:  # 15 from a sweep, 5 as yade-batch job files
        for r in runs[:15]:
            st.append({"key": sweep.runKey({"AR": r["AR"], "L0_hb": r["L0_hb"]}), "status": "ok", "result": r,
                       "params": {"AR": r["AR"], "L0_hb": r["L0_hb"]}})
    for k, r in enumerate(runs[15:]):  # these recorded the energies of Figs 17-18 too
        r.update(block_kinetic_ratio=0.002 * (k + 1), block_kinetic_max_time=0.5, flow_kinetic_max=100.0,
                 flow_kinetic_max_time=0.38)
        with open(out / ("AR=%g_L0hb=%g.json" % (r["AR"], r["L0_hb"])), "w") as f:
            json.dump(r, f)
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "examples", "parametric_study_summary.py"),
                           "--results", str(out)], capture_output=True, text=True, timeout=120, env=children.env())
    assert proc.returncode == 0, proc.stdout + proc.stderr
    energyLines = [line for line in proc.stdout.splitlines() if "E_k,max^b/E_p,0^f" in line]
    assert [line.split()[:2] for line in energyLines] == [["4.00", str(r["L0_hb"])] for r in runs[15:]]
    assert "1.00 %" in energyLines[-1] and "at 0.380 s" in energyLines[-1]
    dissipated = [line.split() for line in proc.stdout.splitlines() if "E_d^f/E_p,0^f" in line]
    end = 100 * runs[10]["flow_dissipated_end"]
    assert [d[:2] for d in dissipated] == [["3.00", "4"], ["4.00", "14"]]
    assert " ".join(dissipated[0][2:]) == "E_d^f/E_p,0^f %.1f %% at 4.50 s (paper: 77 %% at 4.5 s)" % end
    assert "paper" not in " ".join(dissipated[1])
    assert os.path.getsize(out / "parametric_study_energy.png") > 10000
    fits = json.load(open(out / "fits.json"))
    assert fits["runs"] == 20 and fits["cube_at_end"] == 1 and os.path.getsize(out / "parametric_study.png") > 10000
    # a cube still carried at its run's end is flagged (its travel a lower bound) and stays in the fits
    assert fits["still_moving"] == 1
    flagged = [line.split()[:2] for line in proc.stdout.splitlines() if "the travel a lower bound" in line]
    assert flagged == [["%.2f" % runs[3]["AR"], str(runs[3]["L0_hb"])]]
    Fr = np.array([r["free_flow"]["Fr"] for r in runs])
    assert fits["eq21"]["alphaF"] == pytest.approx(
        analysis.fitImpactForceRatio(Fr, [r["force_ratio"] for r in runs])["alphaF"], rel=1e-9)
    assert 0.15 < fits["eq21"]["alphaF"] < 0.21
    for group in ("complete", "partial"):
        sel = [r for r in runs if r["submersion"] == group and not r["cube_at_end"]]  # travel cut short: left out
        assert fits["Fr1"][group]["n"] == len(sel) > 2
        expect = analysis.linearFit([r["free_flow"]["Fr1"] for r in sel], [r["travel_L0"] for r in sel])
        assert fits["Fr1"][group]["r"] == pytest.approx(expect["r"], rel=1e-9)
        assert fits["Fr1"][group]["r"] > 0.9  # the made-up law is linear in Fr1
        assert fits["Fr"][group]["n"] == len(sel)
    # cases.md: a row per case in (AR, L0/h_b) order with its values and how its travel counts,
    # and the fits' r beside the paper's
    table = (out / "cases.md").read_text().splitlines()
    rows = [line.split(" | ") for line in table[2:] if line.startswith("| ")]
    assert [(float(c[0][2:]), float(c[1])) for c in rows] == [(r["AR"], r["L0_hb"]) for r in runs]
    for c, r in zip(rows, runs):
        assert c[6] == "%.2f (%.2f)" % (r["travel_L0"], r["travel"])
        assert c[11] == "%.1f (%.2f)" % (r["force_ratio"], analysis.impactForceRatio(r["free_flow"]["Fr"]))
        assert c[12] == r["submersion"]
    assert [c[13] for c in rows].count("still carried: a lower bound |") == 1 and "still carried" in rows[3][13]
    assert rows[7][13] == "cut short by the end wall (in no fit) |" and rows[9][13] == "at rest |"
    assert "partial: r = %.2f, n %d (the paper: 0.83)" % (fits["Fr1"]["partial"]["r"], fits["Fr1"]["partial"]["n"]) in \
        "\n".join(table)


def test_the_datum_of_fig_17s_shares_is_found_from_the_dissipated_energy():
    """A zero of potential energy on the bed X past the cube adds the flow's weight times that
    drop to E_p,0^f and leaves E_d^f as it is: runs made with the paper's 77 % and 73 % at X = 4 m
    give X back, and the cube's kinetic share against it is E_k,max^b over the shifted E_p,0^f."""
    import math
    import pytest
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import parametric_study_summary as summary
    s10 = math.sin(math.radians(10))
    weight = 0.3 * 0.9 * 0.2 * 1600 * 9.81  # the AR 3.0 column's, 847.6 N

    def run(L0hb, share, t_end=4.5):
        L0, Ep0 = 0.05 * L0hb, 354.0
        shifted = Ep0 + weight * (0.3 + L0 + 4.0) * s10
        return {"AR": 3.0, "L0_hb": L0hb, "L_i": 0.3, "H_i": 0.9, "L0": L0, "flow_potential_0": Ep0,
                "flow_dissipated_end": share * shifted / Ep0, "block_kinetic_max": 3.0,
                "energy": {"t": [0.0, t_end]}}

    runs = [run(4, 0.77), run(24, 0.73), run(54, 0.5), run(24, 0.73, t_end=3.0)]
    runs[3]["AR"] = 2.0  # not one of the paper's two cases
    datum = summary.paperDatum(runs)
    assert set(datum) == {(3.0, 4), (3.0, 24)}
    assert datum[(3.0, 4)] == pytest.approx(4.0, rel=1e-12) and datum[(3.0, 24)] == pytest.approx(4.0, rel=1e-12)
    assert summary.paperDatum([run(4, 0.77, t_end=3.0)]) == {}  # ended before 4.5 s
    assert summary.blockShareAgainst(runs[0], 4.0) == pytest.approx(3.0 / (354.0 + weight * 4.5 * s10), rel=1e-12)
