// The 3-D view: the world as the simulator renders it from a free camera that the page
// moves (MuJoCo's free camera: the point it orbits, its azimuth and elevation in degrees and
// its distance in metres, in MuJoCo's frame: X forward, Y left, Z up).  Left-drag orbits,
// right-drag (or Shift+drag) pans, the wheel zooms; Arena shows the whole world from above
// at an angle, Follow keeps the attached robot in the middle.
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
const FOLLOW_DISTANCE_M = 5; // following starts no farther than this from the robot
const DEFAULT_FOVY_DEG = 45; // MuJoCo's free camera's vertical field of view (mjVisual.global.fovy)

// a position of the USARSim frame (X forward, Y right, Z down) in MuJoCo's, and back
export const toMj = ([x, y, z]) => [x, -y, -(z || 0)];
export const fromMj = ([x, y, z]) => [x, -y, -z];

const clamp = (v, [lo, hi]) => Math.min(hi, Math.max(lo, v));
const rad = (deg) => (deg * Math.PI) / 180;

export class View3D {
  constructor(canvas, { overlay, info, followButton }) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.overlay = overlay;
    this.info = info;
    this.followButton = followButton;
    this.camera = { lookat: [0, 0, 0], azimuth: 0, elevation: -50, distance: 30 };
    this.follow = false; // keep the attached robot in the middle
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
    new ResizeObserver(() => this.request()).observe(canvas);
    document.addEventListener("visibilitychange", () => this.request());
    setInterval(() => this.tick(), 100);
  }

  // the whole world from above at an angle, as the 2-D map shows it (X up, Y right)
  setWorld(world) {
    this.world = world;
    this.arena();
  }

  arena() {
    this.setFollow(false);
    const w = this.world;
    if (w) {
      const [x0, y0, x1, y1] = w.bounds;
      const half = Math.hypot(x1 - x0, y1 - y0) / 2;
      const fovy = (this.shown && this.shown.fovy) || DEFAULT_FOVY_DEG;
      this.camera.lookat = toMj([(x0 + x1) / 2, (y0 + y1) / 2, 0]);
      this.camera.distance = clamp((0.9 * half) / Math.tan(rad(fovy) / 2), DISTANCE_M);
    }
    this.camera.azimuth = 0;
    this.camera.elevation = -55;
    this.request();
  }

  setAttached(robot) {
    this.attached = robot;
    if (!robot && this.follow) this.setFollow(false);
    else if (this.follow) this.request();
    this.showInfo();
  }

  setFollow(on) {
    this.follow = !!on;
    if (this.followButton) this.followButton.setAttribute("aria-pressed", String(this.follow));
    if (this.follow) {
      this.camera.distance = Math.min(this.camera.distance, FOLLOW_DISTANCE_M);
      if (!this.attached) this.message("Attach to a robot (click it) to follow it.");
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
    const c = this.camera;
    c.azimuth = ((((c.azimuth - dx * DEG_PER_PX) % 360) + 540) % 360) - 180;
    c.elevation = clamp(c.elevation - dy * DEG_PER_PX, ELEVATION_DEG);
  }

  // the look-at point moves with the picture: over the ground, as far as the mouse moved
  pan(dx, dy) {
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
