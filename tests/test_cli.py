"""The command line: drydem check."""

import math
import sys

import pytest
from click.testing import CliRunner

from drydem.cli import main


def test_check_prints_blocks_contacts_mass_and_timestep():
    result = CliRunner().invoke(main, ["check", "perforated_wall"])
    assert result.exit_code == 0, result.output
    for expected in ["blocks          174 (173 movable, 1 fixed)", "sub-contacts", "mass            0.42768 kg", "timestep"]:
        assert expected in result.output


def test_check_settle_converges_and_reports_the_settlement():
    result = CliRunner().invoke(main, ["check", "perforated_wall", "--settle"])
    assert result.exit_code == 0, result.output
    assert "equilibrium     converged" in result.output and "settlement" in result.output


SIZES = """
[[block]]
name = "base"
fixed = true
box = { min = [-6, -6, -1], max = [6, 6, 0] }
[[block]]
name = "big"
box = { min = [-5, -5, 0], max = [5, 5, 10] }
[[block]]
name = "small"
box = { min = [0, 0, 10], max = [SIDE, SIDE, 10.SIDE_Z] }
"""


@pytest.mark.parametrize("side, warned", [("0.001", True), ("0.5", False)])
def test_check_warns_when_block_masses_span_more_than_the_ratio_criterion_resolves(tmp_path, side, warned):
    """A 10 m block under a 1 mm one (masses 1e12 apart): the ratio test, over the heavy block's
    weight with the light one's timestep, called such a model at rest while it moved at 0.11 m/s
    (README, "Equilibrium"); the warning names the spread and the velocity criterion."""
    path = tmp_path / "sizes.toml"
    path.write_text(SIZES.replace("10.SIDE_Z", str(10 + float(side))).replace("SIDE", side))
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert ("the movable blocks' masses span 1.0e+12" in result.output and 'criterion = "velocity"' in result.output) == warned
    assert ("masses span" in result.output) == warned


def test_check_settle_stops_when_a_block_falls_out(tmp_path):
    # a brick beside its base, touching nothing: settling cycled it on for up to 2,000,000 cycles
    path = tmp_path / "beside.toml"
    path.write_text(SIZES.replace('box = { min = [-5, -5, 0], max = [5, 5, 10] }', 'box = { min = [7, 0, 0], max = [7.1, 0.1, 0.05] }')
                    .split('[[block]]\nname = "small"')[0])
    result = CliRunner().invoke(main, ["check", str(path), "--settle"])
    assert result.exit_code == 1, result.output
    assert "equilibrium     stopped, a block fell" in result.output
    assert "fell out        1 blocks dropped more than two of their heights: 'big': the model cannot stand under its own weight" in result.output


def test_check_settle_says_a_model_on_too_soft_joints_cannot_stand_and_why(tmp_path):
    """Found by a hunt: a 0.2 m block on kn = 1e4 Pa/m (its own weight closes 392 mm) was "NOT
    converged" by check --settle, where tilt says it cannot stand and why."""
    path = tmp_path / "soft.toml"
    path.write_text('[joint]\nkn = 1e4\nks = 1e4\n[[block]]\nname = "base"\nfixed = true\nbox = { min = [-1, -1, -0.2], max = [2, 1, 0] }\n'
                    '[[block]]\nname = "b0"\nbox = { min = [0, -0.1, 0], max = [1.0, 0.1, 0.2] }\n')
    result = CliRunner().invoke(main, ["check", str(path), "--settle"])
    assert result.exit_code == 1, result.output
    assert "'b0': the model cannot stand under its own weight; the joints are too soft to carry it" in result.output
    assert "NOT converged" not in result.output


def test_bad_model_exits_with_its_message(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[joint]\nkn = -1.0\n[[block]]\nbox = { min = [0, 0, 0], max = [1, 1, 1] }\n")
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 1
    assert "broken.toml: [joint] kn = -1.0: must be a number in [1e+04, 1e+15] Pa/m" in result.output


def small_wall_file(tmp_path):
    """A 2-brick x 6-course running-bond wall (no openings) as a model file."""
    from drydem.io.model_file import save_model
    import drydem as dd
    from conftest import layout_blocks

    model = dd.build_model(
        layout_blocks("bBb\nBB\n" * 3), density=1800.0,
        joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5), supports=dd.Supports(fix_y=True),
    )
    path = tmp_path / "small_wall.toml"
    save_model(model, path)
    return path


def test_a_tilt_that_fails_before_its_first_equilibrium_leaves_nothing_and_the_same_out_takes_the_next(tmp_path, monkeypatch):
    # a timestep 20x the critical one (the divergence test of test_solver) blows the settlement
    # up: pushover.csv's header and the empty VTK series were left, and the corrected
    # command on the same --out was refused as "another run" without --overwrite
    import drydem.engine.inertia

    real = drydem.engine.inertia.critical_timestep
    monkeypatch.setattr(drydem.engine.inertia, "critical_timestep", lambda *args: 20.0 * real(*args))
    monkeypatch.setattr(drydem.engine.inertia, "free_flight_timestep", lambda *args: float("inf"))
    path, out = small_wall_file(tmp_path), tmp_path / "run"
    result = CliRunner().invoke(main, ["tilt", str(path), "--increment", "1.0", "--vtk", "--out", str(out)])
    assert result.exit_code == 1 and "diverged" in result.output
    assert list(out.iterdir()) == []
    monkeypatch.undo()
    result = CliRunner().invoke(main, ["tilt", str(path), "--increment", "1.0", "--out", str(out)])
    assert result.exit_code == 0, result.output


def test_tilt_end_to_end_writes_summary_curve_and_plots(tmp_path):
    import csv
    import json

    out = tmp_path / "run"
    result = CliRunner().invoke(main, ["tilt", str(small_wall_file(tmp_path)), "--increment", "1.0", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "collapse angle" in result.output and "drift limits" in result.output
    summary = json.loads((out / "summary.json").read_text())
    for key in ("collapse_angle_deg", "stable_under_gravity", "drift_limit_angles_deg", "monitored_block", "wall_height_m",
                "model", "analysis", "cycles", "runtime_s", "drydem_version"):
        assert key in summary
    assert set(summary["drift_limit_angles_deg"]) == {"0.005", "0.0075", "0.01"}
    assert summary["wall_height_m"] == pytest.approx(6 * 0.0055, rel=1e-12)  # six courses; the layout's sums round off
    # a 50 mm x 33 mm solid wall on mu = 0.5: it slides (26.6 deg) before it could topple (56 deg)
    assert 25.5 <= summary["collapse_angle_deg"] <= 26.6
    with (out / "pushover.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [float(r["tilt_deg"]) for r in rows] == [float(k) for k in range(len(rows))]
    assert float(rows[-1]["tilt_deg"]) == summary["collapse_angle_deg"]
    for picture in ("pushover.png", "mechanism.png"):
        assert (out / picture).stat().st_size > 10_000


def test_tilt_options_override_the_model_and_the_shipped_example_runs(tmp_path):
    out = tmp_path / "example"
    result = CliRunner().invoke(
        main, ["tilt", "perforated_wall", "--increment", "5", "--max-angle", "10", "--kn", "1e9", "--points", "2", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "no collapse up to 10.00 deg (the last step within max_angle_deg = 10)" in result.output
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["model"]["joint"]["kn"] == 1e9 and summary["model"]["contacts"]["points_per_length"] == 2
    assert summary["collapse_angle_deg"] is None and summary["equilibrium_states"] == 3


def test_tilt_with_an_unknown_monitored_block_names_it():
    result = CliRunner().invoke(main, ["tilt", "perforated_wall", "--monitor", "nosuch"])
    assert result.exit_code == 1 and "no block named 'nosuch'" in result.output


def test_resume_needs_a_checkpoint(tmp_path):
    result = CliRunner().invoke(main, ["tilt", "perforated_wall", "--resume", "--out", str(tmp_path)])
    assert result.exit_code == 1 and "--resume needs --out DIR holding a checkpoint.npz" in result.output


@pytest.mark.parametrize("signal_name, code", [("SIGINT", 130), ("SIGTERM", 143)])
def test_an_interrupted_tilt_keeps_its_checkpoint_and_resumes_from_it(tmp_path, signal_name, code):
    # a real process and a real signal (Ctrl-C, or a kill / a scheduler's time limit): numba
    # must not crash on it (it did, while boxing a NamedTuple return value), what was found
    # stays on disk, the message says how to go on (not asking for the --out it was given),
    # and --resume says where it goes on from
    from processes import interrupted_drydem

    out = tmp_path / "run"
    csv = out / "pushover.csv"
    returncode, err = interrupted_drydem(["tilt", "perforated_wall", "--out", str(out)], csv, 3, signal_name)
    assert returncode == code, err[-500:]
    assert f"interrupted ({signal_name})" in err and "the same command plus --resume" in err and "--out" not in err.split("Go on with")[1]
    assert (out / "checkpoint.npz").is_file() and len(csv.read_text().splitlines()) >= 3
    changed = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume", "--increment", "0.2"])
    assert changed.exit_code == 1 and "tilt setting increment_deg: 0.1 in the checkpoint, 0.2 now" in changed.output
    # found by a hunt: a series begun at the checkpoint would miss the run's first equilibria
    late = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume", "--vtk"])
    assert late.exit_code == 1 and "the run being resumed has no VTK series, and one begun now would miss its" in late.output
    result = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume"])
    assert result.exit_code == 0 and "resuming from" in result.output and "checkpoint.npz: last equilibrium at" in result.output
    # the run is finished: resuming again keeps its results and runs nothing
    summary = (out / "summary.json").read_bytes()
    again = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume"])
    assert again.exit_code == 0 and "holds a finished run of these options (summary.json): nothing to resume" in again.output
    assert "collapse angle" not in again.output and (out / "summary.json").read_bytes() == summary
    frames = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume", "--vtk"])
    assert frames.exit_code == 1 and "holds a finished run without a VTK series: --vtk and --video need it run again" in frames.output
    # found by a hunt: a finished run whose pushover.csv was cut short was said finished and kept
    (out / "pushover.csv").write_text("".join(csv.read_text().splitlines(keepends=True)[:3]))
    cut = CliRunner().invoke(main, ["tilt", "perforated_wall", "--out", str(out), "--resume"])
    assert cut.exit_code == 1 and f"{out / 'pushover.csv'}: 2 rows, where summary.json records" in cut.output
    assert f"the finished run in {out} is damaged: --overwrite runs it again" in cut.output


def test_designs_lists_the_seven_walls_with_their_brief_check():
    result = CliRunner().invoke(main, ["designs"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    for k, team in enumerate(["Newcastle", "Leeds", "Lyon", "Pavia", "Leuven", "Yildiz", "Munich"], start=1):
        line = next(line for line in lines if line.startswith(f"WD{k} "))
        assert team in line and line.endswith("ok")
    assert "perforated_wall" in result.output and "breaks it: 4 lintels, not 1" in result.output
    assert "reconstructions" in lines[-1]
    # found by a hunt: a wall's count left out the fixed base, a building's held it, under one
    # header; the walls now count bricks, as `drydem check` says (171 blocks: 170 movable, 1 fixed)
    assert lines[0].split()[3] == "bricks" and next(line for line in lines if line.startswith("WD3 ")).split()[-2] == "170"
    assert "a building's blocks include its fixed base" in result.output


def test_show_draws_a_wall_and_strict_fails_on_a_brief_violation(tmp_path):
    out = tmp_path / "wd6.png"
    result = CliRunner().invoke(main, ["show", "WD6", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "monitored block c26b4" in result.output and out.stat().st_size > 20_000
    result = CliRunner().invoke(main, ["show", "perforated_wall", "-o", str(tmp_path / "p.png"), "--strict"])
    assert result.exit_code == 1 and "brief: 4 lintels, not 1" in result.output and "breaks the competition brief" in result.output


def test_export_writes_a_model_file_that_loads_back_and_vtk(tmp_path):
    from drydem.io.target import load_target

    for name in ("wd3.toml", "wd3.vtu", "wd3.stl"):
        result = CliRunner().invoke(main, ["export", "WD3", str(tmp_path / name)])
        assert result.exit_code == 0, result.output
    again, original = load_target(str(tmp_path / "wd3.toml")).model, load_target("WD3").model
    assert again.block_name == original.block_name and again.joint == original.joint and again.supports == original.supports
    result = CliRunner().invoke(main, ["export", "WD3", str(tmp_path / "wd3.ply")])
    assert result.exit_code == 1 and "unknown output type '.ply'" in result.output


def test_check_reports_the_brief_and_strict_fails_on_a_violation():
    result = CliRunner().invoke(main, ["check", "WD2", "--strict"])
    assert result.exit_code == 0 and "31.5% voids, meets the competition brief" in result.output
    result = CliRunner().invoke(main, ["check", "perforated_wall", "--strict"])
    assert result.exit_code == 1 and "breaks the brief: 4 lintels, not 1" in result.output


def test_check_reads_vrml_in_millimetres(tmp_path):
    from test_geometry_io import TWO_BOXES

    path = tmp_path / "boxes.wrl"
    path.write_text(TWO_BOXES)
    result = CliRunner().invoke(main, ["check", str(path), "--unit", "mm"])
    assert result.exit_code == 0, result.output
    assert "blocks          3 (2 movable, 1 fixed)" in result.output and "mass            0.00864 kg" in result.output


@pytest.mark.parametrize("target", ["WD1", "WD1.toml"])
def test_unit_on_a_target_in_metres_is_refused_not_ignored(target):
    """--unit scales imported geometry only: on a built-in wall or a model file it would be
    silently ignored, so it is refused (the model's coordinates are metres)."""
    from drydem.masonry import designs

    if target.endswith(".toml"):
        target = str(designs.find("WD1"))
    result = CliRunner().invoke(main, ["check", target, "--unit", "mm"])
    assert result.exit_code == 1 and "--unit mm applies to imported geometry" in result.output, result.output
    assert CliRunner().invoke(main, ["check", target, "--unit", "m"]).exit_code == 0
    broken = CliRunner().invoke(main, ["check", "no_such_model.toml", "--unit", "mm"])  # said before any loading
    assert broken.exit_code == 1 and "no_such_model.toml: --unit mm applies to imported geometry" in broken.output


def test_save_every_without_vtk_is_refused_not_ignored(tmp_path):
    result = CliRunner().invoke(main, ["tilt", "WD1", "--save-every", "3", "--out", str(tmp_path / "run")])
    assert result.exit_code == 1 and "--save-every 3 thins the VTK series: it needs --vtk or --video" in result.output, result.output
    assert not (tmp_path / "run").exists()


def test_an_unknown_target_lists_the_built_in_walls():
    result = CliRunner().invoke(main, ["check", "WD9"])
    assert result.exit_code == 1 and "not a built-in wall (WD1, WD2" in result.output


@pytest.mark.slow
def test_tilt_on_a_built_in_design_end_to_end(tmp_path):
    import json

    # WD5, slender piers: the paper's 3DEC model collapses at 8.1 deg with kn = 3e7 (Table 3),
    # the reconstruction at 5.9 deg (0.1 deg steps, README); 2-degree steps here for speed
    out = tmp_path / "wd5"
    result = CliRunner().invoke(main, ["tilt", "WD5", "--increment", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stable_under_gravity"] and summary["collapse_angle_deg"] == 4.0
    assert summary["monitored_block"] == "c26b3" and summary["wall_height_m"] == pytest.approx(0.1485)
    assert all((out / name).is_file() for name in ("pushover.csv", "pushover.png", "mechanism.png", "checkpoint.npz"))


def test_limit_writes_its_summary_and_mechanism(tmp_path):
    import json

    out = tmp_path / "la"
    result = CliRunner().invoke(main, ["limit", "WD2", "--non-associative", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "LA-NA load multiplier" in result.output and "(converged)" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["method"] == "non-associative" and "Optimal" in summary["solver_status"]
    assert summary["collapse_angle_deg"] == pytest.approx(math.degrees(math.atan(summary["load_multiplier"])))
    assert (out / "mechanism.png").stat().st_size > 10_000


def test_limit_exits_1_when_the_non_associative_iteration_does_not_converge(tmp_path):
    """Found by a hunt: a "NOT converged" LA-NA printed its last iterate as the collapse angle
    and exited 0. A block sliding at mu = 1e-6 in 3D: Clarabel's duality gap (1e-9) is 1e-3 of
    lambda there, which never settles to 1e-4. The results are written (summary.json: converged
    false) and the command exits 1, as a tilt without equilibrium does."""
    import json

    model = tmp_path / "block.toml"
    model.write_text('[joint]\nkn = 1e8\nks = 1e8\nfriction = 0.6\n[contacts]\npoints_per_length = 2\n'
                     '[[block]]\nname = "base"\nfixed = true\nbox = { min = [-0.5, -0.5, -0.1], max = [0.5, 0.5, 0.0] }\n'
                     '[[block]]\nname = "b"\nbox = { min = [-0.1, -0.1, 0.0], max = [0.1, 0.1, 0.8] }\n')
    out = tmp_path / "la"
    result = CliRunner().invoke(main, ["limit", str(model), "--non-associative", "--friction", "1e-6", "--out", str(out)])
    assert result.exit_code == 1, result.output
    assert "(NOT converged (last iterate reported))" in result.output
    assert "the non-associative iteration did not converge within 100 iterations" in result.output
    assert json.loads((out / "summary.json").read_text())["converged"] is False


def _raise(exc):
    def raising(*args, **kwargs):
        raise exc
    return raising


def _system_error_from_an_interrupt():
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt:
        try:
            raise SystemError("<function _numba_unpickle> returned a result with an exception set")
        except SystemError as exc:
            return exc


@pytest.mark.parametrize("raised, code", [
    (KeyboardInterrupt(), 130),  # click's standalone mode said "Aborted!" and exited 1
    (_system_error_from_an_interrupt(), 130),  # numba loading a kernel when Ctrl-C came: a traceback
])
def test_the_drydem_program_exits_130_on_a_ctrl_c_no_command_has_taken_over(monkeypatch, capsys, raised, code):
    """Found by a hunt: Ctrl-C while the target was read (before a command's own handler)."""
    import drydem.cli.tilting
    from drydem.cli import console

    monkeypatch.setattr(drydem.cli.tilting, "resolve_target", _raise(raised))
    monkeypatch.setattr(sys, "argv", ["drydem", "tilt", "WD3"])
    with pytest.raises(SystemExit) as ended:
        console()
    assert ended.value.code == code and "interrupted (SIGINT)" in capsys.readouterr().err


def test_a_sigterm_that_escapes_a_command_is_named_sigterm(monkeypatch, capsys):
    """Found by a hunt: a SIGTERM whose KeyboardInterrupt reached numba loading a kernel (a
    SystemError, as the previous test makes it) was reported as "interrupted (SIGINT)", 130."""
    import os
    import signal
    import time

    import drydem.cli.tilting
    from drydem.cli import console
    from drydem.cli.common import signals_interrupt

    def loading_a_kernel(*args, **kwargs):
        with signals_interrupt():
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5.0)
            except KeyboardInterrupt as exc:
                raise SystemError("numba: error in a kernel's loading") from exc

    monkeypatch.setattr(drydem.cli.tilting, "resolve_target", loading_a_kernel)
    monkeypatch.setattr(sys, "argv", ["drydem", "tilt", "WD3"])
    with pytest.raises(SystemExit) as ended:
        console()
    assert ended.value.code == 143 and "interrupted (SIGTERM)" in capsys.readouterr().err


def test_the_drydem_program_lets_other_system_errors_through(monkeypatch):
    import drydem.cli.tilting
    from drydem.cli import console

    monkeypatch.setattr(drydem.cli.tilting, "resolve_target", _raise(SystemError("a bug")))
    monkeypatch.setattr(sys, "argv", ["drydem", "tilt", "WD3"])
    with pytest.raises(SystemError, match="a bug"):
        console()


def test_the_drydem_program_exits_as_click_does_on_usage_errors_and_help(monkeypatch, capsys):
    from drydem.cli import console

    for argv, code in ((["drydem", "tilt", "WD3", "--increment", "0"], 2), (["drydem", "nosuch"], 2), (["drydem", "--help"], None)):
        monkeypatch.setattr(sys, "argv", argv)
        try:
            console()
            ended = None
        except SystemExit as exc:
            ended = exc.code
        assert ended in ((code,) if code else (None, 0)), (argv, ended)
    assert "Invalid value for '--increment'" in capsys.readouterr().err


def test_check_settle_notes_joints_closed_by_a_large_fraction_of_a_block(tmp_path):
    """Found by a hunt: five 0.2 m blocks on kn = 1e5 Pa/m "converged" 19 % below the sum of
    W / (kn A), the bottom joint closed most of a block's thickness, without a word. On kn = 1e9
    (closures of micrometres) nothing is said."""
    blocks = "".join(f'[[block]]\nname = "b{k}"\nbox = {{ min = [0, -0.1, {0.2 * k:g}], max = [1.0, 0.1, {0.2 * (k + 1):g}] }}\n'
                     for k in range(5))
    for kn, noted in (("1e5", True), ("1e9", False)):
        path = tmp_path / f"stack{kn}.toml"
        path.write_text(f'[joint]\nkn = {kn}\nks = {kn}\n[[block]]\nname = "base"\nfixed = true\n'
                        f'box = {{ min = [-1, -1, -0.2], max = [2, 1, 0] }}\n{blocks}')
        result = CliRunner().invoke(main, ["check", str(path), "--settle"])
        assert result.exit_code == 0, result.output
        assert ("note: a joint of 'b0' closes by" in result.output and "of the block's thickness" in result.output) == noted


@pytest.mark.parametrize("turn_deg, noted", [(44.0, True), (0.0, False)])
def test_check_settle_notes_a_block_that_toppled_under_its_own_weight(tmp_path, turn_deg, noted):
    """Found by a hunt: a 0.1 m cube drawn on its edge, turned 44 deg about y, fell onto its face
    (its centre of mass is outside the edge), and check --settle called the 49.5 mm move a
    settlement of 20.7 mm. The same cube drawn on its face settles by micrometres, unnoted."""
    import numpy as np

    corners = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (-0.05, 0.05)])
    t = np.radians(turn_deg)
    turned = corners @ np.array([[np.cos(t), 0.0, -np.sin(t)], [0.0, 1.0, 0.0], [np.sin(t), 0.0, np.cos(t)]])
    turned[:, 2] -= turned[:, 2].min()
    path = tmp_path / "cube.toml"
    path.write_text('[joint]\nkn = 1e9\nks = 1e9\nfriction = 0.5\n[[block]]\nname = "base"\nfixed = true\n'
                    'box = { min = [-0.5, -0.5, -0.1], max = [0.5, 0.5, 0.0] }\n'
                    f'[[block]]\nname = "cube"\nvertices = {turned.tolist()}\n')
    result = CliRunner().invoke(main, ["check", str(path), "--settle"])
    assert result.exit_code == 0, result.output
    assert ("note: block 'cube' turned" in result.output and "the model does not stand as drawn" in result.output) == noted
