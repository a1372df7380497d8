"""The report of a parametric study (``drydem report RESULTS_DIR``), in the style of the seed
paper: its figures (3, 6, 9-13) and tables (2-4) from the study's run records, drydem's values
beside the paper's (drydem.masonry.published), in Markdown and HTML with PNG figures; and when
the study has shake runs, their incremental dynamic analysis (:mod:`drydem.report.ida`); when
it has runs with a stress-dependent joint law, the calibrated law against the experiments
(:mod:`drydem.report.joints`); when it has Monte Carlo runs (``RESULTS/montecarlo/NAME/``, each
``drydem montecarlo``'s folder), the scatter of their collapse angles against the experiments'.

The paper's tables and figures are of constant joints: a run with a joint law is never taken
for the constant-kn run at its kn.

A figure or table whose runs are missing says so instead of failing: a report can be built
from a study still running. A corrupt record is left out, and the report names its file.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drydem.analysis.drift import EC8_DRIFT_LIMITS
from drydem.errors import DrydemError
from drydem.masonry.published import savalle2022
from drydem.parametric.records import RecordError, load_records
from drydem.report.joints import joint_law, relative_error_percent, wall_of
from drydem.report.plots import new_figure

DESIGNS = [f"WD{k}" for k in range(1, 8)]
#: the paper's grouping of the pushover figures
PUSHOVER_FIGURES = {"fig09_pushover": ["WD1", "WD2"], "fig10_pushover": ["WD3", "WD4"], "fig11_pushover": ["WD5", "WD6", "WD7"]}
POINTS = 4  # the paper's contact density for its parametric study
LAWS_TITLE = "Stress-dependent joints: the calibrated law against the experiments and kn = ks = 3e7"
MONTECARLO_FOLDER = "montecarlo"
MONTECARLO_TITLE = "Monte Carlo scatter of the collapse angle"
#: the statistics of a Monte Carlo summary's collapse angle the report shows (count aside)
MONTECARLO_STATISTICS = ("mean", "std", "cov", "p05")
MONTECARLO_NOTE = (
    "Each row a `drydem montecarlo` run in montecarlo/NAME: the statistics of its collapse angles over the samples with a verdict, "
    "a sample that cannot stand under its own weight counting as 0 deg (samples: how many; std with ddof = 1; p05 the 5th "
    "percentile), with the imperfections drawn; experiment: the mean and CoV "
    "of the wall's tests (Savalle et al. 2022, Table 1; '-': not one of its walls).")
NOTE = ("drydem's WD1-WD7 are reconstructions that obey the competition brief, not the original drawings "
        "(which drydem does not have): compare trends and rankings, not single numbers.")


class Runs:
    """The ok records of a study, looked up by what they are."""

    def __init__(self, records: list[dict]):
        self.ok = [r for r in records if r["status"] == "ok"]
        self.failed = [r for r in records if r["status"] != "ok"]

    def tilts(self, design: str, *, protocol: str | None = None) -> list[dict]:
        """The tilting runs of ``design`` with constant joints (no joint law: those are
        :mod:`drydem.report.joints`'), of ``protocol`` when given."""
        return [r for r in self.ok if r["spec"]["analysis"] == "tilt" and joint_law(r) is None and wall_of(r) == design
                and (protocol is None or r["spec"]["protocol"] == protocol)]

    def tilt(self, design: str, kn: float, *, ks: float | None = None, points: int = POINTS, protocol: str | None = None) -> dict | None:
        """The tilting run of ``design`` at constant kn (ks = kn by default); adaptive preferred
        to fixed (both find the collapse angle within one increment)."""
        ks = kn if ks is None else ks
        found = [r for r in self.tilts(design, protocol=protocol)
                 if _close(r["spec"]["kn"], kn) and _close(r["spec"]["ks"], ks) and r["spec"]["points"] in (points, None)]
        found.sort(key=lambda r: r["spec"]["protocol"] != "adaptive")
        return found[0] if found else None

    def angle(self, design: str, kn: float, **kw) -> float | None:
        run = self.tilt(design, kn, **kw)
        return None if run is None else run["summary"]["collapse_angle_deg"]

    def angle_cell(self, design: str, kn: float) -> str:
        """The collapse angle for a table; for a run that found no equilibrium within max_cycles
        past its last one, and no collapse either, ">= that tilt" (a lower bound, no verdict)."""
        from drydem.analysis.tilt import NO_EQUILIBRIUM

        run = self.tilt(design, kn)
        summary = {} if run is None else run["summary"]
        if summary.get("ended_by") == NO_EQUILIBRIUM:  # records of earlier versions gave that tilt as the collapse angle
            return f">= {summary.get('last_equilibrium_deg', summary['collapse_angle_deg']):.1f}"
        return _cell(summary.get("collapse_angle_deg"))

    def capacity(self, design: str, kn: float) -> float | None:
        """The angle the objective of the calibration uses (:func:`drydem.parametric.calibrate.wall_angle`:
        0 for a wall that cannot stand, None for no verdict)."""
        from drydem.parametric.calibrate import wall_angle

        run = self.tilt(design, kn)
        return None if run is None else wall_angle(run["summary"])

    def dls(self, design: str, kn: float) -> float | None:
        run = self.tilt(design, kn)
        return None if run is None else run["summary"]["drift_limit_angles_deg"]["0.01"]

    def limit(self, design: str, method: str) -> float | None:
        found = [r for r in self.ok if r["spec"]["analysis"] == "limit" and wall_of(r) == design and r["summary"]["method"] == method]
        return found[0]["summary"]["collapse_angle_deg"] if found else None

    def stiffnesses(self, design: str, *, protocol: str | None = None) -> list[float]:
        """The kn of the constant-joint tilting runs of ``design`` with ks = kn, sorted."""
        return sorted({r["spec"]["kn"] for r in self.tilts(design, protocol=protocol)
                       if r["spec"]["kn"] is not None and _close(r["spec"]["ks"], r["spec"]["kn"])})


def _close(a, b) -> bool:
    return a is not None and b is not None and math.isclose(a, b, rel_tol=1e-9)


class ReportError(DrydemError):
    """No report can be made of the folder given."""


@dataclass(frozen=True)
class Report:
    """The report's files, and the errors of the records left out (each naming its file)."""

    markdown: Path
    html: Path
    corrupt: list[RecordError]


def build_report(results: Path, out: Path | None = None) -> Report:
    """Write ``report.md``, ``report.html`` and ``figures/*.png`` for the study in ``results``;
    ReportError if ``results`` holds no ``runs`` folder (not a study's results)."""
    import markdown

    results = Path(results)
    if not (results / "runs").is_dir():
        raise ReportError(f"{results}: no runs/ folder, so not the results of a study (`drydem sweep STUDY --out {results}` writes them)")
    records = load_records(results)
    runs = Runs(records.valid)
    out = Path(out or results / "report")
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    paper = savalle2022()
    sections = [
        f"# Report of the study in `{results}`",
        f"{len(runs.ok)} runs recorded ({len(runs.failed)} failed). {NOTE} Published values: {paper['source'].split(' - ')[0]}.",
        *([_corrupt(records.corrupt)] if records.corrupt else []),
        _table2(runs, paper), _table3(runs, paper), _table4(runs, paper),
        *_laws(records.valid, runs),
        _figure(figures, "fig03_contact_points", "Fig. 3: collapse angle of WD3 against contact points per length, kn = 3e7",
                lambda ax: _contact_points(ax, runs)),
        _figure(figures, "fig06_stiffness", "Fig. 6: collapse angle over the experimental one against kn = ks; grey: the experiments' mean CoV",
                lambda ax: _stiffness(ax, runs, paper)),
        *(_figure(figures, name, f"Figs 9-11: pushover curves of {', '.join(designs)} (fixed protocol), EC8 drift limits dashed",
                  lambda axes, designs=designs: _pushover(axes, runs, designs), panels=len(designs)) for name, designs in PUSHOVER_FIGURES.items()),
        _figure(figures, "fig12_dls", "Fig. 12: tilt angle at 1 % drift (damage limit state) against kn = ks", lambda ax: _dls(ax, runs)),
        _figure(figures, "fig13_ks", "Fig. 13: WD6, influence of ks on the pushover curve (panels: kn)", lambda axes: _ks(axes, runs), panels=4),
        *(_ida(figures, runs) if any(r["spec"]["analysis"] == "shake" for r in records.valid) else []),
        *_montecarlo(results, figures, paper),
    ]
    text = "\n\n".join(sections) + "\n"
    (out / "report.md").write_text(text)
    body = markdown.markdown(text, extensions=["tables"])
    (out / "report.html").write_text(f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>drydem report</title>"
                                     f"<style>table{{border-collapse:collapse}}td,th{{border:1px solid #999;padding:2px 6px}}</style>"
                                     f"</head><body>\n{body}\n</body></html>\n")
    return Report(out / "report.md", out / "report.html", records.corrupt)


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
    """The Monte Carlo run whose top summary is ``path``; OSError, ValueError, KeyError,
    TypeError or ModelError when it cannot be read as one."""
    from drydem.masonry.imperfections import Imperfections

    summary = json.loads(Path(path).read_text(encoding="utf-8"))
    stats = summary["collapse_angle_deg"]
    collapse = {key: None if stats[key] is None else float(stats[key]) for key in MONTECARLO_STATISTICS}
    collapse["count"] = int(stats["count"])
    imperfections = Imperfections(**summary["settings"]["imperfections"])
    return MonteCarloRun(Path(path).parent.name, str(summary["target"]["name"]), collapse, str(imperfections))


def montecarlo_runs(results: Path) -> tuple[list[MonteCarloRun], list[str]]:
    """The study's Monte Carlo runs (``RESULTS/montecarlo/*/summary.json``), by wall then folder,
    and the summaries that cannot be read, each named with its fault."""
    found, unreadable = [], []
    for path in sorted((Path(results) / MONTECARLO_FOLDER).glob("*/summary.json")):
        try:
            found.append(read_montecarlo(path))
        except (OSError, ValueError, KeyError, TypeError, DrydemError) as exc:
            unreadable.append(f"{path}: {type(exc).__name__}: {exc}")
    return sorted(found, key=lambda run: (run.wall, run.name)), unreadable


def _montecarlo(results: Path, figures: Path, paper: dict) -> list[str]:
    """The section of the study's Monte Carlo runs, none without any: per run, the statistics of
    its computed collapse angles (from its summary.json: the samples that found one) and its
    imperfections, beside the experimental mean and CoV of its wall (the paper's Table 1); the
    figure of the CoVs; the summaries that cannot be read, named."""
    found, unreadable = montecarlo_runs(results)
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
        text += f"\n\n{len(unreadable)} Monte Carlo summaries cannot be read, left out:\n\n" + "\n".join(f"- `{u}`" for u in unreadable)
    if not found:
        return [text]
    return [text, _figure(figures, "montecarlo_cov", "Monte Carlo: CoV of the computed collapse angle (imperfect walls) against the "
                          "experiments' (Table 1), per run", lambda ax: _cov_bars(ax, found, experiment))]


def _cov_bars(ax, found: list[MonteCarloRun], experiment: dict) -> bool:
    """Bars: each Monte Carlo run's CoV of the collapse angle beside its wall's experimental CoV (%)."""
    walls = [run.wall for run in found]
    labels = [run.wall if walls.count(run.wall) == 1 else f"{run.wall}\n{run.name}" for run in found]
    computed = [np.nan if run.collapse["cov"] is None else 100 * run.collapse["cov"] for run in found]
    measured = [experiment["cov_percent"].get(run.wall, np.nan) for run in found]
    x = np.arange(len(found))
    ax.bar(x - 0.2, computed, 0.4, label="drydem (imperfections)")
    ax.bar(x + 0.2, measured, 0.4, label="experiment")
    ax.set(xticks=x, ylabel="CoV of the collapse angle (%)")
    ax.set_xticklabels(labels, fontsize="small")
    _legend(ax)
    return not np.all(np.isnan(computed))


def _corrupt(errors: list[RecordError]) -> str:
    """The paragraph naming the records left out, each with its file and fault."""
    lines = "\n".join(f"- `{error}`" for error in errors)
    return f"{len(errors)} corrupt records left out (the same `drydem sweep` runs them again):\n\n{lines}"


def _cell(value: float | None, fmt: str = "{:.1f}") -> str:
    return "-" if value is None else fmt.format(value)


def _table(title: str, header: list[str], rows: list[list[str]]) -> str:
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def _table2(runs: Runs, paper: dict) -> str:
    published = paper["table2_collapse_angle_deg"]
    rows = []
    for d in DESIGNS:
        exp, la_a, la_na, dem9, dem10 = published[d]
        ours = [_cell(runs.limit(d, "associative")), _cell(runs.limit(d, "non-associative")), runs.angle_cell(d, 1e9), runs.angle_cell(d, 1e10)]
        rows.append([d, _cell(exp)] + [f"{_cell(p)} / {o}" for p, o in zip((la_a, la_na, dem9, dem10), ours)])
    return _table("Table 2: collapse angles (deg), paper / drydem",
                  ["wall", "experiment", "LA-A", "LA-NA", "DEM kn = 1e9", "DEM kn = 1e10"], rows) + (
        "\n\n>= X: no equilibrium within max_cycles at the step after X deg, and no collapse either: a lower bound.")


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
    rows.append(["mean absolute", "", "", "", _cell(published["mean_abs_error_percent"]), _cell(mean)])
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
    fig.savefig(path, dpi=120)
    missing = "" if drew else " (no runs for this figure in the study)"
    return f"## {caption}{missing}\n\n![{name}](figures/{path.name})"


def _contact_points(ax, runs: Runs) -> bool:
    points = sorted({r["spec"]["points"] for r in runs.tilts("WD3") if r["spec"]["points"] is not None and _close(r["spec"]["kn"], 3e7)})
    angles = [runs.angle("WD3", 3e7, points=p) for p in points]
    ax.plot(points, angles, "o-")
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
        if kns:
            drew = True
            capacity = [runs.capacity(d, kn) for kn in kns]  # None: no verdict, a gap in the line
            ax.plot(kns, [np.nan if c is None else c / experiment[d] for c in capacity], "o-", label=d, markersize=3)
    ax.axhline(1.0, color="k", linewidth=0.8)
    ax.set(xscale="log" if drew else "linear", xlabel="kn = ks (Pa/m)", ylabel="collapse angle / experiment")
    _legend(ax)
    return drew


def _pushover(axes, runs: Runs, designs: list[str]) -> bool:
    drew = False
    for ax, d in zip(axes, designs):
        height = None
        for kn in runs.stiffnesses(d, protocol="fixed"):
            run = runs.tilt(d, kn, protocol="fixed")
            if not run["pushover"]:  # unstable under its own weight: no curve
                continue
            curve = np.array(run["pushover"])
            ax.plot(curve[:, 1] * 1e3, curve[:, 0], label=f"kn {kn:.0e}")
            height = run["summary"]["wall_height_m"]
        for limit in EC8_DRIFT_LIMITS if height is not None else ():
            ax.axvline(limit * height * 1e3, color="0.5", linestyle="--", linewidth=0.8)
        drew |= height is not None
        ax.set(title=d, xlabel="monitored displacement (mm)", ylabel="tilt (deg)", xlim=(0, None))
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
            curve = np.array(run["pushover"])
            ax.plot(curve[:, 1] * 1e3, curve[:, 0], label=f"ks {run['spec']['ks']:.0e}")
            drew = True
        ax.set(title=f"WD6, kn {kn:.0e}", xlabel="displacement (mm)", ylabel="tilt (deg)", xlim=(0, None))
        _legend(ax)
    return drew


def _legend(ax) -> None:
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="x-small", ncol=2)
