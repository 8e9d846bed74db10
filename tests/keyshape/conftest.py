"""Key-shapes from a real drawing: the bundled character's outline, at rest and posed by
toonmotion (the outline vertices of one mesh, so the points are in correspondence)."""

import numpy as np
import pytest

from toonmotion import api
from toonmotion.rig.pose import Pose


@pytest.fixture(scope="session")
def outlines():
    """Three key-shapes (3, N, 2): the sample's outer outline at rest, with the right forearm
    raised, and with the left arm swung out; every 4th outline point (N = 68)."""
    from toonmotion.samples import sample_rig

    hero = sample_rig()
    loop = hero.mesh.boundary[0][::4]
    poses = [hero.skeleton.positions,
             api.rotate_joint(hero, "right_elbow", -1.2).positions,
             api.rotate_joint(hero, "left_shoulder", 0.9).positions]
    return np.stack([api.pose_character(hero, Pose(p)).deformation.U[loop] for p in poses])


def _lean(P, angle):
    """Each point turned about the feet by ``angle`` times its height over the figure's."""
    base = np.array([P[:, 0].mean(), P[:, 1].max()])
    turn = angle * (base[1] - P[:, 1]) / np.ptp(P[:, 1])
    d = P - base
    return base + np.stack([d[:, 0] * np.cos(turn) - d[:, 1] * np.sin(turn),
                            d[:, 0] * np.sin(turn) + d[:, 1] * np.cos(turn)], axis=1)


@pytest.fixture(scope="session")
def smooth_keys(outlines):
    """Three key-shapes that fold no triangle of the rest outline's triangulation, none an affine
    map of another: the rest outline, leaning (a bend growing with height, 0.6 rad at the top),
    and squashed to 80% height about the feet with the middle bulging 30% wider."""
    rest = outlines[0]
    base = np.array([rest[:, 0].mean(), rest[:, 1].max()])
    d = rest - base
    bulge = 1 + 0.3 * np.sin(np.pi * -d[:, 1] / np.ptp(rest[:, 1]))
    return np.stack([rest, _lean(rest, 0.6), base + d * np.stack([bulge, np.full(len(d), 0.8)], axis=1)])
