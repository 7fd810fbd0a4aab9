"""Running a sweep: each run a Ray task that starts its own simulator, runs the controller
for the simulated duration, stops the simulator and returns one row with its score.

:func:`execute` (:mod:`usarsim.sweep.worker`) is one run, on whatever process calls it (a
Ray worker in a sweep); it never raises: a run that fails returns its row with the error and
the tail of the simulator's log.  :func:`run_sweep` submits the runs not done yet to Ray
(local by default, a cluster when given its address), shows the progress and stores every
row as it arrives.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from usarsim.errors import UsarsimError
from usarsim.sweep.results import SCORE_COLUMNS, ResultsStore
from usarsim.sweep.runs import Experiment, Run
from usarsim.sweep.worker import (
    GRACE_S,
    LOG_TAIL_CHARS,
    OUTPUT_TAIL_CHARS,
    POLL_S,
    RunFailed,
    _describe,
    brain_kwargs,
    command_values,
    execute,
)

__all__ = [
    "GRACE_S",
    "LOG_TAIL_CHARS",
    "OUTPUT_TAIL_CHARS",
    "POLL_S",
    "SAVE_EVERY_S",
    "RunFailed",
    "SweepError",
    "SweepInterrupted",
    "SweepOutcome",
    "brain_kwargs",
    "command_values",
    "execute",
    "run_sweep",
    "start_ray",
    "stop_on_signals",
]

log = logging.getLogger("usarsim.sweep")

SAVE_EVERY_S = 2.0  # the results files are rewritten at most this often while runs arrive


class SweepError(UsarsimError):
    """The sweep itself cannot go on (Ray cannot be started or joined)."""


class SweepInterrupted(KeyboardInterrupt):
    """The sweep was stopped (Ctrl-C, SIGINT or SIGTERM) before its last run: the rows that
    arrived are stored, Ray is shut down.  ``outcome`` is what it did until then, ``signum``
    the signal that stopped it (SIGINT for a plain KeyboardInterrupt)."""

    def __init__(self, outcome: SweepOutcome, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.outcome = outcome
        self.signum = signum


class _Signals:
    """The signals :func:`stop_on_signals` caught, the first first."""

    def __init__(self) -> None:
        self.caught: list[int] = []

    @property
    def first(self) -> int | None:
        return self.caught[0] if self.caught else None

    def handle(self, signum: int, frame: Any) -> None:
        self.caught.append(signum)
        raise KeyboardInterrupt(signal.Signals(signum).name)


_signals: _Signals | None = None  # while stop_on_signals is in force


@contextmanager
def stop_on_signals() -> Iterator[_Signals]:
    """While in the block, SIGINT and SIGTERM raise KeyboardInterrupt in the main thread, as
    Ctrl-C does: a sweep stops, stores what finished and shuts Ray down.  Both stop it even
    when this process was started with them ignored (as a script's background job is, for
    SIGINT): a sweep can always be stopped, and goes on later where it stopped.  The handlers
    in force before come back at the end.  Does nothing outside the main thread."""
    global _signals

    caught = _Signals()
    if threading.current_thread() is not threading.main_thread():
        yield caught
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s in previous:
        signal.signal(s, caught.handle)
    _signals, before = caught, _signals
    try:
        yield caught
    finally:
        _signals = before
        for s, old in previous.items():
            signal.signal(s, old if old is not None else signal.SIG_DFL)


# ---------------------------------------------------------------- the sweep


@dataclass
class SweepOutcome:
    """What a sweep did: the rows of the runs it ran (in the order they finished), the runs
    it skipped as done already, the failed ones, and how long it took."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    skipped: int = 0
    failed: int = 0
    elapsed_s: float = 0.0
    ray_start_s: float = 0.0
    collect_s: list[float] = field(default_factory=list)  # per run: task finished -> row stored


def start_ray(workers: int | None, address: str | None) -> bool:
    """Start (or join) Ray unless this process has it already; True when started here.
    Local by default, with ``workers`` CPUs (default: this machine's); ``address`` joins
    an existing cluster (``auto``, ``ray://host:10001``, ``host:6379``)."""
    import ray

    if ray.is_initialized():
        return False
    quiet: dict[str, Any] = {"include_dashboard": False, "logging_level": logging.ERROR, "log_to_driver": False}
    if address:
        _check_reachable(address)
    # ray.init makes SIGTERM exit the driver (sys.exit) after its native crash handler printed
    # a stack dump; a handler the caller put in place (stop_on_signals: store what finished,
    # then stop, in one line) is put back after it
    own_sigterm = signal.getsignal(signal.SIGTERM) if threading.current_thread() is threading.main_thread() else None
    try:
        if address:
            ray.init(address=address, **quiet)
        else:
            ray.init(num_cpus=workers or os.cpu_count() or 1, object_store_memory=128 * 1024 * 1024, **quiet)
    except Exception as exc:  # Ray's own errors: ConnectionError, RuntimeError, its AuthenticationError...
        cause = exc.__cause__ or exc
        why = str(cause).strip().splitlines()[0] if str(cause).strip() else type(cause).__name__
        where = f"join the Ray cluster at {address}" if address else "start Ray on this machine"
        raise SweepError(f"cannot {where}: {why}") from exc
    finally:
        if callable(own_sigterm):
            signal.signal(signal.SIGTERM, own_sigterm)
    return True


def _check_reachable(address: str) -> None:
    """Fail at once on a ``host:port`` that nothing listens on (Ray would retry for ever)."""
    import socket

    host, sep, port = address.rpartition(":")
    if address == "auto" or "://" in address or not sep or not port.isdigit():
        return
    try:
        socket.create_connection((host or "127.0.0.1", int(port)), timeout=5.0).close()
    except OSError as exc:
        raise SweepError(
            f"cannot join the Ray cluster at {address}: nothing answers there ({exc.strerror or exc}); "
            "start its head with 'ray start --head' or give its address"
        ) from None


def run_sweep(
    experiment: Experiment,
    out_dir: str | Path,
    *,
    workers: int | None = None,
    address: str | None = None,
    progress: bool = True,
    console: Any = None,
) -> SweepOutcome:
    """Run every run of ``experiment`` that ``out_dir`` has no successful row of, as Ray
    tasks (at most ``workers`` at a time when given), storing each row as it arrives.

    Interrupted (KeyboardInterrupt: Ctrl-C, or a signal under :func:`stop_on_signals`), it
    stores the rows that arrived, shuts down the Ray it started and raises
    :class:`SweepInterrupted`; the same call later runs only what is missing."""
    import ray

    store = ResultsStore(out_dir)
    done = store.done_ids()
    todo = [r for r in experiment.runs if r.run_id not in done]
    outcome = SweepOutcome(skipped=len(experiment.runs) - len(todo))
    if not todo:
        return outcome
    t0 = time.monotonic()
    was_running = ray.is_initialized()
    bar = _Progress(len(todo), experiment.name, enabled=progress, console=console)
    try:
        start_ray(workers, address)
        outcome.ray_start_s = time.monotonic() - t0
        task = ray.remote(num_cpus=1, max_retries=0)(execute)
        limit = workers or len(todo)
        pending: dict[Any, Run] = {}
        queue = list(todo)
        last_save = 0.0
        with bar:
            while queue or pending:
                while queue and len(pending) < limit:
                    run = queue.pop(0)
                    pending[task.remote(run)] = run
                ready, _ = ray.wait(list(pending), num_returns=1)
                for ref in ready:
                    run = pending.pop(ref)
                    try:
                        row = ray.get(ref)
                    except Exception as exc:  # the worker itself died: the run still gets its row
                        row = _lost_row(run, exc)
                    finished = row.pop("_finished_epoch", None)
                    if row.get("error"):
                        outcome.failed += 1
                    outcome.rows.append(row)
                    store.add(row)
                    if time.monotonic() - last_save >= SAVE_EVERY_S:
                        store.save()
                        last_save = time.monotonic()
                    if finished is not None:
                        outcome.collect_s.append(max(0.0, time.time() - finished))
                    bar.advance(failed=outcome.failed)
    except KeyboardInterrupt as exc:
        interrupted: KeyboardInterrupt | None = exc
    else:
        interrupted = None
    finally:
        _stop(store, shutdown=not was_running)
        outcome.elapsed_s = time.monotonic() - t0
    if interrupted is not None:
        signum = (_signals.first if _signals is not None else None) or signal.SIGINT
        raise SweepInterrupted(outcome, signum) from interrupted
    return outcome


def _stop(store: ResultsStore, *, shutdown: bool) -> None:
    """Store the rows, and shut down the Ray this sweep started (a signal that comes while
    it does is noted, not obeyed: stopping is what it asks for)."""
    import ray

    with _deferred_signals():
        store.save()
        if shutdown and ray.is_initialized():
            ray.shutdown()


@contextmanager
def _deferred_signals() -> Iterator[None]:
    """While in the block, the signals stop_on_signals handles are noted only."""
    caught = _signals
    if caught is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s, old in previous.items():
        if old == caught.handle:
            signal.signal(s, lambda signum, frame: caught.caught.append(signum))
    try:
        yield
    finally:
        for s, old in previous.items():
            signal.signal(s, old)


def _lost_row(run: Run, exc: BaseException) -> dict[str, Any]:
    row = run.columns()
    row.update({c: None for c in SCORE_COLUMNS})
    row.update(
        time_s=None,
        robots=None,
        error=f"the run's Ray task failed: {_describe(exc)}",
        log="",
        finished_at=datetime.now(UTC).isoformat(timespec="seconds"),
    )
    return row


class _Progress:
    """A rich progress bar: runs done, failed, elapsed, time left."""

    def __init__(self, total: int, name: str, *, enabled: bool, console: Any):
        self.enabled = enabled
        self.total = total
        if enabled:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self.progress = Progress(
                TextColumn("[bold]{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("runs, [red]{task.fields[failed]} failed"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                console=console or Console(stderr=True),
            )
            self.task = self.progress.add_task(name, total=total, failed=0)

    def __enter__(self) -> _Progress:
        if self.enabled:
            self.progress.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.enabled:
            self.progress.stop()

    def advance(self, failed: int) -> None:
        if self.enabled:
            self.progress.update(self.task, advance=1, failed=failed)
