// The Capture panel (thesis ch. 4, 6.2c): send a video, a GIF or an animated PNG; place the
// character's joints on the figure in the first frame, where the joints suggested from the
// footage's curve skeleton (orange dots) draw them, and size their rectangles by dragging a
// corner (the rectangles are what is tracked; they start at the suggestions' size);
// track them with a progress bar; scrub the result, each joint coloured by how sure the tracker
// was (green sure, red unsure); drag a joint that went astray at any frame and track again from
// there (the frames before it are kept); then retarget the motion onto the character and play it.

import { element, hexOf, listen, nearest, rgbOf } from "./panel_kit.js";

export const name = "capture";
export const title = "Capture";

const HANDLE = 6, SNAP = 10, SIZE = 16; // CSS pixels; a rectangle's side in footage pixels

export function mount(ctx) {
  const { project, view, live, side, status, showError, token } = ctx;
  let footage = null, images = [], frame = 0, joints = [], tracked = null, dragging = -1, playing = false, timer = null;
  let resizing = -1; // the joint whose rectangle's corner is being dragged
  let corrected = {}; // joint name -> [x, y] at the current frame, to track again from

  side.innerHTML = `<h2>Capture</h2>
    <p><label>Footage <input id="capture-file" type="file" accept="video/*,.gif,.png,.apng,.webp"></label></p>
    <p><label>or a folder of frames <input id="capture-frames" type="file" webkitdirectory multiple></label></p>
    <p id="capture-info"></p>
    <p><input id="capture-scrub" type="range" min="0" max="0" value="0" style="width: 100%" aria-label="frame"></p>
    <p><label title="On a plain background the joints are matched only on the figure, and a hidden joint is put on it"><input id="capture-free" type="checkbox"> Leave the joints free of the figure</label><br>
      <label title="Once the clip is tracked, each joint's path is chosen again over the whole clip among the places its searches found; tick to keep each frame's own choice"><input id="capture-frame-by-frame" type="checkbox"> Keep each frame's own choice (no whole-clip pass)</label><br>
      <label title="Also track backwards from the last frame and choose each joint's path between the two ways: fewer joints lost for a stretch, in about twice the time"><input id="capture-both-ways" type="checkbox"> Track both ways (slower)</label><br>
      <label title="Footage larger than 1000 px is tracked halved until it fits, two to three times as fast, the joints given back in its own pixels; tick to track it at its own size"><input id="capture-full-resolution" type="checkbox"> Track large footage at full size (slower)</label><br>
      <label title="The flat colour the footage is drawn on, when its border does not show it: the joints are suggested on, and held to, the figure that differs from it"><input id="capture-paper" type="checkbox"> Drawn on</label> <input id="capture-paper-colour" type="color" value="#ffffff" aria-label="the colour the footage is drawn on"></p>
    <p><button id="capture-track" disabled>Track</button> <button id="capture-retrack" disabled>Track again from here</button>
      <button id="capture-play" disabled>Retarget and play</button></p>
    <p><progress id="capture-progress" max="1" value="0" hidden></progress>
      <button id="capture-cancel" hidden>Cancel</button></p>
    <p id="capture-poor" hidden></p>
    <p id="capture-notes" class="warning" hidden></p>
    <p>Drag the joints onto the figure in the first frame (they snap to the orange suggestions),
    drag a rectangle's corner to size it, then track.</p>`;

  // Footage pixels -> canvas pixels, fitting the frame in the stage.
  function fit() {
    const o = view.overlay, scale = Math.min(o.width / footage.width, o.height / footage.height) * 0.95;
    return { scale, x: (o.width - footage.width * scale) / 2, y: (o.height - footage.height * scale) / 2 };
  }
  const toCanvas = ([x, y]) => { const f = fit(); return [f.x + x * f.scale, f.y + y * f.scale]; };
  const fromEvent = (event) => {
    const box = view.overlay.getBoundingClientRect(), ratio = view.overlay.width / box.width, f = fit();
    return [((event.clientX - box.left) * ratio - f.x) / f.scale, ((event.clientY - box.top) * ratio - f.y) / f.scale];
  };
  const positions = () => {
    const P = tracked ? tracked.positions[Math.min(frame, tracked.positions.length - 1)] : joints.map((j) => j.position);
    return P.map((p, i) => corrected[joints[i].name] || p);
  };

  // The footage, the suggestions and the rectangles, over the stage (the character is hidden).
  const drawFootage = (pen) => {
    if (!footage) return;
    const f = fit(), image = images[frame];
    pen.fillStyle = "#fff";
    pen.fillRect(f.x, f.y, footage.width * f.scale, footage.height * f.scale);
    if (image && image.complete) pen.drawImage(image, f.x, f.y, footage.width * f.scale, footage.height * f.scale);
    const P = positions(), ratio = window.devicePixelRatio || 1;
    if (!tracked) {
      pen.fillStyle = "#dd6b20";
      for (const s of footage.joints) {
        pen.beginPath();
        pen.arc(...toCanvas(s.position), 3 * ratio, 0, 2 * Math.PI);
        pen.fill();
      }
    }
    joints.forEach((joint, i) => {
      const [x, y] = toCanvas(P[i]), [hw, hh] = [joint.size[0] * f.scale / 2, joint.size[1] * f.scale / 2];
      const sure = tracked ? tracked.confidence[Math.min(frame, tracked.confidence.length - 1)][i] : 1;
      pen.strokeStyle = `hsl(${Math.round(120 * sure)}, 80%, 40%)`;
      pen.lineWidth = 2 * ratio;
      pen.strokeRect(x - hw, y - hh, 2 * hw, 2 * hh);
      if (!tracked) {
        pen.fillStyle = pen.strokeStyle;
        pen.fillRect(x + hw - 3 * ratio, y + hh - 3 * ratio, 6 * ratio, 6 * ratio); // the corner to size it by
      }
      pen.beginPath();
      pen.arc(x, y, HANDLE * ratio * 0.6, 0, 2 * Math.PI);
      pen.fillStyle = pen.strokeStyle;
      pen.fill();
    });
  };

  view.drawOverlay = drawFootage;

  function show(at) {
    if (!playing) { // back to the footage, after playing the motion on the character
      view.drawOverlay = drawFootage;
      view.canvas.style.visibility = "hidden";
    }
    if (at !== frame) corrected = {};
    frame = at;
    element("capture-retrack", HTMLButtonElement).disabled = Object.keys(corrected).length === 0;
    element("capture-scrub", HTMLInputElement).value = String(at);
    document.getElementById("capture-info").textContent =
      `${footage.frames} frames of ${footage.width}×${footage.height} at ${Number(footage.fps.toFixed(2))} fps; frame ${at}`;
    if (!images[at]) {
      images[at] = new Image();
      images[at].onload = () => view.draw();
      images[at].src = `api/footage/${at}.png?token=${encodeURIComponent(token)}`;
    }
    view.draw();
  }

  async function put(url, file) {
    const reply = await fetch(url, { method: "PUT", body: file, headers: { "X-Toonmotion-Token": token } });
    const body = await reply.json().catch(() => ({ error: `${reply.status} ${reply.statusText}` }));
    if (!reply.ok) throw new Error(body.error);
    return body;
  }
  element("capture-file", HTMLInputElement).onchange = async (event) => {
    const file = /** @type {HTMLInputElement} */ (event.target).files[0];
    if (!file) return;
    const suffix = file.name.split(".").pop().toLowerCase();
    status("sending the footage…");
    try {
      loaded(await put(`api/footage?suffix=${encodeURIComponent(suffix)}&name=${encodeURIComponent(file.name)}`, file));
    } catch (error) {
      showError(error.message);
      status("");
    }
  };
  // A folder of frames: its images in name order (frame_2 before frame_10), sent one by one.
  element("capture-frames", HTMLInputElement).onchange = async (event) => {
    const files = [.../** @type {HTMLInputElement} */ (event.target).files].filter((f) => /\.(png|jpe?g|webp)$/i.test(f.name))
      .sort((a, b) => a.name.localeCompare(b.name, undefined, { numeric: true }));
    if (!files.length) return showError("the folder holds no PNG, JPEG or WebP frames");
    const bar = element("capture-progress", HTMLProgressElement);
    bar.hidden = false;
    bar.max = files.length;
    try {
      let reply = null;
      for (const [index, file] of files.entries()) {
        status(`sending frame ${index + 1} of ${files.length}…`);
        const suffix = file.name.split(".").pop().toLowerCase();
        reply = await put(`api/footage/frames/${index}?count=${files.length}&suffix=${suffix}`, file);
        bar.value = index + 1;
      }
      loaded(reply);
    } catch (error) {
      showError(error.message);
      status("");
    } finally {
      bar.hidden = true;
    }
  };

  // A map of the drawing's points onto the footage: the box round the drawing's figure (its
  // outline) into the box round the footage's first figure (centred, one scale); when the footage
  // gave none, the drawing scaled onto the frame.
  function onFigure() {
    if (!footage.figure) {
      const sx = footage.width / project.width, sy = footage.height / project.height;
      return ([x, y]) => [x * sx, y * sy];
    }
    const P = project.outline.flat();
    const [a0, b0] = [Math.min(...P.map((p) => p[0])), Math.min(...P.map((p) => p[1]))];
    const [a1, b1] = [Math.max(...P.map((p) => p[0])), Math.max(...P.map((p) => p[1]))];
    const [c0, d0, c1, d1] = footage.figure;
    const k = Math.min((c1 - c0) / Math.max(a1 - a0, 1e-9), (d1 - d0) / Math.max(b1 - b0, 1e-9));
    const [cx, cy, ax, ay] = [(c0 + c1) / 2, (d0 + d1) / 2, (a0 + a1) / 2, (b0 + b1) / 2];
    return ([x, y]) => [cx + (x - ax) * k, cy + (y - ay) * k];
  }

  function loaded(body, fresh = true) {
    if (fresh) project.capture = { footage: body, joints: null, tracked: null };
    footage = body;
    images = [];
    tracked = null;
    showPoorly([]);
    // The character's joints laid onto the figure in the footage (names that retarget by
    // themselves): the drawing's figure fitted into the footage's, centred, one scale, so they
    // start on the figure wherever it stands in the frame (scaling the drawing onto the whole frame
    // put them off a figure that does not fill it); their rectangles start at the suggested
    // joints' typical size.
    const place = onFigure();
    const sides = footage.joints.map((j) => j.size[0]).sort((a, b) => a - b);
    const side = sides.length ? Math.round(sides[Math.floor(sides.length / 2)]) : SIZE;
    joints = project.joints.map((j) => ({ name: j.name, parent: j.parent < 0 ? null : project.joints[j.parent].name,
                                           position: place(j.position), size: [side, side] }));
    element("capture-scrub", HTMLInputElement).max = String(footage.frames - 1);
    element("capture-track", HTMLButtonElement).disabled = false;
    show(0);
    status("place the joints on the first frame");
    showError("");
    if (paper()) suggestAgain(); // sent suggestions go by the border's colour
    else if (footage.border) { // show which colour the figure was told from
      element("capture-paper-colour", HTMLInputElement).value = hexOf(footage.border);
    }
  }

  element("capture-scrub", HTMLInputElement).oninput = (event) => show(Number(/** @type {HTMLInputElement} */ (event.target).value));

  async function trackFrom(message) {
    const bar = element("capture-progress", HTMLProgressElement), cancel = element("capture-cancel", HTMLButtonElement);
    bar.hidden = false;
    status("tracking…");
    const job = live.request(message, ({ index, count }) => { bar.max = count; bar.value = index; });
    cancel.hidden = false;
    cancel.onclick = () => { live.cancel(job.id); status("cancelling…"); };
    try {
      const reply = await job;
      project.capture = { ...project.capture, joints: JSON.parse(JSON.stringify(message.joints)), tracked: reply };
      finished(reply);
      showError("");
    } catch (error) {
      if (error.cancelled) {
        showError("");
        status(tracked ? "tracking cancelled: the earlier tracking is kept" : "tracking cancelled");
      } else {
        showError(error.message);
        status("");
      }
    } finally {
      bar.hidden = true;
      cancel.hidden = true;
    }
  }
  function finished(reply) {
    tracked = reply;
    // The motion lists the joints parents first: follow its order.
    joints = tracked.names.map((n) => joints.find((j) => j.name === n));
    corrected = {};
    element("capture-play", HTMLButtonElement).disabled = false;
    showPoorly(tracked.poorly);
    const notes = document.getElementById("capture-notes");
    notes.textContent = (tracked.notes || []).join(" ");
    notes.hidden = !notes.textContent;
    status("tracked: scrub to check it, then retarget");
    show(frame);
  }
  // The joints that matched poorly most (hidden, or their looks changed), each a button to the
  // frame where its longest such stretch starts: where to drag it right and track again from.
  function showPoorly(poorly) {
    const line = document.getElementById("capture-poor");
    line.replaceChildren();
    line.hidden = !poorly.length;
    if (!poorly.length) return;
    line.append("Matched poorly most (drag one right where it is lost, then track again from there): ");
    poorly.forEach(({ name, fraction, start, length }, i) => {
      const go = document.createElement("button");
      go.textContent = `${name}: ${Math.round(100 * fraction)}%, from frame ${start}`;
      go.title = `${name} matched poorly in ${Math.round(100 * fraction)}% of the frames; its longest stretch, ${length} frame${length > 1 ? "s" : ""}, starts at frame ${start}`;
      go.onclick = () => {
        element("capture-scrub", HTMLInputElement).value = String(start);
        show(start);
      };
      line.append(i ? " " : "", go);
    });
  }
  const paper = () => {
    if (!element("capture-paper", HTMLInputElement).checked) return null;
    return rgbOf(element("capture-paper-colour", HTMLInputElement).value);
  };
  element("capture-paper-colour", HTMLInputElement).addEventListener("input", () => {
    element("capture-paper", HTMLInputElement).checked = true; // picking a colour means it
  });
  // The orange suggestions follow the colour the footage is drawn on (once it is picked).
  async function suggestAgain() {
    if (!footage) return;
    const background = paper(), asked = footage;
    try {
      const reply = await live.request({ type: "suggest", background });
      if (footage !== asked) return; // other footage was sent meanwhile: it came with its own
      footage.joints = reply.joints;
      const on = background ? element("capture-paper-colour", HTMLInputElement).value : "the border's colour";
      if (!tracked) status(`${reply.joints.length} joints suggested on the figure drawn on ${on}`);
      showError("");
      show(frame);
    } catch (error) {
      showError(error.message);
    }
  }
  element("capture-paper-colour", HTMLInputElement).addEventListener("change", suggestAgain);
  element("capture-paper", HTMLInputElement).addEventListener("change", suggestAgain);
  const how = () => ({ free: element("capture-free", HTMLInputElement).checked,
    frame_by_frame: element("capture-frame-by-frame", HTMLInputElement).checked,
    both_ways: element("capture-both-ways", HTMLInputElement).checked,
    full_resolution: element("capture-full-resolution", HTMLInputElement).checked, background: paper() });
  // Both ways is a choice of paths over the whole clip: it and "each frame's own choice" exclude each other.
  for (const [id, other] of [["capture-both-ways", "capture-frame-by-frame"], ["capture-frame-by-frame", "capture-both-ways"]]) {
    element(id, HTMLInputElement).addEventListener("change", (event) => {
      if (/** @type {HTMLInputElement} */ (event.target).checked) element(other, HTMLInputElement).checked = false;
    });
  }
  element("capture-track", HTMLButtonElement).onclick = () => { frame = 0; trackFrom({ type: "track", joints, ...how() }); };
  element("capture-retrack", HTMLButtonElement).onclick = () =>
    trackFrom({ type: "track", joints, at: frame, set: corrected, ...how() });

  element("capture-play", HTMLButtonElement).onclick = async () => {
    if (playing) return stop();
    try {
      const reply = await live.request({ type: "retarget" });
      view.canvas.style.visibility = "visible";
      view.drawOverlay = () => {};
      playing = true;
      element("capture-play", HTMLButtonElement).textContent = "Stop";
      let at = reply.first;
      const next = async () => {
        if (!playing) return;
        const started = performance.now();
        const shown = await live.request({ type: "frame", frame: at, source: "capture" });
        view.showDeformed(shown.U);
        at = at >= reply.last ? reply.first : at + 1;
        timer = setTimeout(next, Math.max(0, 1000 / reply.fps - (performance.now() - started)));
      };
      next();
      status("the character plays the captured motion");
    } catch (error) {
      showError(error.message);
    }
  };

  function stop() {
    playing = false;
    clearTimeout(timer);
    element("capture-play", HTMLButtonElement).textContent = "Retarget and play";
  }

  const unlisten = listen(view.overlay, {
    pointerdown: (event) => {
      if (!footage || playing) return;
      const place = { toCanvas, toDrawing: fromEvent };
      if (!tracked) {
        const corners = joints.map((j, i) => [positions()[i][0] + j.size[0] / 2, positions()[i][1] + j.size[1] / 2]);
        resizing = nearest(place, corners, event, HANDLE);
        if (resizing >= 0) return view.overlay.setPointerCapture(event.pointerId);
      }
      dragging = nearest(place, positions(), event, HANDLE + 6);
      if (dragging >= 0) view.overlay.setPointerCapture(event.pointerId);
    },
    pointermove: (event) => {
      if (resizing >= 0) {
        const [x, y] = fromEvent(event), [cx, cy] = joints[resizing].position;
        const most = Math.min(footage.width, footage.height);
        joints[resizing].size = [Math.min(most, Math.max(4, Math.round(2 * Math.abs(x - cx)))),
                                 Math.min(most, Math.max(4, Math.round(2 * Math.abs(y - cy))))];
        view.draw();
        return;
      }
      if (dragging < 0) return;
      if (tracked) {  // a correction at this frame
        corrected[joints[dragging].name] = fromEvent(event);
        element("capture-retrack", HTMLButtonElement).disabled = false;
      } else {  // placing: snap to a suggested joint nearby
        const s = nearest({ toCanvas, toDrawing: fromEvent }, footage.joints.map((j) => j.position), event, SNAP);
        joints[dragging].position = s >= 0 ? footage.joints[s].position.slice() : fromEvent(event);
      }
      view.draw();
    },
    pointerup: () => { dragging = -1; resizing = -1; },
  });
  // The joints, the suggestions, and where a joint is on the screen at the current frame (for
  // the console and tests).
  ctx.capture = {
    joints: () => joints,
    suggestions: () => (footage ? footage.joints : []),
    screen(name) {
      const i = joints.findIndex((j) => j.name === name), [x, y] = toCanvas(positions()[i]);
      const box = view.overlay.getBoundingClientRect(), k = box.width / view.overlay.width;
      return [box.left + x * k, box.top + y * k];
    },
  };
  // Back from another panel, or after a reload: the footage and its tracking as they were left.
  const saved = project.capture;
  if (saved && saved.footage) {
    loaded(saved.footage, false);
    if (saved.joints) joints = JSON.parse(JSON.stringify(saved.joints));
    if (saved.tracked) finished(saved.tracked);
  } else {
    status("send footage to capture from");
    view.draw(); // clear the last panel's handles off the stage
  }

  return {
    unmount() {
      stop();
      unlisten();
      view.canvas.style.visibility = "visible";
      view.drawOverlay = () => {};
      view.draw(); // clear the footage off the overlay
    },
  };
}
