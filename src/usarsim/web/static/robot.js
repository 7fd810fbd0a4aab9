// One robot session: a WebSocket that the console's bridge relays to its own connection on
// the control port.  Lines go out as typed; every line the simulator sends comes back.
// The session keeps what the operation panel shows (latest readings, status, geometry)
// and turns the wheel, camera and light buttons into protocol commands.
//
// A watch session (watch: true) shows a robot that another controller drives: /ws/watch
// brings the lines the simulator sends that controller, read-only.  It sends nothing, and
// says when the robot has left the world.

import { RobotTrack } from "./plots.js";
import { fields, items, parseLine, vec } from "./protocol.js";

const DEG10 = 0.1745; // 10 degrees, the camera group's step (SimpleUI)
const RANGE_TYPES = new Set(["Sonar", "IR", "RangeSensor", "RangeScanner", "IRScanner"]);
const SCANNER_TYPES = new Set(["RangeScanner", "IRScanner"]);

export class RobotSession {
  constructor(console_, { name, cls, initLine, watch = false }) {
    this.console = console_;
    this.name = name || "";
    this.cls = cls || null; // the class description from /api/classes, when known
    this.watch = watch; // another controller's robot, watched read-only
    this.controller = ""; // a watched robot's controller (its address)
    this.left = null; // a watched robot that left the world: { time, reason }
    this.alive = false;
    this.closed = false;
    this.readings = new Map(); // tree key -> { title, time, head, named }
    this.geo = {}; // item type -> name -> { location, orientation }
    this.conf = {}; // item type -> name -> fields
    this.asked = new Set(); // item types whose GEO/CONF were asked for
    this.sta = {};
    this.pose = null; // from the robot's own GroundTruth sensor: { location, rotation }
    this.track = new RobotTrack(); // speed, battery and nearest obstacle over time, for the plots
    this.motion = { v: 0, w: 0, a: 0 }; // forward, right turn, up: -1, 0 or 1 each
    this.speed = 0.4; // share of the robot's top speed
    this.turn = 0.25; // Ackermann: share of its steering range a turn uses
    this.fov = null; // zoom of the camera being viewed, from RES
    this.pan = 0;
    this.tilt = 0;
    this.ptSent = {}; // pan-tilt link -> { value, at } last sent
    const proto = location.protocol === "https:" ? "wss" : "ws";
    const path = watch ? `/ws/watch?robot=${encodeURIComponent(this.name)}&page=${console_.pageId}`
      : `/ws/control?page=${console_.pageId}`;
    this.ws = new WebSocket(`${proto}://${location.host}${path}`);
    this.ws.onopen = () => {
      if (initLine && !watch) this.send(initLine);
    };
    this.ws.onmessage = (ev) => {
      const text = String(ev.data);
      if (watch && text.startsWith("{")) {
        this.watchEvent(JSON.parse(text));
        return;
      }
      for (const line of text.split("\n")) if (line) this.receive(line);
    };
    this.ws.onclose = (ev) => {
      this.closed = true;
      this.alive = false;
      this.console.sessionClosed(this, ev.reason || "");
    };
  }

  get label() {
    return this.name || "(unnamed)";
  }

  // what /ws/watch says besides the robot's lines: whom it watches, that it left, or why not
  watchEvent(msg) {
    if (msg.watching) {
      this.name = msg.watching;
      this.controller = msg.controller || "";
      if (!this.cls && msg.class) this.cls = this.console.classOf(msg.class);
      for (const line of msg.describe || []) this.keepDescription(parseLine(line).type, line);
      this.console.note(this, `watching ${this.name}${this.controller ? ", driven by " + this.controller : ""} (read-only)`);
      this.console.updateBanner();
    } else if (msg.left) {
      this.left = { time: msg.time, reason: msg.reason || "" };
      this.alive = false;
      this.console.robotLeft(this);
    } else if (msg.error) {
      this.left = { time: null, reason: msg.error };
      this.console.robotLeft(this);
    }
  }

  get drive() {
    return this.cls ? this.cls.drive : "skid";
  }

  send(line) {
    if (this.watch) return false; // nothing reaches a watched robot
    if (this.ws.readyState !== WebSocket.OPEN) return false;
    const text = String(line).trim();
    if (!text) return false;
    if (/^INIT\b/i.test(text)) {
      const f = fields(text);
      if (f.Name) this.name = f.Name;
      if (f.ClassName && !this.cls) this.cls = this.console.classOf(f.ClassName);
    }
    this.ws.send(text);
    this.console.logLine(this, text, "out");
    return true;
  }

  close() {
    if (!this.closed) this.ws.close();
  }

  // incoming lines -----------------------------------------------------------------
  receive(line) {
    this.console.logLine(this, line, "in");
    const type = parseLine(line).type;
    if (type === "STA" || type === "SEN" || type === "MISSTA" || type === "EFF") {
      if (!this.alive) {
        this.alive = true;
        this.console.sessionAlive(this);
      }
      this.keepReading(type, line);
    } else if (type === "GEO" || type === "CONF") {
      this.keepDescription(type, line);
    } else if (type === "RES") {
      const f = fields(line);
      if (f.Type === "Camera" && f.FOV) this.fov = Number(f.FOV);
    }
  }

  keepReading(type, line) {
    const it = items(line);
    const head = Object.fromEntries(it.head);
    let key, title;
    if (type === "SEN") {
      title = head.Type || "Sensor";
      key = "SEN " + title;
      if (title === "GroundTruth") {
        const n = it.named[0];
        const f = Object.fromEntries(n ? n.fields : it.head);
        this.pose = { location: vec(f.Location), rotation: vec(f.Orientation) };
      }
      this.trackReading(title, Number(head.Time), it);
      if (RANGE_TYPES.has(title) && !this.asked.has(title)) {
        this.asked.add(title);
        this.send(`GETGEO {Type ${title}}`);
        this.send(`GETCONF {Type ${title}}`);
      }
    } else if (type === "STA") {
      key = "STA";
      title = "Status";
      this.sta = Object.fromEntries(it.head);
      if (this.sta.Battery !== undefined) this.track.batteryLeft(Number(this.sta.Time), Number(this.sta.Battery));
      this.console.statusChanged(this);
    } else if (type === "MISSTA") {
      key = "MISSTA " + (it.named[0] ? it.named[0].name : "");
      title = "MisPkg " + (it.named[0] ? it.named[0].name : "");
    } else {
      key = "EFF " + (head.Type || "") + " " + (head.Name || "");
      title = "Effecter " + (head.Name || head.Type || "");
    }
    const prev = this.readings.get(key);
    const named = new Map(prev && type === "SEN" ? prev.named : []);
    for (const n of it.named) named.set(n.name, n.fields);
    this.readings.set(key, { title, time: head.Time || "", head: it.head, named, line });
    this.console.readingsChanged(this);
  }

  // what the plots take from a SEN line: a position, or the ranges of a range sensor
  trackReading(sensorType, t, it) {
    if (sensorType === "GroundTruth" || sensorType === "INS" || sensorType === "Odometry") {
      const n = it.named[0];
      const f = Object.fromEntries(n ? [...it.head, ...n.fields] : it.head);
      const p = vec(sensorType === "Odometry" ? f.Pose : f.Location);
      if (p.length >= 2) this.track.position(sensorType, t, sensorType === "Odometry" ? [p[0], p[1], 0] : p);
    } else if (RANGE_TYPES.has(sensorType)) {
      const values = [];
      for (const n of it.named) for (const [k, v] of n.fields) if (k === "Range") values.push(...vec(v));
      for (const [k, v] of it.head) if (k === "Range") values.push(...vec(v));
      if (values.length) this.track.ranges(SCANNER_TYPES.has(sensorType), t, values);
    }
  }

  keepDescription(type, line) {
    const it = items(line);
    const head = Object.fromEntries(it.head);
    const itemType = head.Type;
    if (!itemType) return;
    if (type === "GEO") {
      const out = (this.geo[itemType] = this.geo[itemType] || {});
      for (const n of it.named) {
        const f = Object.fromEntries(n.fields);
        out[n.name] = { location: vec(f.Location), orientation: vec(f.Orientation) };
      }
    } else {
      const out = (this.conf[itemType] = this.conf[itemType] || {});
      for (const n of it.named) out[n.name] = Object.fromEntries(n.fields);
    }
    this.console.readingsChanged(this);
  }

  latest(type) {
    const r = this.readings.get("SEN " + type);
    return r || null;
  }

  // wheels -------------------------------------------------------------------------
  setMotion(change) {
    Object.assign(this.motion, change);
    this.applyMotion();
  }

  stop() {
    this.motion = { v: 0, w: 0, a: 0 };
    this.applyMotion();
  }

  faster() {
    this.speed = Math.min(1, this.speed * 1.25);
    this.applyMotion();
  }

  slower() {
    this.speed = Math.max(0.05, this.speed / 1.25);
    this.applyMotion();
  }

  turnMore() {
    this.turn = Math.min(1, this.turn + 0.125);
    this.applyMotion();
  }

  turnLess() {
    this.turn = Math.max(0.0625, this.turn - 0.125);
    this.applyMotion();
  }

  straight() {
    this.motion.w = 0;
    this.applyMotion();
  }

  speedText() {
    const c = this.cls || {};
    const d = this.drive;
    const pct = Math.round(this.speed * 100) + " %";
    if (d === "skid" || d === "holonomic" || d === "ackermann") {
      const rad = this.speed * (c.max_speed || 5);
      return `${rad.toFixed(2)} rad/s (${pct})`;
    }
    return pct;
  }

  driveLine() {
    const { v, w, a } = this.motion;
    const c = this.cls || {};
    const r = (x) => Number(x.toFixed(4));
    switch (this.drive) {
      case "skid":
      case "holonomic": {
        const s = this.speed * (c.max_speed || 5);
        const k = v === 0 ? 1 : 0.5; // turning on the spot: opposite wheel speeds
        const left = r(s * (v + w * k));
        const right = r(s * (v - w * k));
        if (this.drive === "skid") return `DRIVE {Left ${left}} {Right ${right}}`;
        return `DRIVE {WheelNumber 0} {WheelSpeed ${left}} {WheelSteer 0} {WheelNumber 1} {WheelSpeed ${right}} {WheelSteer 0}`;
      }
      case "ackermann": {
        const s = this.speed * (c.max_speed || 5);
        const steer = this.turn * (c.max_front_steer || 0.5);
        return `DRIVE {Speed ${r(v * s)}} {FrontSteer ${r(w * steer)}}`;
      }
      case "aerial": {
        const ae = c.velocities || { linear: 2, vertical: 2, yaw_rate: 1.7 };
        return `DRIVE {AltitudeVelocity ${r(a * this.speed * ae.vertical)}} {LinearVelocity ${r(v * this.speed * ae.linear)}} ` +
          `{LateralVelocity 0} {RotationalVelocity ${r(w * this.speed * ae.yaw_rate)}}`;
      }
      case "legged":
        return `DRIVE {LinearVelocity ${r(v * this.speed * 0.25)}} {LateralVelocity 0} {RotationalVelocity ${r(w * this.speed)}}`;
      case "nautical":
        return `DRIVE {Propeller ${r(v * this.speed)}} {Rudder ${r(w * 0.35)}} {SternPlane ${r(a * 0.35)}}`;
      default:
        return null;
    }
  }

  applyMotion() {
    const line = this.driveLine();
    if (line) this.send(line);
    this.console.statusChanged(this);
  }

  // camera and light ---------------------------------------------------------------
  panTiltPackage() {
    const pkgs = (this.cls && this.cls.packages) || [];
    return pkgs.find((p) => p.name === "CameraPanTilt") || null;
  }

  // where a pan-tilt link is now (MISSTA), or where it was last sent when that was recent
  // (clicks in a row add up while the joint is still on its way)
  linkTarget(pkg, link) {
    const key = `${pkg.name}/${link}`;
    const sent = this.ptSent[key];
    if (sent && performance.now() - sent.at < 1500) return sent.value;
    const r = this.readings.get("MISSTA " + pkg.name);
    if (r) {
      let current = null;
      for (const [k, v] of r.head.concat(...[...r.named.values()])) {
        if (k === "Link") current = Number(v);
        else if (k === "Value" && current === link) return Number(v);
      }
    }
    return sent ? sent.value : 0;
  }

  panTilt(dPan, dTilt) {
    const pkg = this.panTiltPackage();
    if (pkg) {
      // MISPKG position orders: 10 degrees from where the link is
      for (const [link, d] of [[1, dPan], [2, dTilt]]) {
        if (!d || link > pkg.links.length) continue;
        const value = this.linkTarget(pkg, link) + d;
        this.ptSent[`${pkg.name}/${link}`] = { value, at: performance.now() };
        this.send(`MISPKG {Name ${pkg.name}} {Link ${link}} {Value ${value.toFixed(4)}} {Order 0}`);
      }
      return;
    }
    this.pan += dPan;
    this.tilt += dTilt;
    this.send(`CAMERA {Rotation 0,${this.tilt.toFixed(4)},${this.pan.toFixed(4)}}`);
  }

  panLeft() { this.panTilt(-DEG10, 0); }
  panRight() { this.panTilt(DEG10, 0); }
  tiltUp() { this.panTilt(0, DEG10); }
  tiltDown() { this.panTilt(0, -DEG10); }

  zoom(factor, camera) {
    const cams = (this.cls && this.cls.cameras) || ["Camera"];
    const cam = cams.includes(camera) ? camera : cams[0];
    if (!cam) return;
    const conf = (this.conf.Camera || {})[cam] || {};
    const current = this.fov || Number(conf.CameraFov) || 0.8727;
    const lo = Number(conf.CameraMinFov) || 0.05;
    const hi = Number(conf.CameraMaxFov) || 3.0;
    const next = Math.min(hi, Math.max(lo, current * factor));
    this.fov = next;
    this.send(`SET {Type Camera} {Name ${cam}} {Opcode Zoom} {Params ${next.toFixed(4)}}`);
  }

  get lightOn() {
    return this.sta.LightToggle === "True";
  }

  toggleLights() {
    this.send(`DRIVE {Light ${this.lightOn ? "False" : "True"}}`);
  }
}
