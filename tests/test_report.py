"""The study report: every table and figure from a results folder, gaps said, not crashed on."""

import math
import os
import subprocess
import sys

import pytest
from click.testing import CliRunner

from drydem.parametric.records import write_record
from drydem.parametric.study import RunSpec
from drydem.cli import main
from drydem.report.study import DESIGNS, build_report

FIGURES = ["fig03_contact_points", "fig06_stiffness", "fig09_pushover", "fig10_pushover", "fig11_pushover", "fig12_dls", "fig13_ks"]


def tilt_record(design, kn, *, ks=None, points=None, protocol="adaptive", joint_law=None):
    """A made-up record whose collapse angle grows with log kn (the report only reads records);
    ``joint_law``: RunSpec.joint_law (JSON text), None for constant joints."""
    spec = RunSpec(analysis="tilt", target=design, protocol=protocol, kn=kn, ks=kn if ks is None else ks, points=points,
                   joint_law=joint_law)
    angle = 5.0 + 3.0 * math.log10(kn / 1e7) + int(design[2])
    curve = [[t, 1e-4 * t * 1e9 / kn, 0.0, 1e-4 * t * 1e9 / kn / 0.1485, 1000] for t in range(int(angle) + 1)]
    summary = {"collapse_angle_deg": float(int(angle)), "drift_limit_angles_deg": {"0.005": 1.0, "0.0075": 1.5, "0.01": angle / 3},
               "wall_height_m": 0.1485}
    return {"id": spec.id, "spec": spec.__dict__, "status": "ok", "error": None, "summary": summary, "pushover": curve}


def limit_record(design, method):
    spec = RunSpec(analysis="limit", target=design, protocol=method)
    summary = {"collapse_angle_deg": 20.0 + (method == "associative"), "method": method}
    return {"id": spec.id, "spec": spec.__dict__, "status": "ok", "error": None, "summary": summary, "pushover": []}


@pytest.fixture
def results(tmp_path):
    records = []
    for d in DESIGNS:
        records += [tilt_record(d, kn) for kn in (1e7, 3e7, 1e8, 1e9, 1e10)]
        records += [tilt_record(d, kn, protocol="fixed") for kn in (3e7, 1e9)]
        records += [limit_record(d, m) for m in ("associative", "non-associative")]
    records += [tilt_record("WD6", kn, ks=ks, protocol="fixed") for kn in (1e7, 4e7, 7e7, 1e8) for ks in (1e7, 2e7, 1e8)]
    records += [tilt_record("WD3", 3e7, points=p) for p in (1, 2, 8)]
    unstable = tilt_record("WD6", 1e7, ks=1e7, protocol="fixed")  # the paper: WD6 cannot stand at kn = 1e7
    unstable["summary"] |= {"collapse_angle_deg": None, "drift_limit_angles_deg": {"0.005": None, "0.0075": None, "0.01": None}}
    unstable["pushover"] = []
    records = [r for r in records if r["id"] != unstable["id"]] + [unstable]
    broken = RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=5e7, ks=5e7)
    failed = {"id": broken.id, "spec": broken.__dict__, "status": "failed", "error": "ModelError: made up"}
    for record in records + [failed]:
        write_record(tmp_path, record)
    return tmp_path


def test_the_report_has_every_table_and_figure(results):
    text = build_report(results).markdown.read_text()
    for title in ("Table 2", "Table 3", "Table 4"):
        assert f"## {title}" in text
    for name in FIGURES:
        assert f"(figures/{name}.png)" in text
        assert (results / "report" / "figures" / f"{name}.png").stat().st_size > 5_000
    assert "no runs for this figure" not in text
    assert "reconstructions" in text and "1 failed" in text
    # ours beside the paper's: WD1's LA-A is 23.9 in the paper, 21.0 in the made-up record
    assert "| WD1 | 18.3 | 23.9 / 21.0 | 23.5 / 20.0 |" in text
    html = (results / "report" / "report.html").read_text()
    assert html.count("<table>") == 3 and html.count("<img") == len(FIGURES)


def test_a_report_of_an_unfinished_study_says_what_is_missing(tmp_path):
    write_record(tmp_path, limit_record("WD2", "associative"))
    result = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert result.exit_code == 0, result.output
    text = (tmp_path / "report" / "report.md").read_text()
    assert text.count("(no runs for this figure in the study)") == len(FIGURES)
    assert "| WD2 | 7.8 | 17.0 / 21.0 | 16.0 / - |" in text


def test_a_run_without_equilibrium_nor_collapse_is_a_lower_bound_not_an_angle():
    from drydem.report.study import Runs

    record = tilt_record("WD7", 1e10)
    record["summary"] |= {"collapse_angle_deg": None, "last_equilibrium_deg": 22.9, "stable_under_gravity": True,
                          "ended_by": "no equilibrium within max_cycles"}
    runs = Runs([record])
    assert runs.angle_cell("WD7", 1e10) == ">= 22.9" and runs.capacity("WD7", 1e10) is None
    assert Runs([tilt_record("WD7", 1e9)]).angle_cell("WD7", 1e9) == "18.0"  # 5 + 3 log10(100) + 7, truncated


def test_drawing_a_figure_leaves_the_matplotlib_backend_alone(tmp_path):
    """A notebook's backend (here svg, from MPLBACKEND) stays as it is, and pyplot unused."""
    code = """if True:
        import sys
        import matplotlib
        import drydem as dd
        from drydem.report.plots import layout_figure
        blocks = [dd.Block(name="base", shape=dd.box([0, 0, -0.01], [0.1, 0.012, 0]), fixed=True),
                  dd.Block(name="brick", shape=dd.box([0, 0, 0], [0.025, 0.012, 0.0055]))]
        layout_figure(dd.build_model(blocks, density=1800.0), sys.argv[1], monitored="brick")
        print("matplotlib.pyplot" in sys.modules, matplotlib.get_backend())
    """
    figure = tmp_path / "wall.png"
    ran = subprocess.run([sys.executable, "-c", code, str(figure)], env=os.environ | {"MPLBACKEND": "svg"},
                         capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0, ran.stderr
    assert ran.stdout.split() == ["False", "svg"]
    assert figure.read_bytes().startswith(b"\x89PNG") and figure.stat().st_size > 5_000
