"""Monte Carlo tilting analyses of an imperfect wall (issue 17): the collapse and DLS angles
of many copies of one wall, each with its bricks' imperfections drawn from its own seed
(:mod:`drydem.masonry.imperfections`), and their statistics.

Sample k's seed is ``np.random.SeedSequence(seed, spawn_key=(k,))``'s first 32-bit word
(:func:`sample_seed`): the k-th child numpy's ``SeedSequence(seed).spawn(n)`` would give, for
any n > k. So sample k depends on the run's seed and on k only, never on the number of
samples: a run of 200 samples extends one of 100 with the same first 100, and the children's
streams are independent by SeedSequence's construction (not seed + k, whose streams are merely
different).

Results, written as they come (a killed run loses only the samples in flight):

``OUT/samples/NNNN/``: sample NNNN's ``summary.json`` (``drydem tilt``'s,
:func:`drydem.io.results.tilt_summary`, plus ``sample``: its index, seed, imperfections and
status; a failed sample's holds its error instead) and ``pushover.csv``. A sample's folder is
written beside its place and renamed into it, whole or not at all.

``OUT/summary.json``: the settings, every recorded sample (index order) with its collapse and
DLS angles and outcome, and the statistics (:func:`statistics`) of both angles; rewritten
after each sample (paced once it takes long to write, :class:`SummaryWriter`) and at the end.

A run started again with the same settings (:func:`check_resumable`) skips the samples validly
recorded and runs the missing and the corrupt ones (:func:`pending_samples`); it may ask for
more samples, never for fewer than it holds (:func:`check_samples_kept`). One run at a time
works on a folder (:func:`hold_folder`). A run has at most
:data:`~drydem.parametric.limits.MAX_SAMPLES` samples.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
import traceback
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from drydem import __version__
from drydem.analysis.drift import DLS_DRIFT
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.errors import DrydemError, ModelError
from drydem.files import held
from drydem.io.results import MONTECARLO_LOCK, PushoverWriter, tilt_summary, write_summary
from drydem.masonry.imperfections import Imperfections, imperfect_model
from drydem.masonry.walls import Wall
from drydem.model.parameters import CALLBACK, FILE_PATH, InstanceOf, Range, check_arguments, field_problems, refuse, shown
from drydem.parametric.calibrate import wall_angle
from drydem.parametric.limits import SAMPLES
from drydem.parametric.records import ANGLE, RecordError, collapse_problem, drift_problem, read_json, read_pushover

#: the percentile reported as ``p05``
PERCENTILE = 5.0
SAMPLES_FOLDER = "samples"
#: the rules of a run's number of samples (at most MAX_SAMPLES, :mod:`drydem.parametric.limits`
#: says why) and of its seed (any whole number >= 0: numpy's SeedSequence takes any)
SETTINGS_RULES = {"samples": SAMPLES, "seed": Range(0, None, integer=True), "imperfections": InstanceOf(Imperfections),
                  "tilt": InstanceOf(TiltSettings), "model_overrides": InstanceOf(Mapping)}


#: at most this many samples analysed at once (monte_carlo's in_flight; None: all): 1 or more
IN_FLIGHT = Range(1, None, integer=True)


class MonteCarloError(DrydemError):
    """A Monte Carlo run that cannot go on as asked (another run on the folder, settings that
    differ from the recorded run's, an executor that lost a sample)."""


@dataclass(frozen=True, kw_only=True)
class MonteCarloSettings:
    """What a Monte Carlo run is: ``samples`` tilting analyses (``tilt``) of the wall, each
    with ``imperfections`` drawn from its own seed (:func:`sample_seed` of ``seed``), and the
    ``model_overrides`` (keywords of :meth:`drydem.model.assembly.Model.overridden`: kn, ks,
    friction, points, density, criterion) applied to every sample's model."""

    samples: int
    seed: int
    imperfections: Imperfections
    tilt: TiltSettings
    model_overrides: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self):
        refuse(field_problems(self, SETTINGS_RULES))

    def identity(self, wall: Wall) -> dict:
        """Everything that makes the samples of ``wall`` what they are (all but their number), as
        JSON values: the wall (its name and :func:`wall_digest`), the seed, imperfections, tilt
        settings and overrides; a resumed run must have the same (:func:`check_resumable`)."""
        return json.loads(json.dumps({
            "wall": {"name": wall.name, "digest": wall_digest(wall)}, "seed": self.seed, "imperfections": asdict(self.imperfections), "tilt": asdict(self.tilt),
            "model_overrides": {key: value for key, value in self.model_overrides.items() if value is not None},
        }))


def wall_digest(wall: Wall) -> str:
    """A hash of what builds ``wall``'s model (bricks, layout, density, joint, contacts, supports,
    solver), so that a run resumed on another wall, or on its file edited, is refused."""
    what = (wall.brick, wall.layout, wall.density, wall.joint, wall.contacts, wall.supports, wall.solver)
    return hashlib.sha1(repr(what).encode()).hexdigest()[:16]


def sample_seed(seed: int, index: int) -> int:
    """The seed of sample ``index``: the first 32-bit word of the ``index``-th child of
    ``SeedSequence(seed)`` (module docstring)."""
    return int(np.random.SeedSequence(seed, spawn_key=(index,)).generate_state(1)[0])


def sample_model(wall: Wall, settings: MonteCarloSettings, index: int):
    """The model of sample ``index``: the wall with its imperfections drawn from the sample's
    seed, and the settings' overrides."""
    model = imperfect_model(wall, settings.imperfections, sample_seed(settings.seed, index))
    return model.overridden(**settings.model_overrides)


def run_sample(wall: Wall, settings: MonteCarloSettings, index: int) -> dict:
    """Sample ``index`` analysed (in a worker): ``summary`` (see :func:`sample_summary`) and
    ``pushover`` (the Records). An exception is the sample's outcome, recorded, never raised: a
    sample whose drawn wall cannot be built must not stop the run."""
    start = time.perf_counter()
    try:
        model = sample_model(wall, settings, index)
        result = tilt_analysis(model, settings.tilt)
        summary, pushover = tilt_summary(result, model), result.records
        outcome = {"status": "ok", "error": None}
    except Exception as exc:  # the sample's failure is its record
        summary, pushover = {}, []
        outcome = {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(limit=5)}
    sample = {"index": index, "seed": sample_seed(settings.seed, index), "imperfections": asdict(settings.imperfections)} | outcome
    return {"summary": summary | {"sample": sample | {"runtime_s": round(time.perf_counter() - start, 3)}}, "pushover": pushover}


def sample_folder(folder: Path, index: int) -> Path:
    return Path(folder) / SAMPLES_FOLDER / f"{index:04d}"


def write_sample(folder: Path, record: dict) -> Path:
    """A sample's record (:func:`run_sample`) as ``OUT/samples/NNNN/``: written in a hidden
    folder beside it, then renamed into place (a corrupt one there is replaced)."""
    final = sample_folder(folder, record["summary"]["sample"]["index"])
    partial = final.with_name(f".{final.name}.partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    write_summary(partial, record["summary"])
    if record["summary"]["sample"]["status"] == "ok":
        writer = PushoverWriter(partial)
        for row in record["pushover"]:
            writer(row)
    shutil.rmtree(final, ignore_errors=True)
    os.replace(partial, final)
    return final


def sample_entry(summary: dict) -> dict:
    """A sample's line in the top summary: index, seed, status, collapse and DLS angles (deg,
    None where not found; a wall that cannot stand under its own weight has a collapse angle of
    0 deg, :func:`drydem.parametric.calibrate.wall_angle`: its capacity, not a missing value that
    would flatter the statistics), how its analysis ended, its run time, its error if it failed."""
    sample = summary["sample"]
    entry = {"index": sample["index"], "seed": sample["seed"], "status": sample["status"]}
    if sample["status"] != "ok":
        return entry | {"collapse_angle_deg": None, "dls_angle_deg": None, "ended_by": None, "error": sample["error"],
                        "runtime_s": sample["runtime_s"]}
    return entry | {"collapse_angle_deg": wall_angle(summary), "dls_angle_deg": summary["drift_limit_angles_deg"][repr(DLS_DRIFT)],
                    "ended_by": summary["ended_by"], "runtime_s": sample["runtime_s"]}


def read_sample(folder: Path, settings: MonteCarloSettings, index: int) -> dict:
    """The top-summary entry (:func:`sample_entry`) of sample ``index`` as recorded in
    ``folder``; MonteCarloError naming the file and what is wrong when its record is not JSON,
    lacks a key, or is not that of this sample (another index, seed or imperfections)."""
    path = sample_folder(folder, index) / "summary.json"
    try:
        summary = read_json(path, "sample's record")
        sample = summary["sample"]
        expected = {"index": index, "seed": sample_seed(settings.seed, index), "imperfections": asdict(settings.imperfections)}
        wrong = [key for key, value in expected.items() if sample[key] != json.loads(json.dumps(value))]
        if wrong:
            raise MonteCarloError(f"{path}: its {', '.join(wrong)} are not sample {index}'s")
        # the curve checked against its summary (found by a hunt: one cut to 2 rows was kept)
        curve = read_pushover(path.parent, summary) if sample["status"] == "ok" else []
        problem = (collapse_problem("tilt", summary) or drift_problem(summary, curve)) if sample["status"] == "ok" else None
        if problem is not None:  # an angle of -40 deg was averaged in
            raise MonteCarloError(f"{path}: {problem}")
        return sample_entry(summary)
    except (ModelError, RecordError) as exc:
        raise MonteCarloError(str(exc)) from None
    except (TypeError, KeyError) as exc:
        raise MonteCarloError(f"{path}: not a sample's record ({type(exc).__name__}: {exc})") from None


@dataclass(frozen=True)
class PendingSamples:
    """The samples of a run: those ``recorded`` (index -> top-summary entry), the indices
    ``todo`` (missing or corrupt), and the ``corrupt`` records' errors."""

    recorded: dict[int, dict]
    todo: list[int]
    corrupt: list[str]


def pending_samples(folder: Path, settings: MonteCarloSettings) -> PendingSamples:
    """What is recorded in ``folder`` and what is left to run (see :class:`PendingSamples`); the
    folder is listed once (:func:`sample_indices`), not looked up once per sample, so that a
    large run starts at once. MonteCarloError if a sample's place holds something other than a
    folder (it could not be written there)."""
    recorded, todo, corrupt = {}, [], []
    present = sample_indices(folder)
    for index in range(settings.samples):
        if index not in present:
            todo.append(index)
            continue
        if not sample_folder(folder, index).is_dir():  # found by a hunt: computed, then not written, at every --resume
            raise MonteCarloError(f"{sample_folder(folder, index)}: is not a folder but where sample {index} goes; move it away")
        try:
            recorded[index] = read_sample(folder, settings, index)
        except MonteCarloError as exc:
            corrupt.append(str(exc))
            todo.append(index)
    return PendingSamples(recorded, todo, corrupt)


def sample_indices(folder: Path) -> set[int]:
    """The indices of the sample folders in ``folder`` (``samples/NNNN``, valid or corrupt; not
    the hidden partial ones), or none if it has no samples folder."""
    try:
        names = os.listdir(Path(folder) / SAMPLES_FOLDER)
    except FileNotFoundError:
        return set()
    return {int(name) for name in names if name.isascii() and name.isdigit() and sample_folder(folder, int(name)).name == name}


def check_samples_kept(folder: Path, settings: MonteCarloSettings) -> None:
    """MonteCarloError if ``folder`` holds a sample beyond ``settings.samples``: a run goes on
    only with at least the samples it has, since its summary lists the samples asked for and
    would silently leave the others out (more samples extend it, module docstring)."""
    indices = sample_indices(folder)
    beyond = sum(index >= settings.samples for index in indices)
    if beyond:
        raise MonteCarloError(f"{folder}: holds {len(indices)} samples (up to sample {max(indices)}); --samples {settings.samples} "
                              f"would leave {beyond} of them out of its summary: give --samples {max(indices) + 1} or more to go on, "
                              "or --overwrite to start again")


def check_resumable(folder: Path, settings: MonteCarloSettings, wall: Wall) -> None:
    """MonteCarloError unless ``folder/summary.json`` is a Monte Carlo run's with the same
    settings (all but the number of samples: more extend it; fewer than it holds are refused,
    :func:`check_samples_kept`), naming those that differ."""
    path = Path(folder) / "summary.json"
    try:
        recorded = read_json(path, "Monte Carlo summary")["settings"]
    except (RecordError, TypeError, KeyError):
        recorded = None
    if not isinstance(recorded, dict):  # "settings": "x" was an AttributeError
        samples = len(sample_indices(folder))
        kept = (f"; its {samples} sample folders ({Path(folder) / SAMPLES_FOLDER}) are kept, each a run of its own: restore "
                "summary.json from a copy to go on with them, or give another --out (--overwrite deletes them)") if samples else ""
        # found by a hunt: a damaged summary left only --overwrite, which deletes the samples, without a word on them
        raise MonteCarloError(f"{path}: not the summary of a drydem montecarlo run (damaged or edited?), so the settings of the "
                              f"run there cannot be checked; --resume needs the --out of one{kept}")
    differ = differences(recorded, settings.identity(wall))
    if differ:
        raise MonteCarloError(f"{folder}: the recorded run had other settings ({', '.join(key for key, _, _ in differ)}: "
                              + "; ".join(f"{key} {there} there, {now} now" for key, there, now in differ)
                              + "); resume with the same options, or start another --out")
    check_samples_kept(folder, settings)


def differences(recorded: Mapping, current: Mapping, within: str = "") -> list[tuple[str, object, object]]:
    """(key, recorded value, current value) of every setting that differs, tables looked into
    (``tilt.increment_deg``, not the whole tilt table: found by a hunt, the message dumped it),
    sorted by key; an absent one is None."""
    found = []
    for key in sorted(recorded.keys() | current.keys(), key=str):
        there, now = recorded.get(key), current.get(key)
        if isinstance(there, Mapping) and isinstance(now, Mapping):
            found += differences(there, now, f"{within}{key}.")
        elif there != now:
            found.append((f"{within}{key}", there, now))
    return found


def statistics(values) -> dict:
    """Statistics of ``values`` (deg): ``count``; ``mean``; ``std``, the sample standard
    deviation (ddof = 1: unbiased variance), None under two values; ``cov`` = std / mean (None
    when either is None or the mean is 0); ``p05``, the 5th percentile (numpy's linear
    interpolation between order statistics); ``min``, ``max``. All None but the count when
    there is no value."""
    x = np.asarray(list(values), dtype=float)
    if x.size == 0:
        return {"count": 0, "mean": None, "std": None, "cov": None, "p05": None, "min": None, "max": None}
    mean = float(x.mean())
    std = float(x.std(ddof=1)) if x.size > 1 else None
    cov = std / mean if std is not None and mean != 0.0 else None
    return {"count": int(x.size), "mean": mean, "std": std, "cov": cov, "p05": float(np.percentile(x, PERCENTILE)),
            "min": float(x.min()), "max": float(x.max())}


def run_summary(target: dict, wall: Wall, settings: MonteCarloSettings, entries: Mapping[int, dict]) -> dict:
    """The top ``summary.json``: ``target`` (what the caller says of it), the settings, the
    ``samples`` recorded (index order), the statistics of the collapse angle over the samples
    with a verdict (a collapse, or 0 deg for a wall that cannot stand: :func:`sample_entry`; the
    others, listed with their outcome, are counted in ``excluded`` by outcome) and of the DLS
    angle over those that reached a 1 % drift."""
    samples = [entries[index] for index in sorted(entries)]
    collapsed = [s["collapse_angle_deg"] for s in samples if s["collapse_angle_deg"] is not None]
    excluded: dict[str, int] = {}
    for s in samples:
        if s["collapse_angle_deg"] is None:
            outcome = s["ended_by"] or s["status"]
            excluded[outcome] = excluded.get(outcome, 0) + 1
    dls = [s["dls_angle_deg"] for s in samples if s["dls_angle_deg"] is not None]
    return {
        "target": target,
        "samples_requested": settings.samples,
        "samples_recorded": len(samples),
        "settings": settings.identity(wall),
        "collapse_angle_deg": statistics(collapsed),
        "dls_angle_deg": statistics(dls),
        "excluded": {"collapse_angle_deg": excluded, "dls_angle_deg_missing": len(samples) - len(dls)},
        "samples": samples,
        "drydem_version": __version__,
    }


@contextmanager
def hold_folder(folder: Path) -> Iterator[None]:
    """Hold ``folder`` for this run: ``folder/.montecarlo.lock`` locked exclusively
    (:func:`drydem.files.held`: the kernel drops it when the process ends, however it ends);
    MonteCarloError if another run holds it."""
    busy = f"{folder}: another drydem montecarlo is working on it; wait for it to end, or give another --out"
    with held(Path(folder) / MONTECARLO_LOCK, busy, MonteCarloError):
        yield


@dataclass(frozen=True)
class MonteCarloOutcome:
    """How a run went: the samples ``finished`` now, ``skipped`` (validly recorded before), the
    ``corrupt`` records found (run again), and the top ``summary`` written last."""

    finished: int
    skipped: int
    corrupt: tuple[str, ...]
    summary: dict

    def to_dataframe(self):
        """The samples as a pandas DataFrame (:func:`samples_dataframe` of :attr:`summary`)."""
        return samples_dataframe(self.summary)


#: the columns of a sample's row (:func:`sample_entry`'s keys)
SAMPLE_COLUMNS = ("index", "seed", "status", "collapse_angle_deg", "dls_angle_deg", "ended_by", "runtime_s", "error")


def samples_dataframe(summary: dict):
    """A Monte Carlo run's samples, from its top ``summary`` (:func:`run_summary`, as in
    ``OUT/summary.json``), as a pandas DataFrame
    (:func:`drydem.analysis.dataframes.data_frame`), one row per sample in index order:
    ``index``, ``seed``, ``status``, ``collapse_angle_deg`` (0 for a wall that cannot stand,
    NaN without a verdict), ``dls_angle_deg``, ``ended_by``, ``runtime_s``, ``error`` (missing
    unless it failed); ``attrs``: the statistics (``collapse_angle_deg``, ``dls_angle_deg``),
    ``excluded``, ``settings`` and ``target``. MonteCarloError for anything else than such a summary."""
    from drydem.analysis.dataframes import data_frame

    keys = ("samples", "collapse_angle_deg", "dls_angle_deg", "excluded", "settings", "target")
    if not (isinstance(summary, dict) and set(keys) <= set(summary) and isinstance(summary["samples"], list)
            and all(isinstance(sample, dict) for sample in summary["samples"])):
        raise MonteCarloError(f"samples_dataframe summary = {shown(summary)}: not a drydem Monte Carlo summary (a dict with "
                              f"{', '.join(keys)}, samples a list of dicts: OUT/summary.json of drydem montecarlo)")
    samples = summary["samples"]
    columns = {name: [sample.get(name) for sample in samples] for name in SAMPLE_COLUMNS}
    for name in ("collapse_angle_deg", "dls_angle_deg"):
        wrong = [k for k, angle in enumerate(columns[name]) if angle is not None and angle not in ANGLE]
        if wrong:  # found by a hunt: True went into the frame as an angle
            raise MonteCarloError(f"samples_dataframe summary samples[{wrong[0]}] {name} = {shown(columns[name][wrong[0]])}: "
                                  f"{ANGLE}, or None")
        columns[name] = [np.nan if angle is None else angle for angle in columns[name]]
    return data_frame(columns, {name: summary[name] for name in ("collapse_angle_deg", "dls_angle_deg", "excluded", "settings", "target")})


def monte_carlo(wall: Wall, settings: MonteCarloSettings, folder: Path, executor: Executor, *, target: dict,
                in_flight: int | None = None, on_sample: Callable[[dict], None] | None = None,
                on_plan: Callable[[PendingSamples], None] | None = None) -> MonteCarloOutcome:
    """Run on ``executor`` the samples of ``settings`` not validly recorded in ``folder``
    (:func:`pending_samples`, handed to ``on_plan`` before the first runs: the samples' records
    are read once), at most ``in_flight`` at a time (default: all), writing each
    sample's record as it comes and the top summary (:func:`run_summary`, ``target`` in it)
    before the first, as they come (:class:`SummaryWriter`) and at the end, however it ends;
    ``on_sample(entry)`` for each sample finished here. MonteCarloError if another run holds
    the folder, the folder holds samples beyond ``settings.samples``
    (:func:`check_samples_kept`), or the executor loses a sample (the samples finished are
    recorded), or its samples folder is a link (it would mix this run's samples with those of
    the run it leads to). Every argument is checked first (ModelError naming it), and the
    overrides on the wall's model and the imperfections for its brick (which would otherwise
    fail every sample; found by a hunt: height_sd_mm = 1e308 did)."""
    check_arguments("monte_carlo", {"wall": InstanceOf(Wall), "settings": InstanceOf(MonteCarloSettings), "folder": FILE_PATH,
                                    "executor": InstanceOf(Executor), "target": InstanceOf(dict), "in_flight": IN_FLIGHT,
                                    "on_sample": CALLBACK, "on_plan": CALLBACK}, optional=("in_flight",), wall=wall, settings=settings,
                    folder=folder, executor=executor, target=target, in_flight=in_flight, on_sample=on_sample, on_plan=on_plan)
    wall.model().overridden(**settings.model_overrides)
    settings.imperfections.check_for(wall.brick, wall.source)
    folder = Path(folder)
    if (folder / SAMPLES_FOLDER).is_symlink():
        raise MonteCarloError(f"{folder / SAMPLES_FOLDER}: is a link; a run writes its samples in a folder of its own")
    (folder / SAMPLES_FOLDER).mkdir(parents=True, exist_ok=True)
    with hold_folder(folder):
        check_samples_kept(folder, settings)
        plan = pending_samples(folder, settings)
        if on_plan is not None:
            on_plan(plan)
        entries = dict(plan.recorded)
        summaries = SummaryWriter(folder, lambda: run_summary(target, wall, settings, entries))
        try:
            for index, record in _analysed(wall, settings, plan.todo, executor, in_flight):
                write_sample(folder, record)
                entries[index] = sample_entry(record["summary"])
                summaries.changed()
                if on_sample is not None:
                    on_sample(entries[index])
        finally:
            if summaries.stale:
                summaries.write()
    return MonteCarloOutcome(len(plan.todo), len(plan.recorded), tuple(plan.corrupt), summaries.summary)


def _analysed(wall: Wall, settings: MonteCarloSettings, todo: list[int], executor: Executor,
              in_flight: int | None) -> Iterator[tuple[int, dict]]:
    """(index, record) of each sample of ``todo`` as it finishes on ``executor``, at most
    ``in_flight`` submitted at a time (default: all); MonteCarloError if the executor loses one."""
    queue = iter(todo)
    window = in_flight or max(len(todo), 1)
    running: dict[Future, int] = {}
    while True:
        while len(running) < window and (index := next(queue, None)) is not None:
            running[executor.submit(run_sample, wall, settings, index)] = index
        if not running:
            return
        done, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in done:
            index = running.pop(future)
            try:
                record = future.result()
            except Exception as exc:
                raise MonteCarloError(f"sample {index} was lost by the executor ({type(exc).__name__}: {exc}); the samples "
                                      "finished are recorded: resume to go on") from exc
            yield index, record


#: the top summary is rewritten once the time since its last write is this many times what that
#: write took (:class:`SummaryWriter`)
SUMMARY_PACE = 10.0


class SummaryWriter:
    """A run's top summary (``build()``), written now and then again after a sample once the
    time since the last write is at least :data:`SUMMARY_PACE` times what that write took.

    The summary lists every sample, so it grows with each: written after every sample, a run
    of n samples would write n^2 / 2 entries (hours of a 10^5-sample run spent rewriting it).
    Paced, writing it takes under 1 / SUMMARY_PACE of the run; a small run's summary takes
    milliseconds, so it is still written after every sample. Between writes it lags the sample
    folders, which are the results (a resumed run reads them); :func:`monte_carlo` writes it at
    the end, however the run ends."""

    def __init__(self, folder: Path, build: Callable[[], dict]):
        self.folder, self.build = folder, build
        self.summary: dict = {}
        self.stale = True
        self.last = self.took = 0.0
        self.write()

    def changed(self) -> None:
        """A sample was added: write the summary if it is due."""
        self.stale = True
        if time.perf_counter() - self.last >= SUMMARY_PACE * self.took:
            self.write()

    def write(self) -> None:
        start = time.perf_counter()
        self.summary = self.build()
        write_summary(self.folder, self.summary)
        self.last = time.perf_counter()
        self.took, self.stale = self.last - start, False


def experiment(name: str) -> dict | None:
    """The experimental collapse angle of the paper's wall ``name`` (WD1-WD7; Savalle et al.
    2022, Table 1): ``mean_deg`` and ``cov`` (a fraction); None for another wall."""
    from drydem.masonry.published import savalle2022

    table = savalle2022()["table1_experiment"]
    if name not in table["collapse_angle_deg"]:
        return None
    return {"mean_deg": table["collapse_angle_deg"][name], "cov": table["cov_percent"][name] / 100.0}
