"""The ``usarsim sweep`` and ``usarsim report`` commands: :func:`add_parsers` adds them to
the ``usarsim`` command line; each parser's ``handler`` runs its command."""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path
from typing import Any


def add_parsers(subparsers: Any) -> None:
    """Add ``sweep`` and ``report`` to the sub-commands ``subparsers`` (of argparse)."""
    s = subparsers.add_parser(
        "sweep",
        help="run an experiment: many simulator runs on Ray, scored, into a results table",
        description="Run every run of an experiment file (a grid and/or a list over worlds, seeds, teams, "
        "wireless models, durations, clocks and controllers: docs/experiments.md), each as a Ray "
        "task with a simulator of its own on free ports, and store one row per run (its "
        "configuration, its score, its wall time, its error) in DIR/results.parquet and "
        "DIR/results.csv. Runs done already in DIR are skipped; a failed run is recorded and run "
        "again next time. Exit status 0 when every run went well, 1 when a run failed; stopped by "
        "Ctrl-C (SIGINT) or SIGTERM, it stores the runs that finished, says how many, and exits "
        "with 130 or 143: the same command goes on from there.",
    )
    s.add_argument("experiment", metavar="EXPERIMENT.yaml", help="the experiment file")
    s.add_argument("--dry-run", action="store_true", help="list the runs (and which are done already); run none")
    s.add_argument(
        "--workers",
        type=_positive,
        default=None,
        metavar="N",
        help="runs at a time (default: one per CPU of this machine, or of the cluster with --address)",
    )
    s.add_argument(
        "--address",
        default=None,
        metavar="RAY_ADDRESS",
        help="join an existing Ray cluster ('auto', host:6379, ray://host:10001) instead of starting "
        "Ray on this machine",
    )
    s.add_argument(
        "--out", default=None, metavar="DIR", help="results folder (default: results/<the experiment's name>)"
    )
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(handler=cmd_sweep)
    r = subparsers.add_parser(
        "report",
        help="summarize a sweep's results: table, plots, one HTML page",
        description="Read DIR/results.parquet (usarsim sweep) and write DIR/summary.csv (per configuration: "
        "mean, standard deviation and 95 % confidence interval of each score over its seeds: "
        "Student's t, clipped to the range a score can take, or the exact Poisson interval of a "
        "count; docs/experiments.md), "
        "DIR/plot-*.png (score, victims found and area explored against the sweep's axes) and "
        "DIR/report.html, one self-contained page with the table and the plots.",
    )
    r.add_argument("folder", metavar="DIR", help="a sweep's results folder")
    r.set_defaults(handler=cmd_report)
    for p in (s, r):
        p.add_argument(
            "-v", "--verbose", action="count", default=0, dest="verbose_after", help="more log output: -v, -vv"
        )


def _positive(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {n}")
    return n


def _console(stderr: bool = False) -> Any:
    from rich.console import Console

    c = Console(stderr=stderr)
    return c if c.is_terminal else Console(stderr=stderr, width=160)


def cmd_sweep(args: argparse.Namespace) -> int:
    from usarsim.sweep.runner import stop_on_signals

    with stop_on_signals() as caught:
        try:
            return _sweep(args)
        except KeyboardInterrupt:  # outside the runs (reading the file, starting): nothing to store
            signum = caught.first or signal.SIGINT
            print(
                f"usarsim: sweep stopped by {signal.Signals(signum).name}; run the same command again to go on",
                file=sys.stderr,
            )
            return 128 + signum


def _sweep(args: argparse.Namespace) -> int:
    from usarsim.errors import ConfigError, UsarsimError
    from usarsim.sweep.experiment import load_experiment
    from usarsim.sweep.results import ResultsStore

    try:
        exp = load_experiment(args.experiment)
    except ConfigError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    out = Path(args.out) if args.out else Path("results") / exp.name
    store = ResultsStore(out)
    done = store.done_ids()
    failed_before = {r["run_id"] for r in store.rows if r.get("error")}
    if args.dry_run:
        print_plan(exp, done, failed_before, _console())
        todo = sum(1 for r in exp.runs if r.run_id not in done)
        print(f"{len(exp.runs)} runs: {len(exp.runs) - todo} done already in {out}, {todo} to run")
        return 0
    from usarsim.sweep.runner import SweepInterrupted, run_sweep

    todo = sum(1 for r in exp.runs if r.run_id not in done)
    print(
        f"usarsim: sweep {exp.name}: {len(exp.runs)} runs, {len(exp.runs) - todo} done already, {todo} to run; "
        f"results in {out}",
        flush=True,
    )
    try:
        outcome = run_sweep(
            exp,
            out,
            workers=args.workers,
            address=args.address,
            progress=not args.no_progress,
            console=_console(stderr=True),
        )
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    except SweepInterrupted as exc:
        ids = {r.run_id for r in exp.runs}
        stored = len(ResultsStore(out).done_ids() & ids)
        ran = len(exc.outcome.rows)
        print(
            f"usarsim: sweep stopped by {signal.Signals(exc.signum).name}: {stored} of {len(exp.runs)} runs done "
            f"and stored in {out} ({ran} finished now, {exc.outcome.failed} failed); run the same command "
            f"again to run the other {len(exp.runs) - stored}",
            file=sys.stderr,
        )
        return 128 + exc.signum
    for row in outcome.rows:
        if row.get("error"):
            print(
                f"usarsim: run {row['run_id']} ({row['world']}, seed {row['seed']}, {row['controller']}) "
                f"failed: {row['error']}",
                file=sys.stderr,
            )
    ran = len(outcome.rows)
    rate = f", {ran / outcome.elapsed_s * 3600:.0f} runs/hour" if ran and outcome.elapsed_s > 0 else ""
    print(
        f"usarsim: {ran} runs in {outcome.elapsed_s:.1f} s{rate} ({outcome.failed} failed), {outcome.skipped} "
        f"skipped as done; {out / 'results.parquet'}, {out / 'results.csv'}"
    )
    if ran or outcome.skipped:
        print(f"usarsim: summarize with: usarsim report {out}")
    return 1 if outcome.failed else 0


def print_plan(exp: Any, done: set[str], failed_before: set[str], console: Any) -> None:
    """The runs of ``exp`` as a table, each marked new, done or failed (last time)."""
    from rich import box
    from rich.table import Table

    from usarsim.sweep.report import short

    t = Table(title=f"{exp.name}: {len(exp.runs)} runs", box=box.SIMPLE_HEAD, title_justify="left")
    for c in ("#", "run", "world", "seed", "team", "wireless", "duration", "clock", "controller", "status"):
        t.add_column(c, justify="right" if c in ("#", "seed", "duration") else "left")
    for i, r in enumerate(exp.runs, 1):
        status = "done" if r.run_id in done else "failed, again" if r.run_id in failed_before else "new"
        t.add_row(
            str(i),
            r.run_id,
            short(r.world) + ("" if r.variant is None else f" variant {r.variant}"),
            str(r.seed),
            r.team_label,
            r.wireless,
            f"{r.duration_s:g} s",
            r.clock,
            short(r.controller.label, 48),
            status,
        )
    _print_table(t, console)


def _print_table(table: Any, console: Any) -> None:
    """``table`` on stdout, without the blanks rich pads its lines with."""
    with console.capture() as captured:
        console.print(table)
    print("\n".join(line.rstrip() for line in captured.get().splitlines()))


# The scores of the terminal's table (report.html and summary.csv have every one).
TABLE_SCORES = (("score", "score"), ("victims_found", "victims found"), ("area_m2", "area m²"))


def cmd_report(args: argparse.Namespace) -> int:
    from usarsim.sweep.report import AXIS_NAMES, build_report, digits_of, fmt_stat, method_of, short, shown_metrics
    from usarsim.sweep.results import PARQUET

    folder = Path(args.folder)
    if not (folder / PARQUET).exists():
        print(
            f"usarsim: error: {folder}: no {PARQUET} here (the folder 'usarsim sweep' wrote its results to)",
            file=sys.stderr,
        )
        return 1
    report = build_report(folder)
    from rich import box
    from rich.table import Table

    shown = list(report.axes) or ["world", "controller"]
    scores = list(TABLE_SCORES)
    if "messages_lost" in shown_metrics(report.rows):  # a radio channel counted the team's messages
        scores.append(("messages_lost", "messages lost"))
    t = Table(
        box=box.SIMPLE_HEAD,
        title=f"{len(report.rows)} runs in {len(report.groups)} configurations",
        title_justify="left",
    )
    for c in shown:
        t.add_column(AXIS_NAMES[c])
    for c in ("runs", "failed"):
        t.add_column(c, justify="right")
    for _, name in scores:
        t.add_column(f"{name}\nmean [95 % CI]", justify="right")
    for g in report.groups:
        cells = [short(g.config[c], 40) for c in shown] + [str(len(g.seeds)), str(g.failed)]
        cells += [fmt_stat(g.stat(m), digits_of(m)) for m, _ in scores]
        t.add_row(*cells)
    _print_table(t, _console())
    print(
        "mean [95 % confidence interval of the mean] over the seeds; the intervals: "
        + "; ".join(f"{name}: {method_of(m)}" for m, name in scores[:2])
        + ";\n"
        + "; ".join(f"{name}: {method_of(m)}" for m, name in scores[2:])
        + " (docs/experiments.md)"
    )
    print(f"usarsim: summary {report.summary_csv}; {len(report.plots)} plots in {folder}")
    print(f"usarsim: report written to {report.html_path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m usarsim.sweep sweep ...`` / ``report ...``: the two commands on their own."""
    import logging

    p = argparse.ArgumentParser(prog="python -m usarsim.sweep")
    add_parsers(p.add_subparsers(dest="command", metavar="COMMAND", required=True))
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING if not args.verbose_after else logging.INFO)
    return args.handler(args)
