"""scripts/validation/flume_convergence.py and impact_walls.py: their extrapolation to Δx 0 on exact power laws."""
import json
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "validation"))
import flume_convergence as fc  # noqa: E402
import impact_walls as iw  # noqa: E402


@pytest.mark.parametrize("p, h", [(2.0, (0.02, 0.01, 0.005)), (1.5, (0.02, 0.01, 0.2 / 28)),
                                  (0.8, (0.01, 0.2 / 28, 0.005))])
def test_richardson_recovers_an_exact_power_law(p, h):
    # f = 0.3 - 4 h^p, the spacings of the refinement runs (a ratio of 2, or 2 then 1.4)
    order, limit = fc.richardson([0.3 - 4 * x ** p for x in h], list(h))
    assert order == pytest.approx(p, abs=1e-9) and limit == pytest.approx(0.3, abs=1e-12)


def test_richardson_refuses_what_no_power_law_fits():
    h = [0.02, 0.01, 0.005]
    assert fc.richardson([1.0, 2.0, 1.0], h) is None      # the differences change sign
    assert fc.richardson([1.0, 1.0, 2.0], h) is None      # a zero difference
    assert fc.richardson([1.0, 1.1, 1.3], h) is None      # growing steps: not converging


@pytest.mark.parametrize("h", [(0.01, 0.2 / 28, 0.005), (0.02, 0.01, 0.005)])
def test_a_limit_is_trusted_only_within_the_span_of_the_runs(h):
    # on f = 1 + C h^p the limit 1 lies |C| h3^p from the finest run and the runs span
    # |C| (h1^p - h3^p): within it exactly when (h1/h3)^p >= 2, p >= ln 2 / ln(h1/h3)
    pmin = math.log(2) / math.log(h[0] / h[2])
    for p in (0.9 * pmin, 1.1 * pmin, 2.0):
        order, limit, why = fc.limitOf([1 + 40 * x ** p for x in h], list(h))
        assert order == pytest.approx(p, rel=1e-6) and limit == pytest.approx(1.0, abs=1e-6)
        assert (why is None) == (p > pmin)
        if why:
            assert why.startswith("order %.2f: its limit 1 lies farther" % p)
    assert fc.limitOf([1.0, 2.0, 1.0], list(h)) == (None, None, "not monotone")
    # monotone with steps that grow (the wall's deposit: 6.355 / 6.43 / 6.929 N) or shrink too
    # little for the spacings (the §3.2 cube's blow over 1/140, 1/200, 1/250 m: 5.212 / 4.638 /
    # 4.259 N; a power law's last step is at most ln 1.25 / ln 1.4 = 0.63 of the one before, this
    # one 0.66): no power law through them
    assert fc.limitOf([6.355, 6.43, 6.929], list(h))[2] == (
        "monotone, but its steps (0.075, 0.499) do not shrink as a power law's would")
    assert fc.limitOf([5.212, 4.638, 4.259], [1 / 140, 1 / 200, 1 / 250])[2] == (
        "monotone, but its steps (0.574, 0.379) do not shrink as a power law's would")


def test_package_study_errors_against_the_extrapolated_limit():
    # three runs of a quantity on an exact power law (f0 0.5, order 2) and one that zigzags
    h = [0.02, 0.01, 0.2 / 28]

    def run(dx, blow):
        return {"settings": "joint", "hold": "viscosity", "width": 0.2, "dx": dx, "cells_per_block": 0.02 / dx,
                "viscosity": 0.036, "points": 1000 * (0.01 / dx) ** 3, "duration": 0.5, "dt": 5e-5 * dx / 0.01,
                "commit": "abc", "free": {}, "coupled": {"plateau": 0.5 - 100 * dx ** 2, "blow": blow}}
    runs = [run(d, b) for d, b in zip(h, (7.0, 5.8, 6.0))] + [dict(run(0.01, 1.0), hold="rate")]
    s = fc.packageStudy(runs, "joint", "viscosity", 0.2, "cmd")
    assert [r["settings"]["cells_per_block_height"] for r in s["rows"]] == pytest.approx([1.0, 2.0, 2.8])
    assert [r["errors"]["plateau_force"] for r in s["rows"]] == pytest.approx([-100 * d ** 2 / 0.5 for d in h], rel=1e-6)
    assert [r["cost"] for r in s["rows"]] == pytest.approx([1 / 16, 1.0, 1.4 ** 4], rel=1e-9)
    assert list(s["unconverged"]) == ["block_peak_force"]
    assert "7 / 5.8 / 6, not monotone" in s["unconverged"]["block_peak_force"]
    assert fc.packageStudy(runs[:2], "joint", "viscosity", 0.2, "cmd") is None   # two spacings: no study
    # a fourth, finer spacing: the limits through the three finest, a row for every run (the
    # coarsest's error against them too), the cost per simulated second against the 0.01 m run
    # whatever each ran for; its zigzag over the three finest (5.8 / 6 / 5.9) still unconverged
    runs.append(dict(run(0.005, 5.9), duration=0.4))
    s = fc.packageStudy(runs, "joint", "viscosity", 0.2, "cmd")
    assert [r["settings"]["dx"] for r in s["rows"]] == [0.02, 0.01, 0.2 / 28, 0.005]
    assert [r["errors"]["plateau_force"] for r in s["rows"]] == pytest.approx(
        [-100 * d ** 2 / 0.5 for d in h + [0.005]], rel=1e-6)
    assert [r["cost"] for r in s["rows"]] == pytest.approx([1 / 16, 1.0, 1.4 ** 4, 16.0], rel=1e-9)
    assert "Δx 0.01 / 0.007143 / 0.005" in s["extrapolated"] and list(s["unconverged"]) == ["block_peak_force"]
    assert "5.8 / 6 / 5.9" in s["unconverged"]["block_peak_force"]
    # without the run at 0.01 m there is nothing to state the cost against
    assert fc.packageStudy([r for r in runs if r["dx"] != 0.01], "joint", "viscosity", 0.2, "cmd") is None


def test_no_limit_at_or_below_zero_for_what_cannot_be():
    # a first touch on -0.1 + 40 Δx and a plateau on -0.2 + 2e4 Δx² (each positive at every
    # spacing, their power laws through zero) give no limit; a tilt on -1 + 2e4 Δx² (an angle that
    # may tend to zero and cross it) keeps its -1; in the table of extrapolations too
    h = [0.02, 0.01, 0.2 / 28]
    runs = [{"settings": "joint", "hold": "viscosity", "width": 0.2, "dx": dx, "cells_per_block": 0.02 / dx, "ppc": 8,
             "viscosity": 0.036, "points": 1000 * (0.01 / dx) ** 3, "duration": 0.5, "dt": 5e-5 * dx / 0.01,
             "commit": "abc", "free": {"front": {}},
             "coupled": {"first_touch": -0.1 + 40 * dx, "plateau": -0.2 + 2e4 * dx ** 2, "tilt_at": -1 + 2e4 * dx ** 2}}
            for dx in h]
    s = fc.packageStudy(runs, "joint", "viscosity", 0.2, "cmd")
    assert sorted(s["unconverged"]) == ["first_touch", "plateau_force"]
    assert s["unconverged"]["first_touch"].endswith("its limit -0.1 is not positive, as this quantity must be")
    assert [r["errors"]["tilt"] for r in s["rows"]] == pytest.approx([-2e4 * d ** 2 for d in h], rel=1e-6)
    lines = fc.extrapolations(runs).splitlines()
    assert [line.split(" at Δx")[0].split(", ")[-1] for line in lines] == ["first_touch", "plateau", "tilt_at"]
    assert lines[0].endswith("no limit to trust (its limit -0.1 is not positive, as this quantity must be)")
    assert lines[2].endswith("order 2.00, extrapolated to Δx 0: -1")


def test_wall_study_errors_against_the_extrapolated_limit():
    # a wall's first blow on an exact first-order law (8 N + 700 dx), a quasi-steady load that
    # zigzags and a deposit's load that steps further each halving (not converging); a run at
    # another incline and one at another E stay out of the study
    h = [0.02, 0.01, 0.005]

    def run(dx, later, end, theta=20.0, young=1e6):
        return {"kind": "wall", "theta": theta, "L0": 0.5, "young": young, "dx": dx, "width": 0.04,
                "points": 2400 * (0.02 / dx) ** 2, "duration": 1.45, "dt": 1e-4 * dx / 0.02, "commit": "abc",
                "flip_blend": "PIC viscosity 0.0360141 m^2/s (PIC damping 360 /s at dx 0.02 m)",
                "free": {"h_f": 0.04, "arrival": 0.45},
                "obstacle": {"F_peak": 8.0 + 700 * dx, "F_later": later, "F_end": end}}
    runs = [run(d, l, e) for d, l, e in zip(h, (10.8, 9.4, 9.6), (6.3, 6.4, 7.0))]
    runs += [run(0.01, 1, 1, theta=35.0), run(0.01, 1, 1, young=4e6), dict(run(0.01, 1, 1), kind="free")]
    s = iw.packageStudy(runs, 20.0, 0.5, 1e6, "cmd")
    assert s["name"] == "wall_impact_t20_L0.5_E1e+06" and "peak_force 1.00" in s["extrapolated"]
    assert [r["settings"]["cells_per_flow_depth"] for r in s["rows"]] == pytest.approx([2.0, 4.0, 8.0])
    assert [r["errors"]["peak_force"] for r in s["rows"]] == pytest.approx([700 * d / 8.0 for d in h], rel=1e-6)
    assert [r["settings"]["flip_viscosity"] for r in s["rows"]] == [0.0360141] * 3
    assert [r["cost"] for r in s["rows"]] == pytest.approx([1 / 8, 1.0, 8.0], rel=1e-9)   # points x steps
    assert sorted(s["unconverged"]) == ["deposit_force", "quasi_steady_force"]
    assert "10.8 / 9.4 / 9.6 N" in s["unconverged"]["quasi_steady_force"]
    assert iw.packageStudy(runs[:2], 20.0, 0.5, 1e6, "cmd") is None   # two spacings: no study
    # runs of --rest 0.12 end before the deposit rests: the first blow is packaged, no deposit's load
    short = [dict(r, duration=0.57) for r in runs[:3]]
    s = iw.packageStudy(short, 20.0, 0.5, 1e6, "cmd")
    assert sorted(s["unconverged"]) == ["quasi_steady_force"] and "peak_force 1.00" in s["extrapolated"]


def test_impact_walls_rest_must_cover_the_later_window(capsys):
    # an obstacle's run must outlast the 30-70 ms window after the touch; the default keeps the
    # wall's deposit (1 s)
    assert iw.parse([]).rest == pytest.approx(iw.REST) and iw.REST == 1.0
    assert iw.parse(["--rest", "0.3"]).rest == pytest.approx(0.3)
    for bad in ("0.05", "0.1", "inf", "nan"):
        with pytest.raises(SystemExit):
            iw.parse(["--rest", bad])
        assert "--rest" in capsys.readouterr().err

def test_impact_walls_spacing_must_divide_the_slice(capsys):
    # refused before any run is prepared, naming two spacings that do divide the 0.04 m slice
    assert iw.parse(["--dx", "0.005"]).dx == 0.005 and iw.parse(["--dx", "0.008"]).dx == 0.008
    with pytest.raises(SystemExit):
        iw.parse(["--dx", "0.007142857142857143"])
    assert "must divide the width 0.04 m into whole cells, e.g. 0.008 or 0.0066666667 m" in capsys.readouterr().err
    assert iw.parse(["--dx", "0.007142857142857143", "--cases", "block"]).cases == ["block"]  # the lane is rounded
    # the §3.2 flume's width likewise, for every spacing of the sequence
    assert fc.parse(["--dx", "0.01,0.007142857142857143,0.005"]).dx[1] == pytest.approx(0.2 / 28)
    with pytest.raises(SystemExit):
        fc.parse(["--dx", "0.01,0.007"])
    assert "--dx = 0.007: must divide the width 0.2 m into whole cells, e.g. 0.0071428571 or 0.0068965517 m" in capsys.readouterr().err


def test_impact_walls_block_size_and_lane(capsys):
    # the §3.2 cube in its five-cube lane keeps its runs' names; another cube or lane is named by them
    a = iw.parse(["--cases", "free,block", "--dx", "0.005"])
    assert (iw.runName(a, "block", 20.0), iw.laneWidth(a, "block")) == ("block_t20_L0.5_dx0.005", pytest.approx(0.1))
    a = iw.parse(["--cases", "block", "--dx", "0.005", "--block-size", "0.04", "--lane", "0.1"])
    assert iw.runName(a, "block", 20.0) == "block_t20_L0.5_dx0.005_hb0.04_lane0.1"
    assert iw.runName(a, "free", 20.0) == "free_t20_L0.5_dx0.005"  # the same free flow
    assert iw.laneWidth(a, "block") == 0.1 and iw.laneWidth(a, "wall") == 0.04
    assert iw.parse(["--cases", "block", "--dx", "0.02", "--block-size", "0.04"]).dx == 0.02  # two cells
    # five cubes of 0.03 m at 0.007 m: 21.43 cells, rounded up to 22
    a = iw.parse(["--cases", "block", "--dx", "0.007", "--block-size", "0.03"])
    assert iw.laneWidth(a, "block") == pytest.approx(0.154)
    for bad, why in ((["--lane", "0.07", "--block-size", "0.04"], "--lane = 0.07: must be at least twice"),
                     (["--lane", "0.1", "--dx", "0.007"], "must divide the width 0.1 m into whole cells"),
                     (["--block-size", "0"], "--block-size = 0.0: must be > 0"),
                     (["--lane", "-1"], "--lane = -1.0: must be > 0"),
                     (["--dx", "0.02"], "--dx = 0.02: the block (--block-size 0.02 m) would be 1.0 cells tall")):
        with pytest.raises(SystemExit):
            iw.parse(["--cases", "block"] + bad)
        assert why in capsys.readouterr().err


def test_impact_walls_block_area_is_its_face_below_the_flow(tmp_path, monkeypatch):
    # α_f = F/(ρ v² A), A = min(h_f, h_b) h_b: a 40 mm cube in a 41.6 mm flow takes its whole face,
    # the 20 mm cube of an older run (no block_size) its own
    from mpmsdem import analysis
    t = np.arange(201) * 0.001  # 10 N from the touch at 0.1 s on, in the records as the driver's
    force = np.where(t > 0.1 + 1e-9, 10.0, 0.0)
    series = {"t": t, "Ft": force, "J": 10.0 * np.maximum(t - 0.1, 0.0), "flow_kinetic": np.ones(t.size)}
    monkeypatch.setattr(analysis, "driverBlockSeries", lambda folder, block: (series, None))
    free = {"h_f": 0.0416, "v_f": 1.5, "Fr": 2.35}
    for meta, area in (({"kind": "block", "theta": 20.0, "block_size": 0.04}, 0.04 * 0.04),
                       ({"kind": "block", "theta": 20.0}, 0.02 * 0.02)):
        r = iw.readObstacle(str(tmp_path), meta, free)
        assert (r["F_peak"], r["F_peak_20ms"], r["first_touch"]) == pytest.approx((10.0, 10.0, 0.101), rel=1e-9)
        assert r["F_windows"] == pytest.approx({"2": 10.0, "5": 10.0, "10": 10.0, "20": 10.0, "40": 10.0}, rel=1e-9)
        assert r["alpha_f"] == pytest.approx(10.0 / (iw.RHO * 1.5 ** 2 * area), rel=1e-12)
        assert r["ratio"] == pytest.approx(10.0 / (0.5 * iw.RHO * iw.G * 0.0416 * area), rel=1e-12)


def test_impact_walls_figure_draws_what_is_there(tmp_path):
    # no obstacle run: no figure; a wall and a cube (one free flow beside them): the figure,
    # with the §5 cases of a study folder on its right panel
    assert iw.figure(str(tmp_path)) is None
    free = {"h_f": 0.04, "v_f": 1.5, "Fr": 2.4}

    def put(name, kind, obstacle):
        with open(tmp_path / (name + ".json"), "w") as f:
            json.dump({"kind": kind, "dx": 0.01, "free": free, "obstacle": obstacle}, f)
    put("free_t20", "free", {})
    put("wall_t20", "wall", {"alpha": 3.7, "alpha_later": 1.5, "bore": 1.4, "ratio": 43.0})
    put("block_t20", "block", {"alpha_f": 16.0, "alpha_later": 8.0, "ratio": 183.0})
    study = tmp_path / "s5"
    study.mkdir()
    with open(study / "case.json", "w") as f:
        json.dump({"force_ratio": 41.2, "free_flow": {"Fr": 3.1}}, f)
    path = iw.figure(str(tmp_path), str(study))
    assert path == str(tmp_path / "impact_walls.png") and os.path.getsize(path) > 10000


H = [0.01, 0.2 / 28, 0.005]


def law(f0, c, p):
    """f0 + c Δx^p at the spacings H."""
    return [f0 + c * x ** p for x in H]


def test_window_limits_keep_ordered_limits_and_bracket_the_rest():
    # 40 and 20 ms: exact power laws, limits 10 and 12 N (ordered); 10 ms: first order, its limit
    # 13 N farther from the finest run than the runs lie apart (not trusted), bracketed by the 20 ms
    # limit and the 5 ms one; 5 ms: limit 16 N; 2 ms: an exact law whose limit 11 N lies below the
    # 5 ms limit, so it is dropped and bracketed by 16 N and its finest value
    rows = fc.windowLimits({0.04: law(10, 400, 2), 0.02: law(12, 900, 2), 0.01: law(13, 4e3, 0.8),
                            0.005: law(16, 3e4, 2), 0.002: law(11, 5e4, 1.5)}, H)
    by = {r["window"]: r for r in rows}
    assert [r["window"] for r in rows] == [0.002, 0.005, 0.01, 0.02, 0.04]
    for w, f0 in ((0.04, 10), (0.02, 12), (0.005, 16)):
        assert by[w]["why"] is None and by[w]["limit"] == pytest.approx(f0, rel=1e-6) and by[w]["bracket"] is None
    assert by[0.01]["why"].startswith("order 0.80") and by[0.01]["bracket"] == pytest.approx((12, 16), rel=1e-6)
    short = by[0.002]
    assert short["limit"] == pytest.approx(11, rel=1e-6)
    assert short["why"].startswith("limit 11 below the 5 ms window's 16")
    assert short["bracket"] == pytest.approx((16, short["values"][2]), rel=1e-6)


def test_window_limits_bracket_a_rising_sequence_and_refuse_crossed_sides():
    # a rising 10 ms sequence (limit 20 N, order 0.6: not trusted) above a kept 20 ms limit of
    # 18 N: at or above its finest value, at or below nothing: no bracket; with a kept 5 ms limit
    # of 25 N above it: from its finest value to 25 N. A falling one whose finest value lies
    # under the longer window's limit: the sides cross, no bracket
    rising = law(20, -40, 0.6)
    rows = fc.windowLimits({0.01: rising, 0.02: law(18, 900, 2)}, H)
    assert rows[0]["why"].startswith("order 0.60") and rows[0]["bracket"] is None
    rows = fc.windowLimits({0.005: law(25, 3e4, 2), 0.01: rising, 0.02: law(18, 900, 2)}, H)
    assert rows[1]["bracket"] == pytest.approx((rising[2], 25), rel=1e-9)
    rows = fc.windowLimits({0.01: law(10, 40, 0.6), 0.02: law(18, 900, 2)}, H)
    assert rows[0]["values"][2] < 18 and rows[0]["bracket"] is None


def test_impact_walls_refinement_reads_each_obstacle_over_its_windows(tmp_path):
    # a cube at three spacings (its lane rounded to whole cells differs in the last digits) whose
    # 20 ms blow follows 12 + 900 Δx², and a wall at two spacings (too few: not in the report)
    for dx, width in zip(H, (0.1, 0.09999999999999999, 0.1)):
        windows = {"10": 13 + 4e3 * dx ** 0.8, "20": 12 + 900 * dx ** 2}
        run = {"kind": "block", "theta": 20.0, "L0": 0.5, "young": 1e6, "dx": dx, "width": width, "block_size": 0.04,
               "free": {"h_f": 0.04}, "obstacle": {"F_windows": windows}}
        with open(tmp_path / ("block_dx%g.json" % dx), "w") as f:
            json.dump(run, f)
    for dx in (0.01, 0.005):
        with open(tmp_path / ("wall_dx%g.json" % dx), "w") as f:
            json.dump({"kind": "wall", "theta": 20.0, "L0": 0.5, "young": 1e6, "dx": dx, "width": 0.04,
                       "free": {"h_f": 0.04}, "obstacle": {"F_windows": {"10": 20.0}}}, f)
    text = iw.refinement(str(tmp_path))
    assert text.startswith("cube 40 mm in a 0.1 m lane, 20°, L0 0.5 m, E 1 MPa: Δx 0.01 / 0.00714286 / 0.005 m "
                           "(4.0 / 5.6 / 8.0 cells per block height)")
    lines = text.splitlines()
    assert len(lines) == 6 and "wall" not in text
    f10 = [13 + 4e3 * dx ** 0.8 for dx in H]
    assert lines[4].startswith("| 10 | %.3g / %.3g / %.3g | 0.80 | – | 12–%.3g |" % (*f10, f10[2]))
    assert lines[5].startswith("| 20 | ") and "| 2.00 | 12 | – |  |" in lines[5]
    # with the blow by parts in every run: their table after the windows', each span's limit
    for dx, width in zip(H, (0.1, 0.09999999999999999, 0.1)):
        path = tmp_path / ("block_dx%g.json" % dx)
        run = json.loads(path.read_text())
        run["obstacle"]["F_parts"] = {"load_0_2ms": 30 + 2e3 * dx ** 1.5, "load_2_5ms": 20 + 4e3 * dx ** 0.8,
                                      "load_5_25ms": 9 + 900 * dx ** 2}
        path.write_text(json.dumps(run))
    lines = iw.refinement(str(tmp_path)).splitlines()
    assert len(lines) == 12 and lines[7].startswith("| after the touch [ms] | mean force [N] |")
    assert lines[9].startswith("| 0–2 | ") and "| 1.50 | 30 |" in lines[9]
    assert lines[10].startswith("| 2–5 | ") and lines[10].endswith("lies farther from the finest run than the runs lie apart |")
    assert lines[11].startswith("| 5–25 | %.3g / " % (9 + 900 * H[0] ** 2)) and "| 2.00 | 9 |" in lines[11]


def test_impact_walls_refinement_keeps_no_limit_that_is_no_push(tmp_path):
    # a wall's onset falling as -5 + 1e4 Δx^1.2 at the spacings H: limitOf accepts the power law
    # (order 1.2, its limit as near the finest run as the runs lie apart), but a mean push on the
    # obstacle cannot go below zero: no limit, said why; the part after it (8 + 900 Δx²) keeps its 8 N
    for dx in H:
        run = {"kind": "wall", "theta": 20.0, "L0": 0.5, "young": 1e6, "dx": dx, "width": 0.04,
               "free": {"h_f": 0.04}, "obstacle": {"F_windows": {"10": 16 + 900 * dx ** 2},
                                                   "F_parts": {"load_0_2ms": -5 + 1e4 * dx ** 1.2,
                                                               "load_5_25ms": 8 + 900 * dx ** 2}}}
        with open(tmp_path / ("wall_dx%g.json" % dx), "w") as f:
            json.dump(run, f)
    p, f0, why = fc.limitOf(law(-5, 1e4, 1.2), H)
    assert why is None and f0 == pytest.approx(-5, rel=1e-6)
    p, f0, why = fc.limitOf(law(-5, 1e4, 1.2), H, positive=True)
    assert p == pytest.approx(1.2, rel=1e-6) and f0 == pytest.approx(-5, rel=1e-6)
    assert why == "its limit -5 is not positive, as this quantity must be"
    lines = iw.refinement(str(tmp_path)).splitlines()
    assert lines[-2].startswith("| 0–2 | ") and lines[-2].endswith("| 1.20 | – | %s |" % why)
    assert lines[-1].startswith("| 5–25 | ") and lines[-1].endswith("| 2.00 | 8 |  |")


def test_package_block_study_errors_against_the_kept_limits():
    # a cube at Δx 0.02 (coarser than the three finest: a row, not in the limits) and the three
    # of H: its 20 ms blow on 12 + 900 Δx² (limit 12 N kept), its 10 ms blow on 13 + 4e3 Δx^0.8
    # (no limit kept: unconverged, a bracket is not a reference); the work per simulated second
    # (points / step) against the run at 0.01 m
    def cube(dx, f10, f20):
        return {"kind": "block", "theta": 20.0, "L0": 0.5, "young": 1e6, "dx": dx, "width": 0.1, "block_size": 0.04,
                "points": 48000 * (0.01 / dx) ** 3, "dt": 5e-5 * dx / 0.01, "duration": 0.6, "commit": "abc1234",
                "flip_blend": "PIC viscosity 0.0347053 m^2/s, share 4 nu dt/dx^2", "free": {"h_f": 0.04},
                "obstacle": {"F_windows": {"10": f10, "20": f20}}}
    dxs = [0.02] + H
    f10 = [13 + 4e3 * dx ** 0.8 for dx in dxs]
    f20 = [12 + 900 * dx ** 2 for dx in dxs]
    study = iw.packageBlockStudy([cube(*v) for v in zip(dxs, f10, f20)], "CMD")
    assert study["name"] == "glued_cube_40mm_t20_L0.5_lane0.1"
    assert list(study["unconverged"]) == ["glued_block_peak_force"]
    assert study["unconverged"]["glued_block_peak_force"].startswith(
        "glued_block_peak_force of a glued 40 mm cube at 2.0 / 4.0 / 5.6 / 8.0 cells per block height")
    rows = study["rows"]
    assert [r["settings"]["dx"] for r in rows] == dxs
    assert [r["settings"]["cells_per_block_height"] for r in rows] == pytest.approx([2, 4, 5.6, 8])
    assert {r["settings"]["block_height"] for r in rows} == {0.04}
    assert [r["cost"] for r in rows] == pytest.approx([0.5 ** 4, 1, 1.4 ** 4, 16])
    for r, b in zip(rows, f20):
        assert list(r["errors"]) == ["glued_block_peak_force_20ms"]
        assert r["errors"]["glued_block_peak_force_20ms"] == pytest.approx(b / 12 - 1, rel=1e-6)
    # both on exact laws of high order: both kept
    f10 = [14 + 4e3 * dx ** 2 for dx in dxs]
    study = iw.packageBlockStudy([cube(*v) for v in zip(dxs, f10, f20)], "CMD")
    assert study["unconverged"] == {} and study["rows"][-1]["errors"]["glued_block_peak_force"] == pytest.approx(
        f10[-1] / 14 - 1, rel=1e-6)
    # without a run at 0.01 m there is no cost to measure against
    assert iw.packageBlockStudy([cube(*v) for v in zip(dxs, f10, f20)][2:] + [cube(0.004, 20, 13)], "CMD") is None


def test_impact_walls_step_factor_names_the_run_and_is_bounded(capsys):
    a = iw.parse(["--dx", "0.01", "--step-factor", "0.5"])
    assert a.step_factor == 0.5 and iw.runName(a, "wall", 20.0) == "wall_t20_L0.5_dx0.01_dtf0.5"
    assert iw.runName(iw.parse(["--dx", "0.01"]), "wall", 20.0) == "wall_t20_L0.5_dx0.01"
    for bad in ("0", "1.5", "nan"):
        with pytest.raises(SystemExit):
            iw.parse(["--step-factor", bad])
        assert "--step-factor = %s: must be in (0, 1]" % float(bad) in capsys.readouterr().err


def test_liu2018_force_windows_of_a_known_impulse():
    """liu2018_force.forceWindows on records every 1 ms (each record's force the one of the
    interval before it, as coupled.h5's are) of a block first pushed at the record of 0.3 s by
    F = 20 N for 10 ms, then 8 N, in a file without the contact's first step: the first touch is
    the first record with a force, the largest 10 ms mean 20 N (a window on the blow), the 20 ms
    one (20 + 8) / 2 = 14 N, the means after the touch 8 N, the first 20 ms' impulse, from the
    record before the touch, 0.2 + 0.08 = 0.28 N s; all read from the impulse (the records' own
    forces, here off by 5 N, only mark the touch)."""
    np = pytest.importorskip("numpy")
    import liu2018_force as lf
    t = np.arange(0, 451) * 1e-3
    F = np.where(t < 0.3 - 1e-9, 0.0, np.where(t < 0.31 - 1e-9, 20.0, 8.0))
    J = np.concatenate([[0.0], np.cumsum(F[1:] * np.diff(t))])
    w = lf.forceWindows({"t": t, "J": J, "Ft": np.where(F > 0, F + 5.0, 0.0)})
    assert w["touch"] == pytest.approx(0.3, abs=1e-12)
    assert w["peaks"][1] == pytest.approx(20.0, abs=1e-9) and w["peaks"][2] == pytest.approx(14.0, abs=1e-9)
    assert w["after_20_40"] == pytest.approx(8.0, abs=1e-9) and w["after_40_80"] == pytest.approx(8.0, abs=1e-9)
    assert w["late"] == pytest.approx(8.0, abs=1e-9)
    assert w["impulse_20ms"] == pytest.approx(0.28, abs=1e-9)


def test_liu2018_force_windows_count_from_the_contacts_first_step():
    """Where coupled.h5 records the contact's first step (flow_first_contact), the windows count
    from it, between records: a block pushed from 0.2994 s (inside the record interval
    0.299-0.300 s) by 20 N for 10 ms, then 8 N, recorded every 1 ms: by hand the touch 0.2994 s,
    the first 20 ms' impulse 20 x 0.01 + 8 x 0.01 = 0.28 N s, 8 N 20-40 ms after, and the largest
    10 ms mean the window from the touch: (0.192 + 0.4 x 0.0128) / 0.01 = 19.712 N (the blow ends
    between the records of 0.309 and 0.310 s, where the impulse is read linear); from the records
    alone the touch is 0.3 s, the impulse counts from the record of 0.299 s (0.2 + 8 x 0.0096 =
    0.2768 N s) and the largest window is 0.300-0.310 s (20 x 0.0094 + 8 x 0.0006 over 10 ms:
    19.28 N)."""
    np = pytest.importorskip("numpy")
    import liu2018_force as lf
    t, t0 = np.arange(0, 451) * 1e-3, 0.2994

    def J(x):  # the impulse of the force above at time x, by hand
        x = np.asarray(x, dtype=float)
        return 20 * np.clip(x - t0, 0, 0.01) + 8 * np.clip(x - t0 - 0.01, 0, None)

    records = {"t": t, "J": J(t), "Ft": np.where(t > t0, 1.0, 0.0)}
    w = lf.forceWindows(dict(records, first_contact=np.where(t >= t0, t0, np.nan)))
    assert w["touch"] == t0
    assert w["peaks"][1] == pytest.approx(19.712, rel=1e-12)
    assert w["impulse_20ms"] == pytest.approx(0.28, rel=1e-12)
    assert w["after_20_40"] == pytest.approx(8.0, rel=1e-12)
    old = lf.forceWindows(records)
    assert old["touch"] == pytest.approx(0.3, abs=1e-12)
    assert old["impulse_20ms"] == pytest.approx(0.2768, rel=1e-12)
    assert old["peaks"][1] == pytest.approx(19.28, rel=1e-12)


def test_liu2018_force_windows_of_a_block_the_flow_never_reached():
    """No record with a force (a flow too viscous to arrive): no touch and no window, not the
    windows of the run's first record."""
    np = pytest.importorskip("numpy")
    import liu2018_force as lf
    t = np.arange(0, 451) * 1e-3
    w = lf.forceWindows({"t": t, "J": np.zeros(len(t)), "Ft": np.zeros(len(t))})
    assert w["touch"] is None and all(np.isnan(w[k]) for k in ("after_20_40", "after_40_80", "late", "impulse_20ms"))
    assert np.isnan(w["peaks"]).all()


def test_run_prepared_runs_only_what_is_prepared_and_not_done(tmp_path, capsys):
    # (the legs themselves need the driver: scripts/checks/check_flume_convergence_pair.py runs them)
    with pytest.raises(SystemExit, match="no prepared run there"):
        fc.runPrepared(fc.parse(["--run-prepared", str(tmp_path)]))
    with pytest.raises(SystemExit, match="--workers = 2: a prepared run takes a whole device"):
        fc.runPrepared(fc.parse(["--run-prepared", str(tmp_path), "--workers", "2"]))
    done = tmp_path / "joint_viscosity_w0.2_dx0.0025"
    done.mkdir()
    (done / "meta.json").write_text(json.dumps({"dx": 0.0025, "free_wall": 1.0, "coupled_wall": 2.0}))
    fc.runPrepared(fc.parse(["--run-prepared", str(tmp_path), "--exe", str(tmp_path / "no-such-driver")]))
    assert capsys.readouterr().out == "joint_viscosity_w0.2_dx0.0025: done before\n"


def test_the_coupled_leg_starts_only_from_a_free_state_that_is_there(tmp_path):
    # an archive of prepared runs comes back without snapshots and checkpoints: runLegs then runs
    # the free leg again instead of a coupled leg the driver would refuse
    free = tmp_path / "free"
    free.mkdir()
    assert not fc.flowFromThere(str(free))
    (free / "front_snapshot_0.json").write_text(json.dumps({"checkpoint": "front_snapshot_0.checkpoint.json",
                                                             "snapshot": 6, "step": 2470}))
    (free / "front_snapshot_0.checkpoint.json").write_text("{}")
    assert not fc.flowFromThere(str(free))  # the snapshot it names is missing
    (free / "mpm.snapshots").mkdir()
    (free / "mpm.snapshots" / "000006.h5").write_bytes(b"")
    assert fc.flowFromThere(str(free))
    (free / "front_snapshot_0.checkpoint.json").unlink()
    assert not fc.flowFromThere(str(free))


def test_impact_cases_run_prepared_skip_those_run_or_read(tmp_path, capsys):
    # a case run there has its run.json; one run and read here before run.json existed, its OUT/<case>.json
    for name, marker in (("wall_t20_L0.5_dx0.005", "wall_t20_L0.5_dx0.005/run.json"),
                         ("free_t20_L0.5_dx0.005", "free_t20_L0.5_dx0.005.json")):
        (tmp_path / name).mkdir()
        (tmp_path / name / "meta.json").write_text(json.dumps({"kind": name.split("_")[0]}))
        (tmp_path / marker).write_text("{}")
    iw.main(["--run-prepared", str(tmp_path), "--exe", str(tmp_path / "no-such-driver")])
    assert capsys.readouterr().out == "free_t20_L0.5_dx0.005: done before\nwall_t20_L0.5_dx0.005: done before\n"


def test_an_obstacle_prepared_beside_its_free_flow_takes_its_arrival_where_they_run(tmp_path, capsys):
    # the free flows run first whatever the names' order; an obstacle's duration is then the free
    # flow's arrival + its --rest, in its scene and meta.json; without the free flow's outputs it
    # is refused, naming the free case
    free, wall = tmp_path / "free_t20_L0.5_dx0.0025", tmp_path / "block_t20_L0.5_dx0.0025"
    for folder, kind in ((free, "free"), (wall, "block")):
        folder.mkdir()
        (folder / "meta.json").write_text(json.dumps({"kind": kind}))
    order = []
    fc.runPreparedFolders(iw.parse(["--run-prepared", str(tmp_path)]), lambda f: False, order.append,
                          first=lambda f: os.path.basename(f).startswith("free_"))
    assert [os.path.basename(f) for f in order] == [free.name, wall.name]
    meta = {"kind": "block", "duration": None, "rest": 0.12, "free_case": free.name}
    (wall / "scene.json").write_text(json.dumps({"run": {"duration": 3.0, "dt": 1e-5, "output_every": 0.1}}))
    with pytest.raises(RuntimeError, match="its free flow free_t20_L0.5_dx0.0025 has not run"):
        iw.settleDuration(str(wall), meta)
    (free / "out").mkdir()
    (free / "out" / "flow_probes.json").write_text(json.dumps(
        {"probes": [{"arrival": 0.4559, "h_f": 0.0416, "v_f": 1.53, "Fr": 2.40}]}))
    settled = iw.settleDuration(str(wall), meta)
    assert settled["duration"] == pytest.approx(0.5759, abs=1e-12)
    assert json.loads((wall / "meta.json").read_text())["duration"] == pytest.approx(0.5759, abs=1e-12)
    run = json.loads((wall / "scene.json").read_text())["run"]
    assert run["duration"] == pytest.approx(0.5759, abs=1e-12) and run["output_every"] == 0.1 and run["dt"] == 1e-5
    assert iw.settleDuration(str(wall), settled) is settled  # set before: left alone
