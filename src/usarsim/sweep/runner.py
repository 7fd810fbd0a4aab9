"""Running a sweep: each run a Ray task that starts its own simulator, runs the controller
for the simulated duration, stops the simulator and returns one row with its score.

:func:`execute` is one run, on whatever process calls it (a Ray worker in a sweep); it
never raises: a run that fails returns its row with the error and the tail of the
simulator's log.  :func:`run_sweep` submits the runs not done yet to Ray (local by default,
a cluster when given its address), shows the progress and stores every row as it arrives.
"""

from __future__ import annotations

import json
import logging
import os
import platform
import shlex
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from usarsim.errors import UsarsimError
from usarsim.sweep.experiment import Experiment, Run, brain_parameters, resolve_brain
from usarsim.sweep.results import SCORE_COLUMNS, ResultsStore

log = logging.getLogger("usarsim.sweep")

LOG_TAIL_CHARS = 3000  # of the simulator's log (stderr), kept in the row of a failed run
OUTPUT_TAIL_CHARS = 1500  # of a controller command's output, in its error
POLL_S = 0.05  # how often the clock of a run driven by a command is looked at (wall seconds)
# In lock-step a command drives the clock itself: once the duration is reached it has this
# long (wall seconds) to stop by itself before it is stopped.
GRACE_S = 3.0
SAVE_EVERY_S = 2.0  # the results files are rewritten at most this often while runs arrive


class RunFailed(Exception):
    """A run could not be completed; the message says why."""


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


# ---------------------------------------------------------------- one run


def execute(run: Run) -> dict[str, Any]:
    """Run ``run`` here and return its row: the configuration columns, the team's scores,
    the simulated time the score covers, wall times of each phase, the error (None when it
    went well) and, for a failed run, the tail of the simulator's log."""
    from usarsim.client import launch

    row: dict[str, Any] = run.columns()
    row.update({c: None for c in SCORE_COLUMNS})
    row.update(time_s=None, robots=None, error=None, log="", node=platform.node())
    t0 = time.monotonic()
    phases = {"start_s": 0.0, "setup_s": 0.0, "control_s": 0.0, "stop_s": 0.0}
    tmp = Path(tempfile.mkdtemp(prefix="usarsim-run-"))
    score_path = tmp / "score.json"
    server = None
    timed_out = threading.Event()
    watchdog: threading.Timer | None = None
    error: str | None = None
    try:
        extra = ["--score-file", str(score_path)]
        if run.wireless not in ("off", "world"):
            extra += ["--wireless-model", run.wireless]
        server = launch(
            world=run.world,
            seed=run.seed,
            lockstep=run.clock == "lockstep",
            speed=None,
            wireless=run.wireless != "off",
            robot_dirs=run.robot_dirs,
            extra_args=tuple(extra),
        )
        phases["start_s"] = time.monotonic() - t0

        def on_timeout() -> None:
            timed_out.set()
            if server.proc.poll() is None:
                server.proc.terminate()  # the controller's next wait fails; the score is still written

        watchdog = threading.Timer(max(0.0, run.timeout_s - (time.monotonic() - t0)), on_timeout)
        watchdog.daemon = True
        watchdog.start()
        if run.controller.kind == "brain":
            _run_brain(run, server, phases)
        else:
            _run_command(run, server, tmp, phases, deadline=t0 + run.timeout_s)
    except Exception as exc:  # a failed run is a row, never the end of the sweep
        error = _describe(exc)
    finally:
        if watchdog is not None:
            watchdog.cancel()
        t_stop = time.monotonic()
        if server is not None:
            server.close(keep_stderr=True)  # SIGTERM: the simulator writes the score file
            row["log"] = server.stderr_tail(LOG_TAIL_CHARS)
            server.close()
        if timed_out.is_set():
            error = f"timed out after {run.timeout_s:g} s of wall time (the experiment's 'timeout')"
        if server is not None:
            try:
                _read_score(score_path, row)
            except RunFailed as exc:
                error = error or str(exc)
        phases["stop_s"] = time.monotonic() - t_stop
        shutil.rmtree(tmp, ignore_errors=True)
    row.update({k: round(v, 4) for k, v in phases.items()})
    row["wall_s"] = round(time.monotonic() - t0, 4)
    row["error"] = error
    if error is None:
        row["log"] = ""
    else:  # what the simulator scored of a failed run stays out of the score columns (time_s tells how far it got)
        row.update({c: None for c in SCORE_COLUMNS})
    row["finished_at"] = datetime.now(UTC).isoformat(timespec="seconds")
    row["_finished_epoch"] = time.time()
    return row


def _describe(exc: BaseException) -> str:
    text = str(exc).strip()
    if isinstance(exc, RunFailed):
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _read_score(path: Path, row: dict[str, Any]) -> None:
    """The team's scores of the simulator's score file (serve --score-file) into ``row``."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RunFailed("the simulator wrote no score file (see its log)") from None
    except (OSError, ValueError) as exc:
        raise RunFailed(f"the simulator's score file cannot be read: {exc}") from None
    team = data.get("team") or {}
    for c in SCORE_COLUMNS:
        row[c] = team.get(c)
    row["time_s"] = data.get("time_s")
    row["robots"] = json.dumps(data.get("robots") or {}, sort_keys=True)


def _spawn_team(run: Run, world: Any) -> list[tuple[Any, tuple[float, float, float]]]:
    """Every robot of the team in the world, with the world pose it starts from (x, y, yaw)."""
    poses = {p.name: p for p in world.start_poses}
    out = []
    for m in run.team:
        if m.location is not None:
            robot = world.spawn(m.robot, m.name, location=m.location, rotation=(0.0, 0.0, m.yaw))
            out.append((robot, (m.location[0], m.location[1], m.yaw)))
        else:
            pose = poses[m.start]
            robot = world.spawn(m.robot, m.name, start=m.start)
            out.append((robot, (pose.location[0], pose.location[1], pose.rotation[2])))
    return out


def brain_kwargs(run: Run, factory: Callable[..., Any], index: int) -> dict[str, Any]:
    """The keyword arguments of the ``index``-th robot's brain: the experiment's ``params``,
    ``bounds`` as a :class:`usarsim.brains.Bounds` (four numbers, or ``auto``: the box of the
    world's static solids), and ``seed`` (when the brain takes one and the file gives none)
    from the run's seed, so that each seed varies the brain's own choices too."""
    kwargs = run.controller.param_dict
    if "bounds" in kwargs:
        from usarsim.brains import Bounds

        b = kwargs["bounds"]
        if b == "auto":
            from usarsim.brains.coverage import FloorMap
            from usarsim.config.catalog import resolve_world

            b = [float(v) for v in FloorMap.from_world(resolve_world(run.world)).solids_box]
        kwargs["bounds"] = Bounds(*(float(v) for v in b))
    accepted = brain_parameters(factory)
    if "seed" not in kwargs and accepted is not None and "seed" in accepted:
        kwargs["seed"] = run.seed * 1000 + index
    return kwargs


def _run_brain(run: Run, server: Any, phases: dict[str, float]) -> None:
    from usarsim.brains.runner import run as run_brains

    t = time.monotonic()
    factory = resolve_brain(run.controller.target)
    period = run.controller.period
    with server.connect() as world:
        brains = [
            factory(robot, origin=origin, **brain_kwargs(run, factory, i))
            for i, (robot, origin) in enumerate(_spawn_team(run, world))
        ]
        if world.lockstep:
            world.step(period)  # the first readings
        phases["setup_s"] = time.monotonic() - t
        t = time.monotonic()
        run_brains(world, brains, run.duration_s, period=period, until_done="never")
        phases["control_s"] = time.monotonic() - t


def command_values(run: Run, server: Any) -> dict[str, str]:
    """What a controller command's placeholders stand for (docs/experiments.md)."""
    first = run.team[0]
    team = [f"{m.robot}:{m.name}:{m.start or ''}" for m in run.team]
    return {
        "host": server.host,
        "port": str(server.port),
        "truth_port": str(server.ports.get("truth", "")),
        "wcs_port": str(server.ports.get("comserver", "")),
        "seconds": f"{run.duration_s:g}",
        "seed": str(run.seed),
        "world": run.world,
        "lockstep": "1" if run.clock == "lockstep" else "0",
        "robot": first.robot,
        "name": first.name,
        "start": first.start or "",
        "team": ",".join(team),
    }


def _run_command(run: Run, server: Any, tmp: Path, phases: dict[str, float], deadline: float) -> None:
    """Run the controller command until it exits or the simulated time reaches the
    duration (then it is stopped: SIGTERM, SIGKILL 5 s later)."""
    from usarsim.client import connect

    t = time.monotonic()
    values = command_values(run, server)
    argv = [part.format(**values) for part in shlex.split(run.controller.target)]
    env = dict(os.environ)
    env.update({f"USARSIM_{k.upper()}": v for k, v in values.items()})
    env["USARSIM_TEAM_JSON"] = json.dumps([m.as_dict() for m in run.team])
    out_path = tmp / "controller.log"
    with (
        open(out_path, "w+b") as out,
        connect(server.host, server.port, lockstep=False, truth_port=server.ports["truth"]) as clock,
    ):
        try:
            proc = subprocess.Popen(
                argv, cwd=run.cwd, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, env=env
            )
        except OSError as exc:
            raise RunFailed(f"the controller command cannot start: {exc}") from None
        phases["setup_s"] = time.monotonic() - t
        t = time.monotonic()
        stopped = False
        reached: float | None = None  # when the simulated time reached the duration (wall)
        try:
            while proc.poll() is None:
                if time.monotonic() > deadline:
                    break  # the watchdog says so
                if server.proc.poll() is not None:
                    raise RunFailed("the simulator stopped while the controller ran (see its log)")
                if reached is None:
                    now = [o.time for o in clock.truth()]
                    if now and max(now) >= run.duration_s - 1e-9:
                        reached = time.monotonic()
                if reached is not None and (run.clock != "lockstep" or time.monotonic() - reached > GRACE_S):
                    stopped = True
                    break
                time.sleep(POLL_S)
        finally:
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(5)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(5)
        phases["control_s"] = time.monotonic() - t
        if not stopped and proc.returncode != 0 and time.monotonic() <= deadline:
            out.seek(0)
            tail = out.read().decode("utf-8", "replace")[-OUTPUT_TAIL_CHARS:].strip()
            raise RunFailed(
                f"the controller exited with code {proc.returncode}" + (f": {tail}" if tail else " and printed nothing")
            )


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
    quiet = {"include_dashboard": False, "logging_level": logging.ERROR, "log_to_driver": False}
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
