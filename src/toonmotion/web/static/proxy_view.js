// The 3D panel's views of a proxy (metres, +Y up, the ground Y = 0), drawn on 2D canvases: the
// orbit view (drag to turn round the figure, wheel to come nearer) and the view gizmo, whose
// camera is dragged round a small figure to set the artist's view (azimuth, elevation) and whose
// dial sets which way the world's up leans in the picture.

const GROUND_STEP = 0.5; // metres between the ground grid's lines
const GROUND_HALF = 6; // lines each side of the figure
const rad = (d) => (d * Math.PI) / 180;
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => { const n = Math.hypot(...a) || 1; return [a[0] / n, a[1] / n, a[2] / n]; };

// Where a camera at (azimuth, elevation) degrees looks from, as lift's view: 0,0 in front of a
// figure facing +Z, 90,0 on its left (+X).
export function viewDirection(azimuth, elevation) {
  const a = rad(azimuth), e = rad(elevation);
  return [Math.sin(a) * Math.cos(e), Math.sin(e), Math.cos(a) * Math.cos(e)];
}

// A pinhole looking from eye at target, +Y up: points -> canvas [x, y, depth] (depth <= 0: behind).
function looking(eye, target, focal, cx, cy) {
  const f = unit(sub(target, eye)), r = unit(cross(f, [0, 1, 0])), u = cross(r, f);
  return (p) => {
    const d = sub(p, eye), z = dot(d, f);
    return [cx + (focal * dot(d, r)) / z, cy - (focal * dot(d, u)) / z, z];
  };
}

export class ProxyView {
  /** @param {HTMLCanvasElement} canvas */
  constructor(canvas) {
    this.canvas = canvas;
    this.proxy = null;
    this.frame = 0;
    this.yaw = 35;
    this.pitch = 15;
    this.distance = 4;
    this.show = { points: true, volumes: true, skeleton: true, camera: true, ground: true };
    let from = null;
    canvas.addEventListener("pointerdown", (event) => { from = [event.clientX, event.clientY]; canvas.setPointerCapture(event.pointerId); });
    canvas.addEventListener("pointermove", (event) => {
      if (!from) return;
      this.yaw -= (event.clientX - from[0]) * 0.5;
      this.pitch = Math.max(-85, Math.min(85, this.pitch + (event.clientY - from[1]) * 0.5));
      from = [event.clientX, event.clientY];
      this.draw();
    });
    canvas.addEventListener("pointerup", () => { from = null; });
    canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      this.distance = Math.max(0.5, Math.min(60, this.distance * Math.exp(event.deltaY * 0.001)));
      this.draw();
    }, { passive: false });
  }

  setProxy(proxy) {
    this.proxy = proxy;
    if (proxy) { // framed on the figure: its height, from its middle
      const ys = proxy.points.flat().map((p) => p[1]);
      this.distance = Math.max(1.5, 2.6 * (Math.max(...ys) - Math.min(0, ...ys)));
    }
    this.draw();
  }

  setFrame(frame) {
    this.frame = frame;
    this.draw();
  }

  // The figure's middle at this frame, on the ground's level under it.
  target() {
    const P = this.proxy.points[this.frame];
    const mean = (k) => P.reduce((s, p) => s + p[k], 0) / P.length;
    return [mean(0), mean(1), mean(2)];
  }

  draw() {
    const canvas = this.canvas, ratio = window.devicePixelRatio || 1;
    const box = canvas.getBoundingClientRect();
    canvas.width = Math.max(1, Math.round(box.width * ratio));
    canvas.height = Math.max(1, Math.round(box.height * ratio));
    const pen = canvas.getContext("2d");
    pen.fillStyle = "#fbfbf8";
    pen.fillRect(0, 0, canvas.width, canvas.height);
    if (!this.proxy) {
      pen.fillStyle = "#888";
      pen.font = `${13 * ratio}px system-ui, sans-serif`;
      pen.fillText("lift the animation to see it in 3D", 12 * ratio, 24 * ratio);
      return;
    }
    const proxy = this.proxy, t = Math.min(this.frame, proxy.points.length - 1), target = this.target();
    const eye = target.map((v, k) => v + this.distance * viewDirection(this.yaw, this.pitch)[k]);
    const see = looking(eye, target, 1.2 * Math.min(canvas.width, canvas.height), canvas.width / 2, canvas.height / 2);
    const line = (a, b, colour, width) => {
      const [p, q] = [see(a), see(b)];
      if (p[2] <= 0.01 || q[2] <= 0.01) return;
      pen.strokeStyle = colour;
      pen.lineWidth = width;
      pen.beginPath();
      pen.moveTo(p[0], p[1]);
      pen.lineTo(q[0], q[1]);
      pen.stroke();
    };
    if (this.show.ground) {
      const [gx, , gz] = target.map((v) => Math.round(v / GROUND_STEP) * GROUND_STEP), reach = GROUND_HALF * GROUND_STEP;
      for (let i = -GROUND_HALF; i <= GROUND_HALF; i++) {
        const colour = i === 0 ? "#b8b8b0" : "#e0e0d8";
        line([gx + i * GROUND_STEP, 0, gz - reach], [gx + i * GROUND_STEP, 0, gz + reach], colour, ratio);
        line([gx - reach, 0, gz + i * GROUND_STEP], [gx + reach, 0, gz + i * GROUND_STEP], colour, ratio);
      }
    }
    // Volumes and bones far to near, so the nearer cover the farther.
    const items = [];
    if (this.show.volumes && proxy.radii) {
      proxy.limbs.forEach(([a, b], k) => {
        const A = proxy.points[t][a], B = proxy.points[t][b], [ra, rb] = proxy.radii[t][k];
        items.push({ depth: (see(A)[2] + see(B)[2]) / 2, draw: () => this.capsule(pen, see, A, B, ra, rb) });
      });
    }
    items.sort((x, y) => y.depth - x.depth).forEach((item) => item.draw());
    if (this.show.skeleton) {
      proxy.limbs.forEach(([a, b]) => line(proxy.skeleton[t][a], proxy.skeleton[t][b], "#2b6cb0", 2.5 * ratio));
    }
    if (this.show.points) {
      pen.fillStyle = "#dd6b20";
      for (const p of proxy.points[t]) {
        const [x, y, z] = see(p);
        if (z <= 0.01) continue;
        pen.beginPath();
        pen.arc(x, y, 3.5 * ratio, 0, 2 * Math.PI);
        pen.fill();
      }
    }
    if (this.show.camera) this.artistCamera(line, t, ratio);
  }

  // A limb's volume: a tapered cylinder seen from the side, its ends' discs as circles.
  capsule(pen, see, A, B, ra, rb) {
    const [p, q] = [see(A), see(B)];
    if (p[2] <= 0.01 || q[2] <= 0.01) return;
    const F = 1.2 * Math.min(this.canvas.width, this.canvas.height);
    const wa = (F * ra) / p[2], wb = (F * rb) / q[2];
    const along = [q[0] - p[0], q[1] - p[1]], n = Math.hypot(...along) || 1, side = [-along[1] / n, along[0] / n];
    pen.fillStyle = "rgba(56, 161, 105, 0.35)";
    pen.strokeStyle = "rgba(39, 103, 73, 0.8)";
    pen.lineWidth = 1;
    pen.beginPath();
    pen.moveTo(p[0] + side[0] * wa, p[1] + side[1] * wa);
    pen.lineTo(q[0] + side[0] * wb, q[1] + side[1] * wb);
    pen.arc(q[0], q[1], wb, Math.atan2(side[1], side[0]), Math.atan2(-side[1], -side[0]), true);
    pen.lineTo(p[0] - side[0] * wa, p[1] - side[1] * wa);
    pen.arc(p[0], p[1], wa, Math.atan2(-side[1], -side[0]), Math.atan2(side[1], side[0]), true);
    pen.closePath();
    pen.fill();
    pen.stroke();
  }

  // The artist's camera at this frame: its centre and the edges of what it sees, 0.4 m out.
  artistCamera(line, t, ratio) {
    const camera = this.proxy.camera, c = camera.centres[t], [right, down, forward] = camera.axes[t];
    const w = camera.width / (2 * camera.focal), h = camera.height / (2 * camera.focal), reach = 0.4;
    const corner = (sx, sy) => c.map((v, k) => v + reach * (forward[k] + sx * w * right[k] + sy * h * down[k]));
    const corners = [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)];
    corners.forEach((p, i) => {
      line(c, p, "#805ad5", 1.5 * ratio);
      line(p, corners[(i + 1) % 4], "#805ad5", 1.5 * ratio);
    });
    line(corners[0], corners[1], "#553c9a", 3 * ratio); // the picture's top edge
  }
}

// The view gizmo: a small figure facing +Z on a ground disc, seen from above at an angle, and a
// camera round it at (azimuth, elevation); dragging moves the camera. Below it, a dial whose hand
// is the world's up in the picture (degrees clockwise), dragged round. onChange(view) is called
// with {azimuth, elevation, up} as they change.
export class ViewGizmo {
  /** @param {HTMLCanvasElement} canvas */
  constructor(canvas, view, onChange) {
    this.canvas = canvas;
    this.view = { ...view };
    this.onChange = onChange;
    let dragging = null;
    const dial = () => { const s = this.size(); return { x: s.w / 2, y: s.h - s.dial - 4 * s.ratio, r: s.dial }; };
    canvas.addEventListener("pointerdown", (event) => {
      const [x, y] = this.at(event), d = dial();
      dragging = Math.hypot(x - d.x, y - d.y) <= d.r * 1.3 ? "up" : "view";
      this.from = [event.clientX, event.clientY];
      canvas.setPointerCapture(event.pointerId);
      if (dragging === "up") this.turnUp(x, y);
    });
    canvas.addEventListener("pointermove", (event) => {
      if (!dragging) return;
      if (dragging === "up") this.turnUp(...this.at(event));
      else {
        this.view.azimuth = ((this.view.azimuth - (event.clientX - this.from[0]) + 540) % 360) - 180;
        this.view.elevation = Math.max(-80, Math.min(80, this.view.elevation + (event.clientY - this.from[1]) * 0.7));
        this.from = [event.clientX, event.clientY];
      }
      this.view.azimuth = Math.round(this.view.azimuth);
      this.view.elevation = Math.round(this.view.elevation);
      this.draw();
      this.onChange({ ...this.view });
    });
    canvas.addEventListener("pointerup", () => { dragging = null; });
    this.draw();
  }

  size() {
    const ratio = window.devicePixelRatio || 1, box = this.canvas.getBoundingClientRect();
    return { ratio, w: box.width * ratio, h: box.height * ratio, dial: 18 * ratio };
  }

  at(event) {
    const box = this.canvas.getBoundingClientRect(), ratio = window.devicePixelRatio || 1;
    return [(event.clientX - box.left) * ratio, (event.clientY - box.top) * ratio];
  }

  turnUp(x, y) {
    const s = this.size(), cx = s.w / 2, cy = s.h - s.dial - 4 * s.ratio;
    this.view.up = Math.round((Math.atan2(x - cx, cy - y) * 180) / Math.PI);
  }

  set(view) {
    this.view = { ...this.view, ...view };
    this.draw();
  }

  draw() {
    const s = this.size(), pen = this.canvas.getContext("2d");
    this.canvas.width = Math.max(1, Math.round(s.w));
    this.canvas.height = Math.max(1, Math.round(s.h));
    pen.fillStyle = "#f8f8f5";
    pen.fillRect(0, 0, s.w, s.h);
    const top = s.h - 2 * s.dial - 8 * s.ratio; // the 3D part's height
    const see = looking(viewDirection(30, 35).map((v) => 4.2 * v), [0, 0.55, 0], 0.9 * Math.min(s.w, top), s.w / 2, top / 2);
    const line = (a, b, colour, width) => {
      const [p, q] = [see(a), see(b)];
      pen.strokeStyle = colour;
      pen.lineWidth = width * s.ratio;
      pen.beginPath();
      pen.moveTo(p[0], p[1]);
      pen.lineTo(q[0], q[1]);
      pen.stroke();
    };
    for (let i = 0; i < 48; i++) { // the ground disc
      const a = (i / 48) * 2 * Math.PI, b = ((i + 1) / 48) * 2 * Math.PI;
      line([Math.cos(a), 0, Math.sin(a)], [Math.cos(b), 0, Math.sin(b)], "#a0a098", 1);
    }
    line([0, 0, 0], [0, 1.1, 0], "#444", 2.5); // the figure, facing +Z (its nose)
    line([-0.25, 0.8, 0], [0.25, 0.8, 0], "#444", 2.5);
    line([0, 1.0, 0], [0, 1.0, 0.3], "#dd6b20", 2.5);
    const d = viewDirection(this.view.azimuth, this.view.elevation), c = d.map((v, k) => 1.7 * v + (k === 1 ? 0.55 : 0));
    line(c, [0, 0.55, 0], "#805ad5", 1);
    const [x, y] = see(c);
    pen.fillStyle = "#805ad5";
    pen.fillRect(x - 6 * s.ratio, y - 4 * s.ratio, 12 * s.ratio, 8 * s.ratio);
    pen.fillStyle = "#333";
    pen.font = `${11 * s.ratio}px system-ui, sans-serif`;
    pen.fillText(`view ${this.view.azimuth}°, ${this.view.elevation}°`, 4 * s.ratio, 12 * s.ratio);
    const cx = s.w / 2, cy = s.h - s.dial - 4 * s.ratio; // the up dial
    pen.strokeStyle = "#999";
    pen.lineWidth = s.ratio;
    pen.beginPath();
    pen.arc(cx, cy, s.dial, 0, 2 * Math.PI);
    pen.stroke();
    const u = rad(this.view.up);
    pen.strokeStyle = "#2b6cb0";
    pen.lineWidth = 2.5 * s.ratio;
    pen.beginPath();
    pen.moveTo(cx, cy);
    pen.lineTo(cx + Math.sin(u) * s.dial, cy - Math.cos(u) * s.dial);
    pen.stroke();
    pen.fillText(`up ${this.view.up}°`, cx + s.dial + 6 * s.ratio, cy + 4 * s.ratio);
  }
}
