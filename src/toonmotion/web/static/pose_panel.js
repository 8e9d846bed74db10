// The Pose panel: drag a joint and the drawing follows live (needle model + joint-area solve on
// the server). The rest bones are shown as red reference lines from each posed parent
// (thesis fig. 6.2a). While a reply is awaited, newer drags replace the queued pose, so the
// drawing keeps up with the pointer instead of falling behind it.

import { listen, nearest, newest } from "./panel_kit.js";

export const name = "pose";
export const title = "Pose";

const HANDLE = 7; // joint handle radius, CSS pixels

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const rest = project.joints.map((j) => j.position.slice());
  // The pose being made, shared with the other panels (the Timeline keys it).
  ctx.pose = ctx.pose || rest.map((p) => p.slice());
  const positions = ctx.pose;
  let dragging = -1, started = 0;

  side.innerHTML = `<h2>Pose</h2>
    <p>Drag a joint: the drawing follows. Red lines are the rest bones, from each posed parent.</p>
    <p><button id="pose-reset">Reset to the rest pose</button></p>
    <p id="pose-timing"></p>
    <div id="pose-overlaps"></div>`;

  view.drawOverlay = (pen) => {
    const ratio = window.devicePixelRatio || 1;
    pen.lineWidth = 2 * ratio;
    project.joints.forEach((joint, i) => {
      if (joint.parent < 0) return;
      const [px, py] = positions[joint.parent];
      const [rx, ry] = [rest[i][0] - rest[joint.parent][0], rest[i][1] - rest[joint.parent][1]];
      line(pen, view.toCanvas([px, py]), view.toCanvas([px + rx, py + ry]), "rgba(220, 40, 40, 0.8)");
      line(pen, view.toCanvas([px, py]), view.toCanvas(positions[i]), "rgba(20, 20, 20, 0.9)");
    });
    positions.forEach((p, i) => {
      const [x, y] = view.toCanvas(p);
      pen.beginPath();
      pen.arc(x, y, HANDLE * ratio, 0, 2 * Math.PI);
      pen.fillStyle = i === dragging ? "#f6ad55" : "#fff";
      pen.fill();
      pen.strokeStyle = "#222";
      pen.stroke();
    });
  };

  const send = newest(live, (reply) => {
    view.setVertices(reply.U);
    document.getElementById("pose-timing").textContent = `last update ${(performance.now() - started).toFixed(1)} ms`;
    showError("");
  }, (error) => showError(error.message));

  function posed() {
    started = performance.now();
    send({ type: "pose", positions: positions.map((p) => p.slice()) });
    view.draw();
  }

  const overlay = view.overlay;
  const down = (event) => {
    dragging = nearest(view, positions, event, HANDLE + 4);
    if (dragging < 0) return;
    overlay.setPointerCapture(event.pointerId);
    view.draw();
  };
  const move = (event) => {
    if (dragging < 0) return;
    positions[dragging] = view.toDrawing(event);
    posed();
  };
  const up = () => {
    if (dragging < 0) return;
    dragging = -1;
    view.draw();
    overlaps();
  };

  // Regions at the same depth that overlap in this pose: which is in front is undecided.
  async function overlaps() {
    const box = document.getElementById("pose-overlaps");
    try {
      const reply = await live.request({ type: "overlaps", positions });
      box.replaceChildren(...reply.pairs.map(({ a, b, area }) => {
        const p = document.createElement("p");
        p.className = "warning";
        p.textContent = `${a} and ${b} overlap at the same depth (${Math.round(area)} px²): ` +
          "bring one forward in the Regions panel.";
        return p;
      }));
    } catch (error) {
      showError(error.message);
    }
  }
  const unlisten = listen(overlay, { pointerdown: down, pointermove: move, pointerup: up, pointercancel: up });
  document.getElementById("pose-reset").onclick = () => {
    rest.forEach((p, i) => { positions[i] = p.slice(); });
    posed();
    overlaps();
  };
  status("drag a joint");
  posed();

  return {
    positions,
    unmount() {
      unlisten();
      view.drawOverlay = () => {};
    },
  };
}

function line(pen, [x0, y0], [x1, y1], colour) {
  pen.beginPath();
  pen.moveTo(x0, y0);
  pen.lineTo(x1, y1);
  pen.strokeStyle = colour;
  pen.stroke();
}
