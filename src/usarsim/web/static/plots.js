// Small plots over time of the attached robot, the last WINDOW_S seconds of simulated time:
// its speed (from its positions: its GroundTruth sensor, else its INS, else its odometry,
// else the ground-truth service), its battery (STA's Battery, seconds of charge left) and
// the distance to the nearest obstacle (the smallest range of its laser scanners, else of
// its sonars and other range sensors).

export const WINDOW_S = 60; // simulated seconds shown
const KEEP_S = WINDOW_S + 5; // kept a little longer than shown
const SPEED_SPAN_S = 0.2; // a speed is the distance covered over at least this long
const POSITIONS_KEPT_S = 2;

// sources of the robot's position, best first (a better one, once seen, replaces the others)
export const POSITION_RANK = { GroundTruth: 3, INS: 2, Odometry: 1, truth: 0 };

// One quantity over time: times (s) and values, oldest first.
export class Series {
  constructor() {
    this.t = [];
    this.v = [];
  }

  push(t, v) {
    if (!Number.isFinite(t) || !Number.isFinite(v)) return;
    const n = this.t.length;
    if (n && t < this.t[n - 1] - 1e-6) this.clear(); // the clock went back (a new world): start again
    else if (n && Math.abs(t - this.t[n - 1]) < 1e-6) {
      this.v[n - 1] = v; // the same instant again: the latest value counts
      return;
    }
    this.t.push(t);
    this.v.push(v);
    let drop = 0;
    while (drop < this.t.length && this.t[drop] < t - KEEP_S) drop++;
    if (drop) {
      this.t.splice(0, drop);
      this.v.splice(0, drop);
    }
  }

  clear() {
    this.t = [];
    this.v = [];
  }

  get latest() {
    return this.v.length ? this.v[this.v.length - 1] : null;
  }

  get latestTime() {
    return this.t.length ? this.t[this.t.length - 1] : null;
  }
}

// What the plots show of one robot, gathered from the lines it receives.
export class RobotTrack {
  constructor() {
    this.speed = new Series();
    this.battery = new Series();
    this.obstacle = new Series();
    this.positionRank = -1;
    this.positions = []; // [t, [x, y, z]] of the best source, the last POSITIONS_KEPT_S
    this.scannerSeen = false;
  }

  // a position (metres, USARSim frame) at simulated time t, from a source of POSITION_RANK
  position(source, t, p) {
    const rank = POSITION_RANK[source] ?? -1;
    if (rank < this.positionRank || !Number.isFinite(t) || !p || p.length < 2) return;
    if (rank > this.positionRank) {
      this.positionRank = rank;
      this.positions = [];
    }
    const pos = this.positions;
    const last = pos[pos.length - 1];
    if (last && t <= last[0] + 1e-6) {
      if (t < last[0] - 1e-6) this.positions = []; // the clock went back
      else return;
    }
    const here = [Number(p[0]) || 0, Number(p[1]) || 0, Number(p[2]) || 0];
    this.positions.push([t, here]);
    while (this.positions.length > 2 && this.positions[0][0] < t - POSITIONS_KEPT_S) this.positions.shift();
    // the newest earlier position at least SPEED_SPAN_S before this one
    let before = null;
    for (let i = this.positions.length - 2; i >= 0; i--) {
      if (t - this.positions[i][0] >= SPEED_SPAN_S - 1e-6) {
        before = this.positions[i];
        break;
      }
    }
    if (!before) return;
    const [t0, q] = before;
    this.speed.push(t, Math.hypot(here[0] - q[0], here[1] - q[1], here[2] - q[2]) / (t - t0));
  }

  // the ranges (metres) a range sensor measured at time t: scanners first, else the others
  ranges(scanner, t, values) {
    if (scanner) this.scannerSeen = true;
    else if (this.scannerSeen) return;
    let least = Infinity;
    for (const v of values) if (Number.isFinite(v) && v >= 0 && v < least) least = v;
    if (least < Infinity) this.obstacle.push(t, least);
  }

  batteryLeft(t, seconds) {
    this.battery.push(t, seconds);
  }

  get latestTime() {
    const ts = [this.speed.latestTime, this.battery.latestTime, this.obstacle.latestTime].filter((x) => x !== null);
    return ts.length ? Math.max(...ts) : null;
  }
}

// One small plot on a canvas: the series over the last WINDOW_S seconds up to `now`, its
// latest value written in its corner.
export class TimePlot {
  constructor(canvas, { title, unit, digits = 2, colour = "#3d8bfd", floor = 1 }) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.title = title;
    this.unit = unit;
    this.digits = digits;
    this.colour = colour;
    this.floor = floor; // the top of the scale is at least this
    this.latest = null; // the value written, as last drawn
    this.points = 0; // points drawn, as last drawn
  }

  fit() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width * dpr));
    const h = Math.max(1, Math.round(r.height * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
    return [r.width, r.height, dpr];
  }

  draw(series, now, note = "") {
    const [w, h, dpr] = this.fit();
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = "#101216";
    ctx.fillRect(0, 0, w, h);
    const top = 14; // below the words
    const bottom = h - 2;
    const t0 = (now ?? 0) - WINDOW_S;
    const ts = series ? series.t : [];
    const vs = series ? series.v : [];
    let first = ts.findIndex((t) => t >= t0);
    if (first < 0) first = ts.length;
    let hi = this.floor;
    for (let i = first; i < ts.length; i++) hi = Math.max(hi, vs[i]);
    hi = niceCeil(hi);
    // grid: half and full scale
    ctx.strokeStyle = "#262a33";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (const k of [0, 0.5, 1]) {
      const y = Math.round(bottom - k * (bottom - top)) + 0.5;
      ctx.moveTo(0, y);
      ctx.lineTo(w, y);
    }
    ctx.stroke();
    // the line
    const xOf = (t) => ((t - t0) / WINDOW_S) * w;
    const yOf = (v) => bottom - (Math.min(v, hi) / hi) * (bottom - top);
    ctx.strokeStyle = this.colour;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    for (let i = first; i < ts.length; i++) {
      if (i === first) ctx.moveTo(xOf(ts[i]), yOf(vs[i]));
      else ctx.lineTo(xOf(ts[i]), yOf(vs[i]));
    }
    ctx.stroke();
    this.points = ts.length - first;
    this.latest = this.points ? vs[vs.length - 1] : null;
    // the words
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "top";
    ctx.textAlign = "left";
    ctx.fillStyle = "#8a93a3";
    ctx.fillText(this.title, 4, 2);
    const tw = ctx.measureText(this.title).width;
    const value = this.latest === null ? (note || "–") : `${this.latest.toFixed(this.digits)} ${this.unit}`;
    ctx.fillStyle = "#dfe3ea";
    ctx.fillText(value, tw + 10, 2);
    const scale = `${formatScale(hi)} ${this.unit} · ${WINDOW_S} s`;
    if (tw + 10 + ctx.measureText(value).width + 12 + ctx.measureText(scale).width < w) { // where there is room
      ctx.textAlign = "right";
      ctx.fillStyle = "#8a93a3";
      ctx.fillText(scale, w - 4, 2);
    }
    ctx.textBaseline = "alphabetic";
    this.canvas.dataset.latest = this.latest === null ? "" : String(this.latest);
    this.canvas.dataset.points = String(this.points);
  }
}

// the smallest of 1, 2, 2.5, 5 times a power of ten that is at least v
function niceCeil(v) {
  if (!(v > 0)) return 1;
  const p = 10 ** Math.floor(Math.log10(v));
  for (const m of [1, 2, 2.5, 5, 10]) if (m * p >= v * 0.999) return m * p;
  return 10 * p;
}

function formatScale(v) {
  return v >= 10 ? v.toFixed(0) : v >= 1 ? String(Number(v.toFixed(1))) : String(Number(v.toFixed(2)));
}
