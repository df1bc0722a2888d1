"""Samples of uncertain inputs against the distributions they claim to follow."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from xfemslip.studies.sampling import (
    Distribution,
    draw,
    induce_correlation,
    rank_correlation,
    samples_for_half_width,
    unit_samples,
    wilson_interval,
)

CONTINUOUS = [
    (Distribution("uniform", (0.4, 0.8)), stats.uniform(loc=0.4, scale=0.4)),
    (Distribution("normal", (-44.0e6, 2.0e6)), stats.norm(-44.0e6, 2.0e6)),
    (Distribution("lognormal", (5.0e9, 0.3)), stats.lognorm(s=0.3, scale=5.0e9)),
    (
        Distribution("triangular", (0.3, 0.6, 1.0)),
        stats.triang(c=0.3 / 0.7, loc=0.3, scale=0.7),
    ),
]


@pytest.mark.parametrize("method", ["lhs", "monte_carlo"])
@pytest.mark.parametrize("dist, ref", CONTINUOUS, ids=lambda v: getattr(v, "kind", ""))
def test_marginals_follow_the_distribution(dist, ref, method):
    """Kolmogorov-Smirnov against the scipy distribution: 4,000 samples; a
    Latin hypercube is much closer than random (its D is at most 1/n)."""
    x = draw([dist], 4000, method=method, seed=11)[:, 0]
    d = stats.kstest(x, ref.cdf).statistic
    assert d < (1.0 / 4000 + 1e-9 if method == "lhs" else 0.03)


def test_latin_hypercube_puts_one_sample_in_every_stratum():
    u = unit_samples(250, 4, "lhs", np.random.default_rng(3))
    for j in range(4):
        assert sorted(np.floor(u[:, j] * 250).astype(int)) == list(range(250))


def test_truncated_normal_matches_scipy_truncnorm():
    """Mean and bounds of a normal truncated to [mean - 1 std, mean + 2 std]."""
    dist = Distribution("normal", (10.0, 2.0), low=8.0, high=14.0)
    x = draw([dist], 5000, seed=5)[:, 0]
    assert x.min() >= 8.0 and x.max() <= 14.0
    ref = stats.truncnorm(-1.0, 2.0, loc=10.0, scale=2.0)
    assert abs(x.mean() - ref.mean()) < 1e-3
    assert abs(dist.mean() - ref.mean()) < 1e-4


def test_negative_lognormal_keeps_its_sign_and_truncation():
    """A compressive stress drawn as median * exp(sigma Z) with median < 0."""
    dist = Distribution("lognormal", (-40.0e6, 0.1), low=-46.0e6, high=-35.0e6)
    x = draw([dist], 3000, seed=2)[:, 0]
    assert np.all(x < 0.0) and x.min() >= -46.0e6 and x.max() <= -35.0e6
    ref = stats.truncnorm(
        (math.log(35.0) - math.log(40.0)) / 0.1, (math.log(46.0) - math.log(40.0)) / 0.1
    )
    # ln|x| is the truncated normal of ln 40e6, sigma 0.1
    z = (np.log(-x) - math.log(40.0e6)) / 0.1
    assert stats.kstest(z, ref.cdf).statistic < 1.0 / 3000 + 1e-9


def test_choice_frequencies_follow_the_weights():
    dist = Distribution("choice", (0.3, 0.6, 0.9), weights=(1.0, 2.0, 1.0))
    x = draw([dist], 4000, seed=9)[:, 0]
    counts = [np.count_nonzero(x == v) for v in (0.3, 0.6, 0.9)]
    assert counts == [1000, 2000, 1000]  # Latin hypercube: exact strata


def test_values_increase_with_the_quantile():
    """The reordering moves ranks of u: a value must rank where its u ranks,
    for a negative lognormal (a compressive stress) and for choices listed
    in any order too; the choices keep their weights."""
    u = np.linspace(0.0005, 0.9995, 1000)
    for dist in (
        *(d for d, _ in CONTINUOUS),
        Distribution("lognormal", (-44e6, 0.2)),
        Distribution("lognormal", (-44e6, 0.2), low=-60e6, high=-30e6),
        Distribution("choice", (0.9, 0.3, 0.6), weights=(1.0, 2.0, 1.0)),
    ):
        assert np.all(np.diff(dist.ppf(u)) >= 0.0), dist
    x = Distribution("lognormal", (-44e6, 0.2), low=-60e6, high=-30e6).ppf(u)
    assert -60e6 <= x.min() and x.max() <= -30e6
    assert np.median(x) == pytest.approx(-44e6, rel=0.02)
    x = draw([Distribution("choice", (0.9, 0.3, 0.6), weights=(1, 2, 1))], 4000)
    assert [np.count_nonzero(x == v) for v in (0.9, 0.3, 0.6)] == [1000, 2000, 1000]


@pytest.mark.parametrize("rho", [-0.7, 0.3, 0.9])
def test_induced_rank_correlation_keeps_the_marginals(rho):
    rng = np.random.default_rng(1)
    u = unit_samples(2000, 2, "lhs", rng)
    out = induce_correlation(u, np.array([[1.0, rho], [rho, 1.0]]), rng)
    for j in range(2):
        np.testing.assert_array_equal(np.sort(out[:, j]), np.sort(u[:, j]))


SEEDS = 20


@pytest.mark.parametrize("n", [50, 500, 5000])
@pytest.mark.parametrize("rho", [-0.7, 0.3, 0.5, 0.9])
def test_achieved_rank_correlation_is_the_target(rho, n):
    """Spearman's rank correlation of the drawn samples is the target rho,
    within sampling error, for every size.

    Tolerance: for n independent pairs from a bivariate normal, Fisher's
    z = atanh(r_s) of Spearman's r_s has the standard error
    se = sqrt(1.06 / (n - 3)) (Fieller, Hartley & Pearson 1957, Biometrika
    44).  The reordering fixes the Pearson correlation of the scores
    exactly, so its rank correlation scatters less (about se / 3, measured
    over seeds), never more: every draw must lie within 4 se of the
    target's z, and the mean z of 20 seeds within 3 se / sqrt(20) (which
    also bounds a bias).  Imposing rho on the scores themselves gives
    (6 / pi) asin(rho / 2) instead (0.482 for 0.5), 2.7 to 13 of those
    standard errors of the mean away from the target at n = 5000."""
    target = np.array([[1.0, rho], [rho, 1.0]])
    uniform = Distribution("uniform", (0.0, 1.0))
    lognormal = Distribution("lognormal", (-44e6, 0.1))
    se = math.sqrt(1.06 / (n - 3))
    z = []
    for seed in range(SEEDS):
        x = draw([uniform, lognormal], n, seed=seed, correlation=target)
        z.append(math.atanh(rank_correlation(x[:, 0], x[:, 1])))
    z = np.array(z)
    assert np.all(np.abs(z - math.atanh(rho)) < 4.0 * se)
    assert abs(z.mean() - math.atanh(rho)) < 3.0 * se / math.sqrt(SEEDS)


def test_correlation_needs_more_samples_than_inputs():
    """n <= d leaves the scores' correlation singular: refused in words.  At
    n = d + 1 the scores of two columns are often in the same or reversed
    order (1 in 3 for 3 samples): fresh permutations are drawn."""
    dists = [Distribution("uniform", (0.0, 1.0))] * 2
    target = np.array([[1.0, 0.5], [0.5, 1.0]])
    with pytest.raises(ValueError, match="more samples than inputs"):
        draw(dists, 2, correlation=target)
    for seed in range(30):
        x = draw(dists, 3, seed=seed, correlation=target)
        np.testing.assert_array_equal(np.sort(x, axis=0), np.sort(x, axis=0))
        assert sorted(np.floor(x[:, 0] * 3)) == [0.0, 1.0, 2.0]  # strata kept


def test_same_seed_same_samples_other_seed_other_samples():
    dists = [Distribution("uniform", (0.0, 1.0)), Distribution("normal", (0.0, 1.0))]
    a = draw(dists, 50, seed=4)
    np.testing.assert_array_equal(a, draw(dists, 50, seed=4))
    assert not np.array_equal(a, draw(dists, 50, seed=5))


def test_wilson_interval_closed_forms():
    """k = 0: (0, z^2 / (n + z^2)); k = n/2: symmetric about 1/2; and it
    covers the true p in about 95 % of binomial trials."""
    lo, hi = wilson_interval(0, 10)
    z2 = stats.norm.ppf(0.975) ** 2
    assert lo == pytest.approx(0.0, abs=1e-15) and hi == pytest.approx(z2 / (10 + z2))
    lo, hi = wilson_interval(50, 100)
    assert lo + hi == pytest.approx(1.0)
    rng = np.random.default_rng(0)
    k = rng.binomial(200, 0.1, size=20000)
    lo, hi = wilson_interval(k, 200)
    coverage = np.mean((lo <= 0.1) & (0.1 <= hi))
    assert 0.93 < coverage < 0.97


def test_samples_for_half_width():
    # p = 0.5, +-0.05 at 95 %: 0.25 * (1.96 / 0.05)^2 = 384.1 -> 385
    assert samples_for_half_width(0.5, 0.05) == 385
    assert samples_for_half_width(0.1, 0.05) < samples_for_half_width(0.5, 0.05)


def test_wilson_samples_needed_is_the_fewest_that_reach_the_half_width():
    from xfemslip.studies.sampling import wilson_samples_needed

    p = np.array([0.0, 0.01, 0.1, 0.5, 0.9, 1.0])
    for hw, conf in ((0.05, 0.95), (0.01, 0.99)):
        n = wilson_samples_needed(p, hw, conf)
        for pi, ni in zip(p, n, strict=True):
            lo, hi = wilson_interval(pi * ni, ni, conf)
            lo1, hi1 = wilson_interval(pi * (ni - 1), ni - 1, conf)
            assert (hi - lo) / 2 <= hw < (hi1 - lo1) / 2
        assert n[0] == n[-1] > 1  # P = 0 still needs samples to be sure of it


@pytest.mark.parametrize("confidence", [0.5, 0.8, 0.9, 0.95, 0.99, 0.999])
def test_wilson_interval_is_scipys(confidence):
    """Against scipy.stats.binomtest(k, n).proportion_ci(method="wilson") for
    every k of small n and a spread of k for large n (the array form is the
    one the studies call)."""
    for n in (1, 2, 3, 7, 20, 101, 1000, 20000):
        k = np.unique(np.linspace(0, n, min(n + 1, 41)).round().astype(int))
        lo, hi = wilson_interval(k, n, confidence)
        for ki, l_i, h_i in zip(k, lo, hi, strict=True):
            ref = stats.binomtest(int(ki), n).proportion_ci(
                confidence_level=confidence, method="wilson"
            )
            assert l_i == pytest.approx(ref.low, abs=1e-14), (ki, n)
            assert h_i == pytest.approx(ref.high, abs=1e-14), (ki, n)


def test_latin_hypercube_is_stratified_like_scipys_qmc():
    """The construction of scipy.stats.qmc.LatinHypercube, from another
    stream: both put one sample in each of the n strata of every input, the
    offsets inside the strata are uniform (Kolmogorov-Smirnov over many
    draws), and the strata of two inputs are paired independently (the rank
    correlation of the pairs is centred on 0 with the spread of random
    pairings, 1 / sqrt(n - 1))."""
    n, d, draws = 40, 3, 400
    ours = [unit_samples(n, d, "lhs", np.random.default_rng(s)) for s in range(draws)]
    ref = [stats.qmc.LatinHypercube(d, seed=s).random(n) for s in range(draws)]
    for samples in (ours, ref):
        for u in samples:
            for j in range(d):
                assert sorted(np.floor(u[:, j] * n).astype(int)) == list(range(n))
        offsets = np.concatenate([(u * n % 1.0).ravel() for u in samples])
        assert stats.kstest(offsets, "uniform").pvalue > 1e-3
        rho = np.array([stats.spearmanr(u[:, 0], u[:, 1]).statistic for u in samples])
        assert abs(rho.mean()) < 4 / math.sqrt((n - 1) * draws)
        assert rho.std() == pytest.approx(1 / math.sqrt(n - 1), rel=0.15)
    # the two offset samples come from one distribution
    a = np.concatenate([(u * n % 1.0).ravel() for u in ours])
    b = np.concatenate([(u * n % 1.0).ravel() for u in ref])
    assert stats.ks_2samp(a, b).pvalue > 1e-3
