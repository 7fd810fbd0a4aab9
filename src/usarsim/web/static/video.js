// The video of a robot camera, from the simulator's image server through the console's
// bridge (/ws/video): the page asks for a picture with "OK" (as a UPIS client does), the
// bridge forwards each JPEG picture as a binary message, and the page asks for the next
// one when it has drawn it, no more often than the chosen frame rate.

const STALL_MS = 4000; // no picture for this long after asking: ask again

export class Video {
  constructor(canvas, { overlay, fps, width, height }) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.overlay = overlay;
    this.els = { fps, width, height };
    this.maxFps = 10;
    this.target = null; // { robot, camera }
    this.bound = null;
    this.ws = null;
    this.waiting = false;
    this.askedAt = 0;
    this.timer = null;
    this.times = [];
    this.frames = 0;
    this.pageId = "";
    setInterval(() => this.tick(), 500);
    document.addEventListener("visibilitychange", () => this.askSoon());
  }

  open() {
    if (this.ws && this.ws.readyState <= WebSocket.OPEN) return;
    const proto = location.protocol === "https:" ? "wss" : "ws";
    const ws = new WebSocket(`${proto}://${location.host}/ws/video?page=${this.pageId}`);
    ws.binaryType = "arraybuffer";
    ws.onopen = () => this.sendBind();
    ws.onmessage = (ev) => {
      if (typeof ev.data === "string") this.control(JSON.parse(ev.data));
      else this.picture(ev.data);
    };
    ws.onclose = () => {
      this.ws = null;
      this.bound = null;
      this.waiting = false;
      if (this.target) setTimeout(() => this.target && this.open(), 1000);
    };
    this.ws = ws;
  }

  attach(robot, camera) {
    this.target = { robot, camera };
    this.frames = 0;
    this.message(`Connecting to ${camera} of ${robot}…`);
    if (this.ws && this.ws.readyState === WebSocket.OPEN) this.sendBind();
    else this.open();
  }

  detach() {
    this.target = null;
    this.bound = null;
    if (this.ws && this.ws.readyState === WebSocket.OPEN) this.ws.send(JSON.stringify({ bind: null }));
    this.message("Spawn a robot or click one in the world view to see its camera.");
    this.ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    this.times = [];
    this.els.fps.textContent = "0.0";
  }

  sendBind() {
    if (!this.target || !this.ws || this.ws.readyState !== WebSocket.OPEN) return;
    this.bound = null;
    this.ws.send(JSON.stringify({ bind: this.target.robot, camera: this.target.camera }));
  }

  control(msg) {
    if (msg.error) {
      this.message(msg.error);
      return;
    }
    if (msg.bound === undefined) return;
    if (!this.target || msg.bound !== this.target.robot || msg.camera !== this.target.camera) return;
    this.bound = msg;
    this.waiting = false;
    this.ask();
  }

  message(text) {
    this.overlay.textContent = text;
    this.overlay.hidden = !text;
  }

  ask() {
    if (!this.bound || this.waiting || document.hidden || !this.ws || this.ws.readyState !== WebSocket.OPEN) return;
    this.waiting = true;
    this.askedAt = performance.now();
    this.ws.send("OK");
  }

  askSoon() {
    if (this.timer) return;
    const last = this.times[this.times.length - 1] || 0;
    const wait = Math.max(0, 1000 / this.maxFps - (performance.now() - last));
    this.timer = setTimeout(() => {
      this.timer = null;
      this.ask();
    }, wait);
  }

  async picture(data) {
    this.waiting = false;
    try {
      const bitmap = await createImageBitmap(new Blob([data], { type: "image/jpeg" }));
      if (!this.target) return;
      if (this.canvas.width !== bitmap.width || this.canvas.height !== bitmap.height) {
        this.canvas.width = bitmap.width;
        this.canvas.height = bitmap.height;
      }
      this.ctx.drawImage(bitmap, 0, 0);
      bitmap.close();
      this.frames += 1;
      this.times.push(performance.now());
      this.els.width.textContent = this.canvas.width;
      this.els.height.textContent = this.canvas.height;
      if (this.frames === 1) this.message("");
    } catch (exc) {
      this.message(`A picture could not be decoded: ${exc}`);
    }
    this.askSoon();
  }

  tick() {
    const now = performance.now();
    while (this.times.length && now - this.times[0] > 2000) this.times.shift();
    const n = this.times.length;
    const fps = n > 1 ? (n - 1) * 1000 / Math.max(1, this.times[n - 1] - this.times[0]) : 0;
    this.els.fps.textContent = (n > 1 && now - this.times[n - 1] < 2000 ? fps : 0).toFixed(1);
    if (this.waiting && now - this.askedAt > STALL_MS) {
      this.waiting = false;
      this.ask();
    }
  }
}
