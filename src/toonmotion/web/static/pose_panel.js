// The Pose panel. Four ways to pose, each a mode (and a key):
//  D  drag a joint and the drawing follows live (needle model + joint-area solve on the server):
//     its bone turns and carries the joints below (FK), or with I the bones above it reach for the
//     pointer (IK, stopping at a pinned joint: double-click one to pin it); Shift stretches the
//     bone instead. The server makes the pose (toonmotion.api.drag_joint), from the pose at the press;
//  S  sketch the skeleton with strokes (mouse or pen): the server matches them to the bones
//     (thesis 6.2a);
//  T  tune the outline with a sketch curve (thesis 3.5, fig. 3.11);
//  P  drag points of the drawing itself (fig. 3.12b).
// The rest bones are red reference lines from each posed parent (fig. 6.2a). Fine-tuning edits
// belong to the pose being made (ctx.tuning) and are keyed with it in the Timeline. While a
// reply is awaited, newer drags replace the queued pose, so the drawing keeps up with the
// pointer instead of falling behind it.

import { capture, element, listen, nearest, newest } from "./panel_kit.js";

export const name = "pose";
export const title = "Pose";

const HANDLE = 7; // joint handle radius, CSS pixels
const SKETCH_PAUSE = 900; // ms after the last stroke before a sketch is matched
const MODES = {
  drag: ["Drag joints", "d", "Drag a joint: its bone turns and the joints below follow (or, reaching, the bones " +
         "above it bend). Shift-drag stretches the bone. Double-click a joint to pin it. Red lines are the rest " +
         "bones, from each posed parent."],
  sketch: ["Sketch the skeleton", "s", "Draw bones, chains or a whole stick figure, over the drawing or beside it: a " +
           "corner is a joint. Strokes are matched when you pause (Enter: now, Escape: drop them)."],
  tune: ["Tune the outline", "t", "Draw a curve beside the outline: the stretch of outline between the points " +
         "nearest its ends moves onto it."],
  points: ["Drag points", "p", "Drag any point of the drawing (a face, a tuft of hair): its neighbourhood follows."],
};

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  const rest = project.joints.map((j) => j.position.slice());
  // The pose being made and its fine-tuning, shared with the other panels (the Timeline keys them).
  ctx.pose = ctx.pose || rest.map((p) => p.slice());
  ctx.tuning = ctx.tuning || [];
  const positions = ctx.pose;
  ctx.pinned = ctx.pinned || new Set(); // joints (names) an IK reach stops at
  ctx.reach = ctx.reach || false; // a drag reaches with the bones above (IK) instead of turning one (FK)
  let dragging = -1, started = 0, mode = "drag";
  let pressed = null, generation = 0; // the pose at the press a drag is made from; which drag is current
  const strokes = []; // the sketch being drawn: [{points: [[x, y], ...], widths: [...]}, ...]
  let drawing = null, pause = 0, pulled = null;

  side.innerHTML = `<h2>Pose</h2>
    <p role="radiogroup" aria-label="how to pose">${Object.entries(MODES).map(([value, [label, key]]) =>
      `<label><input type="radio" name="pose-mode" value="${value}"> ${label} <kbd>${key.toUpperCase()}</kbd></label>`)
      .join("<br>")}</p>
    <p id="pose-help"></p>
    <p id="pose-bones" role="radiogroup" aria-label="what a dragged joint does">
      <label><input type="radio" name="pose-bones" value="turn"> turn its bone (FK)</label><br>
      <label><input type="radio" name="pose-bones" value="reach"> reach with the bones above (IK) <kbd>I</kbd></label></p>
    <p id="pose-matched"></p>
    <p id="pose-tuning"></p>
    <p><button id="pose-untune">Drop the last tuning</button>
       <button id="pose-reset">Reset to the rest pose</button></p>
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
    if (mode !== "drag" && mode !== "sketch") return; // the handles would hide the outline
    positions.forEach((p, i) => {
      const [x, y] = view.toCanvas(p);
      pen.beginPath();
      pen.arc(x, y, HANDLE * ratio, 0, 2 * Math.PI);
      pen.fillStyle = i === dragging ? "#f6ad55" : ctx.pinned.has(project.joints[i].name) ? "#3182ce" : "#fff";
      pen.fill();
      pen.strokeStyle = "#222";
      pen.stroke();
    });
  };

  const send = newest(live, (reply, message) => {
    // A drag's reply is the pose it made, unless the pose was changed since (reset, another drag).
    if (reply.positions && message.type === "drag" && message.generation === generation) {
      reply.positions.forEach((p, i) => { positions[i] = p; });
      made();
      view.draw();
    }
    view.showDeformed(reply.U);
    document.getElementById("pose-timing").textContent = `last update ${(performance.now() - started).toFixed(1)} ms`;
    showError("");
  }, (error) => showError(error.message));

  // The pose was changed here: it is the frame's pose made and not keyed, kept over a reload and
  // while the Timeline shows other frames, until it is keyed.
  function made() {
    ctx.unkeyed = { frame: ctx.frame || 0, pose: positions.map((p) => p.slice()), tuning: structuredClone(ctx.tuning) };
    if (ctx.remember) ctx.remember();
  }

  // The pose with its tuning (and a drag of points under way) sent to be deformed; ``changed``:
  // by the animator (not the panel opening on it).
  function posed(changed = true) {
    if (changed && !pulled) made();
    started = performance.now();
    const edits = pulled ? [...ctx.tuning, pulled] : ctx.tuning;
    send({ type: "pose", positions: positions.map((p) => p.slice()), edits });
    showTuning();
    view.draw();
  }

  // The joint under the pointer dragged to it, from the pose at the press.
  function dragged(event) {
    started = performance.now();
    send({ type: "drag", positions: pressed, joint: project.joints[dragging].name, to: view.toDrawing(event),
           mode: event.shiftKey ? "stretch" : ctx.reach ? "reach" : "turn", pinned: [...ctx.pinned],
           edits: ctx.tuning, generation });
  }

  function setReach(reach) {
    ctx.reach = reach;
    for (const input of side.querySelectorAll("input[name=pose-bones]")) input.checked = (input.value === "reach") === reach;
  }
  for (const input of side.querySelectorAll("input[name=pose-bones]")) input.onchange = () => setReach(input.value === "reach");

  function showTuning() {
    const count = ctx.tuning.length;
    document.getElementById("pose-tuning").textContent = count
      ? `${count} fine-tuning edit${count === 1 ? "" : "s"} on this pose (keyed with it).` : "";
    element("pose-untune", HTMLButtonElement).disabled = count === 0;
  }

  // Sketching: each stroke's points in drawing pixels; a pen's pressure sets the line's width,
  // and its tilt widens it as a pencil laid on its side does. The strokes are matched once the
  // pen has rested SKETCH_PAUSE ms (or on Enter), so a whole stick figure can be drawn stroke by
  // stroke.
  function width(event) {
    if (event.pointerType !== "pen" || !(event.pressure > 0)) return 3;
    const tilt = Math.min(1, Math.hypot(event.tiltX || 0, event.tiltY || 0) / 90);
    return (1 + 5 * event.pressure) * (1 + tilt);
  }
  async function match() {
    clearTimeout(pause);
    if (!strokes.length) return;
    const sent = strokes.splice(0).map((stroke) => stroke.points);
    status("matching the sketch…");
    try {
      const reply = await live.request({ type: "sketch", strokes: sent, positions });
      generation++; // a drag's reply still to come is not this pose
      reply.positions.forEach((p, i) => { positions[i] = p; });
      view.showDeformed(reply.U);
      document.getElementById("pose-matched").textContent =
        `Sketched ${reply.bones.join(", ")}${reply.elsewhere ? " (drawn beside the figure: scaled to it)" : ""}.`;
      made();
      showError("");
      status("sketch matched");
      if (ctx.tuning.length) posed();
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
    document.getElementById("pose-help").textContent = MODES[mode][2];
    strokes.length = 0;
    drawing = null;
    view.draw();
  }
  for (const input of side.querySelectorAll("input[name=pose-mode]")) input.onchange = () => setMode(input.value);

  const overlay = view.overlay;
  const down = (event) => {
    if (mode === "sketch" || mode === "tune") {
      clearTimeout(pause);
      drawing = { points: [view.toDrawing(event)], widths: [width(event)] };
      capture(overlay, event);
      return;
    }
    if (mode === "points") {
      const at = view.toDrawing(event);
      pulled = { kind: "drag", from: [at], to: [at] };
      capture(overlay, event);
      return;
    }
    dragging = nearest(view, positions, event, HANDLE + 4);
    if (dragging < 0) return;
    pressed = positions.map((p) => p.slice());
    generation++;
    capture(overlay, event);
    view.draw();
  };
  const pin = (event) => { // double-click: pin or unpin the joint under the pointer
    if (mode !== "drag") return;
    const at = nearest(view, positions, event, HANDLE + 4);
    if (at < 0) return;
    const joint = project.joints[at].name;
    if (!ctx.pinned.delete(joint)) ctx.pinned.add(joint);
    status(ctx.pinned.size ? `pinned: ${[...ctx.pinned].join(", ")}` : "no joint pinned");
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
    if (pulled) {
      pulled.to = [view.toDrawing(event)];
      posed();
      return;
    }
    if (dragging < 0) return;
    dragged(event);
  };
  const up = () => {
    if (drawing) {
      const stroke = drawing;
      drawing = null;
      if (mode === "tune") {
        if (stroke.points.length > 1) {
          ctx.tuning.push({ kind: "curve", points: stroke.points });
          posed();
        }
        return;
      }
      if (stroke.points.length > 1) strokes.push(stroke);
      ctx.lastStroke = stroke; // for tests and the console
      pause = setTimeout(match, SKETCH_PAUSE);
      view.draw();
      return;
    }
    if (pulled) {
      const [[x0, y0]] = pulled.from, [[x1, y1]] = pulled.to;
      if (Math.hypot(x1 - x0, y1 - y0) > 0.5) ctx.tuning.push(pulled); // a click moves nothing
      pulled = null;
      posed();
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
    const chosen = Object.entries(MODES).find(([, [, shortcut]]) => shortcut === key);
    if (chosen) setMode(chosen[0]);
    else if (key === "i") setReach(!ctx.reach);
    else if (key === "enter" && mode === "sketch") match();
    else if (key === "escape" && mode === "sketch") setMode("sketch");
  };
  const unlisten = [listen(overlay, { pointerdown: down, pointermove: move, pointerup: up, pointercancel: up,
                                      dblclick: pin }),
                    listen(window, { keydown: keys })];
  element("pose-reset", HTMLButtonElement).onclick = () => {
    generation++; // a drag's reply still to come is not this pose
    rest.forEach((p, i) => { positions[i] = p.slice(); });
    ctx.tuning.length = 0;
    posed();
    overlaps();
  };
  element("pose-untune", HTMLButtonElement).onclick = () => {
    ctx.tuning.pop();
    posed();
  };
  setMode("drag");
  setReach(ctx.reach);
  status("drag a joint");
  posed(false);

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
