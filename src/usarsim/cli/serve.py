"""``usarsim serve``: the simulator and its servers until SIGINT/SIGTERM, with the ROS 2 bridge beside it
when asked for."""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import signal
import sys
from pathlib import Path

from usarsim.cli.options import DEFAULT_PORTS, resolve_foxglove_port, resolve_ports

log = logging.getLogger("usarsim")


def _step_grace_s(args: argparse.Namespace) -> float:
    """``--step-grace-us`` in seconds (usarsim.server.ordering.STEP_GRACE_S by default)."""
    from usarsim.server.ordering import STEP_GRACE_S

    return STEP_GRACE_S if args.step_grace_us is None else args.step_grace_us / 1e6


def _raise_file_limit(want: int = 65536) -> None:
    """Every connection, relay port and link is a file descriptor: lift the soft limit on
    them towards the hard one (a desktop's default soft limit, 1024, is less than what the
    servers' own limits allow together)."""
    try:
        import resource
    except ImportError:  # not on this platform
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    target = want if hard == resource.RLIM_INFINITY else min(want, hard)
    if soft != resource.RLIM_INFINITY and soft < target:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
            log.debug("open files limit raised from %d to %d", soft, target)
        except (ValueError, OSError) as exc:
            log.warning("open files limit stays at %d (%s)", soft, exc)


def cmd_serve(args) -> int:
    from usarsim.errors import UsarsimError
    from usarsim.maps.variation import load_arena
    from usarsim.server.app import Application
    from usarsim.server.config import ServeConfig
    from usarsim.server.listener import call_on_loop

    try:
        world = load_arena(args.world, args.variant)
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    for d in args.robot_dir:
        if not os.path.isdir(d):
            print(f"usarsim: error: --robot-dir {d}: no such folder", file=sys.stderr)
            return 1
    try:
        from usarsim.config.robot import class_name_problem, load_robot

        for d in args.robot_dir:
            for path in sorted(Path(d).glob("*.yaml")):
                # a broken robot file is reported now, not when a client asks for it
                problem = class_name_problem(load_robot(path))
                if problem is not None:
                    print(f"usarsim: error: {path}: {problem}", file=sys.stderr)
                    return 1
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    from usarsim.server.image import IMAGE_TYPES, ImageSettings

    image = ImageSettings(
        image_type=IMAGE_TYPES[args.image_type],
        width=args.image_size[0],
        height=args.image_size[1],
        camera_num=max(1, args.multiview_cameras),
        wide_mode=max(0, args.multiview_columns),
        tile_width=args.multiview_tile[0],
        tile_height=args.multiview_tile[1],
        frame_skip=max(0, args.frame_skip),
        max_fps=args.max_fps,
    )
    wireless = wfile = None
    if not args.no_wireless:
        from usarsim.sim.radio import resolve_model
        from usarsim.sim.wireless_file import load_wireless_file

        try:
            wfile = load_wireless_file(args.wireless_config) if args.wireless_config else None
            layer = wfile.radio if wfile is not None else None
            resolve_model(world.wireless, layer, model=args.wireless_model)  # reported now, not at start
        except UsarsimError as exc:
            print(f"usarsim: error: {exc}", file=sys.stderr)
            return 1
    try:
        ports = resolve_ports(
            {name: getattr(args, name) for name in DEFAULT_PORTS},
            args.port_offset,
            {"wcs_port": wfile.listen_port, "cominterface_port": wfile.interface_port} if wfile is not None else None,
        )
    except ValueError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    if not args.no_wireless:
        from usarsim.server.wireless import WirelessOptions

        wireless = WirelessOptions(
            wcs_port=ports["wcs_port"],
            wss_port=ports["wss_port"],
            interface_port=ports["cominterface_port"],
            model=args.wireless_model,
            config=layer,
            debug=bool(wfile and wfile.debug),
            max_connections=max(1, args.max_wireless_connections),
        )
    control_port = ports["port"]
    from usarsim.sim.settings import SimSettings

    threads = args.physics_threads
    try:
        config = ServeConfig(
            world=world,
            sim=SimSettings(
                shadows=args.shadows,
                textures=not args.no_textures,
                antialias=args.antialias,
                physics_threads=None if threads in (None, "auto") else int(threads),
                sensor_thread=not args.sensors_inline,
                report_phases=report_phases(args),
            ),
            host=args.host,
            port=control_port,
            seed=args.seed,
            speed=args.speed,
            lockstep=args.lockstep,
            max_connections=args.max_connections,
            robot_dirs=tuple(args.robot_dir),
            truth_port=ports["truth_port"],
            image_port=None if args.no_image else ports["image_port"],
            image=image,
            wireless=wireless,
            web_port=None if args.no_web else ports["web_port"],
            max_robots=args.max_robots,
            max_line_bytes=max(64, args.max_line_bytes),
            max_pending_bytes=max(4, args.max_pending_kb) * 1024,
            max_viewers=max(1, args.max_viewers),
            max_web_connections=max(2, args.max_web_connections),
            record=args.record if args.record_format == "foxglove" else None,
            foxglove_port=resolve_foxglove_port(args.foxglove, args.port_offset),
            run_options=run_options(args),
            record_cameras_fps=max(0.0, args.record_cameras),
            record_camera_size=args.record_camera_size,
            score=args.score,
            score_file=args.score_file,
            team_map=args.team_map,
            step_grace_s=_step_grace_s(args),
        )
    except ValueError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    app = Application(config, on_score_line=lambda line: print(f"usarsim: {line}", flush=True))

    _raise_file_limit()

    async def main() -> None:
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        # a simulation that stopped on an error (a bug) leaves nothing to serve: the server stops,
        # so that its clients see the connection close instead of a world that stands still
        app.facade.when_failed(lambda exc: call_on_loop(loop, stop.set))
        try:
            await app.start()
        except OSError as exc:
            which = getattr(exc, "usarsim_listener", f"the control port {control_port} (--port)")
            print(f"usarsim: error: cannot listen on {args.host}, {which}: {exc.strerror}", file=sys.stderr)
            raise SystemExit(1) from exc
        for service, host, port in app.listeners():
            print(f"usarsim: {service} listening on {host}:{port}", flush=True)
        if app.web is not None:
            where = "127.0.0.1" if args.host in ("", "0.0.0.0") else args.host
            where = f"[{where}]" if ":" in where else where
            print(f"usarsim: operator console at http://{where}:{app.web.port}/", flush=True)
        if app.recorder is not None and args.record:
            print(
                f"usarsim: recording to {args.record} (written as it goes: a server that is killed loses "
                "about its last second)",
                flush=True,
            )
        bridge = await _start_ros2_bridge(args, app) if args.ros2 else None
        mode = "lock-step" if args.lockstep else ("max speed" if args.speed is None else f"speed {args.speed:g}x")
        log.info(
            "world %s%s loaded (%d start poses), %s, seed %d",
            world.name,
            "" if world.variant is None else f" variant {world.variant}",
            len(world.start_poses),
            mode,
            args.seed,
        )
        await stop.wait()
        failure = app.facade.failure
        if failure is not None:
            print(
                f"usarsim: error: the simulation stopped on an unexpected error ({failure!r}; the log has the "
                "traceback): the server stops",
                file=sys.stderr,
                flush=True,
            )
        log.info("shutting down")
        if bridge is not None:
            await _stop_ros2_bridge(bridge)
        await app.stop()
        if app.recorder is not None and args.record and os.path.isfile(args.record):
            rec = app.recorder
            print(
                f"usarsim: recorded {args.record}: {os.path.getsize(args.record) / 1e6:.1f} MB, {rec.chunks} "
                f"transcript chunks, {rec.messages} other messages, {rec.pictures} camera pictures",
                flush=True,
            )
        if failure is not None:
            raise SystemExit(1)

    from usarsim.server.polling import new_event_loop, poll_seconds

    poll_s = poll_seconds(args.lockstep, args.poll_us)
    try:
        with asyncio.Runner(loop_factory=lambda: new_event_loop(poll_s)) as runner:
            runner.run(main())
    except SystemExit as exc:
        return int(exc.code or 0)
    return 0


async def _start_ros2_bridge(args, app) -> asyncio.subprocess.Process:
    """``usarsim ros2`` for the robots of ``--ros2``, in a process of its own, on the control
    port just opened; its lines go to this server's output."""
    port = next(p for service, _, p in app.listeners() if service == "control")
    host = "127.0.0.1" if args.host in ("", "0.0.0.0", "::") else args.host
    cmd = [sys.executable, "-m", "usarsim", "ros2", "--host", host, "--port", str(port)]
    image = next((p for service, _, p in app.listeners() if service == "image"), None)
    if image is not None:
        cmd += ["--image-port", str(image)]
    else:
        cmd += ["--camera-hz", "0"]
    if args.lockstep:
        cmd.append("--lockstep")
    for robot in args.ros2:
        cmd += ["--robot", robot]
    if args.record and args.record_format == "ros2":
        cmd += ["--bag", args.record.removesuffix(".mcap")]
    log.info("starting the ROS 2 bridge: %s", " ".join(cmd[1:]))
    return await asyncio.create_subprocess_exec(*cmd, stdin=asyncio.subprocess.DEVNULL, start_new_session=True)


async def _stop_ros2_bridge(proc: asyncio.subprocess.Process) -> None:
    if proc.returncode is None:
        proc.terminate()
        try:
            await asyncio.wait_for(proc.wait(), 15.0)
        except TimeoutError:
            proc.kill()
            await proc.wait()
    if proc.returncode not in (0, -signal.SIGTERM):
        print(f"usarsim: the ROS 2 bridge exited {proc.returncode} (its error is above)", file=sys.stderr)


def run_options(args) -> dict:
    """The options of ``serve`` that a replay needs to start the same server (in a
    recording's metadata)."""
    return {
        "robot_dirs": [os.path.abspath(d) for d in args.robot_dir],
        "wireless": not args.no_wireless,
        "wireless_model": args.wireless_model,
        "wireless_config": os.path.abspath(args.wireless_config) if args.wireless_config else None,
        "max_robots": args.max_robots,
        "max_connections": args.max_connections,
        "max_line_bytes": args.max_line_bytes,
        "report_phases": report_phases(args),
    }


def report_phases(args) -> str:
    """``--report-phases``, else spread with the ROS 2 bridge (its readings in small groups) and
    the grid without."""
    return args.report_phases or ("spread" if args.ros2 else "grid")
