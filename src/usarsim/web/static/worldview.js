// The spectator: the world seen from above.  Static geometry comes from /api/world; where
// robots, victims, tags and movable objects are comes from the ground-truth service.
// World frame (USARSim): X forward (up on the screen), Y right, Z down, yaw clockwise.

const TRACE_STEP_M = 0.05; // a trace gets a new point when its robot moved this far
const TRACE_MAX_POINTS = 20000;

function rgba(c, alpha) {
  const [r, g, b, a] = c || [0.7, 0.7, 0.7, 1];
  return `rgba(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)},${alpha ?? a})`;
}

function shade(c, k) {
  const [r, g, b, a] = c || [0.7, 0.7, 0.7, 1];
  return [r * k, g * k, b * k, a];
}

export class WorldView {
  constructor(canvas, handlers) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.handlers = handlers; // { robotClicked(name), detach(), picked(x, y), isOwn(name), classOf(name) }
    this.world = null;
    this.objects = []; // ground truth rows
    this.robots = new Map(); // name -> row
    this.traces = new Map(); // robot name -> [[x, y], ...]
    this.showTrace = true;
    this.follow = false;
    this.picking = false;
    this.attached = null;
    this.selected = null;
    this.scan = null; // { name, points: [[x, y, colour]] } of the selected robot, world frame
    this.showStartLabels = true;
    // the start poses' names as last drawn: { name, x, y, w, h } of each name's box and the
    // marker it names ([x, y]), in CSS pixels of the canvas
    this.startLabels = [];
    this.view = { cx: 0, cy: 0, scale: 30 };
    this.dirty = true;
    this.drag = null;
    this._bind();
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    const loop = () => {
      if (this.dirty) this.draw();
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  setWorld(world) {
    this.world = world;
    this.fit();
  }

  resize() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    this.canvas.width = Math.max(1, Math.round(r.width * dpr));
    this.canvas.height = Math.max(1, Math.round(r.height * dpr));
    this.dpr = dpr;
    this.dirty = true;
  }

  fit() {
    if (!this.world) return;
    const [x0, y0, x1, y1] = this.world.bounds;
    const w = this.canvas.width / this.dpr;
    const h = this.canvas.height / this.dpr;
    this.view.cx = (x0 + x1) / 2;
    this.view.cy = (y0 + y1) / 2;
    this.view.scale = Math.max(1, 0.92 * Math.min(w / Math.max(1, y1 - y0), h / Math.max(1, x1 - x0)));
    this.dirty = true;
  }

  zoom(factor, sx, sy) {
    const w = this.canvas.width / this.dpr;
    const h = this.canvas.height / this.dpr;
    if (sx === undefined) { sx = w / 2; sy = h / 2; }
    const [x, y] = this.toWorld(sx, sy);
    this.view.scale = Math.min(800, Math.max(2, this.view.scale * factor));
    // keep the world point under the cursor where it is
    this.view.cy = y - (sx - w / 2) / this.view.scale;
    this.view.cx = x + (sy - h / 2) / this.view.scale;
    this.dirty = true;
  }

  // world (x forward, y right) <-> screen (CSS pixels)
  toScreen(x, y) {
    const w = this.canvas.width / this.dpr;
    const h = this.canvas.height / this.dpr;
    return [w / 2 + (y - this.view.cy) * this.view.scale, h / 2 - (x - this.view.cx) * this.view.scale];
  }

  toWorld(sx, sy) {
    const w = this.canvas.width / this.dpr;
    const h = this.canvas.height / this.dpr;
    return [this.view.cx - (sy - h / 2) / this.view.scale, this.view.cy + (sx - w / 2) / this.view.scale];
  }

  setTruth(rows) {
    this.objects = rows;
    const robots = new Map();
    for (const o of rows) {
      if (["Victim", "RFIDTag", "FalseAlarm", "MovableObject", "RadioRelay"].includes(o.class)) continue;
      robots.set(o.name, o);
      const t = this.traces.get(o.name) || [];
      const last = t[t.length - 1];
      const [x, y] = o.location;
      if (!last || Math.hypot(x - last[0], y - last[1]) >= TRACE_STEP_M) {
        t.push([x, y]);
        if (t.length > TRACE_MAX_POINTS) t.splice(0, t.length - TRACE_MAX_POINTS);
        this.traces.set(o.name, t);
      }
    }
    this.robots = robots;
    if (this.follow && this.attached && robots.has(this.attached)) {
      const [x, y] = robots.get(this.attached).location;
      this.view.cx = x;
      this.view.cy = y;
    }
    this.dirty = true;
  }

  robotAt(sx, sy) {
    let best = null;
    let bestD = Infinity;
    for (const [name, o] of this.robots) {
      const [px, py] = this.toScreen(o.location[0], o.location[1]);
      const cls = this.handlers.classOf(o.class);
      const size = cls ? Math.max(cls.dimensions[0], cls.dimensions[1]) / 2 : 0.3;
      const d = Math.hypot(px - sx, py - sy);
      if (d <= Math.max(12, size * this.view.scale + 4) && d < bestD) {
        best = name;
        bestD = d;
      }
    }
    return best;
  }

  _bind() {
    const c = this.canvas;
    c.addEventListener("mousedown", (ev) => {
      if (ev.button !== 0) return;
      this.drag = { x: ev.clientX, y: ev.clientY, cx: this.view.cx, cy: this.view.cy, moved: false };
    });
    c.addEventListener("mousemove", (ev) => {
      if (this.drag || this.picking) return;
      const r = c.getBoundingClientRect();
      c.style.cursor = this.robotAt(ev.clientX - r.left, ev.clientY - r.top) ? "pointer" : "";
    });
    window.addEventListener("mousemove", (ev) => {
      const d = this.drag;
      if (!d) return;
      const dx = ev.clientX - d.x;
      const dy = ev.clientY - d.y;
      if (Math.abs(dx) + Math.abs(dy) > 3) {
        d.moved = true;
        c.classList.add("dragging");
      }
      this.view.cy = d.cy - dx / this.view.scale;
      this.view.cx = d.cx + dy / this.view.scale;
      this.dirty = true;
    });
    window.addEventListener("mouseup", (ev) => {
      const d = this.drag;
      this.drag = null;
      c.classList.remove("dragging");
      if (!d || d.moved || ev.button !== 0) return;
      const r = c.getBoundingClientRect();
      const sx = ev.clientX - r.left;
      const sy = ev.clientY - r.top;
      if (this.picking) {
        const [x, y] = this.toWorld(sx, sy);
        this.handlers.picked(x, y);
        return;
      }
      const name = this.robotAt(sx, sy);
      if (name) this.handlers.robotClicked(name);
    });
    c.addEventListener("contextmenu", (ev) => {
      ev.preventDefault();
      this.handlers.detach();
    });
    c.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      const r = c.getBoundingClientRect();
      this.zoom(Math.exp(-ev.deltaY * 0.0015), ev.clientX - r.left, ev.clientY - r.top);
    }, { passive: false });
  }

  // drawing ------------------------------------------------------------------------
  poly(points, fill, stroke, dash) {
    if (!points || points.length < 2) return;
    const ctx = this.ctx;
    ctx.beginPath();
    points.forEach(([x, y], i) => {
      const [sx, sy] = this.toScreen(x, y);
      if (i === 0) ctx.moveTo(sx, sy); else ctx.lineTo(sx, sy);
    });
    ctx.closePath();
    if (fill) { ctx.fillStyle = fill; ctx.fill(); }
    if (stroke) {
      ctx.setLineDash(dash || []);
      ctx.strokeStyle = stroke;
      ctx.lineWidth = 1;
      ctx.stroke();
      ctx.setLineDash([]);
    }
  }

  label(text, x, y, colour, dy = -10) {
    const [sx, sy] = this.toScreen(x, y);
    const ctx = this.ctx;
    ctx.font = "11px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.lineWidth = 3;
    ctx.strokeStyle = "rgba(0,0,0,.7)";
    ctx.strokeText(text, sx, sy + dy);
    ctx.fillStyle = colour;
    ctx.fillText(text, sx, sy + dy);
  }

  // Each start pose's name beside its marker: on its right, else on its left, below, above or
  // at a corner, wherever it covers no other marker or name and stays on the canvas.  Names
  // are placed one after another, going back to move an earlier one when a later one finds
  // no place (a row of poses closer together than their names are long: above and below in
  // turn); the first place when there is none.
  drawStartLabels(poses) {
    const ctx = this.ctx;
    let labels = [];
    if (this.showStartLabels) {
      ctx.font = "10px system-ui, sans-serif";
      const h = 11;
      const r = Math.max(5, 0.3 * this.view.scale); // how far the marker reaches from its pose
      const cw = this.canvas.width / this.dpr;
      const ch = this.canvas.height / this.dpr;
      const markers = poses.map((p) => {
        const [sx, sy] = this.toScreen(p.location[0], p.location[1]);
        return { x: sx - r, y: sy - r, w: 2 * r, h: 2 * r };
      });
      const overlaps = (a, b) => a.x < b.x + b.w + 2 && b.x < a.x + a.w + 2 && a.y < b.y + b.h + 2 && b.y < a.y + a.h + 2;
      const onCanvas = (b) => b.x >= 0 && b.y >= 0 && b.x + b.w <= cw && b.y + b.h <= ch;
      const candidates = poses.map((p, i) => {
        const m = markers[i];
        const sx = m.x + r;
        const sy = m.y + r;
        const w = ctx.measureText(p.name).width;
        const places = [[sx + r + 3, sy - h / 2], [sx - r - 3 - w, sy - h / 2], [sx - w / 2, sy + r + 2],
          [sx - w / 2, sy - r - 2 - h], [sx + r + 1, sy + r + 1], [sx + r + 1, sy - r - 1 - h],
          [sx - r - 1 - w, sy + r + 1], [sx - r - 1 - w, sy - r - 1 - h]].map(([x, y]) => ({ x, y, w, h }));
        const free = places.filter((b) => onCanvas(b) && !markers.some((o, j) => j !== i && overlaps(b, o)));
        // a name with no free place (its pose out of sight, say) keeps its first place and is
        // left out of the search
        return { name: p.name, marker: [sx, sy], places, free: free.length ? free : [places[0]], forced: !free.length };
      });
      // a search over the free places, in order, with a bound on its steps
      const chosen = [];
      let steps = 0;
      const place = (i) => {
        if (i === candidates.length) return true;
        const c = candidates[i];
        for (const b of c.free) {
          if (++steps > 5000) return false;
          if (!c.forced && chosen.some((o, j) => !candidates[j].forced && overlaps(b, o))) continue;
          chosen.push(b);
          if (place(i + 1)) return true;
          chosen.pop();
        }
        return false;
      };
      if (place(0)) {
        labels = candidates.map((c, i) => ({ name: c.name, ...chosen[i], marker: c.marker }));
      } else { // no arrangement: each name where it is free of those before it, else in its first place
        for (const c of candidates) {
          const b = c.free.find((x) => c.forced || !labels.some((o) => overlaps(x, o))) || c.places[0];
          labels.push({ name: c.name, ...b, marker: c.marker });
        }
      }
      ctx.textAlign = "left";
      ctx.textBaseline = "top";
      ctx.lineWidth = 3;
      for (const l of labels) {
        ctx.strokeStyle = "rgba(0,0,0,.75)";
        ctx.strokeText(l.name, l.x, l.y);
        ctx.fillStyle = "rgba(255,255,255,.7)";
        ctx.fillText(l.name, l.x, l.y);
      }
      ctx.textBaseline = "alphabetic";
    }
    this.startLabels = labels;
    const names = labels.map((l) => l.name).join(" ");
    if (this.canvas.dataset.startLabels !== names) this.canvas.dataset.startLabels = names;
  }

  // a shape given in a body's own frame (forward, right, metres), at x, y turned by yaw
  inFrame(x, y, yaw, draw) {
    const ctx = this.ctx;
    const [sx, sy] = this.toScreen(x, y);
    ctx.save();
    ctx.translate(sx, sy);
    ctx.rotate(yaw);
    const s = this.view.scale;
    draw(ctx, (fx, fy) => [fy * s, -fx * s], s);
    ctx.restore();
  }

  draw() {
    this.dirty = false;
    const ctx = this.ctx;
    const w = this.canvas.width / this.dpr;
    const h = this.canvas.height / this.dpr;
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    ctx.fillStyle = "#101216";
    ctx.fillRect(0, 0, w, h);
    const world = this.world;
    if (!world) return;
    const f = world.floor;
    const fx = f.center[0];
    const fy = f.center[1];
    this.poly([[fx - f.size[0] / 2, fy - f.size[1] / 2], [fx + f.size[0] / 2, fy - f.size[1] / 2],
      [fx + f.size[0] / 2, fy + f.size[1] / 2], [fx - f.size[0] / 2, fy + f.size[1] / 2]],
    rgba(shade(f.rgba, 0.55)), null);
    for (const wv of world.water) this.poly(wv.poly, "rgba(60,110,200,.35)", "rgba(90,140,230,.6)");
    for (const o of world.objects) {
      if (o.movable) continue;
      const k = 0.55 + 0.45 * Math.min(1, Math.max(0, o.top) / 1.5); // higher is lighter
      this.poly(o.poly, rgba(shade(o.rgba, k)), rgba(shade(o.rgba, k * 0.6)));
    }
    // start poses: a marker each, its name beside it
    for (const p of world.start_poses) {
      const [x, y] = p.location;
      this.inFrame(x, y, p.rotation[2], (c, tr) => {
        const a = tr(0.3, 0);
        const b = tr(-0.15, -0.15);
        const d = tr(-0.15, 0.15);
        c.beginPath(); c.moveTo(...a); c.lineTo(...b); c.lineTo(...d); c.closePath();
        c.strokeStyle = "rgba(255,255,255,.35)"; c.lineWidth = 1; c.stroke();
      });
    }
    this.drawStartLabels(world.start_poses);
    const truth = { Victim: [], RFIDTag: [], FalseAlarm: [], MovableObject: [], RadioRelay: [] };
    for (const o of this.objects) if (truth[o.class]) truth[o.class].push(o);
    // movable objects where they are now
    const movable = new Map(world.objects.filter((o) => o.movable).map((o) => [o.name, o]));
    for (const o of truth.MovableObject) {
      const m = movable.get(o.name);
      if (!m) continue;
      this.inFrame(o.location[0], o.location[1], o.rotation[2], (c, tr) => {
        c.beginPath();
        m.local.forEach(([px, py], i) => (i ? c.lineTo(...tr(px, py)) : c.moveTo(...tr(px, py))));
        c.closePath();
        c.fillStyle = rgba(m.rgba); c.fill();
        c.strokeStyle = "rgba(0,0,0,.6)"; c.stroke();
      });
    }
    for (const a of world.false_alarms) this.poly(a.poly, "rgba(154,163,173,.35)", "rgba(200,205,212,.8)", [3, 2]);
    const victims = truth.Victim.length ? truth.Victim : world.victims.map((v) => ({ name: v.name, location: v.location, rotation: v.rotation }));
    for (const v of victims) {
      this.inFrame(v.location[0], v.location[1], v.rotation[2], (c, tr, s) => {
        c.fillStyle = "rgba(240,163,107,.9)";
        c.beginPath();
        const [ax, ay] = tr(0.4, 0);
        c.ellipse(ax, ay, 0.2 * s, 0.55 * s, 0, 0, 2 * Math.PI);
        c.fill();
        c.beginPath();
        const [hx, hy] = tr(0.78, 0);
        c.arc(hx, hy, Math.max(2, 0.11 * s), 0, 2 * Math.PI);
        c.fill();
        c.strokeStyle = "rgba(240,163,107,.9)";
        c.lineWidth = Math.max(1, 0.12 * s);
        c.beginPath(); c.moveTo(...tr(0, -0.1)); c.lineTo(...tr(-0.9, -0.12));
        c.moveTo(...tr(0, 0.1)); c.lineTo(...tr(-0.9, 0.12)); c.stroke();
      });
      if (this.view.scale > 25) this.label(v.name, v.location[0], v.location[1], "#f0a36b", 18);
    }
    for (const t of truth.RFIDTag) {
      const [sx, sy] = this.toScreen(t.location[0], t.location[1]);
      ctx.fillStyle = "#b26cf0";
      ctx.beginPath();
      ctx.moveTo(sx, sy - 5); ctx.lineTo(sx + 5, sy); ctx.lineTo(sx, sy + 5); ctx.lineTo(sx - 5, sy);
      ctx.closePath(); ctx.fill();
      if (this.view.scale > 40) this.label("tag " + t.name, t.location[0], t.location[1], "#c99af5", -8);
    }
    // the radio relays robots dropped: orange squares
    for (const r of truth.RadioRelay) {
      const [sx, sy] = this.toScreen(r.location[0], r.location[1]);
      ctx.fillStyle = "#ff8c00";
      ctx.fillRect(sx - 4, sy - 4, 8, 8);
      ctx.strokeStyle = "rgba(0,0,0,.7)"; ctx.lineWidth = 1; ctx.strokeRect(sx - 4, sy - 4, 8, 8);
      if (this.view.scale > 40) this.label(r.name, r.location[0], r.location[1], "#ffb04d", -8);
    }
    // traces
    if (this.showTrace) {
      ctx.strokeStyle = "rgba(61,220,106,.85)";
      ctx.lineWidth = 2;
      for (const pts of this.traces.values()) {
        if (pts.length < 2) continue;
        ctx.beginPath();
        pts.forEach(([x, y], i) => {
          const [sx, sy] = this.toScreen(x, y);
          if (i) ctx.lineTo(sx, sy); else ctx.moveTo(sx, sy);
        });
        ctx.stroke();
      }
    }
    // the selected robot's laser
    if (this.scan) {
      for (const [x, y, colour] of this.scan.points) {
        const [sx, sy] = this.toScreen(x, y);
        ctx.fillStyle = colour;
        ctx.fillRect(sx - 1.5, sy - 1.5, 3, 3);
      }
    }
    // robots
    for (const [name, o] of this.robots) {
      const cls = this.handlers.classOf(o.class);
      const [len, wid] = cls ? cls.dimensions : [0.5, 0.4];
      const own = this.handlers.isOwn(name);
      this.inFrame(o.location[0], o.location[1], o.rotation[2], (c, tr, s) => {
        const [x0, y0] = tr(len / 2, -wid / 2);
        c.fillStyle = own ? "rgba(61,139,253,.9)" : "rgba(224,89,59,.9)";
        c.fillRect(x0, y0, wid * s, len * s);
        c.strokeStyle = name === this.attached ? "#ffd24a" : "rgba(0,0,0,.7)";
        c.lineWidth = name === this.attached ? 2.5 : 1;
        c.strokeRect(x0, y0, wid * s, len * s);
        // heading
        c.fillStyle = "#fff";
        c.beginPath();
        c.moveTo(...tr(len / 2, 0));
        c.lineTo(...tr(len / 2 - Math.min(len, 0.6) * 0.4, -wid * 0.3));
        c.lineTo(...tr(len / 2 - Math.min(len, 0.6) * 0.4, wid * 0.3));
        c.closePath();
        c.fill();
      });
      if (Math.max(len, wid) * this.view.scale < 8) {
        const [sx, sy] = this.toScreen(o.location[0], o.location[1]);
        ctx.fillStyle = own ? "#3d8bfd" : "#e0593b";
        ctx.beginPath(); ctx.arc(sx, sy, 4, 0, 2 * Math.PI); ctx.fill();
      }
      this.label(name, o.location[0], o.location[1], name === this.attached ? "#ffd24a" : "#fff",
        -Math.max(10, (Math.max(len, wid) / 2) * this.view.scale + 6));
    }
    this.drawScaleBar(w, h);
  }

  drawScaleBar(w, h) {
    const ctx = this.ctx;
    const target = 100 / this.view.scale;
    const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200];
    const m = steps.find((s) => s >= target) || 200;
    const px = m * this.view.scale;
    ctx.strokeStyle = "#dfe3ea";
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(12, h - 14); ctx.lineTo(12 + px, h - 14);
    ctx.moveTo(12, h - 18); ctx.lineTo(12, h - 10);
    ctx.moveTo(12 + px, h - 18); ctx.lineTo(12 + px, h - 10);
    ctx.stroke();
    ctx.fillStyle = "#dfe3ea";
    ctx.font = "11px system-ui, sans-serif";
    ctx.textAlign = "left";
    ctx.fillText(`${m} m`, 16 + px, h - 10);
    ctx.textAlign = "right";
    ctx.fillText("X ↑  Y →", w - 10, h - 10);
  }
}
