"""toonmotion: 2D character animation from one drawing.

The library is layered (see ``docs/architecture.md``): ``geometry`` < ``shape`` < ``rig`` <
``io`` and ``render`` < ``cli``. The names most users need are re-exported here.
"""

from toonmotion.errors import ToonmotionError

__version__ = "0.1.0"

__all__ = ["ToonmotionError", "__version__"]
