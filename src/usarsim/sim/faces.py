"""Victims' faces, for cameras: a picture of a face drawn with NumPy, laid on a thin plate in
front of a victim's head, so that face detectors of the kind rescue teams ran on their cameras
(the Viola-Jones cascades OpenCV ships) find a victim who faces the camera.

The face follows the neoclassical canons of facial proportion (the eyes at half the head's
height, the face five eye-widths wide, the nose as long as the forehead is high; L. G. Farkas,
I. R. Munro, Anthropometric Facial Proportions in Medicine, 1987): an oval of skin, lit from
above and in front (darker towards its edges), hair above the forehead, eyes with their whites,
irises and pupils in shaded sockets under brows, a nose whose ridge catches the light between
shaded sides and dark nostrils, and lips.  What a detector looks for is there because a face
is: the band of the eyes darker than the cheeks below and the forehead above, the bridge of the
nose brighter than the eyes beside it.  The same skin and hair give the same picture.
"""

from __future__ import annotations

from functools import cache

import numpy as np

WIDTH_PX, HEIGHT_PX = 128, 160  # the picture of a face plate (its width and height in the world: FACE_SIZE_M)
FACE_SIZE_M = (0.14, 0.175)  # a face's width and height, chin to hairline (an adult's, after Farkas)
SCLERA = (0.92, 0.90, 0.88)
IRIS = (0.25, 0.15, 0.08)
PUPIL = (0.02, 0.02, 0.02)
LIPS = (0.55, 0.22, 0.22)
LIP_LINE = (0.25, 0.08, 0.08)
GLOW = 0.14  # the brightest sheen, added to the skin's 0..1 colour
# where the sheen lies, (centre across and down, spread across and down) in the oval's half
# axes: the forehead, the two cheekbones, the nose
GLOWS = ((0.0, -0.55, 0.45, 0.14), (-0.45, 0.12, 0.2, 0.12), (0.45, 0.12, 0.2, 0.12), (0.0, 0.05, 0.07, 0.2))


@cache
def face_picture(skin: tuple[float, float, float], hair: tuple[float, float, float]) -> np.ndarray:
    """The face of a victim of ``skin`` and ``hair`` colours (RGB 0..1): HEIGHT_PX x WIDTH_PX x 3
    uint8, rows top (the hair) to bottom (the chin)."""
    h, w = HEIGHT_PX, WIDTH_PX
    y, x = np.mgrid[0:h, 0:w].astype(float)
    cx, cy = w / 2.0, h * 0.55
    rx, ry = w * 0.40, h * 0.42  # the oval of the face
    img = np.ones((h, w, 3)) * np.array(skin) * 0.55  # around the oval: the head's sides, in shadow
    d = ((x - cx) / rx) ** 2 + ((y - cy) / ry) ** 2
    inside = d < 1.0
    shade = 1.0 - 0.35 * np.clip(d, 0.0, 1.0) ** 2  # lit from the front: darker towards the edges
    img[inside] = np.array(skin) * shade[inside, None]
    # the light caught by the forehead, the cheekbones and the nose (skin's sheen, the more
    # visible the darker the skin): what makes the eyes' band stand out on every skin tone
    glow = np.zeros((h, w))
    for gx, gy, sx, sy in (
        (0.0, -0.55, 0.45, 0.14),
        (-0.45, 0.12, 0.2, 0.12),
        (0.45, 0.12, 0.2, 0.12),
        (0, 0.05, 0.07, 0.2),
    ):
        glow += np.exp(-(((x - cx - gx * rx) / (sx * rx)) ** 2 + ((y - cy - gy * ry) / (sy * ry)) ** 2) / 2.0)
    img[inside] += (GLOW * np.clip(glow, 0.0, 1.0))[inside, None]
    img[(d < 1.15) & (y < cy - ry * 0.55 + 0.12 * np.abs(x - cx))] = hair  # above the forehead

    def ellipse(mx: float, my: float, ax: float, ay: float) -> np.ndarray:
        return ((x - mx) / ax) ** 2 + ((y - my) / ay) ** 2 < 1.0

    eye_y = cy - ry * 0.18  # half the head's height
    for side in (-1, 1):
        ex = cx + side * rx * 0.42
        img[ellipse(ex, eye_y, rx * 0.30, ry * 0.15)] *= 0.65  # the socket's shadow
        img[ellipse(ex, eye_y, rx * 0.22, ry * 0.07)] = SCLERA
        img[ellipse(ex, eye_y, rx * 0.09, ry * 0.07)] = IRIS
        img[ellipse(ex, eye_y, rx * 0.045, ry * 0.04)] = PUPIL
        brow = (np.abs(y - (eye_y - ry * 0.17 - 0.02 * (x - ex) ** 2 / rx)) < ry * 0.035) & (np.abs(x - ex) < rx * 0.28)
        img[brow] = np.minimum(np.array(hair) * 1.2, 1.0)
    nose_top, nose_tip = eye_y + ry * 0.05, cy + ry * 0.22
    ridge = (np.abs(x - cx) < rx * 0.07) & (y > nose_top) & (y < nose_tip)
    img[ridge] = np.minimum(img[ridge] * 1.12, 1.0)
    for side in (-1, 1):
        flank = (np.abs(x - (cx + side * rx * 0.13)) < rx * 0.05) & (y > nose_top + ry * 0.1) & (y < nose_tip)
        img[flank] *= 0.85
        img[ellipse(cx + side * rx * 0.09, nose_tip, rx * 0.05, ry * 0.025)] = np.array(skin) * 0.35  # a nostril
    mouth_y = cy + ry * 0.45
    img[ellipse(cx, mouth_y, rx * 0.32, ry * 0.06)] = LIPS
    img[(np.abs(y - mouth_y) < ry * 0.012) & (np.abs(x - cx) < rx * 0.30)] = LIP_LINE
    out = (np.clip(img, 0.0, 1.0) * 255.0).astype(np.uint8)
    out.setflags(write=False)
    return out
