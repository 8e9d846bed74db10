// What the panels share: event listeners that come off together, the handle under the pointer,
// and a sender that keeps only the newest message waiting while one is answered (so the drawing
// keeps up with the pointer instead of falling behind it).

// Add handlers ({type: function}) to target; returns a function that removes them all.
export function listen(target, handlers) {
  for (const [type, handler] of Object.entries(handlers)) target.addEventListener(type, handler);
  return () => {
    for (const [type, handler] of Object.entries(handlers)) target.removeEventListener(type, handler);
  };
}

// The index of the point (drawing pixels) nearest the pointer within reach CSS pixels, or -1;
// on a tie the first point wins.
export function nearest(view, points, event, reach) {
  const ratio = window.devicePixelRatio || 1;
  const [ex, ey] = view.toCanvas(view.toDrawing(event));
  let best = -1, bestDistance = reach * ratio;
  points.forEach((p, i) => {
    const [x, y] = view.toCanvas(p), d = Math.hypot(x - ex, y - ey);
    if (d < bestDistance) { best = i; bestDistance = d; }
  });
  return best;
}

// send(message) through live, one at a time; a message sent while another is answered replaces
// any that was waiting. Replies go to onReply(reply, message), errors to onError.
export function newest(live, onReply, onError) {
  let busy = false, queued = null;
  async function next() {
    if (busy || !queued) return;
    busy = true;
    const message = queued;
    queued = null;
    try {
      onReply(await live.request(message), message);
    } catch (error) {
      onError(error);
    } finally {
      busy = false;
      next();
    }
  }
  return (message) => {
    queued = message;
    next();
  };
}

// Keep the pointer's events coming to target while it is pressed (a synthetic or already
// released pointer cannot be captured, and need not be).
export function capture(target, event) {
  try {
    target.setPointerCapture(event.pointerId);
  } catch {
    // not an active pointer: its events still reach the target while over it
  }
}

// A colour input's "#rrggbb" as [r, g, b], 0-255, as messages carry colours, and back.
export const rgbOf = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16));
export const hexOf = (rgb) => "#" + rgb.map((v) => v.toString(16).padStart(2, "0")).join("");

// Whether a key pressed in ``target`` is typing (a text field, a number, a list): the editor's
// shortcut keys leave it be. A slider, a tick box or a button takes no typing.
export function typingIn(target) {
  if (target instanceof HTMLSelectElement || target instanceof HTMLTextAreaElement) return true;
  return target instanceof HTMLInputElement
    && !["range", "checkbox", "radio", "button", "color", "file"].includes(target.type);
}

/**
 * The page's element ``id``, which must be a ``kind`` (HTMLInputElement, HTMLButtonElement, ...):
 * a missing or different element is a bug, said at once.
 * @template {HTMLElement} T
 * @param {string} id
 * @param {{new (): T, name: string}} kind
 * @returns {T}
 */
export function element(id, kind) {
  const found = document.getElementById(id);
  if (!(found instanceof kind)) throw new Error(`the page has no ${kind.name} #${id}`);
  return found;
}
