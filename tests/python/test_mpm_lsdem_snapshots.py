"""scripts/validation/mpm_lsdem_compare.py's side views: the record picked for a requested time and a
block's outline, on cases made by hand (no run needed)."""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "validation"))
import mpm_lsdem_compare as mlc  # noqa: E402

# records every 0.05 s, a little late as a run writes them (at the start of the step after), and the run's end
TIMES = [0.0, 0.05002, 0.10001, 0.15003, 0.2]


def test_a_time_on_a_record_or_within_half_an_interval_picks_that_record():
    assert mlc.recordAt(TIMES, 0.1) == 2
    assert mlc.recordAt(TIMES, 0.12) == 2      # 0.02 s from it: under half the 0.05 s interval
    assert mlc.recordAt(TIMES, 0.13) == 3      # nearer the next one
    assert mlc.recordAt(TIMES, 0.0) == 0


def test_a_time_with_no_record_near_it_is_refused_naming_the_nearest():
    with pytest.raises(ValueError, match=r"t = 0\.3 s.*nearest is at 0\.2000 s"):
        mlc.recordAt(TIMES, 0.3)
    with pytest.raises(ValueError, match="no records"):
        mlc.recordAt([], 0.1)


def test_a_box_outline_is_its_side_view_upright_and_turned_a_quarter_about_the_cross_axis():
    half = np.array([0.01, 0.1, 0.005])
    up = mlc.outline(np.array([1.0, 0.5, 0.2]), np.zeros(3), half)
    assert sorted(map(tuple, np.round(up, 9))) == [(0.99, 0.195), (0.99, 0.205), (1.01, 0.195), (1.01, 0.205)]
    turned = mlc.outline(np.zeros(3), np.array([0.0, math.pi / 2, 0.0]), half)  # long and flat become tall and thin
    assert np.ptp(turned[:, 0]) == pytest.approx(0.01) and np.ptp(turned[:, 1]) == pytest.approx(0.02)
    assert len(turned) == 4


def test_the_blend_is_passed_on_or_refused_naming_the_option(capsys):
    assert mlc.parse([]).flip_viscosity is None                      # the example's own
    assert mlc.parse(["--flip-viscosity", "0.05"]).flip_viscosity == 0.05
    for bad in ("0", "-0.01", "inf", "nan"):
        with pytest.raises(SystemExit):
            mlc.parse(["--flip-viscosity", bad])
        assert "--flip-viscosity" in capsys.readouterr().err


def test_level_set_spacings_past_the_points_radius_are_refused_before_any_run(capsys):
    # R_p0 at dx 0.01 m: (3 dx^3 / (4 pi ppc))^(1/3) = 6.204 mm with 1 point per cell, 3.102 mm with 8
    assert mlc.parse(["--ls-spacing", "0.006,0.002"]).ls_spacing == [0.006, 0.002]
    assert mlc.parse(["--ppc", "8", "--ls-spacing", "0.003"]).ls_spacing == [0.003]
    for args, named in ((["--ppc", "8", "--ls-spacing", "0.002,0.004"], "0.004"), (["--ls-spacing", "0.007"], "0.007")):
        with pytest.raises(SystemExit):
            mlc.parse(args)
        err = capsys.readouterr().err
        assert "--ls-spacing %s: every spacing must be at most the points' radius R_p0 = " % named in err, err
