// The Exaggerate panel (thesis 5.2, fig. 6.2c-d). For one pose: click joints to fix them (blue;
// feet on the ground), then drag from the root to draw the acceleration arrow; the pose is
// squashed or stretched along it live (the single-frame cartoon filter), bones on the way from
// the root to a fixed joint in blue, the others green. "Use this pose" hands the result to the
// Pose and Timeline panels. For the animation: the filter's strength and width, and a preview
// that plays the key-frames with and without it.

import { element, listen, nearest, newest } from "./panel_kit.js";

export const name = "exaggerate";
export const title = "Exaggerate";

const HANDLE = 7;

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const joints = project.joints;
  const base = (ctx.pose || joints.map((j) => j.position)).map((p) => p.slice());
  const root = joints.findIndex((j) => j.parent < 0);
  let shown = base.map((p) => p.slice()), fixed = new Set(), arrow = null, dragging = false;
  let playing = false, timer = null;

  side.innerHTML = `<h2>Exaggerate</h2>
    <p>Click joints to fix them (blue), then drag from the root to draw the acceleration the pose
    anticipates (thesis eq. 5.5): the figure moves against it, so an arrow up squashes it (the
    crouch before a jump) and an arrow down lifts and stretches it.</p>
    <p><button id="exaggerate-use">Use this pose</button> <button id="exaggerate-clear">Clear</button></p>
    <h3>The animation</h3>
    <p><label>Strength <input id="exaggerate-strength" type="number" value="1.5" step="0.1" min="0"
      style="width: 5em"></label> <label>Width <input id="exaggerate-sigma" type="number" value="3"
      step="0.5" min="0.5" style="width: 4em"></label> frames</p>
    <p><label><input id="exaggerate-on" type="checkbox" checked> exaggerated</label>
      <button id="exaggerate-play">Preview</button></p>`;

  // Joints on the way from the root to a fixed joint: their bones turn blue.
  function onChains() {
    const marked = new Set();
    for (const f of fixed) for (let j = f; j >= 0 && j !== root; j = joints[j].parent) marked.add(j);
    return marked;
  }

  view.drawOverlay = (pen) => {
    const ratio = window.devicePixelRatio || 1, chains = onChains();
    pen.lineWidth = 3 * ratio;
    joints.forEach((joint, i) => {
      if (joint.parent < 0) return;
      pen.beginPath();
      pen.moveTo(...view.toCanvas(shown[joint.parent]));
      pen.lineTo(...view.toCanvas(shown[i]));
      pen.strokeStyle = chains.has(i) ? "#2b6cb0" : "#2f855a";
      pen.stroke();
    });
    shown.forEach((p, i) => {
      pen.beginPath();
      pen.arc(...view.toCanvas(p), HANDLE * ratio, 0, 2 * Math.PI);
      pen.fillStyle = fixed.has(i) ? "#2b6cb0" : i === root ? "#f6ad55" : "#fff";
      pen.fill();
      pen.strokeStyle = "#222";
      pen.lineWidth = ratio;
      pen.stroke();
    });
    if (arrow) {
      const [x0, y0] = view.toCanvas(base[root]), [x1, y1] = view.toCanvas([base[root][0] + arrow[0], base[root][1] + arrow[1]]);
      pen.beginPath();
      pen.moveTo(x0, y0);
      pen.lineTo(x1, y1);
      const a = Math.atan2(y1 - y0, x1 - x0), h = 12 * ratio;
      pen.lineTo(x1 - h * Math.cos(a - 0.4), y1 - h * Math.sin(a - 0.4));
      pen.moveTo(x1, y1);
      pen.lineTo(x1 - h * Math.cos(a + 0.4), y1 - h * Math.sin(a + 0.4));
      pen.strokeStyle = "#c53030";
      pen.lineWidth = 3 * ratio;
      pen.stroke();
    }
  };

  const send = newest(live, (reply) => {
    view.showDeformed(reply.U);
    shown = reply.positions || base.map((p) => p.slice());
    view.draw();
    showError("");
  }, (error) => showError(error.message));

  function exaggerate() {
    send(arrow && fixed.size
      ? { type: "pose", positions: base, accel: arrow, fixed: [...fixed].map((i) => joints[i].name) }
      : { type: "pose", positions: base });
  }

  const overlay = view.overlay;
  const down = (event) => {
    // The root first: a hip often sits on it.
    const hit = nearest(view, [shown[root]], event, HANDLE + 4) === 0 ? root : nearest(view, shown, event, HANDLE + 4);
    if (hit === root) {
      dragging = true;
      overlay.setPointerCapture(event.pointerId);
    } else if (hit >= 0) {
      fixed.has(hit) ? fixed.delete(hit) : fixed.add(hit);
      exaggerate();
      view.draw();
    }
  };
  const move = (event) => {
    if (!dragging) return;
    const [x, y] = view.toDrawing(event);
    arrow = [x - base[root][0], y - base[root][1]];
    if (!fixed.size) showError("fix at least one joint first (click a foot)");
    exaggerate();
  };
  const up = () => { dragging = false; };
  const unlisten = listen(overlay, { pointerdown: down, pointermove: move, pointerup: up });

  element("exaggerate-use", HTMLButtonElement).onclick = () => {
    ctx.pose = shown.map((p) => p.slice());
    status("the exaggerated pose is now the Pose panel's");
  };
  element("exaggerate-clear", HTMLButtonElement).onclick = () => {
    arrow = null;
    fixed = new Set();
    exaggerate();
  };

  async function preview() {
    if (playing) return stop();
    if (!project.keys) return showError("key some poses in the Timeline panel first");
    playing = true;
    element("exaggerate-play", HTMLButtonElement).textContent = "Stop";
    const keys = project.keys.keys, first = keys[0].frame, last = keys[keys.length - 1].frame;
    let at = first;
    const next = async () => {
      if (!playing) return;
      const started = performance.now();
      const on = element("exaggerate-on", HTMLInputElement).checked;
      const message = { type: "frame", frame: at };
      if (on) Object.assign(message, settings());
      try {
        const reply = await live.request(message);
        view.showDeformed(reply.U);
        shown = reply.positions;
        view.draw();
        showError("");
      } catch (error) {
        showError(error.message);
        return stop();
      }
      at = at >= last ? first : at + 1;
      timer = setTimeout(next, Math.max(0, 1000 / project.keys.fps - (performance.now() - started)));
    };
    next();
  }

  // The animation's filter settings, also what the Export panel uses for an exaggerated export.
  function settings() {
    ctx.exaggeration = { strength: Number(element("exaggerate-strength", HTMLInputElement).value),
                         sigma: Number(element("exaggerate-sigma", HTMLInputElement).value) };
    return ctx.exaggeration;
  }
  element("exaggerate-strength", HTMLInputElement).onchange = settings;
  element("exaggerate-sigma", HTMLInputElement).onchange = settings;

  function stop() {
    playing = false;
    clearTimeout(timer);
    element("exaggerate-play", HTMLButtonElement).textContent = "Preview";
  }
  element("exaggerate-play", HTMLButtonElement).onclick = preview;
  exaggerate();
  status("fix joints, then drag from the root");

  return {
    unmount() {
      stop();
      unlisten();
      view.drawOverlay = () => {};
    },
  };
}
