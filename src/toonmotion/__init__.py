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
from pathlib import Path
from typing import Any

from toonmotion.errors import ToonmotionError

__version__ = "0.1.0"

def _api() -> Any:
    return import_module("toonmotion.api")


def __getattr__(name: str) -> Any:
    # The public API is toonmotion.api's __all__ (made from what it imports, not kept by hand),
    # loaded on first use; so is this package's __all__, for ``from toonmotion import *``. A
    # submodule's name is left to the import system (``from toonmotion import limits`` while the
    # API itself is being imported must not import the API).
    if name == "__all__":
        return ["ToonmotionError", "__version__", *_api().__all__]
    if not name.startswith("__") and not _is_submodule(name) and name in _api().__all__:
        return getattr(_api(), name)
    raise AttributeError(f"module 'toonmotion' has no attribute {name!r}")


def _is_submodule(name: str) -> bool:
    here = Path(__file__).parent
    return (here / f"{name}.py").is_file() or (here / name / "__init__.py").is_file()


def __dir__() -> list[str]:
    return sorted({*globals(), *_api().__all__})
