"""Sweep files (xfemslip.studies.sweep): key paths, ranges, product/zip, validation of
every generated case, one-line errors; running (xfemslip.studies.run): summary,
skip on rerun, a failed case kept apart, slipping length."""

from __future__ import annotations

import csv
import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

import xfemslip
from tests.support.casegen import SWEEP_BASE as BASE
from tests.support.casegen import SWEEP_CASE as CASE
from xfemslip.case import build
from xfemslip.case.tables import Table
from xfemslip.cli import cli
from xfemslip.errors import CaseError
from xfemslip.post.metrics import METRICS, arc_extent, slipping_length
from xfemslip.studies.run import run_sweep
from xfemslip.studies.sweep import (
    case_id,
    expand_range,
    load_sweep,
    loads_sweep,
    parse_key_path,
    set_key_path,
)
from xfemslip.studies.uncertainty import is_uncertainty_file
from xfemslip.studies.vary import _check_overlaps, case_count, read_vary


@pytest.fixture
def base(tmp_path: Path) -> Path:
    path = tmp_path / "base.toml"
    path.write_text(BASE)
    return path


def _sweep(tmp_path: Path, body: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(body)
    return path


def _problems(excinfo) -> str:
    return str(excinfo.value)


# --------------------------------------------------------------------------- #
# Key paths and ranges
# --------------------------------------------------------------------------- #


def test_parse_key_path():
    assert parse_key_path("fractures[0].angle") == ["fractures", 0, "angle"]
    assert parse_key_path("loading.stress.xx") == ["loading", "stress", "xx"]
    assert parse_key_path("fractures[1].points[0][1]") == [
        "fractures",
        1,
        "points",
        0,
        1,
    ]
    for bad in ("", "a..b", "fractures[x].angle", "[0]", "a.b[", "a b"):
        assert parse_key_path(bad) is None, bad


def test_set_key_path_creates_tables_but_not_array_items():
    doc = {"fractures": [{"angle": 1.0}]}
    assert set_key_path(doc, ["fractures", 0, "angle"], 27.0) is None
    assert doc["fractures"][0]["angle"] == 27.0
    assert set_key_path(doc, ["solver", "tolerance"], 1e-6) is None
    assert doc["solver"] == {"tolerance": 1e-6}
    message = set_key_path(doc, ["fractures", 3, "angle"], 0.0)
    assert "fractures has 1 item(s)" in message and "index 3" in message
    assert "not an array" in set_key_path(doc, ["solver", 0], 1)


def test_range_step_includes_stop_on_the_grid():
    problems = []
    assert expand_range({"start": 0, "stop": 90, "step": 22.5}, "k", problems) == [
        0.0,
        22.5,
        45.0,
        67.5,
        90.0,
    ]
    # 0.1 * 3 is 0.30000000000000004 > 0.3: still on the grid within 1e-9 step
    values = expand_range({"start": 0.0, "stop": 0.3, "step": 0.1}, "k", problems)
    assert len(values) == 4 and math.isclose(values[-1], 0.3)
    # off the grid: stop is not reached
    assert expand_range({"start": 0, "stop": 10, "step": 4}, "k", problems) == [
        0,
        4,
        8,
    ]
    assert expand_range({"start": 1, "stop": -1, "step": -1}, "k", problems) == [
        1,
        0,
        -1,
    ]
    assert problems == []


def test_range_num_is_linspace():
    problems = []
    values = expand_range({"start": 5e9, "stop": 80e9, "num": 4}, "k", problems)
    np.testing.assert_allclose(values, np.linspace(5e9, 80e9, 4), rtol=0, atol=0)
    assert expand_range({"start": 2.0, "stop": 9.0, "num": 1}, "k", problems) == [2.0]
    assert problems == []


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"start": 0, "stop": 1}, "exactly one of step or num"),
        ({"start": 0, "stop": 1, "step": 1, "num": 2}, "exactly one of step or num"),
        ({"start": 0, "stop": 1, "step": 0}, "must be non-zero"),
        ({"start": 0, "stop": 1, "step": -0.5}, "lead from start"),
        ({"start": 0, "stop": 1, "num": 0}, "integer >= 1"),
        ({"start": 0, "stop": 1, "num": 2.5}, "integer >= 1"),
        ({"start": "a", "stop": 1, "num": 2}, "expected a number"),
        ({"start": 0, "stop": 1, "stp": 1}, "unknown range key 'stp'"),
        ({"start": 0, "stop": 1e9, "step": 1}, "more than"),
    ],
)
def test_range_errors(spec, message):
    problems = []
    assert expand_range(spec, 'vary."x"', problems) is None
    assert len(problems) == 1 and message in problems[0][1], problems


def test_case_id_names_the_parameters():
    assert case_id(2, 5, [("fractures[0].angle", 45.0)]) == "002_angle=45"
    assert case_id(0, 3, [("material.E", 5e9)]) == "000_E=5e9"
    assert (
        case_id(11, 1200, [("material.E", 2e10), ("fractures[0].friction", 0.3)])
        == "0011_E=2e10_friction=0.3"
    )


# --------------------------------------------------------------------------- #
# Sweep files
# --------------------------------------------------------------------------- #


def test_product_and_zip(tmp_path, base):
    body = 'base = "base.toml"\n{combine}\n[vary]\n"material.E" = [5e9, 20e9]\n'
    body += '"fractures[0].friction" = [0.1, 0.3]\n'
    product = loads_sweep(body.format(combine=""), tmp_path / "p.toml")
    assert [c.params for c in product.cases] == [
        (("material.E", 5e9), ("fractures[0].friction", 0.1)),
        (("material.E", 5e9), ("fractures[0].friction", 0.3)),
        (("material.E", 20e9), ("fractures[0].friction", 0.1)),
        (("material.E", 20e9), ("fractures[0].friction", 0.3)),
    ]
    zipped = loads_sweep(body.format(combine='combine = "zip"'), tmp_path / "z.toml")
    assert [c.params for c in zipped.cases] == [
        (("material.E", 5e9), ("fractures[0].friction", 0.1)),
        (("material.E", 20e9), ("fractures[0].friction", 0.3)),
    ]
    # every case went through the case loader: the spec holds the varied values
    last = zipped.cases[-1].spec
    assert last.material.E == 20e9 and last.fractures[0].friction == 0.3
    assert product.directory == Path("out/sweeps/p")


def test_values_and_ranges_with_units(tmp_path, base):
    """Values and range ends written with units vary the key in its SI unit:
    the same specs as the numbers; a unit the key refuses names the range end."""
    body = 'base = "base.toml"\n[vary]\n"material.E" = ["5 GPa", "20 GPa"]\n'
    body += '"fractures[0].angle" = { start = "30 deg", stop = "60 deg", num = 2 }\n'
    sweep = loads_sweep(body, tmp_path / "u.toml")
    assert [c.params for c in sweep.cases] == [
        (("material.E", 5e9), ("fractures[0].angle", 30.0)),
        (("material.E", 5e9), ("fractures[0].angle", 60.0)),
        (("material.E", 20e9), ("fractures[0].angle", 30.0)),
        (("material.E", 20e9), ("fractures[0].angle", 60.0)),
    ]
    assert sweep.cases[-1].spec.material.E == 20e9
    assert sweep.cases[0].case_id == "000_E=5e9_angle=30"
    bad = body.replace('stop = "60 deg"', 'stop = "60 MPa"')
    with pytest.raises(CaseError) as err:
        loads_sweep(bad, tmp_path / "bad.toml")
    assert 'vary."fractures[0].angle".stop: expected an angle' in str(err.value)


def test_unquoted_dotted_keys_and_inline_base(tmp_path):
    inline = build.case_text({"base": build.with_keys(CASE, name=None)})
    body = "[vary]\nmaterial.E = { start = 1e9, stop = 3e9, num = 3 }\n" + inline
    sweep = loads_sweep(body, tmp_path / "inline.toml")
    assert sweep.keys == ("material.E",)
    assert [c.spec.material.E for c in sweep.cases] == [1e9, 2e9, 3e9]
    assert sweep.cases[0].spec.name == "inline-000_E=1e9"


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (
            'base = "base.toml"\ncombne = "zip"\n[vary]\n"material.E" = [1e9]\n',
            "unknown key 'combne'; did you mean 'combine'?",
        ),
        ('base = "base.toml"\n', "vary: required key missing"),
        ('base = "base.toml"\n[vary]\n', "expected at least one key path"),
        ('[vary]\n"material.E" = [1e9]\n', "base: required key missing"),
        (
            'base = "nope.toml"\n[vary]\n"material.E" = [1e9]\n',
            "base: cannot read the base case",
        ),
        (
            'base = "base.toml"\n[vary]\n"material.E" = []\n',
            'vary."material.E": expected a non-empty array',
        ),
        (
            'base = "base.toml"\n[vary]\n"material.E" = 5e9\n',
            'vary."material.E": expected a non-empty array',
        ),
        (
            'base = "base.toml"\n[vary]\n"fractures[x].angle" = [1.0]\n',
            "not a key path",
        ),
        (
            'base = "base.toml"\ncombine = "zip"\n[vary]\n"material.E" = [1e9, 2e9]\n'
            '"material.nu" = [0.2]\n',
            'combine: "zip" needs equal lengths',
        ),
        (
            'base = "base.toml"\ncombine = "cartesian"\n[vary]\n"material.E" = [1e9]\n',
            'combine: must be one of "product", "zip"',
        ),
        (
            'base = "base.toml"\n[vary]\n"fractures[0]" = [{}]\n'
            '"fractures[0].angle" = [1.0]\n',
            'vary."fractures[0].angle": overlaps vary."fractures[0]"',
        ),
        (
            'base = "base.toml"\n[vary]\n"fractures[2].angle" = [1.0]\n',
            "fractures has 1 item(s) in the base case, so index 2 does not exist",
        ),
    ],
)
def test_sweep_file_errors(tmp_path, base, body, expected):
    with pytest.raises(CaseError) as excinfo:
        loads_sweep(body, tmp_path / "bad.toml")
    text = _problems(excinfo)
    assert text.startswith(str(tmp_path / "bad.toml") + ": ")
    assert expected in text
    assert "\n" not in text


def test_invalid_generated_cases_are_named_with_their_parameters(tmp_path, base):
    body = 'base = "base.toml"\n[vary]\n"fractures[0].friction" = [0.1, -0.2]\n'
    body += '"fractures[0].angel" = [3.0]\n'
    with pytest.raises(CaseError) as excinfo:
        loads_sweep(body, tmp_path / "bad.toml")
    text = _problems(excinfo)
    # both generated cases are invalid (typo); the second also for the friction
    assert "2 problems" in text
    assert "case 000_friction=0.1_angel=3 (fractures[0].friction = 0.1" in text
    assert "unknown key 'angel' in [fractures[0]]; did you mean 'angle'?" in text
    assert "fractures[0].friction: must be >= 0, got -0.2" in text


def test_a_case_whose_geometry_cannot_be_built_is_refused_alone(tmp_path):
    # keys all valid, but the second case puts the two fractures on each other
    fracture = CASE["fractures"][0]
    # a second fracture parallel to the first
    two = [dict(fracture, center=[0.5, 0.3]), dict(fracture, center=[0.5, 0.7])]
    (tmp_path / "base.toml").write_text(build.case_text(dict(CASE, fractures=two)))
    body = (
        'base = "base.toml"\n[vary]\n"fractures[1].center" = [[0.5, 0.7], [0.5, 0.3]]\n'
    )
    sweep = loads_sweep(body, tmp_path / "s.toml")
    ok, refused = sweep.cases
    assert ok.refused == "" and len(ok.spec.fractures) == 2
    assert refused.spec is None
    assert refused.label == "case 001_center=0.5_0.3 (fractures[1].center = [0.5, 0.3])"
    assert refused.refused.startswith("fractures[0] and fractures[1] overlap")
    # the same problem in every case: nothing to run, the sweep is refused
    body = 'base = "base.toml"\n[vary]\n"fractures[1].center" = [[0.5, 0.3]]\n'
    with pytest.raises(CaseError) as excinfo:
        loads_sweep(body, tmp_path / "bad.toml")
    assert "case 000_center=0.5_0.3 (fractures[1].center = [0.5, 0.3]): " in (
        _problems(excinfo)
    )


def test_cli_bad_sweep_is_exit_2_one_line_and_writes_nothing(tmp_path, base, runner):
    path = _sweep(tmp_path, 'base = "base.toml"\n[vary]\n"material.E" = [-1.0]\n')
    out = tmp_path / "out"
    result = runner.invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ")
    assert "material.E: must be > 0, got -1.0" in lines[0]
    assert not out.exists()
    missing = runner.invoke(cli, ["sweep", str(tmp_path / "none.toml")])
    assert missing.exit_code == 2 and "no such file" in missing.stderr


def test_paper_sweep_files_are_valid():
    root = Path(__file__).resolve().parents[3] / "cases" / "sweeps"
    found = {
        p.stem: load_sweep(p)
        for p in sorted(root.glob("*.toml"))
        if not is_uncertainty_file(p)  # tests/unit/studies/test_uncertainty.py
    }
    assert set(found) == {
        "young_modulus",
        "fracture_angle",
        "friction",
        "dfn_realizations",
    }
    realizations = found["dfn_realizations"].cases  # docs/networks.md, random networks
    assert [dict(c.params)["network.generate.seed"] for c in realizations] == list(
        range(1, 21)
    )
    assert {len(c.spec.fractures) for c in realizations} == {30}
    assert [c.spec.material.E for c in found["young_modulus"].cases] == [
        5e9,
        20e9,
        80e9,
    ]
    angles = [
        math.degrees(math.atan2(*np.diff(c.spec.fractures[0].points, axis=0)[0][::-1]))
        for c in found["fracture_angle"].cases
    ]
    np.testing.assert_allclose(angles, [0, 27, 45, 63, 90], atol=1e-12)
    assert [c.spec.fractures[0].friction for c in found["friction"].cases] == [
        0.1,
        0.3,
        0.6,
    ]


# --------------------------------------------------------------------------- #
# Metrics
# --------------------------------------------------------------------------- #


def test_slipping_length_voronoi():
    s = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    # cells [0, 0.2], [0.2, 0.4], [0.4, 0.6], [0.6, 0.8], [0.8, 1.0]
    assert slipping_length(s, np.full(5, 2), 0.0, 1.0) == pytest.approx(1.0)
    assert slipping_length(s, np.array([1, 2, 2, 1, 0]), 0.0, 1.0) == pytest.approx(0.4)
    assert slipping_length(s, np.array([2, 1, 1, 1, 2]), 0.0, 1.0) == pytest.approx(0.4)
    assert slipping_length(s, np.zeros(5), 0.0, 1.0) == 0.0


def test_arc_extent_clips_to_the_box():
    box = (0.0, 1.0, 0.0, 1.0)
    assert arc_extent([[0.2, 0.5], [0.8, 0.5]], box) == pytest.approx((0.0, 0.6))
    # starts 0.5 m outside the left edge, kinks inside, ends inside
    lo, hi = arc_extent([[-0.5, 0.5], [0.5, 0.5], [0.5, 0.8]], box)
    assert (lo, hi) == pytest.approx((0.5, 1.3))


# --------------------------------------------------------------------------- #
# Running
# --------------------------------------------------------------------------- #


def _read_summary(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_run_sweep_summary_skip_and_failure(tmp_path, base):
    # max_iterations = 1 cannot converge a slipping fracture with the secant
    # tangent (linear convergence; the stick/slip predictor, which converges
    # the consistent tangent in 1 iteration here, is not used with it): that
    # case fails, the other runs.
    path = _sweep(
        tmp_path,
        'base = "base.toml"\ncombine = "zip"\n[vary]\n'
        '"solver.max_iterations" = [1, 30]\n'
        '"solver.tangent" = ["secant", "consistent"]\n',
    )
    sweep = load_sweep(path)
    out = tmp_path / "out"
    seen = []
    rows = run_sweep(sweep, out, jobs=1, progress=seen.append)
    assert [r.status for r in rows] == ["failed", "ok"]
    assert len(seen) == 2
    assert "did not converge" in rows[0].error.lower() or "step 1" in rows[0].error
    ok = rows[1].metrics
    with h5py.File(out / rows[1].case_id / "result.h5") as f:
        slid = f["fractures/0/plastic_slip"][()]  # max slip: what slid
        state = f["fractures/0/state"][()]
        iterations = int(f.attrs["newton_iterations"])
    assert ok["max_abs_slip_m"] == pytest.approx(np.abs(slid).max(), rel=1e-12)
    assert ok["slip_share"] == pytest.approx(np.mean(state == 2))
    assert ok["newton_iterations"] == iterations and ok["converged"] is True
    # every point slips here: the slipping length is the fracture's, 0.6 m
    assert np.all(state == 2) and ok["slip_length_m"] == pytest.approx(0.6)
    summary = _read_summary(out / "summary.csv")
    assert [r["status"] for r in summary] == ["failed", "ok"]
    assert summary[1]["solver.max_iterations"] == "30"
    assert float(summary[1]["max_abs_slip_m"]) == pytest.approx(
        ok["max_abs_slip_m"], rel=1e-5
    )
    assert summary[0]["converged"] == "false" and summary[0]["error"]
    assert (out / rows[0].case_id / "case.toml").is_file()

    # rerun: the converged case is skipped, the failed one runs again
    mtime = (out / rows[1].case_id / "result.h5").stat().st_mtime_ns
    again = run_sweep(sweep, out, jobs=1)
    assert [r.status for r in again] == ["failed", "skipped"]
    assert (out / rows[1].case_id / "result.h5").stat().st_mtime_ns == mtime
    assert again[1].metrics == ok


def test_summary_adds_event_and_permeability_columns_after_the_metrics(tmp_path, base):
    """summary.csv keeps every earlier column, in order, and adds the event
    size of each fracture (from the member's /events, checked here against
    its arrays: Mw = 2/3 (log10(mu int |d| ds W) - 9.1) with d the plastic
    slip, the slipping length
    and W = events.extent) and, with [permeability], the ratios."""
    text = base.read_text() + (
        "[events]\nextent = 100.0\n[permeability]\naperture = 1.0e-4\n"
        "dilation_angle = 5.0\n"
    )
    base.write_text(text)
    path = _sweep(tmp_path, 'base = "base.toml"\n[vary]\n"material.E" = [5e9]\n')
    out = tmp_path / "out"
    (row,) = run_sweep(load_sweep(path), out)
    with open(out / "summary.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert header[: 2 + len(METRICS)] == ["case", "material.E", *METRICS]
    assert header[-2:] == ["status", "error"]
    (line,) = _read_summary(out / "summary.csv")
    result = xfemslip.read_result(out / row.case_id)
    ff = result.fractures[0]
    mu = 5e9 / (2 * (1 + CASE["material"]["nu"]))
    mid = 0.5 * (ff.s[1:] + ff.s[:-1])
    length = CASE["fractures"][0]["length"]  # inside the domain
    stretch = np.diff(np.concatenate([[0.0], mid, [length]]))
    m0 = mu * float(np.sum(stretch * np.abs(ff.plastic_slip)))  # what slid
    mw = 2.0 / 3.0 * (math.log10(m0 * 100.0) - 9.1)
    assert float(line["fracture0_moment_per_length_Nm_per_m"]) == pytest.approx(
        m0, rel=1e-5
    )
    assert float(line["fracture0_Mw"]) == pytest.approx(mw, abs=1e-5)
    assert float(line["max_Mw"]) == pytest.approx(mw, abs=1e-5)
    assert line["Mw_extent"] == "100 m" and line["fracture0_slipped"] == "true"
    assert float(line["fracture0_max_slip_m"]) == pytest.approx(
        float(line["max_abs_slip_m"]), rel=1e-12
    )
    # one fracture along the block's diagonal direction: both ratios the
    # same, that of the mean a^3 along it over a0^3
    rx, ry = float(line["k_xx_ratio"]), float(line["k_yy_ratio"])
    mean = float(np.sum(stretch * ff.aperture**3) / np.sum(stretch)) / 1.0e-12
    assert rx > 1.0 and rx == pytest.approx(mean, rel=1e-5)
    assert ry == pytest.approx(rx, rel=1e-5)


def test_rerun_after_editing_the_base_runs_again(tmp_path, base):
    path = _sweep(tmp_path, 'base = "base.toml"\n[vary]\n"material.E" = [5e9]\n')
    out = tmp_path / "out"
    assert run_sweep(load_sweep(path), out)[0].status == "ok"
    base.write_text(build.case_text(build.with_keys(CASE, **{"material.nu": 0.25})))
    rows = run_sweep(load_sweep(path), out)
    assert rows[0].status == "ok"  # same id, different case text: not skipped
    assert run_sweep(load_sweep(path), out, force=True)[0].status == "ok"


@pytest.mark.slow  # two spawned interpreters load numba: ~7 s
def test_cli_sweep_two_processes(tmp_path, base, runner, monkeypatch):
    # spawned workers import xfemslip from the same tree as this process
    monkeypatch.setenv("PYTHONPATH", str(Path(__file__).resolve().parents[3]))
    path = _sweep(
        tmp_path, 'base = "base.toml"\n[vary]\n"fractures[0].angle" = [0.0, 45.0]\n'
    )
    out = tmp_path / "out"
    result = runner.invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "2"])
    assert result.exit_code == 0, result.stderr
    summary = _read_summary(out / "summary.csv")
    assert [r["status"] for r in summary] == ["ok", "ok"]
    assert float(summary[0]["slip_share"]) == 0.0
    assert float(summary[1]["slip_share"]) == 1.0
    # the printed table lists the parameters and the metrics
    assert "fractures[0].angle" in result.stdout and "max_abs_slip_m" in result.stdout


# --------------------------------------------------------------------------- #
# Sizes counted before anything is expanded
# --------------------------------------------------------------------------- #


def test_a_product_of_1e12_cases_is_refused_from_the_list_lengths(tmp_path, base):
    """Six ranges of 100 values: 100**6 = 1e12 cases, refused without building
    one (itertools.product into a list would need terabytes)."""
    keys = ["friction", "cohesion", "kn", "kt", "angle", "length"]
    body = 'base = "base.toml"\n[vary]\n' + "".join(
        f'"fractures[0].{k}" = {{ start = 1.0, stop = 100.0, num = 100 }}\n'
        for k in keys
    )
    with pytest.raises(CaseError) as excinfo:
        loads_sweep(body, tmp_path / "big.toml")
    assert excinfo.value.problems == [
        (
            "vary",
            "gives 1000000000000 cases (100 (fractures[0].friction) x 100 "
            "(fractures[0].cohesion) x 100 (fractures[0].kn) x 100 (fractures[0].kt) "
            "x 100 (fractures[0].angle) x 100 (fractures[0].length)), more than 10000",
        )
    ]


@pytest.mark.parametrize(
    ("values", "count"),
    [([[1, 2, 3], [4, 5]], 6), ([list(range(100))] * 2, 10_000), ([[1]] * 50, 1)],
)
def test_case_count_is_the_product_of_the_lengths(values, count):
    vary = [(f"k{i}", v) for i, v in enumerate(values)]
    assert case_count(vary, "product") == count
    assert case_count(vary[:1], "zip") == len(values[0])


@pytest.mark.parametrize(
    ("range_", "key", "message"),
    [
        (
            "{ start = 0.0, stop = 1.0, step = 1e-300 }",
            'vary."material.nu"',
            "gives 1e+300 values, more than 10000",
        ),
        (
            "{ start = 0.0, stop = 1.0, step = 5e-324 }",  # 1 / step overflows
            'vary."material.nu"',
            "gives inf values, more than 10000",
        ),
        (
            "{ start = -1e308, stop = 1e308, step = 1e307 }",
            'vary."material.nu"',
            "stop - start = 1e+308 - -1e+308 overflows the float range",
        ),
        (
            "{ start = -1e308, stop = 1e308, num = 3 }",
            'vary."material.nu"',
            "stop - start = 1e+308 - -1e+308 overflows the float range",
        ),
        (
            "{ start = 0, stop = 1" + "0" * 400 + ", step = 1 }",
            'vary."material.nu".stop',
            "must be finite, got integer 1" + "0" * 400,
        ),
        (
            "{ start = 0, stop = 100000, step = 3 }",  # 33334 values, exactly
            'vary."material.nu"',
            "gives 33334 values, more than 10000",
        ),
    ],
)
def test_ranges_whose_size_overflows_are_refused_at_their_key(range_, key, message):
    problems = []
    document = tomllib.loads(f'[vary]\n"material.nu" = {range_}\n')
    read_vary(Table(document, "", problems), "product")
    assert len(problems) == 1
    assert problems[0][0] == key
    assert problems[0][1].startswith(message[:60]), problems[0][1]


def test_overlap_check_is_linear_and_finds_repeated_keys(tmp_path, base):
    """20,000 distinct keys: a pairwise check would make 2e8 comparisons."""
    vary = [(f"material.k{i}", [1]) for i in range(20_000)]
    vary += [("material.k7.x", [1]), ("material.k3", [2])]
    problems = []
    _check_overlaps(vary, problems)
    assert sorted(problems) == [
        ('vary."material.k3"', 'overlaps vary."material.k3"'),
        ('vary."material.k7.x"', 'overlaps vary."material.k7"'),
    ]


def test_case_ids_and_names_stay_folder_names(tmp_path, base):
    """26 varied keys would make a 300-character folder name: the id is cut
    after the index, and the member's name stays under 255 bytes."""
    params = [(f"solver.key{i}", 1.5) for i in range(26)]
    cid = case_id(7, 10, params)
    assert len(cid) == 100 and cid.startswith("007_key0=1.5_key1=1.5")
    long_name = "\u00e9" * 200  # 400 bytes
    base.write_text(build.case_text(dict(CASE, name=long_name)))
    body = 'base = "base.toml"\n[vary]\n"fractures[0].friction" = [0.1, 0.2]\n'
    spec = loads_sweep(body, tmp_path / "s.toml")
    for case in spec.cases:
        assert len(case.spec.name.encode()) <= 255
        assert case.spec.name.endswith(case.case_id)


def test_a_sweep_of_too_much_case_text_is_refused(tmp_path, base):
    """A base of 6,001 fractures (~0.8 MB of TOML) times 10,000 cases."""
    many = dict(CASE, fractures=CASE["fractures"] * 6001)
    base.write_text(build.case_text(many))
    body = (
        'base = "base.toml"\n[vary]\n'
        '"material.nu" = { start = 0.0, stop = 0.4, num = 10000 }\n'
    )
    with pytest.raises(CaseError) as excinfo:
        loads_sweep(body, tmp_path / "s.toml")
    ((key, message),) = excinfo.value.problems
    assert key == "vary"
    assert message.startswith("gives 10000 cases of a ")
    assert "more than the limit of 0.256 GB" in message


def test_cli_sweep_in_a_pipe_reports_each_case(tmp_path, base, runner):
    """Outside a terminal (CliRunner's streams, like a pipe or CI), each
    finished case is one line on stderr, numbered, with its id, status and
    elapsed time."""
    path = _sweep(
        tmp_path,
        'base = "base.toml"\n[vary]\n"material.E" = [5e9, 6e9]\n',
    )
    out = tmp_path / "out"
    result = runner.invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert result.exit_code == 0, result.stderr
    lines = [ln for ln in result.stderr.splitlines() if ln.startswith("[")]
    assert [ln.split(" ", 1)[0] for ln in lines] == ["[1/2]", "[2/2]"]
    ids = {r.case_id for r in run_sweep(load_sweep(path), out)}  # skipped: done
    assert {ln.split(" ")[1].rstrip(":") for ln in lines} == ids
    assert all(": ok (" in ln and ln.endswith(" s)") for ln in lines)
