"""The core types hold: construction copies arrays, the copies are read-only, bad fields are
refused with a one-line error, and ``dataclasses.replace`` still works (issue 10)."""

import dataclasses
from functools import lru_cache

import numpy as np
import pytest

from toonmotion.animate.motion import Motion, motion_from_timeline
from toonmotion.animate.timeline import Keyframe, Timeline
from toonmotion.deform.deformer import Deformation, Deformer, DeformSettings
from toonmotion.deform.depth import Overlap
from toonmotion.deform.needles import NeedleModel, needle_model
from toonmotion.deform.solve_result import SolveResult
from toonmotion.deform.tuning import CurveEdit, DragEdit
from toonmotion.errors import (
    EditError,
    KeyframeError,
    MeshError,
    MotionError,
    PoseError,
    SettingsError,
    SkeletonError,
)
from toonmotion.geometry.arrays import finite_float, frozen_array, frozen_arrays
from toonmotion.rig.binding import Binding, Correction, CorrectionError, binding_from_bones
from toonmotion.rig.character import Character
from toonmotion.rig.edits import DepthEdit, apply_edit
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import CurveSkeleton
from toonmotion.shape.mesh import Mesh
from toonmotion.shape.silhouette import Part, Silhouette

# --- small instances of every type, built from fresh arrays the test owns ---------------------


def _square():
    return {
        "V": np.array([[0, 0], [0, 1], [1, 1], [1, 0]], dtype=float),
        "F": np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64),
        "boundary": (np.arange(4),),
        "spacing": 1.0,
    }


def _skeleton_fields():
    return {
        "names": ("hip", "knee", "foot"),
        "parents": np.array([-1, 0, 1], dtype=np.int64),
        "positions": np.array([[0.0, 0.0], [0.0, 5.0], [1.0, 10.0]]),
    }


SKELETON = Skeleton(**_skeleton_fields())
MESH = Mesh(**_square())


def _binding_fields():
    return {
        "bone": np.array([0, 0, 1, 1], dtype=np.int64),
        "fallback": np.zeros(4, dtype=bool),
        "corrections": (),
        "joint_triangle": np.array([True, True]),
        "vertex_kind": np.zeros(4, dtype=np.int8),
        "joint_area": np.ones(4, dtype=bool),
    }


@lru_cache
def _bar():
    """A rigged 120 x 40 bar with a three-joint skeleton (fast to rig)."""
    mask = np.zeros((40, 120), dtype=bool)
    mask[8:32, 5:115] = True
    rgba = np.zeros(mask.shape + (4,), dtype=np.uint8)
    rgba[mask] = (200, 120, 40, 255)
    skeleton = Skeleton.from_joints(
        [("a", None, (10.0, 20.0)), ("b", "a", (60.0, 20.0)), ("c", "b", (110.0, 20.0))]
    )
    character = rig_drawing(rgba, skeleton=skeleton)
    box = np.array([[90.0, 5.0], [118.0, 5.0], [118.0, 35.0], [90.0, 35.0]])
    character = apply_edit(character, Correction(curve=box, bone="b"))
    return apply_edit(character, DepthEdit(value=2, bone="c"))


def _character_fields():
    ch = _bar()
    fields = {f.name: getattr(ch, f.name) for f in dataclasses.fields(ch)}
    fields.update(texture=np.array(ch.texture), mask=np.array(ch.mask), depth=np.array(ch.depth))
    return fields


def _curve_skeleton_fields():
    return {
        "nodes": np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.0]]),
        "kinds": ("end", "end", "junction"),
        "radius": np.array([1.0, 1.0, 2.0]),
        "branches": np.array([[2, 0], [2, 1]], dtype=np.int64),
        "paths": (np.array([[2.0, 3.0], [0.0, 0.0]]), np.array([[2.0, 3.0], [4.0, 0.0]])),
    }


def _needle_fields():
    return {
        "bones": np.array([[0, 1], [1, 2]], dtype=np.int64),
        "bone": np.array([0, 1, 1], dtype=np.int64),
        "t": np.array([0.5, 0.2, 0.9]),
        "s": np.array([1.0, -2.0, 0.0]),
        "rest_length": np.array([5.0, 5.1]),
        "rest_direction": np.array([[1.0, 0.0], [0.0, 1.0]]),
        "rigid": np.array([False, False]),
        "offset": np.zeros((3, 2)),
    }


def _outcome_fields():
    return {"U": np.arange(6, dtype=float).reshape(3, 2), "iterations": 4, "energy_start": 2.0,
            "energy": 1.0, "converged": True}


def _motion_fields():
    positions = np.stack([SKELETON.positions + k for k in range(4)])
    return {"skeleton": SKELETON, "positions": positions, "fps": 12.0, "confidence": np.full((4, 3), 0.5)}


# type -> a function giving fresh keyword arguments of a valid instance
FIELDS = {
    Mesh: _square,
    Part: lambda: {"outer": np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]),
                   "holes": (np.array([[1.0, 1.0], [1.0, 2.0], [2.0, 2.0]]),)},
    CurveSkeleton: _curve_skeleton_fields,
    Skeleton: _skeleton_fields,
    Binding: _binding_fields,
    Correction: lambda: {"curve": np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0]]), "bone": "knee"},
    Character: _character_fields,
    Pose: lambda: {"positions": np.array([[0.0, 0.0], [1.0, 6.0], [2.0, 11.0]])},
    NeedleModel: _needle_fields,
    Deformation: lambda: {**_outcome_fields(), "stage_one": np.ones((3, 2))},
    SolveResult: _outcome_fields,
    CurveEdit: lambda: {"points": np.array([[0.0, 0.0], [5.0, 1.0]])},
    DragEdit: lambda: {"start": np.array([[1.0, 1.0]]), "end": np.array([[2.0, 3.0]])},
    Motion: _motion_fields,
}
ARRAY_TYPES = list(FIELDS)


def _caller_arrays(fields):
    """``(field, index or None, array)`` for every array among the keyword arguments."""
    for name, value in fields.items():
        if isinstance(value, np.ndarray):
            yield name, None, value
        elif isinstance(value, tuple):
            for i, item in enumerate(value):
                if isinstance(item, np.ndarray):
                    yield name, i, item


def _held(obj, name, index):
    value = getattr(obj, name)
    return value if index is None else value[index]


def _arrays_in(obj, seen=None):
    """Every ndarray reachable from ``obj`` through dataclass fields and tuples."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        yield obj
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            yield from _arrays_in(getattr(obj, f.name), seen)
    elif isinstance(obj, tuple | list):
        for item in obj:
            yield from _arrays_in(item, seen)


# --- copies, read-only, replace -----------------------------------------------------------


@pytest.mark.parametrize("cls", ARRAY_TYPES, ids=lambda c: c.__name__)
def test_construction_copies_the_callers_arrays(cls):
    fields = FIELDS[cls]()
    obj = cls(**fields)
    arrays = list(_caller_arrays(fields))
    assert arrays
    for name, index, mine in arrays:
        held = _held(obj, name, index)
        assert held is not mine and not np.shares_memory(held, mine), name
        before = held.copy()
        if mine.dtype == bool:
            mine[...] = ~mine
        else:
            mine[...] = 7
        assert mine.flags.writeable, f"{cls.__name__}.{name}: the caller's array was frozen"
        np.testing.assert_array_equal(held, before, err_msg=f"{cls.__name__}.{name}")


@pytest.mark.parametrize("cls", ARRAY_TYPES, ids=lambda c: c.__name__)
def test_arrays_are_read_only_and_c_contiguous(cls):
    obj = cls(**FIELDS[cls]())
    arrays = list(_arrays_in(obj))
    assert arrays
    for array in arrays:
        assert not array.flags.writeable and array.flags.c_contiguous
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0


@pytest.mark.parametrize("cls", ARRAY_TYPES, ids=lambda c: c.__name__)
def test_replace_works_and_copies_again(cls):
    obj = cls(**FIELDS[cls]())
    again = dataclasses.replace(obj)
    for name, index, _ in _caller_arrays(FIELDS[cls]()):
        np.testing.assert_array_equal(_held(again, name, index), _held(obj, name, index))
        assert not _held(again, name, index).flags.writeable
    name, index, mine = next(_caller_arrays(FIELDS[cls]()))
    if index is None:
        changed = dataclasses.replace(obj, **{name: mine})
        assert _held(changed, name, None) is not mine and not _held(changed, name, None).flags.writeable


def test_the_mesh_examples_setters_are_refused():
    mesh = Mesh(**_square())
    with pytest.raises(ValueError, match="read-only"):
        mesh.V[0] = 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        mesh.V = np.zeros((4, 2))


def test_a_rigged_characters_every_array_is_read_only():
    character = _bar()
    assert character.edits and len(character.binding.corrections) == 1
    arrays = list(_arrays_in(character))
    # texture, mask, depth 3; silhouette loop 1; curve skeleton 4+; skeleton 2; mesh 3+;
    # binding 5; the correction's curve 1
    assert len(arrays) >= 19
    for array in arrays:
        assert not array.flags.writeable
    deformer = Deformer(character)
    pose = Pose(rotate_about(character.skeleton, character.skeleton.positions, "b", 0.4))
    deformation = deformer.deform(pose)
    for obj in (deformer.needles, deformation, pose):
        for array in _arrays_in(obj):
            assert not array.flags.writeable


def test_rigging_copies_the_callers_drawing():
    mask = np.zeros((40, 120), dtype=bool)
    mask[8:32, 5:115] = True
    rgba = np.zeros(mask.shape + (4,), dtype=np.uint8)
    rgba[mask] = (200, 120, 40, 255)
    skeleton = Skeleton.from_joints([("a", None, (10.0, 20.0)), ("b", "a", (110.0, 20.0))])
    character = rig_drawing(rgba, skeleton=skeleton)
    rgba[...] = 0
    assert rgba.flags.writeable and character.texture[20, 60, 3] == 255


def test_skeleton_no_longer_freezes_the_callers_arrays():
    fields = _skeleton_fields()
    skeleton = Skeleton(**fields)
    assert fields["positions"].flags.writeable and fields["parents"].flags.writeable
    fields["positions"][0] = 99.0
    assert skeleton.positions[0, 0] == 0.0


def test_a_motion_sampled_from_a_timeline_and_its_poses_are_frozen():
    rest = Pose(SKELETON.positions)
    timeline = Timeline(keys=(Keyframe(0, rest), Keyframe(4, Pose(SKELETON.positions + 1.0))), fps=8)
    motion = motion_from_timeline(SKELETON, timeline)
    assert not motion.pose(2).positions.flags.writeable
    assert not motion.positions.flags.writeable


# --- bad fields are refused with one line -----------------------------------------------------


def _one_line(info):
    assert "\n" not in str(info.value)


BAD = [
    (Mesh, {"V": np.zeros((4, 3))}, MeshError, r"mesh's V must have shape \(n, 2\), got \(4, 3\)"),
    (Mesh, {"V": np.full((4, 2), np.nan)}, MeshError, "V has a non-finite value"),
    (Mesh, {"F": np.array([[0, 1, 4]])}, MeshError, "F names a vertex that does not exist"),
    (Mesh, {"F": np.array([[0, 1, -1]])}, MeshError, "F names a vertex that does not exist"),
    (Mesh, {"F": np.array([[0.0, 1.5, 2.0]])}, MeshError, "whole numbers"),
    (Mesh, {"boundary": (np.arange(5),)}, MeshError, "boundary names a vertex that does not exist"),
    (Mesh, {"spacing": 0.0}, MeshError, "spacing must be a finite number > 0, got 0.0"),
    (Part, {"outer": np.zeros((2, 2))}, MeshError, "needs at least 3 points, got 2"),
    (Part, {"holes": (np.zeros((3, 3)),)}, MeshError, r"holes\[0\] must have shape \(n, 2\)"),
    (CurveSkeleton, {"kinds": ("end", "end", "knot")}, SkeletonError, "one kind per node"),
    (CurveSkeleton, {"radius": np.ones(2)}, SkeletonError, r"radius must have shape \(3,\)"),
    (CurveSkeleton, {"branches": np.array([[0, 3], [2, 1]])}, SkeletonError, "names a node that does not"),
    (CurveSkeleton, {"paths": ()}, SkeletonError, "2 branches but 0 paths"),
    (Skeleton, {"parents": np.array([-1, 2, 0])}, SkeletonError, "parents first"),
    (Skeleton, {"parents": np.array([-1, 0])}, SkeletonError, r"parents must have shape \(3,\)"),
    (Skeleton, {"positions": np.zeros((3, 3))}, SkeletonError, r"positions must have shape \(3, 2\)"),
    (Skeleton, {"names": ("hip", "hip", "foot")}, SkeletonError, "'hip' is used twice"),
    (Skeleton, {"names": ("hip", "", "foot")}, SkeletonError, "non-empty string"),
    (Binding, {"fallback": np.zeros(3, bool)}, ValueError, r"fallback must have shape \(4,\)"),
    (Binding, {"bone": np.array([0, -1, 1, 1])}, ValueError, "bone indices must be >= 0"),
    (Binding, {"vertex_kind": np.full(4, 5, np.int8)}, ValueError, "vertex kinds must be"),
    (Binding, {"joint_area": np.ones(4, np.int64)}, ValueError, "must hold true/false values"),
    (Correction, {"curve": np.zeros((2, 2))}, CorrectionError, "at least 3"),
    (Correction, {"curve": [[0, 0], [1, np.inf], [2, 2]]}, CorrectionError, "non-finite"),
    (Correction, {"bone": 3}, CorrectionError, "by a string"),
    (Character, {"mask": np.zeros((3, 3), bool)}, ValueError, r"mask must have shape \(40, 120\)"),
    (Character, {"texture": np.zeros((40, 120, 3), np.uint8)}, ValueError, r"texture must have shape"),
    (Character, {"depth": np.zeros(5)}, ValueError, r"depth needs one value per bone \(2\)"),
    (Character, {"mesh": MESH}, ValueError, "the binding is for another mesh"),
    (Character, {"skeleton": "skeleton"}, TypeError, "skeleton must be a Skeleton, got str"),
    (Pose, {"positions": np.zeros((3, 3))}, PoseError, r"pose's positions must have shape \(n, 2\)"),
    (Pose, {"positions": [["a", "b"]]}, PoseError, "must hold numbers"),
    (NeedleModel, {"bone": np.array([0, 2, 1])}, ValueError, "name bones outside"),
    (NeedleModel, {"t": np.zeros(2)}, ValueError, r"t must have shape \(3,\)"),
    (Deformation, {"stage_one": np.ones((4, 2))}, ValueError, r"stage_one must have shape \(3, 2\)"),
    (Deformation, {"iterations": -1}, ValueError, "iterations must be a whole number >= 0"),
    (SolveResult, {"U": np.zeros(3)}, ValueError, r"U must have shape \(n, 2\)"),
    (SolveResult, {"energy": "low"}, ValueError, "energy must be a number"),
    (CurveEdit, {"points": [[0, 0]]}, EditError, "at least 2 points"),
    (DragEdit, {"end": np.zeros((2, 2))}, EditError, "1 start points but 2 end points"),
    (Motion, {"confidence": np.full((4, 3), 2.0)}, MotionError, "between 0 and 1"),
    (Motion, {"positions": np.zeros((4, 2, 2))}, MotionError, r"shape \(frames, 3, 2\)"),
]


@pytest.mark.parametrize(("cls", "change", "error", "message"), BAD,
                         ids=[f"{c.__name__}-{next(iter(ch))}" for c, ch, _, _ in BAD])
def test_bad_fields_are_refused_in_one_line(cls, change, error, message):
    fields = {**FIELDS[cls](), **change}
    with pytest.raises(error, match=message) as info:
        cls(**fields)
    _one_line(info)


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (lambda: Silhouette(parts=(np.zeros((3, 2)),)), TypeError, "must be Part objects"),
        (lambda: Silhouette(parts=(), tolerance=-1.0), MeshError, "tolerance must be a finite number >= 0"),
        (lambda: DepthEdit(value=1, bone=5), EditError, "names its bone by a string"),
        (lambda: DepthEdit(value=1, at=("x", 2)), EditError, "give two numbers"),
        (lambda: Overlap("a", "b", -1.0, False), ValueError, "area must be a finite number >= 0"),
        (lambda: Overlap("a", None, 1.0, False), TypeError, "names two bones"),
        (lambda: DeformSettings(preserve_area="yes"), SettingsError, "preserve_area must be true or false"),
        (lambda: Keyframe(0, SKELETON.positions), TypeError, "pose must be a Pose"),
        (lambda: Keyframe(0, Pose(SKELETON.positions), ("drag",)), TypeError, "CurveEdit or DragEdit"),
        (lambda: Timeline(keys=(), fps=12), KeyframeError, "there are no key-frames"),
        (lambda: Timeline(keys=(Keyframe(4, Pose(SKELETON.positions)), Keyframe(2, Pose(SKELETON.positions))),
                          fps=12), KeyframeError, r"in frame order, each frame once; got \[4, 2\]"),
        (lambda: Timeline(keys=(Keyframe(-1, Pose(SKELETON.positions)),), fps=12), KeyframeError,
         "whole numbers >= 0, got -1"),
        (lambda: Timeline(keys=(Keyframe(0, Pose(SKELETON.positions)),), fps=0), KeyframeError,
         "fps must be a finite number > 0, got 0"),
        (lambda: Timeline(keys=(Keyframe(0, Pose(SKELETON.positions)),), fps=12, ease="bounce"),
         KeyframeError, "ease must be one of"),
    ],
    ids=["silhouette-parts", "silhouette-tolerance", "depth-bone", "depth-at", "overlap-area",
         "overlap-bones", "settings-flag", "key-pose", "key-edits", "no-keys", "key-order", "key-frame",
         "timeline-fps", "timeline-ease"],
)
def test_types_without_arrays_check_themselves(make, error, message):
    with pytest.raises(error, match=message) as info:
        make()
    _one_line(info)


def test_types_without_arrays_are_typed_and_replace_works():
    silhouette = Silhouette(parts=[Part(outer=[[0, 0], [4, 0], [4, 4]])], tolerance=1)
    assert isinstance(silhouette.parts, tuple) and silhouette.tolerance == 1.0
    assert dataclasses.replace(silhouette, tolerance=2).tolerance == 2.0
    settings = DeformSettings(weights=[1, 2, 3], joint_width=1)
    assert settings.weights == (1.0, 2.0, 3.0) and isinstance(settings.joint_width, float)
    assert dataclasses.replace(settings, stage_two=False).weights == (1.0, 2.0, 3.0)
    key = Keyframe(3, Pose(SKELETON.positions), [CurveEdit(points=[[0, 0], [1, 1]])])
    assert isinstance(key.edits, tuple)
    timeline = Timeline(keys=[key], fps=np.float64(12))
    assert isinstance(timeline.keys, tuple) and type(timeline.fps) is float
    assert dataclasses.replace(timeline, ease="in").ease == "in"
    overlap = Overlap("a", "b", np.float64(2.5), np.bool_(True))
    assert type(overlap.area) is float and overlap.same_depth is True
    edit = dataclasses.replace(DepthEdit(value=np.int64(2), at=(1, 2)), value=3)
    assert edit.at == (1.0, 2.0) and edit.value == 3
    outcome = SolveResult(**{**_outcome_fields(), "iterations": np.int64(2), "converged": np.bool_(False)})
    assert type(outcome.iterations) is int and outcome.converged is False


def test_binding_from_bones_and_needle_model_give_frozen_types():
    binding = binding_from_bones(MESH, [0, 0, 1, 1], np.zeros(4, bool))
    assert binding.vertex_kind.dtype == np.int8 and not binding.bone.flags.writeable
    needles = needle_model(MESH.V, SKELETON, binding.bone)
    assert all(not a.flags.writeable for a in _arrays_in(needles))


# --- frozen_array itself --------------------------------------------------------------------------


def test_frozen_array_copies_converts_and_freezes():
    mine = [[1, 2], [3, 4]]
    out = frozen_array(mine, dtype=np.float64, shape=(None, 2))
    assert out.dtype == np.float64 and not out.flags.writeable and out.flags.c_contiguous
    fortran = np.asfortranarray(np.arange(6.0).reshape(2, 3))
    assert frozen_array(fortran, dtype=np.float64).flags.c_contiguous
    assert frozen_array([1.0, 2.0], dtype=np.int64).tolist() == [1, 2]
    # Even a read-only array is copied: a writeable view of it may be held elsewhere.
    owner = np.zeros(3)
    writer = owner[:]
    owner.setflags(write=False)
    kept = frozen_array(owner, dtype=np.float64)
    writer[0] = 1.0
    assert kept is not owner and kept[0] == 0.0


@pytest.mark.parametrize(
    ("value", "dtype", "shape", "message"),
    [
        ([1.5], np.int64, None, "must hold whole numbers that fit int64"),
        ([np.nan], np.int64, None, "must hold whole numbers that fit int64"),
        ([300], np.uint8, None, "must hold whole numbers that fit uint8"),
        ([1, 0], np.bool_, None, "must hold true/false values, got int64"),
        (["x"], np.float64, None, "must hold numbers"),
        ([[1], [1, 2]], np.float64, None, "must be an array of numbers of one shape"),
        (np.zeros((2, 3, 2)), np.float64, (None, None), r"must have shape \(n, m\), got \(2, 3, 2\)"),
        (np.zeros(3), np.float64, (4,), r"must have shape \(4,\), got \(3,\)"),
    ],
)
def test_frozen_array_refuses_what_does_not_fit(value, dtype, shape, message):
    with pytest.raises(SettingsError, match=f"^the thing {message}") as info:
        frozen_array(value, dtype=dtype, shape=shape, name="the thing", error=SettingsError)
    _one_line(info)


def test_frozen_array_finiteness_and_sequences():
    with pytest.raises(ValueError, match="x has a non-finite value"):
        frozen_array([1.0, np.inf], dtype=np.float64, name="x", finite=True)
    loops = frozen_arrays([[0, 1], [2, 3, 4]], dtype=np.int64, shape=(None,), name="loops")
    assert [loop.tolist() for loop in loops] == [[0, 1], [2, 3, 4]]
    with pytest.raises(ValueError, match=r"loops\[1\] must have shape"):
        frozen_arrays([[0, 1], [[2]]], dtype=np.int64, shape=(None,), name="loops")
    with pytest.raises(ValueError, match="loops must be a sequence of arrays"):
        frozen_arrays(3, dtype=np.int64, name="loops")


@pytest.mark.parametrize("value", [True, "3", None, float("nan"), float("inf"), -1.0])
def test_finite_float_refuses(value):
    with pytest.raises(ValueError, match="spacing must be a finite number >= 0"):
        finite_float(value, name="spacing", minimum=0)
