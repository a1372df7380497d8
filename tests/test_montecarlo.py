"""drydem montecarlo: statistics against a known distribution (a tall brick toppling at
atan(L / H) with a scattered height H), the statistics against numpy, seeds that do not depend
on the number of samples, resumption, --overwrite and bad inputs."""

import json
import math
import re
import shutil
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import integrate, stats

from drydem.errors import DrydemError
from drydem.parametric import montecarlo as montecarlo_module
from drydem.parametric.limits import MAX_SAMPLES
from drydem.parametric.montecarlo import (MonteCarloError, MonteCarloSettings, SummaryWriter, check_resumable, monte_carlo, read_sample,
                                          sample_seed, statistics)
from drydem.analysis.tilt import TiltSettings
from drydem.cli import main
from drydem.masonry.imperfections import Imperfections, imperfect_blocks
from drydem.masonry.walls import load_wall

#: the tall brick: length along the wall, height, width, m; friction 0.8 > L / H = 0.4, so it
#: topples before it slides. Two points per length put the sub-contacts at the brick's ends,
#: so it pivots on its toe as a rigid block would
L, H, W = 0.020, 0.050, 0.012
TALL_BRICK = f'''joint = {{ kn = 1e9, ks = 1e9, friction = 0.8 }}
contacts = {{ points_per_length = 2 }}
supports = {{ fix_y = true }}
[brick]
length_m = {L}
height_m = {H}
width_m = {W}
[layout]
courses = """
B
"""
'''
#: the height scatter (mm, normal), samples and tilt step (deg) of the known-distribution run
HEIGHT_SD_MM, SAMPLES, INCREMENT_DEG = 2.0, 64, 0.1
#: the toppling angle's elastic loss, deg: the toe sub-contact carries the weight W_b and closes
#: by W_b / (kn A), A = L W / 2 its area, which turns the brick by that over L before its heel
#: lifts, and the centroid (H / 2 up) moves that rotation times H / 2 towards the toe:
#: tan(theta) drops by (H / 2) (W_b / (kn A L)) / (H / 2) = W_b / (kn A L); with W_b = 0.212 N,
#: kn = 1e9 Pa/m, A = 1.2e-4 m2: 8.8e-5 on 0.4, 0.004 deg. Bounded here by 0.02 deg
ELASTIC_LOSS_DEG = 0.02
#: the k of the k-sigma bounds on the statistics' sampling errors (two-sided 6e-5 for a normal estimate)
K_SIGMA = 4.0


def toppling_deg(height_m):
    """A rigid block of length L and height ``height_m`` on a tilting table topples at atan(L / H)."""
    return np.degrees(np.arctan(L / np.asarray(height_m)))


def run(*args):
    return CliRunner().invoke(main, ["montecarlo", *map(str, args)])


@pytest.fixture(scope="module")
def tall_brick(tmp_path_factory):
    path = tmp_path_factory.mktemp("wall") / "tall.toml"
    path.write_text(TALL_BRICK)
    return path


@pytest.fixture(scope="module")
def tall_brick_run(tall_brick, tmp_path_factory):
    """The tall brick's Monte Carlo run: its folder and summary."""
    out = tmp_path_factory.mktemp("mc") / "run"
    result = run(tall_brick, "--samples", SAMPLES, "--seed", 7, "--height-sd", HEIGHT_SD_MM, "--increment", INCREMENT_DEG,
                 "--stop-displacement", 0.02, "--workers", 2, "--out", out)
    assert result.exit_code == 0, result.output
    return out, json.loads((out / "summary.json").read_text())


def drawn_height_m(wall_path, seed: int) -> float:
    """The brick's height in the sample of ``seed``: its blocks drawn again."""
    imperfections = Imperfections(height_sd_mm=HEIGHT_SD_MM)
    brick = next(b for b in imperfect_blocks(load_wall(wall_path), imperfections, seed) if not b.fixed)
    z = brick.shape.vertices[:, 2]
    return float(z.max() - z.min())


def test_each_sample_topples_at_atan_length_over_its_own_drawn_height(tall_brick, tall_brick_run):
    """Sample k's collapse angle is the last step below atan(L / (H + delta_k)), less the
    joints' elastic loss: within one increment below it."""
    _, summary = tall_brick_run
    assert [s["index"] for s in summary["samples"]] == list(range(SAMPLES))
    heights = [drawn_height_m(tall_brick, s["seed"]) for s in summary["samples"]]
    assert np.std(heights) > 0.5 * HEIGHT_SD_MM * 1e-3  # the heights were scattered
    for sample, height in zip(summary["samples"], heights):
        exact = toppling_deg(height)
        assert exact - INCREMENT_DEG - ELASTIC_LOSS_DEG <= sample["collapse_angle_deg"] <= exact + 1e-6, (sample, height, exact)


def test_collapse_angle_statistics_agree_with_the_distribution_of_atan_length_over_a_normal_height(tall_brick_run):
    """theta = atan(L / (H + delta)), delta ~ N(0, sd^2): mean and std by numerical integration,
    p05 = theta(H + z_0.95 sd) (theta falls as the height grows). The sample statistics agree
    within K_SIGMA standard errors (mean: std / sqrt(n); std: std / sqrt(2 (n - 1)); p05:
    sqrt(p (1 - p) / n) / f(p05), f the density of theta there) plus the protocol's bias, the
    recorded angle being up to one increment (and the elastic loss) below the exact one."""
    _, summary = tall_brick_run
    sd = HEIGHT_SD_MM * 1e-3

    def moment(power):
        return integrate.quad(lambda d: toppling_deg(H + d) ** power * stats.norm.pdf(d, scale=sd), -8 * sd, 8 * sd)[0]

    mean = moment(1)
    std = math.sqrt(moment(2) - mean**2)
    p05_height = H + stats.norm.ppf(0.95) * sd
    p05 = float(toppling_deg(p05_height))
    slope = L / (p05_height**2 + L**2) * 180 / math.pi  # |d theta / d height| there, deg/m
    density = stats.norm.pdf(p05_height - H, scale=sd) / slope  # of theta at p05, 1/deg
    n = SAMPLES
    bias = INCREMENT_DEG + ELASTIC_LOSS_DEG
    found = summary["collapse_angle_deg"]
    assert found["count"] == n
    assert mean - bias - K_SIGMA * std / math.sqrt(n) <= found["mean"] <= mean + K_SIGMA * std / math.sqrt(n)
    assert abs(found["std"] - std) <= K_SIGMA * std / math.sqrt(2 * (n - 1)) + bias / 2
    assert p05 - bias - K_SIGMA * math.sqrt(0.05 * 0.95 / n) / density <= found["p05"] <= p05 + K_SIGMA * math.sqrt(0.05 * 0.95 / n) / density


def test_the_summary_holds_every_sample_and_its_record_beside_it(tall_brick_run):
    out, summary = tall_brick_run
    angles = [s["collapse_angle_deg"] for s in summary["samples"]]
    assert summary["collapse_angle_deg"] == statistics(angles)
    assert summary["dls_angle_deg"]["count"] + summary["excluded"]["dls_angle_deg_missing"] == SAMPLES
    assert (out / "histogram.png").stat().st_size > 0
    for sample in summary["samples"]:
        folder = out / "samples" / f"{sample['index']:04d}"
        record = json.loads((folder / "summary.json").read_text())
        assert record["sample"]["seed"] == sample["seed"] == sample_seed(7, sample["index"])
        assert record["sample"]["imperfections"] == asdict(Imperfections(height_sd_mm=HEIGHT_SD_MM))
        assert record["collapse_angle_deg"] == sample["collapse_angle_deg"]
        assert record["analysis"]["adaptive"] is True  # montecarlo's default protocol
        assert (folder / "pushover.csv").read_text().startswith("tilt_deg,")


@pytest.mark.parametrize("values, expected", [
    ([20.0, 21.0, 19.5, 22.5, 18.0], None),
    ([7.8], {"count": 1, "mean": 7.8, "std": None, "cov": None, "p05": 7.8, "min": 7.8, "max": 7.8}),
    ([], {"count": 0, "mean": None, "std": None, "cov": None, "p05": None, "min": None, "max": None}),
])
def test_statistics_are_numpy_sample_mean_std_cov_and_linear_5th_percentile(values, expected):
    x = np.array(values)
    if expected is None:
        std = x.std(ddof=1)
        expected = {"count": 5, "mean": x.mean(), "std": std, "cov": std / x.mean(), "p05": np.percentile(x, 5), "min": 18.0, "max": 22.5}
    assert statistics(values) == pytest.approx(expected)


def test_sample_seeds_do_not_depend_on_the_number_of_samples():
    for n in (3, 10):
        children = np.random.SeedSequence(42).spawn(n)
        assert [sample_seed(42, k) for k in range(n)] == [int(c.generate_state(1)[0]) for c in children]
    assert len({sample_seed(42, k) for k in range(1000)}) == 1000


def settings(samples):
    return MonteCarloSettings(samples=samples, seed=3, imperfections=Imperfections(height_sd_mm=HEIGHT_SD_MM),
                              tilt=TiltSettings(increment_deg=0.5, adaptive=True, stop_displacement_m=0.02))


def without_runtime(samples):
    return [{key: value for key, value in sample.items() if key != "runtime_s"} for sample in samples]


def test_a_resumed_run_computes_only_the_missing_and_corrupt_samples_with_the_same_seeds(tall_brick, tmp_path):
    wall = load_wall(tall_brick)
    with ThreadPoolExecutor(1) as pool:
        first = monte_carlo(wall, settings(3), tmp_path, pool, target={"name": "tall"})
    kept = (tmp_path / "samples" / "0000" / "summary.json").stat()
    (tmp_path / "samples" / "0002" / "summary.json").write_text("{")  # cut short
    computed = []
    with ThreadPoolExecutor(1) as pool:
        second = monte_carlo(wall, settings(4), tmp_path, pool, target={"name": "tall"}, on_sample=lambda e: computed.append(e["index"]))
    assert sorted(computed) == [2, 3] and (second.finished, second.skipped) == (2, 2) and len(second.corrupt) == 1
    assert (tmp_path / "samples" / "0000" / "summary.json").stat().st_mtime_ns == kept.st_mtime_ns
    assert without_runtime(second.summary["samples"][:3]) == without_runtime(first.summary["samples"])
    assert [s["seed"] for s in second.summary["samples"]] == [sample_seed(3, k) for k in range(4)]


def test_a_recorded_sample_with_an_angle_out_of_range_is_corrupt_not_averaged_in(tall_brick, tmp_path):
    """A sample's record with collapse_angle_deg = -40 was read as it was: the resumed run's mean
    and 5th percentile took it in (drydem report called the same record corrupt)."""
    wall = load_wall(tall_brick)
    with ThreadPoolExecutor(1) as pool:
        monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"})
    path = tmp_path / "samples" / "0001" / "summary.json"
    record = json.loads(path.read_text())
    path.write_text(json.dumps(record | {"collapse_angle_deg": -40.0}))
    with pytest.raises(MonteCarloError, match=re.escape(f"{path}: summary collapse_angle_deg = -40.0: must be a number in [0, 90] deg")):
        read_sample(tmp_path, settings(2), 1)
    with ThreadPoolExecutor(1) as pool:
        again = monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"})
    assert len(again.corrupt) == 1 and all(0.0 <= s["collapse_angle_deg"] <= 90.0 for s in again.summary["samples"])


def test_a_sample_whose_curve_is_cut_short_is_corrupt_and_a_file_in_a_sample_s_place_refused(tall_brick, tmp_path):
    """Found by a hunt: a pushover.csv cut to 2 rows was kept as the sample's; a file where a
    sample's folder goes made every --resume compute the sample, then fail to write it."""
    wall = load_wall(tall_brick)
    with ThreadPoolExecutor(1) as pool:
        monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"})
    # found by a review: a sample of a drydem that measured the drift from as drawn was resumed with its angles
    first = tmp_path / "samples" / "0000" / "summary.json"
    record = json.loads(first.read_text())
    first.write_text(json.dumps(record | {"drift_limit_angles_deg": dict.fromkeys(record["drift_limit_angles_deg"], 1.5)}))
    with pytest.raises(MonteCarloError, match=re.escape(f"{first}: summary drift_limit_angles_deg 0.005 = 1.5: its pushover curve gives")):
        read_sample(tmp_path, settings(2), 0)
    first.write_text(json.dumps(record))
    curve = tmp_path / "samples" / "0001" / "pushover.csv"
    curve.write_text("".join(curve.read_text().splitlines(keepends=True)[:2]))
    with pytest.raises(MonteCarloError, match=re.escape(f"{curve}: 1 rows, where summary.json records")):
        read_sample(tmp_path, settings(2), 1)
    computed = []
    with ThreadPoolExecutor(1) as pool:
        again = monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"}, on_sample=lambda e: computed.append(e["index"]))
    assert computed == [1] and len(again.corrupt) == 1 and len(curve.read_text().splitlines()) > 2
    summary_path = tmp_path / "samples" / "0001" / "summary.json"  # found by a review: an AttributeError
    summary_path.write_text(json.dumps(json.loads(summary_path.read_text()) | {"analysis": "tilt"}))
    with pytest.raises(MonteCarloError, match=re.escape(f"{summary_path}: ")):
        read_sample(tmp_path, settings(2), 1)
    shutil.rmtree(tmp_path / "samples" / "0001")
    (tmp_path / "samples" / "0001").write_text("mine")
    with pytest.raises(MonteCarloError, match=re.escape(f"{tmp_path / 'samples' / '0001'}: is not a folder but where sample 1 goes; "
                                                        "move it away")):
        with ThreadPoolExecutor(1) as pool:
            monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"})
    assert (tmp_path / "samples" / "0001").read_text() == "mine"


def test_a_samples_folder_that_is_a_link_is_refused_and_the_run_it_leads_to_left_alone(tall_brick, tmp_path):
    """Found by a hunt: a resumed run whose samples/ linked to another run's wrote its new
    samples there, mixing the two runs (the other one's summary still counting its own)."""
    wall = load_wall(tall_brick)
    other, mine = tmp_path / "other", tmp_path / "mine"
    with ThreadPoolExecutor(1) as pool:
        monte_carlo(wall, settings(1), other, pool, target={"name": "tall"})
    mine.mkdir()
    (mine / "samples").symlink_to(other / "samples")
    with ThreadPoolExecutor(1) as pool, pytest.raises(MonteCarloError, match=re.escape(f"{mine / 'samples'}: is a link; a run writes")):
        monte_carlo(wall, settings(2), mine, pool, target={"name": "tall"})
    assert sorted(p.name for p in (other / "samples").iterdir()) == ["0000"]


@pytest.mark.parametrize("content", [json.dumps({"settings": "x"}), "[" * 100_000])
def test_a_summary_whose_settings_are_not_a_table_is_no_run_to_resume(tall_brick, tmp_path, content):
    # "settings": "x" was an AttributeError traceback on --resume, JSON nested 100,000 deep a RecursionError
    wall = load_wall(tall_brick)
    (tmp_path / "summary.json").write_text(content)
    with pytest.raises(MonteCarloError, match="summary.json: not the summary of a drydem montecarlo run"):
        check_resumable(tmp_path, settings(2), wall)
    (tmp_path / "samples" / "0000").mkdir(parents=True)
    # found by a hunt: the message left only --overwrite, which deletes the samples, without a word on them
    with pytest.raises(MonteCarloError, match=re.escape(f"its 1 sample folders ({tmp_path / 'samples'}) are kept, each a run of "
                                                        "its own: restore summary.json from a copy")):
        check_resumable(tmp_path, settings(2), wall)
    (tmp_path / "samples" / "0000" / "summary.json").write_text("[" * 100_000)
    with pytest.raises(MonteCarloError, match="summary.json: not a sample's record: JSON nested deeper than"):
        read_sample(tmp_path, settings(2), 0)


def test_a_run_asked_for_fewer_samples_than_it_holds_is_refused_and_keeps_them(tall_brick, tmp_path):
    wall = load_wall(tall_brick)
    with ThreadPoolExecutor(1) as pool:
        monte_carlo(wall, settings(3), tmp_path, pool, target={"name": "tall"})
    summary = (tmp_path / "summary.json").read_text()
    message = "holds 3 samples (up to sample 2); --samples 2 would leave 1 of them out of its summary: give --samples 3 or more"
    with pytest.raises(MonteCarloError, match=re.escape(message)):
        check_resumable(tmp_path, settings(2), wall)
    with ThreadPoolExecutor(1) as pool, pytest.raises(MonteCarloError, match=re.escape(message)):
        monte_carlo(wall, settings(2), tmp_path, pool, target={"name": "tall"})
    assert (tmp_path / "summary.json").read_text() == summary
    check_resumable(tmp_path, settings(3), wall)  # as many, or more, go on


def failed_sample(wall, settings, index):
    """A stand-in for run_sample: the record of a sample failed at once."""
    sample = {"index": index, "seed": sample_seed(settings.seed, index), "imperfections": asdict(settings.imperfections),
              "status": "failed", "error": "stand-in", "runtime_s": 0.0}
    return {"summary": {"sample": sample}, "pushover": []}


def test_drydem_montecarlo_exits_1_naming_its_failed_samples(tall_brick, tmp_path, monkeypatch):
    """A failed sample (an error, not an outcome) is left out of the statistics; the command
    says so and exits 1, so that a script does not take the statistics for the whole run's."""
    from contextlib import contextmanager

    from drydem.parametric import workers
    from drydem.parametric.montecarlo import run_sample, write_sample

    @contextmanager
    def threads(count, scheduler):
        with ThreadPoolExecutor(1) as pool:
            yield workers.Workers(pool, "1 thread", 1)

    monkeypatch.setattr(montecarlo_module, "run_sample", failed_sample)
    monkeypatch.setattr(workers, "open_workers", threads)
    out = tmp_path / "run"
    result = run(tall_brick, "--samples", 2, "--height-sd", HEIGHT_SD_MM, "--out", out)
    assert result.exit_code == 1, result.output
    assert "failed: sample 0 (seed" in result.output and "failed: sample 1 (seed" in result.output
    assert f"2 of 2 samples failed (each named above, its error in its summary.json under {out / 'samples'})" in result.output
    assert (out / "summary.json").is_file()
    # a full disk while writing a sample, or the histogram: said, no traceback
    full = OSError(28, "No space left on device", "sample.csv")
    monkeypatch.setattr(montecarlo_module, "write_sample", lambda *args: (_ for _ in ()).throw(full))
    result = run(tall_brick, "--samples", 3, "--height-sd", HEIGHT_SD_MM, "--out", out, "--resume")
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    assert f"sample.csv: cannot write results (No space left on device); the finished samples are recorded in {out}; " \
           "go on with the same command plus --resume" in result.output
    # as the message says, --resume runs a failed sample again once its folder is removed
    monkeypatch.setattr(montecarlo_module, "write_sample", write_sample)
    monkeypatch.setattr(montecarlo_module, "run_sample", run_sample)
    shutil.rmtree(out / "samples" / "0000")
    result = run(tall_brick, "--samples", 2, "--height-sd", HEIGHT_SD_MM, "--out", out, "--resume")
    assert result.exit_code == 1 and "1 samples run, 1 recorded before" in result.output, result.output
    assert "1 of 2 samples failed" in result.output and "failed: sample 1 (seed" in result.output
    assert "failed: sample 0" not in result.output


class Stop(Exception):
    """An interruption after some samples."""


def test_a_run_of_the_most_samples_starts_at_once_and_an_interrupted_one_leaves_its_summary(tall_brick, tmp_path, monkeypatch):
    monkeypatch.setattr(montecarlo_module, "run_sample", failed_sample)
    finished = []

    def stop_after_three(entry):
        finished.append(entry["index"])
        if len(finished) == 3:
            raise Stop

    start = time.perf_counter()
    with ThreadPoolExecutor(1) as pool, pytest.raises(Stop):
        monte_carlo(load_wall(tall_brick), settings(MAX_SAMPLES), tmp_path, pool, target={"name": "tall"}, in_flight=1,
                    on_sample=stop_after_three)
    assert time.perf_counter() - start < 10.0  # not laid out sample by sample first
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert (summary["samples_requested"], summary["samples_recorded"]) == (MAX_SAMPLES, 3)


def test_the_summary_is_rewritten_no_faster_than_its_writing_stays_a_small_part_of_the_run(tmp_path):
    builds = []

    def slow_build():  # a summary of many samples: slow to build and write
        builds.append(1)
        time.sleep(0.05)
        return {"samples": len(builds)}

    writer = SummaryWriter(tmp_path, slow_build)
    for _ in range(5):  # samples finishing faster than SUMMARY_PACE x 0.05 s
        writer.changed()
    assert len(builds) == 1 and writer.stale
    time.sleep(writer.took * montecarlo_module.SUMMARY_PACE)  # then due
    writer.changed()
    assert len(builds) == 2 and not writer.stale and json.loads((tmp_path / "summary.json").read_text()) == {"samples": 2}


def test_more_samples_than_a_run_takes_are_refused_naming_the_limit_and_why(tall_brick):
    result = run(tall_brick, "--samples", MAX_SAMPLES + 1, "--height-sd", 1)
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert (f"Invalid value for '--samples': {MAX_SAMPLES + 1}: must be an integer in [1, {MAX_SAMPLES:.4g}] "
            "(the statistics' sampling error") in result.output
    with pytest.raises(DrydemError, match=rf"samples = {MAX_SAMPLES + 1}: must be an integer in \[1, "):
        settings(MAX_SAMPLES + 1)


def test_the_same_seed_gives_the_same_samples(tall_brick, tmp_path):
    wall = load_wall(tall_brick)
    angles = []
    for folder in (tmp_path / "a", tmp_path / "b"):
        with ThreadPoolExecutor(1) as pool:
            outcome = monte_carlo(wall, settings(2), folder, pool, target={"name": "tall"})
        angles.append([(s["seed"], s["collapse_angle_deg"]) for s in outcome.summary["samples"]])
    assert angles[0] == angles[1]


def test_an_earlier_run_is_kept_unless_overwrite_and_a_resume_must_have_the_same_options(tall_brick, tmp_path):
    out = tmp_path / "run"
    options = ["--seed", 1, "--height-sd", 1.0, "--increment", 1.0, "--stop-displacement", 0.02, "--workers", 1, "--out", out]
    assert run(tall_brick, "--samples", 2, *options).exit_code == 0
    again = run(tall_brick, "--samples", 1, *options)
    assert again.exit_code == 1 and "--overwrite" in again.output and "--resume" in again.output
    other = run(tall_brick, "--samples", 2, *options[:-2], "--friction", 0.9, "--out", out, "--resume")
    # the setting that differs is named, not the whole table it is in (found by a hunt)
    assert other.exit_code == 1 and "other settings (model_overrides.friction: model_overrides.friction None there, 0.9 now)" in other.output
    edited = tmp_path / "edited.toml"  # the same wall's file with another brick: another wall, not a resume
    edited.write_text(tall_brick.read_text().replace(f"height_m = {H}", f"height_m = {H * 1.1}"))
    elsewhere = run(edited, "--samples", 2, *options, "--resume")
    assert elsewhere.exit_code == 1 and "other settings (wall" in elsewhere.output
    replaced = run(tall_brick, "--samples", 1, *options, "--overwrite")
    assert replaced.exit_code == 0, replaced.output
    assert sorted(p.name for p in (out / "samples").iterdir()) == ["0000"]
    assert [s["index"] for s in json.loads((out / "summary.json").read_text())["samples"]] == [0]


def test_a_resumed_command_reads_each_recorded_sample_once_and_names_the_corrupt_one(tall_brick, tmp_path, monkeypatch):
    # the command read every sample's record to print what was recorded, then monte_carlo read
    # them all again under its hold on the folder (1e5 samples: twice the reading)
    import drydem.parametric.montecarlo as montecarlo

    out = tmp_path / "run"
    options = ["--seed", 1, "--height-sd", 1.0, "--increment", 1.0, "--stop-displacement", 0.02, "--workers", 1, "--out", out]
    assert run(tall_brick, "--samples", 2, *options).exit_code == 0
    (out / "samples" / "0001" / "summary.json").write_text("{")  # cut short
    reads = []
    real = montecarlo.read_sample
    monkeypatch.setattr(montecarlo, "read_sample", lambda *args: reads.append(args[2]) or real(*args))
    resumed = run(tall_brick, "--samples", 3, *options, "--resume")
    assert resumed.exit_code == 0, resumed.output
    assert sorted(reads) == [0, 1]
    assert "1 already recorded; running 2 on" in resumed.output
    assert resumed.output.count("corrupt sample, run again: ") == 1
    assert "2 samples run, 1 recorded before" in resumed.output


@pytest.mark.parametrize("args, message", [
    (["--samples", 0], "Invalid value for '--samples': 0 is not in the range x>=1"),
    (["--samples", "true"], "Invalid value for '--samples': 'true' is not a valid integer"),
    (["--resume", "--overwrite"], "--resume goes on with the run in --out and --overwrite deletes it"),
    (["--resume"], "--resume needs --out DIR holding the summary.json of an earlier drydem montecarlo"),
    (["--increment", -1], "Invalid value for '--increment': -1.0: must be a number in [0.001, 90) deg (tilt setting increment_deg)"),
    (["--friction", 0], "Invalid value for '--friction': 0.0: must be a number in (0, 10] ([joint] friction)"),
    (["--monitor", "nothing"], "nothing"),
    (["--height-sd", 6], "--height-sd = 6.0: must be at most 5 mm"),
    (["--height-sd", 0], "no imperfections: every sample would be the perfect wall"),
    # found by a hunt: every sample ran and failed on it, after the run had started
    (["--tilt-axis", "x"], "tilt_axis = 'x' loads the model along y, out of its plane, but it is an in-plane model"),
])
def test_bad_options_are_refused_naming_the_option_and_the_rule(tall_brick, args, message):
    result = run(tall_brick, "--samples", 2, "--height-sd", 1, *args)
    assert result.exit_code != 0 and message in result.output, result.output
    assert "Traceback" not in result.output and "samples run" not in result.output  # refused before any sample


def test_a_model_file_is_refused_as_imperfections_need_a_brick_layout(tmp_path):
    path = tmp_path / "model.toml"
    path.write_text("[[block]]\nname = 'base'\nfixed = true\nbox = { min = [0, 0, -0.01], max = [0.1, 0.01, 0] }\n"
                    "[[block]]\nname = 'b'\nbox = { min = [0, 0, 0], max = [0.02, 0.01, 0.05] }\n")
    result = run(path, "--samples", 2, "--height-sd", 1)
    assert result.exit_code == 1 and "has no brick layout" in result.output, result.output


@pytest.mark.parametrize("marks", [{}, {"mean_deg": 30.0, "p05_deg": 28.0}], ids=["nothing-labelled", "marks-only"])
def test_the_histogram_of_a_run_without_a_collapse_angle_leaks_no_matplotlib_warning(tmp_path, marks):
    """The finding: a run in which no sample found a collapse angle printed matplotlib's 'No
    artists with labels found to put in legend' to stderr; the legend is drawn only when
    something is labelled."""
    import warnings

    from drydem.report.plots import histogram_figure

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        histogram_figure([], tmp_path / "histogram.png", title="tiny: 0 imperfect walls", **marks)
    assert (tmp_path / "histogram.png").stat().st_size > 0


@pytest.mark.parametrize("change, words", [
    ({"in_flight": -1}, "monte_carlo in_flight = -1: must be an integer in [1, inf)"),
    ({"wall": None}, "monte_carlo wall = None: must be a Wall"),
    ({"executor": None}, "monte_carlo executor = None: must be an Executor"),
    ({"folder": 5}, "monte_carlo folder = 5: must be a file path"),
    ({"target": object()}, "monte_carlo target = <object"),
    ({"settings": "overrides"}, "Model.overridden: unknown key(s) ['foo']"),
    ({"settings": "imperfections"}, "imperfections height_sd_mm = 1e+308: must be at most"),
], ids=["in-flight", "wall", "executor", "folder", "target", "override", "imperfections"])
def test_monte_carlo_refuses_each_argument_of_the_wrong_kind_before_any_sample(tall_brick, tmp_path, change, words):
    """Found by a hunt: in_flight = -1 ran no sample and said one was finished; None for the
    wall or executor was an AttributeError; an unknown override failed every sample, one by one."""
    arguments = {"wall": load_wall(tall_brick), "settings": settings(1), "folder": tmp_path / "mc", "target": {}}
    if change.get("settings") == "overrides":
        change = {"settings": MonteCarloSettings(samples=1, seed=3, imperfections=Imperfections(height_sd_mm=HEIGHT_SD_MM),
                                                 tilt=TiltSettings(), model_overrides={"foo": 1})}
    if change.get("settings") == "imperfections":  # found by a hunt: every sample failed, one by one
        change = {"settings": MonteCarloSettings(samples=1, seed=3, imperfections=Imperfections(height_sd_mm=1e308), tilt=TiltSettings())}
    with ThreadPoolExecutor(1) as pool, pytest.raises(DrydemError, match=re.escape(words)):
        monte_carlo(**({**arguments, "executor": pool} | change))
    assert not (tmp_path / "mc").exists()


@pytest.mark.parametrize("field, value", [("tilt", None), ("imperfections", None), ("model_overrides", [1, 2])])
def test_monte_carlo_settings_of_the_wrong_kind_are_refused_naming_the_field(field, value):
    values = {"samples": 1, "seed": 1, "imperfections": Imperfections(height_sd_mm=HEIGHT_SD_MM), "tilt": TiltSettings()}
    with pytest.raises(DrydemError, match=re.escape(f"{field} = {value!r}: must be a")):
        MonteCarloSettings(**(values | {field: value}))


def test_samples_dataframe_of_what_is_no_monte_carlo_summary_is_refused():
    from drydem.parametric.montecarlo import samples_dataframe

    for given in ({}, None, {"samples": [1, 2]}):  # found by a hunt: KeyError, TypeError, AttributeError
        with pytest.raises(MonteCarloError, match="not a drydem Monte Carlo summary"):
            samples_dataframe(given)
