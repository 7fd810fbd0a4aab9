"""``usarsim compete``: every team over the same scenario set, on Ray, and the leaderboard."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def add_parser(sub: Any) -> None:
    from usarsim.sweep.cli import _positive

    c = sub.add_parser(
        "compete",
        help="run a rescue competition: every team over the same scenarios, and a leaderboard",
        description="Run each team of a competition file (a Python brain or any command, as sweeps run "
        "controllers) over the same scenario set (worlds, variants drawn from a seed that can be kept "
        "secret, team size, radio, time limit), each run in a simulator of its own as a Ray task, score "
        "every run (victims, floor explored, collisions, robots lost, radio contact, and the map the team "
        "hands in) and write the leaderboard: leaderboard.csv and .parquet (totals, means with 95 %% "
        "confidence intervals over the scenarios), scenarios.csv (points per scenario), the runs' rows "
        "(results.parquet, results.csv) and leaderboard.html, which shows every run's map over the ground "
        "truth. Runs already done are not run again. docs/competitions.md describes the file.",
    )
    c.add_argument("path", metavar="COMPETITION.yaml", help="the competition file")
    c.add_argument("--out", metavar="DIR", help="results folder (default: results/NAME)")
    c.add_argument("--workers", type=_positive, metavar="N", help="runs at a time (default: one per CPU)")
    c.add_argument("--address", metavar="ADDR", help="a Ray cluster's address (default: Ray on this machine)")
    c.add_argument("--dry-run", action="store_true", help="list the runs and stop")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(handler=cmd_compete)


def cmd_compete(args: argparse.Namespace) -> int:
    from usarsim.compete.competition import load_competition
    from usarsim.errors import UsarsimError
    from usarsim.sweep.cli import _console

    console = _console()
    try:
        comp = load_competition(args.path, args.out)
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    out = Path(args.out) if args.out else Path("results") / comp.name
    console.print(
        f"[bold]{comp.name}[/]: {len(comp.teams)} teams x {len(comp.scenarios)} scenarios = {len(comp.runs)} runs"
        + (" (variants hidden)" if comp.hidden else "")
    )
    if args.dry_run:
        for run in comp.runs:
            s = comp.scenario_of(run)
            variant = "as written" if s.variant is None else ("hidden" if comp.hidden else f"variant {s.variant}")
            console.print(f"  {run.controller.label:<16} {s.label:<4} {s.world} {variant}, seed {s.seed}")
        return 0
    from usarsim.sweep.runner import SweepError, SweepInterrupted, run_sweep, stop_on_signals

    try:
        with stop_on_signals():
            outcome = run_sweep(
                comp.experiment(), out, workers=args.workers, address=args.address, progress=not args.no_progress
            )
    except SweepInterrupted as exc:
        print(
            f"usarsim: compete stopped by {exc}: {len(exc.outcome.rows)} runs finished now and stored in {out}; "
            "run the same command again to run the others",
            file=sys.stderr,
        )
        return 128 + exc.signum
    except SweepError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    return _finish(comp, out, outcome, console)


def _finish(comp: Any, out: Path, outcome: Any, console: Any) -> int:
    from rich.table import Table

    from usarsim.compete.leaderboard import leaderboard_rows, tally, write_leaderboard
    from usarsim.sweep.results import ResultsStore

    rows = ResultsStore(out).rows
    page = write_leaderboard(comp, rows, out)
    table = Table(title=f"{comp.name}: leaderboard", title_justify="left")
    for head in ("rank", "team", "total", "mean (95 % CI)", "failed", "map coverage", "map accuracy"):
        table.add_column(head, justify="left" if head == "team" else "right")
    for r in leaderboard_rows(tally(comp, rows)):
        ci = "" if r["ci_low"] is None else f" ({r['ci_low']:.1f} - {r['ci_high']:.1f})"
        pct = lambda v: "-" if v is None else f"{100 * v:.1f} %"  # noqa: E731
        table.add_row(
            str(r["rank"]),
            r["team"],
            f"{r['total']:.1f}",
            f"{r['mean']:.1f}{ci}",
            str(r["failed"]),
            pct(r["map_coverage"]),
            pct(r["map_accuracy"]),
        )
    console.print(table)
    for row in outcome.rows:
        if row.get("error"):
            print(
                f"usarsim: run {row['run_id']} ({row['controller']}, {row['world']}, seed {row['seed']}) failed: "
                f"{row['error']}",
                file=sys.stderr,
            )
    failed = sum(1 for r in rows if r.get("error"))
    console.print(
        f"{len(outcome.rows)} runs now, {outcome.skipped} done before, {failed} failed; "
        f"leaderboard: {out / 'leaderboard.csv'}, {page}"
    )
    return 0 if failed == 0 else 1
