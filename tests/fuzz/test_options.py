"""Hostile option values for every command (see harness.py for the property).

Each case takes a command line that works and replaces one option's value with a hostile one:
zero, negative, tiny, huge, beyond 64 bits, not a number, empty, or the wrong shape.
"""

from __future__ import annotations

import shutil

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.harness import check, digest, run_cli
from tests.fuzz.mutate import HOSTILE_OPTION_NUMBERS, not_a_finite_number
from tests.fuzz.test_files import _workspace

# command line, then {option: kind}; kind "number" must be a finite number, "text" anything.
COMMANDS = {
    "rig": (
        ["rig", "hero.png", "--skeleton", "hero.json", "-o", "OUT"],
        {"--spacing": "number", "--vertices": "number", "--tolerance": "number", "--max-pixels": "number"},
    ),
    "show": (["show", "P", "-o", "out.png"], {"--height": "number"}),
    "pose": (
        ["pose", "P", "pose.json", "-o", "out.png"],
        {
            "--size": "text",
            "--joint-width": "number",
            "--accel": "text",
            "--weights": "text",
            "--background": "text",
            "--overlay": "text",
        },
    ),
    "pose-accel": (["pose", "P", "pose.json", "-o", "out.png", "--fixed", "root"], {"--accel": "text"}),
    "animate": (
        ["animate", "P", "keys.json", "-o", "anim.gif", "--size", "40x60"],
        {
            "--fps": "number",
            "--exaggerate": "number",
            "--sigma": "number",
            "--shift": "number",
            "--size": "text",
            "--ease": "text",
        },
    ),
    "filter": (
        ["filter", "motion.json", "-o", "out.json", "--strength", "1"],
        {"--strength": "number", "--sigma": "number", "--shift": "number", "--joints": "text"},
    ),
    "track": (
        ["track", "frames", "--joints", "joints.json", "-o", "out.json"],
        {"--search": "number", "--fps": "number", "--background": "text"},
    ),
    "tune": (["tune", "P", "pose.json"], {"--drag": "text", "--curve": "text", "--key": "number"}),
    "depth": (["depth", "P"], {"": "text"}),
    "correct": (["correct", "P", "head"], {"": "text"}),
    "remesh": (["remesh", "P"], {"--vertices": "number", "--spacing": "number"}),
    "undo": (["undo", "P"], {"--steps": "number"}),
    "redo": (["redo", "P"], {"--steps": "number"}),
    "retarget": (
        ["retarget", "motion.json", "P", "-o", "re.gif", "--size", "40x60"],
        {
            "--map": "text",
            "--exaggerate": "number",
            "--sigma": "number",
            "--size": "text",
            "--output": "path",
        },
    ),
    "sample": (["sample", "-o", "s.png"], {"--skeleton": "path", "--keys": "path", "--output": "path"}),
    "pose-output": (["pose", "P", "pose.json"], {"--output": "path"}),
    "animate-output": (
        ["animate", "P", "keys.json", "--size", "40x60"],
        {"--output": "path", "--save-motion": "path"},
    ),
    "filter-output": (["filter", "motion.json", "--strength", "1"], {"--output": "path"}),
}

# Output paths: odd names and suffixes, folders that exist, nested folders that do not (nothing outside
# the scratch folder, and never its parent).
PATHS = [
    "",
    ".",
    "out",
    "out.txt",
    "out.PNG",
    "out.gif",
    "out.mp4",
    "out.json",
    "out.yaml",
    "P",
    "hero.png",
    "frames",
    "new/deeper/out.png",
    "new/deeper/",
    "out_%04d.png",
    "out_%d_%d.png",
    "out_{}.png",
    "x" * 300,
    "out.json/inner.png",
]

TEXTS = [
    "",
    ",",
    "1,2",
    "1,2,3",
    "nan,nan",
    "1e308,1e308",
    "-1e308,1",
    "0,0:1e12,1e12",
    "10,10:1e9,1e9",
    "1,1 2,2 3,3",
    "head=1e30",
    "head=" + str(10**30),
    "@1e9,1e9=1",
    "-100,-100",
    "x" * 1000,
    "root",
    "0x0",
    "100000x100000",
    "16384x16384",
    "-5x5",
    "#zzzzzz",
    "mesh,bogus",
    "in-out",
    "bogus",
]


@given(command=st.sampled_from(sorted(COMMANDS)), data=st.data())
def test_hostile_option_values(valid, command, data):
    argv, options = COMMANDS[command]
    option = data.draw(st.sampled_from(sorted(options)), label="option")
    kind = options[option]
    choices = {"number": HOSTILE_OPTION_NUMBERS, "path": PATHS}.get(kind, TEXTS + HOSTILE_OPTION_NUMBERS)
    value = data.draw(st.sampled_from(choices), label="value")
    extra = [value] if not option else [option, value]
    if command == "correct" and value:
        extra = [value, "60,60", "80,80"]
    must_refuse = kind == "number" and not_a_finite_number(value)
    work = _workspace(valid)
    try:
        kept = {work / o: digest(work / o) for o in ("OUT", "out.png", "out.json")}
        check(
            run_cli([*argv, *extra], work),
            kind=f"option {command} {option}".strip(),
            must_refuse=must_refuse,
            kept=kept,
        )
    finally:
        shutil.rmtree(work, ignore_errors=True)
