// The Rig panel (thesis 6.1): the curve skeleton (grey) and the joints it suggests (orange dots)
// guide the animation skeleton. Drag a joint to move it (it snaps to a suggestion nearby); click
// an empty spot to add a joint, a child of the selected one; rename, re-parent or delete the
// selected joint in the side panel. "Rig with this skeleton" rigs the drawing again (region
// edits are replayed) and saves the project; the page then reloads on the new rig.

import { listen, nearest } from "./panel_kit.js";

export const name = "rig";
export const title = "Rig";

const HANDLE = 7, SNAP = 10; // CSS pixels

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const draft = project.joints.map((j) => ({ name: j.name, parent: j.parent < 0 ? null : project.joints[j.parent].name,
                                             position: j.position.slice() }));
  let selected = -1, dragging = false, moved = false;

  side.innerHTML = `<h2>Rig</h2>
    <p>Drag joints (they snap to the orange suggestions); click an empty spot to add a joint under
    the selected one.</p>
    <div id="rig-joint"></div>
    <p><button id="rig-go">Rig with this skeleton</button></p>
    <p id="rig-note"></p>`;
  if (project.keys) {
    document.getElementById("rig-note").textContent =
      "The key-frames name the joints: move them, but keep their names (or delete the keys).";
  }

  function showJoint() {
    const box = document.getElementById("rig-joint");
    if (selected < 0) return box.replaceChildren();
    const joint = draft[selected];
    box.innerHTML = `<p><label>Name <input id="rig-name" value="${joint.name}"></label></p>
      <p><label>Parent <select id="rig-parent"><option value="">(none: a root)</option></select></label></p>
      <p><button id="rig-delete">Delete joint</button></p>`;
    const parent = document.getElementById("rig-parent");
    for (const other of draft) if (other !== joint) parent.append(new Option(other.name, other.name, false, other.name === joint.parent));
    document.getElementById("rig-name").onchange = (event) => {
      const old = joint.name, next = event.target.value.trim();
      if (!next || draft.some((j) => j !== joint && j.name === next)) return showError(`a joint needs its own name, not ${JSON.stringify(next)}`);
      joint.name = next;
      for (const j of draft) if (j.parent === old) j.parent = next;
      showError("");
      view.draw();
    };
    parent.onchange = () => { joint.parent = parent.value || null; view.draw(); };
    document.getElementById("rig-delete").onclick = remove;
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

  view.drawOverlay = (pen) => {
    const ratio = window.devicePixelRatio || 1;
    pen.lineWidth = 1.5 * ratio;
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

  function snapped(event) {
    const s = nearest(view, project.suggestions, event, SNAP);
    return s >= 0 ? project.suggestions[s].slice() : view.toDrawing(event);
  }

  const overlay = view.overlay;
  const down = (event) => {
    const hit = nearest(view, draft.map((j) => j.position), event, HANDLE + 4);
    moved = false;
    if (hit >= 0) {
      selected = hit;
      dragging = true;
      overlay.setPointerCapture(event.pointerId);
    } else {
      let n = draft.length + 1;
      while (draft.some((j) => j.name === `joint_${n}`)) n++;
      const parent = selected >= 0 ? draft[selected].name : null;
      draft.push({ name: `joint_${n}`, parent, position: snapped(event) });
      selected = draft.length - 1;
    }
    showJoint();
    view.draw();
  };
  const move = (event) => {
    if (!dragging) return;
    draft[selected].position = snapped(event);
    moved = true;
    view.draw();
  };
  const up = () => { dragging = false; };
  const keys = (event) => {
    if ((event.key === "Delete" || event.key === "Backspace") && document.activeElement === document.body) remove();
  };
  const unlisten = [listen(overlay, { pointerdown: down, pointermove: move, pointerup: up }),
                    listen(window, { keydown: keys })];

  document.getElementById("rig-go").onclick = async () => {
    const button = document.getElementById("rig-go");
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
  view.setVertices(project.vertices);
  status("place the joints");

  return {
    unmount() {
      for (const off of unlisten) off();
      view.drawOverlay = () => {};
    },
  };
}
