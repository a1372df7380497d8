"""The command line of the shaking-table analysis: drydem shake, its results folder
(summary.json, history.csv, history.png, the VTK series) and its refusals.

One slender block (25 x 100 mm, b/h = 1/4, in-plane) on a fixed base, kn = 1e8: a few
hundred cycles per run. The runs are shared by module-scoped fixtures (the first compiles the
dynamic kernels when the cache is cold)."""

import csv
import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.cli import PULSE_KINDS, main
from drydem.io.results import RUN_MARK
from conftest import stack_model

#: the first five columns of history.csv: a public interface
HISTORY_HEADER = ["time_s", "ground_acc_x_m_s2", "ux_m", "uz_m", "rotation_rad"]
#: what every summary.json of drydem shake holds
SUMMARY_KEYS = {
    "overturned", "overturn_rule", "fallen_blocks", "monitored_block", "max_rotation_rad", "max_displacement_m",
    "residual_displacement_m", "duration_s", "cycles", "runtime_s", "pga_m_s2", "pga_g", "motion", "contact_damping_ratio",
    "restitution", "timestep_s", "ended_by", "analysis", "model", "drydem_version",
}
#: a pulse that rocks the block without overturning it, sampled every 10 ms for 0.3 s
PULSE = ["--pulse", "one-sine", "--amplitude", "8", "--frequency", "5", "--duration", "0.3", "--output-interval", "0.01"]
#: a small record: two triangles of 2 m/s2, one each way (ends at rest only after correction)
RECORD = "time_s,acc_x_m_s2\n0,0\n0.025,2\n0.05,0\n0.075,-1\n0.1,0\n0.125,1\n0.15,0\n"


def shake(*arguments):
    result = CliRunner().invoke(main, ["shake", *map(str, arguments)])
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    return result


def history(folder):
    with (folder / "history.csv").open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(cell) for cell in row] for row in rows[1:]])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from drydem.io.model_file import save_model

    folder = tmp_path_factory.mktemp("shake_inputs")
    block = stack_model([0.1], size_xy=(0.025, 0.012), joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5),
                        supports=dd.Supports(fix_y=True), points=2)
    squat = stack_model([0.0055], supports=dd.Supports(fix_y=True), points=2)
    paths = {"block": folder / "block.toml", "squat": folder / "squat.toml", "record": folder / "record.csv",
             "bad": folder / "bad.csv", "missing": folder / "nosuch.csv", "tiny": folder / "tiny.csv", "xy": folder / "xy.csv",
             "y": folder / "y.csv"}
    save_model(block, paths["block"])
    save_model(squat, paths["squat"])
    paths["record"].write_text(RECORD)
    paths["bad"].write_text("time_s,acc_x_m_s2\n0,0\n0.1,oops\n")
    paths["tiny"].write_text("time_s,acc_x_m_s2\n0,0\n1e-300,1\n2e-300,0\n")
    paths["xy"].write_text("time_s,acc_x_m_s2,acc_y_m_s2\n0,0,0\n0.025,2,0.5\n0.05,0,0\n")
    paths["y"].write_text("time_s,acc_x_m_s2,acc_y_m_s2\n0,0,0\n0.025,0,0.5\n0.05,0,0\n")
    return paths


@pytest.fixture(scope="module")
def pulse_run(files, tmp_path_factory):
    """The pulse under the block, the contacts' damping calibrated to Housner's restitution, with the VTK series."""
    out = tmp_path_factory.mktemp("pulse") / "run"
    result = shake(files["block"], *PULSE, "--restitution", "housner", "--vtk", "--out", out)
    assert result.exit_code == 0, result.output
    return result, out


def test_the_command_offers_the_analysis_pulses():
    from drydem.analysis.shake import PULSES

    assert PULSE_KINDS == PULSES


def test_a_pulse_run_writes_summary_history_and_figure(pulse_run):
    result, out = pulse_run
    summary = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(summary)
    assert summary["overturned"] is False and summary["fallen_blocks"] == [] and summary["ended_by"] == "duration"
    assert summary["overturn_rule"] == ("a block has fallen when it turned more than 80 deg from its orientation at rest, or its "
                                        "centroid dropped more than 2 of its heights below where it rested")
    assert summary["monitored_block"] == "block0"
    assert summary["pga_m_s2"] == pytest.approx(8.0) and summary["pga_g"] == pytest.approx(8.0 / dd.G)
    assert summary["motion"] | {"name": None} == {"name": None, "duration_s": 0.2, "samples": 201, "scale": 1.0,
                                                  "baseline_corrected": False, "peaks_m_s2": [8.0, 0.0, 0.0]}
    # Housner's restitution of a block with b/h = 1/4, and the damping ratio calibrated to it
    assert summary["restitution"] == pytest.approx(1.0 - 1.5 * math.sin(math.atan(0.25)) ** 2)
    assert summary["analysis"]["restitution"] == "housner" and summary["contact_damping_ratio"] > 0.0
    assert summary["analysis"]["motion"] == summary["motion"]["name"] and summary["analysis"]["duration_s"] == 0.3
    assert summary["model"]["joint"]["kn"] == 1e8 and summary["timestep_s"] > 0 and summary["cycles"] > 0

    header, rows = history(out)
    assert header[:5] == HISTORY_HEADER
    time_s, ground, ux, uz, rotation = rows[:, :5].T
    # a row at rest, then one every output interval (to the timestep) up to the duration
    assert time_s[0] == 0.0 and len(rows) == 31 == summary["history_rows"]
    np.testing.assert_allclose(time_s, 0.01 * np.arange(31), atol=summary["timestep_s"])
    assert np.abs(ground).max() <= 8.0 and np.abs(ground).max() > 7.0
    assert summary["max_rotation_rad"] == pytest.approx(np.abs(rotation).max(), rel=1e-6)
    assert summary["max_displacement_m"] == pytest.approx(np.hypot(ux, rows[:, 7]).max(), rel=1e-6)
    assert summary["residual_displacement_m"] == pytest.approx(abs(ux[-1]), rel=1e-6)
    assert 0.05 < summary["max_rotation_rad"] < 1.4  # it rocked, and did not overturn
    assert (out / "history.png").stat().st_size > 10_000

    for printed in ("overturned      no", "rad (", "deg)", "mm", "PGA 8 m/s2 (0.815 g)", "calibrated to the restitution 0.9118, Housner's",
                    "cycles", str(out)):
        assert printed in result.output


def test_the_vtk_series_is_in_model_time(pulse_run):
    import meshio

    from drydem.report.animation import series_frames

    _, out = pulse_run
    with (out / "vtk" / "frames.csv").open() as f:
        frames = list(csv.DictReader(f))
    _, rows = history(out)
    assert list(frames[0]) == ["frame", "time_s", "ux_m", "load_direction"] and len(frames) == len(rows)  # the first at rest, t = 0
    assert {f["load_direction"] for f in frames} == {"x"}  # the pulse shakes along x
    np.testing.assert_allclose([float(f["time_s"]) for f in frames], rows[:, 0], rtol=1e-8)
    np.testing.assert_allclose([float(f["ux_m"]) for f in frames], rows[:, 2], rtol=1e-6, atol=1e-12)
    for series in ("blocks", "contacts"):
        assert (out / "vtk" / f"{series}.pvd").read_text().count("<DataSet") == len(frames)
    assert f'timestep="{frames[-1]["time_s"]}"' in (out / "vtk" / "blocks.pvd").read_text()
    mesh = meshio.read(out / "vtk" / f"blocks_{len(frames) - 1:04d}.vtu")
    assert sum(len(c.data) for c in mesh.cells) == 2
    captions = [frame.caption for frame in series_frames(out / "vtk")]
    assert captions[1].startswith("t = 0.010 s, monitored ux") and len(captions) == len(frames)


def test_a_csv_record_is_scaled_and_baseline_corrected(files, tmp_path):
    from drydem.analysis.shake import read_motion

    out = tmp_path / "record"
    result = shake(files["block"], "--motion", files["record"], "--scale", "2", "--baseline", "--damping-ratio", "0.05",
                   "--duration", "0.2", "--output-interval", "0.02", "--out", out)
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    analysed = read_motion(files["record"]).baseline_corrected().scaled(2.0)
    assert summary["motion"]["scale"] == 2.0 and summary["motion"]["baseline_corrected"] is True
    assert summary["motion"]["name"] == "record.csv, baseline-corrected x 2" and summary["motion"]["samples"] == 7
    assert summary["pga_m_s2"] == pytest.approx(analysed.pga_m_s2) and summary["pga_m_s2"] != pytest.approx(4.0)
    assert summary["contact_damping_ratio"] == 0.05 and summary["restitution"] is None
    header, rows = history(out)
    assert header[:5] == HISTORY_HEADER and len(rows) == 11
    assert np.abs(rows[:, 1]).max() <= analysed.pga_m_s2 * (1 + 1e-9)
    assert "contact damping ratio 0.05 (given)" in result.output

    # without the correction, the record is taken as it is (a pulse is never corrected)
    plain = shake(files["block"], "--motion", files["record"], "--no-baseline", "--damping-ratio", "0.05", "--duration", "0.04",
                  "--output-interval", "0.02", "--out", tmp_path / "plain")
    assert plain.exit_code == 0, plain.output
    summary = json.loads((tmp_path / "plain" / "summary.json").read_text())
    assert summary["motion"]["baseline_corrected"] is False and summary["pga_m_s2"] == 2.0


def test_an_overturning_pulse_names_the_block_and_overwrite_replaces_only_the_earlier_run(files, tmp_path):
    out = tmp_path / "over"
    out.mkdir()
    for name in (RUN_MARK, "summary.json", "history.csv", "shake.mp4", "notes.txt"):  # an earlier run's folder, and a note
        (out / name).write_text("earlier\n")
    result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "30", "--frequency", "5", "--duration", "0.3",
                   "--damping-ratio", "0.05", "--output-interval", "0.01", "--out", out, "--overwrite")
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overturned"] is True and summary["ended_by"] == "monitored block fell"
    [fallen] = summary["fallen_blocks"]
    assert fallen["block"] == "block0" and fallen["rule"] == "turned more than 80 deg"
    assert summary["duration_s"] == pytest.approx(fallen["time_s"]) and fallen["time_s"] < 0.3
    assert summary["max_rotation_rad"] > math.radians(80)
    assert "overturned      yes: 1 block fell: 'block0' at" in result.output and "the monitored block 'block0' fell" in result.output
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARK, "history.csv", "history.png", "notes.txt", "summary.json"]
    assert (out / "notes.txt").read_text() == "earlier\n"


@pytest.mark.parametrize("arguments, message", [
    ([], "no ground motion: give --motion FILE"),
    (["--motion", "{record}", *PULSE], "--motion FILE (a record) or --pulse KIND, not both"),
    (["--motion", "{missing}"], "nosuch.csv: no such file"),
    (["--motion", "{bad}"], "bad.csv: line 3: acc_x_m_s2: 'oops' is not a number"),
    ([*PULSE, "--restitution", "1.5"], "--restitution = 1.5: must be a number in (0, 1]"),
    ([*PULSE, "--restitution", "foo"], "'--restitution': 'foo' is neither a number nor 'housner'"),
    ([*PULSE, "--damping-ratio", "0.1", "--restitution", "0.5"], "--damping-ratio and --restitution both given"),
    ([*PULSE, "--duration", "0"], "--duration = 0.0: must be a number in (0, 1e+06] s"),
    ([*PULSE, "--duration", "-1"], "--duration = -1.0: must be"),
    ([*PULSE, "--duration", "nan"], "--duration = nan: must be"),
    ([*PULSE, "--output-interval", "0", "--rayleigh-mass", "-1"], "--output-interval = 0.0: must be a number in (0, 1000] s; --rayleigh-mass"),
    (["--motion", "{record}", "--scale", "nan"], "--scale = nan: must be a finite number other than 0"),
    (["--motion", "{record}", "--scale", "0"], "--scale = 0.0: must be a finite number other than 0 (0 is a table at rest, no motion"),
    (["--pulse", "one-sine", "--amplitude", "0", "--frequency", "5"], "--amplitude = 0.0: must be a finite number other than 0"),
    # found by a hunt: a subnormal amplitude or scale ran, "PGA 4.941e-324 m/s2 (0 g)"
    (["--pulse", "one-sine", "--amplitude", "5e-324", "--frequency", "5"],
     "its peak acceleration, 4.94e-324 m/s2, is below 1e-09 m/s2"),
    (["--motion", "{record}", "--scale", "1e-300"], "record.csv, baseline-corrected x 1e-300: its peak acceleration"),
    (["--motion", "{tiny}"], "tiny.csv: line 3: time_s = 1e-300 is 1e-300 s after 0 (line 2): a record's samples must be at least 1e-06 s apart"),
    # the block is in-plane (fix_y): a motion along y would move nothing
    ([*PULSE, "--direction", "y"], "--direction y shakes the model along y (peak 8 m/s2), but its blocks are held in y ([supports] fix_y = true)"),
    (["--motion", "{y}"], "y.csv: its column acc_y_m_s2 shakes the model along y (peak 0.25 m/s2), but its blocks are held in y"),
    (["--motion", "{record}", "--amplitude", "3"], "--amplitude applies to a --pulse only"),
    (["--motion", "{record}", "--direction", "y"], "record.csv: direction = 'y' applies to a single-component .AT2 record"),
    (["--pulse", "sine", "--amplitude", "3"], "--pulse sine needs --frequency F (Hz)"),
    (["--pulse", "sine", "--amplitude", "nan", "--frequency", "-2"], "--amplitude = nan: must be a finite number other than 0 (0 is a "
                                                                     "table at rest, no motion; a negative one flips the motion); --frequency"),
    (["--pulse", "ricker", "--amplitude", "3", "--frequency", "2", "--cycles", "2"], "--cycles 2: a ricker pulse is one period"),
    ([*PULSE, "--baseline"], "--baseline says whether a --motion record is baseline-corrected; a pulse is analytic"),
    ([*PULSE, "--no-baseline"], "--no-baseline says whether a --motion record is baseline-corrected; a pulse is analytic"),
    ([*PULSE, "--kn", "-1"], "Invalid value for '--kn': -1.0: must be a number in [1e+04, 1e+15] Pa/m ([joint] kn)"),
    ([*PULSE, "--density", "true"], "Invalid value for '--density': 'true' is not a valid float"),
    ([*PULSE, "--monitor", "nosuch"], "no block named 'nosuch'"),
])
def test_bad_input_is_refused_with_its_option_or_file_and_no_traceback(files, tmp_path, arguments, message):
    out = tmp_path / "never"
    result = shake(files["block"], *[a.format(**files) for a in arguments], "--out", out)
    assert result.exit_code != 0 and message in result.output, result.output
    assert not out.exists()  # refused before anything was written


@pytest.mark.parametrize("name, text, message", [
    # as --scale 0 and --amplitude 0 are refused (the finding: it ran, and reported a PGA of 0)
    ("zeros.csv", "time_s,acc_x_m_s2\n0,0\n0.01,0\n0.02,0\n", "every acceleration of the record is 0: a table at rest, no motion"),
    ("subnormal.csv", "time_s,acc_x_m_s2\n0,0\n0.01,1e-320\n0.02,0\n",
     "every acceleration of the record is below 1e-09 m/s2: a table at rest"),
    # float() reads 1_0 as 10
    ("underscore.csv", "time_s,acc_x_m_s2\n0,0\n0.01,1_0\n0.02,0\n", "line 3: acc_x_m_s2: '1_0' is not a number"),
    # its message named bigdur.csv alone
    ("bigdur.csv", "time_s,acc_x_m_s2\n0,0\n0.01,1\n999999.0,0\n", "a baseline correction needs samples spread over the record"),
], ids=["all-zero", "subnormal", "underscore", "baseline"])
def test_a_record_that_is_no_motion_is_refused_naming_the_file_as_given(files, tmp_path, monkeypatch, name, text, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mo").mkdir()
    (tmp_path / "mo" / name).write_text(text)
    result = shake(files["block"], "--motion", f"mo/{name}", "--damping-ratio", "0.05", "--duration", "0.05", "--out", "never")
    assert result.exit_code == 1 and f"Error: mo/{name}: {message}" in result.output, result.output
    assert not (tmp_path / "never").exists()


def test_a_record_with_a_component_along_a_held_axis_is_run_along_the_others_with_a_note(files, tmp_path):
    """A 2- or 3-component record on an in-plane model: its y component moves nothing (the
    supports take it), said in a note; its x component is analysed."""
    result = shake(files["block"], "--motion", files["xy"], "--damping-ratio", "0.05", "--out", tmp_path / "xy")
    assert result.exit_code == 0, result.output
    assert (f"note: {files['xy']}: its column acc_y_m_s2 (peak 0.25 m/s2) moves nothing: the blocks are held in y "
            "([supports] fix_y = true); the motion along x is analysed") in result.output


def test_an_output_interval_shorter_than_the_timestep_is_refused_at_the_run_start(files, tmp_path):
    """Found by a hunt: --output-interval 1e-12 was taken, the history written every cycle and
    summary.json recording 1e-12 s."""
    out = tmp_path / "fine"
    result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "2", "--frequency", "4", "--damping-ratio", "0.05",
                   "--output-interval", "1e-12", "--out", out)
    assert result.exit_code == 1
    assert "output_interval_s = 1e-12 s (--output-interval) is shorter than the timestep" in result.output
    assert "the history has a row at most every cycle; give at least" in result.output and not (out / "summary.json").exists()


def test_damping_that_shortens_the_timestep_tenfold_is_said_before_the_shaking(files, tmp_path):
    """Found by a hunt: --rayleigh-stiffness 1 ran 10 million cycles without a word. Rayleigh's
    beta adds beta / dt_crit to the damping ratio at the highest frequency, and the stable step
    is (2 / omega) (sqrt(1 + z^2) - z) (Belytschko & Hughes 1983): beta = 0.03 s overdamps the
    block's joints (z ~ 30) and takes ~60 times more cycles; 0.001 s (z ~ 1) says nothing."""
    notes = {}
    for beta in ("0.03", "0.001"):
        result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "2", "--frequency", "4", "--damping-ratio", "0.05",
                       "--rayleigh-stiffness", beta, "--duration", "0.05", "--out", tmp_path / beta)
        assert result.exit_code == 0, result.output
        notes[beta] = [line for line in result.output.replace("\r", "\n").splitlines() if "shortens the timestep" in line]
    assert notes["0.001"] == []
    [note] = notes["0.03"]
    fold = float(note.split("shortens the timestep ")[1].split("-fold")[0])
    assert 10 < fold < 1000 and "rayleigh_stiffness_s 0.03 s" in note, note
    assert json.loads((tmp_path / "0.03" / "summary.json").read_text())["cycles"] > 1000


def test_a_record_sampled_finer_than_the_timestep_is_run_with_a_note(files, tmp_path):
    # found by a hunt: the aliasing of such a record went unsaid
    record = tmp_path / "fine.csv"
    times = np.arange(20001) * 2.5e-6  # 0.05 s, sampled far finer than the block's timestep
    record.write_text("time_s,acc_x_m_s2\n" + "".join(f"{t:.17g},{math.sin(2 * math.pi * 20 * t):.17g}\n" for t in times))
    result = shake(files["block"], "--motion", record, "--no-baseline", "--damping-ratio", "0.05", "--out", tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert "note: " in result.output and "is sampled every 2.5e-06 s at its finest, finer than the timestep" in result.output


def test_a_vibration_faster_than_the_cycles_barely_changes_the_response(files, tmp_path):
    """Found by a hunt: a record read at the cycles' times turned a vibration near the cycle
    rate into slow motion of its full acceleration. A 20 Hz sine of 1 m/s2 rocks the block
    (timestep 6.87e-4 s), and a vibration of 6 m/s2 at 0.998 times the cycle rate (aliased to
    2.9 Hz) is added: read at the cycles' times it took the block to 14 mm against 0.33 mm
    (2026-11-27); each cycle now takes the record's mean over its step, and the vibration,
    whose own velocity amplitude is 6 / (2 pi 1453 Hz) = 0.66 mm/s, changes the block's
    largest displacement by 2 % (measured)."""
    times = np.arange(50001) * 1e-5  # 0.5 s, 69 samples a timestep
    responses = {}
    for name, vibration in (("smooth", 0.0), ("vibrating", 6.0)):
        record = tmp_path / f"{name}.csv"
        record.write_text("time_s,acc_x_m_s2\n" + "".join(
            f"{t:.17g},{math.sin(2 * math.pi * 20 * t) + vibration * math.sin(2 * math.pi * 0.998 / 6.868372680953528e-4 * t):.17g}\n"
            for t in times))
        result = shake(files["block"], "--motion", record, "--no-baseline", "--damping-ratio", "0.05", "--out", tmp_path / name)
        assert result.exit_code == 0, result.output
        responses[name] = json.loads((tmp_path / name / "summary.json").read_text())
    assert responses["smooth"]["timestep_s"] == pytest.approx(6.868372680953528e-4, rel=1e-9)  # the vibration's frequency is set by it
    assert responses["vibrating"]["max_displacement_m"] == pytest.approx(responses["smooth"]["max_displacement_m"], rel=0.05)


def test_a_duration_of_fewer_than_twenty_timesteps_is_refused_at_the_run_start(files, tmp_path):
    """Found by a hunt: --duration 1e-300 ran no cycle and reported "no block fell" under a PGA
    the table never reached."""
    out = tmp_path / "instant"
    result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "2", "--frequency", "4", "--damping-ratio", "0.05",
                   "--duration", "1e-300", "--out", out)
    assert result.exit_code == 1 and not (out / "summary.json").exists()
    assert "duration_s = 1e-300 s (--duration) spans fewer than 20 timesteps" in result.output, result.output


def test_save_every_without_a_vtk_series_is_refused_as_by_tilt(files, tmp_path):
    # found by a hunt: drydem shake took it and ignored it, where drydem tilt refuses it
    out = tmp_path / "run"
    result = shake(files["block"], *PULSE, "--damping-ratio", "0.3", "--save-every", "3", "--out", out)
    assert result.exit_code == 1 and "--save-every 3 thins the VTK series: it needs --vtk or --video" in result.output
    assert not out.exists()


def test_a_pulse_the_timestep_cannot_follow_is_refused_at_the_run_start(files, tmp_path):
    """The finding: --frequency 1e12 ran and reported. The timestep is the model's (known once
    it has settled and its damping is set): the period must span 20 of them."""
    out = tmp_path / "fast"
    result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "2", "--frequency", "1e12", "--damping-ratio", "0.05",
                   "--vtk", "--out", out)
    assert result.exit_code == 1
    assert "one-sine pulse 2 m/s2, 1e+12 Hz along x: its period, 1e-12 s, spans" in result.output
    assert "the analysis follows a motion only over at least 20 timesteps: give a frequency of at most" in result.output
    assert "(--frequency;" in result.output and not (out / "summary.json").exists()
    # nothing of the refused run is left (a header-only history.csv made the next run on the
    # same --out ask for --overwrite), so the same --out takes the corrected command
    assert sorted(p.name for p in out.iterdir()) == []
    result = shake(files["block"], "--pulse", "one-sine", "--amplitude", "2", "--frequency", "5", "--duration", "0.05",
                   "--damping-ratio", "0.05", "--vtk", "--out", out)
    assert result.exit_code == 0, result.output


def test_a_record_starting_late_is_run_from_zero_with_a_note(files, tmp_path):
    late = tmp_path / "late.csv"
    late.write_text("time_s,acc_x_m_s2\n" + "".join(f"{100 + 0.025 * k:.3f},{a}\n" for k, a in enumerate([0, 2, 0, -1, 0, 1, 0])))
    result = shake(files["block"], "--motion", late, "--damping-ratio", "0.05", "--output-interval", "0.02", "--out", tmp_path / "late")
    assert result.exit_code == 0, result.output
    assert f"note: {late}: the record starts at t = 100 s; it was shifted by 100 s to start at 0" in result.stderr
    assert json.loads((tmp_path / "late" / "summary.json").read_text())["motion"]["duration_s"] == pytest.approx(0.15)


def test_housners_restitution_of_a_squat_block_is_refused_before_the_run(files, tmp_path):
    result = shake(files["squat"], *PULSE, "--restitution", "housner", "--out", tmp_path / "never")
    assert result.exit_code == 1
    assert "the monitored block 'block0' is too squat for Housner's restitution" in result.output and "--damping-ratio" in result.output


def test_an_existing_results_folder_is_kept_without_overwrite(files, tmp_path):
    out = tmp_path / "taken"
    out.mkdir()
    (out / RUN_MARK).write_text("a drydem run's folder")
    (out / "summary.json").write_text("earlier\n")
    result = shake(files["block"], *PULSE, "--out", out)
    assert result.exit_code == 1 and "already holds another run (summary.json); pass --overwrite" in result.output
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARK, "summary.json"] and (out / "summary.json").read_text() == "earlier\n"


def test_an_interrupted_shake_keeps_the_rows_written_so_far(files, tmp_path):
    # a real process and a real Ctrl-C
    from processes import interrupted_drydem

    out = tmp_path / "run"
    path = out / "history.csv"
    arguments = ["shake", str(files["block"]), "--pulse", "sine", "--amplitude", "0.5", "--frequency", "5", "--duration", "1000",
                 "--output-interval", "0.01", "--damping-ratio", "0.05", "--out", str(out)]
    returncode, err = interrupted_drydem(arguments, path, 4)
    assert returncode == 130, err[-500:]
    assert "interrupted (SIGINT)" in err and "history.csv" in err and "Traceback" not in err
    assert not (out / "summary.json").exists()
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0][:5] == HISTORY_HEADER and len(rows) >= 4
    assert all(len(row) == len(rows[0]) for row in rows) and [float(x) for x in rows[1]] == [0.0] * len(rows[0])
    times = [float(row[0]) for row in rows[1:]]
    assert times == sorted(times) and times[1] == pytest.approx(0.01, abs=1e-3)
