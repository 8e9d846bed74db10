"""The orthographic camera and the search for its angles (toonmotion.proxy3d.orthographic, 3.1.3)."""

import numpy as np
import pytest

from toonmotion.capture.mocap import project_orthographic
from toonmotion.errors import ProxyError
from toonmotion.proxy3d import orthographic
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import (
    SEPARATE,
    camera,
    find_view,
    plane_normal,
    twin_view,
    view_direction,
)
from toonmotion.proxy3d.prior import Prior

# Azimuth, elevation (degrees): front, front-left from above, side, back views, from below.
VIEWS = [(0.0, 0.0), (33.3, 12.7), (90.0, -4.0), (-121.5, 27.0), (164.0, -35.5), (-47.0, 52.0)]


def _angle_between(a, b):
    return np.degrees(np.arccos(np.clip(view_direction(*a) @ view_direction(*b), -1, 1)))


def test_camera_is_orthonormal_and_looks_along_the_view():
    for az, el in VIEWS:
        R = camera(az, el)
        assert np.allclose(R @ R.T, np.eye(2), atol=1e-12)
        assert np.allclose(R @ view_direction(az, el), 0, atol=1e-12)
        # right-handed: image x, image *up* and the view direction
        assert np.allclose(np.cross(R[0], -R[1]), view_direction(az, el), atol=1e-12)
        assert abs(R[0, 1]) < 1e-12  # roll zero: the image's x axis stays horizontal


def test_front_view_agrees_with_the_package_s_projection(walk_prior):
    """A +Z-facing CMU figure from azimuth 0 is what capture.mocap's front projection draws."""
    P = walk_prior.positions
    assert np.allclose(P @ camera(0, 0).T, project_orthographic(P, up="y", facing="z"), atol=1e-9)


@pytest.mark.parametrize("view", VIEWS)
def test_find_view_recovers_the_angles_of_a_projected_walk(walk_prior, view):
    drawn = Markers(walk_prior.names, 4.5 * walk_prior.positions @ camera(*view).T + [320, 240],
                    fps=walk_prior.fps)
    fit = find_view(drawn, walk_prior)
    assert abs((fit.azimuth - view[0] + 180) % 360 - 180) < 0.01
    assert abs(fit.elevation - view[1]) < 0.01
    assert fit.cost < 1e-9
    assert fit.scale == pytest.approx(4.5, rel=1e-6)
    assert np.allclose(fit.translation, [320, 240], atol=1e-4)
    # The twin looks from elsewhere and costs more: the named shoulders and hips tell them apart.
    assert _angle_between(view, fit.twin[:2]) > 5
    assert fit.twin[2] > 100 * max(fit.cost, 1e-12)


def test_noise_leaves_the_angles_within_two_degrees(walk_prior):
    rng = np.random.default_rng(7)
    for view in VIEWS[1:4]:
        seen = 5 * walk_prior.positions @ camera(*view).T + [320, 240]  # figure ~150 px tall
        drawn = Markers(walk_prior.names, seen + rng.normal(scale=1.0, size=seen.shape), fps=walk_prior.fps)
        fit = find_view(drawn, walk_prior)
        assert _angle_between(view, (fit.azimuth, fit.elevation)) < 2.0


def test_a_planar_figure_cannot_tell_a_view_from_its_twin(walk_prior):
    """The walk flattened onto its swing plane: the view and its twin match equally well, and the
    fit says so by reporting a twin of the same cost; the back-view twin is not the chosen one."""
    P = walk_prior.positions.copy()
    P[..., 0] = 0.0  # every marker in the plane x = 0: no shoulder or hip width left
    flat = Prior(walk_prior.names, walk_prior.parents, P, walk_prior.fps)
    assert np.allclose(np.abs(plane_normal(flat)), [1, 0, 0])
    view = (40.0, 15.0)
    twin = twin_view(*view, [1.0, 0, 0])
    assert twin == pytest.approx((140.0, -15.0))
    drawn = Markers(flat.names, 3 * P @ camera(*view).T, fps=flat.fps)
    assert np.allclose(P @ camera(*view).T, P @ camera(*twin).T, atol=1e-9)  # the same picture
    fit = find_view(drawn, flat)
    found = (fit.azimuth, fit.elevation)
    assert min(_angle_between(found, view), _angle_between(found, twin)) < 0.01
    assert fit.twin[2] < 1e-9  # reported: the other view fits as well


def test_find_view_needs_an_aligned_prior(walk_prior):
    drawn = Markers(walk_prior.names, np.zeros((10, 16, 2)), fps=walk_prior.fps)
    with pytest.raises(ProxyError, match="must be aligned to the markers"):
        find_view(drawn, walk_prior)
    same = Markers(walk_prior.names, np.zeros((walk_prior.frame_count, 16, 2)), fps=walk_prior.fps)
    with pytest.raises(ProxyError, match="no limb of some length"):
        find_view(same, walk_prior)


def test_camera_refuses_bad_angles():
    with pytest.raises(ProxyError, match="elevation must be between"):
        camera(0, 95)
    with pytest.raises(ProxyError, match="azimuth must be a finite number"):
        camera(float("nan"), 0)


def test_a_planar_figure_is_ambiguous_and_a_real_walk_is_not(walk_prior):
    """The search says when another view explains the drawing about as well (ViewFit.ambiguous):
    the flattened walk's twin does; the real walk has no such rival."""
    P = walk_prior.positions.copy()
    P[..., 0] = 0.0
    flat = Prior(walk_prior.names, walk_prior.parents, P, walk_prior.fps)
    fit = find_view(Markers(flat.names, 3 * P @ camera(40, 15).T, fps=flat.fps), flat)
    assert fit.ambiguous and fit.second is not None
    assert _angle_between((fit.azimuth, fit.elevation), fit.second[:2]) > SEPARATE
    real = find_view(Markers(walk_prior.names, 3 * walk_prior.positions @ camera(40, 15).T,
                             fps=walk_prior.fps), walk_prior)
    assert not real.ambiguous  # its cost has one basin, or others far dearer
    assert real.second is None or real.second[2] > 100 * max(real.cost, 1e-9)


def _swung(prior, factor):
    """The prior with every limb turned ``factor`` times as far from its mean direction (wider
    swings, as a run's against a walk's), each limb's length kept, rebuilt from the roots."""
    P = prior.positions
    out = P.copy()
    for p, c in prior.limbs:
        v = P[:, c] - P[:, p]
        length = np.linalg.norm(v, axis=-1, keepdims=True)
        unit = v / length
        mean = unit.mean(axis=0)
        mean /= np.linalg.norm(mean)
        angle = np.arccos(np.clip(unit @ mean, -1, 1))[:, None]
        away = unit - (unit @ mean)[:, None] * mean
        away /= np.maximum(np.linalg.norm(away, axis=-1, keepdims=True), 1e-12)
        turned = np.cos(factor * angle) * mean + np.sin(factor * angle) * away
        out[:, c] = out[:, p] + length * turned
    return Prior(prior.names, prior.parents, out, prior.fps)


@pytest.mark.parametrize("view", [(33.3, 12.7), (-121.5, 27.0)])
def test_a_prior_that_swings_wider_than_drawn_still_gives_the_view(walk_prior, view, monkeypatch):
    """Limbs weighted by how steadily the prior holds them (STEADY): the hips, shoulders and spine
    keep the view where the swinging limbs, 1.3 times wider in the prior, would pull it away."""
    drawn = Markers(walk_prior.names, 4 * walk_prior.positions @ camera(*view).T, fps=walk_prior.fps)
    wide = _swung(walk_prior, 1.3)
    steady = find_view(drawn, wide)
    assert _angle_between(view, (steady.azimuth, steady.elevation)) < 4.0
    monkeypatch.setattr(orthographic, "STEADY", 1e9)  # every limb alike: the search before
    alike = find_view(drawn, wide)
    assert _angle_between(view, (alike.azimuth, alike.elevation)) > _angle_between(
        view, (steady.azimuth, steady.elevation))
