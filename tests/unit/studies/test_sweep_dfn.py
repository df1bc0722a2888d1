"""A sweep over 3 realizations of a random network, end to end: the summary's
per-fracture columns and dfn_summary.csv against the result.h5 files."""

from __future__ import annotations

import copy
import csv

import numpy as np
import pytest
from click.testing import CliRunner

import xfemslip
from xfemslip.case import build, loads_case
from xfemslip.cli import cli

# Reservoir stress state, friction 0.3: fractures near 45-60 degrees from
# sigma_1 (vertical) slip, the others stick.  "allow" + "reject": seed 4
# has two crossings (X), seed 6 a fracture ending on another (T).
DFN3 = {
    "name": "dfn3",
    "vary": {"network.generate.seed": {"start": 4, "stop": 6, "step": 1}},
    "base": {
        "domain": {"size": [1.0, 1.0]},
        "mesh": {"elements": [20, 20]},
        "material": {"E": 5.0e9, "nu": 0.3},
        "network": {
            "friction": 0.3,
            "tip": "ramp",
            "generate": {
                "seed": 1,
                "count": 6,
                "intersections": "allow",
                "outside": "reject",
                "orientation": {"distribution": "uniform"},
                "length": {
                    "distribution": "power_law",
                    "exponent": 2.0,
                    "min": 0.25,
                    "max": 0.45,
                },
            },
        },
        "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0}},
        "boundary": {
            "bottom": {"uy": 0.0},
            "top": "traction",
            "left": "traction",
            "right": "traction",
        },
    },
}
SWEEP = build.case_text(DFN3)
OLD_COLUMNS = [
    "case",
    "network.generate.seed",
    "converged",
    "max_abs_slip_m",
    "slip_length_m",
    "slip_share",
    "newton_iterations",
    "wall_time_s",
]


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _fracture_reference(fracture, length, ends):
    """(slips?, max |slip|, trapezoid-weighted mean |slip|) of one fracture,
    the slip that slid (its plastic slip).

    Independent of sweep_run: weights from the gaps between the points, each
    split half and half, the end points reaching the fracture's ends as
    built, which result.h5 stores: s = 0 and s = length (the fracture lies
    wholly in the domain with outside = "reject"), or beyond: an end that
    stops short of another fracture is extended onto it (a T, by less than
    h / 2), so its points may reach s < 0 or s > length."""
    s, slip, state = fracture.s, fracture.plastic_slip, fracture.state
    lo, hi = ends
    assert lo <= min(0.0, s[0]) + 1e-12 and hi >= max(length, s[-1]) - 1e-12
    assert hi - lo < length + 0.05  # h = 0.05: at most h / 2 at each end
    gaps = np.diff(np.concatenate([[lo], s, [hi]]))
    weight = 0.5 * (gaps[:-1] + gaps[1:])
    weight[0] += 0.5 * gaps[0]
    weight[-1] += 0.5 * gaps[-1]
    assert weight.sum() == pytest.approx(hi - lo)
    mean = float(np.sum(weight * np.abs(slip)) / (hi - lo))
    return bool(np.any(state == 2)), float(np.abs(slip).max()), mean


def test_three_realizations_end_to_end(tmp_path):
    path = tmp_path / "dfn3.toml"
    path.write_text(SWEEP)
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert result.exit_code == 0, result.output
    assert "over the realizations (dfn_summary.csv):" in result.output
    summary = _rows(out / "summary.csv")
    with open(out / "summary.csv") as fh:
        header = fh.readline().strip().split(",")
    assert header[: len(OLD_COLUMNS)] == OLD_COLUMNS  # existing columns kept
    assert header[-2:] == ["status", "error"]
    assert [r["network.generate.seed"] for r in summary] == ["4", "5", "6"]
    counts = []
    for row in summary:
        folder = out / row["case"]
        spec = loads_case((folder / "case.toml").read_text(), folder / "case.toml")
        assert row["status"] == "ok" and row["converged"] == "true"
        assert int(row["fractures"]) == len(spec.fractures) == 6
        read = xfemslip.read_result(folder / "result.h5")
        fractures = read.fractures
        assert len(fractures) == 6
        refs = [
            _fracture_reference(
                fractures[i],
                float(np.hypot(*np.diff(spec.fractures[i].points, axis=0).T).sum()),
                read.fracture_properties[i].ends,
            )
            for i in range(6)
        ]
        slipping = [r for r in refs if r[0]]
        counts.append(len(slipping))
        assert int(row["slipping_fractures"]) == len(slipping)
        assert float(row["slipping_fraction"]) == pytest.approx(
            len(slipping) / 6, rel=1e-5
        )
        assert float(row["max_abs_slip_m"]) == pytest.approx(
            max(r[1] for r in refs), rel=1e-5
        )
        expected = np.mean([r[2] for r in slipping]) if slipping else 0.0
        assert float(row["mean_slip_m"]) == pytest.approx(expected, rel=1e-5)
    # the realizations differ, and some but not all fractures slip
    assert 0 < sum(counts) < 18 and len(set(counts)) > 1
    aggregate = {r["metric"]: r for r in _rows(out / "dfn_summary.csv")}
    slip = aggregate["slipping_fractures"]
    assert int(slip["realizations"]) == 3 and slip["failed"] == "0"
    assert float(slip["mean"]) == pytest.approx(np.mean(counts), rel=1e-5)
    assert float(slip["std"]) == pytest.approx(np.std(counts, ddof=1), rel=1e-5)
    assert float(slip["min"]) == min(counts) and float(slip["max"]) == max(counts)


def test_aggregate_leaves_failed_cases_out():
    from xfemslip.studies.dfn_summary import AGGREGATED, aggregate, is_dfn_sweep
    from xfemslip.studies.run import CaseRow

    rng = np.random.default_rng(2)
    rows = []
    for k in range(5):
        metrics = {m: float(rng.random()) for m in AGGREGATED}
        rows.append(
            CaseRow(f"{k:03d}", status="skipped" if k == 1 else "ok", metrics=metrics)
        )
    rows.append(CaseRow("005", status="failed", metrics={}, error="boom"))
    table = {r["metric"]: r for r in aggregate(rows)}
    for metric in AGGREGATED:
        values = [r.metrics[metric] for r in rows[:5]]
        row = table[metric]
        assert row["realizations"] == 5 and row["failed"] == 1
        assert row["mean"] == pytest.approx(np.mean(values), rel=1e-12)
        assert row["std"] == pytest.approx(np.std(values, ddof=1), rel=1e-12)
        assert (row["min"], row["median"], row["max"]) == (
            min(values),
            pytest.approx(np.median(values)),
            max(values),
        )
    assert is_dfn_sweep(["material.E", "network.generate.seed"])
    assert not is_dfn_sweep(["fractures[0].angle", "networkx"])


def test_a_realization_that_cannot_be_built_is_refused_and_the_others_run(tmp_path):
    """Seed 5 also moves the inline fracture out of the domain: that case is
    reported (one line on stderr, a 'refused' row) and not run, seeds 4 and
    6 run; exit code 1; dfn_summary.csv counts 2 realizations and 1 left out."""
    inline = [[0.05, 0.05], [0.15, 0.1]]
    outside = [[3.05, 0.05], [3.15, 0.1]]
    document = copy.deepcopy(DFN3)
    document["combine"] = "zip"
    document["vary"] = {
        "network.generate.seed": [4, 5, 6],
        "fractures[0].points": [inline, outside, inline],
    }
    document["base"]["fractures"] = [{"points": inline, "friction": 0.3, "tip": "ramp"}]
    body = build.case_text(document)
    path = tmp_path / "dfn3.toml"
    path.write_text(body)
    out = tmp_path / "out"
    try:  # click < 8.2 mixes stderr into stdout unless told otherwise
        runner = CliRunner(mix_stderr=False)
    except TypeError:
        runner = CliRunner()
    result = runner.invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert result.exit_code == 1, result.stderr
    refused = [line for line in result.stderr.splitlines() if "refused:" in line]
    assert len(refused) == 1
    assert refused[0].startswith("WARNING: case 001_seed=5_points=3.05_0.05_3.15_0.1 (")
    assert "fractures[0]: lies outside the domain [0, 1] x [0, 1]" in refused[0]
    assert "2 done, 0 of them skipped as already done, 0 failed, 1 refused" in (
        result.stderr
    )
    summary = _rows(out / "summary.csv")
    assert [(r["network.generate.seed"], r["status"]) for r in summary] == [
        ("4", "ok"),
        ("5", "refused"),
        ("6", "ok"),
    ]
    assert "lies outside the domain" in summary[1]["error"]
    assert summary[1]["converged"] == "" and summary[0]["converged"] == "true"
    for row in summary:
        folder = out / row["case"]
        assert (folder / "case.toml").is_file()  # for `xfemslip check`
        assert (folder / "result.h5").is_file() == (row["status"] == "ok")
    aggregate = {r["metric"]: r for r in _rows(out / "dfn_summary.csv")}
    assert aggregate["fractures"]["realizations"] == "2"
    assert aggregate["fractures"]["failed"] == "1"
    assert float(aggregate["fractures"]["mean"]) == 7.0  # 6 generated + 1
    # a rerun runs nothing again: the done cases are skipped, the refused one
    # is refused again
    again = runner.invoke(cli, ["sweep", str(path), "-o", str(out), "-j", "1"])
    assert again.exit_code == 1
    statuses = [r["status"] for r in _rows(out / "summary.csv")]
    assert statuses == ["skipped", "refused", "skipped"]
