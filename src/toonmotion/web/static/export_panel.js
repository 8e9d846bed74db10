// The Export panel: the key-frames' animation into the project folder's exports/, with a progress
// bar: pictures (GIF, MP4, PNG frames, APNG, WebP, WebM, a sprite sheet) or rigs other tools replay
// (glTF, Spine). Every file written can then be downloaded.

import { element, rgbOf } from "./panel_kit.js";

export const name = "export";
export const title = "Export";

export function mount(ctx) {
  const { live, side, status, showError, token } = ctx;
  side.innerHTML = `<h2>Export</h2>
    <p>The animation of the key-frames (Timeline panel), into the project's <code>exports/</code>.</p>
    <p><label>Name <input id="export-name" value="animation" pattern="[A-Za-z0-9][A-Za-z0-9_-]*"
       maxlength="64"></label></p>
    <p><label>Format <select id="export-format" style="max-width: 100%">
      <optgroup label="pictures">
        <option value="gif">GIF</option><option value="mp4">MP4</option><option value="png">PNG frames</option>
        <option value="apng">APNG (transparent)</option><option value="webp">WebP (transparent)</option>
        <option value="webm">WebM VP9 (transparent)</option>
        <option value="sheet" title="one PNG and a JSON atlas: Phaser, PixiJS, Godot">sprite sheet</option>
      </optgroup>
      <optgroup label="rigs (the drawing, skinned)">
        <option value="glb" title="Blender, game engines, three.js">glTF (.glb)</option>
        <option value="spine" title="skeleton JSON, atlas and page image">Spine 4.2</option>
      </optgroup>
    </select></label></p>
    <p id="export-rig-note" hidden>A rig replays the animation on the drawing in the other tool: size,
      background and overlays do not apply.</p>
    <p><label><input id="export-exaggerated" type="checkbox"> exaggerated (the Exaggerate panel's
      strength and width, or 1.5 and 3)</label></p>
    <p><label>Size <input id="export-width" type="number" min="1" max="16384" placeholder="auto" style="width: 5em"></label>
      × <input id="export-height" type="number" min="1" max="16384" placeholder="auto" style="width: 5em"
      aria-label="height"> px</p>
    <p><label>Background <select id="export-background"><option value="">transparent (white for GIF, MP4)</option>
      <option value="#ffffff">white</option><option value="#000000">black</option><option value="custom">colour…</option>
      </select></label> <input id="export-colour" type="color" value="#88aacc" hidden aria-label="background colour"></p>
    <p>Draw over it: <label><input type="checkbox" name="export-overlay" value="skeleton"> skeleton</label>
      <label><input type="checkbox" name="export-overlay" value="mesh"> mesh</label>
      <label><input type="checkbox" name="export-overlay" value="rest"> rest bones</label></p>
    <p><button id="export-go">Export</button></p>
    <p><progress id="export-progress" max="1" value="0" hidden></progress>
      <button id="export-cancel" hidden>Cancel</button></p>
    <p id="export-result"></p>
    <img id="export-preview" alt="the exported animation" hidden style="max-width: 100%">`;
  const formatChoice = element("export-format", HTMLSelectElement);
  const pictureOnly = [element("export-width", HTMLInputElement), element("export-height", HTMLInputElement),
                       element("export-background", HTMLSelectElement)];
  formatChoice.onchange = () => {
    const rig = ["glb", "spine"].includes(formatChoice.value);
    document.getElementById("export-rig-note").hidden = !rig;
    for (const field of pictureOnly) field.disabled = rig;
    for (const box of side.querySelectorAll("input[name=export-overlay]")) {
      box.disabled = !["gif", "mp4", "png"].includes(formatChoice.value);
    }
  };
  const colourChoice = element("export-background", HTMLSelectElement);
  colourChoice.onchange = () => { element("export-colour", HTMLInputElement).hidden = colourChoice.value !== "custom"; };
  const button = element("export-go", HTMLButtonElement);
  const bar = element("export-progress", HTMLProgressElement);
  const cancel = element("export-cancel", HTMLButtonElement);
  const result = document.getElementById("export-result");

  button.onclick = async () => {
    const format = element("export-format", HTMLSelectElement).value;
    const message = { type: "export", format, name: element("export-name", HTMLInputElement).value };
    if (!["glb", "spine"].includes(format)) {
      const width = element("export-width", HTMLInputElement).value, height = element("export-height", HTMLInputElement).value;
      if (!width !== !height) return showError("give the size's width and height, or neither (the view's own)");
      if (width) message.size = [Number(width), Number(height)];
      const hex = colourChoice.value === "custom" ? element("export-colour", HTMLInputElement).value : colourChoice.value;
      if (hex) message.background = rgbOf(hex);
      message.overlays = [...side.querySelectorAll("input[name=export-overlay]:checked:not(:disabled)")]
        .map((box) => box.value);
    }
    if (element("export-exaggerated", HTMLInputElement).checked) {
      Object.assign(message, ctx.exaggeration || { strength: 1.5, sigma: 3 });
    }
    button.disabled = true;
    bar.hidden = false;
    bar.value = 0;
    result.textContent = "";
    status("exporting…");
    const job = live.request(message, ({ index, count }) => {
      bar.max = count;
      bar.value = index;
    });
    cancel.hidden = false;
    cancel.onclick = () => { live.cancel(job.id); status("cancelling…"); };
    try {
      const reply = await job;
      const size = reply.size ? `, ${reply.size[0]}×${reply.size[1]}` : "";
      result.textContent = `${reply.frames} frames${size} → ${reply.file} `;
      const preview = element("export-preview", HTMLImageElement);
      preview.hidden = true;
      if (format !== "png") {
        for (const file of reply.files) {
          const name = file.split("/").pop();
          const link = document.createElement("a");
          link.href = `api/exports/${name}?token=${encodeURIComponent(token)}`;
          link.textContent = reply.files.length > 1 ? `download ${name}` : "download";
          link.download = name;
          result.append(link, " ");
        }
        // What plays (or, for a sheet, shows) in the page: the picture itself, or the sheet's PNG.
        const shown = [...result.querySelectorAll("a")].find((a) => /\.(gif|apng|webp|png)$/.test(a.download));
        if (shown && ["gif", "apng", "webp", "sheet"].includes(format)) {
          preview.src = `${shown.href}&t=${Date.now()}`;
          preview.hidden = false;
        }
      }
      status("exported");
      showError("");
    } catch (error) {
      showError(error.cancelled ? "" : error.message);
      status(error.cancelled ? "export cancelled: nothing was written" : "");
    } finally {
      cancel.hidden = true;
      button.disabled = false;
      bar.hidden = true;
    }
  };
  status("export the animation");
  return { unmount() {} };
}
