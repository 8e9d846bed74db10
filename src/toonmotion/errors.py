"""Errors a user can cause.

Every error raised for bad input is a :class:`ToonmotionError`. Its message is one line that
says what was wrong and what to do about it; the CLI prints it and exits with status 2.
"""


class ToonmotionError(Exception):
    """Base of every error caused by input the user can fix."""


class ImageReadError(ToonmotionError):
    """An image file is missing, unreadable, truncated or not an image."""


class LimitError(ToonmotionError):
    """An input or an output is bigger than a resource limit (:mod:`toonmotion.limits`) allows."""


class ImageTooLargeError(LimitError):
    """An image has more pixels than the configured limit."""


class MaskError(ToonmotionError):
    """A mask is empty, covers the whole image, or does not fit the image."""


class SkeletonError(ToonmotionError):
    """A skeleton is malformed: unknown parents, cycles, duplicate names, joints far away."""


class MeshError(ToonmotionError):
    """A silhouette cannot be meshed with the requested settings."""


class ProjectError(ToonmotionError):
    """A project file is missing, malformed or inconsistent."""


class ProjectVersionError(ProjectError):
    """A project file was written by a version of toonmotion this one cannot read."""


class LinkError(ProjectError):
    """A project holds a symbolic link where the editor would read, write or delete through it."""


class SettingsError(ToonmotionError):
    """An option has a value outside its valid range."""


class PoseError(ToonmotionError):
    """A pose is malformed: unknown or missing joints, non-finite positions, collapsed bones."""


class SketchError(PoseError):
    """A sketched skeleton cannot be read: malformed strokes, a loop, a shape the skeleton lacks."""


class KeyframeError(ToonmotionError):
    """Key-frames are malformed: no keys, repeated or negative frame numbers, bad frame rate."""


class ExportError(ToonmotionError):
    """An animation or image cannot be written in the requested format."""


class FilterError(ToonmotionError):
    """A cartoon-filter setting is invalid: a negative or non-finite strength or width, a fixed
    joint that no chain from the root reaches."""


class EditError(ToonmotionError):
    """An edit is malformed or cannot apply: a sketch curve of fewer than two points, a drag
    with no vertex near its start, nothing left to undo."""


class MotionError(ToonmotionError):
    """A motion is malformed: no frames, a frame rate that is not a positive number, joints
    that do not match the skeleton it is used with."""


class TrackingError(ToonmotionError):
    """Tracking cannot start: a joint rectangle outside the frame or of zero size, frames of
    differing sizes, an empty sequence."""


class Cancelled(ToonmotionError):
    """Long work stopped because the user asked (the editor's Cancel): what it would have written
    was not written, and what was saved before it is as it was."""


class VideoReadError(ToonmotionError):
    """An image sequence cannot be read: a video that cannot be decoded, an empty folder."""


class KeyShapeError(ToonmotionError):
    """Key-shapes or contours cannot be used: different point counts, too few points, collinear
    or non-finite points, a model or contour file that does not read."""


class ProxyError(ToonmotionError):
    """A 3D proxy cannot be built: markers that are not finite or repeat a name, no frames, a
    motion prior that lacks markers or is too short to align, a camera that cannot see them."""


class AmbiguousViewError(ProxyError):
    """Two views explain a drawing about equally, so the view must be given, not searched.

    ``views`` holds both, ``(azimuth, elevation, cost)``, the search's choice first."""

    def __init__(self, message: str, views: tuple[tuple[float, float, float], ...] = ()) -> None:
        super().__init__(message)
        self.views = views


class SceneError(ToonmotionError):
    """A 3D scene cannot be built, rendered or composited: an element held at a marker the proxy
    lacks, frames whose count or size differ from the proxy's, primitives that are not finite, a
    missing physics engine."""


class BatchError(ToonmotionError):
    """A batch job cannot run: a malformed job file, an input it names that is missing, a name
    given twice, a pair naming a character or motion the job lacks, a cluster that cannot be reached."""


class MessageError(ToonmotionError):
    """An editor's message is not what the protocol says (:mod:`toonmotion.web.messages`): not
    JSON, an unknown type, a field of the wrong kind or out of range."""
