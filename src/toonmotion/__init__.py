"""toonmotion: 2D character animation from one drawing.

The library is layered (see ``docs/architecture.md``): ``geometry`` < ``shape`` < ``rig`` <
``deform`` < ``animate`` < ``capture`` < ``io`` and ``render`` < :mod:`toonmotion.api` < ``cli``.
The public API (:mod:`toonmotion.api`) is re-exported here, loaded on first use so that
``import toonmotion`` stays light::

    import toonmotion
    hero = toonmotion.rig_image("hero.png", skeleton="hero.json")
    toonmotion.save_project("hero", hero)
"""

from importlib import import_module
from typing import Any

from toonmotion.errors import ToonmotionError

__version__ = "0.1.0"

def _api() -> Any:
    return import_module("toonmotion.api")


def __getattr__(name: str) -> Any:
    # The public API is toonmotion.api's __all__ (made from what it imports, not kept by hand),
    # loaded on first use; so is this package's __all__, for ``from toonmotion import *``.
    if name == "__all__":
        return ["ToonmotionError", "__version__", *_api().__all__]
    if not name.startswith("__") and name in _api().__all__:
        return getattr(_api(), name)
    raise AttributeError(f"module 'toonmotion' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_api().__all__})
