"""Random samples of uncertain inputs: distributions, Latin hypercube, correlation.

Pure NumPy/SciPy; no case keys here (the ``[uncertainty]`` table of a sweep
file is read by the sweep loader, which builds these objects).

Every draw is made in the unit hypercube and mapped through each input's
inverse distribution function, so a truncated distribution is sampled exactly
(u is mapped into [F(low), F(high)] first) and the Latin hypercube keeps its
strata in every marginal.

- **Latin hypercube** (McKay, Beckman & Conover 1979): each of the n strata
  [i/n, (i+1)/n) of every input holds exactly one sample, placed uniformly in
  its stratum, the strata of the inputs paired by independent permutations.
- **Monte Carlo**: independent uniform draws.
- **Correlation** between inputs (Iman & Conover 1982, "A distribution-free
  approach to inducing rank correlation among input variables", Commun.
  Statist. B11): the samples of each input are *reordered* so that their
  ranks follow normal scores; the marginals, and so the Latin hypercube
  strata, are kept exactly.  The target is Spearman's rank correlation
  rho_s: the scores get the Pearson correlation r = 2 sin(pi rho_s / 6),
  the one whose bivariate normal has rank correlation rho_s (Pearson 1907;
  Kruskal 1958, "Ordinal measures of association", JASA 53), since ranks
  of normal scores correlated by rho_s itself come out weaker (0.479 for
  0.5).  The achieved rank correlation then scatters about the target with
  less than the sampling error of n independent pairs.

The generator is ``numpy.random.default_rng(seed)``: the same seed gives the
same samples on every platform NumPy supports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special, stats

KINDS = ("uniform", "normal", "lognormal", "triangular", "choice")


@dataclass(frozen=True)
class Distribution:
    """One uncertain input.

    kind : one of KINDS.
    params : the kind's parameters (SI units of the input):
        uniform (low, high); normal (mean, std); lognormal (median, sigma),
        the value being median * exp(sigma Z), Z standard normal, so a negative
        median gives negative values (a compressive stress); triangular
        (low, mode, high); choice (values...), with ``weights``.
    low, high : optional truncation of normal and lognormal (inclusive).
    weights : choice only, one per value (normalised); None = equal.
    """

    kind: str
    params: tuple
    low: float | None = None
    high: float | None = None
    weights: tuple | None = None

    def _frozen(self):
        """The scipy distribution of a continuous kind."""
        if self.kind == "uniform":
            a, b = self.params
            return stats.uniform(loc=a, scale=b - a)
        if self.kind == "normal":
            mean, std = self.params
            return stats.norm(loc=mean, scale=std)
        if self.kind == "lognormal":
            median, sigma = self.params
            return stats.lognorm(s=sigma, scale=abs(median))
        if self.kind == "triangular":
            a, mode, b = self.params
            return stats.triang(c=(mode - a) / (b - a), loc=a, scale=b - a)
        raise ValueError(f"no continuous distribution for kind {self.kind!r}")

    def _sign(self) -> float:
        return -1.0 if self.kind == "lognormal" and self.params[0] < 0 else 1.0

    def _cdf_bounds(self) -> tuple[float, float]:
        """[F(low), F(high)] of the truncation (0, 1 without one)."""
        if self.low is None and self.high is None:
            return 0.0, 1.0
        d, sign = self._frozen(), self._sign()
        ends = [sign * v if v is not None else None for v in (self.low, self.high)]
        if sign < 0:  # negative lognormal: the magnitude's bounds swap
            ends = ends[::-1]
        lo = d.cdf(ends[0]) if ends[0] is not None else 0.0
        hi = d.cdf(ends[1]) if ends[1] is not None else 1.0
        return float(lo), float(hi)

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the quantiles u in [0, 1) of the (truncated) distribution,
        increasing with u (so that the ranks of u are the ranks of the values,
        which the rank correlation reorders)."""
        u = np.asarray(u, dtype=float)
        if self.kind == "choice":
            values = np.asarray(self.params)
            w = (
                np.ones(values.size)
                if self.weights is None
                else np.asarray(self.weights, float)
            )
            order = np.argsort(values, kind="stable")
            values, w = values[order], w[order]
            edges = np.cumsum(w) / w.sum()
            index = np.minimum(np.searchsorted(edges, u, side="right"), values.size - 1)
            return values[index]
        lo, hi = self._cdf_bounds()
        if self._sign() < 0:  # a negative lognormal grows as its magnitude falls
            return -self._frozen().isf((1.0 - hi) + (hi - lo) * u)
        return self._frozen().ppf(lo + (hi - lo) * u)

    def mean(self) -> float:
        """Mean of the (truncated) distribution, by quadrature over quantiles."""
        if self.kind == "choice":
            values = np.asarray(self.params, float)
            w = (
                np.ones(values.size)
                if self.weights is None
                else np.asarray(self.weights, float)
            )
            return float(values @ w / w.sum())
        u = (np.arange(20000) + 0.5) / 20000
        return float(np.mean(self.ppf(u)))


def unit_samples(n: int, d: int, method: str, rng: np.random.Generator) -> np.ndarray:
    """(n, d) points in [0, 1): "lhs" (Latin hypercube) or "monte_carlo"."""
    # The construction of scipy.stats.qmc.LatinHypercube (a uniform offset
    # in each stratum, strata paired by independent permutations), but
    # drawing from the generator in this order: a sweep file's seed promises
    # the same samples (docs/sweep-format.md), and a study run again reads
    # back the sample folders it wrote, so the stream must not change with
    # scipy's.  tests/unit/studies/test_sampling.py checks both have one
    # sample per stratum of every input.
    if method == "monte_carlo":
        return rng.random((n, d))
    if method != "lhs":
        raise ValueError(f"unknown sampling method {method!r}")
    u = np.empty((n, d))
    for j in range(d):
        u[:, j] = (rng.permutation(n) + rng.random(n)) / n
    return u


def normal_scores(n: int) -> np.ndarray:
    """van der Waerden scores Phi^-1(i / (n + 1)), i = 1..n."""
    return special.ndtri(np.arange(1, n + 1) / (n + 1.0))


def score_correlation(rank_target: np.ndarray) -> np.ndarray:
    """(d, d) Pearson correlation of normal scores whose rank correlation
    (Spearman) is ``rank_target``: r = 2 sin(pi rho_s / 6), ones on the
    diagonal.  It may fail to be positive definite where ``rank_target``
    is nearly singular (the loader refuses that)."""
    r = 2.0 * np.sin(np.pi * np.asarray(rank_target, float) / 6.0)
    np.fill_diagonal(r, 1.0)
    return r


# Fresh permutations of the scores tried when their sample correlation is
# singular (two columns in the same or reversed order, likely only when the
# samples barely outnumber the inputs: 1 in 3 for 3 samples of 2 inputs).
SCORE_DRAWS = 100


def induce_correlation(
    u: np.ndarray, target: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Reorder the columns of u (n, d) so that their rank correlation follows
    ``target`` (d, d, Spearman), Iman & Conover (1982); every column keeps
    its values.  Needs n > d.

    Scores S (n, d): normal scores, each column randomly permuted; their
    sample correlation E = Q Q^T and the score target C = P P^T
    (:func:`score_correlation`, Cholesky) give T = S (P Q^-1)^T, whose
    Pearson correlation is C; each column of u is then sorted into the rank
    order of the same column of T.
    """
    n, d = u.shape
    target = np.asarray(target, float)
    if np.allclose(target, np.eye(d)):
        return u
    if n <= d:
        raise ValueError(
            f"inducing a correlation needs more samples than inputs ({n} <= {d})"
        )
    P = np.linalg.cholesky(score_correlation(target))
    for _ in range(SCORE_DRAWS):
        scores = np.column_stack([rng.permutation(normal_scores(n)) for _ in range(d)])
        try:
            Q = np.linalg.cholesky(np.corrcoef(scores, rowvar=False))
        except np.linalg.LinAlgError:
            continue
        T = scores @ (P @ np.linalg.inv(Q)).T
        out = np.empty_like(u)
        for j in range(d):
            ranks = np.argsort(np.argsort(T[:, j]))
            out[:, j] = np.sort(u[:, j])[ranks]
        return out
    raise ValueError(f"no {SCORE_DRAWS} permutations of {n} scores were independent")


def draw(
    distributions: list[Distribution],
    n: int,
    *,
    method: str = "lhs",
    seed: int = 0,
    correlation: np.ndarray | None = None,
) -> np.ndarray:
    """(n, len(distributions)) samples of the inputs.

    correlation : (d, d) target rank correlation (Spearman; symmetric, ones
    on the diagonal, it and its :func:`score_correlation` positive
    definite), or None for independent inputs; then n > d.
    """
    rng = np.random.default_rng(seed)
    d = len(distributions)
    u = unit_samples(n, d, method, rng)
    if correlation is not None:
        u = induce_correlation(u, correlation, rng)
    return np.column_stack([dist.ppf(u[:, j]) for j, dist in enumerate(distributions)])


def wilson_interval(k, n, confidence: float = 0.95):
    """Wilson score interval (lo, hi) of a binomial proportion k / n.

    Wilson (1927), JASA 22: the interval that the normal approximation gives
    when it is inverted for p, which stays inside [0, 1] and keeps its
    coverage near 0 and 1 (where the plain p +- z sqrt(p(1-p)/n) collapses).
    """
    # scipy.stats.binomtest(k, n).proportion_ci(method="wilson") gives the
    # same bounds (to 1e-15, tests/unit/studies/test_sampling.py) for one
    # integer k at a time; here k is an array (every level of a study, and
    # the non-integer k = p n of wilson_samples_needed), about 1e4 times
    # faster than a loop of binomtest calls.
    k = np.asarray(k, float)
    z = float(special.ndtri(0.5 + confidence / 2.0))
    p = k / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return centre - half, centre + half


def samples_for_half_width(p, half_width: float, confidence: float = 0.95) -> int:
    """Samples needed for a confidence half-width ``half_width`` at proportion p
    (the normal approximation; p = 0.5 is the worst case)."""
    z = float(special.ndtri(0.5 + confidence / 2.0))
    p = float(np.clip(p, 0.0, 1.0))
    return int(math.ceil(max(p * (1 - p), 1e-4) * (z / half_width) ** 2))


def rank_correlation(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's rank correlation of two samples (NaN when one is constant)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if np.ptp(x) == 0.0 or np.ptp(y) == 0.0:
        return math.nan
    return float(stats.spearmanr(x, y).statistic)


def wilson_samples_needed(p, half_width: float, confidence: float = 0.95) -> np.ndarray:
    """Smallest n whose Wilson interval (:func:`wilson_interval`) at proportion
    p is at most ``half_width`` wide on each side (the half of its width).

    Unlike :func:`samples_for_half_width` it stays meaningful at p = 0 and 1,
    where the interval still has a width of about z^2 / n (Wilson 1927); the
    half-width decreases with n at fixed p, so n is found by bisection.
    """
    p = np.clip(np.asarray(p, float), 0.0, 1.0)
    z2 = float(special.ndtri(0.5 + confidence / 2.0)) ** 2

    def half(n):
        denom = 1.0 + z2 / n
        return np.sqrt(z2) * np.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denom

    lo = np.zeros(p.shape)  # half(lo) > half_width (n = 0: no samples)
    hi = np.full(p.shape, 1.0)
    while np.any(half(hi) > half_width):
        hi = np.where(half(hi) > half_width, 2.0 * hi, hi)
    while np.any(hi - lo > 1.0):
        mid = np.floor(0.5 * (lo + hi))
        mid = np.where(mid <= lo, lo + 1.0, mid)
        ok = half(mid) <= half_width
        hi, lo = np.where(ok, mid, hi), np.where(ok, lo, mid)
    return hi.astype(np.int64)
