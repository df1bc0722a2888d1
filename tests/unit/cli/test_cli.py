"""The command line: exit codes 0/1/2/130 and one-line error messages."""

from __future__ import annotations

import logging
import sys
import types
from pathlib import Path

import pytest
from click.testing import CliRunner

from xfemslip import __version__
from xfemslip.case import build
from xfemslip.cli import cli
from xfemslip.errors import ConvergenceError, OutputError, UsageError

VALID = {
    "name": "tiny",
    "domain": {"size": [1.0, 1.0]},
    "mesh": {"elements": [4, 4]},
    "material": {"E": 1.0e9, "nu": 0.25, "model": "plane_strain"},
    "loading": {"steps": 1},
    "boundary": {
        "bottom": {"uy": 0.0},
        "top": {"uy": -0.001},
        "left": "free",
        "right": "free",
    },
}
VALID_CASE = build.case_text(VALID)


@pytest.fixture
def case_file(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(VALID_CASE)
    return path


def _stderr_lines(result) -> list[str]:
    return result.stderr.splitlines()


def _assert_one_error_line(result) -> str:
    lines = _stderr_lines(result)
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("Error: "), lines[0]
    assert "Traceback" not in result.stderr
    return lines[0]


# --------------------------------------------------------------------------- info


def test_info_prints_versions(runner):
    """Every dependency and optional package with its installed version."""
    import importlib.metadata

    result = runner.invoke(cli, ["info"])
    assert result.exit_code == 0, result.output
    for name in (
        "xfemslip",
        "python",
        "numpy",
        "scipy",
        "numba",
        "h5py",
        "meshio",
        "tomli-w",
        "pyamg",
        "matplotlib",
        "dask",
        "distributed",
        "pypardiso",
        "vtk",
        "threading layer",
        "NUMBA_NUM_THREADS",
        "cache dir",
    ):
        assert name in result.stdout
    assert __version__ in result.stdout
    lines = {ln.split()[0]: ln.split()[-1] for ln in result.stdout.splitlines() if ln}
    for name in ("numpy", "matplotlib", "dask"):
        assert lines[name] == importlib.metadata.version(name)


def test_version_option(runner):
    result = runner.invoke(cli, ["--version"])
    assert result.exit_code == 0
    assert __version__ in result.stdout


# --------------------------------------------------------------------------- check


def test_check_valid_case(runner, case_file):
    result = runner.invoke(cli, ["check", str(case_file)])
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip()


def test_check_invalid_case_names_the_key(runner, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(build.case_text(build.with_keys(VALID, **{"material.nu": 0.7})))
    result = runner.invoke(cli, ["check", str(path)])
    assert result.exit_code == 2
    line = _assert_one_error_line(result)
    assert "nu" in line and "bad.toml" in line


def test_check_missing_file(runner, tmp_path):
    result = runner.invoke(cli, ["check", str(tmp_path / "missing.toml")])
    assert result.exit_code == 2
    assert "missing.toml" in _assert_one_error_line(result)


def test_run_missing_file(runner, tmp_path):
    result = runner.invoke(cli, ["run", str(tmp_path / "missing.toml")])
    assert result.exit_code == 2
    _assert_one_error_line(result)


# --------------------------------------------------------------------------- run


class FakeSimulation:
    """Stands in for ``xfemslip.simulation`` and ``load_case``; records calls."""

    def __init__(self, outcome=None):
        self.outcome = outcome
        self.calls = []

    def load_case(self, path):
        output = types.SimpleNamespace(directory=Path("out/tiny"))
        return types.SimpleNamespace(name="tiny", path=Path(path), output=output)

    def run_case(self, spec, out_dir=None, *, overwrite=False):
        self.calls.append((spec, out_dir, overwrite))
        log = logging.getLogger("xfemslip.simulation")
        log.debug("debug detail")
        log.info("step 1: converged")
        log.warning("pinned x at (0, 0)")
        if isinstance(self.outcome, BaseException):
            raise self.outcome
        return types.SimpleNamespace(
            out_dir=Path(out_dir),
            converged=True,
            load_steps=1,
            newton_iterations=4,
            iterations_per_step=[4],
            wall_time_s=0.42,
            steps=[],  # no fields: the run's event table is left out
        )


@pytest.fixture
def fake(monkeypatch) -> FakeSimulation:
    """Insert a fake ``xfemslip.simulation`` module and a fake ``load_case``."""
    sim = FakeSimulation()
    module = types.ModuleType("xfemslip.simulation")
    module.run_case = sim.run_case
    monkeypatch.setitem(sys.modules, "xfemslip.simulation", module)
    monkeypatch.setattr("xfemslip.case.load_case", sim.load_case, raising=False)
    # the fake spec has only what run reads; it has nothing to warn about
    monkeypatch.setattr(
        "xfemslip.case.plausibility.plausibility_warnings", lambda spec: []
    )
    return sim


def test_run_success_prints_summary(runner, fake, case_file):
    result = runner.invoke(cli, ["run", str(case_file)])
    assert result.exit_code == 0, result.stderr
    assert result.stdout.splitlines() == [
        "tiny: converged in 1 step(s), 4 Newton iterations, 0.42 s -> "
        + str(Path("out/tiny"))
    ]
    ((spec, out_dir, overwrite),) = fake.calls
    # without -o: output.directory of the case
    assert spec.name == "tiny" and out_dir == Path("out/tiny") and overwrite is False


def test_run_passes_output_and_overwrite(runner, fake, case_file, tmp_path):
    out = tmp_path / "results"
    result = runner.invoke(cli, ["run", str(case_file), "-o", str(out), "--overwrite"])
    assert result.exit_code == 0, result.stderr
    ((_, out_dir, overwrite),) = fake.calls
    assert out_dir == out and overwrite is True
    assert str(out) in result.stdout


def test_run_logging_levels(runner, fake, case_file):
    default = runner.invoke(cli, ["run", str(case_file)])
    assert _stderr_lines(default) == [
        "step 1: converged",
        "WARNING: pinned x at (0, 0)",
    ]
    quiet = runner.invoke(cli, ["run", "-q", str(case_file)])
    assert _stderr_lines(quiet) == ["WARNING: pinned x at (0, 0)"]
    verbose = runner.invoke(cli, ["run", "-v", str(case_file)])
    assert "debug detail" in _stderr_lines(verbose)
    both = runner.invoke(cli, ["run", "-v", "-q", str(case_file)])
    assert both.exit_code == 2


@pytest.mark.parametrize(
    ("error", "code"),
    [
        (
            ConvergenceError(
                "step 2: no convergence after 30 iterations\n(eta = 1e-3)",
                step=2,
                iteration=30,
                residual=1e-3,
            ),
            1,
        ),
        (OutputError("cannot write out/tiny/result.h5: disk full"), 1),
        (UsageError("out/tiny exists; use --overwrite"), 2),
    ],
)
def test_run_library_errors(runner, fake, case_file, error, code):
    fake.outcome = error
    result = runner.invoke(cli, ["run", "-q", str(case_file)])
    assert result.exit_code == code
    lines = _stderr_lines(result)
    assert lines[-1] == "Error: " + " ".join(str(error).split())
    assert "Traceback" not in result.stderr
    assert not result.stdout


def test_run_debug_shows_traceback(runner, fake, case_file):
    fake.outcome = ConvergenceError("step 1 failed", step=1, iteration=30, residual=1.0)
    result = runner.invoke(cli, ["run", "-q", "--debug", str(case_file)])
    assert result.exit_code == 1
    assert "Traceback" in result.stderr
    assert _stderr_lines(result)[-1] == "Error: step 1 failed"


def test_run_interrupted(runner, fake, case_file):
    fake.outcome = KeyboardInterrupt()
    result = runner.invoke(cli, ["run", "-q", str(case_file)])
    assert result.exit_code == 130
    assert _stderr_lines(result)[-1].startswith("Error: interrupted (SIGINT)")
    assert "Traceback" not in result.stderr


def test_run_programming_error_propagates(runner, fake, case_file):
    fake.outcome = ValueError("a bug")
    result = runner.invoke(cli, ["run", "-q", str(case_file)])
    assert isinstance(result.exception, ValueError)
    assert result.exit_code != 0


# --- input that validates key by key but cannot be built: exit 2, no output ---


def _geometry_case(fractures, left_ux) -> str:
    """A square fixed at the bottom with fractures on the polylines
    ``fractures`` and ux = ``left_ux`` on the left edge."""
    fracture = {"friction": 0.1, "kn": 5.0e12, "kt": 5.0e12}
    return build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [10, 10]},
            "material": {"E": 5.0e9, "nu": 0.3},
            "fractures": [dict(fracture, points=p) for p in fractures],
            "boundary": {
                "bottom": {"ux": 0.0, "uy": 0.0},
                "left": {"ux": left_ux},
                "top": {"uy": -0.001},
            },
        }
    )


@pytest.mark.parametrize(
    ("fractures", "left_ux", "words"),
    [
        (
            [[[0.2, 0.2], [0.8, 0.8]], [[0.5, 0.5], [0.9, 0.9]]],
            0.0,
            "fractures[0] and fractures[1] overlap",
        ),
        (
            [[[0.2, 0.2], [0.8, 0.8]]],
            0.01,
            "boundary.bottom and boundary.left prescribe different ux",
        ),
    ],
    ids=["overlapping-fractures", "corner-conflict"],
)
@pytest.mark.parametrize("command", ["check", "run"])
def test_geometry_errors_are_bad_input(tmp_path, command, fractures, left_ux, words):
    path = tmp_path / "geo.toml"
    path.write_text(_geometry_case(fractures, left_ux))
    out = tmp_path / "out"
    args = [command, str(path)] + (["-o", str(out), "-q"] if command == "run" else [])
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 2, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error: ")
    assert str(path) in lines[0] and words in lines[0]
    assert not out.exists()


def test_overwrite_leaves_no_file_of_the_earlier_run(tmp_path):
    """5 load steps (pvd + steps/), then 1 step without VTU into the same folder
    with --overwrite: only result.h5 of the new run is left."""
    case = tmp_path / "c.toml"

    def text(steps, formats):
        return build.case_text(
            {
                "domain": {"size": [1.0, 1.0]},
                "mesh": {"elements": [6, 6]},
                "material": {"E": 1.0e9, "nu": 0.25},
                "fractures": [
                    {
                        "points": [[0.2, 0.3], [0.8, 0.7]],
                        "friction": 0.3,
                        "kn": 1.0e12,
                        "kt": 1.0e12,
                    }
                ],
                "loading": {"steps": steps},
                "boundary": {"bottom": {"ux": 0.0, "uy": 0.0}, "top": {"uy": -0.001}},
                "output": {"formats": formats},
            }
        )

    out = tmp_path / "out"
    case.write_text(text(5, ["h5", "vtu"]))
    first = CliRunner().invoke(cli, ["run", "-q", str(case), "-o", str(out)])
    assert first.exit_code == 0, first.output
    assert (out / "result.pvd").exists() and (out / "steps").is_dir()
    case.write_text(text(1, ["h5"]))
    again = CliRunner().invoke(cli, ["run", "-q", str(case), "-o", str(out)])
    assert again.exit_code == 2  # refused without --overwrite
    second = CliRunner().invoke(
        cli, ["run", "-q", "--overwrite", str(case), "-o", str(out)]
    )
    assert second.exit_code == 0, second.output
    assert sorted(p.name for p in out.iterdir()) == ["result.h5"]


# ------------------------------------------------------------------- environment


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [
        ("NUMBA_NUM_THREADS", "0", "an integer >= 1"),
        ("NUMBA_NUM_THREADS", "abc", "an integer >= 1"),
        ("NUMBA_DISABLE_JIT", "yes", "an integer (0 or 1)"),
        ("XFEMSLIP_KERNELS", "fortran", "numba, numpy or auto"),
        ("XFEMSLIP_MEMORY_LIMIT", "10Q", "a number of bytes > 0"),
        ("XFEMSLIP_MEMORY_LIMIT", "nan", "a number of bytes > 0"),
    ],
)
@pytest.mark.parametrize("command", ["info", "check"])
def test_bad_environment_is_one_line(runner, case_file, command, name, value, expected):
    args = [command] + ([str(case_file)] if command == "check" else [])
    result = runner.invoke(cli, args, env={name: value})
    assert result.exit_code == 2
    line = _assert_one_error_line(result)
    assert line.startswith(f"Error: environment variable {name} = {value!r}: ")
    assert f": expected {expected}" in line
    assert not result.stdout


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("NUMBA_NUM_THREADS", "2"),
        ("XFEMSLIP_KERNELS", " NumPy "),
        ("XFEMSLIP_MEMORY_LIMIT", "1.5G"),
        ("XFEMSLIP_MEMORY_LIMIT", ""),
    ],
)
def test_good_environment_is_accepted(runner, case_file, name, value):
    result = runner.invoke(cli, ["check", str(case_file)], env={name: value})
    assert result.exit_code == 0, result.stderr


def test_numba_threads_zero_in_a_fresh_interpreter(tmp_path):
    """Numba reads NUMBA_NUM_THREADS when it is imported (ValueError at 0):
    `info`, which imports it, must refuse before that, in one line."""
    import os
    import subprocess

    env = dict(os.environ, NUMBA_NUM_THREADS="0")
    proc = subprocess.run(
        [sys.executable, "-m", "xfemslip", "info"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "Error: environment variable NUMBA_NUM_THREADS = '0': expected an integer "
        ">= 1 (Numba's thread count)"
    ]


# ----------------------------------------------------------------------- options


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["run", "--bogus", "CASE"], "No such option '--bogus'"),
        (["run"], "Missing argument 'CASE'"),
        (["frobnicate"], "No such command 'frobnicate'"),
        (["run", "CASE", "-o", "OUT/file.txt"], "Directory"),
        (["run", "CASE", "-o", ""], "the path is empty"),
        (["run", "CASE", "-o", "a\0b"], "contains a NUL byte"),
        (["run", "CASE", "-o", "p" * 256], "has a part of 256 bytes"),
        (["run", "ca\0se.toml"], "contains a NUL byte"),
        (["screen", "--stress", "nan", "1", "0", "--friction", "0.5"], "nan"),
        (["screen", "--stress", "-1", "-2", "0", "--friction", "inf"], "inf"),
        (
            [
                "screen",
                "--stress",
                "-1",
                "-2",
                "0",
                "--friction",
                "0.5",
                "--step",
                "nan",
            ],
            "--step",
        ),
        (["plot", "CASE", "--dpi", "1e9"], "--dpi"),
        (["dfn", "CASE", "--plot", "net.xyz"], "the suffix must be one of"),
        (["deplete", "CASE", "--tolerance", "nan"], "--tolerance"),
    ],
    ids=lambda v: "-".join(v) if isinstance(v, list) else None,
)
def test_usage_errors_are_one_line_before_any_work(runner, case_file, args, words):
    (case_file.parent / "file.txt").write_text("x")
    args = [
        a.replace("CASE", str(case_file)).replace("OUT", str(case_file.parent))
        for a in args
    ]
    result = runner.invoke(cli, args)
    assert result.exit_code == 2, result.output
    line = _assert_one_error_line(result)
    assert words in line, line
    assert line.endswith("--help')")  # where to look for the usage
    assert sorted(p.name for p in case_file.parent.iterdir()) == [
        "file.txt",
        "tiny.toml",
    ]


def test_group_without_command_still_prints_help(runner):
    result = runner.invoke(cli, [])
    assert "Commands:" in result.output


def test_deplete_names_pore_pressure_change_zero(runner, tmp_path):
    path = tmp_path / "dep.toml"
    path.write_text(
        build.case_text(
            dict(
                VALID,
                name=None,
                pore_pressure={"initial": 0.0, "change": -0.0},
                fractures=[{"points": [[0.2, 0.3], [0.8, 0.7]], "friction": 0.5}],
            )
        )
    )
    out = str(tmp_path / "out")
    result = runner.invoke(cli, ["deplete", "-q", str(path), "-o", out])
    assert result.exit_code == 2
    line = _assert_one_error_line(result)
    assert line.startswith(f"Error: {path}: pore_pressure.change")
    assert "--tolerance" not in line
    assert not (tmp_path / "out").exists()
