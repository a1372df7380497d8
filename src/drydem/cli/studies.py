"""Parametric studies: ``sweep``, ``report`` and ``calibrate``."""

from __future__ import annotations

from pathlib import Path

import click

from drydem.errors import DrydemError
from drydem.cli.common import PLAIN_FLOAT, joint_law_options, main, out_path, scheduler_option, signals_interrupt, workers_option


@main.command()
@click.argument("study_file")
@click.option("--out", type=click.Path(), callback=out_path, help="Results folder (default: results/STUDY-NAME).")
@workers_option
@scheduler_option
@click.option("--retry-failed", is_flag=True, help="Run again the runs recorded as failed.")
@click.option("--retry-changed", is_flag=True, help="Run again the runs recorded on a target or motion file whose content has "
              "changed since (their records are replaced).")
def sweep(study_file: str, out: Path | None, workers: int | None, scheduler: str | None, retry_failed: bool,
          retry_changed: bool) -> None:
    """Run a parametric study (STUDY_FILE, TOML, or a shipped study: savalle2022): every run a
    tilting, limit or shaking-table analysis, each recorded in OUT/runs as it finishes; run again to go on
    where it stopped (corrupt records are run again). The whole study is checked before the
    first run; two sweeps on one OUT share its runs."""
    from tqdm import tqdm

    from drydem.masonry import studies
    from drydem.io.results import records_folder
    from drydem.parametric.study import load_study
    from drydem.parametric.sweep import pending
    from drydem.parametric.sweep import sweep as run_sweep
    from drydem.parametric.workers import open_workers

    if Path(study_file).is_dir():
        raise click.ClickException(f"{study_file}: is a folder, not a study file (a TOML file: README, \"Parametric studies\")")
    if Path(study_file).exists() and not Path(study_file).is_file():
        raise click.ClickException(f"{study_file}: not a regular file (a pipe or a device?), not a study file (a TOML file)")
    path = Path(study_file) if Path(study_file).is_file() else studies.find(study_file)
    if path is None:
        raise click.ClickException(f"{study_file}: no such study file, and not a shipped study (savalle2022)")
    try:
        study = load_study(path)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    try:
        out = records_folder(out or Path("results") / study.name)
        plan = pending(study.runs, out, retry_failed=retry_failed, retry_changed=retry_changed)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for note in study.notes:
        click.echo(f"note: {note}", err=True)
    click.echo(f"{study.name}: {len(study.runs)} runs, {plan.recorded} already recorded in {out}")
    for corrupt in plan.corrupt:
        click.echo(f"corrupt record, run again: {corrupt}", err=True)
    failures = []
    try:  # a DrydemError: a scheduler that does not answer, or runs the executor lost
        with open_workers(workers, scheduler) as pool, signals_interrupt() as received, \
                tqdm(total=len(plan.todo), desc="runs", unit=" run") as bar:
            bar.write(f"running {len(plan.todo)} on {pool.where}")

            def done(record):
                bar.update(1)
                if record["status"] == "failed":
                    failures.append(f"{record['id']}: {record['error']}")
                    bar.set_postfix(failed=len(failures))

            try:
                outcome = run_sweep(study.runs, out, pool.executor, retry_failed=retry_failed, retry_changed=retry_changed,
                                    in_flight=pool.slots, on_done=done,
                                    on_other=lambda spec: bar.update(1))
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); the finished runs are recorded in {out}; the same command goes on", err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for failure in failures:
        click.echo(f"failed: {failure}", err=True)
    click.echo(f"{outcome.finished} runs done ({outcome.failed} failed), {outcome.skipped} skipped; records in {out / 'runs'}")
    problems = _incomplete(outcome, out)
    if problems:
        raise click.ClickException("the study is not complete: " + "; ".join(problems))


def _incomplete(outcome, out: Path) -> list[str]:
    """What keeps a sweep's study from being complete, in words: runs failed, now or before, runs
    recorded on input files that changed since (not retried), and runs left to another sweep
    (found by a hunt: they exited 0, though a sweep killed meanwhile may never record them)."""
    problems = []
    if outcome.elsewhere:
        problems.append(f"{outcome.elsewhere} runs left to another sweep working on {out} (it holds their claims, runs/*.lock); "
                        "run this command again once it has finished to check that every run is recorded")
    if outcome.failed or outcome.failed_before:
        before = f" and {outcome.failed_before} recorded as failed before" if outcome.failed_before else ""
        problems.append(f"{outcome.failed} runs failed now{before} (each record in {out / 'runs'} holds its error); fix the cause "
                        "and run again with --retry-failed")
    if outcome.changed_before:
        files = sorted({path for paths in outcome.changed_before.values() for path in paths})
        problems.append(f"{len(outcome.changed_before)} runs are recorded on files whose content has changed since, or that are "
                        f"gone ({', '.join(files)}): their results are of the files as they were; run again with --retry-changed "
                        "to replace them, or give the changed study another --out")
    return problems


@main.command()
@click.argument("results_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False), callback=out_path, help="Report folder (default: RESULTS_DIR/report).")
@click.option("--overwrite", is_flag=True, help="Replace a report.md or report.html there that drydem did not write, and write "
              "the figures into a figures/ folder of no drydem report (its own earlier report is always replaced: it is made from "
              "the records again).")
def report(results_dir: Path, out: Path | None, overwrite: bool) -> None:
    """Write the report of the runs in RESULTS_DIR (Markdown, HTML, PNG figures): a sweep's
    records (RESULTS_DIR/runs) and the folders of `drydem tilt` and `drydem limit` runs (RESULTS_DIR
    and its sub-folders, e.g. `drydem report results`); the paper's tables and figures with
    drydem's values beside the published ones (when a run is of its walls), and the runs of your
    own targets (wall, model and geometry files, other built-in targets) in their own tables and
    pushover figures; corrupt records are left out and named."""
    from drydem.report.study import build_report

    try:
        written = build_report(results_dir, out, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    except OSError as exc:
        raise click.ClickException(f"{exc.filename}: cannot write the report ({exc.strerror})") from None
    for corrupt in written.corrupt:
        click.echo(f"corrupt record left out: {corrupt}", err=True)
    click.echo(f"report          {written.markdown} and {written.html}")
    if written.corrupt and not written.reported:
        raise click.ClickException(f"every record of {results_dir} is corrupt ({len(written.corrupt)}, named above and in the "
                                   "report): the report holds no run")


@main.command()
@click.argument("results_dir", type=click.Path(), callback=out_path)
@click.option("--designs", default="WD1,WD2,WD3,WD4,WD5,WD6,WD7", show_default=True, help="Walls to fit, comma-separated, each once.")
@click.option("--kn-min", type=PLAIN_FLOAT, default=1e7, show_default=True, help="Smallest kn searched, Pa/m.")
@click.option("--kn-max", type=PLAIN_FLOAT, default=1e9, show_default=True, help="Largest kn searched, Pa/m.")
@click.option("--ks-ratio", type=PLAIN_FLOAT, default=1.0, show_default=True, help="ks = ratio x kn.")
@click.option("--increment", type=PLAIN_FLOAT, default=0.1, show_default=True, help="Tilt step of the (adaptive) runs, deg.")
@joint_law_options
@click.option("--out", type=click.Path(), callback=out_path, help="The calibration's JSON file (default: RESULTS_DIR/calibration.json).")
@click.option("--overwrite", is_flag=True, help="Replace a finished calibration, or one with other settings, in --out (kept otherwise).")
@workers_option
@scheduler_option
def calibrate(results_dir, designs, kn_min, kn_max, ks_ratio, increment, joint_law, out, overwrite, workers, scheduler) -> None:
    """Find the kn that best reproduces the experimental collapse angles (paper Table 1) of
    DESIGNS, reusing and adding runs in RESULTS_DIR (the paper's post-diction, Section 4.4),
    then measure how noisy the objective is at that kn; every option is checked before anything
    runs. The calibration (every kn evaluated, the best, the noise) is written to --out as it
    goes; an interrupted one goes on. With a stress-dependent joint law
    (--joint-model and its keys), the law's shape is kept and its kn (ks = ratio x kn) fitted."""
    from drydem.parametric.calibrate import CALIBRATION_FILE, NEIGHBOURHOOD, StiffnessSearch, calibrate_stiffness, check_calibration_file
    from drydem.files import writable
    from drydem.io.results import records_folder
    from drydem.parametric.workers import open_workers

    names = tuple(d.strip() for d in designs.split(",")) if designs.strip() else ()  # an empty name kept, to be refused
    search = StiffnessSearch(names, kn_min, kn_max, ks_ratio, increment, joint_law)
    problems = search.problems(name=lambda field: "--" + field.replace("_", "-"))
    if problems:
        raise click.ClickException("\n".join(problems))
    out = out or results_dir / CALIBRATION_FILE
    try:
        records_folder(results_dir, "calibrate")
        check_calibration_file(writable(out), search, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    law = f" of the joint law {joint_law}" if joint_law else ""
    click.echo(f"calibrating kn{law} over [{kn_min:.3g}, {kn_max:.3g}] Pa/m on {', '.join(search.designs)} (runs kept in {results_dir})")

    def evaluated(kn, error, outcome):
        for corrupt in outcome.corrupt:
            click.echo(f"corrupt record, run again: {corrupt}", err=True)
        click.echo(f"  kn {kn:10.4g} Pa/m   mean absolute error {error:.2%}")

    try:  # a DrydemError: a scheduler that does not answer, or a kn's runs without an angle
        with open_workers(workers, scheduler) as pool, signals_interrupt() as received:
            click.echo(f"running on {pool.where}")
            try:
                result = calibrate_stiffness(search, results_dir, pool.executor, out=out, overwrite=overwrite, in_flight=pool.slots,
                                             on_evaluation=evaluated)
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); the finished runs are recorded in {results_dir}, the kn evaluated in {out}; "
                           "the same command goes on", err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    noise = result.noise
    click.echo(f"best kn         {result.best_kn:.4g} Pa/m (ks = {ks_ratio:g} kn): mean absolute error {result.best_error:.2%}")
    moved = f" ({noise['wall']})" if noise["largest_deg"] else ""
    click.echo(f"objective noise ~{noise['error']:.2%}: smaller differences of the error are not meaningful (the larger of its range "
               f"over the {len(noise['kn'])} kn within {NEIGHBOURHOOD - 1:.0%} of the best, {noise['spread']:.2%}, collapse angles up to "
               f"{noise['largest_deg']:.2g} deg apart{moved}, "
               f"and its step for one {increment:g} deg tilt step on {noise['step_wall']}, {noise['step']:.2%})")
    click.echo(f"calibration     {out}")
