// The Pose panel: drag a joint and the drawing follows live (needle model + joint-area solve on
// the server), or sketch the skeleton with strokes (mouse or pen) and the server matches them to
// the bones (thesis 6.2a). The rest bones are shown as red reference lines from each posed
// parent (fig. 6.2a). While a reply is awaited, newer drags replace the queued pose, so the
// drawing keeps up with the pointer instead of falling behind it.

import { listen, nearest, newest } from "./panel_kit.js";

export const name = "pose";
export const title = "Pose";

const HANDLE = 7; // joint handle radius, CSS pixels
const SKETCH_PAUSE = 900; // ms after the last stroke before a sketch is matched

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const rest = project.joints.map((j) => j.position.slice());
  // The pose being made, shared with the other panels (the Timeline keys it).
  ctx.pose = ctx.pose || rest.map((p) => p.slice());
  const positions = ctx.pose;
  let dragging = -1, started = 0, mode = "drag";
  const strokes = []; // the sketch being drawn: [{points: [[x, y], ...], widths: [...]}, ...]
  let drawing = null, pause = 0;

  side.innerHTML = `<h2>Pose</h2>
    <p role="radiogroup" aria-label="how to pose">
      <label><input type="radio" name="pose-mode" value="drag" checked> Drag joints <kbd>D</kbd></label><br>
      <label><input type="radio" name="pose-mode" value="sketch"> Sketch the skeleton <kbd>S</kbd></label></p>
    <p id="pose-help">Drag a joint: the drawing follows. Red lines are the rest bones, from each posed parent.</p>
    <p id="pose-matched"></p>
    <p><button id="pose-reset">Reset to the rest pose</button></p>
    <p id="pose-timing"></p>
    <div id="pose-overlaps"></div>`;

  view.drawOverlay = (pen) => {
    const ratio = window.devicePixelRatio || 1;
    pen.lineCap = "round";
    for (const stroke of drawing ? [...strokes, drawing] : strokes) {
      for (let i = 1; i < stroke.points.length; i++) {
        pen.lineWidth = stroke.widths[i] * ratio;
        line(pen, view.toCanvas(stroke.points[i - 1]), view.toCanvas(stroke.points[i]), "rgba(30, 60, 140, 0.85)");
      }
    }
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

  // Sketching: each stroke's points in drawing pixels; a pen's pressure sets the line's width.
  // The strokes are matched once the pen has rested SKETCH_PAUSE ms (or on Enter), so a whole
  // stick figure can be drawn stroke by stroke.
  function width(event) {
    return event.pointerType === "pen" && event.pressure > 0 ? 1 + 5 * event.pressure : 3;
  }
  async function match() {
    clearTimeout(pause);
    if (!strokes.length) return;
    const sent = strokes.splice(0).map((stroke) => stroke.points);
    status("matching the sketch…");
    try {
      const reply = await live.request({ type: "sketch", strokes: sent, positions });
      reply.positions.forEach((p, i) => { positions[i] = p; });
      view.setVertices(reply.U);
      document.getElementById("pose-matched").textContent =
        `Sketched ${reply.bones.join(", ")}${reply.elsewhere ? " (drawn beside the figure: scaled to it)" : ""}.`;
      showError("");
      status("sketch matched");
      overlaps();
    } catch (error) {
      showError(error.message);
      status("");
      view.draw();
    }
  }
  function setMode(next) {
    mode = next;
    for (const input of side.querySelectorAll("input[name=pose-mode]")) input.checked = input.value === mode;
    document.getElementById("pose-help").textContent = mode === "sketch"
      ? "Draw bones, chains or a whole stick figure, over the drawing or beside it: a corner is a joint. " +
        "Strokes are matched when you pause (Enter: now, Escape: drop them)."
      : "Drag a joint: the drawing follows. Red lines are the rest bones, from each posed parent.";
    strokes.length = 0;
    drawing = null;
    view.draw();
  }
  for (const input of side.querySelectorAll("input[name=pose-mode]")) input.onchange = () => setMode(input.value);

  const overlay = view.overlay;
  const down = (event) => {
    if (mode === "sketch") {
      clearTimeout(pause);
      drawing = { points: [view.toDrawing(event)], widths: [width(event)] };
      overlay.setPointerCapture(event.pointerId);
      return;
    }
    dragging = nearest(view, positions, event, HANDLE + 4);
    if (dragging < 0) return;
    overlay.setPointerCapture(event.pointerId);
    view.draw();
  };
  const move = (event) => {
    if (drawing) {
      const events = event.getCoalescedEvents ? event.getCoalescedEvents() : [event];
      for (const e of events.length ? events : [event]) {
        drawing.points.push(view.toDrawing(e));
        drawing.widths.push(width(e));
      }
      view.draw();
      return;
    }
    if (dragging < 0) return;
    positions[dragging] = view.toDrawing(event);
    posed();
  };
  const up = () => {
    if (drawing) {
      if (drawing.points.length > 1) strokes.push(drawing);
      drawing = null;
      pause = setTimeout(match, SKETCH_PAUSE);
      view.draw();
      return;
    }
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
  const keys = (event) => {
    if (event.target instanceof HTMLInputElement && event.target.type !== "radio") return;
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    const key = event.key.toLowerCase();
    if (key === "s") setMode("sketch");
    else if (key === "d") setMode("drag");
    else if (key === "enter" && mode === "sketch") match();
    else if (key === "escape" && mode === "sketch") setMode("sketch");
  };
  const unlisten = [listen(overlay, { pointerdown: down, pointermove: move, pointerup: up, pointercancel: up }),
                    listen(window, { keydown: keys })];
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
      for (const off of unlisten) off();
      clearTimeout(pause);
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
