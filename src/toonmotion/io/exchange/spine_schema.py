"""A pydantic model of the part of Spine 4.2's skeleton JSON that :mod:`.spine_json` writes.

Written from Spine's "JSON export format" page (esotericsoftware.com/spine-json-format) and the
4.2 runtime's reader (spine-runtimes, ``spine-ts/spine-core/src/SkeletonJson.ts``); field names
and defaults are theirs, so dumping with ``by_alias=True, exclude_defaults=True`` leaves out what
a runtime assumes anyway. The subset:

- ``skeleton``: ``spine`` (the version; 4.2 here), ``x, y, width, height`` (the setup pose's
  bounding box, ``x, y`` its bottom-left corner), ``fps``, ``images``.
- ``bones``, parents before children, the first one the root (no parent): ``name``, ``parent``,
  ``length``, ``x``, ``y``, ``rotation`` (degrees), ``scaleX``, ``scaleY``, ``shearX``,
  ``shearY``, ``inherit`` (``"normal"`` unless said; 4.2's name for 3.x's ``transform``).
- ``slots``: ``name``, ``bone``, ``attachment`` (shown in the setup pose).
- ``skins``: a list of ``{"name", "attachments": {slot: {name: attachment}}}``; the only
  attachment type modelled is ``"mesh"``: ``uvs`` (2 per vertex, within the region), ``triangles``
  (3 vertex indices each), ``vertices`` (``x, y`` per vertex when as long as ``uvs``, else
  weighted: per vertex a bone count, then per bone its index in ``bones``, ``x, y`` in that
  bone's setup frame and a weight), ``hull`` (how many vertices, first in the list, make the outer
  hull), ``width``/``height`` (the image's size, nonessential).
- ``animations``: ``{name: {"bones": {bone: {"rotate": [{time, value}], "translate": [{time, x,
  y}], "scale": [{time, x, y}]}}, "attachments": {skin: {slot: {attachment: {"deform": [{time,
  offset, vertices}]}}}}}}``. Rotate and translate values add to the setup pose's, scale values
  multiply it; a deform key's ``vertices`` are offsets starting ``offset`` numbers in (the rest
  zero), 2 per weighted entry (bone-local), and a key without ``vertices`` offsets nothing.

Beyond types, :class:`SpineFile` checks the rules the documentation and the reader rely on: the
version is 4.2, the first bone is the root and every other bone's parent comes before it, names
are unique and every name referred to exists, triangles index existing vertices, weighted
vertices describe exactly as many vertices as ``uvs`` do and name existing bones, the hull is no
longer than the mesh, timeline keys come in increasing time and deform keys fit their mesh.

Examples
--------
>>> file = SpineFile.model_validate({
...     "skeleton": {"spine": "4.2.00"}, "bones": [{"name": "root"}, {"name": "arm", "parent": "root"}],
...     "slots": [{"name": "body", "bone": "root"}]})
>>> [bone.name for bone in file.bones], file.bones[1].scale_x
(['root', 'arm'], 1.0)
>>> from pydantic import ValidationError
>>> try:
...     SpineFile.model_validate({"skeleton": {"spine": "4.2.00"}, "bones": [{"name": "a", "parent": "b"}]})
... except ValidationError as error:
...     print(error.errors()[0]["msg"][:60])
the first bone, 'a', has a parent; Spine's first bone is the
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, StrictStr, model_validator

from toonmotion.errors import ExportError
from toonmotion.io.schema import Float, Int, Model, Name, problem, read_json, validate

VERSION = "4.2"

# A count, an index or a coordinate in a weighted ``vertices`` list: ints stay ints.
Number = Int | Float
Inherit = Literal["normal", "onlyTranslation", "noRotationOrReflection", "noScale", "noScaleOrReflection"]
_Time = Annotated[Float, Field(ge=0)]


class SkeletonHeader(Model):
    """The ``skeleton`` section."""

    spine: StrictStr
    x: Float = 0.0
    y: Float = 0.0
    width: Float = 0.0
    height: Float = 0.0
    fps: Float = 30.0
    images: StrictStr | None = None

    @model_validator(mode="after")
    def _version(self) -> SkeletonHeader:
        if self.spine.split(".")[:2] != VERSION.split("."):
            raise problem(f"'spine' is {self.spine!r}; this is a model of Spine {VERSION}'s JSON "
                          f"(a version {VERSION}.x)")
        return self


class BoneEntry(Model):
    """One of ``bones``: the bone's setup pose relative to its parent."""

    name: Name
    parent: StrictStr | None = None
    length: Float = 0.0
    x: Float = 0.0
    y: Float = 0.0
    rotation: Float = 0.0
    scale_x: Float = Field(1.0, alias="scaleX")
    scale_y: Float = Field(1.0, alias="scaleY")
    shear_x: Float = Field(0.0, alias="shearX")
    shear_y: Float = Field(0.0, alias="shearY")
    inherit: Inherit = "normal"


class SlotEntry(Model):
    """One of ``slots``: a place in the draw order, on a bone."""

    name: Name
    bone: Name
    attachment: StrictStr | None = None


class MeshAttachment(Model):
    """A ``"type": "mesh"`` attachment (see the module docstring)."""

    type: Literal["mesh"]
    path: StrictStr | None = None
    uvs: list[Float]
    triangles: list[Annotated[Int, Field(ge=0)]]
    vertices: list[Number]
    hull: Annotated[Int, Field(ge=0)] = 0
    width: Float = 0.0
    height: Float = 0.0

    @property
    def vertex_count(self) -> int:
        return len(self.uvs) // 2

    @property
    def weighted(self) -> bool:
        """Spine's own test: vertices as long as the uvs are plain ``x, y`` pairs."""
        return len(self.vertices) != len(self.uvs)

    def weighted_bones(self) -> list[list[int]]:
        """Each vertex's bone indices (weighted meshes only; the layout is checked already)."""
        out, i = [], 0
        for _ in range(self.vertex_count):
            count = int(self.vertices[i])
            out.append([int(self.vertices[i + 1 + 4 * k]) for k in range(count)])
            i += 1 + 4 * count
        return out

    @model_validator(mode="after")
    def _consistent(self) -> MeshAttachment:
        n = self.vertex_count
        if len(self.uvs) % 2:
            raise problem(f"'uvs' has {len(self.uvs)} numbers; it needs a u, v pair per vertex")
        if len(self.triangles) % 3:
            raise problem(f"'triangles' has {len(self.triangles)} indices; it needs 3 per triangle")
        if self.triangles and max(self.triangles) >= n:
            raise problem(f"'triangles' index vertex {max(self.triangles)}, but the mesh has {n} vertices "
                          "('uvs' give one u, v pair per vertex)")
        if self.hull > n:
            raise problem(f"'hull' is {self.hull}, more than the mesh's {n} vertices")
        if self.weighted:
            _check_weighted(self.vertices, n)
        return self


def _check_weighted(vertices: list[int | float], n: int) -> None:
    """Weighted ``vertices`` must describe exactly ``n`` vertices: per vertex a bone count >= 1 and
    that many (bone index, x, y, weight) entries."""
    i = 0
    for v in range(n):
        if i >= len(vertices):
            raise problem(f"weighted 'vertices' end after {v} of the {n} vertices 'uvs' give (or, "
                          f"unweighted, they need {2 * n} numbers)")
        count = vertices[i]
        if not float(count).is_integer() or count < 1:
            raise problem(f"weighted 'vertices': vertex {v}'s bone count is {count!r}; it must be a whole "
                          "number >= 1")
        end = i + 1 + 4 * int(count)
        if end > len(vertices):
            raise problem(f"weighted 'vertices' end inside vertex {v}'s {int(count)} bone entries")
        for k in range(i + 1, end, 4):
            if not float(vertices[k]).is_integer() or vertices[k] < 0:
                raise problem(f"weighted 'vertices': vertex {v} names bone index {vertices[k]!r}; bone "
                              "indices are whole numbers >= 0")
        i = end
    if i != len(vertices):
        raise problem(f"weighted 'vertices' hold {len(vertices) - i} numbers beyond the {n} vertices "
                      "'uvs' give")


class SkinEntry(Model):
    """One of ``skins``: attachments by slot name, then by attachment name."""

    name: Name
    attachments: dict[str, dict[str, MeshAttachment]] = {}


class RotateKey(Model):
    time: _Time = 0.0
    value: Float = 0.0


class TranslateKey(Model):
    time: _Time = 0.0
    x: Float = 0.0
    y: Float = 0.0


class ScaleKey(Model):
    time: _Time = 0.0
    x: Float = 1.0
    y: Float = 1.0


class DeformKey(Model):
    time: _Time = 0.0
    offset: Annotated[Int, Field(ge=0)] = 0
    vertices: list[Float] | None = None


def _in_time_order(keys: list[RotateKey] | list[TranslateKey] | list[ScaleKey] | list[DeformKey],
                   what: str) -> None:
    times = [key.time for key in keys]
    for k in range(1, len(times)):
        if times[k] <= times[k - 1]:
            raise problem(f"{what}: key {k} at time {times[k]} does not come after key {k - 1} at "
                          f"{times[k - 1]}; keys must be in increasing time")


class BoneTimelines(Model):
    rotate: list[RotateKey] = []
    translate: list[TranslateKey] = []
    scale: list[ScaleKey] = []

    @model_validator(mode="after")
    def _ordered(self) -> BoneTimelines:
        _in_time_order(self.rotate, "'rotate'")
        _in_time_order(self.translate, "'translate'")
        _in_time_order(self.scale, "'scale'")
        return self


class AttachmentTimelines(Model):
    deform: list[DeformKey] = []

    @model_validator(mode="after")
    def _ordered(self) -> AttachmentTimelines:
        _in_time_order(self.deform, "'deform'")
        return self


class AnimationEntry(Model):
    """One of ``animations``: bone timelines by bone, deform timelines by skin, slot and attachment."""

    bones: dict[str, BoneTimelines] = {}
    attachments: dict[str, dict[str, dict[str, AttachmentTimelines]]] = {}


class SpineFile(Model):
    """A Spine 4.2 skeleton JSON file, the subset :mod:`.spine_json` writes (module docstring)."""

    skeleton: SkeletonHeader
    bones: Annotated[list[BoneEntry], Field(min_length=1)]
    slots: list[SlotEntry] = []
    skins: list[SkinEntry] = []
    animations: dict[str, AnimationEntry] = {}

    @model_validator(mode="after")
    def _references(self) -> SpineFile:
        bones = self._bone_indices()
        slots = _unique([slot.name for slot in self.slots], "slot")
        skins = {skin.name: skin for skin in self.skins}
        _unique([skin.name for skin in self.skins], "skin")
        for slot in self.slots:
            if slot.bone not in bones:
                raise problem(f"slot {slot.name!r} is on bone {slot.bone!r}, which is not in 'bones'")
        for skin in self.skins:
            for slot_name, attachments in skin.attachments.items():
                if slot_name not in slots:
                    raise problem(f"skin {skin.name!r} has attachments for slot {slot_name!r}, which is not "
                                  "in 'slots'")
                for name, mesh in attachments.items():
                    used = [b for vertex in mesh.weighted_bones() for b in vertex] if mesh.weighted else []
                    if used and max(used) >= len(self.bones):
                        raise problem(f"mesh {name!r} in skin {skin.name!r} is weighted to bone index "
                                      f"{max(used)}, but there are {len(self.bones)} bones")
        for slot in self.slots:
            if slot.attachment is not None and not any(
                    slot.attachment in skin.attachments.get(slot.name, {}) for skin in self.skins):
                raise problem(f"slot {slot.name!r} shows attachment {slot.attachment!r}, which no skin "
                              "holds for it")
        for name, animation in self.animations.items():
            for bone in animation.bones:
                if bone not in bones:
                    raise problem(f"animation {name!r} keys bone {bone!r}, which is not in 'bones'")
            for skin_name, by_slot in animation.attachments.items():
                if skin_name not in skins:
                    raise problem(f"animation {name!r} deforms an attachment of skin {skin_name!r}, which "
                                  "is not in 'skins'")
                for slot_name, by_name in by_slot.items():
                    for attachment, timelines in by_name.items():
                        target = skins[skin_name].attachments.get(slot_name, {}).get(attachment)
                        if target is None:
                            raise problem(f"animation {name!r} deforms {skin_name}/{slot_name}/{attachment}, "
                                          "which is not an attachment in 'skins'")
                        _check_deform(timelines.deform, target,
                                      f"the deform of {attachment!r} in animation {name!r}")
        return self

    def _bone_indices(self) -> dict[str, int]:
        first = self.bones[0]
        if first.parent is not None:
            raise problem(f"the first bone, {first.name!r}, has a parent; Spine's first bone is the root and "
                          "has none (bones are listed parents first)")
        index: dict[str, int] = {}
        for i, bone in enumerate(self.bones):
            if bone.name in index:
                raise problem(f"bone name {bone.name!r} is used twice; bone names must be unique")
            if i and bone.parent is None:
                raise problem(f"bone {bone.name!r} has no parent; only the first bone, the root, may "
                              "have none")
            if i and bone.parent not in index:
                later = any(other.name == bone.parent for other in self.bones[i + 1:])
                raise problem(f"bone {bone.name!r} names parent {bone.parent!r}, which "
                              + ("comes after it; Spine lists parents before their children" if later
                                 else "is not in 'bones'"))
            index[bone.name] = i
        return index


def _unique(names: list[str], what: str) -> set[str]:
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise problem(f"{what} name {name!r} is used twice; {what} names must be unique")
        seen.add(name)
    return seen


def _check_deform(keys: list[DeformKey], mesh: MeshAttachment, what: str) -> None:
    """Every key's offsets must fit the mesh: 2 per weighted entry, else 2 per vertex."""
    length = (len(mesh.vertices) - mesh.vertex_count) // 4 * 2 if mesh.weighted else len(mesh.vertices)
    for k, key in enumerate(keys):
        if key.vertices is not None and key.offset + len(key.vertices) > length:
            last = key.offset + len(key.vertices) - 1
            raise problem(f"{what}: key {k} sets numbers {key.offset} to {last}, but the mesh takes "
                          f"{length} deform numbers")


def read_spine_json(path: str | Path) -> SpineFile:
    """Read and check a Spine 4.2 skeleton JSON file against :class:`SpineFile`.

    Raises
    ------
    ExportError
        The file cannot be read or does not fit the model; one line naming the file and field.
    """
    data = read_json(path, ExportError, what="Spine JSON file ")
    model: SpineFile = validate(SpineFile, data, where=str(path), error=ExportError)
    return model
