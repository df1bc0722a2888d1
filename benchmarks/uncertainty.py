"""Uncertainty studies: screen speed, the XFEM path over processes and Dask,
and where the closed form and the XFEM probabilities agree or differ.

Usage, from the project root::

    python benchmarks/uncertainty.py screen --samples 10000 \
        [--markdown docs/performance/uncertainty_screen.md]
    python benchmarks/uncertainty.py xfem --samples 1000 --jobs 2
    python benchmarks/uncertainty.py xfem --samples 1000 --dask 2
    python benchmarks/uncertainty.py compare --samples 200 --jobs 2

- ``screen``: compute time of the closed form (``critical_changes`` and the
  counting) for N samples, best of 5 after a warm-up, on the shipped study
  (cases/sweeps/slip_probability.toml, the depleting reservoir) and on the
  seed paper's 50 x 50 reservoir case with a pore pressure (RESERVOIR below);
  plus the loading and drawing of the samples.
- ``xfem``: wall time of ``evaluate_xfem`` (case generation and validation,
  ``deplete`` of every sample, reading back) for N samples of RESERVOIR, on
  ``--jobs`` local processes or a ``dask.distributed.LocalCluster`` of
  ``--dask`` single-threaded workers (started before timing).
- ``compare``: the screen and the XFEM P curves of the same samples, on an
  isolated fracture in a large box (the closed form is exact: they must
  agree within their intervals), on two fractures side by side that
  interact once one slips, and on the depleting reservoir (fracture 1
  crosses the reservoir top).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import mdtable
import numpy as np

from xfemslip.studies.reactivation import evaluate_screen, evaluate_xfem
from xfemslip.studies.slip_screen import critical_changes, stress_path
from xfemslip.studies.uncertainty import load_uncertainty

ROOT = Path(__file__).resolve().parents[1]

# The seed paper's reservoir case (cases/reservoir_depletion.toml: 1 m box,
# 50 x 50 Q4, a 0.6 m fracture at 45 degrees, E = 5 GPa, nu = 0.3) with an
# in-situ stress, a pore pressure of 10 MPa depleted by 30 MPa in 5 steps,
# and rollers on the sides: the uniaxial-strain path.
RESERVOIR = """
name = "reservoir-pore"
[domain]
size = [1.0, 1.0]
[mesh]
elements = [50, 50]
[material]
E = 5.0e9
nu = 0.3
[[fractures]]
center = [0.5, 0.5]
length = 0.6
angle = 45.0
friction = 0.1
kn = 5.0e12
kt = 5.0e12
[pore_pressure]
initial = 10.0e6
change = -30.0e6
[loading]
initial_stress = { xx = -30.0e6, yy = -40.0e6, xy = 0.0 }
stress = { xx = -30.0e6, yy = -40.0e6, xy = 0.0 }
steps = 5
[boundary]
left = { ux = 0.0 }
right = { ux = 0.0 }
bottom = { uy = 0.0 }
top = "traction"
"""

RESERVOIR_STUDY = """
name = "reservoir-pore"
base = "base.toml"
[uncertainty]
samples = {samples}
seed = 7
evaluate = "{evaluate}"
levels = {{ start = 0.0, stop = -30.0e6, num = 16 }}
[uncertainty.inputs]
"fractures[0].friction" = {{ distribution = "uniform", low = 0.2, high = 0.35 }}
"loading.initial_stress.xx" = {{ distribution = "normal", mean = -30e6, std = 1e6 }}
"pore_pressure.initial" = {{ distribution = "uniform", low = 8e6, high = 12e6 }}
"""

# An isolated 10 m fracture in a 100 m box (tests/unit/studies/test_uncertainty.py)
ISOLATED = RESERVOIR.replace('name = "reservoir-pore"', 'name = "isolated"').replace(
    "size = [1.0, 1.0]", "size = [100.0, 100.0]"
)
ISOLATED = (
    ISOLATED.replace("elements = [50, 50]", "elements = [20, 20]")
    .replace(
        "center = [0.5, 0.5]\nlength = 0.6", "center = [50.0, 50.0]\nlength = 10.0"
    )
    .replace("kn = 5.0e12\nkt = 5.0e12\n", "")
)

# Two parallel 4 m fractures 1.4 m apart (side by side at 45 degrees) in a
# 20 m box of 0.5 m cells, same stresses: once one slips, it loads and
# unloads the other, which the closed form does not see.
INTERACTING = (
    RESERVOIR.replace('name = "reservoir-pore"', 'name = "interacting"')
    .replace("size = [1.0, 1.0]", "size = [20.0, 20.0]")
    .replace("elements = [50, 50]", "elements = [40, 40]")
    .replace("center = [0.5, 0.5]\nlength = 0.6", "center = [10.0, 10.0]\nlength = 4.0")
    .replace("kn = 5.0e12\nkt = 5.0e12\n", "")
    .replace(
        "[pore_pressure]",
        "[[fractures]]\ncenter = [11.0, 9.0]\nlength = 4.0\nangle = 45.0\n"
        "friction = 0.27\n[pore_pressure]",
    )
)


def _study(folder: Path, base: str, samples: int, evaluate: str) -> Path:
    (folder / "base.toml").write_text(base)
    path = folder / "study.toml"
    path.write_text(RESERVOIR_STUDY.format(samples=samples, evaluate=evaluate))
    return path


def _best(fn, repeats=5) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def screen(samples: int, markdown: Path | None = None) -> None:
    """Compute time of the closed form for ``samples`` samples; the table
    goes to ``markdown`` too (docs/performance/uncertainty_screen.md)."""
    rows, loads = [], [mdtable.load()]
    with tempfile.TemporaryDirectory() as tmp:
        shipped = ROOT / "cases" / "sweeps" / "slip_probability.toml"
        base = (ROOT / "cases" / "depleting_reservoir.toml").as_posix()
        copy = Path(tmp) / "shipped.toml"
        copy.write_text(
            shipped.read_text()
            .replace("samples = 20000", f"samples = {samples}")
            .replace('base = "../depleting_reservoir.toml"', f'base = "{base}"')
        )
        studies = [
            ("depleting reservoir (3 fractures)", copy),
            (
                "seed reservoir 50 x 50 (1 fracture)",
                _study(Path(tmp), RESERVOIR, samples, "screen"),
            ),
        ]
        for label, path in studies:
            start = time.perf_counter()
            spec = load_uncertainty(path)
            load = time.perf_counter() - start
            sp, _ = stress_path(spec.base_spec)
            compute = _best(
                lambda spec=spec, sp=sp: critical_changes(
                    spec.base_spec, spec.base, sp, spec.keys, spec.values
                )
            )
            whole = _best(lambda spec=spec: evaluate_screen(spec))
            rows.append((label, samples, compute, whole, load))
            loads.append(mdtable.load())
    mdtable.write(markdown, screen_markdown(rows, loads))


def screen_markdown(rows, loads) -> str:
    """The screen's table: per study, the closed form alone, the whole
    evaluation (with the counts per level, the Wilson intervals and the
    Spearman correlations), and loading the file with drawing the samples."""
    return mdtable.table(
        [
            "study",
            "samples",
            "closed form [ms]",
            "whole evaluation [ms]",
            "loading the file, drawing [ms]",
        ],
        [
            [label, f"{n:,}", f"{c * 1e3:.1f}", f"{w * 1e3:.1f}", f"{ld * 1e3:.0f}"]
            for label, n, c, w, ld in rows
        ],
    ) + mdtable.note("Best of 5 after a warm-up, in one process", loads)


def xfem(samples: int, jobs: int, dask: int) -> None:
    """Wall time of the XFEM path for ``samples`` samples."""
    client = cluster = None
    if dask:
        from distributed import Client, LocalCluster

        cluster = LocalCluster(
            n_workers=dask, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = _study(Path(tmp), RESERVOIR, samples, "xfem")
            spec = load_uncertainty(path)
            start = time.perf_counter()
            result = evaluate_xfem(
                spec, Path(tmp) / "out", jobs=jobs, client=client, force=True
            )
            wall = time.perf_counter() - start
            where = (
                f"Dask LocalCluster of {dask} workers" if dask else f"{jobs} processes"
            )
            print(
                f"xfem, seed reservoir 50 x 50: {samples} samples on {where}: "
                f"{wall:.1f} s ({wall / samples * 1e3:.0f} ms per sample), "
                f"{result.evaluated} evaluated, "
                f"{int(np.sum(result.status == 'failed'))} failed; "
                f"P(-30 MPa) = {result.probability[0, -1]:.3f} "
                f"[{result.ci_low[0, -1]:.3f}, {result.ci_high[0, -1]:.3f}]"
            )
            _agreement("  screen vs xfem on the same samples", spec, result)
    finally:
        if client is not None:
            client.close()
            cluster.close()


def _agreement(label, spec, xfem_result) -> None:
    """Max |P_xfem - P_screen| and whether each lies in the other's interval."""
    import dataclasses

    screen_spec = dataclasses.replace(spec, evaluate="screen")
    scr = evaluate_screen(screen_spec)
    for j, fi in enumerate(xfem_result.fractures):
        diff = np.abs(xfem_result.probability[j] - scr.probability[j])
        inside = (scr.probability[j] >= xfem_result.ci_low[j] - 1e-12) & (
            scr.probability[j] <= xfem_result.ci_high[j] + 1e-12
        )
        dp_x, dp_s = xfem_result.dp_critical[:, j], scr.dp_critical[:, j]
        both = np.isfinite(dp_x) & np.isfinite(dp_s)
        gap = np.abs(dp_x[both] - dp_s[both])
        print(
            f"{label}, fracture {fi}: max |P_xfem - P_screen| = {diff.max():.4f} "
            f"over {len(diff)} levels; screen inside the xfem interval at "
            f"{int(inside.sum())}/{len(diff)} levels; |dp_xfem - dp_screen| "
            f"median {np.median(gap) / 1e3 if gap.size else np.nan:.0f} kPa, "
            f"max {gap.max() / 1e3 if gap.size else np.nan:.0f} kPa "
            f"({both.sum()} samples slipping in both)"
        )


def compare(samples: int, jobs: int) -> None:
    """Screen vs XFEM where the closed form is exact and where it is not."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = _study(folder, ISOLATED, samples, "xfem")
        spec = load_uncertainty(path)
        result = evaluate_xfem(spec, folder / "iso", jobs=jobs, force=True)
        _agreement("isolated fracture, 100 m box", spec, result)
        path = _study(folder, INTERACTING, samples, "xfem")
        spec = load_uncertainty(path)
        result = evaluate_xfem(spec, folder / "two", jobs=jobs, force=True)
        _agreement("two fractures 1.4 m apart", spec, result)
        shipped = (ROOT / "cases" / "sweeps" / "slip_probability.toml").read_text()
        base = (ROOT / "cases" / "depleting_reservoir.toml").as_posix()
        text = (
            shipped.replace("samples = 20000", f"samples = {samples}")
            .replace('evaluate = "screen"', 'evaluate = "xfem"')
            .replace('base = "../depleting_reservoir.toml"', f'base = "{base}"')
        )
        path = folder / "reservoir.toml"
        path.write_text(text)
        spec = load_uncertainty(path)
        result = evaluate_xfem(spec, folder / "res", jobs=jobs, force=True)
        _agreement("depleting reservoir", spec, result)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=("screen", "xfem", "compare"))
    ap.add_argument("--samples", type=int, default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--dask", type=int, default=0, help="LocalCluster workers")
    mdtable.add_option(ap, "docs/performance/uncertainty_screen.md (screen)")
    opts = ap.parse_args()
    if opts.what == "screen":
        screen(opts.samples or 10_000, opts.markdown)
    elif opts.what == "xfem":
        xfem(opts.samples or 1000, opts.jobs, opts.dask)
    else:
        compare(opts.samples or 200, opts.jobs)


if __name__ == "__main__":
    main()
