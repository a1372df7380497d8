"""The ground motion of ``drydem shake``: CSV and PEER .AT2 records, analytic pulses, baseline
correction, scaling and the acceleration handed to each explicit cycle."""

import math
from pathlib import Path

import numpy as np
import pytest

from drydem.analysis.shake.motion import PULSES, GroundMotion, pulse, read_at2, read_csv_motion, read_motion
from drydem.errors import ModelError
from drydem.model.parameters import G

#: a synthetic record in the NGA-West2 layout: 7 values in g, 5 to a line, DT = 0.005 s
AT2_VALUES_G = (0.0063, 0.00364, 0.00099, -0.0018, 0.0107, -0.02, 0.5)
AT2_BODY = ("  .6300000E-02  .3640000E-02  .9900000E-03 -.1800000E-02  .1070000E-01\n"
            " -.2000000E-01  .5000000E+00\n")
AT2_NEW = ("PEER NGA STRONG MOTION DATABASE RECORD\n"
           "Synthetic event, 1/1/2000, Test station, 090\n"
           "ACCELERATION TIME SERIES IN UNITS OF G\n"
           "NPTS=     7, DT=   .0050 SEC\n") + AT2_BODY
#: the same record in the older NGA layout (NPTS and DT first, then their names)
AT2_OLD = ("PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.\n"
           "SYNTHETIC 1/1/00 0000, TEST STATION, 090\n"
           "ACCELERATION TIME HISTORY IN UNITS OF G\n"
           "    7   0.0050    NPTS, DT\n") + AT2_BODY


def written(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


def refused(call, *messages: str):
    """``call()`` must raise a ModelError saying each of ``messages``."""
    with pytest.raises(ModelError) as error:
        call()
    for message in messages:
        assert message in str(error.value)


def motion(time_s, acceleration_x_m_s2, acceleration_y_m_s2=0.0) -> GroundMotion:
    acceleration = np.zeros((len(time_s), 3))
    acceleration[:, 0], acceleration[:, 1] = acceleration_x_m_s2, acceleration_y_m_s2
    return GroundMotion(np.asarray(time_s, float), acceleration, "test record")


# ---------------------------------------------------------------- CSV


def test_a_csv_motion_reads_back_the_numbers_written(tmp_path):
    rng = np.random.default_rng(1)
    time = np.concatenate([[0.0], np.cumsum(rng.uniform(0.001, 0.02, 49))])  # strictly increasing from 0
    acceleration = rng.normal(0.0, 2.0, (50, 3))
    rows = "".join(",".join(repr(float(x)) for x in (t, *a)) + "\n" for t, a in zip(time, acceleration))
    path = written(tmp_path, "table.csv", "time_s,acc_x_m_s2,acc_y_m_s2,acc_z_m_s2\n" + rows)
    read = read_csv_motion(path)
    np.testing.assert_array_equal(read.time_s, time)  # repr writes a float exactly
    np.testing.assert_array_equal(read.acceleration_m_s2, acceleration)
    assert read.name == "table.csv"
    assert read_motion(path).acceleration_m_s2.shape == (50, 3)


def test_csv_columns_come_in_any_order_and_a_missing_component_is_zero(tmp_path):
    path = written(tmp_path, "two.csv", " acc_y_m_s2 , time_s, acc_x_m_s2\n0.5,0,1\n-0.5,0.01,2\n")
    read = read_csv_motion(path)
    np.testing.assert_array_equal(read.acceleration_m_s2, [[1.0, 0.5, 0.0], [2.0, -0.5, 0.0]])
    np.testing.assert_array_equal(read.time_s, [0.0, 0.01])


def test_a_csv_from_a_spreadsheet_with_bom_crlf_and_blank_lines_reads(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbftime_s,acc_x_m_s2\r\n0,1\r\n\r\n0.1,2\r\n\r\n")
    np.testing.assert_array_equal(read_motion(path).acceleration_m_s2[:, 0], [1.0, 2.0])


def test_a_csv_record_starting_after_zero_is_shifted_to_start_at_zero_with_a_note(tmp_path):
    path = written(tmp_path, "late.csv", "time_s,acc_x_m_s2\n2.0,1\n2.5,2\n3.0,3\n")
    read = read_csv_motion(path)
    np.testing.assert_array_equal(read.time_s, [0.0, 0.5, 1.0])  # 2.0, 2.5, 3.0 less 2.0: exact
    assert read.duration_s == 1.0
    assert read.notes == (f"{path}: the record starts at t = 2 s; it was shifted by 2 s to start at 0",)
    # the note goes with the motion through the correction and the scaling, the correction's
    # own after it (this record, 1 to 3 m/s2 one way, ends far from where it started); a record
    # from 0 has none
    kept, corrected = read.baseline_corrected().scaled(2.0).notes
    assert kept == read.notes[0] and "the baseline correction shifts the x acceleration" in corrected
    assert read_csv_motion(written(tmp_path, "zero.csv", "time_s,acc_x_m_s2\n0,1\n0.5,2\n")).notes == ()


@pytest.mark.parametrize("name, text, message", [
    ("notime.csv", "acc_x_m_s2,acc_y_m_s2\n1,2\n3,4\n", "line 1: missing columns 'time_s'"),
    ("nox.csv", "time_s,acc_y_m_s2\n0,2\n1,4\n", "line 1: missing columns 'acc_x_m_s2'"),
    ("extra.csv", "time_s,acc_x_m_s2,acc_w_m_s2,notes\n0,1,2,a\n1,3,4,b\n", "line 1: unknown columns 'acc_w_m_s2', 'notes'"),
    ("twice.csv", "time_s,acc_x_m_s2,acc_x_m_s2\n0,1,2\n1,3,4\n", "line 1: repeated columns 'acc_x_m_s2'"),
    ("word.csv", "time_s,acc_x_m_s2\n0,1\n0.1,one\n", "line 3: acc_x_m_s2: 'one' is not a number"),
    ("nan.csv", "time_s,acc_x_m_s2\n0,1\n0.1,nan\n", "line 3: acc_x_m_s2: 'nan' is not a finite number"),
    ("inf.csv", "time_s,acc_x_m_s2\n0,1\ninf,2\n", "line 3: time_s: 'inf' is not a finite number"),
    ("short.csv", "time_s,acc_x_m_s2\n0,1\n0.1\n", "line 3: 1 values; the header has 2 columns"),
    ("back.csv", "time_s,acc_x_m_s2\n0,1\n0.2,2\n0.1,3\n", "line 4: time_s = 0.1 is not after 0.2 (line 3): times must increase strictly"),
    ("same.csv", "time_s,acc_x_m_s2\n0,1\n0,2\n", "line 3: time_s = 0 is not after 0 (line 2)"),
    ("negative.csv", "time_s,acc_x_m_s2\n-0.1,1\n0,2\n", "line 2: time_s = -0.1: times must be >= 0 s"),
    # the finding: times 1e-300 apart made the baseline's linear system singular (a traceback)
    ("tiny_dt.csv", "time_s,acc_x_m_s2\n0,0\n1e-300,1\n2e-300,0\n",
     "line 3: time_s = 1e-300 is 1e-300 s after 0 (line 2): a record's samples must be at least 1e-06 s apart"),
    ("close.csv", "time_s,acc_x_m_s2\n0,0\n0.01,1\n0.0100005,0\n", "line 4: time_s = 0.0100005 is 5e-07 s after 0.01 (line 3)"),
    ("long.csv", "time_s,acc_x_m_s2\n0,0\n1e30,0\n", "line 3: time_s = 1e+30: the record lasts 1e+30 s; at most 1e+06 s"),
    ("one.csv", "time_s,acc_x_m_s2\n0,1\n", "1 rows of samples; a motion needs at least 2"),
    ("header.csv", "time_s,acc_x_m_s2\n", "0 rows of samples; a motion needs at least 2"),
    ("empty.csv", "", "empty: no header line; expected the columns time_s, acc_x_m_s2"),
    # found by a hunt: the csv module's limit on a field (131,072 characters) ended in a traceback
    ("field.csv", "time_s,acc_x_m_s2\n0,0\n0.01," + "1" * 200_000 + "\n", "line 3: not a CSV row (field larger than field limit"),
])
def test_a_bad_csv_motion_is_refused_naming_the_file_and_the_problem(tmp_path, name, text, message):
    path = written(tmp_path, name, text)
    refused(lambda: read_motion(path), f"{path}: ", message)


@pytest.mark.parametrize("start_s", [0.0, 1.0, 1000.0])
def test_a_record_sampled_at_exactly_one_megahertz_is_read(tmp_path, start_s):
    """1 us steps, the finest allowed (MIN_SAMPLE_STEP_S): 1.000001 - 1.0 rounds to 9.99999999e-07
    s, which is no step below the rule (it was refused, its message saying 1e-06 < 1e-06)."""
    times = [start_s + k * 1e-6 for k in range(4)]
    path = written(tmp_path, "mhz.csv", "time_s,acc_x_m_s2\n" + "".join(f"{t!r},{k % 2}\n" for k, t in enumerate(times)))
    assert len(read_csv_motion(path).time_s) == 4


def test_a_binary_file_named_csv_is_refused(tmp_path):
    path = tmp_path / "binary.csv"
    path.write_bytes(b"\xff\xfe\x00\x01")
    refused(lambda: read_motion(path), f"{path}: not a text file")


@pytest.mark.parametrize("path", [None, 5])
def test_a_motion_path_that_is_no_path_is_refused(path):
    """Found by a hunt: None and 5 were TypeErrors of pathlib's."""
    refused(lambda: read_motion(path), f"read_motion path = {path}: must be")


def test_a_binary_at2_record_is_refused_as_binary(tmp_path):
    """Found by a hunt: Latin-1 decodes any byte, so a binary .AT2 was refused at "line 3: ''"."""
    path = tmp_path / "binary.AT2"
    path.write_bytes(b"title\nevent\n\x00\x01\x02\n\xff\x00")
    refused(lambda: read_motion(path), f"{path}: not a text file (character 12 is a NUL byte); a PEER .AT2 file is text")


def test_a_folder_a_missing_file_and_an_unknown_suffix_are_refused(tmp_path):
    folder = tmp_path / "record.csv"
    folder.mkdir()
    refused(lambda: read_motion(folder), f"{folder}: is a folder")
    refused(lambda: read_csv_motion(folder), f"{folder}: is a folder")
    refused(lambda: read_motion(tmp_path / "gone.at2"), f"{tmp_path / 'gone.at2'}: no such file")
    refused(lambda: read_at2(tmp_path / "gone.at2"), "gone.at2: no such file")
    text = written(tmp_path, "record.txt", "time_s,acc_x_m_s2\n0,1\n1,2\n")
    refused(lambda: read_motion(text), f"{text}: unknown motion file type '.txt'; supported: .csv, .at2")


def test_a_direction_is_refused_for_a_csv_motion(tmp_path):
    path = written(tmp_path, "xy.csv", "time_s,acc_x_m_s2\n0,1\n1,2\n")
    refused(lambda: read_motion(path, direction="y"), f"{path}: direction = 'y' applies to a single-component .AT2 record")


@pytest.mark.parametrize("value", ["1_0", "0x10", "\u0661", "\uff12", "1.0D-3"], ids=["underscore", "hex", "arabic-digit", "fullwidth-digit", "fortran-d"])
def test_a_csv_number_that_is_not_a_plain_decimal_is_refused_naming_the_file_line_and_column(tmp_path, value):
    """The finding: float() reads 1_0 as 10 (and digits of other scripts as theirs), so a
    record said 10 m/s2 where its file said no number drydem writes or reads elsewhere."""
    path = written(tmp_path, "odd.csv", f"time_s,acc_x_m_s2\n0,0\n0.01,{value}\n0.02,0\n")
    refused(lambda: read_motion(path), f"{path}: line 3: acc_x_m_s2: {value!r} is not a number (a plain decimal such as 0.01")


def test_a_long_unreadable_value_is_shown_shortened(tmp_path):
    path = written(tmp_path, "long.csv", "time_s,acc_x_m_s2\n0,0\n0.01," + "1_" * 500 + "1\n")
    refused(lambda: read_motion(path), f"{path}: line 3: acc_x_m_s2: '1_1_1_", "(1003 characters) is not a number")


@pytest.mark.parametrize("name, text", [
    ("zeros.csv", "time_s,acc_x_m_s2,acc_y_m_s2\n0,0,0\n0.01,0,-0\n0.02,0.0,0e5\n"),
    ("zeros.AT2", AT2_NEW.replace(AT2_BODY, "  .0000000E+00" * 5 + "\n" + " -.0000000E+00" * 2 + "\n")),
], ids=["csv", "at2"])
def test_a_record_whose_accelerations_are_all_zero_is_refused_as_a_table_at_rest(tmp_path, name, text):
    """As --scale 0 and a pulse of amplitude 0 are: a table at rest is no shaking test (the
    finding: such a record ran, and reported a PGA of 0)."""
    path = written(tmp_path, name, text)
    refused(lambda: read_motion(path), f"{path}: every acceleration of the record is 0: a table at rest, no motion")


def test_the_messages_of_a_record_name_its_file_as_given(tmp_path, monkeypatch):
    """Every message about a record read from a file names the file as the command was given it,
    as reading it does (the finding: a baseline correction refused named only 'bigdur.csv');
    the motion's name, which the reports show, stays the file's name."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mo").mkdir()
    written(tmp_path / "mo", "bigdur.csv", "time_s,acc_x_m_s2\n0,0\n0.01,1\n999999.0,0\n")
    written(tmp_path / "mo", "r.csv", "time_s,acc_x_m_s2\n0,0\n0.5,1\n1,0\n")
    written(tmp_path / "mo", "r.AT2", AT2_NEW)
    spread = read_motion(Path("mo/bigdur.csv"))
    assert spread.name == "bigdur.csv" and spread.label == "mo/bigdur.csv"
    refused(spread.baseline_corrected, "mo/bigdur.csv: a baseline correction needs samples spread over the record")
    record = read_motion("mo/r.csv")
    refused(lambda: record.baseline_corrected().scaled(1e4), "mo/r.csv, baseline-corrected x 10000: the acceleration reaches")
    assert record.resolution_problem(1.0).startswith("mo/r.csv: its duration, 1 s, spans 1 timesteps")
    at2 = read_motion("mo/r.AT2")
    assert at2.name == "r.AT2" and at2.scaled(2.0).label == "mo/r.AT2 x 2"


# ---------------------------------------------------------------- PEER .AT2


@pytest.mark.parametrize("text", [AT2_NEW, AT2_NEW.replace("SEC\n", "SEC,\n").replace("   .0050", " 0.005"),
                                  AT2_NEW.replace("NPTS=     7, DT=   .0050 SEC", "NPTS=7 DT=.005SEC"), AT2_OLD],
                         ids=["nga-west2", "trailing-comma", "no-comma", "old-nga"])
def test_an_at2_record_reads_in_either_header_style_with_g_converted_to_m_s2(tmp_path, text):
    read = read_motion(written(tmp_path, "RSN1_TEST090.AT2", text))
    # a_i = value_i (g) x 9.81 m/s2 per g, along x only
    np.testing.assert_allclose(read.acceleration_m_s2[:, 0], np.array(AT2_VALUES_G) * 9.81, rtol=1e-15)
    assert G == 9.81
    assert not read.acceleration_m_s2[:, 1:].any()
    np.testing.assert_allclose(read.time_s, np.arange(7) * 0.005, rtol=1e-15)  # t_k = k DT
    assert read.duration_s == pytest.approx(0.03)  # (NPTS - 1) DT = 6 x 0.005
    assert read.pga_g == pytest.approx(0.5)  # the largest |value|, in g
    assert read.name == "RSN1_TEST090.AT2"


@pytest.mark.parametrize("direction, axis", [("y", 1), ("z", 2)])
def test_an_at2_record_drives_the_direction_asked_for(tmp_path, direction, axis):
    path = written(tmp_path, "r.at2", AT2_NEW)
    read = read_motion(path, direction=direction)
    np.testing.assert_allclose(read.acceleration_m_s2[:, axis], np.array(AT2_VALUES_G) * G, rtol=1e-15)
    assert np.count_nonzero(read.acceleration_m_s2) == np.count_nonzero(AT2_VALUES_G)


def test_the_main_direction_is_the_horizontal_axis_with_the_larger_peak():
    """What a video of the shaking is seen from (drydem.io.vtk.ShakeSeries): x on a tie or with
    no horizontal motion."""
    def motion(x, y, z):
        return GroundMotion(np.array([0.0, 0.1]), np.array([[0.0, 0.0, 0.0], [x, y, z]]), "m")

    assert [motion(*peaks).main_direction for peaks in [(1.0, 0.5, 9.0), (-0.5, -1.0, 0.0), (1.0, -1.0, 0.0), (0.0, 0.0, 3.0)]] == [0, 1, 0, 0]
    assert pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=2.0, direction="y").main_direction == 1


@pytest.mark.parametrize("text, message", [
    (AT2_NEW.replace(" -.2000000E-01  .5000000E+00\n", ""), "line 4 gives NPTS = 7, but the file holds 5 values (truncated?)"),
    (AT2_NEW + "  .1000000E-01\n", "line 4 gives NPTS = 7, but the file holds 8 values"),
    (AT2_NEW.replace("UNITS OF G", "UNITS OF CM/S").replace("ACCELERATION", "VELOCITY"),
     "line 3: 'VELOCITY TIME SERIES IN UNITS OF CM/S': expected 'ACCELERATION TIME SERIES IN UNITS OF G'"),
    (AT2_NEW.replace("UNITS OF G", "UNITS OF G/100"),  # found by a hunt: read as g, 100 times too strong
     "line 3: 'ACCELERATION TIME...IN UNITS OF G/100' (44 characters): expected 'ACCELERATION TIME SERIES IN UNITS OF G'"),
    (AT2_NEW.replace("UNITS OF G", "UNITS OF G (CM/S2)"), "NITS OF G (CM/S2)' (48 characters): expected"),
    (AT2_NEW.replace("NPTS=     7, DT=   .0050 SEC", "7 points every 5 ms"),
     "line 4: '7 points every 5 ms': expected 'NPTS=  5590, DT=   .0050 SEC' or '5590    0.0050    NPTS, DT'"),
    (AT2_NEW.replace("DT=   .0050", "DT=   0.000"), "line 4: DT = 0.0: must be a number in [1e-06, inf) s"),
    (AT2_NEW.replace("DT=   .0050", "DT=   1e-300"), "line 4: DT = 1e-300: must be a number in [1e-06, inf) s"),
    (AT2_NEW.replace("DT=   .0050", "DT=   fast"), "line 4: DT: 'fast' is not a number"),
    (AT2_NEW.replace("NPTS=     7", "NPTS=   7.5"), "line 4: NPTS = '7.5': must be an integer in [2, inf)"),
    (AT2_NEW.replace(".5000000E+00", ".5000000E+0x"), "line 6: '.5000000E+0x' is not a number"),
    (AT2_NEW.replace(".5000000E+00", "NaN"), "line 6: 'NaN' is not a finite number"),
    ("PEER NGA STRONG MOTION DATABASE RECORD\n", "1 lines; a PEER .AT2 file has 4 header lines"),
], ids=["truncated", "too-long", "velocity", "g-over-100", "g-in-cm-s2", "no-npts", "zero-dt", "tiny-dt", "word-dt", "fractional-npts", "word-value", "nan", "short"])
def test_a_bad_at2_record_is_refused_naming_the_file_and_the_problem(tmp_path, text, message):
    path = written(tmp_path, "bad.AT2", text)
    refused(lambda: read_motion(path), f"{path}: ", message)


@pytest.mark.parametrize("npts, message", [
    ("\u00b2", "line 4: NPTS = '\u00b2': must be an integer in [2, inf)"),
    ("9" * 5000, "line 4: NPTS = '99999"),
    ("9" * 300, "line 4 gives NPTS = 99999"),
], ids=["superscript", "past-int-digits", "long"])
def test_an_at2_npts_is_refused_without_a_traceback_and_shown_shortened(tmp_path, npts, message):
    """str.isdigit takes a superscript 2, which int() refuses; int() refuses more than 4300
    digits: both were tracebacks. A long NPTS is shown shortened."""
    path = tmp_path / "bad.AT2"
    path.write_text(AT2_NEW.replace("NPTS=     7", f"NPTS= {npts}"), encoding="latin-1")
    with pytest.raises(ModelError) as error:
        read_motion(path)
    assert str(error.value).startswith(f"{path}: ") and message in str(error.value) and "9" * 40 not in str(error.value)


def test_an_at2_value_that_is_not_a_plain_decimal_is_refused_naming_the_file_and_line(tmp_path):
    path = written(tmp_path, "odd.AT2", AT2_NEW.replace(".5000000E+00", "1_0"))
    refused(lambda: read_motion(path), f"{path}: line 6: '1_0' is not a number")


@pytest.mark.parametrize("encoding", ["utf-8", "latin-1"])
def test_an_at2_record_reads_as_utf8_or_latin1_and_names_a_unicode_minus_as_written(tmp_path, encoding):
    path = tmp_path / "station.AT2"
    path.write_bytes(AT2_NEW.replace("Test station", "Estación Sismológica").encode(encoding))
    np.testing.assert_allclose(read_motion(path).acceleration_m_s2[:, 0], np.array(AT2_VALUES_G) * 9.81, rtol=1e-15)
    path.write_bytes(AT2_NEW.replace(" -.1800000E-02", " \u22121.800000E-03").encode("utf-8"))
    refused(lambda: read_motion(path), f"{path}: line 5: '\u22121.800000E-03' is not a number")


def test_an_at2_direction_other_than_x_y_z_is_refused(tmp_path):
    path = written(tmp_path, "r.AT2", AT2_NEW)
    refused(lambda: read_at2(path, direction="north"), f"{path}: direction = 'north': must be one of ('x', 'y', 'z')")


def test_the_suffix_is_read_in_either_case(tmp_path):
    assert read_motion(written(tmp_path, "r.At2", AT2_OLD)).time_s.size == 7
    assert read_motion(written(tmp_path, "r.CSV", "time_s,acc_x_m_s2\n0,1\n1,2\n")).time_s.size == 2


# ---------------------------------------------------------------- pulses


def test_pulses_are_the_three_kinds():
    assert PULSES == ("one-sine", "sine", "ricker")


@pytest.mark.parametrize("amplitude", [2.0, -2.0])
def test_a_one_sine_pulse_peaks_at_a_quarter_period_and_ends_at_zero_velocity(amplitude):
    f = 2.5
    one = pulse("one-sine", amplitude_m_s2=amplitude, frequency_hz=f)
    assert one.duration_s == pytest.approx(1 / f, rel=1e-15)  # one period
    a = one.acceleration_m_s2[:, 0]
    k = int(np.argmax(np.abs(a)))
    assert one.time_s[k] == pytest.approx(1 / (4 * f), rel=1e-15)  # sin(2 pi f t) = 1 at t = 1/(4f)
    assert a[k] == pytest.approx(amplitude, rel=1e-15) and one.pga_m_s2 == pytest.approx(abs(amplitude), rel=1e-15)
    v = one.velocity_m_s()[:, 0]
    # v(t) = A/(2 pi f) (1 - cos 2 pi f t): 0 after a full period, A/(pi f) at its middle
    assert abs(v[-1]) < 1e-12 * abs(amplitude) / f
    assert v.max(initial=0) - v.min(initial=0) == pytest.approx(abs(amplitude) / (math.pi * f), rel=1e-4)
    # d(1/f) = A / (2 pi f^2) (the integral of v); the trapezoidal rule's relative error is (2 pi / 200)^2 / 12 = 8e-5
    assert one.displacement_m()[-1, 0] == pytest.approx(amplitude / (2 * math.pi * f**2), rel=1e-4)


def test_a_sine_of_n_cycles_lasts_n_periods_and_ends_at_zero_velocity():
    sine = pulse("sine", amplitude_m_s2=1.5, frequency_hz=4.0, cycles=3, samples_per_period=40)
    assert sine.duration_s == pytest.approx(3 / 4.0, rel=1e-15)  # N / f
    assert sine.time_s.size == 3 * 40 + 1  # samples_per_period per period, both ends
    assert abs(sine.velocity_m_s()[-1, 0]) < 1e-12  # a whole number of periods: zero mean
    # drift d(N/f) = A N / (2 pi f^2) = 1.5 x 3 / (2 pi 16), less the trapezoidal rule's relative
    # error on the sine, (2 pi / 40)^2 / 12 = 2.1e-3
    assert sine.displacement_m()[-1, 0] == pytest.approx(1.5 * 3 / (2 * math.pi * 16), rel=2.5e-3)


def test_a_ricker_pulse_peaks_at_t0_and_ends_at_rest():
    f, amplitude = 2.0, 3.0
    ricker = pulse("ricker", amplitude_m_s2=amplitude, frequency_hz=f, direction="y")
    t0 = 1.5 / f  # the wavelet's centre
    a = ricker.acceleration_m_s2[:, 1]
    k = int(np.argmax(a))
    assert ricker.time_s[k] == pytest.approx(t0, rel=1e-15) and a[k] == pytest.approx(amplitude, rel=1e-15)  # (1 - 0) e^0
    assert ricker.duration_s == pytest.approx(2 * t0, rel=1e-15)
    # ends: A (1 - 2 u0^2) exp(-u0^2), u0 = 1.5 pi: -1.0e-8 A
    u0 = 1.5 * math.pi
    assert a[0] == pytest.approx(amplitude * (1 - 2 * u0**2) * math.exp(-u0**2), rel=1e-12)
    assert not ricker.acceleration_m_s2[:, [0, 2]].any()
    # the velocity ends at 2 u0 exp(-u0^2) A / (pi f) = 7e-10 A / f, the displacement at
    # 2 u0^2 exp(-u0^2) A / (pi f)^2 = 1e-9 A / f^2 (plus the trapezoidal rule's error)
    assert abs(ricker.velocity_m_s()[-1, 1]) < 1e-8 * amplitude / f
    assert abs(ricker.displacement_m()[-1, 1]) < 1e-8 * amplitude / f**2


@pytest.mark.parametrize("kind, arguments, message", [
    ("square", {}, "pulse kind = 'square': must be one of ('one-sine', 'sine', 'ricker')"),
    ("sine", {"frequency_hz": 0.0}, "pulse frequency_hz = 0.0: must be a number in (0, inf) Hz"),
    ("sine", {"frequency_hz": -1.0}, "pulse frequency_hz = -1.0: must be a number in (0, inf) Hz"),
    ("sine", {"frequency_hz": math.inf}, "pulse frequency_hz = inf"),
    ("sine", {"amplitude_m_s2": True}, "pulse amplitude_m_s2 = True: must be a number"),
    ("sine", {"amplitude_m_s2": math.nan}, "pulse amplitude_m_s2 = nan: must be a number"),
    ("sine", {"cycles": 0}, "pulse cycles = 0: must be an integer in [1, 1000]"),
    ("sine", {"cycles": 1.5}, "pulse cycles = 1.5: must be an integer"),
    ("sine", {"cycles": True}, "pulse cycles = True: must be an integer"),
    ("one-sine", {"cycles": 2}, "pulse cycles = 2: a one-sine pulse has no cycles to repeat"),
    ("ricker", {"cycles": 3}, "pulse cycles = 3: a ricker pulse has no cycles to repeat"),
    ("sine", {"direction": "up"}, "pulse direction = 'up': must be one of ('x', 'y', 'z')"),
    ("sine", {"samples_per_period": 10}, "pulse samples_per_period = 10: must be an integer in [20, 1e+04]"),
])
def test_a_bad_pulse_is_refused_naming_the_parameter_and_rule(kind, arguments, message):
    settings = {"amplitude_m_s2": 1.0, "frequency_hz": 1.0} | arguments
    refused(lambda: pulse(kind, **settings), message)


@pytest.mark.parametrize("kind", PULSES)
def test_a_pulse_carries_its_period_for_the_analysis_to_resolve(kind):
    assert pulse(kind, amplitude_m_s2=1.0, frequency_hz=4.0).scaled(2.0).period_s == 0.25  # 1 / f, through the scaling
    assert motion([0.0, 1.0], [1.0, 2.0]).period_s is None  # a record's content is not known


def test_a_motion_is_followed_only_over_twenty_timesteps():
    """The pulse's period (a record's duration) must span at least STEPS_PER_PERIOD = 20
    timesteps: 1 / f = 0.25 s is 20 steps of 12.5 ms, not of 12.6 ms."""
    one_sine = pulse("one-sine", amplitude_m_s2=1.0, frequency_hz=4.0)
    assert one_sine.resolution_problem(0.0125) is None
    assert one_sine.resolution_problem(0.0126) == (
        "one-sine pulse 1 m/s2, 4 Hz along x: its period, 0.25 s, spans 19.8 timesteps of 0.0126 s (the model's at the start of the "
        "shaking); the analysis follows a motion only over at least 20 timesteps: give a frequency of at most 3.968 Hz "
        "(--frequency; FREQUENCY_HZ of a study's pulse)")
    record = motion([0.0, 1e-4, 2e-4], [0.0, 1.0, 0.0])
    assert record.resolution_problem(1e-5) is None
    assert "its duration, 0.0002 s, spans 2 timesteps of 0.0001 s" in record.resolution_problem(1e-4)
    assert "give a record lasting at least 0.002 s" in record.resolution_problem(1e-4)


def test_every_bad_pulse_parameter_is_named_at_once():
    refused(lambda: pulse("sine", amplitude_m_s2=math.inf, frequency_hz=0), "amplitude_m_s2 = inf", "frequency_hz = 0")


# ---------------------------------------------------------------- the motion's samples


def test_velocity_and_displacement_integrate_a_constant_acceleration_exactly():
    time = np.array([0.0, 0.1, 0.3, 0.6, 1.0])
    table = motion(time, 2.0)
    # v = a t; d = a t^2 / 2, exact: the trapezoidal rule integrates the linear v exactly
    np.testing.assert_allclose(table.velocity_m_s()[:, 0], 2.0 * time, rtol=1e-14)
    np.testing.assert_allclose(table.displacement_m()[:, 0], time**2, rtol=1e-14)


@pytest.mark.parametrize("time, acceleration, message", [
    ([0.1, 0.2], np.zeros((2, 3)), "time_s must start at 0 s; it starts at 0.1 s"),
    ([0.0, 0.2, 0.2], np.zeros((3, 3)), "sample 2 (t = 0.2 s) is not after sample 1 (t = 0.2 s)"),
    ([0.0], np.zeros((1, 3)), "time_s must be a list of at least 2 times"),
    ([0.0, 1.0], np.zeros((2, 2)), "acceleration_m_s2 must have shape (2, 3)"),
    ([0.0, 1.0], [[0, 0, 0], [0, np.nan, 0]], "must be finite numbers"),
    ([0.0, 2e6], np.zeros((2, 3)), "the motion lasts 2e+06 s; at most 1e+06 s (the longest analysed time)"),
    ([0.0, 1.0, 2.0], [[0, 0, 0], [0, 0, -1e300], [0, 0, 0]], "the acceleration reaches -1e+300 m/s2 (z at t = 1 s); at most 1000 m/s2"),
])
def test_a_motion_with_bad_samples_is_refused_naming_it(time, acceleration, message):
    refused(lambda: GroundMotion(time, acceleration, "my record"), "my record: ", message)


def test_accelerations_up_to_about_100_g_are_a_motion_and_beyond_are_refused_however_made():
    # MAX_ACCELERATION_M_S2 = 1000: a record of 1e300 m/s2 overflowed the cycles and was called diverged
    assert motion([0.0, 1.0], [1000.0, -1000.0]).peaks_m_s2[0] == 1000.0
    refused(lambda: motion([0.0, 1.0], [1.0, 2.0]).scaled(600.0), "test record x 600: the acceleration reaches 1200 m/s2 (x at t = 1 s)")
    refused(lambda: pulse("sine", amplitude_m_s2=1e4, frequency_hz=2.0), "the acceleration reaches", "at most 1000 m/s2")


def test_the_samples_of_a_motion_cannot_be_changed():
    table = motion([0.0, 1.0], [1.0, 2.0])
    with pytest.raises(ValueError):
        table.acceleration_m_s2[0, 0] = 5.0


# ---------------------------------------------------------------- PGA and scaling


def test_the_pga_is_the_peak_of_the_horizontal_norm():
    table = motion([0.0, 0.1, 0.2], [3.0, -4.5, 0.0], [4.0, 0.0, -1.0])
    table = GroundMotion(table.time_s, table.acceleration_m_s2 + [0.0, 0.0, 100.0], "with vertical")
    assert table.pga_m_s2 == 5.0  # sqrt(3^2 + 4^2) at t = 0 beats |-4.5| at t = 0.1; z is not horizontal
    assert table.pga_g == 5.0 / 9.81
    assert table.peaks_m_s2 == (4.5, 4.0, 100.0)


@pytest.mark.parametrize("factor", [2.5, -0.5, 0])
def test_scaling_multiplies_every_acceleration_and_the_pga(factor):
    table = motion([0.0, 0.1, 0.2], [3.0, -4.5, 0.0], [4.0, 0.0, -1.0])
    scaled = table.scaled(factor)
    np.testing.assert_array_equal(scaled.acceleration_m_s2, table.acceleration_m_s2 * factor)
    assert scaled.pga_m_s2 == pytest.approx(abs(factor) * table.pga_m_s2, rel=1e-15)  # |k a| = |k| |a|
    np.testing.assert_array_equal(scaled.time_s, table.time_s)


@pytest.mark.parametrize("factor", [True, math.nan, math.inf, "2"])
def test_a_bad_scale_factor_is_refused(factor):
    refused(lambda: motion([0.0, 1.0], [1.0, 2.0]).scaled(factor), "test record: scale factor = ", "must be a number")


# ---------------------------------------------------------------- baseline correction


def test_a_baseline_corrected_record_with_an_offset_ends_at_rest():
    sine = pulse("sine", amplitude_m_s2=1.0, frequency_hz=2.0, cycles=3)
    offset = GroundMotion(sine.time_s, sine.acceleration_m_s2 + [0.1, 0.0, 0.0], "sine + 0.1 m/s2")
    # before: v_end = 0.1 m/s2 x 1.5 s, the offset's integral (the sine's whole periods add 0)
    assert offset.velocity_m_s()[-1, 0] == pytest.approx(0.15, rel=1e-9)
    corrected = offset.baseline_corrected()
    pga, duration = offset.pga_m_s2, offset.duration_s
    assert abs(corrected.velocity_m_s()[-1, 0]) < 1e-9 * pga * duration
    assert abs(corrected.displacement_m()[-1, 0]) < 1e-9 * pga * duration**2
    assert not corrected.acceleration_m_s2[:, 1:].any()
    assert corrected.name == "sine + 0.1 m/s2, baseline-corrected"


def test_a_baseline_correction_takes_a_constant_offset_off_a_record_at_rest():
    ricker = pulse("ricker", amplitude_m_s2=3.0, frequency_hz=2.0)  # ends at rest (2e-8 of its peaks)
    offset = GroundMotion(ricker.time_s, ricker.acceleration_m_s2 + [0.1, 0.0, 0.0], "ricker + 0.1 m/s2")
    corrected = offset.baseline_corrected()
    # the baseline c0 + c1 t / T is the offset: c0 = 0.1, c1 = 0; the PGA goes back from 3.1 to 3
    np.testing.assert_allclose(corrected.acceleration_m_s2, ricker.acceleration_m_s2, rtol=0, atol=1e-8 * 3.0)
    assert offset.pga_m_s2 == pytest.approx(3.1, rel=1e-15)  # A + 0.1 at t0
    assert corrected.pga_m_s2 == pytest.approx(3.0, rel=1e-8)


def test_a_record_already_at_rest_is_left_practically_unchanged():
    ricker = pulse("ricker", amplitude_m_s2=3.0, frequency_hz=2.0)  # ends at rest (2e-8 of its peaks)
    corrected = ricker.baseline_corrected()
    np.testing.assert_allclose(corrected.acceleration_m_s2, ricker.acceleration_m_s2, rtol=0, atol=1e-8 * 3.0)
    assert corrected.pga_m_s2 == pytest.approx(ricker.pga_m_s2, rel=1e-8)


def test_a_baseline_that_changes_the_motion_not_only_its_drift_gets_a_note():
    """Found by a hunt: a one-sine pulse of 5 m/s2 at 2 Hz given as a record leaves the table
    displaced by A / (2 pi f) x 1/(2 f) = 0.199 m (its velocity's integral); bringing it back
    took a baseline of 0.53 m/s2 (10.6 % of the PGA, which rose to 5.27 m/s2) and made the
    residual slip of a block 34 times the pulse's, without a word. Above 1 % of the peak a note
    gives the baseline and the displacement; the offset record above (0.1 of 3.1 m/s2, a drift
    the correction is for) gets one too, and a record at rest none."""
    one_sine = pulse("one-sine", amplitude_m_s2=5.0, frequency_hz=2.0, direction="x")
    tail = one_sine.time_s[-1] + np.arange(1, 101) * 0.01  # then a second at rest
    record = GroundMotion(np.concatenate([one_sine.time_s, tail]), np.concatenate([one_sine.acceleration_m_s2, np.zeros((100, 3))]),
                          "onesine.csv")
    [note] = record.baseline_corrected().notes
    assert note == ("onesine.csv: the baseline correction shifts the x acceleration by up to 0.53 m/s2, 10.6% of the record's peak, "
                    "to bring the table to rest where it started (the record moves it 0.199 m along x); if that displacement is "
                    "genuine (a pulse, a fling step), give --no-baseline")
    ricker = pulse("ricker", amplitude_m_s2=3.0, frequency_hz=2.0)
    assert ricker.baseline_corrected().notes == ()


def test_a_baseline_correction_of_two_samples_is_refused():
    refused(lambda: motion([0.0, 1.0], [1.0, 2.0]).baseline_corrected(), "test record: a baseline correction needs at least 3 samples")


@pytest.mark.parametrize("time_scale", [1e-300, 1e-3, 1e5])
def test_a_baseline_correction_is_the_same_in_any_time_scale(time_scale):
    """The conditions are solved in t / T: the baseline c0 + c1 t / T of a record depends on
    its accelerations and the shape of its sampling, not on its time unit (at 1e-300 s, the
    integrals in seconds, of order a T^2, were below the smallest float: a singular matrix)."""
    record = motion([0.0, 0.25, 0.5, 1.0], [0.0, 2.0, -1.0, 0.5])
    scaled = GroundMotion(record.time_s * time_scale, record.acceleration_m_s2, "scaled record").baseline_corrected()
    np.testing.assert_allclose(scaled.acceleration_m_s2, record.baseline_corrected().acceleration_m_s2, rtol=1e-12, atol=1e-15)


def test_a_baseline_correction_of_one_long_step_and_short_ones_is_refused():
    """1 - sum (dt / T)^3 is 0 for 2 samples (dependent conditions) and about 3e-9 here, where
    the baseline's coefficients would be ~1e8 times the record's peak."""
    nearly_two = motion([0.0, 1e-9, 1.0], [1.0, 0.0, 2.0])
    refused(nearly_two.baseline_corrected, "test record: a baseline correction needs samples spread over the record: one step spans "
            "99.999999900% of it", "1 - sum (dt / T)^3 = 3e-09, at least 1e-06", "--no-baseline")


# ---------------------------------------------------------------- per explicit cycle


def test_a_record_sampled_finer_than_the_timestep_gets_a_note_on_aliasing():
    """Found by a hunt: a record sampled finer than the timestep cannot be followed above half
    the cycle rate, and that went unsaid."""
    fine = motion(np.arange(101) * 1e-4, np.ones(101))
    note = fine.aliasing_note(2e-4)
    assert note == ("test record is sampled every 0.0001 s at its finest, finer than the timestep, 0.0002 s: its content above "
                    "2500 Hz (half the cycle rate) is averaged over each cycle, and what is left of it is aliased into slower "
                    "motion, weakened by the ratio of the frequencies; filter the record below that frequency if it has any")
    assert fine.aliasing_note(1e-4) is None and fine.aliasing_note(5e-5) is None
    sine = pulse("sine", amplitude_m_s2=1.0, frequency_hz=3.0, cycles=2, direction="x")  # analytic: no note
    assert sine.aliasing_note(1.0 / 3.0 / 20) is None


def test_a_vibration_faster_than_the_cycles_moves_the_table_by_its_own_small_velocity():
    """Found by a hunt: read at the cycles' times, a 5.45 kHz vibration of 6 m/s2 (velocity
    amplitude A / omega = 1.75e-4 m/s) became a slow motion of 6 m/s2. Averaged over each
    cycle, the table's velocity in the engine, sum of the rows times dt, is the vibration's own:
    v(t) = A (1 - cos omega t) / omega, at most 2 A / omega = 3.5e-4 m/s (read at the cycles'
    times it reached 1.85 m/s)."""
    frequency_hz, amplitude, dt = 5450.0, 6.0, 1.0 / 5449.0  # nearly a period per cycle: aliased to ~1 Hz
    times = np.arange(0.0, 2.0, 1.0 / 54500.0)
    vibration = motion(times, amplitude * np.sin(2.0 * np.pi * frequency_hz * times))
    table_velocity = np.cumsum(vibration.per_cycle(dt, int(2.0 / dt))[:, 0]) * dt
    assert np.abs(table_velocity).max() <= 2.0 * amplitude / (2.0 * np.pi * frequency_hz) * (1.0 + 1e-6)


def test_the_mean_acceleration_over_a_cycle_of_a_linear_record_is_its_value_at_the_cycle_time():
    """The mean of a linear function over [t - dt/2, t + dt/2] is its value at t; the record
    starts at rest before 0, so the first cycle's mean is the ramp's over [0, dt/2], halved."""
    dt, slope = 0.01, 3.0
    ramp = motion([0.0, 1.0], [0.0, slope])
    rows = ramp.per_cycle(dt, 50)
    np.testing.assert_allclose(rows[1:, 0], slope * np.arange(1, 50) * dt, rtol=0, atol=1e-12 * slope)
    assert rows[0, 0] == pytest.approx(slope * (dt / 2) ** 2 / 2 / dt, rel=1e-12)  # integral of s t over [0, dt/2], over dt


def test_the_mean_acceleration_per_cycle_spans_the_samples_and_is_zero_after_the_end():
    table = motion([0.0, 0.1, 0.2], [0.0, 1.0, -1.0])
    rows = table.per_cycle(0.025, 12)
    # t = 0, 0.025, ..., 0.275; the mean of the line 0 -> 1 -> -1 over [t - 0.0125, t + 0.0125]:
    # at 0, the ramp 10 t over [0, 0.0125] (7.8125e-4 m/s over 0.025 s); at 0.1, 10 t over
    # [0.0875, 0.1] and 1 - 20 (t - 0.1) over [0.1, 0.1125] (0.01171875 + 0.0109375 m/s); at
    # 0.2, the line from -0.75 to -1 over [0.1875, 0.2], then the table at rest; elsewhere the
    # line's value at t
    expected = [0.03125, 0.25, 0.5, 0.75, 0.90625, 0.5, 0.0, -0.5, -0.4375, 0.0, 0.0, 0.0]
    np.testing.assert_allclose(rows[:, 0], expected, rtol=0, atol=1e-15)
    assert not rows[:, 1:].any()


def test_the_table_velocity_in_the_engine_is_exact_at_every_half_step():
    """The rows times the steps telescope: their sum up to cycle k is the table's velocity at
    t_k + dt/2, the record's exact integral, for any record and timestep, also with a first
    step (dt_old + dt) / 2 after a change of timestep (which starts the sum at t_0 - dt_old/2)."""
    rng = np.random.default_rng(1)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-3, 2e-2, 200))])
    record = motion(times, rng.normal(0.0, 3.0, times.size))
    dt, dt_old, start = 3.7e-3, 5.1e-3, 0.4
    first = 0.5 * (dt_old + dt)
    rows = record.per_cycle(dt, 2000, start, first_step_s=first)
    velocity = np.cumsum(rows[:, 0] * np.r_[first, np.full(1999, dt)])
    half_steps = start + (np.arange(2000) + 0.5) * dt
    exact = record._velocity_change(np.full(2000, start - dt_old / 2), half_steps)[:, 0]
    scale = np.abs(exact).max()
    np.testing.assert_allclose(velocity, exact, rtol=0, atol=1e-12 * scale)
    assert record.acceleration_at(times[7])[0] == record.acceleration_m_s2[7, 0]  # the history's value: exact at a sample


def test_consecutive_excerpts_per_cycle_match_one_long_call():
    sine = pulse("sine", amplitude_m_s2=1.0, frequency_hz=3.0, cycles=2, direction="z")
    dt = 1.3e-3  # not a divisor of the sampling step
    whole = sine.per_cycle(dt, 600)  # runs past the end (0.667 s) into zeros
    parts = np.concatenate([sine.per_cycle(dt, 7), sine.per_cycle(dt, 393, start_s=7 * dt), sine.per_cycle(dt, 200, 400 * dt)])
    # t = 7 dt + k dt against (7 + k) dt: the same times to round-off, so the same rows to round-off
    np.testing.assert_allclose(parts, whole, rtol=0, atol=1e-12)
    assert not whole[int(sine.duration_s / dt) + 2:].any()  # every cycle whose step starts after the end
    assert sine.per_cycle(dt, 0).shape == (0, 3)


@pytest.mark.parametrize("arguments, message", [
    ((0.0, 10), "per_cycle dt_s = 0.0: must be a number in (0, inf) s"),
    ((math.nan, 10), "per_cycle dt_s = nan"),
    ((1e-3, -1), "per_cycle cycles = -1: must be an integer in [0, 1e+07]"),
    ((1e-3, 10**12), "per_cycle cycles = 1000000000000: must be an integer in [0, 1e+07]"),  # found by a hunt: a MemoryError
    ((1e-3, 10.0), "per_cycle cycles = 10.0: must be an integer"),
    ((1e-3, 10, True), "per_cycle start_s = True: must be a number"),
    ((1e-3, 10, -1.0), "per_cycle start_s = -1.0: must be a number in [0, inf) s"),
    ((1e-3, 10, 0.0, 0.0), "per_cycle first_step_s = 0.0: must be a number in (0, inf) s"),
])
def test_bad_per_cycle_arguments_are_refused(arguments, message):
    refused(lambda: motion([0.0, 1.0], [1.0, 2.0]).per_cycle(*arguments), message)
