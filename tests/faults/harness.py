"""Fault trials on real processes: kill a run while it writes, race two runs.

Used by ``test_output_sets.py`` (a few trials each) and runnable as a script
for the counts over many trials::

    python tests/faults/harness.py --trials 24 [--code ROOT]

``--code`` runs another checkout's xfemslip (its package on ``PYTHONPATH``).

A folder is classified by comparing its *signature* (every file with the
numbers that tell two runs apart: mesh size and load steps in result.h5,
points in each VTU, the data sets a PVD names) with the signatures of the two
complete results, made in fresh folders:

- ``old``: exactly the earlier complete result;
- ``new``: exactly the new complete result;
- ``none``: no folder or an empty one (a run into a fresh folder that ended
  before it had written anything);
- ``mixed``: anything else (files of both runs, a partial set, a PVD naming
  missing files, an unreadable file).

Leftovers are hidden names (``.*``) beside the folder or anywhere in it.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import meshio

from xfemslip.case import build

ROOT = Path(__file__).resolve().parents[2]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"
TIMEOUT = 300  # s, per process (a harness bound, not a timing assertion)


def case_text(n: int, steps: int) -> str:
    """The reservoir case at n x n cells and ``steps`` load steps."""
    return build.case_text(
        build.file_case(RESERVOIR, **{"mesh.elements": [n, n], "loading.steps": steps})
    )


def write_case(folder: Path, name: str, n: int, steps: int) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(case_text(n, steps))
    return path


def command(*args: str) -> list[str]:
    return [sys.executable, "-m", "xfemslip", *map(str, args)]


def interactive_signals() -> None:
    """In the child before exec: SIGINT as in a terminal (a harness started
    in the background inherits it ignored, and so would its children)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def environment(code: Path = ROOT, **extra: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(code), **extra)
    env.pop("XFEMSLIP_TEST_PAUSE", None)
    env.update(extra)
    return env


# --------------------------------------------------------------------------- #
# Signatures
# --------------------------------------------------------------------------- #


def _file_signature(path: Path):
    """What tells two runs apart in one file; 'unreadable' when it cannot be read."""
    try:
        if path.suffix == ".h5":
            with h5py.File(path, "r") as f:
                return (
                    "h5",
                    int(f["mesh/cells"].shape[0]),
                    int(f.attrs["load_steps"]),
                    bool(f.attrs["converged"]),
                    len(f["steps"]) if "steps" in f else 0,
                )
        if path.suffix == ".vtu":
            mesh = meshio.read(path)
            return ("vtu", len(mesh.points))
        if path.suffix == ".pvd":
            names = re.findall(r'file="([^"]+)"', path.read_text())
            missing = [n for n in names if not (path.parent / n).is_file()]
            return ("pvd", tuple(names), tuple(missing))
    except Exception as exc:  # noqa: BLE001 -- any failure to read is a finding
        return ("unreadable", type(exc).__name__)
    return ("file", path.stat().st_size)


def signature(folder: Path) -> dict:
    """{relative path: file signature} of every visible file under ``folder``."""
    if not folder.is_dir():
        return {}
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if path.is_file() and not any(p.startswith(".") for p in rel.parts):
            out[str(rel)] = _file_signature(path)
    return out


def run_ids(folder: Path) -> set:
    """The run ids carried by the files of ``folder`` (h5, VTU, PVD)."""
    ids = set()
    for path in folder.rglob("*"):
        if path.suffix == ".h5":
            with h5py.File(path, "r") as f:
                ids.add(int(f.attrs["run_id"]))
        elif path.suffix == ".vtu":
            ids.add(int(meshio.read(path).field_data["run_id"][0]))
        elif path.suffix == ".pvd":
            ids.add(int(re.search(r"run_id (\d+)", path.read_text()).group(1)))
    return ids


def leftovers(folder: Path) -> list[str]:
    """Hidden names beside ``folder`` (its parent's ``.*``) or anywhere in it."""
    found = []
    if folder.parent.is_dir():
        found += [p.name for p in folder.parent.iterdir() if p.name.startswith(".")]
    if folder.is_dir():
        found += [
            str(p.relative_to(folder))
            for p in folder.rglob(".*")
            if p.name.startswith(".")
        ]
    return sorted(found)


def classify(folder: Path, old: dict, new: dict) -> str:
    sig = signature(folder)
    if sig == old:
        return "old"
    if sig == new:
        return "new"
    if not sig:
        return "none"
    return "mixed"


# --------------------------------------------------------------------------- #
# Trials
# --------------------------------------------------------------------------- #


@dataclass
class Trial:
    kind: str
    outcome: str  # old | new | none | mixed
    returncode: int
    leftovers: list
    stderr: str

    @property
    def clean_exit(self) -> bool:
        """One 'Error:' line at most, no traceback, nothing swallowed."""
        text = self.stderr
        return (
            "Traceback" not in text
            and "Exception ignored" not in text
            and sum(line.startswith("Error: ") for line in text.splitlines()) <= 1
        )


class Scenario:
    """An old complete result (case A) in ``out`` and a new case B to run over it."""

    def __init__(self, work: Path, code: Path = ROOT, *, n=(10, 40), steps=(3, 20)):
        work.mkdir(parents=True, exist_ok=True)
        self.work, self.code = work, code
        self.case_a = write_case(work, "a.toml", n[0], steps[0])
        self.case_b = write_case(work, "b.toml", n[1], steps[1])
        self.env = environment(code)
        self.sig_a = self._reference(self.case_a, "ref-a")
        self.sig_b = self._reference(self.case_b, "ref-b")

    def _reference(self, case: Path, name: str) -> dict:
        out = self.work / name
        proc = subprocess.run(
            command("run", "-q", case, "-o", out),
            env=self.env,
            cwd=self.work,  # python -m would import a package in the cwd
            preexec_fn=interactive_signals,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
        assert proc.returncode == 0, proc.stderr
        return signature(out)

    def write_time(self) -> float:
        """Seconds from B's last converged load step to the end of its run
        (the write phase; measured, since it depends on the machine's load)."""
        out = self.work / "timing"
        shutil.rmtree(out, ignore_errors=True)
        proc = subprocess.Popen(
            command("run", "-v", self.case_b, "-o", out),
            env=self.env,
            cwd=self.work,  # python -m would import a package in the cwd
            preexec_fn=interactive_signals,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        last = f"step {self._steps_b}/{self._steps_b} iteration"
        converged = None
        for line in proc.stderr:
            if line.startswith(last) and "iteration 0" not in line:
                converged = time.monotonic()
        proc.wait(timeout=TIMEOUT)
        return time.monotonic() - converged

    def fresh_old(self, name: str) -> Path:
        """A folder ``<work>/<name>/out`` holding the complete old result."""
        out = self.work / name / "out"
        shutil.copytree(self.work / "ref-a", out)
        return out

    def kill_while_writing(
        self, name: str, sig: int, delay: float, anchor: str = "converged"
    ) -> Trial:
        """Run B over A with --overwrite and send ``sig`` ``delay`` s after the
        ``anchor``: ``converged`` (B's last load step converged: its write
        phase begins) or ``h5`` (the temporary file of result.h5 appears, in
        the folder or in the staging folder beside it)."""
        out = self.fresh_old(name)
        verbose = "-v" if anchor == "converged" else "-q"
        proc = subprocess.Popen(
            command("run", verbose, self.case_b, "-o", out, "--overwrite"),
            env=self.env,
            cwd=self.work,  # python -m would import a package in the cwd
            preexec_fn=interactive_signals,
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            text=True,
        )
        if anchor == "converged":
            last = f"step {self._steps_b}/{self._steps_b} iteration"
            for line in proc.stderr:
                if line.startswith(last) and "iteration 0" not in line:
                    break
        else:
            temp, staging = f".result.h5.tmp-{proc.pid}", f".out.tmp-{proc.pid}"
            paths = (out / temp, out.parent / staging / temp)
            staged = out.parent / staging / "result.h5"  # renamed, not swapped
            while proc.poll() is None and not any(map(os.path.exists, paths)):
                if staged.exists():
                    break
                time.sleep(0.0001)
            else:
                if proc.poll() is not None:  # it ended before the anchor was seen
                    proc.wait()
                    return Trial("missed", "missed", proc.returncode, [], "")
        time.sleep(delay)
        proc.send_signal(sig)
        rest = proc.stderr.read()
        proc.wait(timeout=TIMEOUT)
        # the verbose log is not the fault's report: keep what follows it
        report = "".join(line for line in rest.splitlines(True) if "Error" in line)
        return Trial(
            f"{signal.Signals(sig).name}",
            classify(out, self.sig_a, self.sig_b),
            proc.returncode,
            leftovers(out),
            report
            + ("Traceback" if "Traceback" in rest else "")
            + ("Exception ignored" if "Exception ignored" in rest else ""),
        )

    @property
    def _steps_b(self) -> int:
        return int(re.search(r"steps = (\d+)", self.case_b.read_text()).group(1))

    def race(self, name: str, overwrite: tuple[bool, bool], stagger: float) -> Trial:
        """Runs of A and B started ``stagger`` s apart into one folder."""
        out = self.work / name / "out"
        out.parent.mkdir(parents=True)
        procs = []
        for case, force in zip((self.case_a, self.case_b), overwrite, strict=True):
            args = ["run", "-q", case, "-o", out] + (["--overwrite"] if force else [])
            procs.append(
                subprocess.Popen(
                    command(*args),
                    env=self.env,
                    cwd=self.work,
                    preexec_fn=interactive_signals,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.PIPE,
                    text=True,
                )
            )
            time.sleep(stagger)
        errs = [p.communicate(timeout=TIMEOUT)[1] for p in procs]
        outcome = classify(out, self.sig_a, self.sig_b)
        return Trial(
            f"race{''.join('o' if f else '-' for f in overwrite)}",
            outcome,
            max(p.returncode for p in procs),
            leftovers(out),
            "".join(errs),
        )


def tally(trials: list[Trial]) -> dict:
    """{kind: Counter of outcomes (+ 'leftovers', 'unclean exit')}."""
    table = collections.defaultdict(collections.Counter)
    for t in trials:
        table[t.kind][t.outcome] += 1
        if t.leftovers:
            table[t.kind]["leftovers"] += 1
        if not t.clean_exit:
            table[t.kind]["unclean exit"] += 1
        if t.returncode == 0 and t.kind.startswith("SIG") and t.outcome != "new":
            table[t.kind]["exit 0 without new result"] += 1
        table[t.kind][f"exit {t.returncode}"] += 1
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trials", type=int, default=24)
    parser.add_argument("--code", type=Path, default=ROOT)
    parser.add_argument(
        "--parts", default="kills,h5,races", help="comma-separated: kills,h5,races"
    )
    args = parser.parse_args()
    parts = args.parts.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        scenario = Scenario(Path(tmp) / "kills", args.code)
        trials = []
        for sig in (signal.SIGKILL, signal.SIGTERM, signal.SIGINT):
            if "kills" not in parts:
                break
            window = 1.2 * scenario.write_time()
            print(f"{signal.Signals(sig).name}: delays 0 to {window:.2f} s", flush=True)
            for k in range(args.trials):
                delay = window * k / max(args.trials - 1, 1)
                trials.append(scenario.kill_while_writing(f"{sig}-{k}", sig, delay))
        for k in range(args.trials if "h5" in parts else 0):
            # Ctrl-C in the first milliseconds of writing result.h5
            delay = 0.0005 * k
            trial = scenario.kill_while_writing(f"h5-{k}", signal.SIGINT, delay, "h5")
            trial.kind = f"SIGINT 0-{0.5 * (args.trials - 1):g} ms into result.h5"
            trials.append(trial)
        # two runs of about the same size, so that their writes overlap
        racing = Scenario(Path(tmp) / "races", args.code, n=(40, 40), steps=(19, 20))
        for k in range(args.trials if "races" in parts else 0):
            overwrite = [(False, False), (True, True), (False, True), (True, False)]
            trials.append(racing.race(f"race-{k}", overwrite[k % 4], 0.01 * (k // 4)))
        for kind, counts in tally(trials).items():
            print(
                f"{kind}: " + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items()))
            )


if __name__ == "__main__":
    main()
