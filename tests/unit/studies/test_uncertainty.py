"""Uncertainty studies: the [uncertainty] table, the closed-form screen per
sample, probability curves against binomial references, the CLI."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from xfemslip.cli import cli as main
from xfemslip.errors import CaseError
from xfemslip.reference.closed_form_depletion import critical_change_uniaxial
from xfemslip.studies.reactivation import evaluate_screen, slipped_counts
from xfemslip.studies.sampling import wilson_interval
from xfemslip.studies.uncertainty import loads_uncertainty

# An isolated fracture in a 100 m box with rollers on the sides, u_y = 0 at
# the bottom and constant overburden: the uniaxial-strain path everywhere.
BASE = """
name = "isolated"
[domain]
size = [100.0, 100.0]
[mesh]
elements = [20, 20]
[material]
E = 10.0e9
nu = 0.25
[pore_pressure]
initial = 30.0e6
change = -20.0e6
[[fractures]]
center = [50.0, 50.0]
length = 10.0
angle = 60.0
friction = 0.6
[loading]
initial_stress = { xx = -44.0e6, yy = -62.0e6, xy = 0.0 }
stress = { xx = -44.0e6, yy = -62.0e6, xy = 0.0 }
steps = 10
[boundary]
left = { ux = 0.0 }
right = { ux = 0.0 }
bottom = { uy = 0.0 }
top = "traction"
"""

STUDY = """
name = "study"
base = "base.toml"
[uncertainty]
samples = {samples}
seed = 3
evaluate = "{evaluate}"
levels = {{ start = 0.0, stop = -20.0e6, num = 11 }}
[uncertainty.inputs]
{inputs}
"""

FRICTION = (
    '"fractures[0].friction" = { distribution = "uniform", low = 0.44, high = 0.52 }'
)


def study(tmp_path, inputs=FRICTION, samples=100, evaluate="screen", base=BASE):
    """Write base.toml and study.toml into tmp_path; the study's path."""
    (tmp_path / "base.toml").write_text(base)
    path = tmp_path / "study.toml"
    path.write_text(STUDY.format(samples=samples, evaluate=evaluate, inputs=inputs))
    return path


def load(path):
    return loads_uncertainty(path.read_text(), path)


# --------------------------------------------------------------------------- #
# Validation
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    ("inputs", "samples", "evaluate", "key", "words"),
    [
        (FRICTION, 10**9, "screen", "uncertainty.samples", "<= 1000000"),
        (FRICTION, 20_000, "xfem", "uncertainty.samples", "<= 10000"),
        (
            '"fractures[0].friction" = { distribution = "uniform", low = 0.5, '
            "high = 0.4 }",
            10,
            "screen",
            'uncertainty.inputs."fractures[0].friction"',
            "low < high",
        ),
        (
            '"fractures[0].friction" = { distribution = "gauss", mean = 0.5 }',
            10,
            "screen",
            "distribution",
            "gauss",
        ),
        (
            '"fractures[0].friction" = { distribution = "uniform", low = 0.1, '
            "high = 0.5, mean = 0.3 }",
            10,
            "screen",
            "mean",
            "not a parameter",
        ),
        (
            '"fractures[3].friction" = { distribution = "uniform", low = 0.1, '
            "high = 0.5 }",
            10,
            "screen",
            "fractures[3]",
            "index 3 does not exist",
        ),
        (
            '"pore_pressure.change" = { distribution = "uniform", low = -2e7, '
            "high = -1e7 }",
            10,
            "screen",
            "pore_pressure.change",
            "axis",
        ),
        (
            '"solver.max_iterations" = { distribution = "choice", values = [10, 20] }',
            10,
            "screen",
            "solver.max_iterations",
            'evaluate = "xfem"',
        ),
        (
            '"fractures[0].friction" = { distribution = "normal", mean = 0.5, '
            "std = 0.1, low = 2.0, high = 3.0 }",
            10,
            "screen",
            "friction",
            "holds no probability",
        ),
    ],
)
def test_bad_uncertainty_tables_name_the_key(
    tmp_path, inputs, samples, evaluate, key, words
):
    path = study(tmp_path, inputs, samples, evaluate)
    with pytest.raises(CaseError) as info:
        load(path)
    text = str(info.value)
    assert str(path) in text and key in text and words in text


@pytest.mark.parametrize(
    ("inputs", "words"),
    [
        (
            '"fractures[0].friction" = { distribution = "uniform", low = -1e308, '
            "high = 1e308 }",
            "draws values beyond the largest number",
        ),
        (
            '"fractures[0].friction" = { distribution = "lognormal", median = 0.5, '
            "sigma = 1000.0 }",
            "draws values beyond the largest number",
        ),
        (
            '"fractures[0].friction" = { distribution = "normal", mean = 0.5, '
            "std = 1e308 }",
            "draws values beyond the largest number",
        ),
        (
            '"material.nu" = { distribution = "uniform", low = -0.4, high = -0.1 }',
            "every value the uniform distribution draws (-0.4 to -0.1) is outside "
            "what the case format allows: must satisfy 0 <= nu < 0.5, got -0.1",
        ),
        (
            '"fractures[0].friction" = { distribution = "choice", '
            "values = [-0.2, -0.1] }",
            "must be >= 0, got -0.1",
        ),
    ],
)
def test_distributions_that_overflow_or_lie_outside_the_key_are_refused(
    tmp_path, inputs, words
):
    path = study(tmp_path, inputs, samples=10)
    with pytest.raises(CaseError) as info:
        load(path)
    assert "uncertainty.inputs." in str(info.value) and words in str(info.value)


def test_samples_outside_the_case_format_are_refused_by_the_screen(tmp_path):
    """nu < 0 is no value of the case format (it reads 0 <= nu < 0.5): the
    screen refuses those samples one by one and counts the others."""
    inputs = '"material.nu" = { distribution = "uniform", low = -0.2, high = 0.3 }'
    spec = load(study(tmp_path, inputs, samples=100))
    result = evaluate_screen(spec)
    negative = spec.values[:, 0] < 0.0
    assert 0 < negative.sum() < 100
    assert np.array_equal(result.status == "refused", negative)
    assert result.evaluated == 100 - negative.sum()
    reasons = {e for e, bad in zip(result.errors, negative, strict=True) if bad}
    assert all(e.startswith("material.nu: must satisfy 0 <= nu < 0.5") for e in reasons)


def test_choice_weights_of_1e308_draw_every_value(tmp_path):
    """Weights summing beyond the largest float are normalised by the
    largest: three equal weights of 1e308 draw each value a third of the
    time (Latin hypercube: exactly, up to one sample)."""
    inputs = (
        '"fractures[0].friction" = { distribution = "choice", '
        "values = [0.45, 0.5, 0.55], weights = [1e308, 1e308, 1e308] }"
    )
    spec = load(study(tmp_path, inputs, samples=300))
    values, counts = np.unique(spec.values[:, 0], return_counts=True)
    assert list(values) == [0.45, 0.5, 0.55]
    assert all(abs(c - 100) <= 1 for c in counts)


def test_a_half_width_no_study_can_reach_is_refused(tmp_path):
    path = study(tmp_path)
    path.write_text(path.read_text().replace("seed = 3", "seed = 3\nhalf_width = 1e-9"))
    with pytest.raises(CaseError) as info:
        load(path)
    # (z / 2h)^2 at the 95 % confidence: z = 1.959964
    assert "uncertainty.half_width: 1e-09 at confidence 0.95 needs about 9.6e+17" in (
        str(info.value)
    )
    assert "give at least 0.00098" in str(info.value)


def test_a_base_case_without_fractures_is_refused(tmp_path):
    base = BASE.replace(
        "[[fractures]]\ncenter = [50.0, 50.0]\nlength = 10.0\nangle = 60.0\n"
        "friction = 0.6\n",
        "",
    )
    inputs = '"material.E" = { distribution = "uniform", low = 9e9, high = 11e9 }'
    for evaluate in ("screen", "xfem"):
        with pytest.raises(CaseError, match="base: the base case has no fracture"):
            load(study(tmp_path, inputs, samples=5, evaluate=evaluate, base=base))


def test_one_sample_names_no_most_sensitive_input(tmp_path, runner):
    """A rank correlation over one sample is undefined (NaN): the summary
    says so instead of naming an input."""
    path = study(tmp_path, samples=1)
    res = runner.invoke(main, ["sweep", str(path), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    assert "most sensitive" not in res.output
    assert "sensitivity: not defined" in res.output


def test_overlapping_inputs_are_refused(tmp_path):
    inputs = (
        FRICTION + '\n"fractures[0]" = { distribution = "choice", values = [1.0, 2.0] }'
    )
    with pytest.raises(CaseError, match=r'"fractures\[0\].friction": overlaps'):
        load(study(tmp_path, inputs, evaluate="xfem"))


def test_levels_must_lie_within_the_case_change(tmp_path):
    path = study(tmp_path)
    path.write_text(path.read_text().replace("stop = -20.0e6", "stop = -30.0e6"))
    with pytest.raises(CaseError, match="between 0 and pore_pressure.change"):
        load(path)


def test_correlation_must_be_a_correlation_matrix(tmp_path):
    inputs = (
        FRICTION
        + '\n"pore_pressure.initial" = { distribution = "uniform", low = 2.9e7, '
        "high = 3.1e7 }"
        + '\n[[uncertainty.correlation]]\nkeys = ["fractures[0].friction", "nope"]'
        + "\nrho = 0.5"
    )
    with pytest.raises(CaseError, match="two different keys"):
        load(study(tmp_path, inputs))


CORRELATED = (
    FRICTION + '\n"pore_pressure.initial" = { distribution = "uniform", low = 2.9e7, '
    "high = 3.1e7 }"
    + '\n[[uncertainty.correlation]]\nkeys = ["fractures[0].friction", '
    '"pore_pressure.initial"]\nrho = 0.5'
)


@pytest.mark.parametrize("samples", [1, 2])
def test_correlation_with_no_more_samples_than_inputs_is_refused(
    tmp_path, runner, samples
):
    """The reordering needs the normal scores of the samples to span the
    inputs: samples <= inputs is refused in one line naming the file and
    the key, exit 2, nothing written; one sample more is drawn."""
    path = study(tmp_path, CORRELATED, samples=samples)
    out = tmp_path / "out"
    result = runner.invoke(main, ["sweep", str(path), "-o", str(out)])
    assert result.exit_code == 2, result.output
    assert result.stderr.strip() == (
        f"Error: {path}: uncertainty.samples: [[uncertainty.correlation]] needs "
        f"more samples than inputs (2), got {samples}"
    )
    assert "Traceback" not in result.output and not out.exists()
    path = study(tmp_path, CORRELATED, samples=3)
    result = runner.invoke(main, ["sweep", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "uncertainty.csv").is_file()


def test_a_reservoir_of_finite_width_is_refused_by_the_screen(tmp_path):
    base = BASE.replace(
        "[pore_pressure]",
        "[reservoir]\nbox = [20.0, 40.0, 80.0, 60.0]\nE = 5e9\nnu = 0.2\n"
        '[pore_pressure]\nregion = "reservoir"',
    )
    with pytest.raises(CaseError) as info:
        load(study(tmp_path, base=base))
    assert "uncertainty.evaluate" in str(info.value)
    assert "does not span the whole width" in str(info.value)
    # the full solve can follow it
    assert load(study(tmp_path, base=base, evaluate="xfem")).evaluate == "xfem"


def test_samples_are_reproducible_from_the_seed(tmp_path):
    inputs = (
        FRICTION + '\n"loading.initial_stress.xx" = { distribution = "normal", '
        "mean = -44e6, std = 2e6 }"
    )
    path = study(tmp_path, inputs)
    first, again = load(path).values, load(path).values
    np.testing.assert_array_equal(first, again)
    path.write_text(path.read_text().replace("seed = 3", "seed = 4"))
    assert not np.array_equal(first, load(path).values)
    # Latin hypercube: one sample in each of the 100 strata of the friction
    strata = np.floor((first[:, 0] - 0.44) / 0.08 * 100).astype(int)
    assert sorted(strata) == list(range(100))


# --------------------------------------------------------------------------- #
# The screen against independent references
# --------------------------------------------------------------------------- #


def test_screen_matches_critical_change_uniaxial_per_sample(tmp_path):
    inputs = (
        '"fractures[0].friction" = { distribution = "uniform", low = 0.45, '
        "high = 0.7 }\n"
        '"fractures[0].cohesion" = { distribution = "uniform", low = 0.0, '
        "high = 1e6 }\n"
        '"fractures[0].angle" = { distribution = "uniform", low = 20.0, '
        "high = 160.0 }\n"
        '"loading.initial_stress.xx" = { distribution = "normal", mean = -44e6, '
        "std = 2e6 }\n"
        '"pore_pressure.initial" = { distribution = "uniform", low = 2.5e7, '
        "high = 3e7 }\n"
        '"material.nu" = { distribution = "uniform", low = 0.15, high = 0.35 }'
    )
    spec = load(study(tmp_path, inputs, samples=1000))
    dp = evaluate_screen(spec).dp_critical[:, 0]
    checked = 0
    for (f, c, angle, sxx, p0, nu), got in zip(spec.values, dp, strict=True):
        initial = (sxx, -62e6, 0.0)
        ref = critical_change_uniaxial(initial, p0, nu, angle, f, c)
        th = math.radians(angle)
        n = np.array([-math.sin(th), math.cos(th)])
        t = np.array([math.cos(th), math.sin(th)])
        S = np.array([[sxx, 0.0], [0.0, -62e6]])
        margin0 = c + f * max(0.0, -(n @ S @ n + p0)) - abs(t @ S @ n)
        if margin0 <= 0.0:
            assert got == 0.0  # slips in situ, as deplete reports it
            continue
        if np.isnan(ref):
            assert np.isnan(got)
        else:
            assert got == pytest.approx(ref, rel=1e-9)
            checked += 1
    assert checked > 25


@pytest.mark.parametrize("method", ["lhs", "monte_carlo"])
def test_probability_of_uniform_friction_matches_the_binomial_reference(
    tmp_path, method
):
    """With f uniform on [a, b] and nothing else uncertain, the fracture has
    slipped by dp when f <= f*(dp) = |tau(dp)| / -sigma_n'(dp) (c = 0), so
    P(dp) = (f*(dp) - a) / (b - a), clipped to [0, 1]: the count is binomial
    and the Wilson interval must hold the exact value."""
    a, b = 0.44, 0.52
    path = study(tmp_path, samples=4000)
    path.write_text(
        path.read_text().replace("seed = 3", f'seed = 3\nmethod = "{method}"')
    )
    spec = load(path)
    result = evaluate_screen(spec)
    th = math.radians(60.0)
    n = np.array([-math.sin(th), math.cos(th)])
    t = np.array([math.cos(th), math.sin(th)])
    for k, dp in enumerate(spec.levels):
        nu = 0.25
        S = np.array([[-44e6 - (1 - 2 * nu) / (1 - nu) * dp, 0.0], [0.0, -62e6]])
        f_star = abs(t @ S @ n) / -(n @ S @ n + 30e6 + dp)
        exact = min(max((f_star - a) / (b - a), 0.0), 1.0)
        # the 95 % interval of a Latin hypercube (conservative for it); a
        # 99.9 % one for Monte Carlo: 11 levels of one seed at 95 % would miss
        # the exact value once in a while by chance alone
        lo, hi = (
            (result.ci_low[0, k], result.ci_high[0, k])
            if method == "lhs"
            else wilson_interval(result.slipped[0, k], result.evaluated, 0.999)
        )
        assert lo - 1e-12 <= exact <= hi + 1e-12
        if method == "lhs":  # stratified: the count is exact to a sample or two
            assert result.probability[0, k] == pytest.approx(exact, abs=2.5 / 4000)
    assert 0.3 < result.probability[0, -1] < 0.7  # the reference is not trivial
    # more friction: a deeper dp; the samples that would need the pore
    # pressure below 0 never slip and share the last rank
    assert np.isnan(result.dp_critical[spec.values[:, 0] > 0.51, 0]).all()
    assert result.sensitivity[0, 0] < -0.95


def test_slipped_counts_by_level():
    dp = np.array([[0.0, np.nan], [-5.0, -1.0], [-10.0, np.nan], [np.nan, -20.0]])
    counts = slipped_counts(dp, np.array([0.0, -5.0, -9.0, -20.0]))
    np.testing.assert_array_equal(counts, [[1, 2, 2, 3], [0, 1, 1, 2]])


def test_constant_total_stress_path_of_a_free_body(tmp_path):
    """Traction edges with u_y = 0 at the bottom: the total stress stays and
    only the pore pressure changes, here rising (injection): the fracture
    slips at dp_slip = margin / f (reference.screen.pressure_to_slip)."""
    from xfemslip.reference.screen import pressure_to_slip

    base = (
        BASE.replace("left = { ux = 0.0 }", 'left = "traction"')
        .replace("right = { ux = 0.0 }", 'right = "traction"')
        .replace("change = -20.0e6", "change = 2.0e6")
    )
    path = study(tmp_path, base=base, samples=50)
    path.write_text(path.read_text().replace("stop = -20.0e6", "stop = 2.0e6"))
    spec = load(path)
    result = evaluate_screen(spec)
    assert "constant total stress" in result.path_text
    th = math.radians(60.0)
    n = np.array([-math.sin(th), math.cos(th)])
    t = np.array([math.cos(th), math.sin(th)])
    S = np.diag([-44e6, -62e6])
    sn, tau = n @ S @ n + 30e6, t @ S @ n
    for f, got in zip(spec.values[:, 0], result.dp_critical[:, 0], strict=True):
        dp_slip = pressure_to_slip(sn, tau, f)[0]
        assert got == (0.0 if dp_slip <= 0.0 else pytest.approx(dp_slip, rel=1e-9))
    assert 0.0 < result.probability[0, -1] < 1.0


# --------------------------------------------------------------------------- #
# Command line
# --------------------------------------------------------------------------- #


def test_cli_screen_end_to_end(tmp_path, runner):
    path = study(tmp_path, samples=2000)
    out = tmp_path / "out"
    res = runner.invoke(main, ["sweep", str(path), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "stress path: uniaxial strain" in res.output
    names = {p.name for p in out.iterdir()}
    assert {
        "uncertainty.csv",
        "probability.csv",
        "sensitivity.csv",
        "uncertainty.h5",
        "probability.png",
    } <= names
    rows = (out / "probability.csv").read_text().splitlines()
    assert rows[0].startswith("fracture,dp_Pa,samples,slipped,probability,ci_low")
    assert len(rows) == 1 + 11
    with h5py.File(out / "uncertainty.h5") as h5:
        assert h5["dp_critical"].attrs["units"] == "Pa"
        assert h5["levels"].attrs["units"] == "Pa"
        assert h5["inputs"].shape == (2000, 1)
        p = h5["probability"][...]
    assert np.all(np.diff(p[0]) >= 0.0)  # slipped by dp stays slipped deeper


def test_cli_refuses_a_bad_study_writing_nothing(tmp_path, runner):
    path = study(tmp_path, samples=0)
    out = tmp_path / "out"
    res = runner.invoke(main, ["sweep", str(path), "-o", str(out)])
    assert res.exit_code == 2
    assert "uncertainty.samples" in res.output
    assert not out.exists()


def test_xfem_matches_the_screen_on_an_isolated_fracture(tmp_path, runner):
    """Under the uniaxial-strain path a stuck fracture does not disturb the
    uniform stress, so the closed form is exact: the XFEM critical changes
    agree to the bisection tolerance (20 kPa) plus the solver's resolution.
    A second run reads the samples back instead of solving them."""
    path = study(tmp_path, samples=4, evaluate="xfem")
    out = tmp_path / "out"
    res = runner.invoke(main, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert res.exit_code == 0, res.output
    with h5py.File(out / "uncertainty.h5") as h5:
        xfem = h5["dp_critical"][:, 0]
        slip = h5["max_slip"][:, 0]
        assert h5["max_slip"].attrs["units"] == "m"
    screen = evaluate_screen(load(path)).dp_critical[:, 0]
    # the screen also gives the change beyond the case's -20 MPa; deplete
    # stops there
    reached = np.abs(np.nan_to_num(screen, nan=np.inf)) <= 20e6
    assert np.array_equal(~np.isnan(xfem), reached)
    both = reached
    assert both.sum() >= 2
    np.testing.assert_allclose(xfem[both], screen[both], atol=2e5)
    assert np.all(slip[both] > 0.0)
    again = runner.invoke(main, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert again.exit_code == 0
    assert "4 evaluated (4 read back)" in again.output


def test_shipped_study_of_the_depleting_reservoir():
    """cases/sweeps/slip_probability.toml: the reservoir is a full-width layer,
    so the screen follows uniaxial strain inside it; fracture 2 lies in the
    host rock, whose stress does not change: its P stays at its in-situ value
    while fractures 0 and 1 (inside / across the top of the layer, mirror
    images at the same depth of the layer) rise together."""
    from pathlib import Path

    from xfemslip.studies.uncertainty import load_uncertainty

    root = Path(__file__).resolve().parents[3]
    spec = load_uncertainty(root / "cases" / "sweeps" / "slip_probability.toml")
    result = evaluate_screen(spec)
    assert "200 m < y < 300 m" in result.path_text
    assert result.evaluated == spec.samples == 20000
    # the pore pressure cannot fall below 0: no critical change below -p0
    # (the closed form's far roots of the Coulomb line are not onsets)
    p0 = spec.values[:, spec.keys.index("pore_pressure.initial")]
    dp = result.dp_critical
    assert np.all(np.isnan(dp) | (dp >= -p0[:, None]))
    assert np.isfinite(dp[:, :2]).sum() > 5000  # and the curve is not empty
    p = result.probability
    assert np.all(p[2] == p[2, 0])
    assert np.all(np.diff(p[0]) >= 0.0) and p[0, -1] > p[0, 0] + 0.1
    # the two mirror-image fractures differ only by their sampled friction
    assert np.all(np.abs(p[0] - p[1]) <= result.ci_high[0] - result.ci_low[0])
    # the correlation asked for between the pore pressure and sigma_h
    rho = np.corrcoef(
        np.argsort(np.argsort(spec.values[:, 4])),
        np.argsort(np.argsort(spec.values[:, 3])),
    )[0, 1]
    # within 2 standard errors of Spearman's rho over 20,000 independent
    # pairs, (1 - 0.5^2) sqrt(1.06 / 19997) = 0.0055 (test_sampling.py)
    assert rho == pytest.approx(0.5, abs=0.011)


def test_refused_samples_are_reported_not_fatal(tmp_path, runner):
    """A normal friction reaching below 0 gives samples the case format
    refuses: they are listed with the reason, left out of the counts, and
    the exit code is 1; the other samples are evaluated."""
    inputs = (
        '"fractures[0].friction" = { distribution = "normal", mean = 0.02, std = 0.1 }'
    )
    path = study(tmp_path, inputs, samples=3, evaluate="xfem")
    out = tmp_path / "out"
    res = runner.invoke(main, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert res.exit_code == 1, res.output
    rows = (out / "uncertainty.csv").read_text().splitlines()[1:]
    status = [r.split(",")[2] for r in rows]
    negative = [float(r.split(",")[1]) < 0.0 for r in rows]
    assert [s == "refused" for s in status] == negative
    assert 0 < sum(negative) < 3
    assert "friction: must be >= 0" in (out / "uncertainty.csv").read_text()
    with h5py.File(out / "uncertainty.h5") as h5:
        assert h5.attrs["evaluated"] == 3 - sum(negative)
    # the screen refuses the same values without a case per sample
    path = study(tmp_path, inputs, samples=200)
    result = evaluate_screen(load(path))
    assert np.array_equal(result.status == "refused", load(path).values[:, 0] < 0)
    assert result.evaluated == int(np.sum(load(path).values[:, 0] >= 0))


@pytest.mark.slow  # a scheduler and two worker processes: ~15 s
def test_xfem_samples_on_a_local_dask_cluster(tmp_path, runner, monkeypatch):
    """The same samples through --scheduler give the critical changes of the
    closed form (exact here) and a second run reads them back."""
    from pathlib import Path

    from distributed import LocalCluster

    monkeypatch.setenv("PYTHONPATH", str(Path(__file__).resolve().parents[3]))
    path = study(tmp_path, samples=4, evaluate="xfem")
    out = tmp_path / "out"
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        args = ["sweep", str(path), "-o", str(out)]
        res = runner.invoke(main, [*args, "--scheduler", cluster.scheduler_address])
        assert res.exit_code == 0, res.output
        again = runner.invoke(main, [*args, "--scheduler", cluster.scheduler_address])
        assert "4 evaluated (4 read back)" in again.output
    with h5py.File(out / "uncertainty.h5") as h5:
        xfem = h5["dp_critical"][:, 0]
    screen = evaluate_screen(load(path)).dp_critical[:, 0]
    reached = np.abs(np.nan_to_num(screen, nan=np.inf)) <= 20e6
    assert np.array_equal(~np.isnan(xfem), reached) and reached.sum() >= 2
    np.testing.assert_allclose(xfem[reached], screen[reached], atol=2e5)
