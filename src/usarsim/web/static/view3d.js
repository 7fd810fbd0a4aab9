// The 3-D view: the world as the simulator renders it from a free camera that the page
// moves (MuJoCo's free camera: the point it orbits, its azimuth and elevation in degrees and
// its distance in metres, in MuJoCo's frame: X forward, Y left, Z up).  Left-drag orbits,
// right-drag (or Shift+drag) pans, the wheel zooms; Arena frames the arena (what the world
// is made of, the floor around it left out) from above at an angle, Follow keeps the attached
// robot in the middle, seen from a few metres behind and above it.
//
// A picture is asked for (GET /api/view3d, one JPEG) when the view changed, and while
// something moves: FOLLOW_MS apart while the followed robot moves, WORLD_MS apart while
// anything else does.  One request at a time; the latest view wins.

const DEG_PER_PX = 0.3; // orbiting: degrees of azimuth and of elevation per pixel dragged
const ELEVATION_DEG = [-90, -2]; // from straight above to nearly level
const DISTANCE_M = [0.5, 1500];
const FOLLOW_MS = 200; // 5 pictures a second while the followed robot moves
const WORLD_MS = 1000; // 1 a second while anything else moves
const RETRY_MS = 1000; // after a refusal (the simulator is busy, or renders nothing)
const MAX_SIDE = 960; // the longest side of a picture asked for (pixels)
const ARENA_ELEVATION_DEG = -55; // Arena: the arena seen from above at an angle
const ARENA_FILL = 0.92; // Arena: the share of the picture's width or height the arena spans
const CHASE_ELEVATION_DEG = -25; // Follow: the robot seen from behind and above
const CHASE_SIZES = 5; // Follow: the camera this many times the robot's longest side away,
const CHASE_DISTANCE_M = [3, 15]; // within these
const DEFAULT_FOVY_DEG = 45; // MuJoCo's free camera's vertical field of view (mjVisual.global.fovy)
const DEFAULT_ASPECT = 4 / 3; // the picture's width over its height while the view has no size

// a position of the USARSim frame (X forward, Y right, Z down) in MuJoCo's, and back
export const toMj = ([x, y, z]) => [x, -y, -(z || 0)];
export const fromMj = ([x, y, z]) => [x, -y, -z];

const clamp = (v, [lo, hi]) => Math.min(hi, Math.max(lo, v));
const rad = (deg) => (deg * Math.PI) / 180;
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

// MuJoCo's free camera's axes (its frame): where it looks, its right and its up
function axes(azimuth, elevation) {
  const az = rad(azimuth);
  const el = rad(elevation);
  const fwd = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
  const right = [Math.sin(az), -Math.cos(az), 0];
  const up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
    right[0] * fwd[1] - right[1] * fwd[0]];
  return { fwd, right, up };
}

// where points (MuJoCo's frame) fall in the picture of a camera: [left, right, bottom, top],
// -1..1 across the picture; null when one is not in front of the camera
export function extent(points, { lookat, azimuth, elevation, distance }, fovy, aspect) {
  const { fwd, right, up } = axes(azimuth, elevation);
  const eye = lookat.map((v, i) => v - distance * fwd[i]);
  const tanV = Math.tan(rad(fovy) / 2);
  const tanH = tanV * aspect;
  const out = [Infinity, -Infinity, Infinity, -Infinity];
  for (const p of points) {
    const v = p.map((c, i) => c - eye[i]);
    const depth = dot(v, fwd);
    if (depth <= 1e-3) return null;
    const sx = dot(v, right) / (depth * tanH);
    const sy = dot(v, up) / (depth * tanV);
    out[0] = Math.min(out[0], sx);
    out[1] = Math.max(out[1], sx);
    out[2] = Math.min(out[2], sy);
    out[3] = Math.max(out[3], sy);
  }
  return out;
}

// the camera at azimuth and elevation that frames a box ([x0, y0, x1, y1, top], USARSim's
// frame, top above the floor): the box in the middle of the picture and spanning ``fill`` of
// its width or of its height, whichever it reaches first
export function frameBox(box, { azimuth, elevation, fovy = DEFAULT_FOVY_DEG, aspect = DEFAULT_ASPECT, fill = ARENA_FILL }) {
  const [x0, y0, x1, y1, top = 0] = box;
  const corners = [];
  for (const x of [x0, x1]) for (const y of [y0, y1]) for (const z of [0, top]) corners.push(toMj([x, y, -z]));
  const cam = { lookat: toMj([(x0 + x1) / 2, (y0 + y1) / 2, -top / 2]), azimuth, elevation, distance: 1 };
  const fits = (d) => {
    const e = extent(corners, { ...cam, distance: d }, fovy, aspect);
    return e !== null && Math.max(-e[0], e[1], -e[2], e[3]) <= fill;
  };
  const solve = () => {
    let [lo, hi] = DISTANCE_M;
    if (fits(lo)) return lo;
    if (!fits(hi)) return hi;
    for (let i = 0; i < 50; i++) {
      const mid = Math.sqrt(lo * hi);
      if (fits(mid)) hi = mid;
      else lo = mid;
    }
    return hi;
  };
  // the near side of the box looks larger than the far side: the point looked at moves
  // over the floor until the box is in the middle of the picture
  const { fwd, right } = axes(azimuth, elevation);
  const ahead = [fwd[0], fwd[1]].map((v) => v / Math.max(1e-6, Math.hypot(fwd[0], fwd[1])));
  const tanV = Math.tan(rad(fovy) / 2);
  for (let i = 0; i < 6; i++) {
    cam.distance = solve();
    const e = extent(corners, cam, fovy, aspect);
    if (!e) break;
    const sx = ((e[0] + e[1]) / 2) * cam.distance * tanV * aspect;
    const sy = (((e[2] + e[3]) / 2) * cam.distance * tanV) / Math.max(0.25, Math.sin(rad(-elevation)));
    cam.lookat = [cam.lookat[0] + right[0] * sx + ahead[0] * sy, cam.lookat[1] + right[1] * sx + ahead[1] * sy,
      cam.lookat[2]];
  }
  cam.distance = solve();
  return cam;
}

// how far from a robot the chase view is: some times its longest side
export function chaseDistance(dimensions) {
  const side = Array.isArray(dimensions) && dimensions.length ? Math.max(...dimensions) : 0.6;
  return clamp(CHASE_SIZES * side, CHASE_DISTANCE_M);
}

export class View3D {
  constructor(canvas, { overlay, info, followButton, sizeOf }) {
    this.canvas = canvas;
    this.sizeOf = sizeOf || (() => null); // a robot's dimensions (length, width, height; metres)
    this.ctx = canvas.getContext("2d");
    this.overlay = overlay;
    this.info = info;
    this.followButton = followButton;
    this.camera = { lookat: [0, 0, 0], azimuth: 0, elevation: -50, distance: 30 };
    this.follow = false; // keep the attached robot in the middle
    this.framed = false; // the camera is Arena's: framed again when the view's size changes
    this.followedRow = null; // the attached robot's ground truth
    this.attached = null; // the console's attached robot
    this.shown = null; // the camera of the picture shown, as the simulator answered
    this.frames = 0;
    this.busy = false;
    this.wanted = false;
    this.askedAt = 0;
    this.retry = null;
    this.drag = null;
    this.world = null;
    this.sigAll = ""; // where everything is (the ground truth), now and at the last picture asked
    this.sigFollowed = "";
    this.askedAll = null;
    this.askedFollowed = null;
    this._bind();
    new ResizeObserver(() => (this.framed ? this.arena() : this.request())).observe(canvas);
    document.addEventListener("visibilitychange", () => this.request());
    setInterval(() => this.tick(), 100);
  }

  // the arena from above at an angle, seen as the 2-D map shows it (X up, Y right)
  setWorld(world) {
    this.world = world;
    this.arena();
  }

  // the box the arena view frames: what the world is made of, or else all of it
  arenaBox() {
    const w = this.world;
    if (!w) return null;
    return w.arena || [...w.bounds, 0];
  }

  arena() {
    this.setFollow(false);
    this.camera.azimuth = 0;
    this.camera.elevation = ARENA_ELEVATION_DEG;
    const box = this.arenaBox();
    if (box) {
      const [w, h] = this.canvas.getBoundingClientRect().width >= 8 ? this.size() : [DEFAULT_ASPECT, 1];
      const fovy = (this.shown && this.shown.fovy) || DEFAULT_FOVY_DEG;
      const cam = frameBox(box, { azimuth: 0, elevation: ARENA_ELEVATION_DEG, fovy, aspect: w / h });
      this.camera.lookat = cam.lookat;
      this.camera.distance = cam.distance;
    }
    this.framed = true;
    this.request();
  }

  // the chase view: behind the attached robot, looking where it heads, a few metres away
  chase() {
    const row = this.followedRow;
    if (row) this.camera.azimuth = (((-row.rotation[2] * 180) / Math.PI + 540) % 360) - 180;
    this.camera.elevation = CHASE_ELEVATION_DEG;
    this.camera.distance = chaseDistance(this.attached && this.sizeOf(this.attached));
    if (row) this.camera.lookat = toMj(row.location);
  }

  setAttached(robot) {
    const changed = robot !== this.attached;
    this.attached = robot;
    if (changed) this.followedRow = null;
    if (!robot && this.follow) this.setFollow(false);
    else if (this.follow) {
      if (changed) this.chase();
      this.request();
    }
    this.showInfo();
  }

  setFollow(on) {
    this.follow = !!on;
    if (this.followButton) this.followButton.setAttribute("aria-pressed", String(this.follow));
    if (this.follow) {
      this.framed = false;
      if (this.attached) this.chase();
      else this.message("Attach to a robot (click it) to follow it.");
      this.request();
    }
    this.showInfo();
  }

  // the ground truth's rows: whether anything moved since the last picture
  setTruth(rows) {
    const key = (o) => `${o.name}:${o.location.map((v) => v.toFixed(2)).join(",")}:${o.rotation[2].toFixed(2)}`;
    this.sigAll = rows.map(key).join(";");
    const f = this.attached && rows.find((o) => o.name === this.attached);
    this.sigFollowed = f ? key(f) : "";
    const first = f && !this.followedRow;
    this.followedRow = f || null;
    if (first && this.follow) {
      this.chase(); // following began before the robot's place was known
      this.request();
    }
  }

  tick() {
    if (document.hidden || this.drag) return;
    const since = performance.now() - this.askedAt;
    if (this.follow && this.attached && this.sigFollowed !== this.askedFollowed && since >= FOLLOW_MS) this.request();
    else if (this.sigAll !== this.askedAll && since >= (this.follow ? FOLLOW_MS : WORLD_MS)) this.request();
  }

  message(text) {
    this.overlay.textContent = text || "";
    this.overlay.hidden = !text;
  }

  // the camera's numbers: those of the picture shown, or while dragging those it will have
  showInfo() {
    const c = (!this.drag && this.shown) || this.camera;
    const following = this.follow && this.attached ? ` · following ${this.attached}` : "";
    this.info.textContent = `az ${c.azimuth.toFixed(0)}° · el ${c.elevation.toFixed(0)}° · ${c.distance.toFixed(1)} m${following}`;
    if (this.shown) this.canvas.dataset.azimuth = this.shown.azimuth.toFixed(2);
  }

  // the picture's size: the element's, in device pixels, no side over MAX_SIDE
  size() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    let w = r.width * dpr;
    let h = r.height * dpr;
    const k = Math.min(1, MAX_SIDE / Math.max(w, h, 1));
    w = Math.max(16, Math.round((w * k) / 8) * 8);
    h = Math.max(16, Math.round((h * k) / 8) * 8);
    return [w, h];
  }

  request() {
    this.wanted = true;
    this.fetchFrame();
  }

  async fetchFrame() {
    if (this.busy || !this.wanted || document.hidden || this.retry) return;
    const r = this.canvas.getBoundingClientRect();
    if (r.width < 8 || r.height < 8) return; // not displayed: asked again when it is
    this.wanted = false;
    this.busy = true;
    this.askedAt = performance.now();
    this.askedAll = this.sigAll;
    this.askedFollowed = this.sigFollowed;
    const c = this.camera;
    const [w, h] = this.size();
    const q = new URLSearchParams({
      lookat: c.lookat.map((v) => v.toFixed(4)).join(","),
      azimuth: c.azimuth.toFixed(3), elevation: c.elevation.toFixed(3), distance: c.distance.toFixed(4),
      width: String(w), height: String(h),
    });
    if (this.follow && this.attached) q.set("follow", this.attached);
    try {
      const resp = await fetch(`/api/view3d?${q}`, { cache: "no-store" });
      if (!resp.ok) {
        let why = `HTTP ${resp.status}`;
        try {
          why = (await resp.json()).error || why;
        } catch (exc) {
          // not JSON: the status says it
        }
        if (!this.frames) this.message(why);
        this.wanted = true;
        this.retry = setTimeout(() => {
          this.retry = null;
          this.fetchFrame();
        }, RETRY_MS);
        return;
      }
      const view = JSON.parse(resp.headers.get("X-View") || "{}");
      const bitmap = await createImageBitmap(await resp.blob());
      if (this.canvas.width !== bitmap.width || this.canvas.height !== bitmap.height) {
        this.canvas.width = bitmap.width;
        this.canvas.height = bitmap.height;
      }
      this.ctx.drawImage(bitmap, 0, 0);
      bitmap.close();
      this.shown = view;
      this.frames += 1;
      this.canvas.dataset.frames = String(this.frames);
      if (this.follow && view.follow && Array.isArray(view.lookat)) this.camera.lookat = view.lookat;
      this.message(this.follow && !this.attached ? "Attach to a robot (click it) to follow it." : "");
      this.showInfo();
    } catch (exc) {
      this.message(`The 3-D view cannot be shown: ${exc}`);
    } finally {
      this.busy = false;
    }
    if (this.wanted) this.fetchFrame();
  }

  // the mouse ------------------------------------------------------------------------
  orbit(dx, dy) {
    this.framed = false;
    const c = this.camera;
    c.azimuth = ((((c.azimuth - dx * DEG_PER_PX) % 360) + 540) % 360) - 180;
    c.elevation = clamp(c.elevation - dy * DEG_PER_PX, ELEVATION_DEG);
  }

  // the look-at point moves with the picture: over the ground, as far as the mouse moved
  pan(dx, dy) {
    this.framed = false;
    if (this.follow) this.setFollow(false);
    const c = this.camera;
    const fovy = (this.shown && this.shown.fovy) || DEFAULT_FOVY_DEG;
    const h = Math.max(1, this.canvas.getBoundingClientRect().height);
    const mpp = (2 * c.distance * Math.tan(rad(fovy) / 2)) / h; // metres per pixel at the look-at point
    const az = rad(c.azimuth);
    const fwd = [Math.cos(az), Math.sin(az)];
    const right = [Math.sin(az), -Math.cos(az)];
    const ahead = (dy * mpp) / Math.max(0.25, Math.sin(rad(-c.elevation)));
    c.lookat = [c.lookat[0] - right[0] * dx * mpp + fwd[0] * ahead,
      c.lookat[1] - right[1] * dx * mpp + fwd[1] * ahead, c.lookat[2]];
  }

  zoom(factor) {
    this.framed = false;
    this.camera.distance = clamp(this.camera.distance * factor, DISTANCE_M);
    this.request();
  }

  _bind() {
    const el = this.canvas;
    el.addEventListener("mousedown", (ev) => {
      if (ev.button > 2) return;
      ev.preventDefault();
      const mode = ev.button === 0 && !ev.shiftKey ? "orbit" : "pan";
      this.drag = { x: ev.clientX, y: ev.clientY, mode };
      el.classList.add("dragging");
    });
    window.addEventListener("mousemove", (ev) => {
      const d = this.drag;
      if (!d) return;
      const dx = ev.clientX - d.x;
      const dy = ev.clientY - d.y;
      if (!dx && !dy) return;
      d.x = ev.clientX;
      d.y = ev.clientY;
      if (d.mode === "orbit") this.orbit(dx, dy);
      else this.pan(dx, dy);
      this.showInfo();
      this.request();
    });
    window.addEventListener("mouseup", () => {
      if (!this.drag) return;
      this.drag = null;
      el.classList.remove("dragging");
      this.showInfo();
      this.request();
    });
    el.addEventListener("contextmenu", (ev) => ev.preventDefault());
    el.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      this.zoom(Math.exp(ev.deltaY * 0.0015));
    }, { passive: false });
  }
}
