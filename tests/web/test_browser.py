"""The editor driven in a real browser (Playwright and Debian's headless Chromium), as a user
would: drag a joint and see the drawing follow.

Without Chromium these tests skip, except under CI=true, where a missing browser is a failure
(`make test` installs it when run as root).
"""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.web.slow_work import slow_work
from toonmotion import api
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.pose import Pose
from toonmotion.samples import sample_character
from toonmotion.web.background import serving

GOLDEN = Path(__file__).parent / "golden"


def _stage(page) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(page.locator("#stage").screenshot())).convert("RGB"), dtype=float)


def _joint_on_screen(page, name: str) -> tuple[float, float]:
    return tuple(
        page.evaluate(
            """(name) => {
        const c = window.toonmotion, j = c.project.joints.find((j) => j.name === name);
        const [x, y] = c.view.toCanvas(j.position), box = c.view.overlay.getBoundingClientRect();
        const k = box.width / c.view.overlay.width;
        return [box.left + x * k, box.top + y * k];
    }""",
            name,
        )
    )


def _close_to_golden(picture: np.ndarray, name: str) -> None:
    if os.environ.get("TOONMOTION_NEW_GOLDEN") == name:  # write a new golden image, then look at it
        Image.fromarray(picture.astype(np.uint8)).save(GOLDEN / name)
    golden = np.asarray(Image.open(GOLDEN / name).convert("RGB"), dtype=float)
    assert golden.shape == picture.shape
    far = np.abs(golden - picture).max(axis=2) > 48
    assert far.mean() < 0.01, f"{far.mean():.2%} of the pixels differ from {name}"


def test_the_page_shows_the_drawing_with_its_joints(page):
    assert page.errors == [] and page.locator("#error").is_hidden()
    _close_to_golden(_stage(page), "rest.png")


def test_dragging_a_joint_deforms_the_drawing_live(page, editor):
    before = _stage(page)
    x, y = _joint_on_screen(page, "right_hand")
    hx, hy = _joint_on_screen(page, "head")
    page.mouse.move(x, y)
    page.mouse.down()
    for step in range(1, 13):  # towards the head: the forearm turns to point at it (FK)
        page.mouse.move(x + (hx - x) * step / 12, y + (hy - y) * step / 12)
        page.wait_for_timeout(20)
    page.mouse.up()
    page.wait_for_function("document.getElementById('pose-timing').textContent !== ''")
    page.wait_for_timeout(300)  # the last queued pose
    served = np.reshape(page.evaluate("Array.from(window.toonmotion.view.vertices)"), (-1, 2))
    rest = api.load_project(editor[1]).mesh.V
    assert np.abs(served - rest).max() > 20  # the mesh the server sent moved the arm
    after = _stage(page)
    changed = np.abs(after - before).max(axis=2) > 48
    assert changed.mean() > 0.002  # and the canvas shows it
    _close_to_golden(after, "dragged.png")
    # The hand now lies on the head, at the same depth: the panel says so and what to do.
    page.wait_for_function("document.getElementById('pose-overlaps').textContent !== ''")
    warning = page.locator("#pose-overlaps").text_content()
    assert "head and right_hand overlap at the same depth" in warning and "Regions panel" in warning
    assert page.errors == [] and page.locator("#error").is_hidden()
    page.click("#pose-reset")
    page.wait_for_timeout(300)
    np.testing.assert_allclose(
        np.reshape(page.evaluate("Array.from(window.toonmotion.view.vertices)"), (-1, 2)), rest, atol=1e-2
    )


def test_a_text_selection_on_the_page_does_not_turn_a_joint_drag_into_drag_and_drop(page, editor):
    """Issue 44: after Ctrl+A (or a stroke that left the stage) a joint drag became the browser's
    drag-and-drop of the selection: the joint moved 3-4 px and the drag was cancelled."""
    page.click("#pose-reset")
    page.wait_for_timeout(300)
    page.keyboard.press("Control+A")
    assert page.evaluate("String(window.getSelection())") != ""  # the page's text is selected
    x, y = _joint_on_screen(page, "right_hand")
    page.mouse.move(x, y)
    page.mouse.down()
    for step in range(1, 13):
        page.mouse.move(x + 5 * step, y - 10 * step)
        page.wait_for_timeout(20)
    page.mouse.up()
    page.wait_for_timeout(300)
    names = page.evaluate("window.toonmotion.project.joints.map((j) => j.name)")
    pose = page.evaluate("window.toonmotion.pose")
    hand, elbow = (_on_screen(page, [pose[names.index(n)]])[0] for n in ("right_hand", "right_elbow"))
    # The whole drag: the forearm turned to point at where the pointer ended (a cancelled drag
    # left it pointing at the pointer 5 px from the start).
    towards, now = np.subtract((x + 60, y - 120), elbow), np.subtract(hand, elbow)
    assert abs(np.arctan2(towards[1], towards[0]) - np.arctan2(now[1], now[0])) < 0.02
    page.click("#pose-reset")
    page.wait_for_timeout(300)




def _drag(page, joint, dx, dy, *, shift=False):
    """Drag ``joint`` by (dx, dy) CSS px in small steps; returns where the pointer ended."""
    x, y = _joint_on_screen(page, joint)
    page.mouse.move(x, y)
    if shift:
        page.keyboard.down("Shift")
    page.mouse.down()
    for step in range(1, 11):
        page.mouse.move(x + dx * step / 10, y + dy * step / 10)
        page.wait_for_timeout(20)
    page.mouse.up()
    if shift:
        page.keyboard.up("Shift")
    page.wait_for_timeout(400)  # the last reply
    return x + dx, y + dy


def _pose_now(page):
    names = page.evaluate("window.toonmotion.project.joints.map((j) => j.name)")
    parents = page.evaluate("window.toonmotion.project.joints.map((j) => j.parent)")
    return names, parents, np.array(page.evaluate("window.toonmotion.pose"), dtype=float)


def test_a_dragged_joint_turns_its_bone_reaches_with_ik_pins_and_stretches_on_shift(page, editor):
    """Issue 44: a drag moved the joint alone (its bone stretched, the joints below stayed). Now:
    FK by default, IK with I (up to a pinned joint), a stretch with Shift."""
    page.click("#pose-reset")
    page.wait_for_timeout(300)
    names, parents, rest = _pose_now(page)
    bones = [(p, c) for c, p in enumerate(parents) if p >= 0]

    def lengths(P):
        return np.array([np.hypot(*(P[c] - P[p])) for p, c in bones])

    hand, elbow, shoulder = (names.index(n) for n in ("right_hand", "right_elbow", "right_shoulder"))
    # FK: the forearm turns about the elbow; nothing else moves, no bone stretches.
    _drag(page, "right_hand", 40, -60)
    _, _, P = _pose_now(page)
    np.testing.assert_allclose(lengths(P), lengths(rest), atol=1e-2)
    assert np.hypot(*(P[hand] - rest[hand])) > 5
    np.testing.assert_allclose(np.delete(P, hand, axis=0), np.delete(rest, hand, axis=0), atol=1e-6)
    # IK: the hand reaches the pointer, the elbow bends, the shoulder stays.
    page.click("#pose-reset")
    page.keyboard.press("i")
    assert page.is_checked("input[name=pose-bones][value=reach]")
    ended = _drag(page, "right_hand", 30, -40)
    _, _, P = _pose_now(page)
    np.testing.assert_allclose(lengths(P), lengths(rest), atol=1e-2)
    np.testing.assert_allclose(_on_screen(page, [P[hand]])[0], ended, atol=1.5)
    assert np.hypot(*(P[elbow] - rest[elbow])) > 1 and np.allclose(P[shoulder], rest[shoulder])
    # A pinned elbow stops the chain: the forearm alone turns.
    page.click("#pose-reset")
    page.mouse.dblclick(*_joint_on_screen(page, "right_elbow"))
    _drag(page, "right_hand", 30, -40)
    _, _, P = _pose_now(page)
    np.testing.assert_allclose(P[elbow], rest[elbow], atol=1e-6)
    page.mouse.dblclick(*_joint_on_screen(page, "right_elbow"))  # unpinned
    page.keyboard.press("i")  # back to FK
    # Shift: the hand goes to the pointer, the forearm stretches.
    page.click("#pose-reset")
    ended = _drag(page, "right_hand", 25, 10, shift=True)
    _, _, P = _pose_now(page)
    np.testing.assert_allclose(_on_screen(page, [P[hand]])[0], ended, atol=1.5)
    assert abs(np.hypot(*(P[hand] - P[elbow])) - np.hypot(*(rest[hand] - rest[elbow]))) > 1
    assert page.errors == [] and page.locator("#error").is_hidden()
    page.click("#pose-reset")
    page.wait_for_timeout(300)

def test_a_panel_that_draws_nothing_on_the_stage_leaves_no_handles_there(page):
    """Issue 44: the Pose panel's joint handles stayed on the stage in the Export panel."""
    inked = """() => {
        const o = window.toonmotion.view.overlay;
        const d = o.getContext("2d").getImageData(0, 0, o.width, o.height).data;
        let n = 0;
        for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
        return n;
    }"""
    page.click("nav button[data-panel=pose]")
    assert page.evaluate(inked) > 0  # the handles
    page.click("nav button[data-panel=export]")
    assert page.evaluate(inked) == 0
    page.click("nav button[data-panel=pose]")
    assert page.evaluate(inked) > 0

def _on_screen(page, points) -> list[tuple[float, float]]:
    """Drawing pixels to the page's CSS pixels."""
    return [tuple(xy) for xy in page.evaluate(
        """(points) => {
        const c = window.toonmotion, box = c.view.overlay.getBoundingClientRect();
        const k = box.width / c.view.overlay.width;
        return points.map((p) => {
            const [x, y] = c.view.toCanvas(p);
            return [box.left + x * k, box.top + y * k];
        });
    }""",
        [list(map(float, p)) for p in points],
    )]


def test_sketch_a_stick_figure_and_the_drawing_takes_its_pose(page, editor):
    from toonmotion.rig.sketch import stroke_chains as chains

    character = api.load_project(editor[1])
    skeleton = character.skeleton
    # Both arms raised: each turned about its shoulder, the rest of the figure as it was.
    target = api.rotate_joint(character, "right_shoulder", 1.2).positions.copy()
    left = [skeleton.index(n) for n in ("left_elbow", "left_hand")]
    target[left] = api.rotate_joint(character, "left_shoulder", -1.2).positions[left]
    page.click("nav button[data-panel=pose]")
    page.click("#pose-reset")
    page.wait_for_timeout(300)
    before = _stage(page)
    page.keyboard.press("s")
    assert page.locator("input[name=pose-mode][value=sketch]").is_checked()
    for chain in chains(skeleton):  # the whole stick figure, one stroke per chain, as drawn
        points = [target[a] + (target[b] - target[a]) * t for a, b in zip(chain, chain[1:], strict=False)
                  for t in np.linspace(0, 1, 6, endpoint=False)] + [target[chain[-1]]]
        screen = _on_screen(page, points)
        page.mouse.move(*screen[0])
        page.mouse.down()
        for xy in screen[1:]:
            page.mouse.move(*xy)
        page.mouse.up()
    page.wait_for_function("document.getElementById('status').textContent === 'sketch matched'",
                           timeout=10_000)
    matched = page.locator("#pose-matched").text_content()
    assert "right_elbow" in matched and "left_hand" in matched
    posed = np.array(page.evaluate("window.toonmotion.pose"))
    size = np.hypot(*np.ptp(target, axis=0))
    assert np.linalg.norm(posed - target, axis=1).max() < 0.03 * size  # every joint where it was drawn
    served = np.reshape(page.evaluate("Array.from(window.toonmotion.view.vertices)"), (-1, 2))
    expected = api.pose_character(character, Pose(posed))
    np.testing.assert_allclose(served, expected.deformation.U, atol=1e-2)  # the mesh for that pose
    page.keyboard.press("d")
    page.mouse.move(0, 0)
    after = _stage(page)
    assert (np.abs(after - before).max(axis=2) > 48).mean() > 0.002  # the canvas shows it
    _close_to_golden(after, "sketched.png")
    assert page.errors == [] and page.locator("#error").is_hidden()
    page.click("#pose-reset")
    page.wait_for_timeout(300)


def test_a_pen_sketches_with_pressure_and_tilt(page, editor):
    character = api.load_project(editor[1])
    bent = api.rotate_joint(character, "left_elbow", -0.9).positions
    elbow, hand = (character.skeleton.index(n) for n in ("left_elbow", "left_hand"))
    page.click("nav button[data-panel=pose]")
    page.click("#pose-reset")
    page.keyboard.press("s")
    screen = _on_screen(page, [bent[elbow] + (bent[hand] - bent[elbow]) * t for t in np.linspace(0, 1, 12)])
    pen = {"pointerType": "pen", "pointerId": 7, "isPrimary": True, "pressure": 0.5, "tiltX": 30, "tiltY": 0,
           "buttons": 1, "bubbles": True}
    page.dispatch_event("#overlay", "pointerdown", {**pen, "clientX": screen[0][0], "clientY": screen[0][1]})
    for x, y in screen[1:]:
        page.dispatch_event("#overlay", "pointermove", {**pen, "clientX": x, "clientY": y})
    page.dispatch_event("#overlay", "pointerup", {**pen, "pressure": 0, "clientX": screen[-1][0],
                                                  "clientY": screen[-1][1]})
    page.keyboard.press("Enter")
    page.wait_for_function("document.getElementById('status').textContent === 'sketch matched'")
    widths = page.evaluate("window.toonmotion.lastStroke.widths")
    assert widths[1:] == pytest.approx([(1 + 5 * 0.5) * (1 + 30 / 90)] * (len(widths) - 1))
    assert page.locator("#pose-matched").text_content() == "Sketched left_hand."
    posed = np.array(page.evaluate("window.toonmotion.pose"))
    assert np.linalg.norm(posed[hand] - bent[hand]) < 2.0
    page.keyboard.press("d")
    page.click("#pose-reset")
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_regions_click_a_region_forward_lasso_vertices_to_a_bone_and_undo(page, editor):
    folder = editor[1]
    page.click("nav button[data-panel=regions]")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('click a region')")
    _close_to_golden(_stage(page), "regions.png")
    x, y = _joint_on_screen(page, "right_elbow")
    page.mouse.click(x, y)
    page.wait_for_function("window.toonmotion.project.edits === 1")
    assert api.load_project(folder).depth.max() == 1  # saved as it happened
    hx, hy = _joint_on_screen(page, "head")
    page.select_option("#regions-bone", "neck")
    page.mouse.move(hx - 25, hy - 25)
    page.mouse.down()
    for px, py in [(hx + 25, hy - 25), (hx + 25, hy + 25), (hx - 25, hy + 25), (hx - 25, hy - 20)]:
        page.mouse.move(px, py, steps=4)
    page.mouse.up()
    page.wait_for_function("window.toonmotion.project.edits === 2")
    saved = api.load_project(folder)
    neck = saved.skeleton.bone_names.index("neck")
    head = saved.skeleton.positions[saved.skeleton.index("head")]
    near = np.hypot(*(saved.mesh.V - head).T) < 8
    assert (saved.binding.bone[near] == neck).all()
    page.keyboard.press("Control+z")
    page.wait_for_function("window.toonmotion.project.edits === 1 && window.toonmotion.project.undone === 1")
    assert len(api.load_project(folder).edits) == 1
    assert page.errors == [] and page.locator("#error").is_hidden()


def _set_frame(page, frame: int) -> None:
    page.evaluate(
        """(frame) => { const s = document.getElementById('timeline-scrub');
        s.value = String(frame); s.dispatchEvent(new Event('input')); }""",
        frame,
    )
    page.wait_for_function(
        "(f) => document.getElementById('timeline-frame').textContent === String(f)", arg=frame
    )
    page.wait_for_timeout(300)


def test_timeline_key_two_poses_scrub_the_inbetween_and_play(page, editor):
    from toonmotion.io.pose_json import load_keyframes

    folder = editor[1]
    page.click("nav button[data-panel=pose]")
    page.click("#pose-reset")
    page.click("nav button[data-panel=timeline]")
    page.click("#timeline-key")  # the rest pose at frame 0
    page.wait_for_function(
        "window.toonmotion.project.keys && window.toonmotion.project.keys.keys.length === 1"
    )
    _set_frame(page, 12)
    page.click("nav button[data-panel=pose]")
    x, y = _joint_on_screen(page, "right_hand")
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 40, y - 90, steps=10)
    page.mouse.up()
    page.wait_for_timeout(300)
    page.click("nav button[data-panel=timeline]")
    page.click("#timeline-key")  # the raised hand at frame 12
    page.wait_for_function("window.toonmotion.project.keys.keys.length === 2")
    timeline = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert [k.frame for k in timeline.keys] == [0, 12]  # saved in the project as it happened
    page.fill("#timeline-fps", "24")
    page.dispatch_event("#timeline-fps", "change")
    page.wait_for_function("window.toonmotion.project.keys.fps === 24")
    timeline = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert timeline.fps == 24.0
    _set_frame(page, 6)
    served = np.reshape(page.evaluate("Array.from(window.toonmotion.view.vertices)"), (-1, 2))
    expected = api.animate_character(api.load_project(folder), timeline).meshes[6][1]
    np.testing.assert_allclose(served, expected, atol=1e-2)  # the library's in-between, drawn
    _close_to_golden(_stage(page), "inbetween.png")
    page.click("#timeline-play")
    page.wait_for_timeout(800)
    page.click("#timeline-play")
    assert page.locator("#timeline-play").text_content() == "Play"
    left_at = page.locator("#timeline-frame").text_content()
    page.reload()  # the editor reopens where it was left: this panel, this frame
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    assert page.locator("nav button[aria-pressed=true]").get_attribute("data-panel") == "timeline"
    assert page.locator("#timeline-frame").text_content() == left_at
    _set_frame(page, 18)
    page.click("#timeline-keys li[data-frame='0'] .copy")  # back to the rest pose at 18
    page.wait_for_function("window.toonmotion.project.keys.keys.length === 3")
    copied = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert [k.frame for k in copied.keys] == [0, 12, 18]
    np.testing.assert_array_equal(copied.keys[2].pose.positions, copied.keys[0].pose.positions)
    # Undo takes the copy back, and the rate before it; redo makes both again; after a reload too.
    page.keyboard.press("Control+z")
    page.wait_for_function("window.toonmotion.project.keys.keys.length === 2")
    assert page.locator("#timeline-keys li").count() == 2
    page.click("#undo")
    page.wait_for_function("window.toonmotion.project.keys.fps === 12")
    assert load_keyframes(folder / "keys.json", api.load_project(folder).skeleton).fps == 12.0
    page.reload()
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    page.keyboard.press("Control+Shift+z")
    page.wait_for_function("window.toonmotion.project.keys.fps === 24")
    page.click("#redo")
    page.wait_for_function("window.toonmotion.project.keys.keys.length === 3")
    assert page.locator("#redo").is_disabled()
    again = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert [k.frame for k in again.keys] == [0, 12, 18]
    # On the ruler: drag the key at 12 to 10, click to go to frame 6, step with the arrow keys.
    at = """(frame) => { const r = document.getElementById('timeline-ruler').getBoundingClientRect();
        const span = Number(document.getElementById('timeline-scrub').max);
        return [r.left + 14 + frame / span * (r.width - 28), r.top + 32]; }"""
    page.mouse.move(*page.evaluate(at, 12))
    page.mouse.down()
    page.mouse.move(*page.evaluate(at, 10), steps=5)
    page.mouse.up()
    page.wait_for_function("window.toonmotion.project.keys.keys.some((k) => k.frame === 10)")
    moved = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert [k.frame for k in moved.keys] == [0, 10, 18]
    np.testing.assert_array_equal(moved.keys[1].pose.positions, again.keys[1].pose.positions)
    page.mouse.click(*page.evaluate(at, 6))
    page.wait_for_function("document.getElementById('timeline-frame').textContent === '6'")
    page.keyboard.press("ArrowRight")
    page.wait_for_function("document.getElementById('timeline-frame').textContent === '7'")
    page.keyboard.press("Control+z")  # the move undone: keys at 0, 12, 18 again
    page.wait_for_function("window.toonmotion.project.keys.keys.some((k) => k.frame === 12)")
    page.click("#timeline-scrub")  # a slider takes no typing: the panel keys still work from it
    page.keyboard.press("1")
    page.wait_for_function(
        "document.querySelector('nav button[data-panel=pose]').getAttribute('aria-pressed') === 'true'")
    assert page.errors == [] and page.locator("#error").is_hidden()



def test_two_tabs_stay_in_step_and_undo_says_what_it_undid(page, editor):
    """Issue 44: two tabs edited one server state but never saw each other's changes (a key
    deleted in one was still listed in the other). Now a key set in one appears in the other's
    timeline, and undoing it there takes it out of the first, each saying what was done."""
    other = page.context.browser.new_page(viewport={"width": 1280, "height": 800})
    other.goto(editor[0])
    other.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    for tab in (page, other):
        tab.click("nav button[data-panel=timeline]")
    frames = "[...document.querySelectorAll('#timeline-keys li')].map((li) => Number(li.dataset.frame))"
    before = page.evaluate(frames)
    assert other.evaluate(frames) == before
    _set_frame(page, 7)
    page.click("#timeline-key")
    other.wait_for_function(f"{frames}.includes(7)")
    assert other.locator("#status").text_content() == "another page: the key at frame 7 set"
    other.click("#undo")
    page.wait_for_function(f"!{frames}.includes(7)")
    assert page.evaluate(frames) == before
    assert page.locator("#status").text_content() == "another page undid: the key at frame 7 set"
    assert other.locator("#status").text_content() == "undid: the key at frame 7 set"
    other.close()
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_the_timeline_reaches_past_its_last_key(page, editor):
    """Issue 44: the timeline ended 12 frames past the last key, so a key could not be set
    further on. Stepping right now always finds a frame beyond."""
    page.click("nav button[data-panel=timeline]")
    last = max(page.evaluate("window.toonmotion.project.keys.keys.map((k) => k.frame)"))
    _set_frame(page, last)
    page.locator("#stage").click(position={"x": 5, "y": 5})  # the keys go to the page, not a field
    for _ in range(40):
        page.keyboard.press("ArrowRight")
    page.wait_for_function(
        "(f) => document.getElementById('timeline-frame').textContent === String(f)", arg=last + 40)
    assert int(page.get_attribute("#timeline-scrub", "max")) >= last + 40 + 12
    _set_frame(page, 0)



def test_a_link_in_the_project_is_refused_in_the_page_and_nothing_is_written(page, editor, tmp_path):
    """Issue 44: files were read and written through symbolic links. A link made in the project
    while the editor runs: keying a frame (which writes keys.json) is refused with the link named
    in the page's error bar, the file it points to is untouched, and with the link gone keying
    works again."""
    folder = editor[1]
    outside = tmp_path / "private.txt"
    outside.write_text("not the project's")
    link = folder / "exports" / "leak.gif"
    link.parent.mkdir(exist_ok=True)
    link.symlink_to(outside)
    try:
        page.click("nav button[data-panel=timeline]")
        _set_frame(page, 0)
        page.click("#timeline-key")
        page.wait_for_function("!document.getElementById('error').hidden")
        assert page.locator("#error").text_content().startswith(
            "exports/leak.gif in the project is a symbolic link; the editor reads, writes and deletes only")
        assert outside.read_text() == "not the project's"
    finally:
        link.unlink()
    page.click("#error")
    page.click("#timeline-key")
    page.wait_for_function("document.getElementById('status').textContent === 'saved'")
    assert page.locator("#error").is_hidden()

def test_a_pose_not_yet_keyed_survives_a_reload_and_scrubbing(page, editor):
    """Issue 44: a pose made and not keyed was lost on reload (the Pose panel showed the rest
    pose), and scrubbing replaced it without a word. Now it is kept at its frame: a reload opens
    on it, and the Timeline says it is kept when scrubbing away and shows it again there."""
    page.click("nav button[data-panel=timeline]")
    _set_frame(page, 3)
    page.click("nav button[data-panel=pose]")
    _drag(page, "left_hand", -30, -50)
    made = np.array(page.evaluate("window.toonmotion.pose"))
    page.reload()
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    np.testing.assert_allclose(page.evaluate("window.toonmotion.pose"), made, atol=1e-9)
    assert page.evaluate("window.toonmotion.frame") == 3
    page.click("nav button[data-panel=timeline]")
    _set_frame(page, 9)
    assert page.locator("#status").text_content() == \
        "the pose made at frame 3 is not keyed: it is kept there (K keys it)"
    assert not np.allclose(page.evaluate("window.toonmotion.pose"), made)
    _set_frame(page, 3)
    np.testing.assert_allclose(page.evaluate("window.toonmotion.pose"), made, atol=1e-9)
    assert page.locator("#status").text_content() == "the pose made at frame 3, not keyed yet (K keys it)"
    page.evaluate("() => { window.toonmotion.unkeyed = null; window.toonmotion.remember(); }")  # as found
    _set_frame(page, 0)
    assert page.errors == [] and page.locator("#error").is_hidden()

def test_export_the_keyed_animation_to_a_gif_with_progress(page, editor):
    folder = editor[1]
    page.click("nav button[data-panel=export]")
    page.fill("#export-name", "walk")
    page.select_option("#export-format", "gif")
    page.click("#export-go")
    page.wait_for_function(
        "document.getElementById('export-result').textContent.includes('exports/walk.gif')"
    )
    with Image.open(folder / "exports" / "walk.gif") as gif:
        assert gif.n_frames == 19  # frames 0 to 18 of the keys set in the Timeline test
    link = page.locator("#export-result a")
    assert link.get_attribute("download") == "walk.gif"
    assert page.locator("#export-progress").is_hidden() and page.errors == []
    page.wait_for_function("document.getElementById('export-preview').complete")
    assert page.locator("#export-preview").is_visible()  # the GIF plays in the page
    # The options: a size, a black background and the skeleton drawn over the drawing.
    page.fill("#export-name", "framed")
    page.fill("#export-width", "120")
    page.click("#export-go")  # a width without a height: said in the page, nothing sent
    page.wait_for_function("!document.getElementById('error').hidden")
    assert "width and height, or neither" in page.locator("#error").text_content()
    page.fill("#export-height", "160")
    page.select_option("#export-background", "#000000")
    page.check("input[name=export-overlay][value=skeleton]")
    page.click("#export-go")
    page.wait_for_function(
        "document.getElementById('export-result').textContent.includes('exports/framed.gif')"
    )
    with Image.open(folder / "exports" / "framed.gif") as gif:
        assert gif.size == (120, 160)
        corner = np.asarray(gif.convert("RGB"))[0, 0]
    assert corner.tolist() == [0, 0, 0]
    assert page.locator("#error").is_hidden()


def test_an_export_can_be_cancelled_and_the_file_before_it_is_kept(page, editor, monkeypatch):
    folder = editor[1]
    stopped = []
    for call in ("write_animation", "export_animation"):  # with overlays drawn, and without
        monkeypatch.setattr(api, call, slow_work(stopped))
    page.click("nav button[data-panel=export]")
    page.fill("#export-name", "kept")
    page.select_option("#export-format", "gif")
    before = b"GIF89a an export made before"
    (folder / "exports").mkdir(exist_ok=True)
    (folder / "exports" / "kept.gif").write_bytes(before)
    page.click("#export-go")
    page.wait_for_function("document.getElementById('export-progress').value > 0")
    page.click("#export-cancel")
    page.wait_for_function(
        "document.getElementById('status').textContent === 'export cancelled: nothing was written'")
    assert stopped == ["Cancelled"]
    assert (folder / "exports" / "kept.gif").read_bytes() == before
    assert page.locator("#export-cancel").is_hidden() and page.locator("#export-progress").is_hidden()
    assert page.locator("#error").is_hidden() and not page.locator("#export-go").is_disabled()


def test_export_a_spine_rig_and_a_sprite_sheet_with_a_link_per_file(page, editor):
    folder = editor[1]
    page.click("nav button[data-panel=export]")
    page.fill("#export-name", "hero")
    page.select_option("#export-format", "spine")
    # Size and background do not apply to a rig: the panel says so and disables them.
    assert page.locator("#export-rig-note").is_visible() and page.locator("#export-width").is_disabled()
    page.click("#export-go")
    page.wait_for_function("document.getElementById('export-result').textContent.includes('hero.spine.json')")
    links = page.locator("#export-result a")
    assert [links.nth(i).get_attribute("download") for i in range(links.count())] == [
        "hero.spine.json", "hero.spine.atlas", "hero.spine.png"]
    skeleton = json.loads((folder / "exports" / "hero.spine.json").read_text())
    assert skeleton["skeleton"]["spine"].startswith("4.2")
    page.select_option("#export-format", "sheet")
    assert page.locator("#export-width").is_enabled()
    page.click("#export-go")
    page.wait_for_function("document.getElementById('export-result').textContent.includes('hero.sheet.json')")
    atlas = json.loads((folder / "exports" / "hero.sheet.json").read_text())
    assert len(atlas["frames"]) == 19 and atlas["meta"]["image"] == "hero.sheet.png"
    page.wait_for_function("document.getElementById('export-preview').complete")
    assert page.locator("#export-preview").is_visible()  # the sheet shows in the page
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_exaggerate_fix_the_feet_and_draw_the_acceleration(page, editor):
    character = api.load_project(editor[1])
    page.click("nav button[data-panel=pose]")
    page.click("#pose-reset")
    page.click("nav button[data-panel=exaggerate]")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('fix joints')")
    for foot in ("right_foot", "left_foot"):
        page.mouse.click(*_joint_on_screen(page, foot))
    x, y = _joint_on_screen(page, "root")
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x, y - 60, steps=8)
    page.mouse.up()
    page.wait_for_timeout(400)
    page.click("#exaggerate-use")
    pose = np.asarray(page.evaluate("window.toonmotion.pose"))
    feet = [character.skeleton.index(f) for f in ("right_foot", "left_foot")]
    np.testing.assert_allclose(pose[feet], character.skeleton.positions[feet], atol=1e-9)  # held
    assert pose[character.skeleton.index("root"), 1] > character.skeleton.positions[0, 1] + 10  # squashed
    _close_to_golden(_stage(page), "exaggerated.png")
    page.click("#exaggerate-play")
    page.wait_for_timeout(600)
    page.click("#exaggerate-play")
    assert page.errors == []
    assert page.locator("#error").is_hidden(), page.locator("#error").text_content()


def test_rig_move_a_joint_and_rig_again(page, editor):
    """Last: it rigs the shared project again and reloads the page."""
    folder = editor[1]
    before = api.load_project(folder)
    page.click("nav button[data-panel=rig]")
    page.wait_for_function("document.getElementById('status').textContent === 'place the joints'")
    _close_to_golden(_stage(page), "rig.png")
    joints = page.evaluate("window.toonmotion.draft.length")
    page.mouse.click(40, 200)  # an empty spot, no joint selected: nothing added (a second root, before)
    assert page.evaluate("window.toonmotion.draft.length") == joints
    assert page.locator("#status").text_content().startswith("select a joint first")
    x, y = _joint_on_screen(page, "head")
    page.mouse.click(x, y)  # select the head
    page.mouse.click(x + 15, y)  # an empty spot: a new joint under the head, which the key-frames do not name
    assert page.evaluate("window.toonmotion.draft.length") == joints + 1
    assert page.evaluate("window.toonmotion.draft.at(-1).parent") == "head"
    page.click("#rig-go")
    page.wait_for_function("!document.getElementById('error').hidden")
    assert "keep their names" in page.locator("#error").text_content()
    # The message is clear of the stage's foot, where the timeline's ruler goes, and clicks away.
    box, stage = page.locator("#error").bounding_box(), page.locator("#stage").bounding_box()
    assert box["y"] + box["height"] < stage["y"] + stage["height"] - 44
    page.click("#error")
    assert page.locator("#error").is_hidden()
    page.click("#rig-delete")  # the new joint is selected: take it out again
    x, y = _joint_on_screen(page, "head")
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 4, y - 30, steps=5)
    page.mouse.up()
    with page.expect_navigation():
        page.click("#rig-go")
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    after = api.load_project(folder)
    head = after.skeleton.index("head")
    assert after.skeleton.names == before.skeleton.names
    assert after.skeleton.positions[head, 1] < before.skeleton.positions[head, 1] - 5
    assert len(after.edits) == len(before.edits)  # the region edits were replayed
    assert page.locator("#error").is_hidden()


def test_capture_names_the_joints_that_matched_poorly_and_goes_to_where(page, editor, tmp_path):
    """After tracking, the joints that matched poorly most are named, each a button to the frame
    where its longest such stretch starts; new footage clears them."""
    from toonmotion.io.motion_json import load_motion
    from toonmotion.samples import sample_character_on

    picture = sample_character_on("white", scale=0.5)[0]  # the character itself, walking right

    def send(name, cover=None):
        frames = []
        for t in range(6):
            frame = np.roll(picture, 2 * t, axis=1)
            if cover is not None and t >= 3:  # white paper over the left knee from frame 3 on
                x, y = np.round(cover + (2 * t, 0)).astype(int)
                frame[y - 20:y + 21, x - 20:x + 21] = 255
            frames.append(Image.fromarray(frame))
        frames[0].save(tmp_path / name, save_all=True, append_images=frames[1:], duration=80)
        page.evaluate("document.getElementById('status').textContent = ''")  # to wait for this footage's own
        page.set_input_files("#capture-file", str(tmp_path / name))
        page.wait_for_function("document.getElementById('status').textContent.startsWith('place the joints')")

    page.click("nav button[data-panel=capture]")
    send("plain.gif")
    # Where the page puts the knee (the project's, which other tests may have moved), and
    # rectangles small enough to stay in the frame wherever the joints now are.
    knee = np.array(page.evaluate("window.toonmotion.capture.joints().find((j) => j.name === 'left_knee')"
                                  ".position"))
    send("covered.gif", cover=knee)
    page.evaluate("window.toonmotion.capture.joints().forEach((j) => { j.size = [20, 20]; })")
    assert page.locator("#capture-poor").is_hidden()
    page.click("#capture-track")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('tracked')")
    motion = load_motion(editor[1] / "motions" / "captured.json")
    poorly = api.Capture(motion, first=0, angles=np.zeros(motion.positions.shape[:2]),
                         held=np.zeros(len(motion.positions), bool)).poorly_matched()
    named = page.locator("#capture-poor button")
    assert named.all_text_contents() == [f"{j.name}: {round(100 * j.fraction)}%, from frame {j.start}"
                                         for j in poorly]
    knee = named.filter(has_text="left_knee")  # the covered joint
    assert knee.text_content().endswith("from frame 3")
    knee.click()
    assert page.evaluate("document.getElementById('capture-scrub').value") == "3"
    send("plain.gif")
    assert page.locator("#capture-poor").is_hidden() and page.locator("#error").is_hidden()


def test_capture_send_footage_track_it_and_play_it_on_the_character(page, editor, tmp_path, monkeypatch):
    from toonmotion.io.motion_json import load_motion
    from toonmotion.samples import sample_character_on

    folder = editor[1]
    held, original = [], api.track_footage  # whether each tracking holds joints to the figure, chooses paths

    def tracking(*args, **kwargs):
        settings = kwargs["settings"]
        held.append((settings.figure, settings.best_path, settings.both_ways, settings.working_side,
                     kwargs["background"]))
        return original(*args, **kwargs)

    monkeypatch.setattr(api, "track_footage", tracking)
    picture = sample_character_on("white", scale=0.5)[0]  # the character itself, walking right
    frames = [Image.fromarray(np.roll(picture, 2 * t, axis=1)) for t in range(4)]
    frames[0].save(tmp_path / "walk.gif", save_all=True, append_images=frames[1:], duration=80)
    page.click("nav button[data-panel=capture]")
    page.set_input_files("#capture-file", str(tmp_path / "walk.gif"))
    page.wait_for_function("document.getElementById('status').textContent.startsWith('place the joints')")
    assert "4 frames of 210×300" in page.locator("#capture-info").text_content()
    # Size the head's rectangle by its corner: 10 footage px to the right and down of the centre.
    side = page.evaluate("window.toonmotion.capture.joints().find((j) => j.name === 'head').size[0]")
    hx, hy = page.evaluate("window.toonmotion.capture.screen('head')")
    scale = page.evaluate("""() => { const o = window.toonmotion.view.overlay, b = o.getBoundingClientRect();
        return Math.min(o.width / 210, o.height / 300) * 0.95 * b.width / o.width; }""")
    page.mouse.move(hx + side / 2 * scale, hy + side / 2 * scale)
    page.mouse.down()
    page.mouse.move(hx + 10 * scale, hy + 14 * scale, steps=4)
    page.mouse.up()
    assert page.evaluate("window.toonmotion.capture.joints().find((j) => j.name === 'head').size") == [20, 28]
    page.click("#capture-track")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('tracked')")
    notes = page.evaluate("window.toonmotion.project.capture.tracked.notes")  # shown when there are any
    assert page.locator("#capture-notes").is_visible() == bool(notes)
    assert page.locator("#capture-notes").text_content() == " ".join(notes)
    motion = load_motion(folder / "motions" / "captured.json")
    assert motion.positions.shape[0] == 4
    assert np.median(motion.positions[-1, :, 0] - motion.positions[0, :, 0]) == pytest.approx(6, abs=1)
    page.evaluate("""() => { const s = document.getElementById('capture-scrub');
        s.value = '2'; s.dispatchEvent(new Event('input')); }""")
    x, y = page.evaluate("window.toonmotion.capture.screen('head')")
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 30, y, steps=4)
    page.mouse.up()
    page.check("#capture-free")  # and this time, joints free of the figure, at full size, tracked both ways
    page.check("#capture-full-resolution")
    page.check("#capture-frame-by-frame")
    page.check("#capture-both-ways")  # which unticks each frame's own choice
    assert not page.is_checked("#capture-frame-by-frame")
    page.fill("#capture-paper-colour", "#fafaf0")  # picking the colour the footage is drawn on ticks it
    assert page.is_checked("#capture-paper")
    page.click("#capture-retrack")  # track again from frame 2 with the head moved
    page.wait_for_function("document.getElementById('status').textContent.startsWith('tracked')")
    assert held == [(True, True, False, 1000, None), (False, True, True, None, (250, 250, 240))]
    corrected = load_motion(folder / "motions" / "captured.json")
    head = corrected.skeleton.index("head")
    np.testing.assert_allclose(corrected.positions[:2], motion.positions[:2])  # kept before frame 2
    assert corrected.positions[2, head, 0] > motion.positions[2, head, 0] + 8
    # A long tracking can be stopped; the one before it stays, in the page and in the project.
    stopped, saved = [], (folder / "motions" / "captured.json").read_bytes()
    monkeypatch.setattr(api, "track_footage", slow_work(stopped))
    page.click("#capture-track")
    page.wait_for_function("document.getElementById('capture-progress').value > 0")
    page.click("#capture-cancel")
    page.wait_for_function("document.getElementById('status').textContent"
                           " === 'tracking cancelled: the earlier tracking is kept'")
    assert stopped == ["Cancelled"] and (folder / "motions" / "captured.json").read_bytes() == saved
    assert page.locator("#capture-cancel").is_hidden() and page.locator("#error").is_hidden()
    monkeypatch.setattr(api, "track_footage", tracking)
    page.click("#capture-play")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('the character plays')")
    page.wait_for_timeout(500)
    page.click("#capture-play")
    assert page.evaluate("document.getElementById('mesh').style.visibility") == "visible"
    # Another panel and back, or a reload: the footage and its tracking are as they were left.
    tracked = page.evaluate("window.toonmotion.capture.joints().map((j) => j.position)")
    page.click("nav button[data-panel=pose]")
    page.click("nav button[data-panel=capture]")
    assert "4 frames of 210×300" in page.locator("#capture-info").text_content()
    page.reload()
    page.wait_for_function("window.toonmotion && window.toonmotion.capture")
    page.click("nav button[data-panel=capture]")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('tracked')")
    assert "4 frames of 210×300" in page.locator("#capture-info").text_content()
    assert page.evaluate("window.toonmotion.capture.joints().map((j) => j.position)") == tracked
    assert not page.is_disabled("#capture-play") and page.locator("#error").is_hidden()
    # A folder of frames, named as cameras and renderers number them (f_2 before f_10).
    shots = tmp_path / "shots"
    shots.mkdir()
    for t in (1, 2, 10):
        Image.fromarray(np.roll(picture, t, axis=1)).save(shots / f"f_{t}.png")
    page.set_input_files("#capture-frames", str(shots))
    page.wait_for_function("document.getElementById('status').textContent.startsWith('place the joints')")
    assert "3 frames of 210×300" in page.locator("#capture-info").text_content()
    last = np.asarray(Image.open(io.BytesIO(page.request.get(
        editor[0].replace("/?", "/api/footage/2.png?")).body())).convert("RGB"))
    np.testing.assert_array_equal(last, np.asarray(Image.open(shots / "f_10.png").convert("RGB")))
    # The suggestions follow the colour the footage is drawn on. Drawn on white in a black frame,
    # the border says black, and the joints suggested run round the frame; told it is white, the
    # page suggests them on the character.
    page.uncheck("#capture-paper")
    framed = picture.copy()
    framed[:3] = framed[-3:] = framed[:, :3] = framed[:, -3:] = 30
    Image.fromarray(framed).save(tmp_path / "framed.png")
    page.set_input_files("#capture-file", str(tmp_path / "framed.png"))
    # (The status said so for the frames before it too: wait for this picture's own.)
    page.wait_for_function("document.getElementById('capture-info').textContent.startsWith('1 frames')")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('place the joints')")
    character = np.argwhere(picture.min(axis=2) < 200)
    (top, left), (bottom, right) = character.min(axis=0), character.max(axis=0)

    def on_character(joints):
        xy = np.array([j["position"] for j in joints])
        return bool(((xy >= (left, top)) & (xy <= (right, bottom))).all())

    assert not on_character(page.evaluate("window.toonmotion.capture.suggestions()"))
    assert page.input_value("#capture-paper-colour") == "#1e1e1e"  # the border's colour, told from
    page.fill("#capture-paper-colour", "#ffffff")
    page.wait_for_function("document.getElementById('status').textContent.includes("
                           "'joints suggested on the figure drawn on #ffffff')")
    again = page.evaluate("window.toonmotion.capture.suggestions()")
    assert len(again) > 2 and on_character(again)
    # After playing the motion on the character, new footage is shown again; leaving the panel
    # takes it off the stage.
    drawn = """() => { const o = window.toonmotion.view.overlay, pen = o.getContext('2d');
        const alpha = pen.getImageData(0, 0, o.width, o.height).data;
        let opaque = 0;
        for (let i = 3; i < alpha.length; i += 4) if (alpha[i]) opaque++;
        return [o.width, o.height, opaque]; }"""
    assert page.evaluate(drawn)[2] > 0  # the footage is back on the stage after playing
    page.click("nav button[data-panel=export]")
    assert page.evaluate(drawn)[2] == 0
    assert page.errors == [] and page.locator("#error").is_hidden()



def test_capture_starts_the_joints_on_the_figure_wherever_it_stands_in_the_frame(page, editor, tmp_path):
    """Issue 44: the starting joints were the drawing's scaled onto the whole frame, so on footage
    whose figure does not fill it they lay off the figure and the first Track was refused. They
    are now laid onto the figure the footage's own suggestions find."""
    from toonmotion.samples import sample_character_on

    picture = sample_character_on("white", scale=0.5)[0]  # 210x300
    frame = np.full((360, 560, 3), 255, np.uint8)
    frame[40:340, 320:530] = picture[..., :3]  # the figure small, in the right of a wide frame
    frames = [Image.fromarray(np.roll(frame, 2 * t, axis=1)) for t in range(4)]
    frames[0].save(tmp_path / "aside.gif", save_all=True, append_images=frames[1:], duration=80)
    page.click("nav button[data-panel=capture]")
    page.set_input_files("#capture-file", str(tmp_path / "aside.gif"))
    page.wait_for_function("document.getElementById('status').textContent.startsWith('place the joints')")
    figure = (frame < 200).any(axis=2)
    near = np.zeros_like(figure)  # the figure and 6 px round it
    ys, xs = np.nonzero(figure)
    for dy in range(-6, 7, 3):
        for dx in range(-6, 7, 3):
            near[np.clip(ys + dy, 0, 359), np.clip(xs + dx, 0, 559)] = True
    for joint in page.evaluate("window.toonmotion.capture.joints()"):
        x, y = (int(round(v)) for v in joint["position"])
        assert 0 <= x < 560 and 0 <= y < 360 and near[y, x], joint
    page.click("#capture-track")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('tracked')",
                           timeout=60_000)
    assert page.errors == [] and page.locator("#error").is_hidden(), page.locator("#error").text_content()

def test_fine_tune_drag_a_point_and_sketch_the_outline_then_key_them(page, editor):
    from toonmotion.deform.tuning import CurveEdit, DragEdit
    from toonmotion.io.pose_json import load_keyframes

    folder = editor[1]
    character = api.load_project(folder)
    page.click("nav button[data-panel=pose]")
    page.click("#pose-reset")
    page.wait_for_timeout(300)
    page.keyboard.press("p")
    head = character.skeleton.positions[character.skeleton.index("head")]
    top = character.mesh.V[np.argmin(np.where(np.abs(character.mesh.V[:, 0] - head[0]) < 6,
                                              character.mesh.V[:, 1], np.inf))]  # the top of the hair
    (x0, y0), (x1, y1) = _on_screen(page, [top, top + [0, -15]])
    page.mouse.move(x0, y0)
    page.mouse.down()
    page.mouse.move(x1, y1, steps=5)
    page.mouse.up()
    page.wait_for_function("window.toonmotion.tuning.length === 1")
    page.keyboard.press("t")
    hand = character.skeleton.positions[character.skeleton.index("right_hand")]
    curve = [hand + [-14, -30 + 6 * k] for k in range(11)]  # beside the arm's outer edge
    screen = _on_screen(page, curve)
    page.mouse.move(*screen[0])
    page.mouse.down()
    for xy in screen[1:]:
        page.mouse.move(*xy)
    page.mouse.up()
    page.wait_for_function("window.toonmotion.tuning.length === 2")
    page.wait_for_timeout(400)
    assert page.locator("#error").is_hidden(), page.locator("#error").text_content()
    edits = page.evaluate("window.toonmotion.tuning")
    served = np.reshape(page.evaluate("Array.from(window.toonmotion.view.vertices)"), (-1, 2))
    expected = api.pose_character(character, Pose(character.skeleton.positions), edits=[
        DragEdit(edits[0]["from"], edits[0]["to"]), CurveEdit(edits[1]["points"])]).deformation.U
    np.testing.assert_allclose(served, expected, atol=1e-2)  # the library's fine-tuning, drawn
    assert served[:, 1].min() < character.mesh.V[:, 1].min() - 10  # the tuft went up
    page.click("nav button[data-panel=timeline]")
    _set_frame(page, 20)
    page.evaluate("() => { const c = window.toonmotion; c.pose = c.project.joints.map((j) => j.position); }")
    page.evaluate("() => { window.toonmotion.tuning = " + str(edits).replace("'", '"') + "; }")
    page.click("#timeline-key")
    page.wait_for_function("(window.toonmotion.project.keys?.keys || []).some((k) => k.frame === 20)")
    keyed = load_keyframes(folder / "keys.json", character.skeleton)
    assert [type(e).__name__ for e in keyed.keys[-1].edits] == ["DragEdit", "CurveEdit"]  # saved with the key
    page.keyboard.press("Control+z")  # and undone like any key edit
    page.wait_for_function("!(window.toonmotion.project.keys?.keys || []).some((k) => k.frame === 20)")
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_rig_load_a_skeleton_file_open_a_redrawn_drawing_and_undo_it(page, editor, tmp_path):
    from toonmotion.io.char_cfg import save_char_cfg
    from toonmotion.rig.skeleton import Skeleton

    folder = editor[1]
    character = api.load_project(folder)
    page.click("nav button[data-panel=rig]")
    page.check("#rig-show-mask")
    page.wait_for_timeout(300)
    assert page.errors == [] and page.locator("#error").is_hidden()
    # A skeleton file: the same joints with the head 5 px higher.
    joints = [(n, p, (x, y - 5 if n == "head" else y)) for n, p, (x, y) in character.skeleton.joints()]
    save_char_cfg(tmp_path / "char_cfg.yaml", Skeleton.from_joints(joints), character.size)
    page.set_input_files("#rig-skeleton-file", str(tmp_path / "char_cfg.yaml"))
    page.wait_for_function("document.getElementById('status').textContent.startsWith('loaded')")
    head = page.evaluate("window.toonmotion.draft.find((j) => j.name === 'head').position")
    assert head == pytest.approx(joints[character.skeleton.index("head")][2], abs=1e-3)  # as the file has it
    # The artist redrew the character (here: recoloured): open it, keeping the skeleton and keys.
    page.evaluate("""() => { const c = window.toonmotion, rest = c.project.joints.map((j) => j.position);
        return c.live.request({ type: "set_key", frame: 0, positions: rest }); }""")
    redrawn = character.texture.copy()
    redrawn[..., :3] = 255 - redrawn[..., :3]
    Image.fromarray(redrawn).save(tmp_path / "redrawn.png")
    page.set_input_files("#rig-drawing", str(tmp_path / "redrawn.png"))
    page.wait_for_function("!document.getElementById('rig-open').disabled")
    page.click("#rig-open")
    page.wait_for_load_state("load")
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=60_000)
    opened = api.load_project(folder)
    np.testing.assert_array_equal(opened.texture[..., :3], redrawn[..., :3])
    assert (folder / "keys.json").exists()  # the key-frames still name these joints
    page.keyboard.press("Control+z")  # the old drawing comes back (the page reloads for it)
    page.wait_for_function("window.toonmotion?.project?.history?.redo === 1", timeout=30_000)
    np.testing.assert_array_equal(api.load_project(folder).texture, character.texture)
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_a_sign_in_code_opens_the_editor_and_leaves_no_token_in_the_address(page, tmp_path):
    """What ``toonmotion edit --open`` gives the browser: a code good once. The page it opens
    works on the cookie alone (the project, the texture, a live drag), its address carries neither
    the code nor the token, and the page's script cannot read the cookie."""
    from toonmotion.web.server import sign_in_code

    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    with serving(folder) as served:
        port, token = served.port, served.token
        fresh = page.context.browser.new_page(viewport={"width": 1280, "height": 800})  # its own cookies
        fresh.goto(f"http://127.0.0.1:{port}/?code={sign_in_code(served.app)}")
        fresh.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
        assert fresh.url == f"http://127.0.0.1:{port}/"
        assert token not in fresh.evaluate("document.cookie")
        reply = fresh.evaluate("""async () => {
            const c = window.toonmotion;
            return await c.live.request({type: "pose", positions: c.project.joints.map((j) => j.position)});
        }""")
        assert reply["type"] == "mesh"
        fresh.close()
