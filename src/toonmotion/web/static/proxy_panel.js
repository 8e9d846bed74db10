// The 3D panel (Jain et al. 2012): lift the key-frames' animation into a 3D proxy with a
// motion-capture clip as the prior (from the library the editor was started with, or a .bvh
// sent here), from the view set by dragging the camera round the gizmo's figure (or searched);
// see the proxy in an orbit view (drag to turn, wheel to zoom) beside the frames it was lifted
// from, its points on them; add elements (a balloon, balls, a scarf, a skirt, a cape, rain),
// simulate them with a progress bar and play the composited frames here or in the Timeline; and
// export the proxy (glTF, BVH) or the scene (MP4, GIF, PNG frames, depth passes). What it makes
// is kept in the project's proxy3d/ folder: a reload shows it again.

import { element } from "./panel_kit.js";
import { ProxyView, ViewGizmo } from "./proxy_view.js";

export const name = "proxy";
export const title = "3D";

const ELEMENTS = {
  balloon: { label: "Balloon held at", markers: 1 }, balls: { label: "Balls in the path of", markers: 1 },
  scarf: { label: "Scarf tied at", markers: 1 }, skirt: { label: "Skirt round", markers: 1 },
  cape: { label: "Cape from (left, right)", markers: 2 }, rain: { label: "Rain, drops at a time", markers: 0 },
};

export function mount(ctx) {
  const { live, side, status, showError, token } = ctx;
  const stage = document.getElementById("stage");
  let state = null, frame = 0, playing = null, running = null, images = {};
  let elements = [];
  let view = { azimuth: 0, elevation: 0, up: 0 };

  side.innerHTML = `<h2>3D</h2>
    <p><label>Prior <select id="proxy-prior" style="max-width: 100%"></select></label><br>
      <label>or send a clip <input id="proxy-prior-file" type="file" accept=".bvh"></label><br>
      <span title="The part of the clip that moves like the drawing (blank: from its start, to its end)">Its frames
        <input id="proxy-from" type="number" min="0" placeholder="start" style="width: 4.5em" aria-label="the prior's first frame">
        to <input id="proxy-to" type="number" min="0" placeholder="end" style="width: 4.5em" aria-label="the prior's frame to stop before"></span></p>
    <p><canvas id="proxy-gizmo" style="width: 220px; height: 190px; touch-action: none; cursor: grab"
       aria-label="view gizmo: drag the camera round the figure; drag the dial for the world's up"></canvas><br>
      <label><input id="proxy-search" type="checkbox"> Search the view</label><br>
      <label>Ground <select id="proxy-ground"><option value="prior">the prior's floor</option>
        <option value="feet">the drawn feet</option></select></label><br>
      <label title="The camera pans but does not tilt: the world's vertical stays the picture's, for a figure unlike its prior"><input id="proxy-hold" type="checkbox"> Keep the view's elevation</label></p>
    <p><button id="proxy-lift">Lift</button> <progress id="proxy-progress" max="1" value="0" hidden></progress>
      <button id="proxy-cancel" hidden>Cancel</button></p>
    <p id="proxy-found"></p>
    <div id="proxy-warnings"></div>
    <p id="proxy-show">${["points", "volumes", "skeleton", "camera", "ground"].map((k) =>
      `<label><input type="checkbox" data-show="${k}" checked> ${k}</label>`).join(" ")}</p>
    <h3>Elements</h3>
    <p><select id="proxy-kind">${Object.entries(ELEMENTS).map(([k, e]) => `<option value="${k}">${e.label}</option>`).join("")}</select>
      <select id="proxy-marker"></select> <select id="proxy-marker2"></select>
      <input id="proxy-count" type="number" min="1" max="10000" value="30" style="width: 4.5em" hidden>
      <button id="proxy-add">Add</button></p>
    <ul id="proxy-elements"></ul>
    <p><button id="proxy-simulate" disabled>Simulate</button></p>
    <p id="proxy-scene"></p>
    <p><input id="proxy-scrub" type="range" min="0" max="0" value="0" style="width: 100%" aria-label="frame">
      <button id="proxy-play" disabled>Play</button> frame <output id="proxy-frame">0</output></p>
    <h3>Export</h3>
    <p><select id="proxy-format"><option value="glb">the proxy, glTF (.glb)</option><option value="bvh">its skeleton, BVH</option>
      <option value="mp4">the scene, MP4</option><option value="gif">the scene, GIF</option>
      <option value="png">the scene, PNG frames</option><option value="passes">the elements' passes (beauty, depth, occlusion)</option></select>
      <input id="proxy-name" value="scene" size="10" aria-label="export name"> <button id="proxy-export" disabled>Export</button></p>
    <ul id="proxy-files"></ul>`;

  // The stage: the orbit view on the left, the frames on the right (the drawing's canvases hidden).
  const canvases = [element("mesh", HTMLCanvasElement), element("overlay", HTMLCanvasElement)];
  for (const c of canvases) c.style.visibility = "hidden";
  const orbit = document.createElement("canvas"), picture = document.createElement("canvas");
  orbit.id = "proxy-3d";
  orbit.setAttribute("aria-label", "the 3D proxy: drag to turn round it, wheel to zoom");
  picture.id = "proxy-2d";
  picture.setAttribute("aria-label", "the frames lifted, with the proxy's points; the scene once simulated");
  Object.assign(orbit.style, { left: "0", width: "50%", touchAction: "none", cursor: "grab" });
  Object.assign(picture.style, { left: "50%", width: "50%" });
  stage.append(orbit, picture);
  const proxyView = new ProxyView(orbit);
  const gizmo = new ViewGizmo(element("proxy-gizmo", HTMLCanvasElement), view, (changed) => {
    view = changed;
    element("proxy-search", HTMLInputElement).checked = false;
  });

  const frames = () => (state && state.scene ? state.scene.frames : state && state.proxy ? state.proxy.points.length : 0);
  function image(kind, t) {
    const key = `${kind}/${t}/${state.stamp}`;
    if (!images[key]) {
      images[key] = new Image();
      images[key].onload = () => drawPicture();
      images[key].src = `${kind === "scene" ? "api/scene" : "api/proxy/frames"}/${t}.png?token=${encodeURIComponent(token)}&v=${state.stamp}`;
    }
    return images[key];
  }

  // The frame lifted (or composited), fitted to its half of the stage, the proxy's points on it.
  function drawPicture() {
    const ratio = window.devicePixelRatio || 1, box = picture.getBoundingClientRect();
    picture.width = Math.max(1, Math.round(box.width * ratio));
    picture.height = Math.max(1, Math.round(box.height * ratio));
    const pen = picture.getContext("2d");
    pen.fillStyle = "#f4f3f0";
    pen.fillRect(0, 0, picture.width, picture.height);
    if (!state || !state.proxy) return;
    const camera = state.proxy.camera, scale = Math.min(picture.width / camera.width, picture.height / camera.height) * 0.95;
    const x0 = (picture.width - camera.width * scale) / 2, y0 = (picture.height - camera.height * scale) / 2;
    const shown = image(state.scene ? "scene" : "frames", frame);
    pen.fillStyle = "#fff";
    pen.fillRect(x0, y0, camera.width * scale, camera.height * scale);
    if (shown.complete && shown.naturalWidth) pen.drawImage(shown, x0, y0, camera.width * scale, camera.height * scale);
    if (state.scene) return; // the scene as it will be exported
    const c = camera.centres[frame], R = camera.axes[frame];
    pen.fillStyle = "#dd6b20";
    for (const p of state.proxy.points[frame]) {
      const d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]], q = R.map((row) => row[0] * d[0] + row[1] * d[1] + row[2] * d[2]);
      const u = camera.width / 2 + (camera.focal * q[0]) / q[2], v = camera.height / 2 + (camera.focal * q[1]) / q[2];
      pen.beginPath();
      pen.arc(x0 + u * scale, y0 + v * scale, 3 * ratio, 0, 2 * Math.PI);
      pen.fill();
    }
  }

  function show(at) {
    frame = Math.max(0, Math.min(at, Math.max(0, frames() - 1)));
    element("proxy-scrub", HTMLInputElement).value = String(frame);
    element("proxy-frame", HTMLOutputElement).textContent = String(frame);
    if (state && state.proxy) proxyView.setFrame(Math.min(frame, state.proxy.points.length - 1));
    drawPicture();
  }

  // Everything the panel shows, from the server's reply (after a lift, or on opening).
  function shown(reply) {
    const prior = element("proxy-prior", HTMLSelectElement), chosen = prior.value;
    state = { ...reply, stamp: Date.now() };
    ctx.project.scene = reply.timeline; // what the Timeline plays over the key-frames
    prior.replaceChildren(...reply.priors.map((p) => new Option(p.replace(/^library\//, "").replace(/^project\//, "sent: "), p)));
    if (!reply.priors.length) prior.append(new Option("none: send a .bvh clip, or start with --mocap DIR", ""));
    const lift = reply.lift;
    if (lift) {
      prior.value = reply.priors.includes(chosen) ? chosen : lift.prior;
      element("proxy-search", HTMLInputElement).checked = lift.view === null;
      element("proxy-ground", HTMLSelectElement).value = lift.ground;
      element("proxy-hold", HTMLInputElement).checked = lift.hold_elevation;
      const [from, to] = lift.segment || [0, null];
      element("proxy-from", HTMLInputElement).value = from ? String(from) : "";
      element("proxy-to", HTMLInputElement).value = to === null ? "" : String(to);
      view = { azimuth: Math.round(lift.found[0]), elevation: Math.round(lift.found[1]), up: lift.up };
      gizmo.set(view);
      element("proxy-found", HTMLParagraphElement).textContent = `view ${lift.found[0]}°, ${lift.found[1]}° (${lift.searched ? "searched" : "given"}), camera fit ${lift.camera_px} px`
        + (lift.stale ? " — the key-frames changed since: lift again" : "");
    } else if (chosen) prior.value = chosen;
    const warnings = [...(lift ? lift.warnings : []), ...(reply.scene ? reply.scene.warnings : [])];
    element("proxy-warnings", HTMLDivElement).replaceChildren(...warnings.map((w) => Object.assign(document.createElement("p"), { className: "warning", textContent: w })));
    proxyView.setProxy(reply.proxy);
    const markers = reply.proxy ? reply.proxy.names : [];
    for (const id of ["proxy-marker", "proxy-marker2"]) {
      const select = element(id, HTMLSelectElement), was = select.value;
      select.replaceChildren(...markers.map((m) => new Option(m, m)));
      if (markers.includes(was)) select.value = was;
    }
    if (reply.scene) elements = reply.scene.elements.map((e) => ({ ...e }));
    listElements();
    element("proxy-scene", HTMLParagraphElement).textContent = reply.scene ? `${reply.scene.frames} frames composited` : "";
    element("proxy-scrub", HTMLInputElement).max = String(Math.max(0, frames() - 1));
    element("proxy-play", HTMLButtonElement).disabled = !reply.proxy;
    element("proxy-export", HTMLButtonElement).disabled = !reply.proxy;
    show(frame);
  }

  function listElements() {
    const list = element("proxy-elements", HTMLUListElement);
    list.replaceChildren(...elements.map((e, i) => {
      const item = document.createElement("li"), remove = document.createElement("button");
      item.textContent = `${e.kind} ${e.kind === "rain" ? e.count : e.markers.join(", ")} `;
      remove.textContent = "×";
      remove.title = "remove it";
      remove.onclick = () => { elements.splice(i, 1); listElements(); };
      item.append(remove);
      return item;
    }));
    element("proxy-simulate", HTMLButtonElement).disabled = !(state && state.proxy) || elements.length === 0;
  }

  function chooseKind() {
    const kind = element("proxy-kind", HTMLSelectElement).value, need = ELEMENTS[kind].markers;
    element("proxy-marker", HTMLSelectElement).hidden = need < 1;
    element("proxy-marker2", HTMLSelectElement).hidden = need < 2;
    element("proxy-count", HTMLInputElement).hidden = kind !== "rain";
  }
  element("proxy-kind", HTMLSelectElement).onchange = chooseKind;
  chooseKind();
  element("proxy-add", HTMLButtonElement).onclick = () => {
    const kind = element("proxy-kind", HTMLSelectElement).value, need = ELEMENTS[kind].markers;
    const markers = [element("proxy-marker", HTMLSelectElement).value, element("proxy-marker2", HTMLSelectElement).value].slice(0, need);
    if (markers.some((m) => !m)) return showError("lift the animation first: elements are placed at the proxy's markers");
    elements.push({ kind, markers, count: kind === "rain" ? Number(element("proxy-count", HTMLInputElement).value) : 3 });
    listElements();
  };

  // A slow request with the progress bar and Cancel; resolves with its reply (or null if it failed).
  async function slow(message, doing) {
    const bar = element("proxy-progress", HTMLProgressElement), cancel = element("proxy-cancel", HTMLButtonElement);
    bar.hidden = cancel.hidden = false;
    bar.value = 0;
    showError(""); // the last failure's message goes as the next try starts
    status(`${doing}…`);
    try {
      running = live.request(message, (p) => { bar.max = Math.max(1, p.count); bar.value = p.index; });
      cancel.onclick = () => live.cancel(running.id);
      const reply = await running;
      showError("");
      return reply;
    } catch (error) {
      showError(error.message);
      status("");
      return null;
    } finally {
      running = null;
      bar.hidden = cancel.hidden = true;
    }
  }

  element("proxy-lift", HTMLButtonElement).onclick = async () => {
    const prior = element("proxy-prior", HTMLSelectElement).value;
    if (!prior) return showError("choose a prior: send a .bvh clip, or start the editor with --mocap DIR");
    const searched = element("proxy-search", HTMLInputElement).checked;
    const from = element("proxy-from", HTMLInputElement).value, to = element("proxy-to", HTMLInputElement).value;
    const reply = await slow({ type: "lift", prior, view: searched ? null : [view.azimuth, view.elevation], up: view.up,
                               ground: element("proxy-ground", HTMLSelectElement).value,
                               hold_elevation: element("proxy-hold", HTMLInputElement).checked,
                               segment: [from ? Number(from) : 0, to ? Number(to) : null] }, "lifting");
    if (reply) { shown(reply); status(`lifted ${reply.proxy.names.length} markers over ${reply.proxy.points.length} frames`); }
  };
  element("proxy-simulate", HTMLButtonElement).onclick = async () => {
    const reply = await slow({ type: "scene", elements }, "simulating");
    if (!reply) return;
    const again = await live.request({ type: "proxy" });
    shown(again);
    status(`simulated: ${reply.frames} frames composited`);
  };
  element("proxy-export", HTMLButtonElement).onclick = async () => {
    const reply = await slow({ type: "proxy_export", format: element("proxy-format", HTMLSelectElement).value,
                               name: element("proxy-name", HTMLInputElement).value }, "exporting");
    if (!reply) return;
    const files = reply.files.length > 6 ? [...reply.files.slice(0, 3), null, ...reply.files.slice(-2)] : reply.files;
    element("proxy-files", HTMLUListElement).replaceChildren(...files.map((file) => {
      const item = document.createElement("li");
      if (file === null) { item.textContent = `… ${reply.files.length} files in all`; return item; }
      const link = Object.assign(document.createElement("a"), { textContent: file, download: file.split("/").pop() });
      link.href = `api/${file}?token=${encodeURIComponent(token)}`;
      item.append(link);
      return item;
    }));
    status(`exported ${reply.files.length} file${reply.files.length === 1 ? "" : "s"}`);
  };
  element("proxy-prior-file", HTMLInputElement).onchange = async (event) => {
    const file = /** @type {HTMLInputElement} */ (event.target).files[0];
    if (!file) return;
    try {
      status("sending the clip…");
      const reply = await fetch(`api/priors?name=${encodeURIComponent(file.name)}`, { method: "PUT", body: file, headers: { "X-Toonmotion-Token": token } });
      const body = await reply.json().catch(() => ({ error: `${reply.status} ${reply.statusText}` }));
      if (!reply.ok) throw new Error(body.error);
      shown({ ...state, priors: body.priors });
      element("proxy-prior", HTMLSelectElement).value = body.sent;
      status(`the clip is a prior: ${body.frames} frames, ${body.joints} joints`);
      showError("");
    } catch (error) {
      showError(error.message);
      status("");
    }
  };
  for (const box of side.querySelectorAll("[data-show]")) {
    /** @type {HTMLInputElement} */ (box).onchange = () => {
      proxyView.show[/** @type {HTMLInputElement} */ (box).dataset.show] = /** @type {HTMLInputElement} */ (box).checked;
      proxyView.draw();
    };
  }
  element("proxy-scrub", HTMLInputElement).oninput = (event) => show(Number(/** @type {HTMLInputElement} */ (event.target).value));
  element("proxy-play", HTMLButtonElement).onclick = () => {
    const button = element("proxy-play", HTMLButtonElement);
    if (playing) { clearInterval(playing); playing = null; button.textContent = "Play"; return; }
    const fps = state.scene ? state.scene.fps : state.proxy.fps;
    button.textContent = "Stop";
    playing = setInterval(() => show((frame + 1) % Math.max(1, frames())), 1000 / fps);
  };
  const resize = () => { proxyView.draw(); drawPicture(); };
  window.addEventListener("resize", resize);

  live.request({ type: "proxy" }).then(shown, (error) => showError(error.message));

  return {
    unmount() {
      if (playing) clearInterval(playing);
      if (running) live.cancel(running.id);
      window.removeEventListener("resize", resize);
      orbit.remove();
      picture.remove();
      for (const c of canvases) c.style.visibility = "";
    },
  };
}
