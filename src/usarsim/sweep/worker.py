"""One run of a sweep, on whatever process calls it (a Ray worker in a sweep): start its own
simulator, spawn the team, drive it with the run's controller (a Python brain, or a command
that connects itself) for the simulated duration, stop the simulator and return the run's
row with its score.

:func:`execute` never raises: a run that fails returns its row with the error and the tail
of the simulator's log.
"""

from __future__ import annotations

import functools
import json
import logging
import os
import platform
import shlex
import shutil
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from usarsim.sweep.results import MAP_COLUMNS, SCORE_COLUMNS
from usarsim.sweep.runs import Run, brain_parameters, resolve_brain

log = logging.getLogger("usarsim.sweep")

TEAM_MAP = "team_map.yaml"  # where a run's team hands its map in (its folder; serve --team-map)
LOG_TAIL_CHARS = 3000  # of the simulator's log (stderr), kept in the row of a failed run
OUTPUT_TAIL_CHARS = 1500  # of a controller command's output, in its error
POLL_S = 0.05  # how often the clock of a run driven by a command is looked at (wall seconds)
# In lock-step a command drives the clock itself: once the duration is reached it has this
# long (wall seconds) to stop by itself before it is stopped.
GRACE_S = 3.0


class RunFailed(Exception):
    """A run could not be completed; the message says why."""


def execute(run: Run) -> dict[str, Any]:
    """Run ``run`` here and return its row: the configuration columns, the team's scores,
    the simulated time the score covers, wall times of each phase, the error (None when it
    went well) and, for a failed run, the tail of the simulator's log."""
    from usarsim.client import launch

    row: dict[str, Any] = run.columns()
    row.update({c: None for c in (*SCORE_COLUMNS, *MAP_COLUMNS)})
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
        extra = ["--score-file", str(score_path), *server_arguments(run)]
        if run.maps_dir:
            extra += ["--team-map", str(tmp / TEAM_MAP)]
        server = launch(
            world=run.world,
            variant=run.variant,
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
            _run_brain(run, server, phases, tmp / TEAM_MAP)
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
            if run.maps_dir:
                _keep_map(run, tmp, score_path)
        phases["stop_s"] = time.monotonic() - t_stop
        shutil.rmtree(tmp, ignore_errors=True)
    row.update({k: round(v, 4) for k, v in phases.items()})
    row["wall_s"] = round(time.monotonic() - t0, 4)
    row["error"] = error
    if error is None:
        row["log"] = ""
    else:  # what the simulator scored of a failed run stays out of the score columns (time_s tells how far it got)
        row.update({c: None for c in (*SCORE_COLUMNS, *MAP_COLUMNS)})
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
    if not data.get("radio"):  # no link counted a message (USARSim's ideal channel counts none)
        row["messages_delivered"] = row["messages_lost"] = None
    row["time_s"] = data.get("time_s")
    row["robots"] = json.dumps(data.get("robots") or {}, sort_keys=True)
    m = data.get("map")
    if isinstance(m, dict) and "coverage" in m:
        row.update(
            map_coverage=m["coverage"],
            map_accuracy=m["accuracy"],
            map_residual_m=m["residual_m"],
            map_victims=m["victims_on_map"],
        )


@functools.lru_cache(maxsize=8)
def _ground_truth(world: str, variant: int | None, stamp: int) -> Any:
    """The ground-truth map of ``world`` (a file, as of its modification time ``stamp``, or a
    shipped world) and ``variant``, made once in this process: a competition's teams and seeds
    play each scenario again (about 0.2 s saved a run)."""
    from usarsim.maps.truth import ground_truth_map
    from usarsim.maps.variation import load_arena

    return ground_truth_map(load_arena(world, variant), variant=variant)


def _modified(path: str) -> int:
    """A world file's modification time in nanoseconds (0 for a shipped world's name)."""
    try:
        return os.stat(path).st_mtime_ns
    except OSError:
        return 0


def _keep_map(run: Run, tmp: Path, score_path: Path) -> None:
    """The team's map (as handed in) and a picture of it over the ground truth, in the run's maps
    folder as ``<run_id>.yaml``, ``.pgm`` and ``.png`` (the ground truth alone when no map came)."""
    from usarsim.maps.mapfile import read_map, write_map
    from usarsim.maps.picture import draw_overlay

    folder = Path(run.maps_dir)
    folder.mkdir(parents=True, exist_ok=True)
    try:
        score = json.loads(score_path.read_text(encoding="utf-8")).get("map") or {}
    except (OSError, ValueError):
        score = {}
    try:
        truth = _ground_truth(run.world, run.variant, _modified(run.world))
        team = read_map(tmp / TEAM_MAP) if (tmp / TEAM_MAP).exists() else None
        if team is not None:
            write_map(folder / f"{run.run_id}.yaml", team.grid, victims=team.victims)
        draw_overlay(
            folder / f"{run.run_id}.png",
            None if team is None else team.grid,
            truth,
            score,
            victims=() if team is None else team.victims,
        )
    except Exception as exc:  # a picture that cannot be drawn never fails the run
        log.warning("run %s: the map's picture cannot be drawn: %s", run.run_id, exc)


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


def _run_brain(run: Run, server: Any, phases: dict[str, float], map_path: Path) -> None:
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
        if run.maps_dir:  # the team hands its map in before the simulator stops
            from usarsim.brains.teammap import write_team_map

            write_team_map(brains, map_path)


def command_values(run: Run, server: Any, map_path: str = "") -> dict[str, str]:
    """What a controller command's placeholders stand for (docs/experiments.md); ``map_path``:
    where the team hands its map in (empty when it hands none in)."""
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
        "map": map_path,
    }


def _run_command(run: Run, server: Any, tmp: Path, phases: dict[str, float], deadline: float) -> None:
    """Run the controller command until it exits or the simulated time reaches the
    duration (then it is stopped: SIGTERM, SIGKILL 5 s later); isolated, one for each robot,
    each in a network namespace of its own (:mod:`usarsim.sweep.isolation`)."""
    from usarsim.client import connect

    t = time.monotonic()
    values = command_values(run, server, str(tmp / TEAM_MAP) if run.maps_dir else "")
    relay = None
    if run.controller.isolate:
        from usarsim.sweep.isolation import REACHABLE, HostRelay, isolation_problem

        problem = isolation_problem()
        if problem is not None:
            raise RunFailed(f"the controllers cannot be isolated: {problem}")
        relay = HostRelay(server.host, [server.ports[k] for k in REACHABLE if k in server.ports])
        commands = [
            (relay.launcher(command_argv(run, v)), v, f"controller-{m.name}.log")
            for m, v in ((m, member_values(values, m)) for m in run.team)
        ]
    else:
        commands = [(command_argv(run, values), values, "controller.log")]
    procs: list[tuple[subprocess.Popen, Any]] = []
    try:
        with connect(server.host, server.port, lockstep=False, truth_port=server.ports["truth"]) as clock:
            for argv, vals, log_name in commands:
                out = open(tmp / log_name, "w+b")  # noqa: SIM115 (closed below, with its process)
                try:
                    procs.append((start_command(run, argv, vals, out), out))
                except BaseException:
                    out.close()
                    raise
            phases["setup_s"] = time.monotonic() - t
            t = time.monotonic()
            stopped = _wait_commands(run, server, clock, [p for p, _ in procs], deadline)
        phases["control_s"] = time.monotonic() - t
        for proc, out in procs:
            if not stopped and proc.returncode not in (None, 0) and time.monotonic() <= deadline:
                out.seek(0)
                tail = out.read().decode("utf-8", "replace")[-OUTPUT_TAIL_CHARS:].strip()
                raise RunFailed(
                    f"the controller exited with code {proc.returncode}"
                    + (f": {tail}" if tail else " and printed nothing")
                )
    finally:
        for proc, out in procs:
            stop_process(proc)
            out.close()
        if relay is not None:
            relay.close()


def command_argv(run: Run, values: dict[str, str]) -> list[str]:
    """The controller command's words, its placeholders filled in."""
    return [part.format(**values) for part in shlex.split(run.controller.target)]


def member_values(values: dict[str, str], member: Any) -> dict[str, str]:
    """``values`` with ``{robot}``, ``{name}`` and ``{start}`` those of one team ``member``."""
    return {**values, "robot": member.robot, "name": member.name, "start": member.start or ""}


def start_command(run: Run, argv: list[str], values: dict[str, str], out: Any) -> subprocess.Popen:
    env = dict(os.environ)
    env.update({f"USARSIM_{k.upper()}": v for k, v in values.items()})
    env["USARSIM_TEAM_JSON"] = json.dumps([m.as_dict() for m in run.team])
    try:
        return subprocess.Popen(
            argv, cwd=run.cwd, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, env=env
        )
    except OSError as exc:
        raise RunFailed(f"the controller command cannot start: {exc}") from None


def _wait_commands(run: Run, server: Any, clock: Any, procs: list[subprocess.Popen], deadline: float) -> bool:
    """Wait until every process exits, the watchdog's deadline, or the simulated duration
    (True: they were stopped then)."""
    reached: float | None = None  # when the simulated time reached the duration (wall)
    # isolated controllers each spawn their robot: the duration counts from when all stand
    started: float | None = None if run.controller.isolate else 0.0
    team = {m.name.lower() for m in run.team}
    while any(p.poll() is None for p in procs):
        if any(p.returncode not in (None, 0) for p in procs):
            return False  # one failed: the run fails now
        if time.monotonic() > deadline:
            return False  # the watchdog says so
        if server.proc.poll() is not None:
            raise RunFailed("the simulator stopped while the controller ran (see its log)")
        if reached is None:
            objects = clock.truth()
            now = max((o.time for o in objects), default=None)
            if started is None and now is not None and team <= {o.name.lower() for o in objects}:
                started = now
            if started is not None and now is not None and now - started >= run.duration_s - 1e-9:
                reached = time.monotonic()
        if reached is not None and (run.clock != "lockstep" or time.monotonic() - reached > GRACE_S):
            return True
        time.sleep(POLL_S)
    return False


def stop_process(proc: subprocess.Popen) -> None:
    """SIGTERM, then SIGKILL 5 s later."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def server_arguments(run: Run) -> list[str]:
    """The simulator's options for ``run``'s radio: a wireless configuration file, or a radio
    model (none for the world's own, or with the wireless servers off)."""
    if run.wireless.lower().endswith((".yaml", ".yml", ".ini")):
        return ["--wireless-config", run.wireless]
    if run.wireless not in ("off", "world"):
        return ["--wireless-model", run.wireless]
    return []
