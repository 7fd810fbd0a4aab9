"""The four kinds of camera picture of one view, side by side: colour, depth, thermal and labels.

It starts a lock-step simulator of its own with its image server (or uses a running one with
--port), puts a P2AT two metres from a victim of DM-USAR_yellow, switches its camera through the
four kinds with ``SET {Type Camera} {Name Camera} {Opcode Picture} {Params <kind>}``, takes a
picture of each from the image server and writes them as one PNG, each drawn for people to look
at (depth: near bright, far dark; temperature: a thermal palette, the victim's skin brightest; labels: a
colour per class), with the numbers it read printed.

    python examples/camera_kinds.py                     # writes camera_kinds.png
    python examples/camera_kinds.py --out view.png --port 3000 --lockstep
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
from PIL import Image, ImageDraw

from usarsim.client import ClientError, connect, launch

KINDS = ("colour", "depth", "thermal", "label")
# where the robot stands: 2 m from Ben (DM-USAR_yellow's second victim), looking at him
LOCATION, ROTATION = (2.1, 4.37, -0.3), (0.0, 0.0, 1.0472)
STEP_C = 0.2  # a thermal level, degrees Celsius (docs/protocol.md, "Pictures beyond colour")
# labels: nothing, floor, wall, obstacle, victim, false alarm, robot
PALETTE = np.array(
    [[0, 0, 0], [90, 90, 90], [230, 200, 80], [150, 100, 60], [230, 40, 40], [60, 120, 230], [60, 200, 90]]
)
CLASS_NAMES = ("nothing", "floor", "wall", "obstacle", "victim", "false alarm", "robot")


def thermal_palette(level: np.ndarray) -> np.ndarray:
    """Black, purple, red, orange, yellow, white: the 'iron' look of thermal viewers, over 15
    to 36 degrees (below: black; above: white)."""
    stops = np.array([[0, 0, 0], [80, 0, 120], [200, 30, 40], [250, 130, 0], [255, 230, 60], [255, 255, 255]], float)
    x = np.clip((level * STEP_C - 15.0) / 21.0, 0.0, 1.0) * (len(stops) - 1)
    k = np.minimum(x.astype(int), len(stops) - 2)
    f = (x - k)[..., None]
    return (stops[k] * (1 - f) + stops[k + 1] * f).astype(np.uint8)


def drawn(kind: str, picture: np.ndarray) -> np.ndarray:
    """An RGB rendition of a picture of ``kind``."""
    if kind == "colour":
        return picture
    if kind == "depth":  # from the nearest to the farthest depth seen: bright to dark; nothing black
        seen = picture[picture > 0]
        near, far = (float(seen.min()), float(seen.max())) if seen.size else (0.0, 1.0)
        scaled = 255.0 - 200.0 * (picture - near) / max(far - near, 1.0)
        level = np.where(picture > 0, scaled, 0).astype(np.uint8)
        return np.repeat(level[..., None], 3, axis=2)
    if kind == "thermal":
        return thermal_palette(picture.astype(float))
    return PALETTE[np.minimum(picture[..., 0], len(PALETTE) - 1)].astype(np.uint8)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="camera_kinds.png", help="the PNG to write (default: %(default)s)")
    parser.add_argument("--port", type=int, help="use the simulator running on this control port")
    parser.add_argument("--lockstep", action="store_true", help="with --port: it runs with --lockstep")
    args = parser.parse_args(argv)
    server = None
    try:
        if args.port is None:
            server = launch("DM-USAR_yellow", image=True)
            world = connect(port=server.port, lockstep=True, image_port=server.ports["image"])
        else:
            world = connect(port=args.port, lockstep=args.lockstep)
        with world:
            robot = world.spawn("P2AT", "Viewer", location=LOCATION, rotation=ROTATION)
            world.step(1.0) if args.port is None or args.lockstep else world.wait(1.0)
            tiles = []
            for kind in KINDS:
                robot.send(f"SET {{Type Camera}} {{Name Camera}} {{Opcode Picture}} {{Params {kind}}}")
                picture = robot.picture("Camera")
                tiles.append(Image.fromarray(drawn(kind, picture)).resize((320, 240)))
                if kind == "depth":
                    seen = picture[picture > 0]
                    print(f"depth: {seen.min() / 1000:.2f} to {seen.max() / 1000:.2f} m")
                elif kind == "thermal":
                    print(f"thermal: {picture.min() * STEP_C:.1f} to {picture.max() * STEP_C:.1f} degrees Celsius")
                elif kind == "label":
                    classes, counts = np.unique(picture[..., 0], return_counts=True)
                    share = ", ".join(
                        f"{CLASS_NAMES[c]} {n / picture[..., 0].size:.0%}" for c, n in zip(classes, counts)
                    )
                    print(f"labels: {share}")
            robot.send("SET {Type Camera} {Name Camera} {Opcode Picture} {Params colour}")
    except ClientError as exc:
        print(f"camera_kinds: {exc}", file=sys.stderr)
        return 1
    finally:
        if server is not None:
            server.close()
    sheet = Image.new("RGB", (640, 500), "white")
    pen = ImageDraw.Draw(sheet)
    for k, (kind, tile) in enumerate(zip(KINDS, tiles)):
        x, y = (k % 2) * 320, (k // 2) * 250
        sheet.paste(tile, (x, y + 10))
        pen.text((x + 4, y), kind, fill="black")
    sheet.save(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
