"""Pictures of every shipped world for the documentation: one from above (the arena at an
angle, from the image server's free camera) and one from a robot's camera (a P2AT at a start
pose), written as PNG files under docs/images/worlds/.

    MUJOCO_GL=egl python tools/world_pictures.py [--out docs/images/worlds] [WORLD ...]

Rendering is the simulator's own (usarsim.sim.render.RenderService, as the image server
renders), with the world's textures, lights and shadows.
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import numpy as np
from PIL import Image

# The robot camera shown for each world: the start pose whose view tells most about it.
ROBOT_VIEWS = {
    "DM-USAR_yellow": "PlayerStart1",
    "DM-USAR_orange": "PlayerStart5",
    "DM-USAR_red": "PlayerStart2",
    "DM-CollapsedBuilding": "PlayerStart2",
    "DM-Harbour": "Quay1",
    "DM-Road_UrbanChallenge": "PlayerStart1",
}
# The view from above: (look-at point in the USARSim frame, azimuth and elevation in degrees,
# distance in metres); None: the floor's centre, from the south-west, 0.75 of its size away.
TOP_VIEWS = {
    "DM-Road_UrbanChallenge": ((-41.0, -41.0, 0.0), 0.0, -90.0, 55.0),  # a crossing, north up
    "DM-CollapsedBuilding": ((0.0, 0.0, 0.0), 45.0, -40.0, 38.0),
    "DM-Harbour": ((-5.0, 0.0, 0.0), 45.0, -40.0, 70.0),
}
WIDTH, HEIGHT = 480, 360
MAX_BYTES = 120_000  # each file: a README stays light


def save_png(picture: np.ndarray, path: Path) -> int:
    """Save as PNG, reduced to a 128-colour palette when the full colours would pass MAX_BYTES."""
    im = Image.fromarray(picture)
    for colours in (None, 128, 64):
        buf = io.BytesIO()
        (im if colours is None else im.quantize(colours, dither=Image.Dither.NONE)).save(buf, "PNG", optimize=True)
        if buf.tell() <= MAX_BYTES or colours == 64:
            path.write_bytes(buf.getvalue())
            return buf.tell()
    return 0


def world_pictures(name: str, out: Path) -> list[tuple[Path, int]]:
    from usarsim.config.catalog import resolve_robot, resolve_world
    from usarsim.sim.render import RenderService
    from usarsim.sim.simulation import Simulation
    from usarsim.sim.tiles import Tile

    world = resolve_world(name)
    sim = Simulation(world)
    robot = resolve_robot("P2AT")
    shown = ROBOT_VIEWS.get(name, world.start_poses[0].name)
    uid = 0
    for k, pose in enumerate(world.start_poses, start=1):  # a robot at every start pose: they show in the views
        sim.spawn(k, robot, f"R{k}", pose.location, pose.rotation, set_down=True)
        if pose.name == shown:
            uid = k
    sim.advance(1.0)
    service = RenderService(lambda reuse, done: done(sim.cameras.render_snapshot(reuse), None), max_fps=0, shadows=True)
    written = []
    try:
        camera = service.render(WIDTH, HEIGHT, [Tile(uid, "Camera", 0, 0, WIDTH, HEIGHT)]).result(timeout=120)
        fl = world.floor
        look, azimuth, elevation, distance = TOP_VIEWS.get(
            name, ((fl.center[0], fl.center[1], 0.0), 45.0, -50.0, 0.75 * max(fl.size))
        )
        above, _ = service.render_free(
            WIDTH, HEIGHT, lookat=(look[0], -look[1], -look[2]), azimuth=azimuth, elevation=elevation, distance=distance
        ).result(timeout=120)
        for kind, picture in (("above", above), ("camera", camera)):
            path = out / f"{name}-{kind}.png"
            written.append((path, save_png(picture, path)))
    finally:
        service.stop()
    return written


def main(argv=None) -> int:
    from usarsim.config.catalog import world_files

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "images" / "worlds")
    ap.add_argument("worlds", nargs="*", help="world names (default: every shipped world)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for name in args.worlds or sorted(world_files()):
        for path, size in world_pictures(name, args.out):
            print(f"{path} ({size // 1000} kB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
