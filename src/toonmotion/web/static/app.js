// The editor's shell: reads the token from the address, loads the project, opens the live
// connection, and mounts the panels. A panel is one module exporting {name, title, mount(ctx)};
// mount returns {unmount()}. Add a panel by importing it into PANELS.
import { MeshView } from "./mesh_view.js";
import { element, typingIn } from "./panel_kit.js";
import * as posePanel from "./pose_panel.js";
import * as rigPanel from "./rig_panel.js";
import * as regionsPanel from "./regions_panel.js";
import * as timelinePanel from "./timeline_panel.js";
import * as exaggeratePanel from "./exaggerate_panel.js";
import * as exportPanel from "./export_panel.js";
import * as capturePanel from "./capture_panel.js";
import * as proxyPanel from "./proxy_panel.js";
import * as keyshapesPanel from "./keyshapes_panel.js";

const PANELS = [posePanel, rigPanel, regionsPanel, timelinePanel, exaggeratePanel, capturePanel, proxyPanel, exportPanel,
                keyshapesPanel];

const token = new URLSearchParams(location.search).get("token") || "";

export function showError(message) {
  const box = document.getElementById("error");
  box.textContent = message;
  box.hidden = !message;
}

// The message stays until something works again, or until it is clicked away.
document.getElementById("error").title = "click to dismiss";
document.getElementById("error").addEventListener("click", () => showError(""));

function status(text) {
  const line = document.getElementById("status");
  line.textContent = text;
  line.title = text; // in full, when it is cut short
}

async function getJSON(path) {
  const reply = await fetch(path, { headers: { "X-Toonmotion-Token": token } });
  const body = await reply.json().catch(() => ({ error: `${reply.status} ${reply.statusText}` }));
  if (!reply.ok) throw new Error(body.error || `${reply.status} ${reply.statusText}`);
  return body;
}

function loadImage(src) {
  return new Promise((resolve, reject) => {
    const image = new Image();
    image.onload = () => resolve(image);
    image.onerror = () => reject(new Error("the drawing could not be loaded"));
    image.src = src;
  });
}

// The live connection: request(message, onProgress) resolves with the server's reply to it.
// Replies carry the id of the message they answer; an error reply rejects; progress messages
// on the way go to onProgress. A slow request (tracking, an export) can be stopped with
// cancel(reply.id): it then rejects with an error whose .cancelled is true.
class Live {
  constructor(url) {
    this.next = 1;
    this.waiting = new Map();
    /** @type {((note: any) => void) | null} another page changed the project */
    this.onChanged = null;
    /** @type {((counts: any) => void) | null} a reply carried the undo history's counts */
    this.onHistory = null;
    this.socket = new WebSocket(url);
    this.opened = new Promise((resolve, reject) => {
      this.socket.onopen = () => resolve(undefined);
      this.socket.onerror = () => reject(new Error("the live connection failed"));
    });
    this.socket.onmessage = (event) => {
      const reply = JSON.parse(event.data);
      if (reply.type === "changed") { // another page changed the project
        if (this.onChanged) this.onChanged(reply);
        return;
      }
      if (reply.history && this.onHistory) this.onHistory(reply.history);
      const pending = this.waiting.get(reply.id);
      if (!pending) return;
      if (reply.type === "progress") {
        if (pending.progress) pending.progress(reply);
        return;
      }
      this.waiting.delete(reply.id);
      if (reply.type === "error") pending.reject(Object.assign(new Error(reply.message), { cancelled: !!reply.cancelled }));
      else pending.resolve(reply);
    };
    this.socket.onclose = (event) => {
      showError(`the connection to toonmotion closed${event.reason ? ": " + event.reason : ""}; reload to reconnect`);
      for (const pending of this.waiting.values()) pending.reject(new Error("connection closed"));
      this.waiting.clear();
    };
  }

  request(message, progress = null) {
    const id = this.next++;
    const reply = /** @type {Promise<any> & {id: number}} */ (this.opened.then(() => new Promise((resolve, reject) => {
      this.waiting.set(id, { resolve, reject, progress });
      this.socket.send(JSON.stringify({ ...message, id }));
    })));
    reply.id = id;
    return reply;
  }

  cancel(id) {
    if (this.waiting.has(id)) this.socket.send(JSON.stringify({ type: "cancel", id }));
  }
}

async function start() {
  try {
    status("loading…");
    const project = await getJSON("api/project");
    document.getElementById("project-name").textContent = project.name;
    const texture = await loadImage(`api/texture.png?token=${encodeURIComponent(token)}`);
    const wsURL = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws?token=${encodeURIComponent(token)}`;
    const live = new Live(wsURL);
    await live.opened;
    const view = new MeshView(element("mesh", HTMLCanvasElement), element("overlay", HTMLCanvasElement), project, texture);
    const ctx = { project, view, live, token, side: document.getElementById("side"), status, showError };
    /** @type {any} */ (window).toonmotion = ctx; // for tests and the console
    const memory = remembered(ctx);
    await restorePose(ctx, memory.saved);
    mountPanels(ctx, memory);
    history(ctx);
    status("ready");
  } catch (error) {
    status("");
    showError(error.message);
  }
}

// The editor reopens where the user left it: the panel, the frame and a pose made but not keyed
// yet (ctx.unkeyed: {frame, pose, tuning}), kept in the browser per project (the project itself,
// its keys and its edit history are on disk).
function remembered(ctx) {
  const key = `toonmotion:${ctx.project.name}:${ctx.project.width}x${ctx.project.height}`;
  let saved = {};
  try {
    saved = JSON.parse(localStorage.getItem(key) || "{}");
  } catch {
    saved = {};
  }
  return {
    saved,
    keep: (panel) => {
      try {
        localStorage.setItem(key, JSON.stringify({ panel, frame: ctx.frame || 0, unkeyed: ctx.unkeyed || null }));
      } catch {
        // storage full or off: reopening at the first panel is no loss
      }
    },
  };
}

// Undo and redo for every kind of edit (regions, keys, rigging), newest first: the history is
// the server's, kept in the project folder, so it survives a reload. After a step the current
// panel is mounted again on the project as it now is; undoing a rig reloads the page.
function history(ctx) {
  const undo = element("undo", HTMLButtonElement), redo = element("redo", HTMLButtonElement);
  const show = (counts) => {
    ctx.project.history = counts;
    undo.disabled = counts.undo === 0 && ctx.project.edits === 0;
    redo.disabled = counts.redo === 0;
    undo.title = `Undo (Ctrl+Z): ${counts.undo} edit${counts.undo === 1 ? "" : "s"}`;
    redo.title = `Redo (Ctrl+Shift+Z): ${counts.redo} edit${counts.redo === 1 ? "" : "s"}`;
  };
  async function step(type) {
    try {
      const reply = await ctx.live.request({ type });
      if (reply.kind === "rig" || reply.kind === "drawing") return location.reload(); // a new rig
      Object.assign(ctx.project, { triangles: reply.triangles, vertex_bone: reply.vertex_bone, depth: reply.depth,
                                   fallback: reply.fallback, edits: reply.edits, undone: reply.undone,
                                   keys: reply.keys });
      ctx.view.setTriangles(reply.triangles);
      show(reply.history);
      ctx.remount();
      showError("");
      status(`${type === "undo" ? "undid" : "redid"}: ${reply.says}`);
    } catch (error) {
      showError(error.message);
    }
  }
  // Another page (a second tab) changed the project: this one fetches it again and shows it.
  ctx.live.onChanged = async (note) => {
    const rigged = note.kind === "rigged" || note.kind === "opened" || note.step === "rig" || note.step === "drawing";
    if (rigged) return location.reload(); // a new rig: the page starts again on it
    try {
      const project = await getJSON("api/project");
      Object.assign(ctx.project, project);
      ctx.view.setTriangles(project.triangles);
      show(project.history);
      ctx.remount();
      const verb = { undone: "undid", redone: "redid" }[note.kind];
      status(`another page${verb ? ` ${verb}` : ""}: ${note.says || "changed the project"}`);
    } catch (error) {
      showError(error.message);
    }
  };
  ctx.undo = () => step("undo");
  ctx.redo = () => step("redo");
  ctx.live.onHistory = show;
  undo.onclick = ctx.undo;
  redo.onclick = ctx.redo;
  window.addEventListener("keydown", (event) => {
    if (!(event.ctrlKey || event.metaKey) || (event.target instanceof HTMLInputElement && event.target.type === "text")) return;
    const key = event.key.toLowerCase();
    if (key === "z" && !event.shiftKey) {
      event.preventDefault();
      ctx.undo();
    } else if (key === "y" || (key === "z" && event.shiftKey)) {
      event.preventDefault();
      ctx.redo();
    }
  });
  show(ctx.project.history);
}

// The pose the Pose panel starts from after a reload: the one made at the remembered frame and
// not keyed, else that frame's pose in the key-frames' animation, else the rest pose.
async function restorePose(ctx, saved) {
  ctx.frame = Number.isInteger(saved.frame) ? saved.frame : 0;
  const unkeyed = saved.unkeyed;
  const fits = (pose) => Array.isArray(pose) && pose.length === ctx.project.joints.length;
  ctx.unkeyed = unkeyed && Number.isInteger(unkeyed.frame) && fits(unkeyed.pose) ? unkeyed : null;
  if (ctx.unkeyed && ctx.unkeyed.frame === ctx.frame) {
    ctx.pose = ctx.unkeyed.pose.map((p) => p.slice());
    ctx.tuning = structuredClone(ctx.unkeyed.tuning || []);
  } else if (ctx.project.keys) {
    try {
      const reply = await ctx.live.request({ type: "frame", frame: ctx.frame });
      const key = ctx.project.keys.keys.find((k) => k.frame === reply.frame);
      ctx.pose = reply.positions;
      ctx.tuning = key ? structuredClone(key.edits) : [];
    } catch {
      // the rest pose, then
    }
  }
}

function mountPanels(ctx, memory) {
  const nav = document.getElementById("panels");
  let current = null, currentName = null;
  for (const panel of PANELS) {
    const button = document.createElement("button");
    button.textContent = panel.title;
    button.title = `${panel.title} (${PANELS.indexOf(panel) + 1})`;
    button.dataset.panel = panel.name;
    button.onclick = () => {
      if (current) current.unmount();
      for (const b of nav.children) b.setAttribute("aria-pressed", String(b === button));
      ctx.side.replaceChildren();
      current = panel.mount(ctx);
      currentName = panel.name;
      ctx.view.draw(); // the stage as this panel shows it: no handles left from the last one
      memory.keep(currentName);
    };
    nav.append(button);
  }
  window.addEventListener("pagehide", () => memory.keep(currentName));
  ctx.remember = () => memory.keep(currentName);
  ctx.remount = () => /** @type {HTMLButtonElement} */ (nav.querySelector(`button[data-panel=${currentName}]`)).click();
  // Keys 1 to 9 open the panels, in the order of the bar.
  window.addEventListener("keydown", (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey || typingIn(event.target)) return;
    const button = /** @type {HTMLButtonElement | undefined} */ (nav.children[Number(event.key) - 1]);
    if (/^[1-9]$/.test(event.key) && button) button.click();
  });
  const buttons = [.../** @type {HTMLCollectionOf<HTMLButtonElement>} */ (nav.children)];
  (buttons.find((b) => b.dataset.panel === memory.saved.panel) || buttons[0]).click();
}

// A text selection on the page (Ctrl+A, a stroke that left the stage) must not turn a drag on
// the stage into the browser's drag-and-drop of that selection, which cancels the drag after a
// few pixels: a press on the stage drops the selection, and the stage starts no drag-and-drop.
function keepDragsOnTheStage() {
  const stage = document.getElementById("stage");
  stage.addEventListener("pointerdown", () => window.getSelection()?.removeAllRanges(), { capture: true });
  stage.addEventListener("dragstart", (event) => event.preventDefault());
}

keepDragsOnTheStage();
start();
