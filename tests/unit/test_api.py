"""The public Python API: load_case, run_case -> Result, read_result.

References: the Result that run_case returns without writing anything is
compared, array for array, with the one read back from the result.h5 it
writes when given a folder (output-format.md: the element stresses are kept
for the final step only), and with the arrays of the file read with h5py
directly; the attributes a run summary reports are checked against the
per-step figures they sum up.
"""

from __future__ import annotations

import tomllib
from dataclasses import fields
from pathlib import Path

import h5py
import numpy as np
import pytest

import xfemslip
from xfemslip.case.build import case_text
from xfemslip.conventions import SLIP

CASES = Path(__file__).resolve().parents[2] / "cases"


def _case(tmp_path, name, **changes) -> Path:
    """A shipped case with some tables replaced, as a file in tmp_path."""
    doc = tomllib.loads((CASES / f"{name}.toml").read_text())
    for key, value in changes.items():
        table, _, item = key.partition(".")
        doc.setdefault(table, {})[item] = value
    path = tmp_path / f"{name}.toml"
    path.write_text(case_text(doc))
    return path


def _assert_same_step(read, kept, *, final):
    """Every array of the read-back step equals the one kept in memory; the
    element stresses are read back for the final step only."""
    assert (read.step, read.load_factor, read.newton_iterations) == (
        kept.step,
        kept.load_factor,
        kept.newton_iterations,
    )
    np.testing.assert_array_equal(read.displacement, kept.displacement)
    for name in ("stress", "stress_zz", "principal_stress"):
        if final:
            np.testing.assert_array_equal(getattr(read, name), getattr(kept, name))
        else:
            assert getattr(read, name) is None
    for name in ("effective_stress", "pore_pressure"):
        want = getattr(kept, name) if final else None
        got = getattr(read, name)
        assert (got is None) == (want is None)
        if want is not None:
            np.testing.assert_array_equal(got, want)
    assert len(read.fractures) == len(kept.fractures)
    for a, b in zip(read.fractures, kept.fractures, strict=True):
        for item in fields(a):
            x, y = getattr(a, item.name), getattr(b, item.name)
            assert (x is None) == (y is None), item.name
            if x is not None:
                assert x.dtype == y.dtype, item.name
                np.testing.assert_array_equal(x, y, err_msg=item.name)


def _assert_same_result(read, kept):
    assert set(read.attrs) == set(kept.attrs)
    for key, value in kept.attrs.items():
        np.testing.assert_array_equal(read.attrs[key], value, err_msg=key)
    np.testing.assert_array_equal(read.points, kept.points)
    np.testing.assert_array_equal(read.cells, kept.cells)
    assert len(read.steps) == len(kept.steps)
    for k, (a, b) in enumerate(zip(read.steps, kept.steps, strict=True)):
        _assert_same_step(a, b, final=k == len(kept.steps) - 1)


def test_the_public_names_are_at_the_top():
    for name in ("load_case", "run_case", "read_result", "Result", "errors"):
        assert hasattr(xfemslip, name), name
    assert issubclass(xfemslip.ConvergenceError, xfemslip.XfemslipError)
    assert xfemslip.Result is xfemslip.post.result.Result


def test_run_case_without_a_folder_writes_nothing(tmp_path, monkeypatch):
    case = _case(tmp_path, "reservoir_depletion", **{"mesh.elements": [20, 20]})
    work = tmp_path / "cwd"
    work.mkdir()
    monkeypatch.chdir(work)
    before = sorted(tmp_path.rglob("*"))
    result = xfemslip.run_case(xfemslip.load_case(case))
    assert sorted(tmp_path.rglob("*")) == before
    assert result.out_dir is None
    assert result.converged and result.load_steps == 1 and len(result.steps) == 1
    final = result.final
    assert final.displacement.shape == (21 * 21, 2)
    assert final.stress.shape == (400, 3)
    (fracture,) = result.fractures
    assert np.all(np.diff(fracture.s) > 0.0)  # ordered by arc length
    # the 45-degree fracture of this case slips (liu_borja / reservoir golden)
    assert np.any(fracture.state == SLIP)
    assert result.newton_iterations == sum(result.iterations_per_step)


def test_run_case_result_equals_the_file_read_back(tmp_path):
    """Three load steps: every step's displacement and fracture fields, the
    final step's stresses and every attribute come back as they were."""
    case = _case(
        tmp_path,
        "reservoir_depletion",
        **{"mesh.elements": [20, 20], "loading.steps": 3},
    )
    spec = xfemslip.load_case(case)
    out = tmp_path / "out"
    kept = xfemslip.run_case(spec, out)
    assert kept.out_dir == out
    assert {p.name for p in out.iterdir()} >= {"result.h5", "result.pvd"}
    read = xfemslip.read_result(out / "result.h5")
    assert len(kept.steps) == 3
    _assert_same_result(read, kept)
    assert xfemslip.read_result(out).run_id == kept.run_id  # a folder reads too
    # the same numbers as the file holds, read without xfemslip
    with h5py.File(out / "result.h5") as h5:
        np.testing.assert_array_equal(
            h5["steps/0002/fractures/0/slip"][()], kept.steps[1].fractures[0].slip
        )
        np.testing.assert_array_equal(h5["fields/stress"][()], kept.stress)
        assert h5.attrs["run_id"] == kept.run_id
    # writing changes no number: the same run without a folder
    alone = xfemslip.run_case(spec)
    for a, b in zip(alone.steps, kept.steps, strict=True):
        _assert_same_step(a, b, final=True)
    for key in set(kept.attrs) - {"wall_time_s", "run_id"}:
        np.testing.assert_array_equal(alone.attrs[key], kept.attrs[key])


def test_pore_pressure_fields_read_back(tmp_path):
    """The depletion case: effective stress, pore pressure, fluid pressure and
    the effective normal traction round-trip too."""
    case = _case(
        tmp_path,
        "depleting_reservoir",
        **{"loading.steps": 2, "output.formats": ["h5"]},
    )
    kept = xfemslip.run_case(xfemslip.load_case(case), tmp_path / "out")
    final = kept.final
    assert final.pore_pressure is not None
    assert all(f.fluid_pressure is not None for f in final.fractures)
    # total = effective - fluid pressure (tension positive, poro.py)
    f0 = final.fractures[0]
    np.testing.assert_allclose(
        f0.normal_traction, f0.effective_normal_traction - f0.fluid_pressure
    )
    _assert_same_result(xfemslip.read_result(tmp_path / "out"), kept)


def test_a_failed_run_keeps_its_converged_steps(tmp_path):
    """The reservoir case that cannot converge at step 3 (test_failure.py):
    the error carries the Result of steps 1 and 2, the same as the file."""
    case = _case(
        tmp_path,
        "reservoir_depletion",
        **{
            "loading.steps": 5,
            "solver.max_iterations": 1,
            "solver.tangent": "secant",
            "output.formats": ["h5"],
        },
    )
    doc = tomllib.loads(case.read_text())
    doc["fractures"][0]["cohesion"] = 3.0e6
    case.write_text(case_text(doc))
    out = tmp_path / "out"
    with pytest.raises(xfemslip.ConvergenceError) as info:
        xfemslip.run_case(xfemslip.load_case(case), out)
    err = info.value
    assert err.step == 3 and not err.result.converged
    assert [s.step for s in err.result.steps] == [1, 2]
    assert err.reason and err.reason in str(err)
    _assert_same_result(xfemslip.read_result(out), err.result)


def test_read_result_of_a_missing_file_is_a_usage_error(tmp_path):
    with pytest.raises(xfemslip.UsageError, match="no such file"):
        xfemslip.read_result(tmp_path / "result.h5")


@pytest.mark.parametrize("spec", [None, {"name": "x"}, "cases/x.toml", 3])
def test_run_case_of_anything_but_a_case_spec_is_a_usage_error(spec, tmp_path):
    with pytest.raises(xfemslip.UsageError, match="run_case needs a CaseSpec"):
        xfemslip.run_case(spec, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_read_result_of_a_case_file_is_an_output_error():
    """api.md: read_result raises OutputError for a file that is not a
    result (a ResultError, which the command line reports with exit 2)."""
    path = CASES / "reservoir_depletion.toml"
    with pytest.raises(xfemslip.OutputError, match="not a readable result.h5") as info:
        xfemslip.read_result(path)
    assert isinstance(info.value, xfemslip.ResultError)
    assert str(info.value).startswith(f"{path}: ")
