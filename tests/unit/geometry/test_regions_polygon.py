"""in_polygon (the even-odd rule over the edges a horizontal line meets)
against matplotlib.path.Path.contains_points on random points and shapes."""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.geometry.regions import in_polygon

mpath = pytest.importorskip("matplotlib.path")


def _distance_to_edges(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest polygon edge."""
    P, Q = polygon, np.roll(polygon, -1, axis=0)
    d = Q - P
    t = np.einsum("nke,ke->nk", xy[:, None, :] - P[None], d) / np.einsum(
        "ke,ke->k", d, d
    )
    foot = P[None] + np.clip(t, 0.0, 1.0)[..., None] * d[None]
    return np.linalg.norm(xy[:, None, :] - foot, axis=2).min(axis=1)


def _star(rng, k: int) -> np.ndarray:
    """A simple polygon: k vertices at increasing angles, random radii."""
    angle = np.sort(rng.uniform(0.0, 2.0 * np.pi, k))
    radius = rng.uniform(0.2, 1.0, k)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])


def _comb(rng, teeth: int) -> np.ndarray:
    """A non-convex comb: many edges met by one horizontal line."""
    x = np.linspace(0.0, 1.0, 2 * teeth + 1)
    top = np.where(np.arange(x.size) % 2 == 0, 1.0, rng.uniform(0.2, 0.8, x.size))
    upper = np.column_stack([x, top])
    return np.vstack([[[1.0, 0.0], [0.0, 0.0]], upper])


@pytest.mark.parametrize("seed", range(12))
def test_in_polygon_is_matplotlibs_off_the_edges(seed):
    rng = np.random.default_rng(seed)
    shapes = [_star(rng, k) for k in (3, 4, 7, 30, 500)] + [_comb(rng, 40)]
    for polygon in shapes:
        xy = rng.uniform(-1.1, 1.1, (3000, 2))
        # points on a vertex's y and on a vertex: the ray's tie-breaking
        xy[:50, 1] = polygon[rng.integers(0, len(polygon), 50), 1]
        off = _distance_to_edges(xy, polygon) > 1e-9
        ours = in_polygon(xy, polygon)
        ref = mpath.Path(polygon).contains_points(xy)
        np.testing.assert_array_equal(ours[off], ref[off])
        assert 0 < ours.sum() < len(xy)  # both sides are exercised
        # the orientation of the polygon does not matter
        np.testing.assert_array_equal(in_polygon(xy, polygon[::-1])[off], ours[off])
