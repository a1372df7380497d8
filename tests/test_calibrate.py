"""Calibration of kn: the search finds a known optimum and reuses what it evaluated."""

import math

import pytest

from drydem.parametric.calibrate import calibrate, mean_absolute_relative_error


def test_finds_the_minimum_of_a_synthetic_error_curve():
    calls = []

    def error(kn):  # V-shaped in log kn, least (0.02) at 3.3e7
        calls.append(kn)
        return 0.02 + 0.3 * abs(math.log10(kn) - math.log10(3.3e7))

    result = calibrate(error, 1e7, 1e10)
    assert result.best_kn == pytest.approx(3.3e7, rel=0.03)
    assert result.best_error == pytest.approx(0.02, abs=0.005)
    assert len(calls) == len(set(calls)) == len(result.curve) <= 30  # each kn run once
    assert [kn for kn, _ in result.curve] == sorted(kn for kn, _ in result.curve)


def test_the_coarse_grid_keeps_it_out_of_a_local_minimum():
    # a shallow dip at 1e9 and the true minimum at 2e7
    def error(kn):
        x = math.log10(kn)
        return min(0.5 * abs(x - 7.3), 0.4 + 0.1 * abs(x - 9.0))

    assert calibrate(error, 1e7, 1e10).best_kn == pytest.approx(2e7, rel=0.05)


def test_mean_absolute_relative_error_as_in_the_paper():
    # paper Table 3: 20.0 vs 18.3 is +9.5 %, 5.9 vs 7.8 is -24.7 %
    error = mean_absolute_relative_error({"WD1": 20.0, "WD6": 5.9}, {"WD1": 18.3, "WD6": 7.8})
    assert error == pytest.approx((1.7 / 18.3 + 1.9 / 7.8) / 2)


def test_the_objective_counts_a_wall_that_cannot_stand_as_0_deg_and_no_verdict_as_no_angle():
    from drydem.parametric.calibrate import wall_angle

    assert wall_angle({"stable_under_gravity": False, "collapse_angle_deg": None, "ended_by": "unstable under gravity"}) == 0.0
    assert wall_angle({"stable_under_gravity": True, "collapse_angle_deg": 18.3, "ended_by": "stop displacement"}) == 18.3
    no_verdict = {"stable_under_gravity": None, "collapse_angle_deg": None, "ended_by": "no equilibrium under gravity within max_cycles"}
    assert wall_angle(no_verdict) is None
