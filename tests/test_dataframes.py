"""Results as pandas DataFrames (issue 19): a tilting analysis' pushover curve, a shaking-table
analysis' history, a study's run records and a Monte Carlo run's samples, each a table with
the units in its column names and the outcome in ``attrs``; without pandas, an error saying
how to install it."""

from __future__ import annotations

import re
import sys
from dataclasses import asdict

import numpy as np
import pytest

from drydem.analysis.shake import History, ShakeResult, ShakeSettings, pulse
from drydem.analysis.tilt import Record, TiltResult, TiltSettings
from drydem.errors import DrydemError
from drydem.parametric.montecarlo import MonteCarloOutcome
from drydem.parametric.records import record_path, write_record
from drydem.parametric.study import RunSpec
from drydem.parametric.sweep import records_dataframe

#: a made-up pushover curve: three equilibria, the drift 1 % at 2 deg
RECORDS = [Record(0.0, 0.0, 0.0, 0.0, 100), Record(1.0, 0.001, -1e-5, 0.005, 200), Record(2.0, 0.002, -2e-5, 0.01, 300)]


def tilt_result(records=RECORDS) -> TiltResult:
    return TiltResult(settings=TiltSettings(), monitored_block="top", wall_height_m=0.2, stable_under_gravity=True,
                      last_equilibrium_deg=2.0, collapse_angle_deg=2.0, records=records, lost_blocks=[("b7", 2.1)], cycles=600,
                      runtime_s=1.5, collapse_state=None, final_state=None, ended_by="stop displacement")


def test_a_tilt_result_is_its_pushover_curve_with_the_outcome_in_attrs():
    frame = tilt_result().to_dataframe()
    assert list(frame.columns) == ["tilt_deg", "load_multiplier", "ux_m", "uz_m", "drift", "cycles"]  # pushover.csv's
    assert frame["ux_m"].tolist() == [0.0, 0.001, 0.002] and frame["cycles"].tolist() == [100, 200, 300]
    assert frame["load_multiplier"].iloc[2] == pytest.approx(np.tan(np.radians(2.0)))
    assert frame.attrs["collapse_angle_deg"] == 2.0 and frame.attrs["ended_by"] == "stop displacement"
    assert frame.attrs["lost_blocks"] == [("b7", 2.1)]
    # the drift limits by number, the 1 % drift reached at 2 deg (RECORDS)
    assert frame.attrs["drift_limit_angles_deg"][0.01] == pytest.approx(2.0)


def test_a_tilt_result_without_equilibria_is_an_empty_table():
    frame = tilt_result(records=[]).to_dataframe()
    assert frame.empty and list(frame.columns)[:2] == ["tilt_deg", "load_multiplier"]


def test_a_shake_result_is_its_history_with_the_outcome_in_attrs():
    motion = pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=5.0)
    time_s = np.array([0.0, 0.1, 0.2])
    ground = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.1], [0.0, 0.0, 0.0]])
    history = History(time_s, ground, np.array([0.0, 1e-3, 2e-3]), np.zeros(3), np.array([0.0, -1e-5, 0.0]), np.array([0.0, 0.01, 0.02]))
    result = ShakeResult(settings=ShakeSettings(motion=motion), monitored_block="top", overturned=False, fallen_blocks=[],
                         max_rotation_rad=0.02, max_displacement_m=2e-3, residual_displacement_m=2e-3, duration_s=0.2, cycles=10,
                         runtime_s=0.1, contact_damping_ratio=0.5, restitution=None, timestep_s=1e-5, ended_by="duration",
                         history=history, final_state=None)
    frame = result.to_dataframe()
    assert list(frame.columns) == ["time_s", "ground_acc_x_m_s2", "ground_acc_y_m_s2", "ground_acc_z_m_s2", "ux_m", "uy_m", "uz_m",
                                   "rotation_rad"]
    assert frame["ground_acc_x_m_s2"].tolist() == [0.0, 2.0, 0.0] and frame["ground_acc_z_m_s2"].tolist() == [0.0, 0.1, 0.0]
    assert frame["rotation_rad"].tolist() == [0.0, 0.01, 0.02]
    assert frame.attrs["overturned"] is False and frame.attrs["pga_m_s2"] == pytest.approx(2.0)
    assert frame.attrs["motion"] == motion.name


def run_record(spec: RunSpec, summary: dict) -> dict:
    return {"id": spec.id, "spec": asdict(spec), "status": "ok", "error": None, "summary": summary, "pushover": [], "runtime_s": 1.0}


def test_a_results_folder_is_a_table_of_its_runs_with_the_corrupt_ones_named(tmp_path):
    tilt = RunSpec(analysis="tilt", target="WD1", protocol="adaptive", kn=3e7, ks=3e7)
    limit = RunSpec(analysis="limit", target="WD1", protocol="associative")
    failed = RunSpec(analysis="tilt", target="WD2", protocol="adaptive", kn=1e8, ks=1e8)
    write_record(tmp_path, run_record(tilt, {"collapse_angle_deg": 18.5, "drift_limit_angles_deg": {"0.005": 4.0, "0.01": 9.0},
                                             "wall_height_m": 0.2, "ended_by": "stop displacement", "model": {"blocks": 50}}))
    write_record(tmp_path, run_record(limit, {"collapse_angle_deg": 21.0, "method": "associative"}))
    write_record(tmp_path, {"id": failed.id, "spec": asdict(failed), "status": "failed", "error": "ModelError: made up"})
    corrupt = record_path(tmp_path, RunSpec(analysis="tilt", target="WD3", protocol="fixed").id)
    corrupt.write_text("{")
    frame = records_dataframe(tmp_path).set_index("target", drop=False)
    assert sorted(frame["id"]) == sorted([tilt.id, limit.id, failed.id])
    assert {"kn_Pa_m", "ks_Pa_m", "analysis", "protocol", "collapse_angle_deg", "drift_0.01_angle_deg"} <= set(frame.columns)
    assert "model" not in frame.columns  # a table in the summary is not a cell
    row = frame[frame["analysis"] == "tilt"].loc["WD1"]
    assert (row["kn_Pa_m"], row["collapse_angle_deg"], row["drift_0.01_angle_deg"], row["ended_by"]) == (3e7, 18.5, 9.0, "stop displacement")
    assert frame.loc["WD2", "error"] == "ModelError: made up" and np.isnan(frame.loc["WD2", "collapse_angle_deg"])
    assert len(frame.attrs["corrupt"]) == 1 and str(corrupt) in frame.attrs["corrupt"][0]


def test_a_results_folder_that_is_not_one_is_refused_by_name(tmp_path):
    with pytest.raises(DrydemError, match=f"{tmp_path / 'missing'}: no such results folder"):
        records_dataframe(tmp_path / "missing")
    # found by a hunt: a tilt run's folder was an empty table, a file "no such folder", None a TypeError
    with pytest.raises(DrydemError, match=re.escape(f"{tmp_path}: no runs/ folder, so no sweep's results")):
        records_dataframe(tmp_path)
    (tmp_path / "summary.json").write_text("{}")
    with pytest.raises(DrydemError, match=re.escape(f"{tmp_path / 'summary.json'}: not a folder")):
        records_dataframe(tmp_path / "summary.json")
    with pytest.raises(DrydemError, match=re.escape("records_dataframe results = None: must be")):
        records_dataframe(None)
    (tmp_path / "runs").mkdir()
    assert records_dataframe(tmp_path).empty  # a sweep's folder without runs yet


def test_a_monte_carlo_run_is_a_table_of_its_samples_with_the_statistics_in_attrs():
    samples = [{"index": 0, "seed": 11, "status": "ok", "collapse_angle_deg": 18.0, "dls_angle_deg": 8.0, "ended_by": "stop displacement",
                "runtime_s": 3.0},
               {"index": 1, "seed": 12, "status": "failed", "collapse_angle_deg": None, "dls_angle_deg": None, "ended_by": None,
                "error": "ModelError: made up", "runtime_s": 0.1}]
    summary = {"samples": samples, "collapse_angle_deg": {"count": 1, "mean": 18.0}, "dls_angle_deg": {"count": 1, "mean": 8.0},
               "excluded": {"collapse_angle_deg": {"failed": 1}}, "settings": {"seed": 1}, "target": {"name": "WD3"}}
    frame = MonteCarloOutcome(finished=2, skipped=0, corrupt=(), summary=summary).to_dataframe()
    assert frame["seed"].tolist() == [11, 12] and frame["status"].tolist() == ["ok", "failed"]
    assert frame["collapse_angle_deg"].iloc[0] == 18.0 and np.isnan(frame["collapse_angle_deg"].iloc[1])
    assert frame["error"].isna().tolist() == [True, False] and frame["error"].iloc[1] == "ModelError: made up"
    assert frame.attrs["collapse_angle_deg"]["mean"] == 18.0 and frame.attrs["target"] == {"name": "WD3"}
    # found by a hunt: an angle True went into the frame
    summary["samples"][1]["dls_angle_deg"] = True
    with pytest.raises(DrydemError, match=re.escape("samples[1] dls_angle_deg = True: must be a number in [0, 90] deg, or None")):
        MonteCarloOutcome(finished=2, skipped=0, corrupt=(), summary=summary).to_dataframe()


def test_without_pandas_a_dataframe_is_a_drydem_error_saying_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    with pytest.raises(DrydemError, match=r"needs pandas, which is not installed: pip install pandas \(or pip install 'drydem\[data\]'\)"):
        tilt_result().to_dataframe()


def test_the_analyses_do_not_import_pandas():
    import subprocess

    code = "import sys, drydem.analysis.tilt, drydem.analysis.shake, drydem.parametric.sweep; print('pandas' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
