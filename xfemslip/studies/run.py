"""Running a sweep: local processes or a Dask cluster, reruns, the summary.

Each case of a :class:`~xfemslip.studies.sweep.SweepSpec` runs in its own folder
``<sweep directory>/<case id>/`` (``case.toml``, ``result.h5``, VTU files).

- ``jobs = 1``: in this process, one case after the other.
- ``jobs = N > 1``: a ``ProcessPoolExecutor`` of N workers started with
  ``spawn`` (a fresh interpreter: no forked Numba or BLAS state).
- ``scheduler = ADDRESS``: the cases are submitted to an existing
  ``dask.distributed`` scheduler.  The workers need xfemslip installed and the
  sweep folder on a file system they share with this machine.

A case whose folder holds a whole converged result of the same case text
(:func:`is_done`) is skipped; any other case runs (again). Each member's
folder is written as one set (:mod:`xfemslip.io.folder`), the sweep
folder is locked while a sweep runs, and ``summary.csv`` with
``dfn_summary.csv`` are replaced together (``replace_files``). A failed case
is reported in its row and the others go on; so is a case the sweep refused
(it cannot be built: ``SweepCase.refused``), which is logged and not run.
``summary.csv`` has one row per case: the parameters, max |slip| [m],
slipping length [m], share of contact points in slip, converged, Newton
iterations, wall time [s], the number of fractures, how many have a point in
slip, that fraction, the mean over those of their length-weighted mean |slip|
[m], the largest moment magnitude with the W it used, the block's k_xx and
k_yy over their in-situ values (cases with ``[permeability]``), per fracture
(up to ten) whether it slipped, its max |slip|, slipping length, moment per
unit length and magnitude (``fracture<i>_...``), status (ok, skipped, failed,
refused) and error. A sweep that varies a
``network.*`` key also gets ``dfn_summary.csv`` (:mod:`xfemslip.studies.dfn_summary`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import traceback
from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

from xfemslip import display
from xfemslip.errors import OutputError, ResultError, UsageError, XfemslipError
from xfemslip.io.csv import write_rows
from xfemslip.io.fileset import replace_files
from xfemslip.io.lock import folder_lock
from xfemslip.io.read import read_attrs, read_result
from xfemslip.post.events import CASE_COLUMNS, fracture_metrics
from xfemslip.post.metrics import METRICS, result_metrics
from xfemslip.studies.dfn_summary import DFN_SUMMARY, is_dfn_sweep, write_dfn_summary

logger = logging.getLogger(__name__)

SUMMARY = "summary.csv"


@dataclass(frozen=True)
class CaseTask:
    """What a worker needs to run one case (picklable, no spec objects)."""

    case_id: str
    text: str  # case TOML
    path: str  # the path the case is loaded as (CSV files relative to it)
    out_dir: str


@dataclass
class CaseRow:
    """One line of the summary."""

    case_id: str
    params: tuple = ()
    status: str = "ok"  # ok | skipped | failed | refused
    metrics: dict = field(default_factory=dict)
    error: str = ""


# --------------------------------------------------------------------------- #
# Reruns
# --------------------------------------------------------------------------- #


def is_done(out_dir: Path, text: str, spec=None) -> bool:
    """Whether ``out_dir`` holds a converged result of this case text, whole.

    ``result.h5`` must say ``converged = true``, hold the same case text and a
    ``run_id`` (written only by a run that swapped its whole set in, see
    :mod:`xfemslip.io.folder`).  Given the case ``spec``, the VTU and PVD
    files its ``output.formats`` call for must be there with the same
    ``run_id``: a folder with a result.h5 but no (or another run's) VTU is run
    again.
    """
    path = Path(out_dir) / "result.h5"
    if not path.is_file():
        return False
    try:
        attrs = read_attrs(path)
    except ResultError:  # unreadable: run it again
        return False
    if not (
        bool(attrs.get("converged", False))
        and attrs.get("case_toml") == text
        and "run_id" in attrs
    ):
        return False
    return spec is None or _vtu_set_whole(Path(out_dir), spec, int(attrs["run_id"]))


def _vtu_set_whole(out_dir: Path, spec, run_id: int) -> bool:
    """Whether the VTU/PVD files of ``spec``'s output are there, of ``run_id``."""
    from xfemslip.io.vtu import pvd_files, read_run_id

    if "vtu" not in spec.output.formats:
        return True
    names = ["result.vtu"]
    if (out_dir / "fractures.vtu").exists():
        names.append("fractures.vtu")
    if spec.loading.steps > 1:
        series = ["result.pvd"]
        if (out_dir / "fractures.pvd").exists():
            series.append("fractures.pvd")
        for name in series:
            if read_run_id(out_dir / name) != run_id:
                return False
            try:
                names += pvd_files(out_dir / name)
            except (OSError, ElementTree.ParseError):  # cut short: run it again
                return False
    return all(read_run_id(out_dir / name) == run_id for name in names)


def done_metrics(out_dir: Path, text: str, spec) -> dict | None:
    """The summary columns of a case whose folder holds its result whole
    (:func:`is_done`), read back; None when it must run (again): no result,
    another case's, or a file that cannot be read (damaged: flipped bits, cut
    short), which is said in a warning."""
    if not is_done(out_dir, text, spec):
        return None
    try:
        return case_metrics(read_result(out_dir), spec)
    except ResultError as err:
        logger.warning("%s: run again: %s", out_dir, " ".join(str(err).split()))
        return None


# --------------------------------------------------------------------------- #
# One case (runs in a worker)
# --------------------------------------------------------------------------- #


def case_metrics(result, spec) -> dict:
    """The summary columns of one case: METRICS, then the event sizes (and
    permeability ratios) of :func:`xfemslip.post.events.fracture_metrics`."""
    return result_metrics(result, spec) | fracture_metrics(result, spec)


def run_task(task: CaseTask) -> tuple[str, str, dict, str]:
    """Run one case; never raises.  Returns (case_id, status, metrics, error).

    A library error (no convergence, unwritable output) is the case's error
    message; any other exception is a bug and its traceback is the message.
    """
    from xfemslip.case import loads_case
    from xfemslip.simulation import run_case
    from xfemslip.solve.shared import sharing

    out_dir = Path(task.out_dir)
    spec = None
    try:
        spec = loads_case(task.text, Path(task.path))
        with sharing():  # members of the same geometry share their build
            result = run_case(spec, out_dir, overwrite=True)
        return task.case_id, "ok", case_metrics(result, spec), ""
    except XfemslipError as err:
        error = " ".join(str(err).split())
    except Exception:  # a bug: keep the other cases, show where it happened
        error = " | ".join(traceback.format_exc().strip().splitlines()[-3:])
    metrics = {}
    if spec is not None and (out_dir / "result.h5").is_file():
        try:  # the converged steps of a failed run
            metrics = case_metrics(read_result(out_dir), spec)
        except ResultError:
            metrics = {}
    return task.case_id, "failed", metrics, error


# --------------------------------------------------------------------------- #
# The sweep
# --------------------------------------------------------------------------- #


def _prepare(sweep, directory: Path, force: bool) -> tuple[list, list[CaseRow]]:
    """Write each case.toml; (tasks to run, rows of the refused and skipped
    cases)."""
    tasks, skipped = [], []
    for case in sweep.cases:
        out_dir = directory / case.case_id
        if case.refused:
            logger.warning("%s refused: %s", case.label, case.refused)
            skipped.append(
                CaseRow(case.case_id, case.params, "refused", error=case.refused)
            )
            if case.text:  # for `xfemslip check` on it
                write_case(sweep, out_dir, case.text)
            continue
        metrics = done_metrics(out_dir, case.text, case.spec) if not force else None
        if metrics is not None:
            skipped.append(CaseRow(case.case_id, case.params, "skipped", metrics))
            continue
        write_case(sweep, out_dir, case.text)
        # absolute: a Dask worker runs in a working directory of its own
        tasks.append(
            CaseTask(
                case.case_id,
                case.text,
                os.path.abspath(case.path),
                os.path.abspath(out_dir),
            )
        )
    return tasks, skipped


def write_case(sweep, out_dir: Path, text: str) -> None:
    """``<out_dir>/case.toml``: the generated case, with where it came from
    (``sweep.path``, the sweep file); nothing without a text."""
    if not text:
        return
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        header = f"# generated by xfemslip sweep from {sweep.path}\n"
        (out_dir / "case.toml").write_text(header + text, encoding="utf-8")
    except OSError as exc:
        raise OutputError(f"cannot write {out_dir}: {exc.strerror}") from None


def _outcome(task: CaseTask, future) -> tuple:
    """A finished future's result; a lost worker (killed, out of memory) or a
    pickling problem is that case's failure, not the sweep's."""
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 -- reported in the case's row
        return lost_task(task, f"{type(exc).__name__}: {exc}")


def lost_task(task, reason: str) -> tuple:
    """The outcome of a task whose worker was lost: that case failed."""
    return task.case_id, "failed", {}, f"worker error: {reason}"


def run_local(tasks: list, jobs: int, fn=run_task) -> Generator[tuple, None, None]:
    """``fn(task)`` of every task, in completion order: in this process, or
    on ``jobs`` worker processes that stop with the sweep
    (:mod:`xfemslip.studies.workers`; ``fn`` must be importable by the
    workers and never raise, as :func:`run_task`)."""
    from xfemslip.studies.workers import run_local as run_on_workers

    return run_on_workers(tasks, jobs, fn, lost_task)


def require_dask() -> None:
    """UsageError (exit 2) when dask.distributed cannot be imported."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise UsageError(
            "--scheduler needs dask.distributed: pip install 'xfemslip[dask]'"
        ) from None


def connect(scheduler: str):
    """A dask.distributed Client of the scheduler at ``scheduler``."""
    require_dask()
    from distributed import Client

    try:
        return Client(scheduler, timeout="10s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise UsageError(
            f"--scheduler {scheduler}: cannot connect to a Dask scheduler: "
            f"{' '.join(str(exc).split())}"
        ) from None


def run_dask(tasks: list, client, fn=run_task) -> Generator[tuple, None, None]:
    """``fn(task)`` of every task, in completion order, from a
    dask.distributed ``client``.  Each task runs in a child process of its
    Dask worker (:func:`dask_task`), stopped when the sweep cancels the task
    (an interrupt, an error) or its process dies: a Dask worker's thread
    cannot be stopped, a process can."""
    from distributed import as_completed as dask_completed

    # pure=False: a rerun of the same task must run, not hit a cached result
    futures = client.map(dask_task, tasks, fn=fn, pure=False)
    owner = {future.key: task for future, task in zip(futures, tasks, strict=True)}
    try:
        for future in dask_completed(futures):
            yield _outcome(owner[future.key], future)
    finally:
        client.cancel(futures)


def dask_task(task, fn=run_task) -> tuple:
    """On a Dask worker: ``fn(task)`` in a child process
    (:func:`xfemslip.studies.workers.run_in_child`), stopped once the
    scheduler no longer wants the task (cancelled, or its client gone)."""
    from xfemslip.studies.workers import run_in_child

    wanted = _dask_task_wanted()
    try:
        out = run_in_child(fn, task, wanted)
    except RuntimeError as exc:
        return lost_task(task, str(exc))
    return out if out is not None else lost_task(task, "stopped with the sweep")


def _dask_task_wanted() -> Callable[[], bool]:
    """Whether the Dask task running in this thread is still wanted: its
    state on this worker is not "cancelled" (the scheduler marks it so when
    its client cancels it or disconnects).  Always True where the worker's
    state cannot be read."""
    try:
        from distributed import get_worker
        from distributed.worker import thread_state

        worker, key = get_worker(), thread_state.key
    except (ImportError, ValueError, AttributeError):
        return lambda: True

    def wanted() -> bool:
        try:
            state = worker.state.tasks.get(key)
        except AttributeError:
            return True
        return state is not None and state.state not in ("cancelled", "released")

    return wanted


def run_sweep(
    sweep,
    directory: Path | None = None,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    force: bool = False,
    progress: Callable[[CaseRow], None] | None = None,
) -> list[CaseRow]:
    """Run every case of ``sweep`` not already done; write ``summary.csv``.

    Returns the rows in case order.  ``progress(row)`` is called once per
    case: first for the skipped ones, then as each case finishes.
    """
    if jobs < 1:
        raise UsageError(f"--jobs must be >= 1, got {jobs}")
    directory = Path(directory) if directory is not None else sweep.directory
    # connect first: a wrong address must not leave case folders behind
    client = connect(scheduler) if scheduler else None
    try:
        with sweep_lock(directory):
            rows = _run_all(sweep, directory, jobs, client, force, progress)
    finally:
        if client is not None:
            client.close()
    order = {case.case_id: case.index for case in sweep.cases}
    rows.sort(key=lambda r: order[r.case_id])
    # one set: a dfn_summary.csv of an earlier sweep of this folder goes too
    dfn = is_dfn_sweep(sweep.keys)  # realizations of a random network
    replace_files(
        {
            directory / SUMMARY: lambda tmp: write_summary(tmp, sweep.keys, rows),
            directory / DFN_SUMMARY: (lambda tmp: write_dfn_summary(tmp, rows))
            if dfn
            else None,
        }
    )
    return rows


def sweep_lock(directory: Path):
    """The lock of the sweep folder (``.NAME.lock`` beside it): one sweep at a
    time writes its members and summary."""
    try:
        directory.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot write {directory}: {exc.strerror}") from None
    return folder_lock(Path(os.path.realpath(directory)), directory)


def _run_all(sweep, directory, jobs, client, force, progress) -> list[CaseRow]:
    """Prepare the folders, run what is not done; the rows in completion order."""
    tasks, rows = _prepare(sweep, directory, force)
    for row in rows if progress is not None else ():
        progress(row)
    if not tasks:
        return rows
    params = {case.case_id: case.params for case in sweep.cases}
    results = run_dask(tasks, client) if client else run_local(tasks, jobs)
    # closed on any way out: an interrupt stops the workers at once
    with contextlib.closing(results) as outcomes:
        for case_id, status, metrics, error in outcomes:
            row = CaseRow(case_id, params[case_id], status, metrics, error)
            if status == "failed":
                logger.warning("case %s failed: %s", case_id, error)
            rows.append(row)
            if progress is not None:
                progress(row)
    return rows


# --------------------------------------------------------------------------- #
# Summary
# --------------------------------------------------------------------------- #


def _cell(value) -> str:
    """One summary value as text."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _extra_columns(rows: list[CaseRow], per_fracture: bool) -> list[str]:
    """The columns after METRICS: CASE_COLUMNS, then (``per_fracture``) the
    per-fracture ones that any row has, in the order they first appear."""
    extra = list(CASE_COLUMNS)
    if per_fracture:
        seen = dict.fromkeys(
            name for row in rows for name in row.metrics if name.startswith("fracture")
        )
        extra += [name for name in seen if name not in METRICS]
    return extra


def summary_table(
    keys, rows: list[CaseRow], per_fracture: bool = True
) -> tuple[list[str], list[list[str]]]:
    """Header and text cells of the summary (CSV and printout alike): the
    parameters, METRICS, the event and permeability columns, status, error.
    The columns of METRICS keep their names and meaning; the others follow
    them (read a summary.csv by column name)."""
    columns = [*METRICS, *_extra_columns(rows, per_fracture)]
    header = ["case", *keys, *columns, "status", "error"]
    body = []
    for row in rows:
        values = dict(row.params)
        cells = [row.case_id, *(_cell(values[k]) for k in keys)]
        cells += [_cell(row.metrics[m]) if m in row.metrics else "" for m in columns]
        body.append([*cells, row.status, row.error])
    return header, body


def write_summary(path: Path, keys, rows: list[CaseRow]) -> None:
    """``summary.csv`` (run_sweep writes it through ``replace_files``)."""
    header, body = summary_table(keys, rows)
    write_rows(path, header, body)


def format_table(keys, rows: list[CaseRow]) -> str:
    """The summary as an aligned text table (the error column last, unpadded);
    the per-fracture columns are in summary.csv only."""
    header, body = summary_table(keys, rows, per_fracture=False)
    header = header[1:-1]  # the case id is long; the parameters say it all
    body = [[*cells[1:-1], cells[-1]] for cells in body]
    return display.table(header, body, left=range(len(header)))
