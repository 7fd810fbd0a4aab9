"""Camera pictures that a vision pipeline can use: every shipped world is lit without black
or washed-out areas from every start pose, a classical skin-colour detector finds a victim
a robot faces at 2 m and nothing where no victim is in view, and a threshold finds the lane
markings of the road world.  Pictures come from the simulator's own render service (the one
the image server uses).  Rendering needs an OpenGL context; where none can be made these
tests are skipped, with the reason."""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers import gl_problem, settled

GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")

WIDTH, HEIGHT = 320, 240
WORLDS = (
    "DM-USAR_yellow",
    "DM-USAR_orange",
    "DM-USAR_red",
    "DM-CollapsedBuilding",
    "DM-Harbour",
    "DM-Road_UrbanChallenge",
)
# Picture statistics: a pixel is nearly black when its brightness (the mean of R, G and B,
# 0..255) is below 12, nearly white above 248: detail is lost there (a camera's dark noise and
# clipping).  Neither share may pass 2 % of a start pose's view.
NEARLY_BLACK, NEARLY_WHITE = 12, 248
MAX_SHARE = 0.02

# The skin detector: HSV thresholds on the skin cluster (hue 8-28 degrees, the red-orange of
# blood under skin of every tone; saturation 0.2-0.6; value at least 0.2), after Kovac, Peer
# and Solina (EUROCON 2003) and the HSV skin models reviewed by Kakumanu, Makrogiannis and
# Bourbakis, "A survey of skin-color modeling and detection methods", Pattern Recognition
# 40(3), 2007.  A detection is at least MIN_SKIN_PIXELS such pixels (a head 0.2 m across at
# 2 m covers about 800 pixels of a 320 x 240 picture of 50 degrees), after an erosion that
# removes lines one or two pixels wide.
HUE_DEG = (8.0, 28.0)
SATURATION = (0.2, 0.6)
MIN_VALUE = 0.2
MIN_SKIN_PIXELS = 80


def skin_mask(rgb: np.ndarray) -> np.ndarray:
    p = rgb.astype(float) / 255.0
    mx, mn = p.max(axis=2), p.min(axis=2)
    chroma = mx - mn
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        sat = np.where(mx > 0, chroma / mx, 0.0)
        # hue of a pixel whose red is the largest channel (skin's): 60 (G - B) / chroma
        hue = np.where(chroma > 0, 60.0 * (g - b) / chroma, -1.0)
    red_max = (r >= g) & (r >= b)
    return (
        red_max
        & (hue >= HUE_DEG[0])
        & (hue <= HUE_DEG[1])
        & (sat >= SATURATION[0])
        & (sat <= SATURATION[1])
        & (mx >= MIN_VALUE)
    )


def skin_blobs(rgb: np.ndarray) -> np.ndarray:
    """The skin mask opened by a 3 x 3 erosion: edges one or two pixels wide (a seam between
    two boards, where colours blend) go, a face or a hand stays."""
    m = skin_mask(rgb)
    out = m.copy()
    out[1:-1, 1:-1] = (
        m[1:-1, 1:-1]
        & m[:-2, 1:-1]
        & m[2:, 1:-1]
        & m[1:-1, :-2]
        & m[1:-1, 2:]
        & m[:-2, :-2]
        & m[:-2, 2:]
        & m[2:, :-2]
        & m[2:, 2:]
    )
    out[0], out[-1], out[:, 0], out[:, -1] = False, False, False, False
    return out


def finds_skin(rgb: np.ndarray) -> bool:
    return int(skin_blobs(rgb).sum()) >= MIN_SKIN_PIXELS


class Camera:
    """A simulation of a world with a P2AT at each pose, and its render service."""

    def __init__(self, world, poses):
        from usarsim.config.catalog import resolve_robot
        from usarsim.sim.render import RenderService
        from usarsim.sim.simulation import Simulation

        self.sim = Simulation(world)
        robot = resolve_robot("P2AT")
        for k, (location, rotation) in enumerate(poses, start=1):
            self.sim.spawn(k, robot, f"R{k}", location, rotation, set_down=True)
        self.sim.advance(0.5)  # every robot landed
        self.service = RenderService(lambda reuse: settled(self.sim.cameras.render_snapshot(reuse)), max_fps=0)

    def picture(self, uid: int) -> np.ndarray:
        from usarsim.sim.tiles import Tile

        return self.service.render(WIDTH, HEIGHT, [Tile(uid, "Camera", 0, 0, WIDTH, HEIGHT)]).result(timeout=60)

    def segmentation(self, uid: int, every_group: bool = False):
        """(model, each pixel's object id and type) of the robot camera's view: MuJoCo's default
        geom groups, or (``every_group``) what cameras see, victims' faces too."""
        import mujoco

        from usarsim.sim.render import SEEN
        from usarsim.sim.robotspec import camera_fovy_deg, camera_name

        snap = self.sim.cameras.render_snapshot()
        m = snap.model
        cam = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, camera_name(f"robot{uid}", "Camera"))
        m.cam_fovy[cam] = camera_fovy_deg(math.radians(50.0), WIDTH, HEIGHT)
        r = mujoco.Renderer(m, HEIGHT, WIDTH)
        try:
            r.enable_segmentation_rendering()
            r.update_scene(snap.data, camera=cam, scene_option=SEEN if every_group else None)
            return m, r.render()
        finally:
            r.close()

    def sees_victim(self, uid: int) -> bool:
        """Whether any victim or false alarm is in the robot camera's view (a segmentation
        picture of the same view)."""
        import mujoco

        m, seg = self.segmentation(uid)
        ids = np.unique(seg[..., 0][seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)])
        names = [m.geom(int(g)).name for g in ids if g >= 0]
        return any(n.startswith(("victim/", "falsealarm/", "look/")) for n in names)

    def geom_at(self, uid: int, u: int, v: int) -> str:
        """The name of the geom the robot camera's pixel (u, v) shows ('' for none)."""
        import mujoco

        m, seg = self.segmentation(uid, every_group=True)
        gid, kind = seg[v, u]
        return m.geom(int(gid)).name if gid >= 0 and kind == int(mujoco.mjtObj.mjOBJ_GEOM) else ""

    def close(self):
        self.service.stop()


@pytest.fixture(scope="module")
def start_pose_views():
    """Every start pose of every shipped world: (world, pose, picture, whether it sees a victim)."""
    from usarsim.config.catalog import resolve_world

    out = []
    for name in WORLDS:
        world = resolve_world(name)
        cam = Camera(world, [(p.location, p.rotation) for p in world.start_poses])
        try:
            for uid, pose in enumerate(world.start_poses, start=1):
                out.append((name, pose.name, cam.picture(uid), cam.sees_victim(uid)))
        finally:
            cam.close()
    return out


def picture_shares(rgb: np.ndarray) -> tuple[float, float]:
    """(share of nearly black pixels, share of nearly white pixels)."""
    brightness = rgb.astype(float).mean(axis=2)
    return float((brightness < NEARLY_BLACK).mean()), float((brightness > NEARLY_WHITE).mean())


def test_every_start_pose_sees_neither_black_nor_washed_out_areas(start_pose_views):
    failures = []
    for world, pose, rgb, _ in start_pose_views:
        black, white = picture_shares(rgb)
        if black > MAX_SHARE or white > MAX_SHARE:
            failures.append(f"{world} {pose}: {black:.1%} nearly black, {white:.1%} nearly white")
    assert not failures, failures


def test_the_skin_detector_finds_nothing_where_no_victim_is_in_view(start_pose_views):
    clear = [(w, p, rgb) for w, p, rgb, sees in start_pose_views if not sees]
    assert len(clear) >= 20  # most start poses face no victim
    found = [(w, p, int(skin_blobs(rgb).sum())) for w, p, rgb in clear if finds_skin(rgb)]
    assert not found, found


VICTIM_WORLD = """\
name: VictimAhead
description: a victim lying across the view of a robot 2 m away, among arena walls (tests only)
floor: {center: [0.0, 0.0], size: [20.0, 20.0], material: floor}
ambient_light: [0.3, 0.3, 0.3]
lights:
  - {name: lamp, type: spot, position: [0.0, 0.0, -4.0], cutoff_deg: 70, exponent: 2, intensity: 0.45}
materials:
  floor: {rgba: [0.55, 0.55, 0.52, 1.0], texture: concrete}
  wall: {rgba: [0.93, 0.84, 0.42, 1.0], texture: painted_panel}
  wood: {rgba: [0.78, 0.64, 0.44, 1.0], texture: plywood}
  osb: {rgba: [0.62, 0.47, 0.30, 1.0], texture: osb}
objects:
  - {name: back_wall, shape: box, center: [3.5, 0.0, -0.6], size: [0.1, 6.0, 1.2], material: wall}
  - {name: crate, shape: box, center: [2.6, -1.6, -0.3], size: [0.6, 0.6, 0.6], material: osb}
  - {name: deck, shape: box, center: [2.6, 1.7, -0.1], size: [1.0, 1.0, 0.2], material: wood}
start_poses:
  - {name: Facing, location: [0.0, 0.0, -0.25]}
  - {name: Away, location: [0.0, 0.0, -0.25], rotation: [0.0, 0.0, 3.1416]}
victims:
  - {name: V, location: [2.0, -0.6, -0.1], rotation: [0.0, 0.0, 1.5708]}  # head 2 m ahead, body to the left
"""


@pytest.mark.parametrize("victim", ["Anna", "Ben", "Dora", "Lea"])
def test_the_skin_detector_finds_a_victim_2_m_ahead(tmp_path, victim):
    """Victims of every skin tone (their names choose it), seen by a robot 2 m away."""
    from usarsim.config.world_file import load_world
    from usarsim.sim.victims import victim_colours

    p = tmp_path / "VictimAhead.yaml"
    p.write_text(VICTIM_WORLD.replace("{name: V,", f"{{name: {victim},"))
    world = load_world(p)
    cam = Camera(world, [(s.location, s.rotation) for s in world.start_poses])
    try:
        facing, away = cam.picture(1), cam.picture(2)
        assert cam.sees_victim(1) and not cam.sees_victim(2)
    finally:
        cam.close()
    assert finds_skin(facing), (victim, victim_colours(victim)["skin"], int(skin_blobs(facing).sum()))
    assert not finds_skin(away), int(skin_blobs(away).sum())
    # the skin found is where the victim is: in the middle third of the picture, below the horizon
    rows, cols = np.nonzero(skin_blobs(facing))
    assert HEIGHT / 2 < np.median(rows) and WIDTH / 3 < np.median(cols) < 2 * WIDTH / 3


# OpenCV's frontal face detector (the Viola-Jones cascade of Lienhart's extended Haar features
# that OpenCV ships, haarcascade_frontalface_alt2.xml), as rescue teams ran such detectors on
# their cameras' pictures: scale step 1.1, 4 neighbours, faces of 20 pixels and more.
FACE_CASCADE = "haarcascade_frontalface_alt2.xml"


def faces(rgb: np.ndarray) -> list[tuple[int, int, int, int]]:
    """The faces OpenCV's detector finds in a picture: (x, y, width, height) each."""
    import cv2

    cascade = cv2.CascadeClassifier(cv2.data.haarcascades + FACE_CASCADE)
    gray = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY)
    return [tuple(int(v) for v in box) for box in cascade.detectMultiScale(gray, 1.1, 4, minSize=(20, 20))]


# Eight victims of every skin tone (their names choose it) sitting in good light, each facing
# its own robot 1.5 m away (the robots 4 m apart), each robot's camera tilted up to the face
FACE_NAMES = ("Anna", "Ben", "Carl", "Dana", "Emil", "Fatima", "Goran", "Hana")
FACES_WORLD = """name: FacesAhead
description: sitting victims, each facing a robot 1.5 m away, in daylight (tests only)
floor: {center: [0.0, 12.0], size: [12.0, 40.0]}
lights:
  - {name: sun, type: directional, direction: [1.0, 0.2, 0.6], color: [0.8, 0.8, 0.8]}
victims:
%s
start_poses:
%s
"""


def test_opencvs_face_detector_finds_the_faces_of_victims_facing_the_camera(tmp_path):
    from helpers import drive_joint
    from usarsim.config.world_file import load_world
    from usarsim.sim.victims import SKIN_TONES, victim_colours

    assert {victim_colours(n)["skin"] for n in FACE_NAMES} == set(SKIN_TONES)
    victims = "\n".join(
        f"  - {{name: {n}, location: [1.6, {4.0 * k}, -0.1], rotation: [0.0, 0.0, 3.1416], posture: sitting}}"
        for k, n in enumerate(FACE_NAMES)
    )
    poses = "\n".join(f"  - {{name: P{k}, location: [0.0, {4.0 * k}, -0.25]}}" for k in range(len(FACE_NAMES)))
    p = tmp_path / "FacesAhead.yaml"
    p.write_text(FACES_WORLD % (victims, poses))
    world = load_world(p)
    cam = Camera(world, [(s.location, s.rotation) for s in world.start_poses])
    try:
        for uid in range(1, len(FACE_NAMES) + 1):
            assert drive_joint(cam.sim, uid, "CameraPanTilt_Link2", 0.3)  # look up at the face
        cam.sim.advance(2.0)
        found = []
        for uid, name in enumerate(FACE_NAMES, start=1):
            boxes = faces(cam.picture(uid))
            # each face found is the victim's: the middle of its box shows the victim's face
            on_face = [
                b for b in boxes if cam.geom_at(uid, b[0] + b[2] // 2, b[1] + b[3] // 2) == f"look/victim/{name}/face"
            ]
            assert len(on_face) == len(boxes), (name, boxes)
            found.append(name) if on_face else None
    finally:
        cam.close()
    assert len(found) >= 6, f"faces found: {found}"


def test_opencvs_face_detector_finds_no_face_where_no_victim_is_in_view(start_pose_views):
    clear = [(w, p, rgb) for w, p, rgb, sees in start_pose_views if not sees]
    assert len(clear) >= 20
    found = [(w, p, faces(rgb)) for w, p, rgb in clear if faces(rgb)]
    assert not found, found


def test_the_victims_show_every_skin_tone():
    from usarsim.sim.victims import SKIN_TONES, victim_colours

    assert {victim_colours(n)["skin"] for n in ("Anna", "Ben", "Dora", "Lea")} == set(SKIN_TONES)
    for tone in SKIN_TONES:
        assert finds_skin(np.full((10, 10, 3), np.array(tone) * 255, dtype=np.uint8).repeat(3, 0).repeat(3, 1))


def test_lane_markings_are_found_down_the_road():
    """A robot on its lane looks down the avenue: the white and yellow lines are bright,
    saturated (yellow) or near white, on dark asphalt, and run towards the horizon."""
    from usarsim.config.catalog import resolve_world

    world = resolve_world("DM-Road_UrbanChallenge")
    pose = world.start_pose("PlayerStart1")
    cam = Camera(world, [(pose.location, pose.rotation)])
    try:
        rgb = cam.picture(1)
    finally:
        cam.close()
    p = rgb.astype(float)
    road = p[HEIGHT // 2 + 8 :]  # the ground ahead, below the horizon
    brightness = road.mean(axis=2)
    asphalt = np.median(brightness)
    white = (brightness > asphalt + 60) & (road.max(axis=2) - road.min(axis=2) < 40)
    yellow = (road[..., 0] > asphalt + 40) & (road[..., 2] < road[..., 0] - 60)
    assert asphalt < 110  # dark asphalt
    # the markings are lines: long runs of marking pixels, the yellow centre line on the left
    # of a robot on its lane, the white edge line on its right
    ys, xs = np.nonzero(yellow)
    ws, wx = np.nonzero(white)
    assert len(xs) > 60 and len(wx) > 60, (len(xs), len(wx))
    assert np.median(xs) < WIDTH / 2 < np.median(wx), (np.median(xs), np.median(wx))
    assert np.ptp(xs) > WIDTH / 6 and np.ptp(wx) > WIDTH / 6  # lines running into the distance


# The paint of the markings and the asphalt (textures.YELLOW, WHITE; the road world's asphalt
# material), RGB 0..1: both lie flat under the same light, so the asphalt's brightness in a
# picture tells how bright the paint must be.
YELLOW_PAINT, WHITE_PAINT, ASPHALT = (0.95, 0.75, 0.10), (0.93, 0.93, 0.90), (0.22, 0.22, 0.24)


def test_lane_markings_keep_their_paint_far_down_the_road():
    """A P2AT's camera, 0.3 m above the road, looks down its lane at a grazing angle: out to the
    far end of the block the double yellow centre line (left) and the white edge line (right)
    keep the colour of their paint (painted into the road's texture, the renderer's mipmaps
    would smear them across the asphalt into faint streaks)."""
    from usarsim.config.catalog import resolve_world

    world = resolve_world("DM-Road_UrbanChallenge")
    pose = world.start_pose("PlayerStart1")
    cam = Camera(world, [(pose.location, pose.rotation)])
    try:
        p = cam.picture(1).astype(float)
    finally:
        cam.close()
    asphalt = np.median(p[HEIGHT // 2 + 8 :, WIDTH // 3 : 2 * WIDTH // 3].mean(axis=2))
    light = asphalt / (255.0 * np.mean(ASPHALT))
    yellow = 255.0 * light * (YELLOW_PAINT[0] - YELLOW_PAINT[2])  # its red over its blue
    white = 255.0 * light * np.mean(WHITE_PAINT)
    # the far stretch: rows 3 to 31 below the horizon, the road from about 60 m to 4 m ahead
    rows = range(HEIGHT // 2 + 3, HEIGHT // 2 + 32)
    yellow_kept = np.median([(p[r, : WIDTH // 2, 0] - p[r, : WIDTH // 2, 2]).max() / yellow for r in rows])
    white_kept = np.median([(p[r, WIDTH // 2 + 10 :].mean(axis=1).max() - asphalt) / (white - asphalt) for r in rows])
    assert yellow_kept > 0.75, (yellow_kept, yellow)
    assert white_kept > 0.75, (white_kept, white)


def test_road_paint_is_for_cameras_only():
    """The markings lie on the road as thin boxes that nothing collides with and no range
    sensor sees; on every street, one stop line before each crossing on each side."""
    import mujoco

    from usarsim.config.catalog import resolve_world
    from usarsim.sim.constants import RAY_GROUPS
    from usarsim.sim.simulation import Simulation

    sim = Simulation(resolve_world("DM-Road_UrbanChallenge"), seed=1)
    m = sim.model
    paint = [g for g in range(m.ngeom) if m.geom(g).name.startswith("paint/")]
    assert paint
    for g in paint:
        assert m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0
        assert RAY_GROUPS[m.geom_group[g]] == 0
        assert m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX and m.geom_size[g][2] < 0.001
    stops = [g for g in paint if 0.2 < 2 * min(m.geom_size[g][:2]) < 0.5]  # 0.45 m across the lane
    assert len(stops) == 8 * 3 * 2  # eight streets of three blocks, both ways


def test_the_texture_names_of_world_files_are_the_textures_drawn():
    from usarsim.config.world import TEXTURE_NAMES
    from usarsim.sim.textures import TEXTURES, texture_image

    assert set(TEXTURE_NAMES) == set(TEXTURES)
    a = texture_image("brick", (0.62, 0.27, 0.2))
    b = texture_image("brick", (0.62, 0.27, 0.2))
    assert a is b and a.dtype == np.uint8 and a.ndim == 3
    # a texture's average colour is its material's colour
    assert np.allclose(a.reshape(-1, 3).mean(axis=0) / 255.0, (0.62, 0.27, 0.2), atol=0.08)


def crossing_from_above(size: int = 400, span_m: float = 45.6) -> tuple[np.ndarray, float]:
    """The road world's crossing of Avenue B and Second Street (USARSim X = Y = -41) seen
    straight from above, north up and east right, as the picture and its pixels a metre."""
    import mujoco

    from usarsim.config.catalog import resolve_world
    from usarsim.sim.render import SEEN, nearest_mipmap
    from usarsim.sim.simulation import Simulation

    sim = Simulation(resolve_world("DM-Road_UrbanChallenge"), seed=1)
    m, d = sim.model, sim.data
    r = mujoco.Renderer(m, size, size)
    nearest_mipmap(r)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = [-41.0, 41.0, 0.0]  # USARSim (X, Y) is MuJoCo (x, -y)
    cam.azimuth, cam.elevation = 0.0, -90.0  # looking down, +x (north) up the picture
    # the distance that shows span_m metres of the ground across the picture
    cam.distance = span_m / 2 / math.tan(math.radians(m.vis.global_.fovy) / 2)
    try:
        r.update_scene(d, camera=cam, scene_option=SEEN)
        return r.render(), size / span_m
    finally:
        r.close()


def test_every_approach_to_a_crossing_has_its_stop_line_on_its_own_lane():
    """Right-hand traffic: each approach lane stops 7.5 m before the crossing street's centre
    line (the RNDF's stop waypoints), so the four stop lines make a pinwheel; on the streets
    running north-south and on those running east-west alike.  Each quarter turn of the
    picture brings the next approach to the bottom, its own lane then on the right."""
    if gl_problem():
        pytest.skip(gl_problem())
    rgb, px_m = crossing_from_above()
    centre = rgb.shape[0] / 2
    shares = {}
    approaches = {
        "from the south": rgb,
        "from the north": np.rot90(rgb, 2),
        "from the west": np.rot90(rgb, 1),
        "from the east": np.rot90(rgb, -1),
    }
    for name, pic in approaches.items():
        p = pic.astype(float)
        white = (p.min(axis=2) > 190) & (p.max(axis=2) - p.min(axis=2) < 40)
        rows = slice(int(centre + 6.5 * px_m), int(centre + 8.5 * px_m))  # 7.5 m down the approach
        own = white[rows, int(centre + 0.6 * px_m) : int(centre + 3.1 * px_m)]  # its own lane (right)
        other = white[rows, int(centre - 3.1 * px_m) : int(centre - 0.6 * px_m)]  # the oncoming lane
        assert own.mean() > 0.06, (name, own.mean())  # a line 0.45 m wide across a band of 2 m
        assert other.mean() < 0.01, (name, other.mean())
        shares[name] = (own.mean(), other.mean())
    assert len(shares) == 4, shares


@pytest.mark.parametrize("waving", [True, False])
def test_a_waving_victim_moves_in_the_picture(tmp_path, waving):
    """Half a wave apart (its arm at either end of its swing), the pictures of a waving victim
    2 m ahead differ over a patch of the victim's size; those of a still one do not."""
    from usarsim.config.world_file import load_world
    from usarsim.sim.constants import WAVE_PERIOD_S

    p = tmp_path / "VictimAhead.yaml"
    p.write_text(
        VICTIM_WORLD.replace(
            "rotation: [0.0, 0.0, 1.5708]}", f"rotation: [0.0, 0.0, 1.5708], waving: {str(waving).lower()}}}"
        )
    )
    world = load_world(p)
    cam = Camera(world, [(world.start_poses[0].location, world.start_poses[0].rotation)])
    try:
        cam.sim.advance(WAVE_PERIOD_S - cam.sim.time % WAVE_PERIOD_S)  # a whole period: the arm down
        first = cam.picture(1).astype(int)
        cam.sim.advance(WAVE_PERIOD_S / 2)  # half a period on: the arm at its highest
        second = cam.picture(1).astype(int)
    finally:
        cam.close()
    moved = np.abs(first - second).max(axis=2) > 40
    if not waving:
        assert moved.sum() < 20, int(moved.sum())
        return
    rows, cols = np.nonzero(moved)
    assert moved.sum() > 0.004 * WIDTH * HEIGHT, int(moved.sum())  # a patch, not a few pixels
    assert WIDTH / 4 < np.median(cols) < 3 * WIDTH / 4  # where the victim is
