// The Regions panel (thesis 3.5, 6.3): each bone's region of the drawing in its own colour.
// Click a region to bring it one depth layer forward (Shift-click: back); draw a lasso round
// vertices to attach them to the chosen bone. Every edit is saved in the project at once; the
// editor's Undo / Redo (Ctrl+Z, Ctrl+Shift+Z or Ctrl+Y) take edits back and make them again,
// also after a reload: the history lives in the project.

import { element, listen } from "./panel_kit.js";

export const name = "regions";
export const title = "Regions";

const CLICK = 4; // CSS pixels a pointer may move and still click

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  let lasso = null, start = null;

  side.innerHTML = `<h2>Regions</h2>
    <p>Click a region to bring it forward (Shift-click: back). Draw a lasso round vertices to
    attach them to <select id="regions-bone"></select></p>

    <p id="regions-state"></p>
    <p id="regions-fallback"></p>`;
  const select = element("regions-bone", HTMLSelectElement);
  for (const bone of project.bones) select.append(new Option(bone, bone));

  function showState() {
    const count = project.fallback.length;
    document.getElementById("regions-fallback").textContent = count
      ? `${count} vertices (red dots) were attached by distance, not by the decomposition's rule: ` +
        "check them, and lasso them to the right bone if they are wrong."
      : "";
    document.getElementById("regions-state").textContent =
      `${project.edits} region edit${project.edits === 1 ? "" : "s"} in the project (Undo, Ctrl+Z, takes the newest back)`;
  }

  view.drawOverlay = (pen) => {
    const V = project.vertices, T = project.triangles, bones = project.vertex_bone;
    pen.globalAlpha = 0.35;
    for (let t = 0; t < T.length; t += 3) {
      const [a, b, c] = [T[t], T[t + 1], T[t + 2]];
      pen.beginPath();
      pen.moveTo(...view.toCanvas([V[2 * a], V[2 * a + 1]]));
      pen.lineTo(...view.toCanvas([V[2 * b], V[2 * b + 1]]));
      pen.lineTo(...view.toCanvas([V[2 * c], V[2 * c + 1]]));
      pen.closePath();
      pen.fillStyle = colour(bones[a], project.depth[bones[a]]);
      pen.fill();
    }
    pen.globalAlpha = 1;
    pen.fillStyle = "#e53e3e";
    for (const v of project.fallback) {
      pen.beginPath();
      pen.arc(...view.toCanvas([V[2 * v], V[2 * v + 1]]), 2.5 * (window.devicePixelRatio || 1), 0, 2 * Math.PI);
      pen.fill();
    }
    if (lasso && lasso.length > 1) {
      pen.beginPath();
      pen.moveTo(...view.toCanvas(lasso[0]));
      for (const p of lasso.slice(1)) pen.lineTo(...view.toCanvas(p));
      pen.closePath();
      pen.setLineDash([6, 4]);
      pen.lineWidth = 2 * (window.devicePixelRatio || 1);
      pen.strokeStyle = "#111";
      pen.stroke();
      pen.setLineDash([]);
    }
  };

  async function edit(message) {
    try {
      const reply = await live.request(message);
      Object.assign(project, { triangles: reply.triangles, vertex_bone: reply.vertex_bone, depth: reply.depth,
                               fallback: reply.fallback, edits: reply.edits, undone: reply.undone });
      view.setTriangles(reply.triangles);
      showState();
      showError("");
      status("saved");
    } catch (error) {
      showError(error.message);
    }
  }

  const overlay = view.overlay;
  const down = (event) => {
    start = [event.clientX, event.clientY];
    lasso = [view.toDrawing(event)];
    overlay.setPointerCapture(event.pointerId);
  };
  const move = (event) => {
    if (!lasso) return;
    lasso.push(view.toDrawing(event));
    view.draw();
  };
  const up = (event) => {
    if (!lasso) return;
    const moved = Math.hypot(event.clientX - start[0], event.clientY - start[1]);
    const curve = lasso;
    lasso = null;
    view.draw();
    if (moved <= CLICK && curve.length < 6) edit({ type: "depth", at: view.toDrawing(event), by: event.shiftKey ? -1 : 1 });
    else if (curve.length >= 3) edit({ type: "correct", bone: select.value, curve });
  };
  const unlisten = [listen(overlay, { pointerdown: down, pointermove: move, pointerup: up })];
  view.setVertices(project.vertices); // regions are edited on the rest pose
  showState();
  status("click a region or draw a lasso");

  return {
    unmount() {
      for (const off of unlisten) off();
      view.drawOverlay = () => {};
    },
  };
}

// A bone's colour: evenly spread hues, lighter for regions further forward.
function colour(bone, depth) {
  const hue = (bone * 137.508) % 360;
  return `hsl(${hue.toFixed(0)}, 70%, ${Math.min(75, 50 + 8 * depth)}%)`;
}
