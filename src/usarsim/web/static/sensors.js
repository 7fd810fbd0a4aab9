// The sensor tree (every sensor's latest reading, SimpleUI's Sensor Data group) and the
// range sensors drawn around the robot with a colour code (its Range Sensor Data group).

import { vec } from "./protocol.js";

const DEFAULT_MAX_RANGE = { Sonar: 5, IR: 1.5, RangeSensor: 5, RangeScanner: 20, IRScanner: 5 };
const SONAR_HALF_ANGLE = 0.13; // radians, how wide a sonar's wedge is drawn when CONF does not say

function esc(text) {
  return String(text).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c]));
}

function short(value) {
  const v = String(value);
  return v.length > 90 ? v.slice(0, 87) + "…" : v;
}

// near (red) to far (green), from the share of the sensor's maximum range
export function rangeColour(range, max) {
  const f = Math.max(0, Math.min(1, range / (max || 5)));
  if (f >= 0.999) return "hsla(120,40%,45%,.35)"; // nothing within range
  return `hsl(${Math.round(120 * f)},85%,${f < 0.5 ? 52 : 45}%)`;
}

export class SensorTree {
  constructor(el) {
    this.el = el;
    this.open = new Set(["STA"]);
    this.session = null;
    this.pending = false;
    this.last = 0;
    el.addEventListener("toggle", (ev) => {
      const d = ev.target;
      if (!d.dataset || !d.dataset.key) return;
      if (d.open) this.open.add(d.dataset.key); else this.open.delete(d.dataset.key);
    }, true);
  }

  show(session) {
    this.session = session;
    this.render();
  }

  changed(session) {
    if (session !== this.session || this.pending) return;
    const wait = Math.max(0, 250 - (performance.now() - this.last));
    this.pending = true;
    setTimeout(() => {
      this.pending = false;
      this.render();
    }, wait);
  }

  table(pairs) {
    return "<table>" + pairs.map(([k, v]) =>
      `<tr><td>${esc(k)}</td><td class="v" title="${esc(short(v))}">${esc(short(v))}</td></tr>`).join("") + "</table>";
  }

  render() {
    this.last = performance.now();
    const s = this.session;
    if (!s) {
      this.el.innerHTML = '<span class="muted">No robot selected.</span>';
      return;
    }
    const keys = [...s.readings.keys()].sort((a, b) => (a === "STA" ? -1 : b === "STA" ? 1 : a.localeCompare(b)));
    if (!keys.length) {
      this.el.innerHTML = '<span class="muted">No readings yet.</span>';
      return;
    }
    const parts = [];
    for (const key of keys) {
      const r = s.readings.get(key);
      const head = r.head.filter(([k]) => k !== "Type");
      let body = head.length ? this.table(head) : "";
      for (const [name, f] of r.named) {
        const sub = `${key}/${name}`;
        body += `<details data-key="${esc(sub)}"${this.open.has(sub) ? " open" : ""}><summary>${esc(name)}` +
          (f.length === 1 ? `<span class="t">${esc(f[0][0])} ${esc(short(f[0][1]))}</span>` : "") +
          `</summary>${this.table(f)}</details>`;
      }
      parts.push(`<details data-key="${esc(key)}"${this.open.has(key) ? " open" : ""}><summary>${esc(r.title)}` +
        `<span class="t">${r.time ? "t " + esc(r.time) : ""}</span></summary>${body}</details>`);
    }
    this.el.innerHTML = parts.join("");
  }
}

// What the range sensors see, in the robot's frame (x forward, y right, metres):
// sonar-like wedges and scanner points, each with its colour.
export function rangeGeometry(session) {
  const wedges = [];
  const points = [];
  if (!session) return { wedges, points };
  for (const type of ["Sonar", "IR", "RangeSensor"]) {
    const r = session.latest(type);
    if (!r) continue;
    const geo = session.geo[type] || {};
    const conf = session.conf[type] || {};
    for (const [name, f] of r.named) {
      const range = Number((f.find(([k]) => k === "Range") || [])[1]);
      if (!Number.isFinite(range)) continue;
      const g = geo[name];
      const c = conf[name] || {};
      const max = Number(c.MaxRange) || DEFAULT_MAX_RANGE[type];
      const half = Number(c.BeamAngle) / 2 || SONAR_HALF_ANGLE;
      const at = g ? g.location : [0, 0, 0];
      const yaw = g ? g.orientation[2] : 0;
      wedges.push({ x: at[0], y: at[1], yaw, half, range: Math.min(range, max), colour: rangeColour(range, max) });
    }
  }
  for (const type of ["RangeScanner", "IRScanner"]) {
    const r = session.latest(type);
    if (!r) continue;
    const geo = session.geo[type] || {};
    const conf = session.conf[type] || {};
    for (const [name, f] of r.named) {
      const kv = Object.fromEntries(f);
      if (!kv.Range) continue;
      const ranges = vec(kv.Range);
      const res = Number(kv.Resolution) || Math.PI / 180;
      const fov = Number(kv.FOV) || Math.PI;
      const g = geo[name];
      const at = g ? g.location : [0, 0, 0];
      const yaw = g ? g.orientation[2] : 0;
      const max = Number((conf[name] || {}).MaxRange) || DEFAULT_MAX_RANGE[type];
      ranges.forEach((d, i) => {
        if (!(d > 0) || d >= max * 0.999) return; // no echo
        const a = yaw + fov / 2 - i * res; // the first value is the rightmost beam
        points.push([at[0] + d * Math.cos(a), at[1] + d * Math.sin(a), rangeColour(d, max)]);
      });
    }
  }
  return { wedges, points };
}

export function drawRanges(canvas, session, radius) {
  const ctx = canvas.getContext("2d");
  const w = canvas.width;
  const h = canvas.height;
  ctx.fillStyle = "#101216";
  ctx.fillRect(0, 0, w, h);
  const s = (Math.min(w, h) / 2 - 6) / radius;
  const cx = w / 2;
  const cy = h / 2;
  const tr = (x, y) => [cx + y * s, cy - x * s];
  ctx.strokeStyle = "rgba(255,255,255,.12)";
  ctx.lineWidth = 1;
  for (let r = 1; r <= radius; r += radius > 5 ? 5 : 1) {
    ctx.beginPath();
    ctx.arc(cx, cy, r * s, 0, 2 * Math.PI);
    ctx.stroke();
  }
  if (!session) return;
  const { wedges, points } = rangeGeometry(session);
  for (const wd of wedges) {
    const [sx, sy] = tr(wd.x, wd.y);
    // canvas angles: 0 along +x of the screen (the robot's right), clockwise
    const a = wd.yaw - Math.PI / 2;
    ctx.beginPath();
    ctx.moveTo(sx, sy);
    ctx.arc(sx, sy, Math.max(1, wd.range * s), a - wd.half, a + wd.half);
    ctx.closePath();
    ctx.fillStyle = wd.colour;
    ctx.globalAlpha = 0.55;
    ctx.fill();
    ctx.globalAlpha = 1;
  }
  for (const [x, y, colour] of points) {
    const [sx, sy] = tr(x, y);
    ctx.fillStyle = colour;
    ctx.fillRect(sx - 1.5, sy - 1.5, 3, 3);
  }
  // the robot
  const dims = session.cls ? session.cls.dimensions : [0.5, 0.4];
  const [x0, y0] = tr(dims[0] / 2, -dims[1] / 2);
  ctx.fillStyle = "rgba(61,139,253,.85)";
  ctx.fillRect(x0, y0, dims[1] * s, dims[0] * s);
  ctx.fillStyle = "#fff";
  ctx.beginPath();
  ctx.moveTo(...tr(dims[0] / 2, 0));
  ctx.lineTo(...tr(dims[0] / 2 - 0.12, -0.08));
  ctx.lineTo(...tr(dims[0] / 2 - 0.12, 0.08));
  ctx.closePath();
  ctx.fill();
  ctx.fillStyle = "rgba(255,255,255,.5)";
  ctx.font = "10px system-ui, sans-serif";
  ctx.fillText(`${radius} m`, 6, 12);
}
