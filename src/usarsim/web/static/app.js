// The operator console: the spectator (world view, 3-D view, plots of the attached robot),
// robot operation (video, range sensors, sensor tree, wheels, camera, light) and the
// command console (spawn, any protocol line, the log of every message received).  A robot that another controller
// drives is watched read-only: its sensors, range view and log, never its controls.

import { TimePlot } from "./plots.js";
import { cleanName, parseLine, splitSegment } from "./protocol.js";
import { RobotSession } from "./robot.js";
import { drawRanges, rangeGeometry, SensorTree } from "./sensors.js";
import { Video } from "./video.js";
import { View3D } from "./view3d.js";
import { WorldView } from "./worldview.js";

const $ = (id) => document.getElementById(id);
const TRUTH_PERIOD_MS = 200;
const PLOT_PERIOD_MS = 250;
const LOG_MAX = 3000; // entries kept; older ones are dropped
const CHASE = "Chase"; // the camera name of the view from above and behind a robot

class Console {
  constructor() {
    this.pageId = Math.random().toString(36).slice(2, 10);
    this.sessions = [];
    this.selected = null;
    this.classes = new Map();
    this.world = null;
    this.info = null;
    this.truthRows = [];
    this.attached = null; // { robot, camera, view: "camera" | "chase" }
    this.watching = null; // the watch session of another controller's robot, if any
    this.log = [];
    this.logQueue = [];
    this.logSeq = 0;
    this.history = [];
    this.keysDown = new Set();
    this.map = new WorldView($("world-view"), {
      robotClicked: (name) => this.robotClicked(name),
      detach: () => this.detach(),
      picked: (x, y) => this.picked(x, y),
      isOwn: (name) => !!this.ownSession(name),
      classOf: (name) => this.classOf(name),
    });
    this.video = new Video($("video"), {
      overlay: $("video-overlay"), fps: $("video-fps"), width: $("video-width"), height: $("video-height"),
    });
    this.video.pageId = this.pageId;
    this.view3d = new View3D($("view3d"), { overlay: $("view3d-overlay"), info: $("view3d-info"),
      followButton: $("view3d-follow"), sizeOf: (name) => this.dimensionsOf(name) });
    this.plots = {
      speed: new TimePlot($("plot-speed"), { title: "Speed", unit: "m/s", digits: 2, colour: "#3ddc6a", floor: 0.5 }),
      battery: new TimePlot($("plot-battery"), { title: "Battery", unit: "s", digits: 0, colour: "#ffcc4d", floor: 10 }),
      obstacle: new TimePlot($("plot-obstacle"), { title: "Nearest obstacle", unit: "m", digits: 2, colour: "#e0593b", floor: 1 }),
    };
    this.simTime = null;
    this.tree = new SensorTree($("sensor-tree"));
    this.bindUi();
    this.load();
    setInterval(() => this.drawRanges(), 200);
    setInterval(() => this.drawPlots(), PLOT_PERIOD_MS);
    requestAnimationFrame(() => this.flushLog());
  }

  async load() {
    try {
      const [info, world, classes] = await Promise.all(
        ["/api/info", "/api/world", "/api/classes"].map((u) => fetch(u).then((r) => r.json())));
      this.info = info;
      this.world = world;
      for (const c of classes) this.classes.set(c.name.toLowerCase(), c);
      $("world-name").textContent = world.name;
      document.title = `usarsim · ${world.name}`;
      if (info.lockstep) {
        const note = $("mode-note");
        note.hidden = false;
        note.textContent = "lock-step: the world moves only on STEP {Time s}";
      }
      this.map.setWorld(world);
      this.view3d.setWorld(world);
      this.fillSpawnForm();
    } catch (exc) {
      this.status(`cannot load the console's data: ${exc}`);
    }
    this.pollTruth();
    this.pollRadio();
  }

  status(text) {
    $("status").textContent = text || "";
  }

  ownSession(name) {
    return this.sessions.find((s) => s.name === name && !s.closed && !s.watch) || null;
  }

  classOf(name) {
    if (!name) return null;
    const bare = String(name).replace(/^usarbot\./i, "").toLowerCase();
    return this.classes.get(bare) || null;
  }

  // ground truth ---------------------------------------------------------------------
  async pollTruth() {
    let wait = TRUTH_PERIOD_MS;
    try {
      const r = await fetch("/api/truth");
      const data = await r.json();
      if (data.error) {
        this.status(data.error);
        wait = 1000;
      } else {
        this.status("");
      }
      this.truthRows = data.objects || [];
      this.map.setTruth(this.truthRows);
      this.view3d.setTruth(this.truthRows);
      const t = this.truthRows.length ? this.truthRows[0].time : null;
      if (t !== null) {
        $("sim-time").textContent = t.toFixed(1);
        this.simTime = t;
      }
      // where each robot is: its speed for the plots when it has no position sensor of its own
      for (const s of this.sessions) {
        const row = s.name && !s.closed ? this.map.robots.get(s.name) : null;
        if (row) s.track.position("truth", row.time, row.location);
      }
      this.updateRobotList();
      this.updateScanOnMap();
    } catch (exc) {
      this.status("the simulator does not answer");
      wait = 1000;
    }
    setTimeout(() => this.pollTruth(), wait);
  }

  // the radio channel's traffic, link by link (nothing to show under USARSim's ideal channel)
  async pollRadio() {
    let data;
    try {
      data = await (await fetch("/api/radio")).json();
    } catch (exc) {
      setTimeout(() => this.pollRadio(), 2000);
      return;
    }
    if (!data.channel || data.channel === "ideal") return; // it counts nothing: no panel
    $("radio-traffic").hidden = false;
    $("radio-channel").textContent = data.channel;
    const rows = data.links.map((l) => {
      const tr = document.createElement("tr");
      const lost = l.dropped.range + l.dropped.loss + l.dropped.capacity;
      const why = `out of range ${l.dropped.range}, lost ${l.dropped.loss}, queue full ${l.dropped.capacity}`;
      const ms = 1000 * l.mean_delay_s;
      const cells = [`${l.from} → ${l.to}`, String(l.delivered), String(lost), ms < 10 ? ms.toFixed(1) : ms.toFixed(0)];
      for (const [i, text] of cells.entries()) {
        const td = document.createElement("td");
        td.textContent = text;
        if (i === 2) td.title = why;
        tr.append(td);
      }
      return tr;
    });
    $("radio-links").querySelector("tbody").replaceChildren(...rows);
    setTimeout(() => this.pollRadio(), 1000);
  }

  updateRobotList() {
    const list = $("world-robots");
    const robots = [...this.map.robots.values()];
    const sig = robots.map((o) => `${o.name}|${o.class}|${this.map.handlers.isOwn(o.name)}|${this.attached && this.attached.robot === o.name}`).join(";");
    if (sig === this.robotSig) return;
    this.robotSig = sig;
    list.replaceChildren(...robots.map((o) => {
      const li = document.createElement("li");
      li.dataset.name = o.name;
      li.className = this.map.handlers.isOwn(o.name) ? "own" : "other";
      if (this.attached && this.attached.robot === o.name) li.classList.add("attached");
      li.title = this.map.handlers.isOwn(o.name) ? `Attach to ${o.name}` : `Watch ${o.name} (read-only)`;
      li.append(o.name + " ");
      const cls = document.createElement("span");
      cls.className = "cls";
      cls.textContent = o.class;
      li.append(cls);
      li.addEventListener("click", () => this.robotClicked(o.name));
      return li;
    }));
  }

  // the selected robot's laser in the world view, from its own GroundTruth where it has one
  updateScanOnMap() {
    const s = this.selected;
    if (!s || !s.alive) {
      this.map.scan = null;
      return;
    }
    const row = this.map.robots.get(s.name);
    const pose = s.pose || (row ? { location: row.location, rotation: row.rotation } : null);
    if (!pose) return;
    const { points } = rangeGeometry(s);
    const [x, y] = pose.location;
    const yaw = pose.rotation[2];
    const c = Math.cos(yaw);
    const sn = Math.sin(yaw);
    this.map.scan = { name: s.name, points: points.map(([px, py, col]) => [x + c * px - sn * py, y + sn * px + c * py, col]) };
    this.map.dirty = true;
  }

  // sessions -----------------------------------------------------------------------
  fillSpawnForm() {
    const sel = $("spawn-class");
    sel.replaceChildren(...[...this.classes.values()].map((c) => {
      const o = document.createElement("option");
      o.value = c.name;
      o.textContent = `${c.name} (${c.drive})`;
      o.title = c.description;
      return o;
    }));
    sel.value = this.classes.has("p2at") ? "P2AT" : sel.options[0]?.value;
    const starts = $("spawn-start");
    starts.replaceChildren(...this.world.start_poses.map((p) => {
      const o = document.createElement("option");
      o.value = p.name;
      o.textContent = p.name;
      return o;
    }));
    this.updateSpawnZ();
  }

  updateSpawnZ() {
    const c = this.classOf($("spawn-class").value);
    if (c) $("spawn-z").value = c.spawn_z.toFixed(2);
  }

  uniqueName(cls) {
    const taken = new Set([...this.map.robots.keys(), ...this.sessions.filter((s) => !s.closed).map((s) => s.name)]);
    for (let i = 1; ; i++) if (!taken.has(`${cls}${i}`)) return `${cls}${i}`;
  }

  spawn() {
    const clsName = $("spawn-class").value;
    const cls = this.classOf(clsName);
    if (!cls) return;
    const name = cleanName($("spawn-name").value) || this.uniqueName(cls.name);
    let where;
    if (document.querySelector('input[name="spawn-at"]:checked').value === "start") {
      where = `{Start ${$("spawn-start").value}}`;
    } else {
      const n = (id) => Number($(id).value) || 0;
      where = `{Location ${n("spawn-x")},${n("spawn-y")},${n("spawn-z")}} {Rotation 0,0,${n("spawn-yaw")}}`;
    }
    const s = this.openSession({ name, cls, initLine: `INIT {ClassName USARBot.${cls.name}} {Name ${name}} ${where}` });
    $("spawn-name").value = "";
    return s;
  }

  openSession({ name, cls, initLine }) {
    const s = new RobotSession(this, { name, cls, initLine });
    this.sessions.push(s);
    this.select(s);
    return s;
  }

  sessionAlive(s) {
    if (s.cls && s.cls.cameras.length) s.send("GETCONF {Type Camera}");
    if (this.selected === s) {
      this.renderSessions();
      this.updateControls();
      if (s.name && !s.watch) this.attach(s.name); // a robot just spawned: its camera
    }
  }

  sessionClosed(s, reason) {
    if (s.watch) {
      if (!s.left) {
        s.left = { time: null, reason: reason || "the console's server closed the connection" };
        this.robotLeft(s);
      }
      return;
    }
    this.note(s, `connection closed${reason ? ": " + reason : ""}`);
    if (this.attached && this.attached.robot === s.name) this.detach();
    this.renderSessions();
    this.updateControls();
    this.updateBanner();
  }

  // a watched robot left the world (or could not be watched): the panes keep its last
  // readings under a banner that says so; its video ends
  robotLeft(s) {
    const l = s.left || {};
    this.note(s, l.time !== null && l.time !== undefined
      ? `${s.name} left the world at ${Number(l.time).toFixed(1)} s${l.reason ? " (" + l.reason + ")" : ""}`
      : `cannot watch ${s.name}${l.reason ? ": " + l.reason : ""}`);
    if (this.attached && this.attached.robot === s.name) {
      this.attached = null;
      this.map.attached = null;
      this.map.dirty = true;
      this.view3d.setAttached(null);
      $("video-robot").textContent = "";
      $("video-camera").replaceChildren();
      this.video.detach();
      this.video.message(`${s.name} left the world.`);
      this.robotSig = "";
      this.updateRobotList();
    }
    this.renderSessions();
    this.updateControls();
    this.updateBanner();
  }

  select(s) {
    this.selected = s;
    this.tree.show(s);
    this.renderSessions();
    this.updateControls();
    this.updateBanner();
  }

  // what the operation panel shows: a watched robot (read-only), or one that has left
  updateBanner() {
    const s = this.selected;
    const el = $("robot-banner");
    let text = "";
    let kind = "";
    if (s && s.watch && s.left) {
      const l = s.left;
      kind = "gone";
      text = l.time !== null && l.time !== undefined
        ? `Robot ${s.name} left the world at ${Number(l.time).toFixed(1)} s (${l.reason || "its controller disconnected"}). ` +
          "The readings below are the last it sent."
        : `Cannot watch ${s.name}: ${l.reason}`;
    } else if (s && s.watch) {
      kind = "watch";
      text = `Watching ${s.name}${s.controller ? ", driven by " + s.controller : ""}: read-only.`;
    } else if (s && s.closed && s.name) {
      kind = "gone";
      text = `Robot ${s.name} left the world: its connection closed. The readings below are the last it sent.`;
    }
    el.textContent = text;
    el.hidden = !text;
    el.className = "banner " + kind;
    $("operation").classList.toggle("stale", kind === "gone");
  }

  // watch another controller's robot: its sensors, range view and log, read-only
  watchRobot(name) {
    const w = this.watching;
    if (w && w.name === name && !w.closed) {
      if (this.selected !== w) this.select(w);
      return;
    }
    this.stopWatching();
    const row = this.map.robots.get(name);
    const s = new RobotSession(this, { name, cls: row ? this.classOf(row.class) : null, watch: true });
    this.watching = s;
    this.sessions.push(s);
    this.select(s);
  }

  stopWatching() {
    if (this.watching) this.closeSession(this.watching);
  }

  closeSession(s) {
    s.close();
    if (s === this.watching) this.watching = null;
    this.sessions = this.sessions.filter((x) => x !== s);
    if (s.watch && this.attached && this.attached.robot === s.name) this.detach();
    if (this.selected === s) this.select(this.sessions.filter((x) => !x.watch).pop() || null);
    this.renderSessions();
  }

  renderSessions() {
    const box = $("sessions");
    box.replaceChildren(...this.sessions.map((s) => {
      const b = document.createElement("button");
      b.type = "button";
      b.setAttribute("role", "tab");
      b.className = (s === this.selected ? "selected " : "") + (s.closed || s.left ? "dead " : "") + (s.watch ? "watch" : "");
      b.textContent = s.watch ? `${s.label} · ${s.left ? "left" : "watching"}` : s.label;
      b.title = s.watch ? (s.left ? `${s.label} has left the world` : `Watching ${s.label} (read-only)`)
        : s.closed ? "Connection closed" : `Operate ${s.label}`;
      const x = document.createElement("span");
      x.className = "x";
      x.textContent = "×";
      x.title = s.watch ? "Stop watching (the robot stays)" : "Close this connection (removes the robot)";
      x.addEventListener("click", (ev) => {
        ev.stopPropagation();
        this.closeSession(s);
      });
      b.append(x);
      b.addEventListener("click", () => {
        this.select(s);
        if (s.alive && s.name && !(this.attached && this.attached.robot === s.name)) this.attach(s.name);
      });
      return b;
    }));
    const t = this.commandSession();
    $("command-target").textContent = t ? t.label : "a new connection";
  }

  // the session the command box and the controls speak for: the selected robot of this page
  commandSession() {
    const s = this.selected;
    return s && !s.closed && !s.watch ? s : null;
  }

  readingsChanged(s) {
    this.tree.changed(s);
  }

  statusChanged(s) {
    if (s === this.selected) this.updateControls();
  }

  updateControls() {
    const s = this.selected;
    const live = !!(s && s.alive && !s.closed && !s.watch);
    $("wheels").disabled = !live || s.drive === "static";
    $("camera-group").disabled = !live || !(s.cls && s.cls.cameras.length);
    $("light-group").disabled = !live;
    $("wheels").classList.toggle("aerial", !!(s && (s.drive === "aerial" || s.drive === "nautical")));
    for (const b of document.querySelectorAll("#wheels .ack")) b.disabled = !(s && s.drive === "ackermann");
    $("speed").textContent = s ? s.speedText() : "–";
    $("lights-button").textContent = s && s.lightOn ? "Lights Off" : "Lights On";
  }

  // a robot's length, width and height (metres), from its class; null when not known
  dimensionsOf(robot) {
    const row = this.map.robots.get(robot);
    const s = this.sessions.find((x) => x.name === robot);
    const cls = (s && s.cls) || (row && this.classOf(row.class));
    return cls ? cls.dimensions : null;
  }

  // video --------------------------------------------------------------------------
  camerasOf(robot) {
    const row = this.map.robots.get(robot);
    const s = this.sessions.find((x) => x.name === robot);
    const cls = (s && s.cls) || (row && this.classOf(row.class));
    return cls ? cls.cameras : ["Camera"];
  }

  attach(robot, camera) {
    const cams = this.camerasOf(robot);
    const cam = camera || cams[0] || CHASE;
    this.attached = { robot, camera: cam };
    this.map.attached = robot;
    this.map.dirty = true;
    this.view3d.setAttached(robot);
    const sel = $("video-camera");
    sel.replaceChildren(...[...cams, CHASE].map((c) => {
      const o = document.createElement("option");
      o.value = c;
      o.textContent = c === CHASE ? "Chase (above and behind)" : c;
      return o;
    }));
    sel.value = cam;
    $("video-robot").textContent = robot;
    this.video.attach(robot, cam);
    const own = this.ownSession(robot);
    if (own) {
      if (this.watching) this.stopWatching();
      if (own !== this.selected) this.select(own);
    } else {
      this.watchRobot(robot); // another controller's robot: watched, never operated
    }
    this.robotSig = "";
    this.updateRobotList();
  }

  detach() {
    this.stopWatching();
    this.attached = null;
    this.map.attached = null;
    this.map.dirty = true;
    this.view3d.setAttached(null);
    $("video-robot").textContent = "";
    $("video-camera").replaceChildren();
    this.video.detach();
    this.robotSig = "";
    this.updateRobotList();
  }

  toggleChase() {
    const a = this.attached;
    if (!a) return;
    if (a.camera === CHASE) this.attach(a.robot, a.previous || this.camerasOf(a.robot)[0] || CHASE);
    else {
      const prev = a.camera;
      this.attach(a.robot, CHASE);
      this.attached.previous = prev;
    }
  }

  robotClicked(name) {
    this.attach(name);
  }

  picked(x, y) {
    $("spawn-x").value = x.toFixed(2);
    $("spawn-y").value = y.toFixed(2);
    document.querySelector('input[name="spawn-at"][value="location"]').checked = true;
    this.setPicking(false);
  }

  setPicking(on) {
    this.map.picking = on;
    $("map-pick").setAttribute("aria-pressed", String(on));
    $("world-view").classList.toggle("picking", on);
  }

  setTrace(on) {
    this.map.showTrace = on;
    this.map.dirty = true;
    for (const b of document.querySelectorAll(".trace-toggle")) {
      b.setAttribute("aria-pressed", String(on));
      b.textContent = on ? "Trace On" : "Trace Off";
    }
  }

  drawRanges() {
    drawRanges($("range-view"), this.selected, Number($("range-radius").value) || 5);
  }

  // the plots of the selected robot (the attached one), up to the latest simulated time
  drawPlots() {
    if (document.hidden) return;
    const s = this.selected;
    const tr = s ? s.track : null;
    const times = [this.simTime, tr && tr.latestTime].filter((x) => x !== null && x !== undefined);
    const now = times.length ? Math.max(...times) : 0;
    const note = s ? "no reading yet" : "no robot";
    for (const k of ["speed", "battery", "obstacle"]) this.plots[k].draw(tr ? tr[k] : null, now, note);
  }

  // the command box ------------------------------------------------------------------
  sendCommand(text) {
    const line = text.trim();
    if (!line) return;
    let s = this.commandSession();
    if (!s) {
      // a new connection, as USAR_UI's Connect: the line (an INIT, say) goes out on it
      s = this.openSession({ name: "", cls: null, initLine: line });
    } else {
      s.send(line);
    }
    this.history = [line, ...this.history.filter((h) => h !== line)].slice(0, 30);
    $("command-history").replaceChildren(...this.history.map((h) => {
      const o = document.createElement("option");
      o.value = h;
      return o;
    }));
    this.renderSessions();
  }

  // the log ------------------------------------------------------------------------
  logLine(session, text, dir) {
    this.logQueue.push({ id: ++this.logSeq, who: session.label, text, dir });
  }

  note(session, text) {
    this.logQueue.push({ id: ++this.logSeq, who: session.label, text, dir: "note" });
  }

  flushLog() {
    requestAnimationFrame(() => this.flushLog());
    if (!this.logQueue.length) return;
    const q = this.logQueue;
    this.logQueue = [];
    for (const e of q) this.log.push(e);
    if (this.log.length > LOG_MAX) this.log.splice(0, this.log.length - LOG_MAX);
    const el = $("log");
    const filter = $("log-filter").value.trim().toLowerCase();
    const frag = document.createDocumentFragment();
    for (const e of q) {
      if (filter && !e.text.toLowerCase().includes(filter)) continue;
      frag.append(this.logEntry(e));
    }
    el.append(frag);
    while (el.childElementCount > LOG_MAX) el.firstElementChild.remove();
    if ($("log-follow").checked) el.scrollTop = el.scrollHeight;
    $("log-count").textContent = `${this.logSeq} lines`;
  }

  logEntry(e) {
    const div = document.createElement("div");
    div.className = "entry " + e.dir;
    div.dataset.id = e.id;
    const who = document.createElement("span");
    who.className = "who";
    who.textContent = e.who;
    const txt = document.createElement("span");
    txt.className = "txt";
    txt.textContent = e.text.length > 400 ? e.text.slice(0, 400) + "…" : e.text;
    div.append(who, txt);
    return div;
  }

  refilterLog() {
    const el = $("log");
    const filter = $("log-filter").value.trim().toLowerCase();
    el.replaceChildren(...this.log.filter((e) => !filter || e.text.toLowerCase().includes(filter)).map((e) => this.logEntry(e)));
    el.scrollTop = el.scrollHeight;
  }

  openMessage(id) {
    const e = this.log.find((x) => x.id === id);
    if (!e) return;
    $("message-title").textContent = `${e.dir === "out" ? "Sent on" : e.dir === "in" ? "Received by" : "Note on"} ${e.who}`;
    $("message-text").textContent = e.text;
    const { type, segments } = parseLine(e.text);
    const rows = [["type", type], ...segments.map((b) => splitSegment(b))];
    $("message-segments").replaceChildren(...rows.map(([k, v]) => {
      const tr = document.createElement("tr");
      const a = document.createElement("td");
      const b = document.createElement("td");
      a.textContent = k;
      b.textContent = v;
      tr.append(a, b);
      return tr;
    }));
    $("message-dialog").showModal();
  }

  // buttons and keys -----------------------------------------------------------------
  act(name) {
    const s = this.commandSession();
    if (name === "trace") return this.setTrace(!this.map.showTrace);
    if (!s || !s.alive) return;
    const cam = this.attached && this.attached.robot === s.name ? this.attached.camera : null;
    const acts = {
      forward: () => s.setMotion({ v: 1, w: 0 }),
      back: () => s.setMotion({ v: -1, w: 0 }),
      left: () => (s.drive === "ackermann" ? s.setMotion({ w: -1 }) : s.setMotion({ v: 0, w: -1 })),
      right: () => (s.drive === "ackermann" ? s.setMotion({ w: 1 }) : s.setMotion({ v: 0, w: 1 })),
      stop: () => s.stop(),
      faster: () => s.faster(),
      slower: () => s.slower(),
      "turn-more": () => s.turnMore(),
      "turn-less": () => s.turnLess(),
      straight: () => s.straight(),
      rise: () => s.setMotion({ a: s.motion.a === 1 ? 0 : 1 }),
      sink: () => s.setMotion({ a: s.motion.a === -1 ? 0 : -1 }),
      "tilt-up": () => s.tiltUp(),
      "tilt-down": () => s.tiltDown(),
      "pan-left": () => s.panLeft(),
      "pan-right": () => s.panRight(),
      "zoom-in": () => s.zoom(0.8, cam),
      "zoom-out": () => s.zoom(1.25, cam),
      lights: () => s.toggleLights(),
    };
    if (acts[name]) acts[name]();
    this.updateControls();
  }

  // arrow keys drive while held (USAR_UI's keyboard control)
  keyMotion() {
    const k = this.keysDown;
    return {
      v: (k.has("ArrowUp") ? 1 : 0) - (k.has("ArrowDown") ? 1 : 0),
      w: (k.has("ArrowRight") ? 1 : 0) - (k.has("ArrowLeft") ? 1 : 0),
      a: (k.has("PageUp") ? 1 : 0) - (k.has("PageDown") ? 1 : 0),
    };
  }

  onKey(ev, down) {
    const t = ev.target;
    if (t && (t.tagName === "INPUT" || t.tagName === "TEXTAREA" || t.tagName === "SELECT" || t.isContentEditable)) return;
    if ($("message-dialog").open) return;
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const s = this.commandSession();
    const driveKeys = ["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", "PageUp", "PageDown"];
    if (driveKeys.includes(ev.key)) {
      ev.preventDefault();
      if (down) {
        if (this.keysDown.has(ev.key)) return; // auto-repeat
        this.keysDown.add(ev.key);
      } else {
        this.keysDown.delete(ev.key);
      }
      if (s && s.alive) s.setMotion(this.keyMotion());
      return;
    }
    if (!down) return;
    const key = ev.key.length === 1 ? ev.key.toLowerCase() : ev.key;
    const handled = {
      " ": () => this.act("stop"),
      c: () => this.toggleChase(),
      l: () => this.act("lights"),
      t: () => this.setTrace(!this.map.showTrace),
      "+": () => this.act("faster"),
      "=": () => this.act("faster"),
      "-": () => this.act("slower"),
      Escape: () => this.detach(),
    }[key];
    if (handled) {
      ev.preventDefault();
      handled();
    }
  }

  bindUi() {
    $("spawn-form").addEventListener("submit", (ev) => {
      ev.preventDefault();
      this.spawn();
    });
    $("spawn-class").addEventListener("change", () => this.updateSpawnZ());
    $("command-form").addEventListener("submit", (ev) => {
      ev.preventDefault();
      this.sendCommand($("command").value);
      $("command").select();
    });
    $("log").addEventListener("click", (ev) => {
      const entry = ev.target.closest(".entry");
      if (entry) this.openMessage(Number(entry.dataset.id));
    });
    $("log-filter").addEventListener("input", () => this.refilterLog());
    $("log-sent").addEventListener("change", (ev) => $("log").classList.toggle("hide-sent", !ev.target.checked));
    $("log-clear").addEventListener("click", () => {
      this.log = [];
      $("log").replaceChildren();
    });
    $("message-copy").addEventListener("click", () => navigator.clipboard?.writeText($("message-text").textContent));
    for (const b of document.querySelectorAll("[data-act]")) b.addEventListener("click", () => this.act(b.dataset.act));
    for (const b of document.querySelectorAll(".trace-toggle")) b.addEventListener("click", () => this.setTrace(!this.map.showTrace));
    $("map-fit").addEventListener("click", () => this.map.fit());
    $("map-zoom-in").addEventListener("click", () => this.map.zoom(1.4));
    $("map-zoom-out").addEventListener("click", () => this.map.zoom(1 / 1.4));
    $("map-follow").addEventListener("click", (ev) => {
      this.map.follow = !this.map.follow;
      ev.currentTarget.setAttribute("aria-pressed", String(this.map.follow));
    });
    $("map-pick").addEventListener("click", () => this.setPicking(!this.map.picking));
    $("view3d-arena").addEventListener("click", () => this.view3d.arena());
    $("view3d-follow").addEventListener("click", () => this.view3d.setFollow(!this.view3d.follow));
    $("view3d-wide").addEventListener("click", (ev) => {
      const wide = !document.querySelector("main").classList.contains("wide3d");
      document.querySelector("main").classList.toggle("wide3d", wide);
      ev.currentTarget.setAttribute("aria-pressed", String(wide));
    });
    $("video-camera").addEventListener("change", (ev) => {
      if (this.attached) this.attach(this.attached.robot, ev.target.value);
    });
    $("video-maxfps").addEventListener("change", (ev) => (this.video.maxFps = Number(ev.target.value) || 10));
    window.addEventListener("keydown", (ev) => this.onKey(ev, true));
    window.addEventListener("keyup", (ev) => this.onKey(ev, false));
    window.addEventListener("blur", () => {
      // keys released while the page had no focus: stop a robot driven by the keyboard
      const s = this.commandSession();
      if (this.keysDown.size && s && s.alive) {
        this.keysDown.clear();
        s.setMotion(this.keyMotion());
      }
    });
    window.addEventListener("beforeunload", () => this.sessions.forEach((s) => s.close()));
  }
}

// reachable from the browser's developer console (and from tests)
window.usarsimConsole = new Console();
