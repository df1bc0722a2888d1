"""``xfemslip sweep --scheduler ADDRESS`` against a real dask.distributed
LocalCluster (2 worker processes), and the message when Dask is missing."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import pytest

from tests.support.casegen import SWEEP_BASE as BASE
from xfemslip.cli import cli

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture
def sweep_file(tmp_path: Path) -> Path:
    (tmp_path / "base.toml").write_text(BASE)
    path = tmp_path / "angles.toml"
    path.write_text(
        'base = "base.toml"\n[vary]\n"fractures[0].angle" = [0.0, 45.0, 90.0]\n'
    )
    return path


@pytest.mark.slow  # a scheduler and two worker processes: ~12 s
def test_sweep_on_a_local_dask_cluster(sweep_file, tmp_path, runner, monkeypatch):
    from distributed import LocalCluster

    # the worker processes import xfemslip from this tree
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    out = tmp_path / "out"
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        args = ["sweep", str(sweep_file), "-o", str(out)]
        result = runner.invoke(cli, [*args, "--scheduler", cluster.scheduler_address])
        assert result.exit_code == 0, result.stderr
        # the same command again skips every case
        again = runner.invoke(cli, [*args, "--scheduler", cluster.scheduler_address])
        assert again.exit_code == 0, again.stderr
    with open(out / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["fractures[0].angle"] for r in rows] == ["0", "45", "90"]
    assert [r["status"] for r in rows] == ["skipped"] * 3
    # the slip window of f = 0.1 under (-20, -40) MPa: 45 slips, 0 and 90 stick
    assert [float(r["slip_share"]) for r in rows] == [0.0, 1.0, 0.0]
    assert all(r["converged"] == "true" for r in rows)
    for r in rows:
        assert (out / r["case"] / "result.h5").is_file()


def test_missing_dask_is_a_usage_error(sweep_file, tmp_path, runner, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails
    out = tmp_path / "out"
    result = runner.invoke(
        cli, ["sweep", str(sweep_file), "-o", str(out), "--scheduler", "tcp://x:1"]
    )
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "Error: --scheduler needs dask.distributed: pip install 'xfemslip[dask]'"
    ]
    assert not out.exists()
