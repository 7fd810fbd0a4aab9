"""``usarsim map`` (a world's ground-truth map as map_server files and a picture) and ``usarsim
score-map`` (a team's map scored against it): docs/scoring.md, "Map quality"."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from usarsim.maps.truth import DEFAULT_HEIGHT_M, DEFAULT_RESOLUTION_M


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of metres, got {text!r}") from None
    if not v > 0 or v > 100:
        raise argparse.ArgumentTypeError(f"expected a number of metres > 0, got {text!r}")
    return v


def add_parsers(sub) -> None:
    from usarsim.cli.options import _variant

    m = sub.add_parser(
        "map",
        help="write a world's ground-truth occupancy map (map_server PGM and YAML, and a PNG)",
        description="Write the ground-truth occupancy grid of a world (a variant of it with --variant) at a "
        "robot's sensing height: OUT.pgm and OUT.yaml as ROS's map_server reads them (in the ROS map frame, "
        "as the ROS 2 bridge's 'map'), and OUT.png for people with the victims (red), RFID tags (blue) and "
        "start poses (green) drawn. A cell is occupied where a solid stands at that height, free where a "
        "robot could drive to it from a start pose, unknown elsewhere. The same world and variant give "
        "the same files, byte for byte.",
    )
    m.add_argument("world", metavar="WORLD", help="a shipped world (usarsim worlds) or the path of a world file")
    m.add_argument("--variant", type=_variant, metavar="N", help="the world's variant N (default: as written)")
    m.add_argument(
        "--resolution",
        type=_positive,
        default=DEFAULT_RESOLUTION_M,
        metavar="M",
        help="cell size in metres (default: %(default)s)",
    )
    m.add_argument(
        "--height",
        type=_positive,
        default=DEFAULT_HEIGHT_M,
        metavar="M",
        help="sensing height above the floor, metres (default: %(default)s, a P2AT's laser)",
    )
    m.add_argument(
        "--out",
        metavar="PREFIX",
        help="where to write PREFIX.yaml, PREFIX.pgm and PREFIX.png (default: WORLD, or WORLD-vN for a "
        "variant, in the current folder)",
    )
    m.set_defaults(handler=cmd_map)

    s = sub.add_parser(
        "score-map",
        help="score a team's map (map_server YAML) against a world's ground truth",
        description="Align a team's occupancy map (a map_server YAML file and its picture) to the ground "
        "truth of a world (a rigid transform, found and reported), then score it: coverage of the "
        "reachable free floor, accuracy of its occupied and free cells, the alignment's residual, and the "
        "victims it lists (its 'victims' key, in its own frame) lying within 1 m of a real one. Each "
        "metric is defined in docs/scoring.md.",
    )
    s.add_argument("team_map", metavar="TEAM_MAP.yaml", help="the team's map: a map_server YAML file")
    s.add_argument("--world", required=True, help="the world the map was made in (a name or a world file)")
    s.add_argument("--variant", type=_variant, metavar="N", help="the world's variant (default: as written)")
    s.add_argument(
        "--height",
        type=_positive,
        default=DEFAULT_HEIGHT_M,
        metavar="M",
        help="the ground truth's sensing height, metres (default: %(default)s)",
    )
    s.add_argument("--json", action="store_true", help="print the score as JSON instead of a table")
    s.add_argument("--picture", metavar="PNG", help="also draw the team's map aligned over the ground truth")
    s.set_defaults(handler=cmd_score_map)


def cmd_map(args) -> int:
    from usarsim.errors import UsarsimError
    from usarsim.maps.mapfile import draw_map, write_map
    from usarsim.maps.truth import ground_truth_map
    from usarsim.maps.variation import load_arena

    try:
        world = load_arena(args.world, args.variant)
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    truth = ground_truth_map(world, resolution=args.resolution, height=args.height, variant=args.variant)
    out = Path(args.out or (world.name if args.variant is None else f"{world.name}-v{args.variant}"))
    yaml_path = write_map(
        out.with_suffix(".yaml"),
        truth.grid,
        extra={"world": world.name, "variant": args.variant, "height": args.height},
        victims=[(v.name, v.x, v.y) for v in truth.victims()],
    )
    png = draw_map(out.with_suffix(".png"), truth.grid, truth.markers)
    rows, cols = truth.grid.shape
    cell = truth.grid.resolution**2
    print(
        f"{world.name}{'' if args.variant is None else f' variant {args.variant}'}: {cols} x {rows} cells of "
        f"{truth.grid.resolution:g} m at {args.height:g} m above the floor, {truth.grid.free.sum() * cell:.1f} m2 "
        f"free, {truth.grid.occupied.sum() * cell:.1f} m2 occupied, {len(truth.victims())} victims"
    )
    print(f"wrote {yaml_path}, {yaml_path.with_suffix('.pgm')} and {png}")
    return 0


def cmd_score_map(args) -> int:
    from usarsim.errors import UsarsimError
    from usarsim.maps.mapfile import read_map
    from usarsim.maps.quality import score_map
    from usarsim.maps.truth import ground_truth_map
    from usarsim.maps.variation import load_arena

    try:
        team = read_map(args.team_map)
        world = load_arena(args.world, args.variant)
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    truth = ground_truth_map(world, height=args.height, variant=args.variant)
    score = score_map(team, truth)
    result = score.as_dict()
    if args.picture:
        from usarsim.maps.picture import draw_overlay

        draw_overlay(args.picture, team.grid, truth, result, victims=team.victims)
        result["picture"] = args.picture
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(format_score(result, world.name, args.variant))
    return 0


def format_score(r: dict, world: str, variant: int | None) -> str:
    """The score of a map as the terminal shows it."""
    a = {k: (round(v, 3) + 0.0 if isinstance(v, float) else v) for k, v in r["alignment"].items()}  # no -0.000
    lines = [
        f"map scored against {world}{'' if variant is None else f' variant {variant}'}:",
        f"  alignment       turned {a['theta_deg']:+.2f} deg, moved ({a['tx']:+.3f}, {a['ty']:+.3f}) m, "
        f"residual {'-' if r['residual_m'] is None else format(r['residual_m'], '.3f')} m",
        f"  coverage        {100 * r['coverage']:.1f} % of the reachable free floor",
        f"  accuracy        {100 * r['accuracy']:.1f} % (occupied cells {100 * r['occupied_accuracy']:.1f} % "
        f"right, free cells {100 * r['free_accuracy']:.1f} % right)",
        f"  victims on map  {r['victims_on_map']} of {r['victims_total']} ({r['victims_reported']} reported)",
    ]
    return "\n".join(lines)
