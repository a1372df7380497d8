"""Calibration of kn: the search finds a known optimum and reuses what it evaluated."""

import math

import pytest

from drydem.errors import ModelError
from drydem.parametric.calibrate import CalibrationError, calibrate, calibration_error, mean_absolute_relative_error


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


@pytest.mark.parametrize("settings, rule", [
    ({"kn_min": 1e9, "kn_max": 1e7}, "calibrate kn_min = 1000000000.0, calibrate kn_max = 10000000.0: need calibrate kn_min < calibrate kn_max"),
    ({"kn_min": 0.0}, "calibrate kn_min = 0.0: must be a number in [1e+04, 1e+15] Pa/m"),
    ({"kn_max": True}, "calibrate kn_max = True: must be a number in [1e+04, 1e+15] Pa/m"),
    ({"grid": 1}, "calibrate grid = 1: must be an integer in [2, 1000]"),
    ({"grid": True}, "calibrate grid = True: must be an integer in [2, 1000]"),
    ({"tolerance": 0}, "calibrate tolerance = 0: must be a number in (0, 1)"),
    ({"max_evaluations": 0}, "calibrate max_evaluations = 0: must be an integer in [1, inf)"),
])
def test_a_bad_calibration_range_is_a_model_error_naming_it_and_its_range(settings, rule):
    arguments = {"kn_min": 1e7, "kn_max": 1e9} | settings
    with pytest.raises(ModelError) as refused:
        calibrate(lambda kn: 0.0, arguments.pop("kn_min"), arguments.pop("kn_max"), **arguments)
    assert str(refused.value) == rule


def record(summary=None, error=None):
    return {"status": "failed", "error": error} if error else {"status": "ok", "error": None, "summary": summary}


def test_the_objective_of_a_kn_is_the_mean_error_of_its_records_with_a_fallen_wall_at_0_deg():
    records = {"WD1": record({"stable_under_gravity": True, "collapse_angle_deg": 20.0, "ended_by": "stop displacement"}),
               "WD6": record({"stable_under_gravity": False, "collapse_angle_deg": None, "ended_by": "unstable under gravity"})}
    assert calibration_error(records, {"WD1": 18.3, "WD6": 7.8}) == pytest.approx((1.7 / 18.3 + 1.0) / 2)
    assert calibration_error(records) == pytest.approx(calibration_error(records, {"WD1": 18.3, "WD6": 7.8}))  # the paper's Table 1
    records["WD7"] = record({"stable_under_gravity": None, "collapse_angle_deg": None, "ended_by": "no equilibrium under gravity"})
    records["WD2"] = record(error="ModelError: made up")
    with pytest.raises(CalibrationError, match="runs without a collapse angle:\n  WD2: ModelError: made up\n  WD7: no equilibrium under gravity"):
        calibration_error(records)
