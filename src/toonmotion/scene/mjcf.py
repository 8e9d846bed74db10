"""The MuJoCo XML pieces every scene builder shares: collision bits, contact parameters, the
proxy's mass, and how numbers and colours are written (:mod:`toonmotion.scene.build`,
:mod:`toonmotion.scene.cloth`)."""

from __future__ import annotations

from toonmotion.errors import SceneError

KINEMATIC_MASS = 1000.0  # kg: the proxy does not give way


# Collision bits: proxies (2) touch elements (3) only; elements touch the ground (1) and each other.
PROXY_BITS = 'contype="2" conaffinity="0"'


ELEMENT_BITS = 'contype="1" conaffinity="3"'


# Rain (4) touches the proxy, the ground and the elements but not other drops.
DROP_BITS = 'contype="4" conaffinity="3"'


CONTACT_TIME = 0.004  # seconds: the contacts' time constant (MuJoCo's solref), twice the longest step


CONTACT = f'solref="{CONTACT_TIME} 1" condim="6" friction="0.9 0.005 0.002"'


def load_mujoco():
    try:
        import mujoco
    except ImportError:  # a required dependency, but a broken install must still say so
        raise SceneError("scenes need the MuJoCo physics engine: pip install mujoco") from None
    return mujoco


def vec(x):
    return " ".join(repr(float(c)) for c in x)


def rgba_text(colour):
    return " ".join(f"{c / 255:.6g}" for c in colour) + " 1"
