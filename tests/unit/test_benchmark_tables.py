"""The tables of docs/performance/ are written by their benchmarks: each
benchmark's table writer, run here on a synthetic result, gives the cells
worked out by hand below; every table file in docs/performance/ has the
header its benchmark writes and a line saying where and when it was measured;
docs/performance.md links every file with the command that rewrites it."""

from __future__ import annotations

import importlib
import re
import sys

import pytest

from tests.support.golden import ROOT

BENCH = ROOT / "benchmarks"
DOCS = ROOT / "docs" / "performance"


@pytest.fixture(scope="module")
def bench():
    """Import a benchmark script by name, as `python benchmarks/NAME.py` does
    (its folder first on sys.path: the scripts import mdtable by basename)."""
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module
    finally:
        sys.path.remove(str(BENCH))


def rows_of(text: str) -> list[list[str]]:
    """The cells of every table row of a markdown text (separators left out;
    an escaped pipe, \\|, is part of a cell)."""
    return [
        [c.strip() for c in re.split(r"(?<!\\)\|", line.strip()[1:-1])]
        for line in text.splitlines()
        if line.startswith("|") and not set(line) <= set("|- ")
    ]


def tables_of(text: str) -> list[list[list[str]]]:
    """The tables of a markdown text, each as its rows of cells."""
    return [rows_of(block) for block in text.split("\n\n") if block.startswith("|")]


# the line under a table: "...; x86_64, 2 cores, 2026-11-21, load average 0.5-1.1."
MACHINE = re.compile(
    r"; [\w-]+, \d+ cores, \d{4}-\d\d-\d\d(, load average \d+\.\d(-\d+\.\d)?)?\.$"
)


def test_mdtable_writes_header_separator_rows_and_note(bench):
    md = bench("mdtable")
    text = md.table(["a", "b [s]"], [[1, "2.00"], ["x", 3.5]])
    assert text == "| a | b [s] |\n| --- | --- |\n| 1 | 2.00 |\n| x | 3.5 |\n"
    with pytest.raises(ValueError, match="2 cells"):
        md.table(["a", "b", "c"], [[1, 2]])
    note = md.note("Medians of 3", [1.04, 2.31, 1.5])
    assert note.startswith("\nMedians of 3; ")
    assert note.endswith(", load average 1.0-2.3.\n")
    assert MACHINE.search(note.strip())
    # one load value, or equal ones: a single number, not "1.5-1.5"
    assert md.note("x", [1.5, 1.52]).endswith(", load average 1.5.\n")
    assert "load average" not in md.note("errors only")


def test_mdtable_write_prints_and_writes(bench, tmp_path, capsys):
    md = bench("mdtable")
    path = tmp_path / "sub" / "t.md"
    md.write(path, "| a |\n")
    assert path.read_text() == "| a |\n"
    md.write(None, "| b |\n")
    assert "| a |" in capsys.readouterr().out


def test_startup_table(bench):
    startup = bench("startup")
    rows = {
        "auto": {
            "cold": [3.0, 1.0, 2.0],
            "warm": [0.7, 0.5, 0.6],
            "warm_cpu": [0.4, 0.6, 0.5],
        },
        "numba": {
            "cold": [10.0, 14.0, 12.5],
            "warm": [1.2, 1.3, 1.1],
            "warm_cpu": [1.0, 1.0, 2.0],
        },
    }
    text = startup.markdown("cases/x.toml", 3, rows, [0.8, 1.2])
    cells = rows_of(text)
    assert cells[1] == [
        "auto (the default)",
        "2.00 s (1.00, 3.00)",
        "0.60 s (0.50, 0.70)",
        "0.50 s",
    ]
    assert cells[2] == [
        "numba (forced)",
        "12.50 s (10.00, 14.00)",
        "1.20 s (1.10, 1.30)",
        "1.00 s",
    ]
    assert "medians of 3 runs" in text and MACHINE.search(text.strip())


def test_kernels_backend_table(bench):
    kb = bench("kernels_backend")
    row = {
        "case": "reservoir 50",
        "work": 3.6e7,
        "numpy_wall": 0.64,
        "numpy_cpu": 0.6,
        "numba_wall": 1.12,
        "numba_cpu": 1.2,
    }
    cells = rows_of(kb.markdown([row], 3, [1.0]))
    assert cells[1] == [
        "reservoir 50 x 50",
        "3.6e+07",
        "0.64 (0.60)",
        "1.12 (1.20)",
        "0.50",
    ]


def test_scaling_table(bench):
    scaling = bench("scaling")
    res = [
        {
            "n": 50,
            "config": "default",
            "runs": 3,
            "dofs": 6128,
            "wall": 0.6,
            "cpu": 0.61,
            "maxrss_mib": 116.2,
            "loads": [1.1],
            "threads": "T=1",
        },
        {
            "n": 50,
            "config": "pardiso",
            "runs": 3,
            "dofs": 6128,
            "wall": 0.9,
            "cpu": 0.9,
            "maxrss_mib": 120.0,
            "loads": [1.4],
            "threads": "T=1",
        },
        {
            "n": 50,
            "config": "floor_pardiso",
            "runs": 3,
            "dofs": 6000,
            "wall": 0.3,
            "cpu": 0.8,
            "maxrss_mib": 103.0,
            "loads": [1.2],
            "threads": "T=1",
        },
        {"n": 50, "config": "floor_superlu", "error": "killed"},
    ]
    text = scaling.table(res)
    cells = rows_of(text)
    assert cells[0] == scaling.HEADER
    assert cells[1][:9] == [
        "50",
        "6,128",
        "0.60",
        "0.90",
        "0.30",
        "killed",
        "2.00",
        "3.00",
        "-",
    ]
    assert cells[1][9:] == ["0.6 / 0.9 / 0.8", "116 / 120 / 103"]
    assert "Medians of 3 whole processes" in text and "T=1" in text
    assert text.rstrip().endswith("load average 1.1-1.4.")


def test_depletion_table(bench):
    dep = bench("depletion")
    rows = {"run": [(3.0, 2.0), (3.2, 2.0)], "deplete": [(4.0, 2.4), (3.8, 3.0)]}
    text = dep.markdown("c.toml", rows, [4.1])
    assert rows_of(text)[1:] == [
        ["`xfemslip run`", "3.10", "2.00"],
        ["`xfemslip deplete`", "3.90", "2.70"],
    ]
    # CPU ratios of the pairs 1.2 and 1.5: median 1.35
    assert "ratio 1.35 (1.20 to 1.50 over the 2 pairs)" in text


def test_hard_inputs_and_memory_tables(bench):
    hard = bench("hard_inputs")
    text = hard.markdown([("arc-20k", 0, 3.104, 101.6)], 60.0, [2.7])
    assert rows_of(text)[1] == ["arc of 20,000 points", "0", "3.10", "102"]
    mem = bench("memory_estimate")
    text = mem.markdown([("dfn-60-30x30", 1, [161.6, 380.4, 386.0], 360.2)], [1.5])
    assert rows_of(text)[1] == [
        "60 fractures, 30 x 30 (exit 1)",
        "162",
        "380",
        "386",
        "360",
    ]


def test_sweep_and_auto_choice_tables(bench):
    sw = bench("sweep_parallel")
    times = {
        "--jobs 1": [13.0, 12.0, 14.0],
        "--jobs 2": [8.0, 6.0, 7.0],
        "Dask, 2 workers": [9.0, 6.5, 6.0],
    }
    text = sw.markdown([{"label": "x", "cases": 31, "times": times}], 3, "1.0", [1.0])
    assert rows_of(text)[1] == [
        "x, 31 cases",
        "13.00 s (1.00)",
        "7.00 s (1.86)",
        "6.50 s (2.00)",
    ]
    assert "first run, importing xfemslip: 9.00 s" in text
    ac = bench("auto_choice")
    row = {
        "source": "dfn",
        "mesh": 200,
        "tip": "ramp",
        "fractures": 100,
        "n_free": 101747,
        "enriched_share": 0.2081,
        "band_share": 0.7182,
        "systems": 8,
        "run_finished": "stopped",
        "superlu": 13.29,
        "amg": 14.38,
        "ratio": 14.38 / 13.29,
        "superlu_factorizations": 8,
        "amg_krylov": 0,
        "amg_fallbacks": 1,
        "runs": {"amg": [1.0, 2.0]},
    }
    assert rows_of(ac.markdown([row]))[1] == [
        "dfn",
        "200²",
        "ramp",
        "100",
        "101,747",
        "20.8 %",
        "71.8 %",
        "8+",
        "13.29 s",
        "14.38 s",
        "1.08",
        "8",
        "0, fell back",
    ]


def test_contact_patch_and_screen_tables(bench):
    cp = bench("contact_patches")
    text = cp.markdown(
        (40, 80),
        {1.5: [(0.008, 0.0017, 2), (0.0041, 0.0031, 2)]},
        {100.0: ((0.00389, 2), (4.2e-5, 1))},
    )
    cells = rows_of(text)
    assert cells[0][1:] == [
        "a/10: L2 slip error, p_N oscillation",
        "a/20: L2 slip error, p_N oscillation",
    ]
    assert cells[1] == ["1.5", "0.80 %, 0.17 %", "0.41 %, 0.31 %"]
    assert cells[3] == ["100", "0.389 %, 2", "4.2e-05, 1"]
    unc = bench("uncertainty")
    text = unc.screen_markdown([("s", 10000, 0.0045, 0.04, 0.018)], [1.5])
    assert rows_of(text)[1] == ["s", "10,000", "4.5", "40.0", "18"]


def test_continuation_cost_table(bench):
    cost = bench("continuation_cost")
    rows = [
        {"size": 12.5, "states": 21, "deplete": 31.04, "run": 10.0},
        {"size": 3.125, "states": 34, "deplete": 120.0, "run": 40.0},
    ]
    text = cost.markdown(rows, [2.0, 2.5], 3)
    assert rows_of(text)[1:] == [
        ["12.5", "21", "31.0", "10.0", "3.1"],
        ["3.125", "34", "120.0", "40.0", "3.0"],
    ]
    assert "Medians of 3 whole processes" in text
    assert text.rstrip().endswith("load average 2.0-2.5.")


def test_network_floor_table(bench):
    nf = bench("network_floor")
    rows = [
        {
            "config": "floor",
            "wall": 3.0,
            "cpu": 2.0,
            "rss_mib": 250.0,
            "load": 1.0,
            "dofs": 80600,
            "run": 0,
        },
        {
            "config": "floor",
            "wall": 2.0,
            "cpu": 2.0,
            "rss_mib": 260.0,
            "load": 1.2,
            "dofs": 80600,
            "run": 1,
        },
        {
            "config": "pardiso",
            "wall": 25.0,
            "cpu": 20.0,
            "rss_mib": 1800.0,
            "load": 1.1,
            "dofs": 147524,
            "newton": [11, 6],
            "run": 0,
        },
        {
            "config": "pardiso",
            "wall": 15.0,
            "cpu": 10.0,
            "rss_mib": 1700.0,
            "load": 1.3,
            "dofs": 147524,
            "newton": [11, 6],
            "run": 1,
        },
    ]
    args = type("A", (), {"count": 100, "seed": 1, "n": 200, "runs": 2})()
    text = nf.markdown(rows, ["floor", "pardiso"], args)
    assert rows_of(text)[0] == nf.HEADER
    assert rows_of(text)[1:] == [
        [nf.LABELS["floor"], "2.50 (2.00, 3.00)", "1.0", "2.0", "260", "-"],
        [
            nf.LABELS["pardiso"],
            "20.00 (15.00, 25.00)",
            "8.0",
            "15.0",
            "1,800",
            "11 + 6",
        ],
    ]
    assert "147524 dofs" in text and "medians of 2 whole processes" in text
    assert text.rstrip().endswith("load average 1.0-1.3.")


def test_network_floor_trees_table(bench):
    """--trees: each configuration but the floor once per tree, in order,
    labelled with its tree; the ratios to the one floor."""
    nf = bench("network_floor")
    configs = nf.expanded(["floor", "pardiso", "default"], ["/w/base", "."])
    assert configs == [
        "floor",
        "pardiso@/w/base",
        "pardiso@.",
        "default@/w/base",
        "default@.",
    ]
    assert nf.split("default@/w/base") == ("default", "/w/base")
    assert nf.split("floor") == ("floor", None)
    assert nf.expanded(["floor", "pardiso"], None) == ["floor", "pardiso"]

    def row(config, wall):
        return {
            "config": config,
            "wall": wall,
            "cpu": wall,
            "rss_mib": 100.0,
            "load": 1.0,
            "dofs": 80600 if config == "floor" else 147524,
            "newton": None if config == "floor" else [11, 6],
            "run": 0,
        }

    rows = [row("floor", 2.0), row("pardiso@/w/base", 8.0), row("pardiso@.", 6.0)]
    args = type("A", (), {"count": 100, "seed": 1, "n": 200, "runs": 1})()
    text = nf.markdown(rows, ["floor", "pardiso@/w/base", "pardiso@."], args)
    body = rows_of(text)[1:]
    assert [r[0] for r in body] == [
        nf.LABELS["floor"],
        nf.LABELS["pardiso"] + ", tree `/w/base`",
        nf.LABELS["pardiso"] + ", tree `.`",
    ]
    assert [r[2] for r in body] == ["1.0", "4.0", "3.0"]
    assert "147524 dofs" in text


# docs/performance/<file>: the benchmark that writes it, and a synthetic
# result that gives the header its writer prints
def _headers(bench) -> dict[str, list[str]]:
    scaling, dep = bench("scaling"), bench("depletion")
    startup, kb = bench("startup"), bench("kernels_backend")
    one_pair = {"run": [(1, 1)], "deplete": [(1, 1)]}
    return {
        "startup.md": rows_of(startup.markdown("c", 1, {}, []))[0],
        "kernels_backend.md": rows_of(kb.markdown([], 1, []))[0],
        "scaling.md": scaling.HEADER,
        "depletion.md": rows_of(dep.markdown("c", one_pair, []))[0],
        "hard_inputs.md": rows_of(bench("hard_inputs").markdown([], 1, []))[0],
        "memory_estimate.md": rows_of(bench("memory_estimate").markdown([], []))[0],
        "sweep_parallel.md": ["sweep", *bench("sweep_parallel").MODES],
        "auto_choice.md": bench("auto_choice").HEADER,
        "contact_patches.md": rows_of(
            bench("contact_patches").markdown((40, 80, 160), {}, {})
        )[0],
        "uncertainty_screen.md": rows_of(bench("uncertainty").screen_markdown([], []))[
            0
        ],
        "accuracy_vs_time.md": rows_of(bench("accuracy_vs_time").md_tips([]))[0],
        "continuation_cost.md": rows_of(bench("continuation_cost").markdown([], [], 1))[
            0
        ],
        "network_floor.md": bench("network_floor").HEADER,
    }


def test_every_table_file_is_in_its_benchmarks_format(bench):
    headers = _headers(bench)
    for name, header in headers.items():
        text = (DOCS / name).read_text(encoding="utf-8")
        tables = tables_of(text)
        assert tables[0][0] == header, name
        for rows in tables:  # every row as wide as its table's header
            assert len(rows) > 1, name
            assert {len(r) for r in rows} == {len(rows[0])}, name
        assert MACHINE.search(text.strip()), name


def test_performance_md_links_every_table_with_its_command():
    doc = (ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    for path in sorted(DOCS.glob("*.md")):
        assert f"](performance/{path.name})" in doc, path.name
        if path.name != "stability.md":  # stability.py writes it unasked
            assert f"--markdown docs/performance/{path.name}" in doc, path.name
    # no table typed into the page itself: its only table rows are the rule
    # of the automatic solver choice (not a measurement)
    rows = [line for line in doc.splitlines() if line.startswith("|")]
    assert all("dofs" in r or "---" in r or "50,000" in r for r in rows), rows
