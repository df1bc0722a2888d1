"""The same case gives bitwise-identical result.h5 datasets: on repeated runs
and with NUMBA_NUM_THREADS = 1 and 2 (separate processes).

Every dataset is compared bitwise, and every attribute except the wall time
(``wall_time_s``, the only attribute that holds a time).  result.vtu and
fractures.vtu are compared byte for byte as well.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np

from xfemslip.case import build

ROOT = Path(__file__).resolve().parents[2]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"
TIMED_ATTRS = {"wall_time_s"}


def _run(case: Path, out: Path, threads: int) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_NUM_THREADS=str(threads))
    proc = subprocess.run(
        [sys.executable, "-m", "xfemslip", "run", "-q", str(case), "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]


def _contents(path: Path) -> dict:
    out = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
            for key, value in obj.attrs.items():
                out[f"{name}@{key}"] = value

        f.visititems(visit)
        for key, value in f.attrs.items():
            if key not in TIMED_ATTRS:
                out[f"/@{key}"] = value
    return out


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind in "fc":
        return a.shape == b.shape and a.tobytes() == b.tobytes()
    return a.shape == b.shape and bool(np.all(a == b))


def test_result_h5_is_bitwise_reproducible(tmp_path):
    keys = {"mesh.elements": [16, 16], "loading.steps": 3}
    text = build.case_text(build.file_case(RESERVOIR, **keys))
    case = tmp_path / "case.toml"
    case.write_text(text)
    runs = {
        "threads1-a": 1,
        "threads1-b": 1,
        "threads2": 2,
    }
    for name, threads in runs.items():
        _run(case, tmp_path / name, threads)
    ref = _contents(tmp_path / "threads1-a" / "result.h5")
    assert any(k.startswith("steps/") for k in ref)  # premise: 3 steps written
    for name in ("threads1-b", "threads2"):
        got = _contents(tmp_path / name / "result.h5")
        assert sorted(got) == sorted(ref)
        differ = [k for k in ref if not _same(ref[k], got[k])]
        assert not differ, (name, differ)
        for vtu in ("result.vtu", "fractures.vtu"):
            a = (tmp_path / "threads1-a" / vtu).read_bytes()
            assert (tmp_path / name / vtu).read_bytes() == a, (name, vtu)
