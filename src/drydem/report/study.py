"""The report of a parametric study (``drydem report RESULTS_DIR``), in the style of the seed
paper: its figures (3, 6, 9-13) and tables (2-4) from the study's run records (a sweep's, and
the folders of ``drydem tilt`` and ``drydem limit`` runs read as records:
:func:`drydem.parametric.records.run_folder_record`), drydem's values beside the paper's
(drydem.masonry.published), in Markdown and HTML with PNG figures; and when the study has
shake runs, their incremental dynamic analysis (:mod:`drydem.report.ida`); when it has runs
with a stress-dependent joint law, the calibrated law against the experiments
(:mod:`drydem.report.joints`); when it has Monte Carlo runs (``RESULTS/montecarlo/NAME/`` or
``RESULTS/NAME/``, each ``drydem montecarlo``'s folder), the scatter of their collapse angles
against the experiments'.

The paper's tables and figures are of constant joints: a run with a joint law is never taken
for the constant-kn run at its kn. They take the runs of the paper's walls as the paper ran
them (:func:`paper_wall`: a built-in WD1-WD7 at the paper's friction); every other tilting or
limit run (a wall or model file of the user's, even one named WD3.toml, drydem's other built-in
targets, a paper wall at another friction) is the user's: its own section (:func:`_yours`), with
its collapse and DLS angles and its pushover curves, and no published values beside them.
Without a run of the paper's walls, its tables and figures are left out.

A figure or table whose runs are missing says so instead of failing: a report can be built
from a study still running. A corrupt record is left out, and the report names its file.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drydem.analysis.drift import DLS_DRIFT, EC8_DRIFT_LIMITS
from drydem.errors import DrydemError
from drydem.masonry.published import savalle2022
from drydem.model.parameters import Range
from drydem.parametric.limits import MAX_SAMPLES
from drydem.parametric.records import (ANGLE, SUMMARY_FILE, RecordError, Records, load_records, load_run_folders, read_json, run_folders,
                                       table_problems)
from drydem.parametric.study import ID_PART_CHARACTERS
from drydem.files import replaceable, replaced_atomically, writable_folder
from drydem.io.results import being_written
from drydem.report.joints import joint_law, law_words, relative_error_percent
from drydem.report.plots import new_figure, plain_text

DESIGNS = [f"WD{k}" for k in range(1, 8)]
#: the paper's grouping of the pushover figures
PUSHOVER_FIGURES = {"fig09_pushover": ["WD1", "WD2"], "fig10_pushover": ["WD3", "WD4"], "fig11_pushover": ["WD5", "WD6", "WD7"]}
POINTS = 4  # the paper's contact density for its parametric study
LAWS_TITLE = "Stress-dependent joints: the calibrated law against the experiments and kn = ks = 3e7"
MONTECARLO_FOLDER = "montecarlo"
MONTECARLO_TITLE = "Monte Carlo scatter of the collapse angle"
#: the statistics of a Monte Carlo summary's collapse angle the report shows (count aside)
MONTECARLO_STATISTICS = ("mean", "std", "cov", "p05")
#: the rules of those statistics (:func:`drydem.parametric.montecarlo.statistics`), each null
#: where there is none, but the count: samples, at most those of a run (MAX_SAMPLES,
#: drydem.parametric.limits); the angles' mean, std and p05 in [0, 90] deg; their CoV (std /
#: mean, ddof = 1) at most sqrt(count)
MONTECARLO_RULES = {"count": Range(0, MAX_SAMPLES, integer=True), "mean": ANGLE, "std": ANGLE, "cov": Range(0.0, math.sqrt(MAX_SAMPLES)),
                    "p05": ANGLE}
MONTECARLO_NOTE = (
    "Each row a `drydem montecarlo` run (its folder, NAME, in montecarlo/ or in the results folder): the statistics of its "
    "collapse angles over the samples with a verdict, "
    "a sample that cannot stand under its own weight counting as 0 deg (samples: how many; std with ddof = 1; p05 the 5th "
    "percentile), with the imperfections drawn; experiment: the mean and CoV "
    "of the wall's tests (Savalle et al. 2022, Table 1; '-': not one of its walls).")
YOURS = "Your targets"
YOURS_TITLE = f"{YOURS}: runs without published values"
YOURS_NOTE = (
    "Runs of targets the paper did not analyse (wall, model and geometry files, named by file; drydem's other built-in "
    "targets), and of its walls at a friction other than its {friction:g} or tilted otherwise than its test (another stop "
    "displacement, maximum angle, loading, tilt axis, monitored block or lost-block rule): drydem's results alone, with no "
    "published values to compare them with. kn, ks, friction, points: the run's overrides, else its model's as recorded "
    "('-': not recorded). "
    "Collapse angle: the last tilt in equilibrium; '>= X': no equilibrium within max_cycles after X deg (or that step's "
    "integration diverged), and no collapse either (a lower bound); 'none up to X': no collapse up to the run's maximum "
    "angle, X deg (a lower bound); 'cannot stand': the model falls under its own weight. DLS: the tilt at which the monitored "
    "drift first reaches 1 % (EN 1998-1 4.4.3.2, the paper's damage limit state); '-': never before the collapse.")
NO_PAPER_RUNS = ("No run of the paper's walls (the built-in WD1-WD7 at its friction): its tables and figures are left out.")
NOTE = ("drydem's WD1-WD7 are reconstructions that obey the competition brief, not the original drawings "
        "(which drydem does not have): compare trends and rankings, not single numbers.")


def paper_wall(record: dict) -> str | None:
    """The paper's wall (WD1-WD7) a run analyses as the paper did, so that its published values
    compare: its target is the built-in wall's name (case aside, as
    :func:`drydem.masonry.designs.find` reads it; a file is the user's, whatever its name), its
    friction the paper's (None: the wall's own, which is the paper's) and its test the paper's
    (:func:`is_paper_test`). None for every other run."""
    spec = record["spec"]
    design = next((d for d in DESIGNS if d.lower() == str(spec["target"]).lower()), None)
    friction = spec.get("friction")
    paper_friction = friction is None or _close(friction, savalle2022()["wall"]["friction"])
    return design if paper_friction and is_paper_test(record) else None


#: the tilting settings (:class:`~drydem.analysis.tilt.TiltSettings`) that make the paper's test
#: when they are their defaults: the table tilted about y to the collapse, the top block's
#: displacement monitored up to the 0.10 m stop. The increment and protocol only change how
#: closely the collapse is found (:func:`_preferred` picks among runs)
PAPER_TEST = ("stop_displacement_m", "loading", "tilt_axis", "monitor", "max_angle_deg", "lost_drop_heights")


def is_paper_test(record: dict) -> bool:
    """Whether a run is of the paper's test: no setting of :data:`PAPER_TEST` changed
    (:func:`changed_test_settings`). Found by a hunt: a WD3 run stopped at 2 mm of displacement,
    "collapsed" at 10.0 deg, was compared with the paper's 20 deg."""
    return not changed_test_settings(record)


def changed_test_settings(record: dict) -> dict:
    """The settings of :data:`PAPER_TEST` in which a tilting run's, as its summary records them
    (``analysis``), are not the defaults: {setting: value}; {} for another analysis, and for a
    run that records none (a sweep's runs have no others)."""
    from drydem.analysis.tilt import TiltSettings

    settings = (record.get("summary") or {}).get("analysis")
    if record["spec"]["analysis"] != "tilt" or not isinstance(settings, dict):
        return {}
    default = TiltSettings()
    return {key: settings[key] for key in PAPER_TEST if key in settings and not _same(settings[key], getattr(default, key))}


def _same(value, default) -> bool:
    """A recorded setting equals its default: numbers to round-off, anything else exactly."""
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (value, default))
    return _close(value, default) if numbers else value == default


def angle_text(summary: dict) -> str:
    """A tilting run's collapse angle for a table: the angle (deg); ">= X" for a run that found
    no equilibrium within max_cycles past its last one (X deg), or diverged there, and no
    collapse either (a lower bound, no verdict); "none up to X" for a run that reached its
    maximum angle, X deg, standing (a lower bound too); "cannot stand" for a model that falls
    under its own weight; "-" else (a run without equilibrium that records no last one). The
    angles are checked when the record is read (:data:`drydem.parametric.records.SUMMARY_RULES`)."""
    from drydem.analysis.tilt import DIVERGED, MAXIMUM_ANGLE, NO_EQUILIBRIUM

    bound = summary.get("last_equilibrium_deg", summary["collapse_angle_deg"])  # earlier versions gave it as the collapse angle
    if summary.get("ended_by") in (NO_EQUILIBRIUM, DIVERGED) and bound is not None:
        return f">= {bound:.1f}"
    if summary.get("ended_by") == MAXIMUM_ANGLE and bound is not None:
        return f"none up to {bound:.1f}"
    if summary.get("collapse_angle_deg") is None and summary.get("stable_under_gravity") is False:
        return "cannot stand"
    return _cell(summary.get("collapse_angle_deg"))


def dls_angle(summary: dict) -> float | None:
    """A tilting run's DLS angle (deg): the tilt at 1 % drift (:data:`drydem.analysis.drift.DLS_DRIFT`), None if never reached."""
    return summary["drift_limit_angles_deg"].get(repr(DLS_DRIFT))


class Runs:
    """The ok records of a study, looked up by what they are."""

    def __init__(self, records: list[dict]):
        self.ok = [r for r in records if r["status"] == "ok"]
        self.failed = [r for r in records if r["status"] != "ok"]

    def tilts(self, design: str, *, protocol: str | None = None) -> list[dict]:
        """The tilting runs of ``design`` with constant joints (no joint law: those are
        :mod:`drydem.report.joints`'), of ``protocol`` when given."""
        return [r for r in self.ok if r["spec"]["analysis"] == "tilt" and joint_law(r) is None and paper_wall(r) == design
                and (protocol is None or r["spec"]["protocol"] == protocol)]

    def tilt(self, design: str, kn: float, *, ks: float | None = None, points: int = POINTS, protocol: str | None = None) -> dict | None:
        """The tilting run of ``design`` at constant kn (ks = kn by default): of several,
        :func:`_preferred`'s first."""
        ks = kn if ks is None else ks
        found = [r for r in self.tilts(design, protocol=protocol)
                 if _close(r["spec"]["kn"], kn) and _close(r["spec"]["ks"], ks) and r["spec"]["points"] in (points, None)]
        return min(found, key=_preferred) if found else None

    def left_out(self) -> list[dict]:
        """The constant-joint tilting runs of the paper's walls that no table or figure shows:
        :meth:`tilt` gives another for the run's own wall, kn, ks, points and protocol (one
        preferred, :func:`_preferred`), or none (a run without its kn recorded)."""
        return [r for r in self.ok if r["spec"]["analysis"] == "tilt" and joint_law(r) is None and paper_wall(r) is not None
                and self._shown(r) is not r]

    def _shown(self, record: dict) -> dict | None:
        spec = record["spec"]
        if spec["kn"] is None:
            return None
        return self.tilt(paper_wall(record), spec["kn"], ks=spec["ks"], points=spec["points"] or POINTS, protocol=spec["protocol"])

    def angle(self, design: str, kn: float, **kw) -> float | None:
        run = self.tilt(design, kn, **kw)
        return None if run is None else run["summary"]["collapse_angle_deg"]

    def angle_cell(self, design: str, kn: float) -> str:
        """The collapse angle for a table (:func:`angle_text`), "-" without the run."""
        run = self.tilt(design, kn)
        return "-" if run is None else angle_text(run["summary"])

    def capacity(self, design: str, kn: float) -> float | None:
        """The angle the objective of the calibration uses (:func:`drydem.parametric.calibrate.wall_angle`:
        0 for a wall that cannot stand, None for no verdict)."""
        from drydem.parametric.calibrate import wall_angle

        run = self.tilt(design, kn)
        return None if run is None else wall_angle(run["summary"])

    def dls(self, design: str, kn: float) -> float | None:
        run = self.tilt(design, kn)
        return None if run is None else dls_angle(run["summary"])

    def limit(self, design: str, method: str) -> float | None:
        found = [r for r in self.ok if r["spec"]["analysis"] == "limit" and paper_wall(r) == design and r["summary"]["method"] == method]
        return found[0]["summary"]["collapse_angle_deg"] if found else None

    def stiffnesses(self, design: str, *, protocol: str | None = None) -> list[float]:
        """The kn of the constant-joint tilting runs of ``design`` with ks = kn, sorted."""
        return sorted({r["spec"]["kn"] for r in self.tilts(design, protocol=protocol)
                       if r["spec"]["kn"] is not None and _close(r["spec"]["ks"], r["spec"]["kn"])})


def _preferred(record: dict) -> tuple:
    """The order in which tilting runs of one wall and joints are shown: adaptive before fixed
    (both find the collapse angle within one increment), then the finest increment, then by
    id (not by the order the folders were found in)."""
    spec = record["spec"]
    return spec["protocol"] != "adaptive", spec["increment_deg"] or math.inf, record["id"]


def _close(a, b) -> bool:
    return a is not None and b is not None and math.isclose(a, b, rel_tol=1e-9)


class ReportError(DrydemError):
    """No report can be made of the folder given."""


@dataclass(frozen=True)
class Report:
    """The report's files, the errors of the records left out (each naming its file), and how
    many runs it reports (records and Monte Carlo runs)."""

    markdown: Path
    html: Path
    corrupt: list[RecordError]
    reported: int


def build_report(results: Path, out: Path | None = None, *, overwrite: bool = False) -> Report:
    """Write ``report.md``, ``report.html`` and ``figures/*.png`` for the runs in ``results``: a
    sweep's records (``runs/``), the folders of ``drydem tilt`` and ``drydem limit`` runs (itself
    and its sub-folders: :func:`~drydem.parametric.records.load_run_folders`) and Monte Carlo
    runs (:func:`montecarlo_summaries`); ReportError if it holds none of them. The paper's
    tables and figures only when a run is of one of its walls (:func:`paper_wall`). A report
    drydem wrote before is replaced (it is made from the records again); another file of its
    name only with ``overwrite`` (:func:`_report_files`)."""
    import markdown

    results = Path(results)
    swept, folders, summaries = load_records(results), load_run_folders(results), montecarlo_summaries(results)
    if not ((results / "runs").is_dir() or folders.valid or folders.corrupt or summaries):
        other = next((folder / SUMMARY_FILE for folder in run_folders(results) if (folder / SUMMARY_FILE).is_file()), None)
        running = [folder for folder in run_folders(results) if being_written(folder)]  # found by a hunt: not said
        raise ReportError(f"{results}: nothing to report: no runs/ folder (`drydem sweep STUDY --out {results}` writes one) and no "
                          f"folder of a finished `drydem tilt`, `drydem limit` or `drydem montecarlo` run (its {SUMMARY_FILE})"
                          + ("" if other is None else f"; {other} is of another analysis (a `drydem shake` run's folder is its "
                                                      "own report: summary.json, history.csv, history.png; a sweep's shake runs are reported)")
                          + ("" if not running else f"; a drydem run is writing in {', '.join(map(str, running))}: report it once it "
                                                    "has finished"))
    records = Records(swept.valid + folders.valid, swept.corrupt + folders.corrupt)
    runs, (monte_carlo, unreadable) = Runs(records.valid), montecarlo_runs(summaries)
    out = writable_folder(out or results / "report")
    markdown_path, html_path = _report_files(out, overwrite)
    figures = _figures_folder(out, overwrite)
    paper = savalle2022()
    of_paper = any(paper_wall(r) is not None for r in records.valid if r["spec"]["analysis"] in ("tilt", "limit"))
    counted = f"{len(runs.ok)} runs recorded ({len(runs.failed)} failed)" + (
        f", {len(folders.valid)} of them in the folders of `drydem tilt` and `drydem limit` runs" if folders.valid else "")
    about = f"{NOTE} Published values: {paper['source'].split(' - ')[0]}." if of_paper else NO_PAPER_RUNS
    sections = [
        f"# Report of the study in {_code(results)}",
        f"{counted}. {about}",
        *([_corrupt(records.corrupt)] if records.corrupt else []),
        *_others([f for f in folders.other if f / SUMMARY_FILE not in summaries]),
        *_yours(records.valid, figures, paper),
        *(_paper_tables(runs, paper) if of_paper else []),
        *_laws(records.valid, runs),
        *(_paper_figures(figures, runs, paper) if of_paper else []),
        *(_ida(figures, runs) if any(r["spec"]["analysis"] == "shake" for r in records.valid) else []),
        *_montecarlo(monte_carlo, unreadable, figures, paper),
    ]
    text = "\n\n".join(sections) + "\n"
    _write(markdown_path, text)
    body = markdown.markdown(text, extensions=["tables"])
    _write(html_path, f"{REPORT_STARTS['report.html']}<style>table{{border-collapse:collapse}}td,th{{border:1px solid #999;padding:2px 6px}}"
                      f"</style></head><body>\n{body}\n</body></html>\n")
    return Report(markdown_path, html_path, records.corrupt, len(records.valid) + len(monte_carlo))


#: how the files of a report drydem writes begin: a file there that does not is someone else's
REPORT_STARTS = {"report.md": "# Report of the study in `",
                 "report.html": "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>drydem report</title>"}


def _report_files(out: Path, overwrite: bool) -> tuple[Path, Path]:
    """``out``/report.md and report.html, once each may be written: nothing there, a report
    drydem wrote (it begins as REPORT_STARTS says), or, with ``overwrite``, another regular file
    (:func:`~drydem.files.replaceable`; a link or a pipe is never written through); checked
    before any figure is drawn."""
    found = [path if _ours(path) else replaceable(path, overwrite, other="another --out") for path in (out / name for name in REPORT_STARTS)]
    return found[0], found[1]


def _ours(path: Path) -> bool:
    """Whether ``path`` is a report file drydem wrote: a regular file (no link) that begins as
    REPORT_STARTS says for its name (its first bytes only are read)."""
    head = REPORT_STARTS[path.name].encode()
    if not path.is_file() or path.is_symlink():
        return False
    with path.open("rb") as f:
        return f.read(len(head)) == head


def _figures_folder(out: Path, overwrite: bool) -> Path:
    """``out``/figures, made if missing: a drydem report's figures, replaced by this one's. A
    figures folder holding files where no report of drydem's is (report.md) is someone else's:
    ReportError naming it, unless ``overwrite`` (then only the report's own figure names are
    written; the other files are kept)."""
    figures = out / "figures"
    present = sorted(p.name for p in figures.iterdir()) if figures.is_dir() else []
    if present and not overwrite and not _ours(out / "report.md"):
        listed = ", ".join(present[:3]) + (", ..." if len(present) > 3 else "")
        raise ReportError(f"{figures}: holds files of no drydem report ({listed}); pass --overwrite to write the report's figures "
                          "there (files of other names are kept), or give another --out")
    figures.mkdir(parents=True, exist_ok=True)
    return figures


def _paper_tables(runs: Runs, paper: dict) -> list[str]:
    """The paper's Tables 2-4, drydem's values beside the published ones, then the runs of its
    walls they leave out (:meth:`Runs.left_out`), named."""
    left_out = runs.left_out()
    shown = ("Also recorded, in no table or figure (another run of the same wall, joints, points and protocol is shown: "
             "adaptive, then the finest increment, preferred):\n\n"
             + "\n".join(f"- {_code(r['id'])}: {paper_wall(r)}, {_joints(r)}, {r['spec']['protocol']}, increment "
                          f"{_cell(r['spec']['increment_deg'], '{:g}')} deg: collapse angle {angle_text(r['summary'])} deg"
                          for r in left_out))
    return [_table2(runs, paper), _table3(runs, paper), _table4(runs, paper), *([shown] if left_out else [])]


def _paper_figures(figures: Path, runs: Runs, paper: dict) -> list[str]:
    """The paper's Figs 3, 6, 9-13 drawn from the runs (each says so where it has none)."""
    return [
        _figure(figures, "fig03_contact_points", "Fig. 3: collapse angle of WD3 against contact points per length, kn = 3e7",
                lambda ax: _contact_points(ax, runs)),
        _figure(figures, "fig06_stiffness", "Fig. 6: collapse angle over the experimental one against kn = ks; grey: the experiments' mean CoV",
                lambda ax: _stiffness(ax, runs, paper)),
        *(_figure(figures, name, f"Figs 9-11: pushover curves of {', '.join(designs)} (fixed protocol), EC8 drift limits dashed",
                  lambda axes, designs=designs: _pushover(axes, runs, designs), panels=len(designs)) for name, designs in PUSHOVER_FIGURES.items()),
        _figure(figures, "fig12_dls", "Fig. 12: tilt angle at 1 % drift (damage limit state) against kn = ks", lambda ax: _dls(ax, runs)),
        _figure(figures, "fig13_ks", "Fig. 13: WD6, influence of ks on the pushover curve (panels: kn)", lambda axes: _ks(axes, runs), panels=4),
    ]


def _write(path: Path, text: str) -> None:
    """``text`` written to ``path`` whole or not at all (:func:`~drydem.files.replaced_atomically`)."""
    with replaced_atomically(path) as partial:
        partial.write_text(text, encoding="utf-8")


def _ida(figures: Path, runs: Runs) -> list[str]:
    """The sections of the study's shake runs (:mod:`drydem.report.ida`): the collapse table
    and the IDA figure."""
    from drydem.report.ida import FIGURE_CAPTION, TABLE_NOTE, TABLE_TITLE, collapse_table, draw_ida, ida_curves

    curves = ida_curves(runs.ok)
    failed = sum(r["spec"]["analysis"] == "shake" for r in runs.failed)
    note = f"\n\n{failed} failed shake runs left out." if failed else ""
    return [_table(TABLE_TITLE, *collapse_table(curves)) + f"\n\n{TABLE_NOTE}{note}",
            _figure(figures, "ida_rotation", FIGURE_CAPTION, lambda ax: draw_ida(ax, curves))]


def _laws(records: list[dict], runs: Runs) -> list[str]:
    """The section of the runs with a stress-dependent joint law (:mod:`drydem.report.joints`),
    none without such runs: the calibrated law's collapse angles beside the experiments' and
    those at constant kn = ks = 3e7 (:meth:`Runs.capacity`, counted as the calibration counts)."""
    from drydem.parametric.calibrate import experimental_angles
    from drydem.report.joints import calibrated, law_caption, law_evaluations, law_table

    evaluations = law_evaluations(records)
    if not evaluations:
        return []
    experiment = experimental_angles()
    best = calibrated(evaluations, experiment)
    caption = law_caption(evaluations, best, experiment)
    if best is None:
        return [f"## {LAWS_TITLE}\n\n{caption}"]
    constant = {d: runs.capacity(d, 3e7) for d in experiment if runs.tilt(d, 3e7) is not None}
    return [_table(LAWS_TITLE, *law_table(best, constant, experiment)) + f"\n\n{caption}"]


#: where a run's summary records the settings of its model (:func:`drydem.io.results.model_summary`)
MODEL_SETTINGS = {"kn": ("joint", "kn"), "ks": ("joint", "ks"), "friction": ("joint", "friction"),
                  "points": ("contacts", "points_per_length")}


def _recorded(record: dict, table: str) -> dict:
    """A table of the run's model as its summary records it ({} for a failed run or a record without it)."""
    return ((record.get("summary") or {}).get("model") or {}).get(table) or {}


def _setting(record: dict, key: str):
    """The run's ``key`` (:data:`MODEL_SETTINGS`): its override, else its model's as recorded; None if neither says."""
    value = record["spec"].get(key)
    table, name = MODEL_SETTINGS[key]
    return _recorded(record, table).get(name) if value is None else value


def _joints(record: dict) -> str:
    """The run's joint stiffness in words (:func:`law_words`: kn, ks, the law if not constant), as
    its model records it, else from its overrides; "-" where neither gives kn and ks."""
    kn, ks = _setting(record, "kn"), _setting(record, "ks")
    if kn is None or ks is None:
        return "-"
    joint = {key: value for key, value in _recorded(record, "joint").items() if key not in ("kn", "ks")}
    return law_words(json.dumps(joint) if joint else joint_law(record) or "{}", kn, ks)


def _settings(record: dict) -> dict[str, str]:
    """The settings of one of the user's tilting runs, in words, by column of its table."""
    spec = record["spec"]
    friction, points = _setting(record, "friction"), _setting(record, "points")
    return {"joints": _joints(record), "friction": _cell(friction, "{:g}"), "points": _cell(points, "{:g}"),
            "protocol": spec["protocol"] + _test_words(record), "increment (deg)": _cell(spec["increment_deg"], "{:g}")}


def _test_words(record: dict) -> str:
    """The settings in which a tilting run is not the paper's test (:func:`changed_test_settings`), in
    words after its protocol (" (stop_displacement_m 0.002)"), "" for none."""
    changed = ", ".join(f"{key} {value:g}" if isinstance(value, float) else f"{key} {value}"
                        for key, value in changed_test_settings(record).items())
    return f" ({changed})" if changed else ""


def _target_labels(records: list[dict]) -> dict[str, str]:
    """Each target's name in the report: its file's name (a built-in's name), or where targets
    share it, the shortest ending of its path that no other target has (``a/pier.toml``)."""
    targets = sorted({r["spec"]["target"] for r in records})

    def ending(target: str, parts: int) -> str:
        return "/".join(Path(target).parts[-parts:])

    labels = {}
    for target in targets:
        parts = 1
        while parts < len(Path(target).parts) and sum(ending(t, parts) == ending(target, parts) for t in targets) > 1:
            parts += 1
        labels[target] = ending(target, parts)
    return labels


def _yours(records: list[dict], figures: Path, paper: dict) -> list[str]:
    """The sections of the user's runs (module docstring), none without any: the tilting and
    limit runs that :func:`paper_wall` leaves out of the paper's tables, in a table each (the
    collapse and DLS angles; the limit angle and multiplier), the failed ones named with their
    errors, and per target a figure of its pushover curves, with the EC8 drift limits."""
    mine = [r for r in records if r["spec"]["analysis"] in ("tilt", "limit") and paper_wall(r) is None]
    if not mine:
        return []
    labels = _target_labels(mine)
    mine.sort(key=lambda r: (labels[r["spec"]["target"]], r["spec"]["analysis"], [_setting(r, k) or 0 for k in MODEL_SETTINGS],
                             r["spec"]["protocol"], r["spec"]["increment_deg"] or 0))
    ok = [r for r in mine if r["status"] == "ok"]
    tilts, limits = ([r for r in ok if r["spec"]["analysis"] == analysis] for analysis in ("tilt", "limit"))
    failed = [r for r in mine if r["status"] != "ok"]
    intro = (f"## {YOURS_TITLE}\n\nTargets: {len(labels)} ({', '.join(_code(label) for label in sorted(labels.values()))}); "
             f"tilting runs: {len(tilts)}; limit analyses: {len(limits)}; failed runs: {len(failed)}."
             f"\n\n{YOURS_NOTE.format(friction=paper['wall']['friction'])}")
    if failed:
        intro += "\n\nFailed runs:\n\n" + "\n".join(f"- {_code(r['id'])}: {_md(r['error'])}" for r in failed)
    sections = [intro]
    if tilts:
        rows = [[labels[r["spec"]["target"]], *_settings(r).values(), angle_text(r["summary"]), _cell(dls_angle(r["summary"]))]
                for r in tilts]
        header = ["target", *_settings(tilts[0]), "collapse angle (deg)", "DLS angle, 1 % drift (deg)"]
        sections.append(_table(f"{YOURS}: tilting runs", header, rows))
    if limits:
        rows = [[labels[r["spec"]["target"]], _cell(_setting(r, "friction"), "{:g}"), r["summary"]["method"],
                 _cell(r["summary"]["collapse_angle_deg"]), _cell(r["summary"].get("load_multiplier"), "{:.4g}")] for r in limits]
        sections.append(_table(f"{YOURS}: limit analyses",
                               ["target", "friction", "method", "collapse angle (deg)", "load multiplier"], rows))
    for k, target in enumerate(dict.fromkeys(r["spec"]["target"] for r in tilts if r["pushover"])):
        curves = [r for r in tilts if r["spec"]["target"] == target and r["pushover"]]
        name = "yours{}_{}_pushover".format(k + 1, _file_part(Path(target).name))
        sections.append(_figure(figures, name, f"{YOURS}: pushover curves of {_md(labels[target])}, EC8 drift limits dashed",
                                lambda ax, curves=curves: _run_curves(ax, curves)))
    return sections


def _file_part(name: str) -> str:
    """``name`` as a part of a figure's file name: ASCII letters, digits, - and _ (anything else
    a -), at most ID_PART_CHARACTERS of them, the length of a name in the runs' ids (a target of
    245 characters gave a figure name past the system's 255 bytes, and no report)."""
    return "".join(c if (c.isascii() and c.isalnum()) or c in "-_" else "-" for c in name)[:ID_PART_CHARACTERS]


def _run_curves(ax, runs: list[dict]) -> bool:
    """The pushover curves of ``runs`` (one target's), each labelled by the settings that differ
    between them, and the EC8 drift limits of the target's height."""
    settings = [_settings(r) for r in runs]
    differ = [key for key in settings[0] if len({s[key] for s in settings}) > 1] or ["protocol"]
    for run, setting in zip(runs, settings):
        _plot_pushover(ax, run, ", ".join(setting[key] if key in ("joints", "protocol") else f"{key} {setting[key]}" for key in differ))
    _drift_lines(ax, runs[-1]["summary"]["wall_height_m"])
    ax.set(xlabel="monitored displacement since 0 deg (mm)", ylabel="tilt (deg)", xlim=(0, None))
    _legend(ax)
    return True


@dataclass(frozen=True)
class MonteCarloRun:
    """One ``drydem montecarlo`` run of the study (``RESULTS/montecarlo/NAME/summary.json``):
    its folder's ``name``, its ``wall`` (the summary's target), the ``collapse`` angle's
    statistics (:func:`drydem.parametric.montecarlo.statistics`: count, mean, std, cov, p05 in deg
    or a fraction, None where there is none) and its ``imperfections`` in words."""

    name: str
    wall: str
    collapse: dict
    imperfections: str


def read_montecarlo(path: Path) -> MonteCarloRun:
    """The Monte Carlo run whose top summary is ``path``; RecordError naming the file, and the
    field and its rule, when it cannot be read as one: its target's name a string, its collapse
    angle's statistics within :data:`MONTECARLO_RULES`, its imperfections those of
    :class:`~drydem.masonry.imperfections.Imperfections`."""
    summary = read_json(Path(path), "Monte Carlo summary")
    stats, name, settings = (_json_table(summary, key) for key in ("collapse_angle_deg", "target", "settings"))
    if stats is None or not isinstance((name or {}).get("name"), str) or _json_table(settings, "imperfections") is None:
        raise RecordError(f"{path}: not a drydem montecarlo summary: it needs its target's name, its settings' imperfections "
                          "and its collapse_angle_deg statistics (tables)")
    problems = table_problems(stats, MONTECARLO_RULES, "collapse_angle_deg", optional=MONTECARLO_STATISTICS)
    if problems:
        raise RecordError(f"{path}: {'; '.join(problems)}")
    collapse = {key: stats.get(key) for key in MONTECARLO_RULES}  # a statistic may be absent (none)
    return MonteCarloRun(Path(path).parent.name, name["name"], collapse, _imperfections(path, settings["imperfections"]))


def _json_table(summary, key: str) -> dict | None:
    """The table ``key`` of a JSON object ``summary``, None if either is not a table."""
    table = summary.get(key) if isinstance(summary, dict) else None
    return table if isinstance(table, dict) else None


def _imperfections(path: Path, settings: dict) -> str:
    """The imperfections of a Monte Carlo summary's settings in words; RecordError naming the file
    if they are not :class:`~drydem.masonry.imperfections.Imperfections`' (unknown keys, values out of range)."""
    from drydem.masonry.imperfections import Imperfections

    try:
        return str(Imperfections(**settings))
    except (TypeError, DrydemError) as exc:
        raise RecordError(f"{path}: settings imperfections: {exc}") from None


def montecarlo_summaries(results: Path) -> list[Path]:
    """The top summaries of the Monte Carlo runs in ``results``: a study's (``montecarlo/*/``)
    and the folders of ``drydem montecarlo --out`` runs among ``results`` and its sub-folders
    (a summary.json beside a samples/ folder)."""
    results = Path(results)
    kept = sorted((results / MONTECARLO_FOLDER).glob(f"*/{SUMMARY_FILE}"))
    made = [folder / SUMMARY_FILE for folder in run_folders(results) if (folder / "samples").is_dir() and (folder / SUMMARY_FILE).is_file()]
    return kept + made


def montecarlo_runs(summaries: list[Path]) -> tuple[list[MonteCarloRun], list[str]]:
    """The Monte Carlo runs of ``summaries`` (:func:`montecarlo_summaries`), by wall then folder,
    and the summaries that cannot be read, each named with its fault."""
    found, unreadable = [], []
    for path in summaries:
        try:
            found.append(read_montecarlo(path))
        except RecordError as exc:
            unreadable.append(str(exc))
    return sorted(found, key=lambda run: (run.wall, run.name)), unreadable


def _montecarlo(found: list[MonteCarloRun], unreadable: list[str], figures: Path, paper: dict) -> list[str]:
    """The section of the study's Monte Carlo runs (:func:`montecarlo_runs`), none without any:
    per run, the statistics of its computed collapse angles (from its summary.json: the samples
    that found one) and its imperfections, beside the experimental mean and CoV of its wall (the
    paper's Table 1); the figure of the CoVs; the summaries that cannot be read, named."""
    if not found and not unreadable:
        return []
    experiment = paper["table1_experiment"]
    rows = [[run.wall, run.name, str(run.collapse["count"]), _cell(run.collapse["mean"], "{:.2f}"), _cell(run.collapse["std"], "{:.2f}"),
             _cell(None if run.collapse["cov"] is None else 100 * run.collapse["cov"]), _cell(run.collapse["p05"], "{:.2f}"),
             run.imperfections, _cell(experiment["collapse_angle_deg"].get(run.wall)), _cell(experiment["cov_percent"].get(run.wall))]
            for run in found]
    header = ["wall", "run", "samples", "mean (deg)", "std (deg)", "CoV (%)", "p05 (deg)", "imperfections", "experiment (deg)",
              "experiment CoV (%)"]
    text = _table(MONTECARLO_TITLE, header, rows) + f"\n\n{MONTECARLO_NOTE}"
    if unreadable:
        text += (f"\n\n{len(unreadable)} Monte Carlo summaries cannot be read, left out:\n\n"
                 + "\n".join(f"- {_code(u)}" for u in unreadable))
    if not found:
        return [text]
    return [text, _figure(figures, "montecarlo_cov", "Monte Carlo: CoV of the computed collapse angle (imperfect walls) against the "
                          "experiments' (Table 1), per run", lambda ax: _cov_bars(ax, found, experiment))]


def _cov_bars(ax, found: list[MonteCarloRun], experiment: dict) -> bool:
    """Bars: each Monte Carlo run's CoV of the collapse angle beside its wall's experimental CoV
    (%); a run of a wall without an experiment (a user's) has its bar alone, centred on its tick,
    and the experiment is in the legend only if one is drawn (found by a hunt: such a run's tick
    sat at its bar's edge, beside an "experiment" entry with no bar)."""
    walls = [run.wall for run in found]
    labels = [run.wall if walls.count(run.wall) == 1 else f"{run.wall}\n{run.name}" for run in found]
    computed = np.array([np.nan if run.collapse["cov"] is None else 100 * run.collapse["cov"] for run in found])
    measured = np.array([experiment["cov_percent"].get(run.wall, np.nan) for run in found])
    x = np.arange(len(found))
    paired = ~np.isnan(measured)
    ax.bar(x - 0.2 * paired, computed, np.where(paired, 0.4, 0.6), label="drydem (imperfections)")
    if paired.any():
        ax.bar(x[paired] + 0.2, measured[paired], 0.4, label="experiment")
    ax.set(xticks=x, ylabel="CoV of the collapse angle (%)")
    ax.set_xticklabels(labels, fontsize="small")
    _legend(ax)
    return not np.all(np.isnan(computed))


def _others(folders: list[Path]) -> list[str]:
    """The paragraph naming the run folders of other analyses, left out (found by a hunt: a
    shake run's folder beside tilting runs was left out without a word); none without any."""
    if not folders:
        return []
    return [f"{len(folders)} run folder(s) of another analysis left out (a `drydem shake` run's folder is its own report: "
            f"summary.json, history.csv, history.png; a sweep's shake runs are reported): {', '.join(map(_code, folders))}"]


def _corrupt(errors: list[RecordError]) -> str:
    """The paragraph naming the records left out, each with its file and fault."""
    lines = "\n".join(f"- {_code(error)}" for error in errors)
    return (f"{len(errors)} corrupt records left out (a sweep's are run again by the same `drydem sweep`; a run folder's, by "
            f"its command with --overwrite):\n\n{lines}")


def _cell(value: float | None, fmt: str = "{:.1f}") -> str:
    return "-" if value is None else fmt.format(value)


def _table(title: str, header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table; its cells (names, numbers) shown as written (:func:`_md`)."""
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(map(_md, row)) + " |" for row in rows])


def _md(text) -> str:
    """``text`` (a name, a path, a message) as Markdown that shows it as written, in report.md
    and in report.html: & and < as entities and Markdown's characters escaped (found
    by a hunt: a target named a|b.toml moved the values of its row into the wrong columns, and
    one named with an <img onerror=...> tag put the tag into report.html)."""
    text = str(text).replace("&", "&amp;").replace("<", "&lt;")  # no tag begins without a <
    return re.sub(r"([\\`*|])", r"\\\1", text).replace("](", "]\\(")  # [text](url) is no link: a [joint] stays as written


def _code(text) -> str:
    """``text`` as a Markdown code span (which Markdown shows as written, HTML escaped), fenced
    by more backticks than it holds in a row."""
    text = str(text)
    fence = "`" * (max((len(run) for run in re.findall("`+", text)), default=0) + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def _table2(runs: Runs, paper: dict) -> str:
    published = paper["table2_collapse_angle_deg"]
    rows = []
    for d in DESIGNS:
        exp, la_a, la_na, dem9, dem10 = published[d]
        ours = [_cell(runs.limit(d, "associative")), _cell(runs.limit(d, "non-associative")), runs.angle_cell(d, 1e9), runs.angle_cell(d, 1e10)]
        rows.append([d, _cell(exp)] + [f"{_cell(p)} / {o}" for p, o in zip((la_a, la_na, dem9, dem10), ours)])
    return _table("Table 2: collapse angles (deg), paper / drydem",
                  ["wall", "experiment", "LA-A", "LA-NA", "DEM kn = 1e9", "DEM kn = 1e10"], rows) + (
        "\n\nA cell '>= X': no equilibrium within max_cycles at the step after X deg (or that step's integration diverged), "
        "and no collapse either: a lower bound; "
        "'none up to X': no collapse up to the run's maximum angle, X deg.")


def _table3(runs: Runs, paper: dict) -> str:
    experiment = paper["table1_experiment"]["collapse_angle_deg"]
    published = paper["table3_kn_3e7"]
    rows, errors = [], []
    for d in DESIGNS:
        ours = runs.angle(d, 3e7)
        error = relative_error_percent(ours, experiment[d])
        if error is not None:
            errors.append(abs(error))
        rows.append([d, _cell(experiment[d]), _cell(published["numerical_collapse_angle_deg"][d]), _cell(ours),
                     _cell(published["relative_error_percent"][d], "{:+.1f}"), _cell(error, "{:+.1f}")])
    mean = np.mean(errors) if errors else None
    # over the walls with a run only: a mean of one wall beside the paper's of seven read as a better fit
    over = "" if len(errors) in (0, len(DESIGNS)) else f" ({len(errors)} of {len(DESIGNS)} walls)"
    rows.append(["mean absolute", "", "", "", _cell(published["mean_abs_error_percent"]), _cell(mean) + over])
    return _table("Table 3: kn = ks = 3e7 against the experiments",
                  ["wall", "experiment (deg)", "paper (deg)", "drydem (deg)", "paper error (%)", "drydem error (%)"], rows)


def _table4(runs: Runs, paper: dict) -> str:
    published = paper["table4_ratio_kn1e9_over_kn3e7"]
    rows = []
    for d in DESIGNS:
        pairs = [(runs.angle(d, 1e9), runs.angle(d, 3e7)), (runs.dls(d, 1e9), runs.dls(d, 3e7))]
        ours = [None if a is None or b is None else a / b for a, b in pairs]
        rows.append([d, f"{_cell(published['collapse_angle'][d])} / {_cell(ours[0], '{:.2f}')}",
                     f"{_cell(published['dls_angle_drift_1pct'][d])} / {_cell(ours[1], '{:.2f}')}"])
    return _table("Table 4: ratios kn = 1e9 over kn = 3e7, paper / drydem", ["wall", "collapse angle", "DLS angle (1 % drift)"], rows)


def _figure(folder: Path, name: str, caption: str, draw, *, panels: int = 1) -> str:
    fig = new_figure(figsize=(4.4 * max(panels, 1.4), 3.8), layout="constrained")
    axes = fig.subplots(1, panels, squeeze=False)
    drew = draw(axes[0][0] if panels == 1 else axes[0])
    path = folder / f"{name}.png"
    plain_text(fig)
    with replaced_atomically(path) as partial:
        fig.savefig(partial, dpi=120)
    missing = "" if drew else " (no runs for this figure in the study)"
    return f"## {caption}{missing}\n\n![{name}](figures/{path.name})"


def _contact_points(ax, runs: Runs) -> bool:
    points = sorted({r["spec"]["points"] for r in runs.tilts("WD3") if r["spec"]["points"] is not None and _close(r["spec"]["kn"], 3e7)})
    found = {p: runs.angle("WD3", 3e7, points=p) for p in points}
    points = [p for p, angle in found.items() if angle is not None]  # a run without a verdict has no angle to draw
    ax.plot(points, [found[p] for p in points], "o-")
    ax.set(xlabel="contact points per block length", ylabel="collapse angle (deg)")
    if points:
        ax.set(xscale="log", xticks=points, xticklabels=[str(p) for p in points])
    ax.grid(alpha=0.3)
    return bool(points)


def _stiffness(ax, runs: Runs, paper: dict) -> bool:
    experiment, cov = paper["table1_experiment"]["collapse_angle_deg"], paper["table1_experiment"]["cov_percent"]
    band = np.mean(list(cov.values())) / 100
    ax.axhspan(1 - band, 1 + band, color="0.85")
    drew = False
    for d in DESIGNS:
        kns = runs.stiffnesses(d)
        capacity = [runs.capacity(d, kn) for kn in kns]  # None: no verdict, a gap in the line
        if any(c is not None for c in capacity):  # found by a hunt: only runs without a verdict failed on the log scale
            drew = True
            ax.plot(kns, [np.nan if c is None else c / experiment[d] for c in capacity], "o-", label=d, markersize=3)
    ax.axhline(1.0, color="k", linewidth=0.8)
    ax.set(xscale="log" if drew else "linear", xlabel="kn = ks (Pa/m)", ylabel="collapse angle / experiment")
    _legend(ax)
    return drew


def _plot_pushover(ax, run: dict, label: str) -> None:
    """A run's pushover curve: tilt (deg) against the monitored displacement since the tilt began
    (from its first row's, as the drift: :class:`~drydem.analysis.tilt.Record`), mm (found by a
    hunt: WD1, which settles 0.11 mm back under its own weight, was drawn from 0.76 deg on)."""
    curve = np.array(run["pushover"])
    ax.plot((curve[:, 1] - curve[0, 1]) * 1e3, curve[:, 0], label=label)


def _drift_lines(ax, height_m: float | None) -> None:
    """The EC8 drift limits (EN 1998-1 4.4.3.2) of a wall ``height_m`` high as displacements (mm), dashed."""
    for limit in EC8_DRIFT_LIMITS if height_m is not None else ():
        ax.axvline(limit * height_m * 1e3, color="0.5", linestyle="--", linewidth=0.8)


def _pushover(axes, runs: Runs, designs: list[str]) -> bool:
    drew = False
    for ax, d in zip(axes, designs):
        height = None
        for kn in runs.stiffnesses(d, protocol="fixed"):
            run = runs.tilt(d, kn, protocol="fixed")
            if not run["pushover"]:  # unstable under its own weight: no curve
                continue
            _plot_pushover(ax, run, f"kn {kn:.0e}")
            height = run["summary"]["wall_height_m"]
        _drift_lines(ax, height)
        drew |= height is not None
        ax.set(title=d, xlabel="monitored displacement since 0 deg (mm)", ylabel="tilt (deg)", xlim=(0, None))
        _legend(ax)
    return drew


def _dls(ax, runs: Runs) -> bool:
    drew = False
    for d in DESIGNS:
        kns = [kn for kn in runs.stiffnesses(d) if runs.dls(d, kn) is not None]
        if kns:
            drew = True
            ax.plot(kns, [runs.dls(d, kn) for kn in kns], "o-", label=d, markersize=3)
    ax.set(xscale="log" if drew else "linear", xlabel="kn = ks (Pa/m)", ylabel="DLS tilt angle (deg)")
    _legend(ax)
    return drew


def _ks(axes, runs: Runs) -> bool:
    drew = False
    wd6 = runs.tilts("WD6", protocol="fixed")
    for ax, kn in zip(axes, (1e7, 4e7, 7e7, 1e8)):
        for run in sorted((r for r in wd6 if _close(r["spec"]["kn"], kn) and r["pushover"]), key=lambda r: r["spec"]["ks"]):
            _plot_pushover(ax, run, f"ks {run['spec']['ks']:.0e}")
            drew = True
        ax.set(title=f"WD6, kn {kn:.0e}", xlabel="displacement (mm)", ylabel="tilt (deg)", xlim=(0, None))
        _legend(ax)
    return drew


def _legend(ax) -> None:
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="x-small", ncol=2)
