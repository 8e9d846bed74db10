// The Key-shapes panel (Bregler et al. 2002, docs/keyshapes.md): key outlines from a file (a
// contours JSON or CSV, or SVG), drawn on the stage, or picked on footage by a click on the layer;
// the key-shape model built from them with its sheet of in-betweens; capture from a contours file
// or from footage (off the server's event loop, with a progress bar), the captured outline over
// each frame, the key weights plotted over time and the affine path drawn; then the motion
// retargeted onto the character's key poses, chosen among the Timeline's keys, and played in the
// Timeline. Everything is kept in the project folder's keyshapes/, in the CLI's files, and shown
// again on mount (the "keyshapes" message).

import { element, listen } from "./panel_kit.js";

export const name = "keyshapes";
export const title = "Key-shapes";

const COLOURS = ["#2b6cb0", "#dd6b20", "#38a169", "#805ad5", "#d53f8c", "#319795", "#b7791f", "#e53e3e"];

export function mount(ctx) {
  const { project, view, live, side, status, showError, token } = ctx;
  /** @type {{points: number[][], frame: number | null}[]} the key outlines, as given */
  let outlines = [];
  /** @type {any} the server's "keyshapes" state */
  let state = null;
  let frame = 0, drawing = null, mode = "", job = null;
  const images = [];

  side.innerHTML = `<h2>Key-shapes</h2>
    <h3>1. Key outlines</h3>
    <p><label>Outlines file <input id="ks-outlines-file" type="file" accept=".json,.csv,.svg"></label></p>
    <p><button id="ks-draw" aria-pressed="false" title="Press and drag round the shape on the stage: a closed curve">Draw an outline</button>
      <button id="ks-pick" aria-pressed="false" title="Click the layer in the footage frame shown: its colour region's outline">Pick on the footage</button></p>
    <p><label>Resample each to <input id="ks-points" type="number" min="3" max="10000" value="96" style="width: 5em"> points</label>
      <label><input id="ks-resample" type="checkbox" checked> resample</label></p>
    <ol id="ks-keys"></ol>
    <p><button id="ks-build" disabled>Build the model</button> <span id="ks-model-info"></span></p>
    <p><img id="ks-sheet" alt="the keys and their in-betweens" hidden style="max-width: 100%; border: 1px solid #ccc"></p>
    <h3>2. Capture</h3>
    <p><label>Contours to capture <input id="ks-contours-file" type="file" accept=".json,.csv,.svg"></label></p>
    <p><label>or footage <input id="ks-footage-file" type="file" accept="video/*,.gif,.png,.apng,.webp"></label></p>
    <p id="ks-inputs"></p>
    <p><button id="ks-capture-contours" disabled>Capture the contours</button>
      <button id="ks-capture-video" disabled>Capture the footage</button></p>
    <p><progress id="ks-progress" max="1" value="0" hidden></progress> <button id="ks-cancel" hidden>Cancel</button></p>
    <p><input id="ks-scrub" type="range" min="0" max="0" value="0" style="width: 100%" aria-label="frame">
      frame <output id="ks-frame">0</output></p>
    <canvas id="ks-weights" width="600" height="220" style="width: 100%; height: 110px" aria-label="each key's weight over time"></canvas>
    <p id="ks-legend"></p>
    <h3>3. Retarget</h3>
    <p id="ks-poses"></p>
    <p><label><input id="ks-pin" type="checkbox"> Pin</label> <select id="ks-pin-joint" aria-label="joint to pin"></select>
      at <input id="ks-pin-x" type="number" style="width: 4.5em" aria-label="x"> <input id="ks-pin-y" type="number" style="width: 4.5em" aria-label="y"></p>
    <p><button id="ks-retarget" disabled>Retarget and play in the Timeline</button></p>
    <p id="ks-retargeted"></p>`;

  const info = (id, text) => { document.getElementById(id).textContent = text; };

  // The stage shows the footage's pixels (or the drawing's, without footage), fitted.
  function space() {
    if (state && state.footage) return { width: state.footage.width, height: state.footage.height };
    let x1 = project.width, y1 = project.height;
    const shapes = [...outlines.map((o) => o.points), ...(state && state.contours ? state.contours.shapes : [])];
    for (const shape of shapes) for (const [x, y] of shape) { x1 = Math.max(x1, x + 10); y1 = Math.max(y1, y + 10); }
    return { width: x1, height: y1 };
  }
  function fit() {
    const o = view.overlay, s = space(), scale = Math.min(o.width / s.width, o.height / s.height) * 0.95;
    return { scale, x: (o.width - s.width * scale) / 2, y: (o.height - s.height * scale) / 2 };
  }
  const toCanvas = ([x, y]) => { const f = fit(); return [f.x + x * f.scale, f.y + y * f.scale]; };
  const fromEvent = (event) => {
    const box = view.overlay.getBoundingClientRect(), ratio = view.overlay.width / box.width, f = fit();
    return [((event.clientX - box.left) * ratio - f.x) / f.scale, ((event.clientY - box.top) * ratio - f.y) / f.scale];
  };

  function curve(pen, points, colour, width, closed = true, dash = []) {
    if (!points || points.length < 2) return;
    const ratio = window.devicePixelRatio || 1;
    pen.strokeStyle = colour;
    pen.lineWidth = width * ratio;
    pen.setLineDash(dash.map((d) => d * ratio));
    pen.beginPath();
    points.forEach((p, i) => (i ? pen.lineTo(...toCanvas(p)) : pen.moveTo(...toCanvas(p))));
    if (closed) pen.closePath();
    pen.stroke();
    pen.setLineDash([]);
  }

  view.drawOverlay = (pen) => {
    const f = fit(), s = space(), capture = !mode && state && state.capture;
    pen.fillStyle = "#fff";
    pen.fillRect(f.x, f.y, s.width * f.scale, s.height * f.scale);
    const image = images[frame];
    if (state && state.footage && image && image.complete) {
      pen.drawImage(image, f.x, f.y, s.width * f.scale, s.height * f.scale);
    }
    if (capture) {
      const at = Math.min(frame, capture.shapes.length - 1);
      if (state.contours && capture.source === "contours") curve(pen, state.contours.shapes[at], "#999", 1.5, true, [4, 3]);
      curve(pen, capture.path, "rgba(128, 90, 213, 0.8)", 1.5, false);
      const [px, py] = toCanvas(capture.path[at]), A = capture.affine[at], arm = 30 / fit().scale;
      for (const column of [0, 1]) { // the affine's axes at this frame: its turn, scale and shear
        const tip = [capture.path[at][0] + arm * A[0][column], capture.path[at][1] + arm * A[1][column]];
        curve(pen, [capture.path[at], tip], column ? "#38a169" : "#dd6b20", 2, false);
      }
      pen.fillStyle = "#805ad5";
      pen.beginPath();
      pen.arc(px, py, 4 * (window.devicePixelRatio || 1), 0, 2 * Math.PI);
      pen.fill();
      curve(pen, capture.shapes[at], "#e53e3e", 2.5);
    } else {
      outlines.forEach((o, i) => {
        if (o.frame === null || !state || !state.footage || o.frame === frame) curve(pen, o.points, COLOURS[i % COLOURS.length], 2);
      });
    }
    if (drawing) curve(pen, drawing, "#e53e3e", 2, false);
  };

  function frames() {
    if (state && state.capture) return state.capture.shapes.length;
    if (state && state.footage) return state.footage.frames;
    return 1;
  }
  function show(at) {
    frame = Math.max(0, Math.min(at, frames() - 1));
    element("ks-scrub", HTMLInputElement).max = String(frames() - 1);
    element("ks-scrub", HTMLInputElement).value = String(frame);
    element("ks-frame", HTMLOutputElement).textContent = String(frame);
    if (state && state.footage && !images[frame]) {
      images[frame] = new Image();
      images[frame].onload = () => view.draw();
      images[frame].src = `api/footage/${frame}.png?token=${encodeURIComponent(token)}`;
    }
    plotWeights();
    view.draw();
  }

  // Each key's weight over the frames, the current frame marked.
  function plotWeights() {
    const canvas = element("ks-weights", HTMLCanvasElement), pen = canvas.getContext("2d");
    const capture = state && state.capture, W = canvas.width, H = canvas.height, pad = 16;
    pen.clearRect(0, 0, W, H);
    canvas.hidden = !capture;
    if (!capture) return;
    const weights = capture.weights, T = weights.length;
    const low = Math.min(0, ...weights.flat()), high = Math.max(1, ...weights.flat());
    const x = (t) => pad + (t / Math.max(T - 1, 1)) * (W - 2 * pad), y = (w) => H - pad - ((w - low) / (high - low)) * (H - 2 * pad);
    pen.strokeStyle = "#ccc";
    pen.lineWidth = 1;
    for (const w of [0, 1]) { pen.beginPath(); pen.moveTo(pad, y(w)); pen.lineTo(W - pad, y(w)); pen.stroke(); }
    pen.fillStyle = "#555";
    pen.font = "18px system-ui, sans-serif";
    pen.fillText("1", 0, y(1) + 6);
    pen.fillText("0", 0, y(0) + 6);
    weights[0].forEach((_, k) => {
      pen.strokeStyle = COLOURS[k % COLOURS.length];
      pen.lineWidth = 3;
      pen.beginPath();
      weights.forEach((w, t) => (t ? pen.lineTo(x(t), y(w[k])) : pen.moveTo(x(t), y(w[k]))));
      pen.stroke();
    });
    pen.strokeStyle = "#c53030";
    pen.lineWidth = 2;
    pen.beginPath();
    pen.moveTo(x(frame), 0);
    pen.lineTo(x(frame), H);
    pen.stroke();
    const legend = document.getElementById("ks-legend");
    legend.replaceChildren();
    weights[0].forEach((_, k) => {
      const item = document.createElement("span");
      item.style.color = COLOURS[k % COLOURS.length];
      item.textContent = `■ key ${k + 1}: ${weights[frame][k].toFixed(2)} `;
      legend.append(item);
    });
    const error = capture.error[frame];
    legend.append(`· fit ${error.toFixed(2)} px rms (${capture.source})`);
  }

  function thumbnail(points, colour) {
    const canvas = document.createElement("canvas");
    canvas.width = canvas.height = 48;
    const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
    const [x0, y0] = [Math.min(...xs), Math.min(...ys)], side = Math.max(Math.max(...xs) - x0, Math.max(...ys) - y0, 1);
    const pen = canvas.getContext("2d");
    pen.strokeStyle = colour;
    pen.lineWidth = 2;
    pen.beginPath();
    points.forEach(([x, y], i) => {
      const at = [4 + ((x - x0) / side) * 40, 4 + ((y - y0) / side) * 40];
      if (i) pen.lineTo(at[0], at[1]); else pen.moveTo(at[0], at[1]);
    });
    pen.closePath();
    pen.stroke();
    return canvas;
  }

  function showKeys() {
    const list = document.getElementById("ks-keys");
    list.replaceChildren();
    outlines.forEach((o, i) => {
      const item = document.createElement("li");
      item.append(thumbnail(o.points, COLOURS[i % COLOURS.length]), ` ${o.points.length} points `);
      const at = document.createElement("input");
      Object.assign(at, { type: "number", min: "0", value: o.frame === null ? "" : String(o.frame), placeholder: "frame" });
      at.style.width = "4em";
      at.setAttribute("aria-label", `the footage frame key ${i + 1} is drawn on`);
      at.onchange = () => { o.frame = at.value === "" ? null : Number(at.value); };
      const remove = document.createElement("button");
      remove.textContent = "Remove";
      remove.className = "remove";
      remove.onclick = () => { outlines.splice(i, 1); showKeys(); };
      item.append("on frame ", at, " ", remove);
      list.append(item);
    });
    element("ks-build", HTMLButtonElement).disabled = outlines.length === 0;
    view.draw();
  }

  function showState(reply) {
    state = reply;
    if (reply.outlines.length) {
      outlines = reply.outlines.map((points, i) => ({ points, frame: reply.key_frames ? reply.key_frames[i] : null }));
    }
    if (reply.points) element("ks-points", HTMLInputElement).value = String(reply.points);
    element("ks-resample", HTMLInputElement).checked = reply.points !== null || !reply.model;
    const sheet = element("ks-sheet", HTMLImageElement);
    sheet.hidden = !reply.model;
    if (reply.model) sheet.src = `${reply.model.sheet}&token=${encodeURIComponent(token)}`;
    info("ks-model-info", reply.model ? `${reply.model.keys.length} keys of ${reply.model.keys[0].length} points, `
      + `${reply.model.eigen} eigen-shapes, every example within ${reply.model.error} px` : "");
    const inputs = [];
    if (reply.contours) inputs.push(`contours: ${reply.contours.frames} frames of ${reply.contours.points} points`);
    if (reply.footage) inputs.push(`footage: ${reply.footage.frames} frames of ${reply.footage.width}×${reply.footage.height}`);
    info("ks-inputs", inputs.join("; "));
    element("ks-capture-contours", HTMLButtonElement).disabled = !(reply.model && reply.contours);
    element("ks-capture-video", HTMLButtonElement).disabled = !(reply.model && reply.footage);
    element("ks-pick", HTMLButtonElement).disabled = !reply.footage;
    showKeys();
    showPoses();
    const done = reply.retargeted;
    info("ks-retargeted", done ? `retargeted: frames ${done.first} to ${done.last} at ${done.fps} fps, saved in ${done.file}` : "");
    show(frame);
  }

  // One of the Timeline's keys per key-shape, in order: the character's pose for it.
  function showPoses() {
    const line = document.getElementById("ks-poses"), count = state && state.model ? state.model.keys.length : 0;
    const keys = project.keys ? project.keys.keys.map((k) => k.frame) : [];
    line.replaceChildren();
    const chosen = state && state.retargeted && state.retargeted.keys ? state.retargeted.keys : keys;
    if (!count) line.append("Build the model and capture first.");
    else if (keys.length === 0) line.append("Key the character's poses in the Timeline first: one per key-shape.");
    for (let k = 0; k < count && keys.length; k++) {
      const pick = document.createElement("select");
      pick.className = "ks-pose";
      pick.setAttribute("aria-label", `the Timeline key for key-shape ${k + 1}`);
      for (const f of keys) pick.append(new Option(`key at frame ${f}`, String(f)));
      pick.value = String(chosen[Math.min(k, chosen.length - 1)]);
      const label = document.createElement("span");
      label.style.color = COLOURS[k % COLOURS.length];
      label.textContent = `key-shape ${k + 1} → `;
      line.append(label, pick, document.createElement("br"));
    }
    element("ks-retarget", HTMLButtonElement).disabled = !(count && keys.length && state.capture);
  }
  const joints = element("ks-pin-joint", HTMLSelectElement);
  for (const joint of project.joints) joints.append(new Option(joint.name, joint.name));

  async function refresh() {
    try {
      showState(await live.request({ type: "keyshapes" }));
      status(state.capture ? "captured: scrub the frames, then retarget" : state.model ? "model built: capture"
        : "give the key outlines: a file, drawn, or picked on footage");
    } catch (error) {
      showError(error.message);
    }
  }

  async function slow(message, saying) {
    const bar = element("ks-progress", HTMLProgressElement), cancel = element("ks-cancel", HTMLButtonElement);
    bar.hidden = false;
    bar.value = 0;
    status(saying);
    job = live.request(message, ({ index, count }) => { bar.max = count; bar.value = index; });
    cancel.hidden = false;
    cancel.onclick = () => { live.cancel(job.id); status("cancelling…"); };
    try {
      showState(await job);
      showError("");
      return true;
    } catch (error) {
      showError(error.cancelled ? "" : error.message);
      status(error.cancelled ? "cancelled: nothing changed" : "");
      return false;
    } finally {
      job = null;
      bar.hidden = true;
      cancel.hidden = true;
    }
  }

  async function put(url, file) {
    const reply = await fetch(url, { method: "PUT", body: file, headers: { "X-Toonmotion-Token": token } });
    const body = await reply.json().catch(() => ({ error: `${reply.status} ${reply.statusText}` }));
    if (!reply.ok) throw new Error(body.error);
    return body;
  }
  const points = () => (element("ks-resample", HTMLInputElement).checked ? Number(element("ks-points", HTMLInputElement).value) : null);
  const query = (file) => {
    const n = points();
    return `suffix=${encodeURIComponent(file.name.split(".").pop().toLowerCase())}&name=${encodeURIComponent(file.name)}`
      + (n === null ? "" : `&points=${n}`);
  };
  const chosen = (id) => /** @type {HTMLInputElement} */ (document.getElementById(id)).files[0];

  element("ks-outlines-file", HTMLInputElement).onchange = async () => {
    const file = chosen("ks-outlines-file");
    if (!file) return;
    try {
      const reply = await put(`api/keyshapes/outlines?${query(file)}`, file);
      outlines.push(...reply.outlines.map((p) => ({ points: p, frame: null })));
      showKeys();
      showError("");
      status(`${reply.outlines.length} outlines read from ${file.name}: build the model`);
    } catch (error) {
      showError(error.message);
    }
  };
  element("ks-contours-file", HTMLInputElement).onchange = async () => {
    const file = chosen("ks-contours-file");
    if (!file) return;
    try {
      const reply = await put(`api/keyshapes/contours?${query(file)}`, file);
      status(`${reply.frames} contours of ${reply.points} points read: capture them`);
      await refresh();
      showError("");
    } catch (error) {
      showError(error.message);
    }
  };
  element("ks-footage-file", HTMLInputElement).onchange = async () => {
    const file = chosen("ks-footage-file");
    if (!file) return;
    status("sending the footage…");
    try { // the Capture panel's footage: the same request, the same frames
      const suffix = encodeURIComponent(file.name.split(".").pop().toLowerCase());
      const body = await put(`api/footage?suffix=${suffix}&name=${encodeURIComponent(file.name)}`, file);
      project.capture = { footage: body, joints: null, tracked: null };
      images.length = 0;
      await refresh();
      showError("");
      status("pick the layer, or draw it, on its key frames");
    } catch (error) {
      showError(error.message);
      status("");
    }
  };

  function setMode(next) {
    mode = mode === next ? "" : next;
    element("ks-draw", HTMLButtonElement).setAttribute("aria-pressed", String(mode === "draw"));
    element("ks-pick", HTMLButtonElement).setAttribute("aria-pressed", String(mode === "pick"));
    view.draw(); // drawing or picking shows the outlines over the footage, not the capture
    status(mode === "draw" ? "press and drag round the shape: a closed curve" : mode === "pick" ? "click the layer" : "");
  }
  element("ks-draw", HTMLButtonElement).onclick = () => setMode("draw");
  element("ks-pick", HTMLButtonElement).onclick = () => setMode("pick");
  const onFootage = () => (state && state.footage ? frame : null);
  const unlisten = listen(view.overlay, {
    pointerdown: async (event) => {
      if (mode === "draw") {
        drawing = [fromEvent(event)];
        view.overlay.setPointerCapture(event.pointerId);
      } else if (mode === "pick") {
        try {
          const reply = await live.request({ type: "keyshape_pick", frame, at: fromEvent(event), points: points() || 100 });
          outlines.push({ points: reply.outline, frame: reply.frame });
          showKeys();
          showError("");
          status(`the layer picked on frame ${reply.frame}: ${outlines.length} key outline${outlines.length > 1 ? "s" : ""}`);
        } catch (error) {
          showError(error.message);
        }
      }
    },
    pointermove: (event) => {
      if (!drawing) return;
      drawing.push(fromEvent(event));
      view.draw();
    },
    pointerup: () => {
      if (!drawing) return;
      const curveDrawn = drawing;
      drawing = null;
      if (curveDrawn.length >= 3) {
        outlines.push({ points: curveDrawn, frame: onFootage() });
        status(`an outline of ${curveDrawn.length} points drawn: the library resamples it when the model is built`);
      }
      showKeys();
    },
  });

  element("ks-build", HTMLButtonElement).onclick = () => {
    const frames = outlines.map((o) => o.frame);
    slow({ type: "keyshape_model", outlines: outlines.map((o) => o.points), points: points(),
           key_frames: frames.every((f) => f !== null) ? frames : null }, "building the model…")
      .then((ok) => ok && status("model built: capture contours or footage"));
  };
  element("ks-capture-contours", HTMLButtonElement).onclick = () =>
    slow({ type: "keyshape_capture", source: "contours" }, "capturing the contours…")
      .then((ok) => ok && status("captured: scrub the frames, then retarget"));
  element("ks-capture-video", HTMLButtonElement).onclick = () =>
    slow({ type: "keyshape_capture", source: "video" }, "capturing the footage…")
      .then((ok) => ok && status("captured: scrub the frames, then retarget"));
  element("ks-scrub", HTMLInputElement).oninput = () => show(Number(element("ks-scrub", HTMLInputElement).value));

  element("ks-retarget", HTMLButtonElement).onclick = async () => {
    const keys = [...document.querySelectorAll("select.ks-pose")].map((s) => Number(/** @type {HTMLSelectElement} */ (s).value));
    const pin = element("ks-pin", HTMLInputElement).checked
      ? { joint: joints.value, at: [Number(element("ks-pin-x", HTMLInputElement).value), Number(element("ks-pin-y", HTMLInputElement).value)] }
      : null;
    try {
      status("retargeting…");
      const reply = await live.request({ type: "keyshape_retarget", keys, pin });
      showError("");
      // The Timeline plays it (frame messages with source "keyshapes") until told to go back.
      ctx.playSource = { source: "keyshapes", first: reply.first, last: reply.last, fps: reply.fps, file: reply.file };
      ctx.frame = reply.first;
      /** @type {HTMLButtonElement} */ (document.querySelector("#panels button[data-panel=timeline]")).click();
    } catch (error) {
      showError(error.message);
      status("");
    }
  };
  joints.onchange = () => {
    const joint = project.joints.find((j) => j.name === joints.value);
    element("ks-pin-x", HTMLInputElement).value = String(Math.round(joint.position[0]));
    element("ks-pin-y", HTMLInputElement).value = String(Math.round(joint.position[1]));
  };
  joints.value = project.joints.some((j) => j.name === "left_foot") ? "left_foot" : project.joints[0].name;
  joints.onchange(null);

  // For the console and tests: the state shown, and a drawn outline added as if by the pointer.
  ctx.keyshapes = { state: () => state, outlines: () => outlines, screen: (p) => {
    const [x, y] = toCanvas(p), box = view.overlay.getBoundingClientRect(), k = box.width / view.overlay.width;
    return [box.left + x * k, box.top + y * k];
  } };
  view.canvas.style.visibility = "hidden";
  refresh();

  return {
    unmount() {
      if (job) live.cancel(job.id);
      unlisten();
      view.canvas.style.visibility = "visible";
      view.drawOverlay = () => {};
      view.draw();
    },
  };
}
