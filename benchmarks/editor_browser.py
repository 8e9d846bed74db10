"""The editor as the animator feels it: a joint dragged in headless Chromium, from the pointer's
move to the server's reply and to the frame painted; JSON lines.

    python benchmarks/editor_browser.py [DRAWING_DIR|sample ...] [--moves N]

Each drawing folder (texture.png, mask.png, char_cfg.yaml; default: every drawing in
../shared/data/drawings, then the bundled sample character, named ``sample``) is rigged to about
1,500 vertices and served by the editor on a free loopback port; Debian's Chromium (Playwright)
opens the page at 1280x800 and drags one joint in the Pose panel (its bone turns, FK) through an
arc, a pointer move at a time, each once the page has painted the last one (a hand moving
steadily; no move waits behind another). The joint is chosen by the skeleton's structure, never
by name: the first joint, parents first, whose parent has a parent (an elbow or a knee in a
biped). Timed in the page with ``performance.now()``:

Keys, one line per drawing:
  drawing, vertices, moves        the mesh; pointer moves timed (after 5 to warm up)
  pointer_to_reply_ms_median/_p95 the pointer's move event -> the deformed mesh received
  pointer_to_paint_ms_median/_p95 the move -> the first animation frame after the reply, when
                                  the new mesh is on the screen (goal: median at most 50)
  webgl                           the page's WebGL renderer (SwiftShader: drawn on the CPU here)
Needs Chromium (apt-get install chromium) and the dev extra (Playwright).
"""

import argparse
import json
import math
import statistics
import sys
import tempfile
from pathlib import Path

from toonmotion import api
from toonmotion.io.drawing_folder import load_drawing_folder
from toonmotion.rig.character import RigSettings
from toonmotion.samples import sample_character
from toonmotion.testing.browser import CHROMIUM_ARGS, chromium_path
from toonmotion.web.background import serving

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
WARM_UP = 5

# Installed in the page: every pointer move on the stage, every reply of the live connection and
# the animation frame after it, stamped with performance.now().
STAMPS = """() => {
    const c = window.toonmotion, b = window.bench = { moves: [], replies: [], paints: [] };
    c.view.overlay.addEventListener("pointermove", () => b.moves.push(performance.now()), { capture: true });
    c.live.socket.addEventListener("message", () => {
        b.replies.push(performance.now());
        requestAnimationFrame(() => b.paints.push(performance.now()));
    });
}"""


def rig(folder):
    """``(name, Character)`` for a drawing folder, or the bundled sample for ``"sample"``."""
    settings = RigSettings(vertices=1500)
    if str(folder) == "sample":
        rgba, skeleton = sample_character()
        return "sample", api.rig_image(rgba, skeleton=skeleton, settings=settings)
    drawing = load_drawing_folder(folder)
    return folder.name, api.rig_image(drawing.texture, mask=drawing.mask, skeleton=drawing.skeleton,
                                      settings=settings)


def dragged_joint(skeleton):
    """The first joint whose parent has a parent: it turns a bone that is not the root's."""
    for j, parent in enumerate(skeleton.parents):
        if parent >= 0 and skeleton.parents[parent] >= 0:
            return skeleton.names[j]
    return skeleton.names[-1]


def drag(page, joint, moves):
    """Drag ``joint`` through an arc, a move at a time; returns the timings in ms."""
    x, y = page.evaluate(
        """(name) => {
        const c = window.toonmotion, j = c.project.joints.find((j) => j.name === name);
        const [x, y] = c.view.toCanvas(j.position), box = c.view.overlay.getBoundingClientRect();
        const k = box.width / c.view.overlay.width;
        return [box.left + x * k, box.top + y * k];
    }""", joint)
    page.evaluate(STAMPS)
    page.mouse.move(x, y)
    page.mouse.down()
    reply_ms, paint_ms = [], []
    for step in range(1, moves + WARM_UP + 1):
        angle = 2 * math.pi * step / (moves + WARM_UP)
        before = page.evaluate("window.bench.paints.length")
        page.mouse.move(x + 40 * math.sin(angle), y - 40 * (1 - math.cos(angle)))
        page.wait_for_function("(n) => window.bench.paints.length > n", arg=before, timeout=30_000)
        moved, replied, painted = page.evaluate(
            "() => [window.bench.moves.at(-1), window.bench.replies.at(-1), window.bench.paints.at(-1)]")
        if step > WARM_UP:
            reply_ms.append(replied - moved)
            paint_ms.append(painted - moved)
    page.mouse.up()
    return reply_ms, paint_ms


def bench(folder, moves):
    from playwright.sync_api import sync_playwright

    name, character = rig(folder)
    with tempfile.TemporaryDirectory() as scratch:
        project = Path(scratch) / "project"
        api.save_project(project, character)
        with serving(project) as served, sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=chromium_path(), args=list(CHROMIUM_ARGS))
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(served.page)
            page.wait_for_function("document.getElementById('status').textContent === 'ready'",
                                   timeout=60_000)
            page.click("nav button[data-panel=pose]")
            webgl = page.evaluate("""() => {
                const gl = document.createElement("canvas").getContext("webgl2");
                const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
                return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : "unknown";
            }""")
            reply_ms, paint_ms = drag(page, dragged_joint(character.skeleton), moves)
            browser.close()

    def p95(values):
        return round(statistics.quantiles(values, n=20)[18], 1)

    return {
        "drawing": name,
        "vertices": len(character.mesh.V),
        "moves": len(reply_ms),
        "pointer_to_reply_ms_median": round(statistics.median(reply_ms), 1),
        "pointer_to_reply_ms_p95": p95(reply_ms),
        "pointer_to_paint_ms_median": round(statistics.median(paint_ms), 1),
        "pointer_to_paint_ms_p95": p95(paint_ms),
        "webgl": webgl,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders, or 'sample'")
    parser.add_argument("--moves", type=int, default=60, help="pointer moves timed per drawing (default 60)")
    args = parser.parse_args(argv)
    if chromium_path() is None:
        sys.exit("the browser benchmark needs Debian's chromium (apt-get install chromium)")
    folders = args.drawings or [*sorted(p for p in DEFAULT_DIR.glob("*") if (p / "char_cfg.yaml").is_file()),
                                Path("sample")]
    for folder in folders:
        print(json.dumps(bench(folder, args.moves)), flush=True)


if __name__ == "__main__":
    main()
