"""The network path of PARDISO (xfemslip.solve.lowrank): the stuck matrix
factored once with the Schur complement on the patch jumps, each Newton
system a low-rank change of it.  Checked against SuperLU and against the
general PARDISO path on the same systems and whole runs."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.support.newton_systems import recorded_systems, solve_like_spsolve
from xfemslip.case import loads_case
from xfemslip.fem.assembly import coo_block
from xfemslip.simulation import build_model, newton_solver
from xfemslip.solve import linear, lowrank, pardiso
from xfemslip.solve.linear import LU_BACKWARD_ERROR, LinearSolver

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "cases" / "reservoir_depletion.toml"
NETWORK = ROOT / "cases" / "fracture_network.toml"
needs_mkl = pytest.mark.skipif(not pardiso.available(), reason="pypardiso missing")


def _reservoir(n=20, steps=3, friction=0.1):
    text = CASE.read_text().replace("elements = [50, 50]", f"elements = [{n}, {n}]")
    text = text.replace("steps = 1", f"steps = {steps}")
    return text.replace("friction = 0.1", f"friction = {friction}")


def _stick(newton):
    c = newton.p.contact
    return lowrank.stick_tangents(c.weight, c.kn, c.kt, c.normal, c.tangent)


def _lowrank_solver(newton):
    c = newton.p.contact
    return LinearSolver(
        newton.K_ff,
        "pardiso",
        newton.free,
        None,
        newton.c_dofs,
        contact_coef=c.coef,
        contact_stick=_stick(newton),
    )


def test_patch_tangents_reads_each_blocks_2x2():
    """Blocks c c^T (x) D (as the contact kernel forms them) give back D to
    round-off, whichever coefficients have fixed dofs; a block that is not
    such a product is refused."""
    rng = np.random.default_rng(2)
    m, J = 7, 5
    coef = rng.standard_normal((m, J))
    coef[3, 2:] = 0.0  # a patch with fewer live coefficients
    dofs = rng.integers(0, 100, size=(m, 2 * J))
    dofs[1, 0:2] = -1  # its largest coefficient may sit on fixed dofs
    D = rng.standard_normal((m, 2, 2))
    blocks = np.einsum("mk,ml,mab->mkalb", coef, coef, D).reshape(m, 2 * J, 2 * J)
    got = lowrank.patch_tangents(blocks, coef, dofs)
    np.testing.assert_allclose(got, D, rtol=1e-14, atol=0)
    bad = blocks.copy()
    bad[4, 0, 3] += 1e-6 * np.abs(bad[4]).max()
    assert lowrank.patch_tangents(bad, coef, dofs) is None


@pytest.mark.parametrize("chunk", [1, 3, 7, 100])
def test_patch_tangents_checks_every_chunk(chunk, monkeypatch):
    """The form check runs over the patches a chunk at a time: the same D
    whatever the chunk, and a bad block is found in the first, a middle
    and the last chunk."""
    monkeypatch.setattr(lowrank, "FORM_CHUNK", chunk)
    rng = np.random.default_rng(5)
    m, J = 11, 4
    coef = rng.standard_normal((m, J))
    dofs = rng.integers(0, 100, size=(m, 2 * J))
    D = rng.standard_normal((m, 2, 2))
    blocks = np.einsum("mk,ml,mab->mkalb", coef, coef, D).reshape(m, 2 * J, 2 * J)
    np.testing.assert_allclose(
        lowrank.patch_tangents(blocks, coef, dofs), D, rtol=1e-14, atol=0
    )
    for i in (0, m // 2, m - 1):
        bad = blocks.copy()
        bad[i, 1, 2] += 1e-6 * np.abs(bad[i]).max()
        assert lowrank.patch_tangents(bad, coef, dofs) is None


def test_tangents_are_read_again_where_the_blocks_changed():
    """The systems' tangents after a first read: the changed patches read
    again, the others kept; the same as reading every block, and a changed
    block not of the patch form refused."""
    from types import SimpleNamespace

    rng = np.random.default_rng(5)
    m, J = 9, 4
    coef = rng.standard_normal((m, J))
    dofs = rng.integers(0, 100, size=(m, 2 * J))

    def blocks_of(D):
        return np.einsum("mk,ml,mab->mkalb", coef, coef, D).reshape(m, 2 * J, 2 * J)

    D = rng.standard_normal((m, 2, 2))
    systems = SimpleNamespace(_update=None, coef=coef, dofs=dofs)
    LRS = lowrank.LowRankSystems
    assert LRS._changed(systems, blocks_of(D)) is None  # no last tangent
    first = LRS._tangents(systems, blocks_of(D), None)
    np.testing.assert_allclose(first, D, rtol=1e-14, atol=0)
    systems._update = (blocks_of(D), first)
    assert LRS._changed(systems, blocks_of(D)).size == 0
    D2 = D.copy()
    D2[[2, 7]] = rng.standard_normal((2, 2, 2))
    changed = LRS._changed(systems, blocks_of(D2))
    np.testing.assert_array_equal(changed, [2, 7])
    got = LRS._tangents(systems, blocks_of(D2), changed)
    np.testing.assert_array_equal(
        got[[0, 1, 3, 4, 5, 6, 8]], first[[0, 1, 3, 4, 5, 6, 8]]
    )
    np.testing.assert_allclose(got, lowrank.patch_tangents(blocks_of(D2), coef, dofs))
    np.testing.assert_allclose(got, D2, rtol=1e-13, atol=0)
    bad = blocks_of(D2)
    bad[7, 0, 3] += 1e-6 * np.abs(bad[7]).max()
    assert LRS._tangents(systems, bad, LRS._changed(systems, bad)) is None


def test_stick_tangent_is_the_kernels():
    """D0 = w (k_N n n^T + k_T t t^T) is the block of a stuck patch as the
    contact kernel gives it (read back with patch_tangents)."""
    newton, seq = recorded_systems(_reservoir(friction=10.0, steps=1), CASE, 1)
    c = newton.p.contact
    D = lowrank.patch_tangents(seq[0][0], c.coef, newton.c_dofs)
    np.testing.assert_allclose(D, _stick(newton), rtol=1e-13, atol=0)


@needs_mkl
def test_schur_block_is_the_jump_compliance(monkeypatch):
    """G = M R^-1 M^T from PARDISO's Schur complement of the augmented
    matrix equals the product computed with SuperLU's solves of the stuck
    matrix R = K_ff + M^T M."""
    newton, _ = recorded_systems(_reservoir(n=12, steps=1), CASE, 1)
    c = newton.p.contact
    stats = dict.fromkeys(("factorizations", "pardiso_analyses"), 0)
    stats["factor_time"] = 0.0
    systems = lowrank.LowRankSystems(
        newton.K_ff, newton.c_dofs, c.coef, _stick(newton), LU_BACKWARD_ERROR, stats
    )
    systems._factor()
    M = systems.M.toarray()
    R = (newton.K_ff + sp.csr_matrix(M.T @ M)).tocsc()
    ref = M @ spla.splu(R).solve(M.T)
    np.testing.assert_allclose(systems.G, ref, rtol=0, atol=1e-10 * abs(ref).max())
    # eigenvalues in [0, 1]: the Schur block 2 I - G is well conditioned
    lam = np.linalg.eigvalsh(0.5 * (ref + ref.T))
    assert lam.min() > -1e-12 and lam.max() < 1.0 + 1e-12
    systems.release()


@needs_mkl
@pytest.mark.parametrize(
    ("friction", "slips"), [(0.1, True), (10.0, False)], ids=["sliding", "stuck"]
)
def test_newton_systems_match_superlu(friction, slips, monkeypatch):
    """Every Newton system of a 3-step run (the reservoir case, its contact
    dofs sent past the Schur mode's limit) through the low-rank path: the
    backward error bound against the assembled matrix and spsolve's answer
    to 1e-8; one factorization for the run, a dense LU per new tangent."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(friction=friction), CASE, 3)
    ls = _lowrank_solver(newton)
    changes, _ = solve_like_spsolve(newton, seq, ls)
    st = ls.stats
    assert isinstance(ls._pardiso, lowrank.LowRankSystems)
    assert st["pardiso_lowrank"] == len(seq) and st["pardiso_fallbacks"] == 0
    assert st["factorizations"] == 1 and st["pardiso_analyses"] == 1
    assert st["lowrank_updates"] == changes
    # stuck: nothing changes from the factored matrix; sliding: rank 1 per
    # slipping patch
    assert (st["lowrank_rank"] > 0) == slips


@needs_mkl
def test_open_patches_are_a_rank_two_change(monkeypatch):
    """Patches with no contact stiffness (open: zero blocks) next to stuck
    and slipping ones: the same answer as spsolve, rank 2 per open patch."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(friction=0.1, steps=1), CASE, 1)
    blocks, r = seq[-1]
    blocks = blocks.copy()
    blocks[::3] = 0.0
    ls = _lowrank_solver(newton)
    x = ls.solve_contact(blocks, r)
    A = (
        newton.K_ff + coo_block(newton.c_dofs, blocks, newton.free.size, "numpy")
    ).tocsc()
    x_ref = spla.spsolve(A, r)
    assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert ls.stats["lowrank_rank"] >= 2 * len(blocks[::3])


@needs_mkl
def test_blocks_of_another_form_go_to_the_general_path(monkeypatch, caplog):
    """A block that is not c c^T (x) D: one warning, that system and the
    later ones on PARDISO's general path, the same answer."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(n=16, steps=1), CASE, 1)
    blocks, r = seq[0]
    blocks = blocks.copy()
    blocks[0] += np.diag(np.arange(blocks.shape[1], dtype=float)) * abs(blocks).max()
    ls = _lowrank_solver(newton)
    with caplog.at_level(logging.WARNING, logger="xfemslip.solve.linear"):
        x = ls.solve_contact(blocks, r)
    A = (
        newton.K_ff + coo_block(newton.c_dofs, blocks, newton.free.size, "numpy")
    ).tocsc()
    x_ref = spla.spsolve(A, r)
    assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert "not of the patch form" in caplog.text
    assert ls.method == "pardiso" and ls.stats["pardiso_fallbacks"] == 1
    assert isinstance(ls._pardiso, pardiso.PardisoSystems)


@needs_mkl
def test_network_run_matches_the_general_path(monkeypatch):
    """The shipped 15-fracture network (crossings, T's, branch tips, 4
    load steps) solved through the low-rank path and through PARDISO on the
    whole matrix: the same Newton iterations and the same slip to 1e-7 of
    its maximum (the Newton tolerance is 1e-8 on the residual)."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    text = NETWORK.read_text().replace("elements = [80, 80]", "elements = [40, 40]")
    text = text.replace("[solver]", '[solver]\nlinear_solver = "pardiso"', 1)
    assert "elements = [40, 40]" in text and 'linear_solver = "pardiso"' in text
    out = {}
    for path in ("lowrank", "general"):
        if path == "general":
            monkeypatch.setattr(lowrank, "MAX_ROWS", 0)
        model = build_model(loads_case(text, NETWORK))
        solver = newton_solver(model)
        steps = solver.run(model.spec.loading.steps)
        st = solver.linear.stats
        assert (st["pardiso_lowrank"] > 0) == (path == "lowrank")
        assert st["pardiso_fallbacks"] == 0
        out[path] = (
            [s.iterations for s in steps],
            np.concatenate([s.contact.point_gt for s in steps]),
            st["factorizations"],
        )
    assert out["lowrank"][0] == out["general"][0]
    ref = np.abs(out["general"][1]).max()
    assert ref > 0.0
    assert np.abs(out["lowrank"][1] - out["general"][1]).max() <= 1e-7 * ref
    assert out["lowrank"][2] == 1 < out["general"][2]


def test_without_coefficients_the_paths_are_as_before(monkeypatch):
    """No jump coefficients given: never the low-rank path."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    ls = LinearSolver(sp.identity(4, format="csr"), "superlu")
    assert not ls._lowrank_applies(np.array([[0, 1, 2, 3]]))
    assert linear.lowrank is lowrank


# ------------------------------------------------- the same on SuperLU alone


def _augmented_solver(newton, kernels="numpy"):
    c = newton.p.contact
    return LinearSolver(
        newton.K_ff,
        "superlu",
        newton.free,
        None,
        newton.c_dofs,
        kernels=kernels,
        contact_coef=c.coef,
        contact_stick=_stick(newton),
    )


# the augmented path solves each system in two whole SuperLU solves with the
# NumPy kernels and in one pass through the factors with the compiled ones
KERNELS = pytest.mark.parametrize("kernels", ["numpy", "numba"])


@pytest.mark.parametrize(
    ("friction", "slips"), [(0.1, True), (10.0, False)], ids=["sliding", "stuck"]
)
@KERNELS
def test_superlu_augmented_systems_match_spsolve(friction, slips, kernels, monkeypatch):
    """Without PARDISO: every Newton system of a 3-step run (the reservoir
    case, its contact dofs sent past the Schur limit) on ONE SuperLU
    factorization of the augmented matrix: the backward error bound and
    spsolve's answer to 1e-8, a dense LU per new tangent."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(friction=friction), CASE, 3)
    ls = _augmented_solver(newton, kernels)
    changes, _ = solve_like_spsolve(newton, seq, ls)
    st = ls.stats
    assert isinstance(ls._augmented, lowrank.AugmentedLU)
    assert (ls._augmented._factors is not None) == (kernels == "numba")
    assert st["lowrank_superlu"] == len(seq) == st["solves"]
    assert st["factorizations"] == 1 and st["lowrank_updates"] == changes
    assert (st["lowrank_rank"] > 0) == slips


@pytest.mark.parametrize("reordered", [False, True], ids=["its-order", "moved-last"])
def test_superlu_schur_block_is_the_jump_compliance(reordered, monkeypatch):
    """G = M R^-1 M^T read off the trailing block of the augmented factors
    equals the product from SuperLU's solves of the stuck matrix R =
    K_ff + M^T M, whether the minimum-degree ordering left the jump rows
    last by itself or they were moved there (its eigenvalues in [0, 1])."""
    from scipy.sparse.linalg import splu as real_splu

    newton, _ = recorded_systems(_reservoir(n=12, steps=1), CASE, 1)
    c = newton.p.contact
    stats = dict.fromkeys(("factorizations",), 0)
    stats["factor_time"] = 0.0
    calls = []

    def splu(A, **kw):  # the first ordering with the jump rows not last
        lu = real_splu(A, **kw)
        calls.append(kw["permc_spec"])
        if reordered and len(calls) == 1:

            class Shuffled:
                perm_r = perm_c = np.arange(A.shape[0])[::-1].copy()

            return Shuffled()
        return lu

    monkeypatch.setattr(spla, "splu", splu)
    systems = lowrank.AugmentedLU(
        newton.K_ff,
        newton.c_dofs,
        c.coef,
        _stick(newton),
        LU_BACKWARD_ERROR,
        stats,
        linear.LU_FAST,
    )
    systems._factor()
    n = newton.K_ff.shape[0]
    if reordered:
        assert calls == ["MMD_AT_PLUS_A", "NATURAL"] and systems._order is not None
        m2 = systems.M.shape[0]
        assert np.array_equal(systems._order[-m2:] - n, np.arange(m2))
    M = systems.M.toarray()
    R = (newton.K_ff + sp.csr_matrix(M.T @ M)).tocsc()
    ref = M @ real_splu(R).solve(M.T)
    np.testing.assert_allclose(systems.G, ref, rtol=0, atol=1e-10 * abs(ref).max())
    lam = np.linalg.eigvalsh(0.5 * (ref + ref.T))
    assert lam.min() > -1e-12 and lam.max() < 1.0 + 1e-12
    assert systems._B is None  # released once factored


@pytest.mark.parametrize("network", [True, False], ids=["network", "reservoir"])
def test_superlu_one_pass_equals_two_whole_solves(network, monkeypatch):
    """The compiled kernels' one pass through the augmented factors (forward
    over the stuck matrix, the jumps by Woodbury, backward with them held)
    gives the two whole SuperLU solves' answer to round-off on every Newton
    system of a run whose tangents change: the shipped 15-fracture network,
    whose minimum-degree ordering leaves the jump rows last (both
    permutations of the factors non-trivial), and the reservoir case, where
    they are moved last; SuperLU's own copy of the factors is not kept."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    if network:
        path = CASE.parent / "fracture_network.toml"
        newton, seq = recorded_systems(path.read_text(), path, 1)
    else:
        newton, seq = recorded_systems(_reservoir(friction=0.1, steps=1), CASE, 1)
    answers = {}
    for kernels in ("numpy", "numba"):
        ls = _augmented_solver(newton, kernels)
        answers[kernels] = [ls.solve_contact(b, r) for b, r in seq]
        aug = ls._augmented
        assert isinstance(aug, lowrank.AugmentedLU)
        assert (aug._order is None) == network
        assert ls.stats["lowrank_updates"] > 1 and aug._update[2].size > 0
        assert (aug._lu is None) == (kernels == "numba")
    if network:
        _, _, perm_r, perm_c = aug._factors
        n = newton.K_ff.shape[0]
        assert not np.array_equal(perm_c[:n], np.arange(n))
        assert not np.array_equal(perm_r[:n], np.arange(n))
    for x1, x2 in zip(answers["numpy"], answers["numba"], strict=True):
        assert np.linalg.norm(x2 - x1) <= 1e-11 * np.linalg.norm(x1)


@KERNELS
def test_superlu_open_patches_are_a_rank_two_change(kernels, monkeypatch):
    """Open patches (zero blocks) next to stuck and slipping ones on the
    augmented SuperLU path: spsolve's answer, rank 2 per open patch."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(friction=0.1, steps=1), CASE, 1)
    blocks, r = seq[-1]
    blocks = blocks.copy()
    blocks[::3] = 0.0
    ls = _augmented_solver(newton, kernels)
    x = ls.solve_contact(blocks, r)
    A = (
        newton.K_ff + coo_block(newton.c_dofs, blocks, newton.free.size, "numpy")
    ).tocsc()
    x_ref = spla.spsolve(A, r)
    assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert ls.stats["lowrank_rank"] >= 2 * len(blocks[::3])
    assert ls.stats["lowrank_superlu"] == 1


def test_superlu_blocks_of_another_form_go_to_the_kept_factorization(
    monkeypatch, caplog
):
    """A block that is not c c^T (x) D on the augmented path: one warning,
    that system and the later ones on SuperLU's factorization of the whole
    matrix, the same answers."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = recorded_systems(_reservoir(n=16, steps=1), CASE, 1)
    blocks, r = seq[0]
    blocks = blocks.copy()
    blocks[0] += np.diag(np.arange(blocks.shape[1], dtype=float)) * abs(blocks).max()
    ls = _augmented_solver(newton)
    with caplog.at_level(logging.WARNING, logger="xfemslip.solve.linear"):
        for _ in range(2):
            x = ls.solve_contact(blocks, r)
            A = (
                newton.K_ff
                + coo_block(newton.c_dofs, blocks, newton.free.size, "numpy")
            ).tocsc()
            x_ref = spla.spsolve(A, r)
            assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert caplog.text.count("not of the patch form") == 1
    assert ls._augmented is False and ls._lu is not None
    assert ls.stats["lowrank_superlu"] == 0 and ls.stats["solves"] == 2


def test_network_run_on_superlu_matches_the_kept_factorization_path(monkeypatch):
    """The shipped 15-fracture network (crossings, T's, branch tips, 4 load
    steps) on SuperLU through the augmented factorization and through the
    factorizations of the whole matrix: the same Newton iterations and the
    same slip to 1e-7 of its maximum; one factorization for the run."""
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    text = NETWORK.read_text().replace("elements = [80, 80]", "elements = [40, 40]")
    text = text.replace("[solver]", '[solver]\nlinear_solver = "superlu"', 1)
    assert "elements = [40, 40]" in text and 'linear_solver = "superlu"' in text
    out = {}
    for path in ("augmented", "whole"):
        if path == "whole":
            monkeypatch.setattr(lowrank, "AUGMENTED_MAX_ROWS", 0)
        model = build_model(loads_case(text, NETWORK))
        solver = newton_solver(model)
        steps = solver.run(model.spec.loading.steps)
        st = solver.linear.stats
        assert (st["lowrank_superlu"] > 0) == (path == "augmented")
        if path == "augmented":  # the clique left the jump rows last by itself
            assert solver.linear._augmented._order is None
        out[path] = (
            [s.iterations for s in steps],
            np.concatenate([s.contact.point_gt for s in steps]),
            st["factorizations"],
        )
    assert out["augmented"][0] == out["whole"][0]
    ref = np.abs(out["whole"][1]).max()
    assert ref > 0.0
    assert np.abs(out["augmented"][1] - out["whole"][1]).max() <= 1e-7 * ref
    assert out["augmented"][2] == 1 < out["whole"][2]


@pytest.mark.parametrize("method", ["auto", "superlu"])
def test_network_on_superlu_says_what_pardiso_would_gain(method, monkeypatch, caplog):
    """A network taking the augmented SuperLU path under "auto" without the
    mkl extra says once what PARDISO gained on such networks (the measured
    factor and the install command); asked for SuperLU by name, it does not."""
    monkeypatch.setattr(pardiso, "available", lambda: False)
    # this small network's contact dofs would go to the Schur path
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    text = NETWORK.read_text().replace("elements = [80, 80]", "elements = [40, 40]")
    text = text.replace("[solver]", f'[solver]\nlinear_solver = "{method}"', 1)
    assert "elements = [40, 40]" in text
    model = build_model(loads_case(text, NETWORK))
    solver = newton_solver(model)
    with caplog.at_level(logging.INFO, logger="xfemslip.solve.linear"):
        solver.run(model.spec.loading.steps)
    assert solver.linear.stats["lowrank_superlu"] > 1
    lines = [m for m in caplog.messages if "xfemslip[mkl]" in m]
    if method == "superlu":
        assert lines == []
        return
    assert len(lines) == 1
    rows = 2 * len(solver.linear.contact_dofs)
    assert f"bordered by {rows} patch jumps" in lines[0]
    assert f"1/{linear.PARDISO_NETWORK_GAIN:.1f} of the time" in lines[0]
