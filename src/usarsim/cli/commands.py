"""The commands of ``usarsim`` other than ``serve``: validate, worlds, robots, bench and replay."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path
from typing import Any


def validate_target(text: str) -> str:
    """What ``usarsim validate`` checks: ``text`` itself when it is a file (or looks like a
    path), else the shipped world or robot class of that name (any case; ``USARBot.P2AT``
    too), as ``serve --world`` and INIT find them."""
    from usarsim.config.catalog import robot_files, world_files
    from usarsim.config.reader import did_you_mean
    from usarsim.errors import ConfigError

    p = Path(text)
    if p.exists() or p.suffix.lower() in (".yaml", ".yml", ".rndf", ".mdf") or os.sep in text:
        return text
    bare = text.split(".", 1)[1] if text.lower().startswith("usarbot.") else text
    for name, files in ((text, world_files()), (bare, robot_files())):
        for stem, path in files.items():
            if stem.lower() == name.lower():
                return str(path)
    known = {**world_files(), **robot_files()}
    raise ConfigError(f"'{text}' is no file, shipped world or robot class{did_you_mean(bare, known)}")


def check_robot_items(robot) -> None:
    """What ``usarsim validate`` checks of a robot's items beyond their own settings: each
    type is a registered plugin, a Gripper's ``fingers`` are links of the robot and a
    RollerTable's ``surface`` is the index of one of its chassis pieces (both checked when
    the robot is spawned, too late for the author of the file).  Raises ConfigError."""
    from usarsim.config.reader import did_you_mean
    from usarsim.effecters.gripper import Gripper
    from usarsim.effecters.roller_table import RollerTable
    from usarsim.errors import ConfigError, PluginNotFoundError
    from usarsim.sensors import make_item

    def key_of(item, plugin, field_name: str) -> str:  # the setting as written: surface, Surface
        names = {field_name.lower(), *(a.lower() for a, f in type(plugin).ALIASES.items() if f == field_name)}
        raw = next((str(k) for k in item.params if str(k).lower() in names), None)
        return f"{item.key_path}.{raw}" if raw is not None else item.key_path

    links = [ln.name for ln in robot.links]
    for item in robot.items:
        try:
            plugin = make_item(item, robot, 0, "validate")
        except PluginNotFoundError as exc:
            raise ConfigError(str(exc), path=robot.path, key=f"{item.key_path}.type") from None
        if isinstance(plugin, Gripper):
            fingers = plugin.config.fingers
            for f in [fingers] if isinstance(fingers, str) else fingers:
                if f not in links:
                    hint = did_you_mean(str(f), links) if links else "; this robot has no links"
                    raise ConfigError(
                        f"unknown finger link '{f}': a Gripper's fingers are links of the robot{hint}",
                        path=robot.path,
                        key=key_of(item, plugin, "fingers"),
                    )
        if isinstance(plugin, RollerTable) and plugin.config.surface >= len(robot.chassis):
            n = len(robot.chassis)
            raise ConfigError(
                f"surface {plugin.config.surface} is out of range: it is the index of the chassis "
                f"piece that is the table's top, and this robot has {n} (chassis[0] to "
                f"chassis[{n - 1}])",
                path=robot.path,
                key=key_of(item, plugin, "surface"),
            )


def cmd_validate(args) -> int:
    from usarsim.config.catalog import file_kind
    from usarsim.config.reader import load_yaml, name_entries
    from usarsim.errors import ConfigError, UsarsimError

    path = args.path
    try:
        path = validate_target(args.path)
        kind = file_kind(path)
        if kind in ("rndf", "mdf"):
            from usarsim.config.rndf import describe_route_file

            print(describe_route_file(path))
        elif kind == "world":
            from usarsim.config.world_file import check_world_file
            from usarsim.maps.variation import apply_variant, check_arena
            from usarsim.sim.simulation import Simulation

            variant = getattr(args, "variant", None)
            w = check_world_file(path)
            if variant is not None:
                w = apply_variant(w, variant)
            problems = check_arena(w)
            for found in problems:
                if variant is not None:  # a variant's placing must keep every rule
                    print(f"usarsim: error: {w.name} variant {variant}: {found}", file=sys.stderr)
                else:  # a world as written may hide a victim where few robots get (a void under a slab)
                    logging.getLogger("usarsim.validate").info("%s: %s", w.name, found)
            if problems and variant is not None:
                return 1
            notes = "" if not problems else f", {len(problems)} placement notes (-v lists them)"
            sim = Simulation(w)
            print(
                f"ok: world {w.name}{'' if variant is None else f' variant {variant}'}: {len(w.objects)} objects, "
                f"{len(w.start_poses)} start poses, "
                f"floor {w.floor.size[0]:g} x {w.floor.size[1]:g} m, MuJoCo model with {sim.model.ngeom} geoms{notes}"
            )
        else:
            from usarsim.config.robot import class_name_problem, load_robot
            from usarsim.sim.robotspec import robot_model_summary
            from usarsim.sim.simulation import describe_items

            r = load_robot(path)
            check_robot_items(r)
            items = describe_items(r)
            summary = robot_model_summary(r)
            problem = class_name_problem(r)  # last: what is wrong inside the file comes first
            if problem is not None:
                raise ConfigError(problem, path=path, key="class_name")
            print(
                f"ok: robot {r.class_name}: {r.steering_type}, {r.mass_kg:g} kg, {len(items)} sensors, "
                f"MuJoCo model with {summary}"
            )
    except UsarsimError as exc:
        if isinstance(exc, ConfigError) and exc.path == path:
            try:  # an error about an entry of a list names it (sensors[3] (RangeScanner 'Scanner1'))
                name_entries(exc, load_yaml(path))
            except UsarsimError:
                pass
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    return 0


def cmd_worlds(args) -> int:
    from usarsim.config.catalog import world_files
    from usarsim.config.world_file import load_world

    for path in world_files().values():
        w = load_world(path)
        print(f"{w.name}  {w.description}")
    return 0


def cmd_robots(args) -> int:
    from usarsim.config.catalog import robot_files
    from usarsim.config.robot import load_robot

    files = robot_files([args.robot_dir] if getattr(args, "robot_dir", None) else [])
    if getattr(args, "picture", None):
        return _robot_picture(args, files)
    for path in files.values():
        r = load_robot(path)
        kit = ", ".join(sorted({i.item_type for i in r.items}))
        drive = r.drive if r.steering_type in ("", "None") else f"{r.drive} ({r.steering_type})"
        print(f"{r.class_name:<11} {drive:<27} {r.description}\n{'':<11} {'':<27} kit: {kit}")
    return 0


# The tiles of ``usarsim robots --picture``: each robot's portrait with its name below
TILE_W, TILE_H, LABEL_H, COLUMNS = 320, 240, 22, 4


def _robot_picture(args, files) -> int:
    """Draw the robot classes (``--robot``, or all of ``files``) in a grid of portraits."""
    import numpy as np
    from PIL import Image, ImageDraw

    from usarsim.config.robot import load_robot
    from usarsim.errors import ConfigError
    from usarsim.sim.gallery import robot_portrait

    names = args.robot or list(files)
    unknown = [n for n in names if n not in files]
    if unknown:
        print(f"usarsim: error: unknown robot class {unknown[0]!r} (usarsim robots lists them)", file=sys.stderr)
        return 1
    columns = min(COLUMNS, len(names))
    rows = -(-len(names) // columns)
    sheet = Image.new("RGB", (columns * TILE_W, rows * (TILE_H + LABEL_H)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for k, name in enumerate(names):
        try:
            robot = load_robot(files[name])
        except ConfigError as exc:
            print(f"usarsim: error: {exc}", file=sys.stderr)
            return 1
        x, y = (k % columns) * TILE_W, (k // columns) * (TILE_H + LABEL_H)
        sheet.paste(Image.fromarray(np.asarray(robot_portrait(robot, TILE_W, TILE_H))), (x, y))
        draw.text((x + 8, y + TILE_H + 5), robot.class_name, fill=(20, 20, 20))
        print(f"drew {robot.class_name}", file=sys.stderr)
    sheet.save(args.picture)
    print(f"wrote {args.picture}: {len(names)} robot(s), {sheet.width}x{sheet.height}")
    return 0


def cmd_bench(args) -> int:
    from usarsim.errors import ConfigError

    try:
        return _bench(args)
    except ConfigError as exc:  # the world asked for: said in one line, as serve says it
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1


def _bench(args) -> int:
    from usarsim.bench import run_bench, run_camera_bench

    if args.env:
        return run_env_bench(args)
    if args.targets:
        from usarsim.bench.targets import run_targets_bench

        return run_targets_bench(args)
    if getattr(args, "league", False):
        from usarsim.bench.league import run_league_bench

        return run_league_bench(args)
    if args.ros2:
        from usarsim.ros2.bench import run_ros2_bench

        return run_ros2_bench(args)
    if getattr(args, "radio_load", False):
        from usarsim.bench.radio import run_radio_bench

        return run_radio_bench(args)
    if args.round_trips:
        from usarsim.bench import run_round_trip_bench

        return run_round_trip_bench(args)
    return run_camera_bench(args) if args.cameras else run_bench(args)


def cmd_replay(args) -> int:
    from usarsim.replay import main as replay_main

    return replay_main(args)


def run_env_bench(args) -> int:
    """Environment steps per second (usarsim.envs.bench_env), one robot and a team."""
    import json

    from usarsim.envs import bench_env

    transports = ("tcp", "inproc") if args.transport == "both" else (args.transport,)
    if args.profile:
        from usarsim.envs.profile import env_profile, print_profile

        print(f"Where an env step's time goes ({args.world}, {args.steps} steps, random actions):")
        profiles = []
        for transport in transports:
            profiles.append(env_profile(args.steps, world=args.world, transport=transport))
            if args.team > 0:
                profiles.append(
                    env_profile(max(1, args.steps // 3), team=args.team, world=args.world, transport=transport)
                )
        if args.json:
            print(json.dumps(profiles))
        else:
            for p in profiles:
                print_profile(p)
        return 0
    from usarsim.envs.bench import bench_one_and_vector

    rows: list[dict[str, Any]] = []
    for transport in transports:
        if transport == "inproc" and args.worlds > 1:  # the one world timed in turns with the vector
            both = bench_one_and_vector(args.steps, args.worlds, world=args.world)
            one = both["one"]
            rows.append({"transport": transport, "env": "Explore-v0", "robots": 1, "steps_per_s": round(one, 1)})
            rows.append(
                {
                    "transport": transport,
                    "env": f"ExploreVectorEnv({args.worlds})",
                    "robots": 1,
                    "worlds": args.worlds,
                    "steps_per_s": round(both["vector"], 1),
                    "times_one": round(both["times_one"], 2),
                    "stretches": both["blocks"],
                }
            )
        else:
            one = bench_env(args.steps, world=args.world, transport=transport)
            rows.append({"transport": transport, "env": "Explore-v0", "robots": 1, "steps_per_s": round(one, 1)})
        if args.team > 0:
            team = bench_env(max(1, args.steps // 3), team=args.team, world=args.world, transport=transport)
            rows.append(
                {"transport": transport, "env": "TeamExplore", "robots": args.team, "steps_per_s": round(team, 1)}
            )
    if args.json:
        print(json.dumps({"control_period_s": 0.1, "cpu_count": os.cpu_count(), "rows": rows}))
        return 0
    for row in rows:
        path = "in-process" if row["transport"] == "inproc" else "over TCP"
        what = "one P2AT" if row["robots"] == 1 else f"{row['robots']} P2ATs"
        unit = "env steps/s" if row["robots"] == 1 else "team steps/s"
        rate = row["steps_per_s"]
        if "worlds" in row:
            spread = row["stretches"]
            print(
                f"{row['env']}, {row['worlds']} worlds of one P2AT at 0.1 s, {path} in worker processes: "
                f"{rate:.0f} env steps/s in all ({row['times_one']:.2f} times one world: the median of "
                f"{len(spread)} stretches timed in turns with it, {min(spread):.2f} - {max(spread):.2f})"
            )
            continue
        print(f"{row['env']}, {what} at 0.1 s, {path}: {rate:.0f} {unit} ({rate * 0.1:.0f}x real time)")
    return 0
