// The Timeline panel: key-frames on a frame ruler along the bottom of the stage. "Key this
// frame" (K) keys the pose made in the Pose panel at the current frame; keys are moved by
// dragging their diamonds on the ruler (or typing a frame), copied to the current frame (a hold,
// or a return to a pose) and deleted; clicking or dragging on the ruler scrubs through the
// in-betweens (← and → step), and Play (Space) plays them at the animation's frame rate. Every
// change is saved in the project folder's keys.json at once (the file `toonmotion animate
// PROJECT PROJECT/keys.json` reads). Scrubbing to a frame also makes its pose the Pose panel's,
// to adjust and key again.

import { element, listen } from "./panel_kit.js";

const RULER = 44; // the ruler's height, CSS pixels

export const name = "timeline";
export const title = "Timeline";

export function mount(ctx) {
  const { project, view, live, side, status, showError } = ctx;
  let playing = false, timer = null;
  ctx.frame = ctx.frame || 0; // the current frame, kept while other panels are open

  side.innerHTML = `<h2>Timeline</h2>
    <p><input id="timeline-scrub" type="range" min="0" value="0" style="width: 100%"
       aria-label="frame"> frame <output id="timeline-frame">0</output></p>
    <p><button id="timeline-key">Key this frame</button> <button id="timeline-play">Play</button></p>
    <p id="timeline-scene-row" hidden><label title="The frames the 3D panel composited, its simulated elements in them"><input id="timeline-scene" type="checkbox"> Show the 3D scene</label></p>
    <p><label>Rate <input id="timeline-fps" type="number" min="0.01" max="1000" step="1" style="width: 4em">
      fps</label> <label>Easing <select id="timeline-ease"><option>linear</option><option>in-out</option>
      <option>in</option><option>out</option></select></label></p>
    <p id="timeline-source" hidden></p>
    <ol id="timeline-keys"></ol>
    <p>Make the pose in the Pose panel, then key it here. On the ruler below the drawing, drag a
    key's diamond to move it, click to go to a frame.</p>
    <p><kbd>K</kbd> key this frame, <kbd>←</kbd> <kbd>→</kbd> step, <kbd>Space</kbd> play,
    <kbd>Delete</kbd> delete this frame's key.</p>`;
  const scrub = element("timeline-scrub", HTMLInputElement);
  const ruler = document.createElement("canvas");
  ruler.id = "timeline-ruler";
  ruler.className = "ruler";
  ruler.setAttribute("aria-label", "frame ruler: drag a key to move it, click to go to a frame");
  document.getElementById("stage").append(ruler);

  // Another motion to play instead of the key-frames' (ctx.playSource, the Key-shapes panel's
  // retargeted motion: {source, first, last, fps, file}), until "Back to the key-frames".
  const played = () => ctx.playSource || null;
  function showSource() {
    const line = document.getElementById("timeline-source"), source = played();
    line.hidden = !source;
    offerScene();
    view.canvas.style.visibility = sceneBox.checked && project.scene && !source ? "hidden" : "";
    line.replaceChildren();
    if (!source) return;
    const back = document.createElement("button");
    back.textContent = "Back to the key-frames";
    back.onclick = () => { stop(); ctx.playSource = null; showSource(); showKeys(); show(ctx.frame).catch((error) => showError(error.message)); };
    line.append(`Playing the key-shape retarget (${source.file}), frames ${source.first} to ${source.last}. `, back);
  }

  function lastFrame() {
    if (played()) return played().last;
    const keys = project.keys ? project.keys.keys : [];
    return keys.length ? keys[keys.length - 1].frame : 0;
  }

  function showKeys() {
    const list = document.getElementById("timeline-keys");
    list.replaceChildren();
    for (const key of project.keys ? project.keys.keys : []) {
      const item = document.createElement("li");
      item.dataset.frame = key.frame;
      item.innerHTML = `key at frame <input type="number" min="0" value="${key.frame}" style="width: 5em"
        aria-label="move to frame"> <button class="copy">Copy here</button> <button class="delete">Delete</button>`;
      item.querySelector("input").onchange = (event) =>
        change({ type: "move_key", frame: key.frame, to: Number(/** @type {HTMLInputElement} */ (event.target).value) });
      const copy = /** @type {HTMLButtonElement} */ (item.querySelector(".copy"));
      copy.title = "Key this pose again at the current frame";
      copy.onclick = () => change({ type: "set_key", frame: ctx.frame, positions: key.positions, edits: key.edits });
      /** @type {HTMLButtonElement} */ (item.querySelector(".delete")).onclick =
        () => change({ type: "delete_key", frame: key.frame });
      list.append(item);
    }
    scrub.max = String(span());
    drawRuler();
    if (project.keys) {
      element("timeline-fps", HTMLInputElement).value = project.keys.fps;
      element("timeline-ease", HTMLSelectElement).value = project.keys.ease;
    }
  }

  // The 3D panel's scene, when one was made from these key-frames: its composited frame at the
  // current frame, fitted to the stage, in place of the drawing.
  const sceneBox = element("timeline-scene", HTMLInputElement), sceneImages = {};
  const offerScene = () => { // not while another motion plays: the scene is the key-frames'
    element("timeline-scene-row", HTMLParagraphElement).hidden = !project.scene || !!played();
  };
  function sceneFrame(pen) {
    // The scene's frames are the animation's, from the first key to the last.
    const first = project.keys ? project.keys.keys[0].frame : 0, scene = project.scene;
    const at = Math.max(0, Math.min(ctx.frame - first, scene.frames - 1)), key = `${scene.made}/${at}`;
    if (!sceneImages[key]) {
      sceneImages[key] = new Image();
      sceneImages[key].onload = () => view.draw();
      sceneImages[key].src = `api/scene/${at}.png?token=${encodeURIComponent(ctx.token)}&v=${scene.made}`;
    }
    const image = sceneImages[key], o = view.overlay;
    pen.fillStyle = "#f4f3f0";
    pen.fillRect(0, 0, o.width, o.height);
    if (!image.complete || !image.naturalWidth) return;
    const k = Math.min(o.width / image.naturalWidth, (o.height - RULER * (window.devicePixelRatio || 1)) / image.naturalHeight);
    pen.drawImage(image, (o.width - image.naturalWidth * k) / 2, 0, image.naturalWidth * k, image.naturalHeight * k);
  }
  sceneBox.onchange = () => {
    view.canvas.style.visibility = sceneBox.checked ? "hidden" : "";
    view.draw();
  };

  // Onion skin: the keys either side of the current frame, as faint skeletons.
  view.drawOverlay = (pen) => {
    if (sceneBox.checked && project.scene && !played()) return sceneFrame(pen);
    const keys = project.keys ? project.keys.keys : [];
    const before = keys.filter((k) => k.frame < ctx.frame).pop(), after = keys.find((k) => k.frame > ctx.frame);
    pen.lineWidth = 2 * (window.devicePixelRatio || 1);
    for (const [key, colour] of [[before, "rgba(49, 130, 206, 0.45)"], [after, "rgba(221, 107, 32, 0.45)"]]) {
      if (!key) continue;
      pen.strokeStyle = colour;
      project.joints.forEach((joint, i) => {
        if (joint.parent < 0) return;
        pen.beginPath();
        pen.moveTo(...view.toCanvas(key.positions[joint.parent]));
        pen.lineTo(...view.toCanvas(key.positions[i]));
        pen.stroke();
      });
    }
  };

  async function change(message) {
    try {
      const reply = await live.request(message);
      project.keys = reply.keys;
      if (message.type === "set_key" && ctx.unkeyed && ctx.unkeyed.frame === message.frame) {
        ctx.unkeyed = null; // keyed now
        if (ctx.remember) ctx.remember();
      }
      showKeys();
      showError("");
      status("saved");
      if (project.keys) await show(ctx.frame);
    } catch (error) {
      showError(error.message);
      showKeys();
    }
  }

  // The frames the ruler shows: past the last key and the current frame by 12, so that stepping
  // right (or dragging a key right) always finds frames beyond (it ended 12 past the last key).
  function span() {
    return Math.max(24, lastFrame() + 12, ctx.frame + 12);
  }

  function mark(at) {
    ctx.frame = at;
    scrub.max = String(span());
    scrub.value = String(at);
    element("timeline-frame", HTMLOutputElement).textContent = String(at);
    drawRuler();
  }

  // The ruler: a tick per frame (labelled every 6th), a diamond per key, the current frame's
  // line; a key being dragged is drawn where it would land.
  let held = null; // {from, to}: a key being dragged
  function frameX(frame) {
    const span = Number(scrub.max), inset = 14;
    return inset + (frame / span) * (ruler.clientWidth - 2 * inset);
  }
  function frameAt(event) {
    const box = ruler.getBoundingClientRect(), span = Number(scrub.max), inset = 14;
    return Math.max(0, Math.min(span, Math.round(((event.clientX - box.left - inset) / (box.width - 2 * inset)) * span)));
  }
  function drawRuler() {
    const ratio = window.devicePixelRatio || 1;
    ruler.width = Math.round(ruler.clientWidth * ratio);
    ruler.height = Math.round(RULER * ratio);
    const pen = ruler.getContext("2d");
    pen.scale(ratio, ratio);
    pen.fillStyle = "rgba(255, 255, 255, 0.92)";
    pen.fillRect(0, 0, ruler.clientWidth, RULER);
    pen.strokeStyle = "#999";
    pen.fillStyle = "#555";
    pen.font = "10px system-ui, sans-serif";
    for (let f = 0; f <= Number(scrub.max); f++) {
      const x = frameX(f), labelled = f % 6 === 0;
      pen.beginPath();
      pen.moveTo(x, 0);
      pen.lineTo(x, labelled ? 10 : 5);
      pen.stroke();
      if (labelled) pen.fillText(String(f), x - 3, 21);
    }
    for (const key of project.keys ? project.keys.keys : []) {
      const frame = held && held.from === key.frame ? held.to : key.frame;
      diamond(pen, frameX(frame), 32, held && held.from === key.frame ? "#dd6b20" : "#2b6cb0");
    }
    pen.strokeStyle = "#c53030";
    pen.lineWidth = 2;
    pen.beginPath();
    pen.moveTo(frameX(ctx.frame), 0);
    pen.lineTo(frameX(ctx.frame), RULER);
    pen.stroke();
  }
  const rulerDown = (event) => {
    const at = frameAt(event);
    const key = (project.keys ? project.keys.keys : []).find((k) => Math.abs(frameX(k.frame) - frameX(at)) < 6
                                                            && event.offsetY > 22);
    ruler.setPointerCapture(event.pointerId);
    if (key) {
      held = { from: key.frame, to: key.frame };
      drawRuler();
    } else {
      held = null;
      show(at).catch((error) => showError(error.message));
    }
    ruler.dataset.down = "1";
  };
  const rulerMove = (event) => {
    if (!ruler.dataset.down) return;
    if (held) {
      held.to = frameAt(event);
      drawRuler();
    } else if (frameAt(event) !== ctx.frame) {
      show(frameAt(event)).catch((error) => showError(error.message));
    }
  };
  const rulerUp = () => {
    delete ruler.dataset.down;
    if (!held) return;
    const { from, to } = held;
    held = null;
    if (to !== from) change({ type: "move_key", frame: from, to });
    else drawRuler();
  };
  const keyboard = (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey || event.target instanceof HTMLInputElement
        || event.target instanceof HTMLSelectElement) return;
    if (event.key === "ArrowLeft" || event.key === "ArrowRight") {
      event.preventDefault();
      const next = Math.max(0, ctx.frame + (event.key === "ArrowLeft" ? -1 : 1)); // the ruler grows to the right
      show(next).catch((error) => showError(error.message));
    } else if (event.key.toLowerCase() === "k") {
      element("timeline-key", HTMLButtonElement).click();
    } else if (event.key === " " && !(event.target instanceof HTMLButtonElement)) { // a button takes its own
      event.preventDefault();
      element("timeline-play", HTMLButtonElement).click();
    } else if (event.key === "Delete" && project.keys && project.keys.keys.some((k) => k.frame === ctx.frame)) {
      change({ type: "delete_key", frame: ctx.frame });
    }
  };
  const unlisten = [listen(ruler, { pointerdown: rulerDown, pointermove: rulerMove, pointerup: rulerUp,
                                    pointercancel: rulerUp }),
                    listen(window, { keydown: keyboard, resize: drawRuler })];

  // Frame ``at``: the animation's pose there, or the pose made there and not keyed yet (which
  // scrubbing keeps, and says so, instead of dropping it).
  async function show(at) {
    mark(at);
    const unkeyed = ctx.unkeyed;
    if (unkeyed && unkeyed.frame === at) {
      ctx.pose = unkeyed.pose.map((p) => p.slice());
      ctx.tuning = structuredClone(unkeyed.tuning || []);
      const reply = await live.request({ type: "pose", positions: ctx.pose, edits: ctx.tuning });
      view.showDeformed(reply.U);
      status(`the pose made at frame ${at}, not keyed yet (K keys it)`);
      return;
    }
    if (unkeyed) status(`the pose made at frame ${unkeyed.frame} is not keyed: it is kept there (K keys it)`);
    if (!project.keys && !played()) return;
    const reply = await live.request({ type: "frame", frame: at, ...(played() ? { source: played().source } : {}) });
    const key = project.keys && !played() ? project.keys.keys.find((k) => k.frame === reply.frame) : undefined;
    ctx.pose = reply.positions;
    ctx.tuning = key ? structuredClone(key.edits) : []; // a key's fine-tuning, to adjust and key again
    view.showDeformed(reply.U);
  }

  async function play() {
    if ((!project.keys && !played()) || playing) return;
    playing = true;
    element("timeline-play", HTMLButtonElement).textContent = "Stop";
    const keys = project.keys ? project.keys.keys : [];
    const first = played() ? played().first : keys[0].frame, last = played() ? played().last : keys[keys.length - 1].frame;
    const step = 1000 / (played() ? played().fps : project.keys.fps);
    let at = first;
    const next = async () => {
      if (!playing) return;
      const started = performance.now();
      try {
        await show(at);
      } catch (error) {
        showError(error.message);
        return stop();
      }
      at = at >= last ? first : at + 1;
      timer = setTimeout(next, Math.max(0, step - (performance.now() - started)));
    };
    next();
  }

  function stop() {
    playing = false;
    clearTimeout(timer);
    element("timeline-play", HTMLButtonElement).textContent = "Play";
  }

  scrub.oninput = () => show(Number(scrub.value)).catch((error) => showError(error.message));
  element("timeline-key", HTMLButtonElement).onclick = () => {
    const positions = ctx.pose || project.joints.map((j) => j.position);
    change({ type: "set_key", frame: ctx.frame, positions, edits: ctx.tuning || [] });
  };
  element("timeline-play", HTMLButtonElement).onclick = () => (playing ? stop() : play());
  const timing = () => change({ type: "timing", fps: Number(element("timeline-fps", HTMLInputElement).value),
                                ease: element("timeline-ease", HTMLSelectElement).value });
  element("timeline-fps", HTMLInputElement).onchange = timing;
  element("timeline-ease", HTMLSelectElement).onchange = timing;
  showKeys();
  showSource();
  mark(ctx.frame); // the drawing stays as the Pose panel left it, to be keyed here
  status(played() ? "the key-shape retarget: scrub or play" : project.keys ? "scrub or play" : "key a pose to start");
  if (played()) show(ctx.frame).catch((error) => showError(error.message));

  return {
    unmount() {
      stop();
      for (const off of unlisten) off();
      ruler.remove();
      view.drawOverlay = () => {};
      view.canvas.style.visibility = "";
    },
  };
}

function diamond(pen, x, y, colour) {
  pen.beginPath();
  pen.moveTo(x, y - 7);
  pen.lineTo(x + 6, y);
  pen.lineTo(x, y + 7);
  pen.lineTo(x - 6, y);
  pen.closePath();
  pen.fillStyle = colour;
  pen.fill();
}
