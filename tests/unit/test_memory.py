"""The memory estimate: refused before allocating, with the estimate named."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from tests.support.casegen import sweep_member
from tests.support.hardcases import estimates, measure
from xfemslip.case import build, load_case, loads_case
from xfemslip.cli import cli
from xfemslip.errors import MeshError, UsageError
from xfemslip.fem.enrichment import find_candidates
from xfemslip.memory import (
    ENV_LIMIT,
    GRID_BYTES,
    MMAP_THRESHOLD,
    NEWTON_BLOCKS,
    TRIM_THRESHOLD,
    TRIPLET_BYTES,
    Footprint,
    available_bytes,
    check_memory,
    enriched_footprint,
    estimate_dofs,
    estimate_terms,
    model_footprint,
)
from xfemslip.simulation import build_model
from xfemslip.solve import linear as linsolve
from xfemslip.solve.guess import KEEP
from xfemslip.solve.linear import (
    AMG_BYTES,
    AMG_RESTART,
    LU_BYTES,
    LU_FACTORS,
    MATRIX_BYTES,
    PARDISO_BYTES,
    solver_bytes,
)

CASES = Path(__file__).resolve().parents[2] / "cases"
CASE = CASES / "reservoir_depletion.toml"


@pytest.mark.parametrize(
    ("text", "value"), [("500M", 5e8), ("2g", 2e9), ("1e9", 1e9), ("123", 123.0)]
)
def test_limit_from_the_environment(monkeypatch, text, value):
    monkeypatch.setenv(ENV_LIMIT, text)
    assert available_bytes() == (value, ENV_LIMIT)


@pytest.mark.parametrize("text", ["abc", "-1G", "0", "nan", "1X", "inf"])
def test_bad_limit_is_a_usage_error(monkeypatch, text):
    monkeypatch.setenv(ENV_LIMIT, text)
    with pytest.raises(UsageError, match=ENV_LIMIT):
        available_bytes()


def test_physical_memory_is_the_default(monkeypatch):
    monkeypatch.delenv(ENV_LIMIT, raising=False)
    limit, source = available_bytes()
    assert source == "physical memory" and 1e8 < limit < math.inf


def test_estimate_counts_the_dofs():
    """50 x 50 reservoir: 5202 standard dofs plus the enriched ones (6128 in
    total, measured); the estimate from the case is within 20 %."""
    spec = load_case(CASE)
    n = estimate_dofs(spec)
    assert 2 * 51 * 51 < n and abs(n - 6128) < 0.2 * 6128


def test_terms_follow_their_sizes():
    """Each term grows with the size it counts: doubling the steps doubles
    the kept-steps term, the LU term grows like nnz log2(n_dofs), the padded
    element matrices like (8 + 2 S)^2, the contact tangents like the patches
    times the square of the widest block."""
    fp = Footprint(n_nodes=10_000, n_cells=9_801, n_dofs=20_000, nnz=4e5, steps=10)
    t = estimate_terms(fp)
    assert estimate_terms(replace(fp, steps=20))["steps"] == pytest.approx(
        2 * t["steps"]
    )
    big = estimate_terms(replace(fp, n_dofs=40_000, nnz=8e5))["solver"]
    lu = LU_FACTORS * LU_BYTES
    ratio = (MATRIX_BYTES + lu * math.log2(40_000)) / (
        MATRIX_BYTES + lu * math.log2(20_000)
    )
    assert big == pytest.approx(2 * t["solver"] * ratio)
    contact = replace(fp, patches=100, block=20, contact_entries=0.0)
    tangents = estimate_terms(contact)["contact tangents"]
    assert tangents == pytest.approx(
        (NEWTON_BLOCKS + 1) * 8.0 * 100 * 20**2  # NumPy kernels: one more array
    )
    wider = estimate_terms(replace(contact, block=40))["contact tangents"]
    assert wider == pytest.approx(4 * tangents)
    # PARDISO: one factorization and the dense Schur complement of the
    # contact dofs with its LU (16 B per entry) while it is used
    pardiso = replace(fp, linear="pardiso", contact_dofs=1000.0)
    assert estimate_terms(pardiso)["solver"] == pytest.approx(
        4e5 * (MATRIX_BYTES + PARDISO_BYTES * math.log2(20_000)) + 16.0 * 1000**2
    )
    many = replace(pardiso, contact_dofs=1e5)  # fixed-pattern mode: no dense block
    assert estimate_terms(many)["solver"] == pytest.approx(
        4e5 * (MATRIX_BYTES + PARDISO_BYTES * math.log2(20_000))
    )
    wide = replace(
        fp, enriched_cells=100, slots=10, entries=6e5, enriched_entries=5e5, numba=True
    )
    assert estimate_terms(wide)["assembly"] == pytest.approx(
        100 * 28**2 * 8 + GRID_BYTES * 10_000 + TRIPLET_BYTES * 5e5
    )
    assert t["total"] == pytest.approx(
        t["base"]
        + t["enriched cells"]
        + max(t["assembly"], t["solver"] + t["contact tangents"] + t["steps"])
    )


def test_solver_term_is_the_solvers_own_statement(monkeypatch):
    """The solver term is solve.linear.solver_bytes of the footprint's
    sizes (a hand sum for AMG: the matrices and hierarchy per non-zero, the
    GMRES basis and the kept solutions per dof), and the solver the
    estimate counts is the one LinearSolver takes on the same matrix (the
    reservoir case on 30 x 30 cells, the AMG floor lowered, the band limit
    on both sides of the case's band share)."""
    fp = Footprint(
        n_nodes=10_000, n_cells=9_801, n_dofs=20_000, nnz=4e5, steps=1, contact_dofs=50
    )
    for method in ("superlu", "amg", "pardiso"):
        assert estimate_terms(replace(fp, linear=method))["solver"] == solver_bytes(
            method, 4e5, 20_000, 50
        )
    assert solver_bytes("amg", 4e5, 20_000, 50) == pytest.approx(
        4e5 * (MATRIX_BYTES + AMG_BYTES) + (AMG_RESTART + 1 + KEEP) * 8.0 * 20_000
    )
    pytest.importorskip("pyamg")
    monkeypatch.setattr(linsolve.pardiso, "available", lambda: False)
    monkeypatch.setattr(linsolve, "AUTO_AMG_MIN_DOFS", 100)
    text = build.case_text(build.file_case(CASE, **{"mesh.elements": [30, 30]}))
    model = build_model(loads_case(text, CASE))
    p = model.problem
    share = linsolve.system_facts(p.K, np.arange(p.n_dofs), p.node_xy)["band_share"]
    for limit, method in ((share, "amg"), (0.99 * share, "superlu")):
        monkeypatch.setattr(linsolve, "AUTO_AMG_MAX_BAND", limit)
        assert model_footprint(model).linear == method
        solver = linsolve.LinearSolver(p.K, "auto", np.arange(p.n_dofs), p.node_xy)
        assert solver.method == method


def _text(name, **keys):
    """The shipped case ``name`` with the values at dotted key paths set."""
    return build.case_text(build.file_case(CASES / f"{name}.toml", **keys))


# (case text, what it stands for): the shipped reservoir, many kept load
# steps, and a crowded generated network (60 fractures on 30 x 30 cells: up
# to 58 enrichment slots in a cell, the element matrices padded to them).
MEASURED = {
    "reservoir": lambda: _text("reservoir_depletion"),
    "60-steps": lambda: _text("reservoir_depletion", **{"loading.steps": 60}),
    "crowded-network": lambda: sweep_member(
        index=0,
        **{
            "network.generate.count": 60,
            "mesh.elements": [30, 30],
            "network.tip": "ramp",
        },
    ),
}
# Stated accuracy: the estimates after the node enrichments and from the
# built model lie within this factor range of the measured peak (measured
# 0.90 to 1.34 over the cases of benchmarks/memory_estimate.py).
FACTOR = (0.85, 1.5)


# the long and the crowded run take a minute of CPU: slow tier
@pytest.mark.parametrize(
    "name",
    [
        pytest.param(name, marks=pytest.mark.slow) if name != "reservoir" else name
        for name in MEASURED
    ],
)
def test_estimate_against_the_measured_peak(tmp_path, monkeypatch, name):
    """The peak resident memory of `xfemslip run` in its own process (its
    ru_maxrss, a measured reference) against the estimates."""
    monkeypatch.delenv(ENV_LIMIT, raising=False)
    case = tmp_path / f"{name}.toml"
    case.write_text(MEASURED[name]())
    argv = [sys.executable, "-m", "xfemslip", "run", "-q", str(case)]
    _, enriched, model = estimates(case)
    peaks = []
    # The crowded network peaked at 356 MiB alone and at 450 MiB while a
    # second test suite ran on the 2-core machine: the peak depends on the
    # machine's state as well as on the run, so a peak that puts the estimate
    # below the range is measured once more and the smaller one is taken.
    for attempt in range(2):
        out = tmp_path / f"out{attempt}"
        code, _, peak_mb, lines = measure(
            argv + ["-o", str(out)], 300.0, out.with_suffix(".log")
        )
        assert code in (0, 1), lines[-3:]  # a failed solve has its peak too
        peaks.append(peak_mb)
        if min(enriched, model) / 1e6 / min(peaks) > FACTOR[0]:
            break
    peak_mb = min(peaks)
    for estimate in (enriched, model):
        assert FACTOR[0] < estimate / 1e6 / peak_mb < FACTOR[1], (estimate, peaks)


def test_crowded_network_refused_below_its_peak(tmp_path, monkeypatch):
    """200 fractures on 100 x 100 cells (measured peak 1.3 GB) under a 600 MB
    limit: refused in one line naming the estimate and the limit, before the
    enriched cells are built, so the process never reaches the limit;
    nothing is written."""
    case = tmp_path / "dense.toml"
    case.write_text(
        sweep_member(
            index=0,
            **{
                "network.generate.count": 200,
                "mesh.elements": [100, 100],
                "network.tip": "ramp",
                # AMG's smaller solver term lets the case pass the first
                # check (from the fracture lengths), so the second one, from
                # the enriched nodes, is what refuses it
                "solver.linear_solver": "amg",
            },
        )
    )
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "xfemslip", "run", "-q", str(case), "-o", str(out)]
    monkeypatch.setenv(ENV_LIMIT, "600M")
    code, _, peak_mb, lines = measure(argv, 300.0, tmp_path / "log.txt")
    assert code == 2
    errors = [ln for ln in lines if ln.startswith("Error:")]
    assert len(errors) == 1 and "Traceback" not in "\n".join(lines)
    assert "need an estimated" in errors[0] and "0.6 GB available" in errors[0]
    assert ENV_LIMIT in errors[0]
    # the largest terms are named (the contact tangents lead on this network)
    assert "contact tangents" in errors[0]
    assert peak_mb < 600.0
    assert not out.exists()


def test_model_check_sees_the_kept_steps(monkeypatch):
    """The shipped network with 100 load steps: its model estimate exceeds the
    one made before the enriched cells (the tangent blocks of its patches are
    wider than that one assumes); a limit between the two is refused by
    build_model, after assembly and before the first solve."""
    spec = loads_case(_text("fracture_network", **{"loading.steps": 100}), "net.toml")
    monkeypatch.delenv(ENV_LIMIT, raising=False)
    model = build_model(spec)
    mesh, fractures = model.mesh, model.fractures
    cand = find_candidates(mesh, fractures)
    before = estimate_terms(enriched_footprint(spec, mesh, fractures, cand))
    after = estimate_terms(model_footprint(model))
    assert after["total"] > before["total"]
    limit = 0.5 * (before["total"] + after["total"])
    monkeypatch.setenv(ENV_LIMIT, f"{limit:.0f}")
    with pytest.raises(MeshError, match="100 kept load steps"):
        build_model(spec)


def test_refused_before_building_with_the_estimate(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_LIMIT, "100M")
    spec = load_case(CASE)
    with pytest.raises(MeshError) as info:
        check_memory(spec)
    text = str(info.value)
    assert str(CASE) in text and "mesh: 50 x 50 elements" in text
    assert "GB of memory" in text and ENV_LIMIT in text
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["run", str(CASE), "-o", str(out)])
    assert result.exit_code == 2
    assert not out.exists()


def _allocator_in_child(env):
    """configure_allocator() in a fresh interpreter: its return value and the
    thresholds it leaves in the environment for the processes it starts."""
    code = (
        "import os; from xfemslip.memory import configure_allocator as c; "
        "print(c(), os.environ.get('MALLOC_MMAP_THRESHOLD_'), "
        "os.environ.get('MALLOC_TRIM_THRESHOLD_'))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


@pytest.mark.skipif(
    not os.confstr("CS_GNU_LIBC_VERSION").startswith("glibc"), reason="glibc only"
)
def test_allocator_thresholds_are_fixed_unless_the_user_chose():
    """On glibc the thresholds are set and passed on to child processes; a
    threshold or a glibc.malloc tunable already in the environment is the
    user's choice and is left alone."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.pop("GLIBC_TUNABLES", None)
    assert _allocator_in_child(env) == [
        "True",
        str(MMAP_THRESHOLD),
        str(TRIM_THRESHOLD),
    ]
    assert _allocator_in_child({**env, "MALLOC_TRIM_THRESHOLD_": "1"}) == [
        "False",
        "None",
        "1",
    ]
    tunable = {**env, "GLIBC_TUNABLES": "glibc.malloc.mmap_threshold=65536"}
    assert _allocator_in_child(tunable) == ["False", "None", "None"]
