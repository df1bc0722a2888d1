"""The random network generator against its stated distributions (fixed
seeds, large samples), reproducibility, "avoid" and the domain rules."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import trapezoid

from xfemslip.geometry import dfn
from xfemslip.geometry.dfn import DfnParams, FractureSet, LengthLaw, Orientation

BOX = (0.0, 2.0, 0.0, 1.0)
UNIFORM = Orientation(kind="uniform")
CONST = LengthLaw(kind="constant", value=0.1)


def power_law_cdf(x, exponent: float, lmin: float, lmax: float):
    """CDF of pdf ~ l^-exponent on [lmin, lmax] (the reference of the KS tests)."""
    x = np.clip(np.asarray(x, dtype=float), lmin, lmax)
    a = 1.0 - exponent
    if abs(a) < 1e-12:
        return np.log(x / lmin) / math.log(lmax / lmin)
    return (x**a - lmin**a) / (lmax**a - lmin**a)


def _params(**kw) -> DfnParams:
    sets = kw.pop("sets", None) or (
        FractureSet(
            weight=1.0,
            orientation=kw.pop("orientation", UNIFORM),
            length=kw.pop("length", CONST),
        ),
    )
    return DfnParams(seed=kw.pop("seed", 1), sets=sets, **kw)


def _rng(seed=12345):
    return np.random.default_rng(seed)


@pytest.mark.parametrize(
    ("exponent", "lmin", "lmax"), [(2.5, 0.1, 2.0), (1.0, 0.5, 5.0), (-0.5, 1.0, 3.0)]
)
def test_power_law_lengths_ks(exponent, lmin, lmax):
    law = LengthLaw(kind="power_law", exponent=exponent, lmin=lmin, lmax=lmax)
    x = dfn.sample_lengths(_rng(), law, 20_000)
    assert lmin <= x.min() and x.max() <= lmax
    result = stats.kstest(x, lambda v: power_law_cdf(v, exponent, lmin, lmax))
    assert result.pvalue > 0.01, result
    # the closed-form mean (used for P21 -> count) against the sample mean
    assert dfn.mean_length(law) == pytest.approx(x.mean(), rel=0.02)
    # and against numerical integration of l * pdf
    grid = np.linspace(lmin, lmax, 200_001)
    pdf = grid**-exponent
    mean = trapezoid(grid * pdf, grid) / trapezoid(pdf, grid)
    assert dfn.mean_length(law) == pytest.approx(mean, rel=1e-8)


def test_power_law_is_a_different_distribution_for_another_exponent():
    """The KS test above can fail: a sample of exponent 2.5 rejects 1.5."""
    x = dfn.sample_lengths(
        _rng(), LengthLaw(kind="power_law", exponent=2.5, lmin=0.1, lmax=2.0), 20_000
    )
    assert stats.kstest(x, lambda v: power_law_cdf(v, 1.5, 0.1, 2.0)).pvalue < 1e-6


@pytest.mark.parametrize(("lmin", "lmax"), [(None, None), (0.05, 0.3), (0.2, None)])
def test_lognormal_lengths_ks(lmin, lmax):
    law = LengthLaw(kind="lognormal", median=0.1, sigma=0.6, lmin=lmin, lmax=lmax)
    x = dfn.sample_lengths(_rng(7), law, 20_000)
    ref = stats.lognorm(s=0.6, scale=0.1)
    lo, hi = lmin or 0.0, lmax or np.inf
    mass = ref.cdf(hi) - ref.cdf(lo)

    def cdf(v):
        return (ref.cdf(np.clip(v, lo, hi)) - ref.cdf(lo)) / mass

    assert lo <= x.min() and x.max() <= hi
    assert stats.kstest(x, cdf).pvalue > 0.01
    assert dfn.mean_length(law) == pytest.approx(x.mean(), rel=0.02)
    # the closed-form truncated mean against numerical integration of l * pdf
    grid = np.linspace(lo, min(hi, 20.0), 400_001)
    pdf = ref.pdf(grid)
    integral = trapezoid(grid * pdf, grid) / trapezoid(pdf, grid)
    assert dfn.mean_length(law) == pytest.approx(integral, rel=1e-6)


def test_von_mises_circular_mean_and_resultant_length():
    kappa, mean = 4.0, 30.0
    theta = np.radians(
        dfn.sample_angles(
            _rng(3), Orientation(kind="von_mises", mean=mean, kappa=kappa), 50_000
        )
    )
    z = np.mean(np.exp(1j * theta))
    assert math.degrees(np.angle(z)) == pytest.approx(mean, abs=0.5)
    # E[R] = I1(kappa) / I0(kappa) for a von Mises law
    assert abs(z) == pytest.approx(stats_ratio(kappa), abs=0.005)


def stats_ratio(kappa):
    from scipy.special import i0, i1

    return float(i1(kappa) / i0(kappa))


def test_normal_and_uniform_orientations():
    a = dfn.sample_angles(
        _rng(4), Orientation(kind="normal", mean=120.0, std=10.0), 50_000
    )
    assert a.mean() == pytest.approx(120.0, abs=0.2)
    assert a.std() == pytest.approx(10.0, rel=0.02)
    u = dfn.sample_angles(_rng(5), UNIFORM, 50_000)
    assert 0.0 <= u.min() and u.max() < 180.0
    assert stats.kstest(u, stats.uniform(0, 180).cdf).pvalue > 0.01


def test_centres_uniform_chi_square_on_a_grid():
    net = dfn.generate(
        _params(
            count=20_000,
            region=(0.0, 2.0, 0.0, 1.0),
            length=LengthLaw(kind="constant", value=1e-3),
        ),
        BOX,
    )
    assert net.placed == 20_000
    counts, _, _ = np.histogram2d(
        net.centers[:, 0], net.centers[:, 1], bins=(8, 4), range=((0, 2), (0, 1))
    )
    assert stats.chisquare(counts.ravel()).pvalue > 0.01
    # a non-uniform pattern (left half only) is rejected by the same test
    left = np.histogram2d(
        net.centers[:, 0] / 2, net.centers[:, 1], bins=(8, 4), range=((0, 2), (0, 1))
    )[0]
    assert stats.chisquare(left.ravel()).pvalue < 1e-6


def test_count_from_densities():
    law = LengthLaw(kind="power_law", exponent=2.0, lmin=0.05, lmax=0.5)
    box_area = 2.0
    # P21: count = round(P21 A / E[L]); E[L] = ln(lmax/lmin) / (1/lmin - 1/lmax)
    mean = math.log(10.0) / (20.0 - 2.0)
    params = _params(p21=30.0, length=law)
    assert dfn.resolve_count(params, BOX) == round(30.0 * box_area / mean) == 469
    # the drawn (unclipped) length per area matches P21 for a large network
    big = _params(p21=400.0, length=law, intersections="allow")
    net = dfn.generate(big, BOX)
    assert net.placed == dfn.resolve_count(big, BOX)
    assert net.lengths.sum() / box_area == pytest.approx(400.0, rel=0.03)
    assert dfn.resolve_count(_params(p20=12.3), BOX) == round(12.3 * box_area)
    # a region sets the area
    assert dfn.resolve_count(_params(p20=10.0, region=(0.0, 0.5, 0.0, 0.4)), BOX) == 2


def test_set_weights():
    sets = (
        FractureSet(
            weight=3.0,
            orientation=Orientation(kind="normal", mean=10.0, std=1.0),
            length=CONST,
        ),
        FractureSet(
            weight=1.0,
            orientation=Orientation(kind="normal", mean=100.0, std=1.0),
            length=LengthLaw(kind="constant", value=0.05),
        ),
    )
    net = dfn.generate(_params(count=8000, sets=sets), BOX)
    share = np.mean(net.set_index == 0)
    assert share == pytest.approx(0.75, abs=0.02)
    np.testing.assert_allclose(net.angles[net.set_index == 1], 100.0, atol=6.0)
    np.testing.assert_array_equal(net.lengths[net.set_index == 1], 0.05)


def test_same_seed_same_network_bitwise_other_seed_differs():
    law = LengthLaw(kind="lognormal", median=0.2, sigma=0.5, lmin=0.05)
    params = _params(
        count=60, seed=42, length=law, intersections="avoid", min_spacing=0.01
    )
    a, b = dfn.generate(params, BOX), dfn.generate(params, BOX)
    assert a.segments.tobytes() == b.segments.tobytes()
    c = dfn.generate(
        _params(count=60, seed=43, length=law, intersections="avoid", min_spacing=0.01),
        BOX,
    )
    assert not np.array_equal(a.segments, c.segments)


def test_avoid_gives_no_intersections_and_keeps_the_spacing():
    law = LengthLaw(kind="power_law", exponent=2.0, lmin=0.1, lmax=0.6)
    allow = dfn.generate(_params(count=80, length=law), BOX)
    assert dfn.intersecting_pairs(allow.segments)  # random lines do cross
    for spacing in (0.0, 0.03):
        net = dfn.generate(
            _params(count=80, length=law, intersections="avoid", min_spacing=spacing),
            BOX,
        )
        assert net.placed == 80
        assert dfn.intersecting_pairs(net.segments, spacing) == []
    # and it keeps away from given segments (the case's other fractures)
    wall = np.array([[[1.0, 0.0], [1.0, 1.0]]])
    net = dfn.generate(_params(count=40, length=law, intersections="avoid"), BOX, wall)
    assert np.all(
        np.sign(net.segments[:, 0, 0] - 1.0) == np.sign(net.segments[:, 1, 0] - 1.0)
    )


def test_segment_distances_against_brute_force():
    rng = _rng(9)
    a = rng.random((2, 2))
    b = rng.random((300, 2, 2))
    d = dfn.segment_distances(a[0], a[1], b[:, 0], b[:, 1])
    t = np.linspace(0, 1, 401)
    pa = a[0] + t[:, None] * (a[1] - a[0])
    for k in range(0, 300, 37):
        pb = b[k, 0] + t[:, None] * (b[k, 1] - b[k, 0])
        brute = np.min(np.hypot(*(pa[:, None] - pb[None]).transpose(2, 0, 1)))
        assert d[k] <= brute + 1e-12
        assert d[k] == pytest.approx(brute, abs=5e-3)


def test_clip_keeps_everything_in_the_domain_reject_keeps_whole_fractures():
    law = LengthLaw(kind="constant", value=0.5)
    region = (-0.5, 2.5, -0.5, 1.5)  # centres also outside the domain
    clip = dfn.generate(
        _params(count=500, length=law, region=region, min_length=0.05), BOX
    )
    x, y = clip.segments[..., 0], clip.segments[..., 1]
    assert x.min() >= 0.0 and x.max() <= 2.0 and y.min() >= 0.0 and y.max() <= 1.0
    kept = np.hypot(*(clip.segments[:, 1] - clip.segments[:, 0]).T)
    assert kept.min() > 0.05 and kept.max() <= 0.5 + 1e-12
    assert np.any(kept < 0.499)  # some were cut
    reject = dfn.generate(
        _params(count=300, length=law, region=region, outside="reject"), BOX
    )
    lengths = np.hypot(*(reject.segments[:, 1] - reject.segments[:, 0]).T)
    np.testing.assert_allclose(lengths, 0.5, rtol=1e-12)
    assert reject.segments[..., 0].min() >= 0.0 and reject.segments[..., 1].max() <= 1.0


def test_placement_gives_up_and_says_so():
    params = _params(
        count=50,
        length=LengthLaw(kind="constant", value=1.5),
        intersections="avoid",
        outside="reject",
    )
    net = dfn.generate(params, BOX)
    assert net.placed < net.requested == 50
    assert net.candidates == dfn.ATTEMPTS_PER_FRACTURE * 50


def test_stats_of_a_network():
    polylines = [
        np.array([[-1.0, 0.5], [3.0, 0.5]]),
        np.array([[0.5, 0.2], [0.5, 0.4], [0.7, 0.4]]),
    ]
    s = dfn.network_stats(polylines, BOX)
    assert s["count"] == 2 and s["p20"] == 1.0
    assert s["total_length"] == pytest.approx(2.0 + 0.4)
    assert s["p21"] == pytest.approx(1.2)
