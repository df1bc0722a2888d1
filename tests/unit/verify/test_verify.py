"""``xfemslip verify``: order, targets, table and CLI (the solves are in the
slow test at the end; the rest uses hand-made rows)."""

from __future__ import annotations

import csv
import math

import pytest
from click.testing import CliRunner

from xfemslip.cli import cli
from xfemslip.verify import problems as V
from xfemslip.verify import report as VO


def rows(errors, kii=0.001, problem="inclined-30"):
    return [
        V.Row(problem=problem, a_over_h=k, slip_error=e, kii_error=kii, dofs=100 * k)
        for k, e in errors.items()
    ]


def test_every_problem_is_of_its_kind():
    # a "slip" problem must have a driving shear (else its errors are 0/0), a
    # "stick" problem none; the window sweep spans both sides of both edges
    for p in V.PROBLEMS:
        assert (p.driving_shear() != 0.0) == (p.kind == "slip"), p.name
    assert set(V.QUICK_PROBLEMS) <= {p.name for p in V.PROBLEMS}
    (lo, hi), _ = V.window_edges()
    assert lo == pytest.approx(21.42, abs=0.01) and hi == pytest.approx(51.88, abs=0.01)


def test_observed_order_of_a_first_order_sequence():
    rs = rows({10: 0.04, 20: 0.02, 40: 0.01})
    V.observed_orders(rs)
    assert math.isnan(rs[0].order)
    assert rs[1].order == pytest.approx(1.0)
    assert rs[2].order == pytest.approx(1.0)
    assert V.order_between(rs, "inclined-30", 10, 40) == pytest.approx(1.0)


def test_targets_met_and_missed():
    good = rows({10: 0.016, 20: 0.008, 40: 0.004})
    assert V.check_targets(good, []) == []
    bad = rows({10: 0.02, 20: 0.015, 40: 0.012}, kii=0.03)
    fails = V.check_targets(bad, [])
    text = " | ".join(fails)
    assert "slip L2 error 1.50 % > 1 %" in text
    assert "K_II error 3.00 % > 2 %" in text
    assert "observed order 0.37 between a/10 and a/40" in text
    # without a/40 (--quick) the order target is not checked
    quick = rows({10: 0.02, 20: 0.015})
    assert not any("order" in f for f in V.check_targets(quick, []))


def test_window_misclassification_counts_only_beyond_two_degrees():
    near = V.WindowPoint(
        beta=20.9, psi=0, slips_exact=False, slip_share=0.9, distance=0.5
    )
    far = V.WindowPoint(
        beta=18.0, psi=0, slips_exact=False, slip_share=0.9, distance=3.4
    )
    right = V.WindowPoint(
        beta=30.0, psi=0, slips_exact=True, slip_share=1.0, distance=8.6
    )
    assert near.misclassified and far.misclassified and not right.misclassified
    fails = V.check_targets([], [near, far, right])
    assert len(fails) == 1 and "beta = 18.00" in fails[0]


def test_stuck_crack_with_slipping_points_is_a_failure():
    r = V.Row(problem="stick-80", a_over_h=10, slip_error=0.01, kii_error=0.01)
    r.extra["slipping_points"] = 3
    assert "3 point(s) slip" in V.check_targets([r], [])[0]


def test_table_lists_every_row_and_the_verdict():
    rs = rows({10: 0.016, 20: 0.008})
    V.observed_orders(rs)
    report = V.Report(rows=rs, window=[], failures=[], tip=None)
    text = VO.format_table(report)
    assert "inclined-30" in text and "a/20" in text and "all targets met" in text
    report.failures = ["x: y"]
    assert "targets missed:\n  - x: y" in VO.format_table(report)


def test_plot_name_must_be_png_or_pdf(tmp_path):
    res = CliRunner().invoke(
        cli, ["verify", "--quick", "--plot", str(tmp_path / "p.txt")]
    )
    assert res.exit_code == 2
    assert "expected a .png or .pdf" in res.output
    assert not (tmp_path / "p.txt").exists()


def test_unknown_tip_is_refused():
    res = CliRunner().invoke(cli, ["verify", "--quick", "--tip", "sharp"])
    assert res.exit_code == 2
    assert "--tip sharp: expected one of branch, ramp" in res.output


def test_bad_penalty_is_refused():
    res = CliRunner().invoke(cli, ["verify", "--quick", "--penalty", "-3"])
    assert res.exit_code == 2
    assert "expected a positive number (kn h / E) or auto" in res.output


def test_auto_penalty_leaves_kn_kt_out():
    text = V.case_text(40, V.PROBLEMS[0], None, None)
    assert "kn =" not in text and "kt =" not in text
    text = V.case_text(40, V.PROBLEMS[0], "ramp", 100.0)
    # kn = 100 E / h with h = 2 m / 40
    assert f"kn = {100.0 * V.E / 0.05!r}" in text and 'tip = "ramp"' in text


@pytest.mark.slow
def test_verify_quick_end_to_end(tmp_path):
    png, table = tmp_path / "v.png", tmp_path / "v.csv"
    res = CliRunner().invoke(
        cli, ["verify", "--quick", "--plot", str(png), "--csv", str(table)]
    )
    met = "all targets met" in res.output
    assert res.exit_code == (0 if met else 1), res.output
    assert met or "targets missed:" in res.output
    with open(table) as fh:
        data = list(csv.DictReader(fh))
    assert {d["problem"] for d in data} == set(V.QUICK_PROBLEMS)
    assert len(data) == len(V.QUICK_PROBLEMS) * len(V.QUICK_MESHES)
    # the frictional crack at a/20: the slip target holds with today's numerics
    a20 = next(
        d for d in data if d["problem"] == "inclined-30" and d["a_over_h"] == "20"
    )
    assert float(a20["slip_error"]) <= V.SLIP_TARGET
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
