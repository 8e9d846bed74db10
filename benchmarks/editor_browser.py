"""The editor as the animator feels it: a joint dragged in headless Chromium, from the pointer's
move to the server's reply and to the frame painted; and the 3D panel's lift and simulation, from
the click to the reply shown; JSON lines.

    python benchmarks/editor_browser.py [DRAWING_DIR|sample ...] [--moves N] [--prior CLIP.bvh]
                                        [--keys KEYS.json]
        [--keyshape-footage VIDEO|DIR --keyshape-outlines KEYS.json --keyshape-key-frames 0,8,16]
        [--only-keyshapes]

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

And one line per drawing for the 3D panel (``"step": "3d"``), its project keyed with ``--keys``
(a key-frames file for that skeleton) or else a swing of the skeleton made from its structure
(every joint whose parent has a parent turned 0.3 rad one way, then the other, twice), lifted with the
``--prior`` clip (default: ../shared/data/mocap's CMU jump) from the view 0, 0, then a balloon held
at the dragged joint simulated and composited:
  frames, markers                 the animation's frames, the proxy's markers
  lift_s, simulate_s              the click on Lift (Simulate) -> the panel showing the reply
Then one line for the Key-shapes panel's capture step, on the generated clip
(``toonmotion.sample_cartoons.morphing_character``, 24 frames, its outlines on its key frames) and
on footage given with ``--keyshape-footage`` (a video, GIF or folder of frames, sent as the page
sends it) and ``--keyshape-outlines`` (a contours file or SVG, its outlines drawn on
``--keyshape-key-frames``), in the sample character's project:
  keyshapes, frames, size, keys, points   the clip and the model
  model_ms                        "Build the model" clicked -> the sheet shown
  capture_ms, capture_ms_per_frame "Capture the footage" clicked -> the capture shown in the page
  library_ms                      api.capture_video and api.capture_contours on the same frames,
                                  called directly (the editor's overhead is the difference)
Needs Chromium (apt-get install chromium) and the dev extra (Playwright).
"""

import argparse
import contextlib
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
DEFAULT_PRIOR = DEFAULT_DIR.parent / "mocap" / "cmu_16_07_jump.bvh"
SWING = 0.3  # radians each joint turns in the swing key-frames
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


@contextlib.contextmanager
def editor_page(served):
    """A Chromium page (1280x800) open on the editor ``served``, once it says it is ready."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium_path(), args=list(CHROMIUM_ARGS))
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(served.page)
            page.wait_for_function("document.getElementById('status').textContent === 'ready'",
                                   timeout=60_000)
            yield page
        finally:
            browser.close()


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

    name, character = rig(folder)
    with tempfile.TemporaryDirectory() as scratch:
        project = Path(scratch) / "project"
        api.save_project(project, character)
        with serving(project) as served, editor_page(served) as page:
            page.click("nav button[data-panel=pose]")
            webgl = page.evaluate("""() => {
                const gl = document.createElement("canvas").getContext("webgl2");
                const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
                return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : "unknown";
            }""")
            reply_ms, paint_ms = drag(page, dragged_joint(character.skeleton), moves)

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


def swing_keys(skeleton):
    """Key-frames made from the skeleton's structure alone: rest, every joint whose parent has a
    parent turned by SWING, then by -SWING, twice, then rest; 6 frames apart at 12 fps."""
    from toonmotion.animate.timeline import Keyframe, make_timeline
    from toonmotion.rig.pose import Pose, rotate_about

    turned = {}
    pivots = sorted({int(p) for p in skeleton.parents if p >= 0 and skeleton.parents[p] >= 0})
    for sign in (1, -1):
        positions = skeleton.positions
        for pivot in pivots:
            positions = rotate_about(skeleton, positions, skeleton.names[pivot], sign * SWING)
        turned[sign] = positions
    poses = {0: skeleton.positions, 6: turned[1], 12: turned[-1], 18: turned[1], 24: turned[-1],
             30: skeleton.positions}
    return make_timeline(skeleton, [Keyframe(f, Pose(p)) for f, p in poses.items()], fps=12.0)


def bench_3d(folder, prior, keys_file):
    """The 3D panel on one drawing: Lift, then Simulate a balloon, each timed click to reply."""
    import time

    from toonmotion.io.pose_json import load_keyframes, save_keyframes

    name, character = rig(folder)
    skeleton = character.skeleton
    keys = load_keyframes(keys_file, skeleton) if keys_file else swing_keys(skeleton)
    with tempfile.TemporaryDirectory() as scratch:
        project = Path(scratch) / "project"
        api.save_project(project, character)
        save_keyframes(project / "keys.json", skeleton, keys)
        with serving(project, library=prior.parent) as served, editor_page(served) as page:
            page.click("nav button[data-panel=proxy]")
            page.wait_for_function("document.querySelectorAll('#proxy-prior option').length > 0")
            page.select_option("#proxy-prior", f"library/{prior.name}")
            timed, lifted = {}, ""
            for step, button, said in (("lift_s", "#proxy-lift", "lifted"), ("simulate_s", "#proxy-simulate",
                                                                              "simulated")):
                if step == "simulate_s":
                    page.select_option("#proxy-kind", "balloon")
                    page.select_option("#proxy-marker", dragged_joint(skeleton))
                    page.click("#proxy-add")
                started = time.perf_counter()
                page.click(button)
                page.wait_for_function(
                    f"""() => document.getElementById('status').textContent.startsWith({said!r})
                              || !document.getElementById('error').hidden""", timeout=600_000)
                timed[step] = round(time.perf_counter() - started, 2)
                error = page.locator("#error")
                if error.is_visible():
                    return {"drawing": name, "step": "3d", "prior": prior.name, "error": error.text_content()}
                lifted = lifted or page.locator("#status").text_content()  # "lifted N markers over T frames"
    markers, frames = (int(word) for word in lifted.split() if word.isdigit())
    return {"drawing": name, "step": "3d", "prior": prior.name, "frames": frames, "markers": markers, **timed}


def keyshape_inputs(scratch, footage, outlines, key_frames):
    """``(name, footage file, outlines file, key frames)``: the generated clip written into
    ``scratch`` when no footage is given."""
    if footage is not None:
        return footage.name, footage, outlines, [int(f) for f in key_frames.split(",")]
    from PIL import Image

    from toonmotion.io.keyshape_json import save_contours
    from toonmotion.sample_cartoons import morphing_character

    clip = morphing_character(frames=24, hold=1)
    pictures = [Image.fromarray(f) for f in clip.frames]
    gif = Path(scratch) / "morphing.gif"
    pictures[0].save(gif, save_all=True, append_images=pictures[1:], duration=42, loop=0)
    keys = Path(scratch) / "keys.json"
    save_contours(keys, clip.contours[list(clip.key_frames)], fps=clip.fps)
    return "morphing_character", gif, keys, list(clip.key_frames)


def send_footage(served, clip):
    """Send ``clip`` (a file, or a folder of frames) as the editor's pages do; returns where the
    project keeps it, given the project folder."""
    import urllib.request

    def put(path, body):
        request = urllib.request.Request(f"http://127.0.0.1:{served.port}{path}", data=body, method="PUT",
                                         headers={"X-Toonmotion-Token": served.token})
        with urllib.request.urlopen(request, timeout=600) as reply:
            return json.loads(reply.read())

    if clip.is_dir():
        images = sorted(p for p in clip.iterdir() if p.suffix.lower() in (".png", ".jpg", ".jpeg", ".webp"))
        for index, image in enumerate(images):
            put(f"/api/footage/frames/{index}?count={len(images)}&suffix={image.suffix[1:].lower()}",
                image.read_bytes())
        return lambda project: project / "footage" / "frames"
    put(f"/api/footage?suffix={clip.suffix[1:].lower()}", clip.read_bytes())
    return lambda project: project / "footage" / f"clip.{clip.suffix[1:].lower()}"


def bench_keyshapes(footage=None, outlines=None, key_frames=None):
    """The Key-shapes panel's model and capture steps, timed in the page, and the library's."""
    import time

    from toonmotion.io.frames import load_frames
    from toonmotion.io.keyshape_json import load_contours

    rgba, skeleton = sample_character(scale=0.5)
    with tempfile.TemporaryDirectory() as scratch:
        name, clip, keys_file, frames_at = keyshape_inputs(scratch, footage, outlines, key_frames)
        project = Path(scratch) / "project"
        api.save_project(project, api.rig_image(rgba, skeleton=skeleton))
        with serving(project) as served, editor_page(served) as page:
            sent = send_footage(served, clip)  # as the page sends it (a folder: frame by frame)
            page.click("nav button[data-panel=keyshapes]")
            status = "(t) => document.getElementById('status').textContent.startsWith(t)"
            page.wait_for_function("document.getElementById('ks-inputs').textContent.includes('footage')",
                                   timeout=60_000)
            page.uncheck("#ks-resample")
            page.set_input_files("#ks-outlines-file", str(keys_file))
            page.wait_for_function("(n) => document.querySelectorAll('#ks-keys li').length === n",
                                   arg=len(frames_at), timeout=60_000)
            for i, frame in enumerate(frames_at):
                page.locator("#ks-keys li input").nth(i).fill(str(frame))
                page.locator("#ks-keys li input").nth(i).dispatch_event("change")
            started = time.perf_counter()
            page.click("#ks-build")
            page.wait_for_function(status, arg="model built", timeout=600_000)
            page.wait_for_function("document.getElementById('ks-sheet').naturalWidth > 0")
            model_ms = (time.perf_counter() - started) * 1000
            started = time.perf_counter()
            page.click("#ks-capture-video")
            page.wait_for_function(status, arg="captured", timeout=3_600_000)
            capture_ms = (time.perf_counter() - started) * 1000
            errors = page.evaluate("document.getElementById('error').textContent")
        if errors:
            sys.exit(f"the Key-shapes panel said: {errors}")
        frames, _ = load_frames(sent(project))
        keys = load_contours(keys_file)[0]
        started = time.perf_counter()
        found = api.capture_video(frames, keys, key_frames=frames_at)
        api.capture_contours(found.shapes, keys)
        library_ms = (time.perf_counter() - started) * 1000
    return {"keyshapes": name, "frames": len(frames), "size": [frames.shape[2], frames.shape[1]],
            "keys": len(keys), "points": keys.shape[1], "model_ms": round(model_ms, 1),
            "capture_ms": round(capture_ms, 1), "capture_ms_per_frame": round(capture_ms / len(frames), 1),
            "library_ms": round(library_ms, 1)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders, or 'sample'")
    parser.add_argument("--moves", type=int, default=60, help="pointer moves timed per drawing (default 60)")
    parser.add_argument("--prior", type=Path, default=DEFAULT_PRIOR, help="the 3D panel's prior (.bvh)")
    parser.add_argument("--keys", type=Path, help="key-frames for the drawings' skeleton (default: a swing)")
    parser.add_argument("--keyshape-footage", type=Path, help="footage for the key-shape capture step")
    parser.add_argument("--keyshape-outlines", type=Path, help="its key outlines (contours file or SVG)")
    parser.add_argument("--keyshape-key-frames", help="the frames the outlines are drawn on, e.g. 0,8,16")
    parser.add_argument("--only-keyshapes", action="store_true", help="time the key-shape steps only")
    args = parser.parse_args(argv)
    given = (args.keyshape_footage, args.keyshape_outlines, args.keyshape_key_frames)
    if any(v is not None for v in given) and any(v is None for v in given):
        parser.error("--keyshape-footage, --keyshape-outlines and --keyshape-key-frames go together")
    if chromium_path() is None:
        sys.exit("the browser benchmark needs Debian's chromium (apt-get install chromium)")
    folders = args.drawings or [*sorted(p for p in DEFAULT_DIR.glob("*") if (p / "char_cfg.yaml").is_file()),
                                Path("sample")]
    for folder in [] if args.only_keyshapes else folders:
        print(json.dumps(bench(folder, args.moves)), flush=True)
        if args.prior.is_file():
            print(json.dumps(bench_3d(folder, args.prior, args.keys)), flush=True)
        else:
            print(json.dumps({"drawing": str(folder), "step": "3d", "skipped": f"no prior at {args.prior}"}))
    print(json.dumps(bench_keyshapes()), flush=True)
    if args.keyshape_footage is not None:
        print(json.dumps(bench_keyshapes(*given)), flush=True)


if __name__ == "__main__":
    main()
