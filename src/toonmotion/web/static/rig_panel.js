// The Rig panel (thesis 6.1): the silhouette (blue), the curve skeleton (grey) and the joints it
// suggests (orange dots) guide the animation skeleton. Drag a joint to move it (it snaps to a
// suggestion nearby, else to the curve skeleton); click an empty spot to add a joint, a child
// of the selected one (with none selected, a click adds nothing: a skeleton has one root); rename, re-parent or delete the selected joint in the side panel, or load
// a char_cfg.yaml / skeleton .json. "Rig with this skeleton" rigs the drawing again (region
// edits are replayed) and saves the project; the page then reloads on the new rig. A new
// drawing (PNG or JPEG, with or without a mask) can be opened or dropped on the stage: it is
// rigged into this project, and Undo brings the old one back.

import { element, listen, nearest } from "./panel_kit.js";

// A file the user chose, sent to the project's upload area; resolves with the server's reply.
async function upload(ctx, part, file, query = "") {
  const named = `${query ? query + "&" : "?"}name=${encodeURIComponent(file.name || "")}`; // named in errors
  const reply = await fetch(`api/uploads/${part}${named}`, {
    method: "PUT", body: file, headers: { "X-Toonmotion-Token": ctx.token },
  });
  const body = await reply.json().catch(() => ({ error: `${reply.status} ${reply.statusText}` }));
  if (!reply.ok) throw new Error(body.error);
  return body;
}

export const name = "rig";
export const title = "Rig";

const HANDLE = 7, SNAP = 10; // CSS pixels

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const draft = project.joints.map((j) => ({ name: j.name, parent: j.parent < 0 ? null : project.joints[j.parent].name,
                                             position: j.position.slice() }));
  ctx.draft = draft; // for tests and the console
  let selected = -1, dragging = false;

  side.innerHTML = `<h2>Rig</h2>
    <p>Drag joints (they snap to the orange suggestions, then to the grey curve skeleton); click an
    empty spot to add a joint under the selected one (<kbd>Esc</kbd>: select none).</p>
    <div id="rig-joint"></div>
    <p><label>Load a skeleton <input type="file" id="rig-skeleton-file" accept=".yaml,.yml,.json"></label></p>
    <p><button id="rig-go">Rig with this skeleton</button></p>
    <p><label><input type="checkbox" id="rig-show-mask"> Show the mask</label></p>
    <p id="rig-note"></p>
    <h3>A new drawing</h3>
    <p>Open one, or drop it on the stage (PNG or JPEG; a transparent background is its mask).</p>
    <p><label>Drawing <input type="file" id="rig-drawing" accept="image/png,image/jpeg"></label></p>
    <p><label>Mask (optional) <input type="file" id="rig-mask" accept="image/png,image/jpeg"></label></p>
    <p><label><input type="radio" name="rig-skeleton" value="keep" checked> keep this skeleton</label><br>
       <label><input type="radio" name="rig-skeleton" value="new"> find a new one</label></p>
    <p><button id="rig-open" disabled>Rig the new drawing</button> <progress id="rig-progress" hidden></progress></p>`;
  if (project.keys) {
    document.getElementById("rig-note").textContent =
      "The key-frames name the joints: move them (the keys follow), but keep their names (or delete the keys).";
  }

  function showJoint() {
    const box = document.getElementById("rig-joint");
    if (selected < 0) return box.replaceChildren();
    const joint = draft[selected];
    box.innerHTML = `<p><label>Name <input id="rig-name" value="${joint.name}"></label></p>
      <p><label>Parent <select id="rig-parent"><option value="">(none: a root)</option></select></label></p>
      <p><button id="rig-delete">Delete joint</button></p>`;
    const parent = element("rig-parent", HTMLSelectElement);
    for (const other of draft) if (other !== joint) parent.append(new Option(other.name, other.name, false, other.name === joint.parent));
    element("rig-name", HTMLInputElement).onchange = (event) => {
      const old = joint.name, next = /** @type {HTMLInputElement} */ (event.target).value.trim();
      if (!next || draft.some((j) => j !== joint && j.name === next)) return showError(`a joint needs its own name, not ${JSON.stringify(next)}`);
      joint.name = next;
      for (const j of draft) if (j.parent === old) j.parent = next;
      showError("");
      view.draw();
    };
    parent.onchange = () => { joint.parent = parent.value || null; view.draw(); };
    element("rig-delete", HTMLButtonElement).onclick = remove;
  }

  function remove() {
    if (selected < 0) return;
    const gone = draft[selected];
    for (const j of draft) if (j.parent === gone.name) j.parent = gone.parent; // children move up
    draft.splice(selected, 1);
    selected = -1;
    showJoint();
    view.draw();
  }

  let maskImage = null;
  view.drawOverlay = (pen) => {
    const ratio = window.devicePixelRatio || 1;
    if (maskImage && element("rig-show-mask", HTMLInputElement).checked) {
      const [x, y] = view.toCanvas([0, 0]);
      pen.globalAlpha = 0.35;
      pen.drawImage(maskImage, x, y, project.width * view.scale, project.height * view.scale);
      pen.globalAlpha = 1;
    }
    pen.lineWidth = 1.5 * ratio;
    pen.strokeStyle = "rgba(49, 130, 206, 0.9)";
    for (const loop of project.outline) {
      pen.beginPath();
      pen.moveTo(...view.toCanvas(loop[0]));
      for (const p of loop.slice(1)) pen.lineTo(...view.toCanvas(p));
      pen.closePath();
      pen.stroke();
    }
    pen.strokeStyle = "rgba(90, 90, 90, 0.8)";
    for (const path of project.curve_skeleton) {
      pen.beginPath();
      pen.moveTo(...view.toCanvas(path[0]));
      for (const p of path.slice(1)) pen.lineTo(...view.toCanvas(p));
      pen.stroke();
    }
    pen.fillStyle = "#dd6b20";
    for (const s of project.suggestions) {
      pen.beginPath();
      pen.arc(...view.toCanvas(s), 3 * ratio, 0, 2 * Math.PI);
      pen.fill();
    }
    const index = new Map(draft.map((j, i) => [j.name, i]));
    pen.lineWidth = 2.5 * ratio;
    pen.strokeStyle = "#1a202c";
    for (const j of draft) {
      if (j.parent === null || !index.has(j.parent)) continue;
      pen.beginPath();
      pen.moveTo(...view.toCanvas(draft[index.get(j.parent)].position));
      pen.lineTo(...view.toCanvas(j.position));
      pen.stroke();
    }
    draft.forEach((j, i) => {
      pen.beginPath();
      pen.arc(...view.toCanvas(j.position), HANDLE * ratio, 0, 2 * Math.PI);
      pen.fillStyle = i === selected ? "#3182ce" : "#fff";
      pen.fill();
      pen.lineWidth = ratio;
      pen.stroke();
    });
  };

  const skeletonPoints = project.curve_skeleton.flat();
  function snapped(event) {
    const s = nearest(view, project.suggestions, event, SNAP);
    if (s >= 0) return project.suggestions[s].slice();
    const c = nearest(view, skeletonPoints, event, SNAP);
    return c >= 0 ? skeletonPoints[c].slice() : view.toDrawing(event);
  }

  const overlay = view.overlay;
  const down = (event) => {
    const hit = nearest(view, draft.map((j) => j.position), event, HANDLE + 4);
    if (hit >= 0) {
      selected = hit;
      dragging = true;
      overlay.setPointerCapture(event.pointerId);
    } else if (selected < 0 && draft.length) {
      // A skeleton has one root: a click with no joint selected adds nothing (it added a second
      // root, and rigging then failed), and says how to add one.
      status("select a joint first (click it): a click on an empty spot adds a joint under it");
      return;
    } else {
      let n = draft.length + 1;
      while (draft.some((j) => j.name === `joint${n}`)) n++;
      const parent = selected >= 0 ? draft[selected].name : null;
      draft.push({ name: `joint${n}`, parent, position: snapped(event) });
      selected = draft.length - 1;
    }
    showJoint();
    view.draw();
  };
  const move = (event) => {
    if (!dragging) return;
    draft[selected].position = snapped(event);
    view.draw();
  };
  const up = () => { dragging = false; };
  const keys = (event) => {
    if (document.activeElement !== document.body) return;
    if (event.key === "Delete" || event.key === "Backspace") remove();
    if (event.key === "Escape" && selected >= 0) {  // nothing selected: a click adds no joint
      selected = -1;
      showJoint();
      view.draw();
    }
  };
  const unlisten = [listen(overlay, { pointerdown: down, pointermove: move, pointerup: up }),
                    listen(window, { keydown: keys })];

  element("rig-go", HTMLButtonElement).onclick = async () => {
    const button = element("rig-go", HTMLButtonElement);
    button.disabled = true;
    status("rigging…");
    try {
      const reply = await live.request({ type: "rig", joints: draft });
      status(`rigged${reply.skipped ? `; ${reply.skipped} region edits no longer applied` : ""}`);
      location.reload();
    } catch (error) {
      showError(error.message);
      status("");
      button.disabled = false;
    }
  };
  element("rig-show-mask", HTMLInputElement).onchange = async () => {
    if (!maskImage) {
      maskImage = new Image();
      maskImage.src = `api/mask.png?token=${encodeURIComponent(ctx.token)}`;
      await maskImage.decode().catch(() => showError("the mask could not be loaded"));
    }
    view.draw();
  };

  element("rig-skeleton-file", HTMLInputElement).onchange = async (event) => {
    const file = /** @type {HTMLInputElement} */ (event.target).files[0];
    if (!file) return;
    try {
      const format = /\.json$/i.test(file.name) ? "json" : "yaml";
      const reply = await upload(ctx, "skeleton", file, `?format=${format}`);
      draft.splice(0, draft.length, ...reply.joints.map((j) => ({ ...j, position: j.position.slice() })));
      selected = -1;
      showJoint();
      view.draw();
      showError("");
      status(`loaded ${reply.joints.length} joints: check them, then rig with this skeleton`);
    } catch (error) {
      showError(error.message);
    }
  };

  // A new drawing: sent to the upload area as soon as it is chosen (or dropped), rigged on "Rig".
  let haveDrawing = false, haveMask = false;
  async function choose(part, file) {
    if (!file) return;
    try {
      const reply = await upload(ctx, part, file);
      if (part === "drawing") haveDrawing = true; else haveMask = true;
      element("rig-open", HTMLButtonElement).disabled = !haveDrawing;
      showError("");
      status(`${part} ${reply.width}×${reply.height} ready: rig it`);
    } catch (error) {
      showError(error.message);
    }
  }
  element("rig-drawing", HTMLInputElement).onchange = (event) => choose("drawing", /** @type {HTMLInputElement} */ (event.target).files[0]);
  element("rig-mask", HTMLInputElement).onchange = (event) => choose("mask", /** @type {HTMLInputElement} */ (event.target).files[0]);
  const stage = document.getElementById("stage");
  const over = (event) => { event.preventDefault(); };
  const dropped = (event) => {
    event.preventDefault();
    const file = [...event.dataTransfer.files].find((f) => /^image\/(png|jpeg)$/.test(f.type));
    if (file) choose("drawing", file);
    else showError("drop a PNG or JPEG drawing");
  };
  unlisten.push(listen(stage, { dragover: over, drop: dropped }));
  element("rig-open", HTMLButtonElement).onclick = async () => {
    const button = element("rig-open", HTMLButtonElement), bar = element("rig-progress", HTMLProgressElement);
    const skeleton = side.querySelector("input[name=rig-skeleton]:checked").value;
    button.disabled = true;
    bar.hidden = false;
    status("rigging the new drawing…");
    try {
      await live.request({ type: "open_drawing", skeleton, mask: haveMask }, (p) => {
        bar.max = p.count;
        bar.value = p.index + 1;
      });
      location.reload();
    } catch (error) {
      showError(error.message);
      status("");
      button.disabled = false;
      bar.hidden = true;
    }
  };

  view.setVertices(project.vertices);
  status("place the joints");

  return {
    unmount() {
      for (const off of unlisten) off();
      view.drawOverlay = () => {};
    },
  };
}
