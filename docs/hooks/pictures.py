"""MkDocs hook: the guides' pictures, made from real runs of the library each time the docs build.

Before the site is built, the bundled character is rigged, posed, animated, exaggerated, tracked,
lifted into 3D and given a balloon, and a key-shape model is made of the sample cartoon; each
result is drawn into ``docs/pictures/`` (ignored by git), where the guides link to it. Nothing is
downloaded: the 3D pictures take their motion-capture prior from the shared clips beside the
project (``../shared/data/mocap``, or ``TOONMOTION_MOCAP``); without them those two pictures are
drawn as a note saying so. Pictures newer than every source file are kept.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

ROOT = Path(__file__).resolve().parents[2]
PRIOR = "cmu_16_07_jump.bvh"
PICTURES = ("rig", "animation", "exaggerated", "tracking", "keyshapes", "proxy", "scene")


def on_pre_build(config, **kwargs):
    out = Path(config["docs_dir"]) / "pictures"
    out.mkdir(exist_ok=True)
    newest = max(p.stat().st_mtime for p in (ROOT / "src").rglob("*.py"))
    paths = [out / f"{name}.png" for name in PICTURES]
    if all(p.is_file() and p.stat().st_mtime > newest for p in paths):
        return
    _make(out)


def _make(out: Path) -> None:
    from toonmotion import api
    from toonmotion.render.overview import render_overview
    from toonmotion.render.sequence import render_animation
    from toonmotion.render.track_overlay import draw_tracking
    from toonmotion.sample_animation import sample_keyframes
    from toonmotion.samples import sample_rig

    hero = sample_rig()
    keys = sample_keyframes(hero.skeleton)
    render_overview(hero, height=360).save(out / "rig.png")

    animation = api.animate_character(hero, keys)
    shown = [0, 6, 12, 18, 24, 30]
    frames = list(render_animation(hero, animation, background=(255, 255, 255), overlays=("skeleton",)))
    _strip([frames[i] for i in shown]).save(out / "animation.png")

    exaggerated = api.animate_character(hero, keys, exaggeration=api.FilterSettings(strength=1.5))
    plain = list(render_animation(hero, animation, background=(255, 255, 255)))
    filtered = list(render_animation(hero, exaggerated, background=(255, 255, 255)))
    both = [_strip([plain[i] for i in shown]), _strip([filtered[i] for i in shown])]
    _rows(both).save(out / "exaggerated.png")

    footage = np.stack([frame[..., :3] for frame in plain])
    skeleton, sizes = api.suggest_joints(footage)
    motion = api.track_footage(footage, joints=(skeleton, sizes), fps=keys.fps).motion
    tracked = [draw_tracking(footage[i], motion.positions[i], sizes, np.asarray(skeleton.parents),
                             confidence=motion.confidence[i]) for i in shown]
    _strip(tracked).save(out / "tracking.png")

    from toonmotion.sample_cartoons import character_keys

    space = api.keyshape_space(character_keys(), inbetweens=3)
    Image.fromarray(api.keyshape_sheet(space)).save(out / "keyshapes.png")

    prior = _prior()
    if prior is None:
        for name in ("proxy", "scene"):
            _note(f"no motion-capture prior found ({PRIOR}): set TOONMOTION_MOCAP").save(out / f"{name}.png")
        return
    from toonmotion.io.bvh import load_bvh

    proxy, _ = api.lift_proxy(api.motion_in_frames(hero, animation), load_bvh(prior), frames=footage,
                              view=(0.0, 0.0))
    previews = api.preview_proxy(proxy, footage)
    _strip([previews[i] for i in shown[:4]]).save(out / "proxy.png")
    drawn, limbs = api.animation_frames(hero, animation, proxy)
    motion3d = api.simulate_scene(proxy, [api.Balloon("right_hand"), api.Balls("left_foot")])
    scene = list(api.composite_scene(proxy, drawn, motion3d, limbs=limbs))
    _strip([scene[i] for i in shown]).save(out / "scene.png")


def _prior() -> Path | None:
    for folder in (os.environ.get("TOONMOTION_MOCAP"), ROOT.parent / "shared" / "data" / "mocap"):
        if folder and (Path(folder) / PRIOR).is_file():
            return Path(folder) / PRIOR
    return None


def _strip(pictures, gap: int = 6) -> Image.Image:
    """Pictures side by side on white, each laid on white if it has an alpha channel."""
    images = [Image.fromarray(np.asarray(p)).convert("RGBA") for p in pictures]
    height = max(im.height for im in images)
    strip = Image.new("RGB", (sum(im.width for im in images) + gap * (len(images) - 1), height), "white")
    x = 0
    for im in images:
        strip.paste(im, (x, 0), im)
        x += im.width + gap
    return strip


def _rows(strips, gap: int = 6) -> Image.Image:
    width = max(s.width for s in strips)
    sheet = Image.new("RGB", (width, sum(s.height for s in strips) + gap * (len(strips) - 1)), "white")
    y = 0
    for s in strips:
        sheet.paste(s, (0, y))
        y += s.height + gap
    return sheet


def _note(text: str) -> Image.Image:
    picture = Image.new("RGB", (640, 60), "white")
    ImageDraw.Draw(picture).text((10, 20), text, fill="black")
    return picture
