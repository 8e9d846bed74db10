"""The line of action (keyshape/line_of_action.py, Bregler et al. section 4): open lines resampled
by arc length, captured with key lines (a straight one among them), and retargeted onto a chain
of the bundled character's skeleton; the command that does it from files."""

import json

import numpy as np
import pytest

from tests.conftest import run_cli
from toonmotion import api
from toonmotion.errors import KeyShapeError, SkeletonError
from toonmotion.io.keyshape_json import load_contours, save_contours
from toonmotion.keyshape.line_of_action import (
    capture_lines,
    captured_lines,
    chain_joints,
    default_chain,
    resample_line,
    retarget_line,
)
from toonmotion.keyshape.model import check_shapes, warp
from toonmotion.keyshape.retarget import pin
from toonmotion.rig.kinematics import bone_angles
from toonmotion.samples import sample_rig

N = 40


def _curve(x):
    """A line 120 px long up the screen, bulging sideways by ``x(u)``, u from 0 (bottom) to 1."""
    u = np.linspace(0, 1, 400)
    return resample_line(np.stack([x(u), -120 * u], axis=1), N)


@pytest.fixture(scope="module")
def key_lines():
    """Straight; a C bulging right; a reverse C bulging left, highest near the top (not a mirror
    of the C, so no key is a blend of the others)."""
    return np.stack([_curve(lambda u: 0 * u), _curve(lambda u: 40 * np.sin(np.pi * u)),
                     _curve(lambda u: -45 * np.sin(np.pi * u) ** 2 * (0.5 + u))])


@pytest.fixture(scope="module")
def hero():
    return sample_rig()


def _clip(keys, frames=12, seed=0):
    rng = np.random.default_rng(seed)
    affine, weights = [], []
    for _ in range(frames):
        angle = rng.uniform(-0.4, 0.4)
        c, s = np.cos(angle), np.sin(angle)
        turn = rng.uniform(0.7, 1.3) * np.array([[c, -s], [s, c]])
        affine.append(np.column_stack([turn, rng.uniform(-80, 80, 2) + 200]))
        weights.append(rng.dirichlet(np.ones(len(keys))))
    lines = np.stack([warp(A, w, keys) for A, w in zip(affine, weights, strict=True)])
    return lines, np.array(affine), np.array(weights)


def test_resample_line_spaces_points_evenly_and_keeps_both_ends():
    polyline = [(0, 0), (3, 4), (3, 4), (10, 4), (10, -6)]  # a repeated point adds no length
    line = resample_line(polyline, 23)
    steps = np.hypot(*np.diff(line, axis=0).T)
    np.testing.assert_allclose(line[0], (0, 0), atol=0)
    np.testing.assert_allclose(line[-1], (10, -6), atol=0)
    # Every step is the same arc length (a chord cutting a corner is shorter, so along a
    # straight run; the run from (3, 4) to (10, 4) holds steps of exactly 22 / 22 px).
    inside = [i for i in range(22) if line[i, 1] == 4 and line[i + 1, 1] == 4]
    np.testing.assert_allclose(steps[inside], 1.0, atol=1e-12)
    np.testing.assert_allclose(steps.sum(), 22, atol=1.5)  # corners cut by at most a step
    straight = resample_line([(5, 5), (5, 105)], 11)
    np.testing.assert_allclose(np.diff(straight[:, 1]), 10, atol=1e-12)


@pytest.mark.parametrize(("polyline", "message"), [
    ([(1, 1)], "at least 2 distinct points"),
    ([(1, 1), (1, 1), (1, 1)], "at least 2 distinct points"),
    ([(0, 0), (np.nan, 1)], "finite"),
    ([1, 2, 3], "list of \\[x, y\\] points"),
])
def test_resample_line_refuses_bad_lines_in_one_line(polyline, message):
    with pytest.raises(KeyShapeError, match=message) as info:
        resample_line(polyline, 10)
    assert "\n" not in str(info.value)
    with pytest.raises(KeyShapeError, match="2 to 100,000 points"):
        resample_line([(0, 0), (1, 1)], 1)


def test_a_straight_key_line_is_accepted_on_this_path_only(key_lines):
    with pytest.raises(KeyShapeError, match="one line"):
        check_shapes(key_lines[:1])  # closed contours: still refused
    assert check_shapes(key_lines[:1], allow_straight=True).shape == (1, N, 2)
    with pytest.raises(KeyShapeError, match="all one point"):
        check_shapes([[(3, 3)] * 5], allow_straight=True)
    found = capture_lines(key_lines[:1] + [10, 0], key_lines)  # the straight key itself, moved
    assert found.error[0] < 1e-6
    np.testing.assert_allclose(found.weights[0], [1, 0, 0], atol=1e-6)


@pytest.mark.parametrize("K", [2, 3])
def test_noise_free_lines_are_captured_back(key_lines, K):
    keys = key_lines[:K]
    lines, affine, weights = _clip(keys, seed=K)
    found = capture_lines(lines, keys)
    assert found.error.max() < 1e-6
    np.testing.assert_allclose(found.weights, weights, atol=1e-6)
    np.testing.assert_allclose(found.affine, affine, atol=1e-6)
    np.testing.assert_allclose(captured_lines(found, keys), lines, atol=1e-6)


def _chain_polyline(skeleton, chain, per_bone=6):
    """The chain's rest polyline, with points along every bone (the joints among them)."""
    P = skeleton.positions[chain_joints(skeleton, chain)]
    t = np.linspace(0, 1, per_bone, endpoint=False)[:, None]
    inner = [a + t * (b - a) for a, b in zip(P[:-1], P[1:], strict=True)]
    return np.concatenate([*inner, P[-1:]])


ARM = ("root", "hip", "torso", "right_shoulder", "right_elbow", "right_hand")


@pytest.mark.parametrize("chain", [None, ARM, ("root", "left_hip", "left_knee", "left_foot")])
def test_a_line_along_the_chains_rest_polyline_gives_the_rest_pose(hero, chain):
    skeleton = hero.skeleton
    line = _chain_polyline(skeleton, chain)
    for drawn in (line, line[::-1]):
        posed = retarget_line([drawn], skeleton, chain)
        np.testing.assert_allclose(posed[0], skeleton.positions, atol=1e-6)


def test_another_rest_pose_is_bent_the_same_way(hero):
    skeleton = hero.skeleton
    pose = api.rotate_joint(hero, "torso", 0.4).positions  # the neck and head bent at the torso
    line = pose[chain_joints(skeleton, None)]  # the joints themselves (the first two coincide)
    posed = retarget_line([line], skeleton, rest=pose)
    np.testing.assert_allclose(posed[0], pose, atol=1e-6)


def test_the_default_chain_is_the_spine_and_bad_chains_are_one_line(hero):
    skeleton = hero.skeleton
    assert default_chain(skeleton) == ("root", "hip", "torso", "neck", "head")
    for chain, error, message in [
        (("hip", "neck", "head"), KeyShapeError, "'hip' is not the parent of 'neck'"),
        (("head", "neck"), KeyShapeError, "'head' is not the parent of 'neck'"),
        (("hip", "tail"), SkeletonError, "no joint is called 'tail'"),
        (("hip",), KeyShapeError, "at least 2 joints"),
        (("hip", "torso", "hip"), KeyShapeError, "twice"),
    ]:
        with pytest.raises(error, match=message) as info:
            retarget_line([_chain_polyline(skeleton, None)], skeleton, chain)
        assert "\n" not in str(info.value)
    with pytest.raises(KeyShapeError, match="direction must be one of"):
        retarget_line([_chain_polyline(skeleton, None)], skeleton, direction="up")


@pytest.fixture(scope="module")
def bent(hero, key_lines):
    """The character bent along captured lines of action (3 keys, 12 frames)."""
    lines, _, _ = _clip(key_lines, seed=7)
    model = captured_lines(capture_lines(lines, key_lines), key_lines)
    return model, retarget_line(model, hero.skeleton)


def test_chain_bones_keep_their_rest_lengths_and_follow_the_line(hero, bent):
    skeleton = hero.skeleton
    lines, posed = bent
    _, lengths = bone_angles(skeleton, posed)
    np.testing.assert_allclose(lengths, np.broadcast_to(skeleton.bone_lengths, lengths.shape), atol=1e-9)
    # The chain's first joint sits on the line's start (in the character's frame: only moved
    # and scaled from the first frame's), and moves with it.
    root = skeleton.index("root")
    spine = [skeleton.bone_names.index(n) for n in ("hip", "torso", "neck", "head")]
    scale = skeleton.bone_lengths[spine].sum() / np.hypot(*np.diff(lines[0], axis=0).T).sum()
    np.testing.assert_allclose(posed[:, root] - posed[0, root], scale * (lines[:, 0] - lines[0, 0]),
                               atol=1e-9)


def test_joints_off_the_chain_hang_rigidly_from_their_parents(hero, bent):
    skeleton = hero.skeleton
    _, posed = bent
    chain = set(chain_joints(skeleton, None).tolist())
    rest_angles, _ = bone_angles(skeleton, skeleton.positions)
    angles, _ = bone_angles(skeleton, posed)
    row = {int(child): r for r, child in enumerate(skeleton.bones[:, 1])}
    checked = 0
    for j in range(len(skeleton)):
        parent = int(skeleton.parents[j])
        if j in chain or parent < 0 or skeleton.bone_lengths[row[j]] == 0:
            continue
        if parent not in row or skeleton.bone_lengths[row[parent]] == 0:  # hangs from a root
            continue
        turned = angles[:, row[j]] - rest_angles[row[j]]
        parent_turned = angles[:, row[parent]] - rest_angles[row[parent]]
        np.testing.assert_allclose(np.angle(np.exp(1j * (turned - parent_turned))), 0, atol=1e-9)
        checked += 1
    assert checked >= 6  # both arms' shoulders, elbows and hands; both legs' knees and feet
    # What hangs from the root (the legs) turns with the line's chord, end to end.
    lines = bent[0]
    chord = lines[:, -1] - lines[:, 0]
    turn = np.arctan2(chord[:, 1], chord[:, 0]) - np.arctan2(-1.0, 0.0)  # the spine points up at rest
    for leg in ("left_hip", "right_hip"):
        turned = angles[:, row[skeleton.index(leg)]] - rest_angles[row[skeleton.index(leg)]]
        np.testing.assert_allclose(np.angle(np.exp(1j * (turned - turn))), 0, atol=1e-9)
    # A whole arm moves as one rigid body with the torso bone it hangs from.
    arm = [skeleton.index(n) for n in ("torso", "right_shoulder", "right_elbow", "right_hand")]
    rest = skeleton.positions[arm]
    for frame in posed[:, arm]:
        np.testing.assert_allclose(np.hypot(*(frame[:, None] - frame[None]).transpose(2, 0, 1)),
                                   np.hypot(*(rest[:, None] - rest[None]).transpose(2, 0, 1)), atol=1e-9)


def test_a_line_drawn_the_other_way_gives_the_same_pose(hero, bent):
    lines, posed = bent
    np.testing.assert_allclose(retarget_line(lines[:, ::-1], hero.skeleton), posed, atol=1e-9)
    np.testing.assert_allclose(retarget_line(lines[:, ::-1], hero.skeleton, direction="tip-first"), posed,
                               atol=1e-9)
    flipped = retarget_line(lines, hero.skeleton, direction="tip-first")  # told wrong: head down
    head, root = hero.skeleton.index("head"), hero.skeleton.index("root")
    assert (flipped[:, head, 1] > flipped[:, root, 1]).all()


def test_pins_hold_a_joint_on_the_result(hero, bent):
    _, posed = bent
    foot = hero.skeleton.index("left_foot")
    pinned = pin(posed, foot, {0: posed[0, foot], 11: posed[0, foot]})
    np.testing.assert_allclose(pinned[[0, 11], foot], posed[[0, 0], foot], atol=1e-9)
    motion = api.retarget_line_of_action(bent[0], bent[0][[0, 5, 9]], hero.skeleton,
                                         pin=("left_foot", {t: (140.0, 280.0) for t in range(12)}))
    np.testing.assert_allclose(motion.positions[:, foot], np.tile([140.0, 280.0], (12, 1)), atol=1e-9)


def test_open_lines_load_resampled_and_straight(tmp_path, key_lines):
    raw = [np.array([(0.0, 0), (0, -50), (0, -120)]), np.array([(0.0, 0), (30, -60), (0, -120)])]
    (tmp_path / "lines.json").write_text(json.dumps({"format": "toonmotion.contours", "version": 1,
                                                     "closed": False, "contours": [r.tolist() for r in raw]}))
    lines, _, closed = load_contours(tmp_path / "lines.json", points=9)
    assert not closed and lines.shape == (2, 9, 2)
    np.testing.assert_allclose(lines[:, 0], [(0, 0), (0, 0)], atol=1e-12)
    np.testing.assert_allclose(lines[:, -1], [(0, -120), (0, -120)], atol=1e-12)
    with pytest.raises(KeyShapeError, match="a start point is for closed contours"):
        load_contours(tmp_path / "lines.json", points=9, start=(0, 0))
    svg = """<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200">
      <path d="M 100,190 C 130,140 130,60 100,10" fill="none"/>
      <path d="M 100,190 L 100,10" fill="none"/>
    </svg>"""
    (tmp_path / "lines.svg").write_text(svg)
    lines, _, closed = load_contours(tmp_path / "lines.svg", points=25, closed=False)
    assert not closed and lines.shape == (2, 25, 2)
    np.testing.assert_allclose(lines[:, 0], [(100, 190)] * 2, atol=1e-6)
    np.testing.assert_allclose(lines[:, -1], [(100, 10)] * 2, atol=1e-6)
    np.testing.assert_allclose(np.diff(lines[1, :, 1]), -7.5, atol=1e-6)


def test_the_command_retargets_a_lines_file_onto_the_sample_character(tmp_path, hero, key_lines, capsys):
    from toonmotion.io.motion_json import load_motion

    api.save_project(tmp_path / "hero", hero)
    lines, _, _ = _clip(key_lines, frames=6, seed=3)
    save_contours(tmp_path / "lines.json", lines[:, ::-1], fps=8, closed=False)  # drawn head to hip
    save_contours(tmp_path / "keys.json", key_lines[:, ::-1], closed=False)
    assert run_cli("retarget-line", tmp_path / "lines.json", "--keys", tmp_path / "keys.json",
                "--project", tmp_path / "hero", "-o", tmp_path / "motion.json") == 0
    assert "retargeted 6 frames" in capsys.readouterr().out
    motion = load_motion(tmp_path / "motion.json")
    assert motion.positions.shape == (6, len(hero.skeleton), 2) and motion.fps == 8
    model = captured_lines(capture_lines(lines, key_lines), key_lines)
    np.testing.assert_allclose(motion.positions, retarget_line(model, hero.skeleton), atol=1e-5)
    # Frames as keys, another chain, and the motion renders.
    assert run_cli("retarget-line", tmp_path / "lines.json", "--key-frames", "0,2,4", "--chain",
                "hip,torso,neck", "--project", tmp_path / "hero", "-o", tmp_path / "frames.json") == 0
    assert run_cli("animate", tmp_path / "hero", tmp_path / "frames.json", "-o", tmp_path / "out.gif") == 0
    assert (tmp_path / "out.gif").stat().st_size > 0


@pytest.mark.parametrize(("extra", "message"), [
    (["--keys", "KEYS", "--chain", "hip,neck"], "'hip' is not the parent of 'neck'"),
    (["--keys", "KEYS", "--chain", "hip,tail"], "no joint is called 'tail'"),
    (["--key-frames", "0,9"], "--key-frames"),
    ([], "--keys"),
])
def test_the_command_refuses_bad_input_in_one_line(tmp_path, hero, key_lines, capsys, extra, message):
    api.save_project(tmp_path / "hero", hero)
    save_contours(tmp_path / "lines.json", _clip(key_lines, frames=3)[0], closed=False)
    save_contours(tmp_path / "keys.json", key_lines, closed=False)
    (tmp_path / "motion.json").write_text("earlier")
    argv = [str(tmp_path / "keys.json") if a == "KEYS" else a for a in extra]
    code = run_cli("retarget-line", tmp_path / "lines.json", *argv, "--project", tmp_path / "hero",
                "-o", tmp_path / "motion.json")
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert (tmp_path / "motion.json").read_text() == "earlier"


def test_the_commands_help_names_its_options(capsys):
    assert run_cli("retarget-line", "--help") == 0
    out = capsys.readouterr().out
    for option in ("--keys", "--key-frames", "--project", "--chain", "--direction", "--points", "-o"):
        assert option in out
