"""Probability of reactivation: the samples of an ``[uncertainty]`` study
evaluated, then counted per fracture and depletion level.

- ``evaluate = "screen"``: :func:`xfemslip.studies.slip_screen.critical_changes`
  on all samples at once (closed form along the stress path it states).
- ``evaluate = "xfem"``: each sample's case through
  :func:`xfemslip.studies.depletion.deplete` (the engine of ``run``) in its
  folder ``<sweep folder>/<sample id>/``, on local processes or a Dask cluster
  like a sweep (:mod:`xfemslip.studies.run`); a sample whose folder holds a
  converged result of the same case text is read back, not run; a sample
  that cannot be built is *refused*, one whose solve fails *failed*: both are
  reported and left out of the counts.

A fracture has slipped by level L (a pore-pressure change, < 0 depletion)
when its critical change dp_c is finite and |dp_c| <= |L| (same sign).  Over
the n evaluated samples the count k gives P = k / n, its Wilson interval and
the samples the Wilson interval needs for a target half-width
(:mod:`xfemslip.studies.sampling`).  The sensitivity is Spearman's rank
correlation of each input with dp_c, a fracture that never slips counting as
slipping beyond every level (ranked last).
"""

from __future__ import annotations

import contextlib
import csv
import logging
import os
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import stats

from xfemslip.errors import XfemslipError
from xfemslip.studies.sampling import (
    rank_correlation,
    wilson_interval,
    wilson_samples_needed,
)
from xfemslip.studies.uncertainty import UncertaintySpec

logger = logging.getLogger(__name__)

OK, SKIPPED, REFUSED, FAILED = "ok", "skipped", "refused", "failed"
EVALUATED = (OK, SKIPPED)


@dataclass
class UncertaintyResult:
    """The evaluated samples and what they add up to."""

    spec: UncertaintySpec
    path_text: str  # the stress path (screen) or the engine (xfem)
    ids: list  # sample ids (xfem: folder names)
    status: np.ndarray  # (n,) str
    errors: list  # (n,) one-line reasons ("" when evaluated)
    dp_critical: np.ndarray  # (n, n_fractures) [Pa], NaN = no slip
    max_slip: np.ndarray | None = None  # (n, n_fractures) [m], xfem only
    slip_length: np.ndarray | None = None  # (n, n_fractures) [m], xfem only
    compute_time_s: float = 0.0
    # filled by aggregate:
    slipped: np.ndarray | None = None  # (n_fractures, n_levels) counts
    evaluated: int = 0
    probability: np.ndarray | None = None  # (n_fractures, n_levels)
    ci_low: np.ndarray | None = None
    ci_high: np.ndarray | None = None
    samples_needed: np.ndarray | None = None  # (n_fractures, n_levels)
    sensitivity: np.ndarray | None = None  # (n_fractures, n_inputs)
    written: list = field(default_factory=list)

    @property
    def fractures(self) -> list[int]:
        """Case-file indices of the fractures."""
        return [f.index for f in self.spec.base_spec.fractures]


# --------------------------------------------------------------------------- #
# Screen
# --------------------------------------------------------------------------- #


def evaluate_screen(spec: UncertaintySpec) -> UncertaintyResult:
    """All samples through the closed form (the path was checked on loading)."""
    from xfemslip.studies.slip_screen import (
        critical_changes,
        sample_problems,
        stress_path,
    )

    path, _ = stress_path(spec.base_spec)
    assert path is not None  # the path was checked when the study was read
    start = time.perf_counter()
    errors = sample_problems(spec.keys, spec.values)
    bad = np.array([bool(e) for e in errors], dtype=bool)
    with np.errstate(all="ignore"):  # the refused samples' values are not used
        dp = critical_changes(spec.base_spec, spec.base, path, spec.keys, spec.values)
    dp[bad] = np.nan
    elapsed = time.perf_counter() - start
    status = np.where(bad, REFUSED, OK)
    ids = [f"{i:0{max(3, len(str(spec.samples - 1)))}d}" for i in range(spec.samples)]
    result = UncertaintyResult(spec, path.description, ids, status, errors, dp)
    result.compute_time_s = elapsed
    return aggregate(result)


# --------------------------------------------------------------------------- #
# XFEM
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class SampleTask:
    """What a worker needs to deplete one sample (picklable)."""

    case_id: str
    text: str
    path: str
    out_dir: str


def deplete_task(task: SampleTask) -> tuple[str, str, dict, str]:
    """Critical depletion of one sample; never raises.

    Returns (case_id, status, values, error): values holds ``dp_critical``,
    ``max_slip`` and ``slip_length`` per fracture (the last two at the case's
    final step), read from the files ``deplete`` wrote.
    """
    from xfemslip.case import loads_case
    from xfemslip.solve.shared import sharing
    from xfemslip.studies.depletion import deplete

    out_dir = Path(task.out_dir)
    try:
        spec = loads_case(task.text, Path(task.path))
        with sharing():  # the samples of a study share their bulk matrix
            deplete(spec, out_dir, overwrite=True)
        return task.case_id, OK, read_sample(out_dir), ""
    except XfemslipError as err:
        error = " ".join(str(err).split())
    except Exception:  # a bug: keep the other samples, show where it happened
        error = " | ".join(traceback.format_exc().strip().splitlines()[-3:])
    return task.case_id, FAILED, {}, error


def read_sample(out_dir: Path) -> dict:
    """Per fracture dp_critical [Pa] (NaN: no slip), max |slip| [m] and
    slipping length [m] at the final step, from ``deplete``'s tables."""
    with (out_dir / "critical_depletion.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    dp = [float(r["dp_upper_Pa"]) for r in rows]
    dp = [
        0.5 * (float(r["dp_lower_Pa"]) + u) if np.isfinite(u) else np.nan
        for r, u in zip(rows, dp, strict=True)
    ]
    with (out_dir / "slip_vs_depletion.csv").open(newline="") as fh:
        last = list(csv.DictReader(fh))[-1]
    n = len(rows)
    return {
        "dp_critical": dp,
        "max_slip": [float(last[f"max_abs_slip_{i}_m"]) for i in range(n)],
        "slip_length": [float(last[f"slip_length_{i}_m"]) for i in range(n)],
    }


def sample_cases(spec) -> list:
    """(case id, TOML text, CaseSpec or None, why refused) of every sample."""
    import tomli_w

    from xfemslip.studies.sweep import case_id, validate_case
    from xfemslip.studies.uncertainty import sample_document

    out = []
    short = spec.base_name.encode("utf-8")[:100].decode("utf-8", "ignore")
    for i in range(spec.samples):
        params = tuple(zip(spec.keys, spec.values[i], strict=True))
        cid = case_id(i, spec.samples, params)
        document = sample_document(spec, i)
        document["name"] = f"{short}-{cid}"
        output = document.setdefault("output", {})
        if isinstance(output, dict):
            output.pop("directory", None)  # the study chooses the folder
            # the study reads the tables of deplete; the fields of a sample
            # are in its result.h5 (`xfemslip run` of its case.toml writes
            # them as VTU), not written as VTU for every sample (a third of
            # a sample's time)
            output["formats"] = ["h5"]
        try:
            text = tomli_w.dumps(document)
        except (TypeError, ValueError) as exc:
            out.append((cid, "", None, f"cannot be written as TOML: {exc}"))
            continue
        case, reason = validate_case(text, spec.case_path)
        out.append((cid, text, case, reason))
    return out


def evaluate_xfem(
    spec, directory: Path, *, jobs=1, client=None, force=False, progress=None
) -> UncertaintyResult:
    """Every sample through ``deplete`` (see the module doc)."""
    from xfemslip.solve.shared import sharing
    from xfemslip.studies.run import run_dask, run_local, write_case

    start = time.perf_counter()
    with sharing():  # the geometry checked once is the one the samples solve
        cases = sample_cases(spec)
    n, nf = spec.samples, len(spec.base_spec.fractures)
    ids = [c[0] for c in cases]
    status = np.full(n, OK, dtype=object)
    errors = [""] * n
    values = {
        k: np.full((n, nf), np.nan) for k in ("dp_critical", "max_slip", "slip_length")
    }
    index = {cid: i for i, cid in enumerate(ids)}
    tasks = []
    for i, (cid, text, case, reason) in enumerate(cases):
        out_dir = directory / cid
        if reason:
            status[i], errors[i] = REFUSED, reason
            logger.warning("sample %s refused: %s", cid, reason)
            write_case(spec, out_dir, text)
        elif not force and (found := _read_back(out_dir, text, case)) is not None:
            status[i] = SKIPPED
            _store(values, i, found)
        else:
            write_case(spec, out_dir, text)
            # absolute: a Dask worker runs in a working directory of its own
            tasks.append(
                SampleTask(
                    cid, text, os.path.abspath(spec.case_path), os.path.abspath(out_dir)
                )
            )
        if progress is not None and status[i] != OK:
            progress(cid, status[i])
    results = (
        run_dask(tasks, client, deplete_task)
        if client
        else run_local(tasks, jobs, deplete_task)
    )
    # closed on any way out: an interrupt stops the workers at once
    with contextlib.closing(results) as outcomes:
        for cid, state, found, error in outcomes:
            i = index[cid]
            status[i], errors[i] = state, error
            if state == OK:
                _store(values, i, found)
            else:
                logger.warning("sample %s failed: %s", cid, error)
            if progress is not None:
                progress(cid, state)
    result = UncertaintyResult(
        spec,
        "the full XFEM solve of every sample (xfemslip deplete: bisection of "
        "each fracture's first slip)",
        ids,
        status.astype(str),
        errors,
        values["dp_critical"],
        values["max_slip"],
        values["slip_length"],
    )
    result.compute_time_s = time.perf_counter() - start
    return aggregate(result)


def _read_back(out_dir: Path, text: str, case) -> dict | None:
    """The values of a sample whose folder holds its whole result
    (:func:`xfemslip.studies.run.is_done`) and both tables, read back; None
    when it must be solved (again): a table missing, cut short or damaged
    (said in a warning)."""
    from xfemslip.studies.run import is_done

    if not is_done(out_dir, text, case):
        return None
    try:
        found = read_sample(out_dir)
        if any(len(v) != len(case.fractures) for v in found.values()):
            raise ValueError("not one value per fracture")
    except (OSError, KeyError, ValueError, IndexError, TypeError, csv.Error) as exc:
        if any((out_dir / name).exists() for name in TABLES):
            logger.warning(
                "%s: solve again: its tables cannot be read (%s)", out_dir, exc
            )
        return None
    return found


TABLES = ("critical_depletion.csv", "slip_vs_depletion.csv")


def _store(values: dict, i: int, found: dict) -> None:
    for key, arr in values.items():
        arr[i, :] = found[key]


# --------------------------------------------------------------------------- #
# Counting
# --------------------------------------------------------------------------- #


def slipped_counts(dp: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """(n_fractures, n_levels): samples (rows of dp) whose fracture has slipped
    by each level: finite dp with |dp| <= |level|.  Sorting makes it
    O(n log n) per fracture whatever the number of levels."""
    reach = np.where(np.isfinite(dp), np.abs(dp), np.inf)
    reach = np.sort(reach, axis=0)
    return np.stack(
        [
            np.searchsorted(reach[:, j], np.abs(levels), side="right")
            for j in range(dp.shape[1])
        ]
    )


def aggregate(result: UncertaintyResult) -> UncertaintyResult:
    """Fill the counts, probabilities, intervals, samples needed, sensitivity."""
    spec = result.spec
    use = np.isin(result.status, EVALUATED)
    n = int(use.sum())
    result.evaluated = n
    dp = result.dp_critical[use]
    slipped = result.slipped = slipped_counts(dp, spec.levels)
    if n == 0:
        shape = slipped.shape
        for name in ("probability", "ci_low", "ci_high"):
            setattr(result, name, np.full(shape, np.nan))
        result.samples_needed = np.zeros(shape, int)
        result.sensitivity = np.full((dp.shape[1], len(spec.keys)), np.nan)
        return result
    probability = result.probability = slipped / n
    result.ci_low, result.ci_high = wilson_interval(slipped, n, spec.confidence)
    result.samples_needed = wilson_samples_needed(
        probability, spec.half_width, spec.confidence
    )
    pore = spec.base_spec.pore_pressure
    assert pore is not None and pore.change is not None  # the levels scale it
    sign = np.sign(pore.change)
    result.sensitivity = sensitivity(spec.values[use], dp, sign)
    return result


def sensitivity(inputs: np.ndarray, dp: np.ndarray, sign: float) -> np.ndarray:
    """(n_fractures, n_inputs) Spearman correlation of each input with dp_c;
    NaN dp_c (never slips) ranks beyond every level: sign * inf."""
    out = np.full((dp.shape[1], inputs.shape[1]), np.nan)
    for j in range(dp.shape[1]):
        y = np.where(np.isfinite(dp[:, j]), dp[:, j], sign * np.inf)
        ranks = stats.rankdata(y)
        for k in range(inputs.shape[1]):
            out[j, k] = rank_correlation(inputs[:, k], ranks)
    return out
