"""[network]: CSV of segments (round trip, numbering, every error path) and
the validation of [network.generate]."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from xfemslip.case import build, describe, load_case
from xfemslip.cli import cli
from xfemslip.errors import CaseError
from xfemslip.geometry.dfn import segments_csv_text

HEAD = {
    "domain": {"size": [2.0, 1.0]},
    "mesh": {"elements": [20, 10]},
    "material": {"E": 5.0e9, "nu": 0.3},
    "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6}},
    "boundary": {"bottom": {"uy": 0.0}, "top": "traction"},
}
INLINE = {"points": [[0.2, 0.8], [0.6, 0.9]], "friction": 0.4}


def _case(tmp_path, network=None, csv: str | None = None, inline=INLINE):
    """Write case.toml (+ seg.csv) into tmp_path; return the case path.
    ``network`` is the [network] table, ``inline`` the one [[fractures]]
    table (None: none)."""
    if csv is not None:
        (tmp_path / "seg.csv").write_text(csv, encoding="utf-8")
    path = tmp_path / "case.toml"
    fractures = None if inline is None else [inline]
    text = build.case_text(dict(HEAD, fractures=fractures, network=network))
    path.write_text(text, encoding="utf-8")
    return path


def _problems(tmp_path, network, csv=None, inline=INLINE) -> str:
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, network, csv, inline))
    return str(info.value)


FILE = {"file": "seg.csv", "friction": 0.6}


def test_csv_round_trip_and_numbering(tmp_path):
    rng = np.random.default_rng(0)
    # 25 two-segment polylines with random ends inside the domain, one per id
    a = rng.uniform([0.05, 0.05], [1.95, 0.95], size=(25, 2))
    b = a + rng.uniform(0.01, 0.05, size=(25, 2))
    c = b + np.array([0.03, -0.01])
    friction = rng.uniform(0.1, 0.9, 25)
    a, b, c, friction = (v.tolist() for v in (a, b, c, friction))  # plain reprs
    rows = ["fracture,x0,y0,x1,y1,friction,kn"]
    for i in range(25):
        kn = "" if i % 2 else repr(1e12 + i)
        rows.append(
            f"F{i},{a[i][0]!r},{a[i][1]!r},{b[i][0]!r},{b[i][1]!r},{friction[i]!r},{kn}"
        )
        rows.append(f"F{i},{b[i][0]!r},{b[i][1]!r},{c[i][0]!r},{c[i][1]!r},,")
    spec = load_case(_case(tmp_path, FILE, "\n".join(rows)))
    # inline first (index 0), then the file's fractures in order of first row
    assert [f.index for f in spec.fractures] == list(range(26))
    assert spec.fractures[0].source == "" and spec.fractures[0].friction == 0.4
    for i, f in enumerate(spec.fractures[1:]):
        np.testing.assert_array_equal(f.points, [a[i], b[i], c[i]])  # bitwise
        assert f.friction == friction[i]
        assert f.kn == (None if i % 2 else 1e12 + i)
        assert f.kt is None and f.cohesion == 0.0
        assert (
            f.source
            == f"network.file seg.csv: fracture 'F{i}', lines {2 + 2 * i}, {3 + 2 * i}"
        )
    # export -> read back: the same fractures, bitwise
    (tmp_path / "seg.csv").write_text(segments_csv_text(spec.fractures[1:]))
    again = load_case(tmp_path / "case.toml")
    for f, g in zip(spec.fractures, again.fractures, strict=True):
        np.testing.assert_array_equal(f.points, g.points)
        assert (f.friction, f.cohesion, f.kn, f.kt) == (
            g.friction,
            g.cohesion,
            g.kn,
            g.kt,
        )
    text = describe(spec)
    assert "fractures: 26 ([[fractures]] 1, network.file 25)" in text
    assert "[25] " in text and "fracture 'F24', lines 50, 51" in text


def test_rows_without_id_are_single_fractures_and_defaults_apply(tmp_path):
    csv = "x1,y1,x0,y0,cohesion\n0.5,0.5,0.1,0.1,\n\n# comment\n1.5,0.5,1.1,0.1,2e5\n"
    spec = load_case(_case(tmp_path, {**FILE, "kt": 3e11}, csv, inline=None))
    assert len(spec.fractures) == 2
    np.testing.assert_array_equal(spec.fractures[1].points, [[1.1, 0.1], [1.5, 0.5]])
    assert [f.cohesion for f in spec.fractures] == [0.0, 2e5]
    assert [f.kt for f in spec.fractures] == [3e11, 3e11]
    assert [f.friction for f in spec.fractures] == [0.6, 0.6]
    assert spec.fractures[1].source == "network.file seg.csv: line 5"


CSV_ERRORS = [
    ("x0,y0,x1\n0,0,1\n", "seg.csv line 1: missing column(s) y1"),
    (
        "x0,y0,x1,y1,frction\n0,0,1,1,0.3\n",
        "unknown column 'frction'; did you mean 'friction'?",
    ),
    ("x0,y0,x1,y1,x0\n0,0,1,1,0\n", "column 'x0' appears twice"),
    ("", "seg.csv line 1: empty file"),
    ("x0,y0,x1,y1\n", "seg.csv: no segment rows after the header"),
    (
        "x0,y0,x1,y1\n0.1,0.1,0.5\n",
        "seg.csv line 2: expected 4 values (x0,y0,x1,y1), got 3",
    ),
    ("x0,y0,x1,y1\n0.1,abc,0.5,0.5\n", "seg.csv line 2: y0 is not a number: 'abc'"),
    ("x0,y0,x1,y1\n0.1,0.1,nan,0.5\n", "seg.csv line 2: x1 must be finite, got 'nan'"),
    ("x0,y0,x1,y1\n0.1,0.1,0.5,inf\n", "seg.csv line 2: y1 must be finite, got 'inf'"),
    ("x0,y0,x1,y1\n0.1,,0.5,0.5\n", "seg.csv line 2: y0 is empty"),
    ("x0,y0,x1,y1\n0.1,0.2,0.1,0.2\n", "seg.csv line 2: zero-length segment"),
    (
        "x0,y0,x1,y1,friction\n0.1,0.1,0.5,0.5,-0.1\n",
        "seg.csv line 2: friction must be >= 0, got -0.1",
    ),
    ("x0,y0,x1,y1,kn\n0.1,0.1,0.5,0.5,0\n", "seg.csv line 2: kn must be > 0, got 0.0"),
    (
        "x0,y0,x1,y1\n3.1,0.1,3.5,0.5\n",
        "seg.csv line 2: lies outside the domain [0, 2] x [0, 1]",
    ),
    (
        "fracture,x0,y0,x1,y1\na,0.1,0.1,0.5,0.5\na,0.6,0.5,0.9,0.5\n",
        "seg.csv line 3: fracture 'a' continues at (0.6, 0.5) but its segment on "
        "line 2 ends at (0.5, 0.5)",
    ),
    (
        "fracture,x0,y0,x1,y1,friction\na,0.1,0.1,0.5,0.5,0.3\na,0.5,0.5,0.9,0.5,0.4\n",
        "seg.csv lines 2 and 3: fracture 'a' has friction 0.3 and 0.4; "
        "its rows must agree",
    ),
    (
        "fracture,x0,y0,x1,y1\na,0.1,0.1,0.5,0.5\na,0.5,0.5,0.5,0.1\na,0.5,0.1,0.1,0.5\n",
        "seg.csv lines 2, 3, 4: self-intersecting polyline",
    ),
]


@pytest.mark.parametrize(("csv", "expected"), CSV_ERRORS)
def test_csv_errors_name_file_line_and_column(tmp_path, csv, expected):
    message = _problems(tmp_path, FILE, csv)
    assert message.startswith(f"{tmp_path / 'case.toml'}: network.file: ")
    assert expected in message
    assert "\n" not in message


def test_csv_errors_are_collected_and_capped(tmp_path):
    csv = "x0,y0,x1,y1\n" + "".join(f"0.1,x{i},0.5,0.5\n" for i in range(15))
    message = _problems(tmp_path, FILE, csv)
    assert "11 problems" in message and "... and 5 more rows" in message


def test_missing_file_and_friction(tmp_path):
    assert "network.file: cannot read" in _problems(tmp_path, {"file": "no.csv"})
    message = _problems(tmp_path, {"file": "seg.csv"}, "x0,y0,x1,y1\n0.1,0.1,0.5,0.5\n")
    assert (
        "seg.csv line 2: no friction: give it in a friction column or as "
        "network.friction" in message
    )


GENERATE = {
    "friction": 0.5,
    "generate": {
        "seed": 3,
        "count": 5,
        "intersections": "avoid",
        "orientation": {"distribution": "uniform"},
        "length": {"distribution": "constant", "value": 0.2},
    },
}


def _network(**keys):
    """GENERATE with the values at dotted key paths set (None removes one)."""
    return build.with_keys(GENERATE, **keys)


GENERATE_ERRORS = [
    ({"generate.seed": -1}, "network.generate.seed: must be >= 0, got -1"),
    ({"generate.p21": 2.0}, "give exactly one of count, p20"),
    (
        {"generate.count": None},
        "network.generate.count: give exactly one of count, p20",
    ),
    (
        {"generate.orientation.kappa": 2.0},
        'orientation.kappa: not used with distribution = "uniform"',
    ),
    (
        {"generate.orientation": {"distribution": "von_mises", "mean": 10.0}},
        "orientation.kappa: required key missing",
    ),
    (
        {"generate.orientation": {"distribution": "fisher"}},
        'orientation.distribution: must be one of "uniform", "von_mises", "normal"',
    ),
    (
        {
            "generate.length": {
                "distribution": "power_law",
                "exponent": 2.0,
                "min": 0.3,
                "max": 0.2,
            }
        },
        "length.max: must be > min = 0.3, got 0.2",
    ),
    (
        {
            "generate.length": {
                "distribution": "lognormal",
                "median": 0.1,
                "sigma": 0.1,
                "min": 5.0,
            }
        },
        "holds only 0 of the lognormal's probability",
    ),
    (
        {"generate.intersections": "sometimes"},
        "network.generate.intersections: must be one of",
    ),
    (
        {"generate.intersections": "allow", "generate.min_spacing": 0.1},
        'min_spacing: only used with intersections = "avoid"',
    ),
    (
        {"generate.region": [[1.0, 0.0], [0.5, 1.0]]},
        "network.generate.region: upper-right corner",
    ),
    (
        {"generate.sets": []},
        "give either sets or orientation and length, not both",
    ),
    (
        {"friction": None, "frction": 0.5},
        "unknown key 'frction' in [network]; did you mean 'friction'?",
    ),
    pytest.param(  # places 60 fractures one by one: slow tier
        {"generate.count": 60, "generate.min_spacing": 0.1},
        "placed only",
        marks=pytest.mark.slow,
    ),
]


@pytest.mark.parametrize(("keys", "expected"), GENERATE_ERRORS)
def test_generate_errors(tmp_path, keys, expected):
    message = _problems(tmp_path, _network(**keys))
    assert expected in message, message


def test_generated_fractures_follow_inline_and_file(tmp_path):
    network = _network(file="seg.csv")
    spec = load_case(_case(tmp_path, network, "x0,y0,x1,y1\n1.2,0.1,1.8,0.4\n"))
    assert [f.source.split(" ")[0] for f in spec.fractures] == (
        ["", "network.file"] + ["network.generate"] * 5
    )
    assert [f.index for f in spec.fractures] == list(range(7))
    lengths = [
        float(np.hypot(*np.diff(f.points, axis=0).T).sum()) for f in spec.fractures[2:]
    ]
    assert all(0.0 < v <= 0.2 + 1e-12 for v in lengths)  # clipped or whole


def test_cli_check_and_dfn_exit_2_with_one_line(tmp_path):
    runner = CliRunner()
    path = _case(tmp_path, FILE, "x0,y0,x1,y1\n0.1,0.1,nan,0.5\n")
    for command in (
        ["check", str(path)],
        ["dfn", str(path), "--csv", str(tmp_path / "o.csv")],
    ):
        result = runner.invoke(cli, command)
        assert result.exit_code == 2, result.output
        lines = [line for line in result.output.splitlines() if line.strip()]
        assert len(lines) == 1 and "seg.csv line 2: x1 must be finite" in lines[0]
    assert not (tmp_path / "o.csv").exists()  # no partial output


def test_cli_dfn_exports_a_network_that_reads_back(tmp_path):
    path = _case(tmp_path, GENERATE)
    out = tmp_path / "net.csv"
    result = CliRunner().invoke(cli, ["dfn", str(path), "--csv", str(out)])
    assert result.exit_code == 0, result.output
    assert "6 fractures (1 from [[fractures]])" in result.output
    spec = load_case(path)
    copy = _case(tmp_path, {"file": "net.csv"})
    again = load_case(copy)
    assert len(again.fractures) == len(spec.fractures)
    for f, g in zip(spec.fractures, again.fractures, strict=True):
        np.testing.assert_array_equal(f.points, g.points)
        assert f.friction == g.friction


def test_two_hundred_generated_fractures_build(tmp_path):
    """Hundreds of fractures: the case and its geometry (not solved) build;
    the time is measured in benchmarks/dfn_build.py, not asserted here."""
    import importlib.util
    from pathlib import Path

    script = Path(__file__).resolve().parents[3] / "benchmarks" / "dfn_build.py"
    spec = importlib.util.spec_from_file_location("dfn_build", script)
    dfn_build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(dfn_build)
    case_text = dfn_build.case_text

    from xfemslip.geometry.dfn import intersecting_pairs
    from xfemslip.simulation import check_geometry

    path = tmp_path / "dfn200.toml"
    path.write_text(case_text(200, 100))
    spec = load_case(path)
    assert [f.index for f in spec.fractures] == list(range(200))
    segments = np.array([f.points for f in spec.fractures])
    assert segments.shape == (200, 2, 2)
    assert segments.min() >= 0.0 and segments.max() <= 1.0  # outside = "reject"
    assert intersecting_pairs(segments, 0.012) == []  # min_spacing = 1.2 cells
    check_geometry(spec)  # the geometry refuses any crossing pair


def test_allow_network_that_crosses_is_built_with_a_junction_per_crossing(tmp_path):
    """An "allow" network whose fractures cross is accepted (exit 0) and every
    crossing found by the generator's own segment test (dfn.intersecting_pairs,
    independent of the geometry code) becomes a junction of the model."""
    from xfemslip.fem.mesh import build_mesh
    from xfemslip.geometry.dfn import intersecting_pairs
    from xfemslip.geometry.fracture import GEOMETRY_TOL
    from xfemslip.geometry.junctions import find_junctions

    network = _network(**{"generate.intersections": "allow", "generate.count": 40})
    path = _case(tmp_path, network, inline=None)
    spec = load_case(path)
    pairs = intersecting_pairs(np.array([f.points for f in spec.fractures]))
    assert len(pairs) >= 3  # 40 random 0.2 m fractures on 2 m^2 do cross
    result = CliRunner().invoke(cli, ["check", str(path)])
    assert result.exit_code == 0, result.output
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    polylines = [np.array(f.points, float) for f in spec.fractures]
    free = [[True, True] for _ in polylines]
    names = [f"fractures[{f.index}]" for f in spec.fractures]
    found = find_junctions(
        polylines, free, names, mesh.h_min, GEOMETRY_TOL * mesh.h_min
    )
    met = {tuple(sorted((main, sec))) for _, main, sec, _ in found}
    assert {tuple(sorted(p)) for p in pairs} <= met


def test_cli_dfn_without_network_fractures_and_plot(tmp_path):
    runner = CliRunner()
    path = _case(tmp_path, None, inline=INLINE)
    result = runner.invoke(cli, ["dfn", str(path), "--csv", str(tmp_path / "o.csv")])
    assert result.exit_code == 2 and "no [network] fractures to export" in result.output
    assert not (tmp_path / "o.csv").exists()
    result = runner.invoke(
        cli, ["dfn", str(path), "--all", "--csv", str(tmp_path / "o.csv")]
    )
    assert result.exit_code == 0
    # P21 of the one inline fracture: its length over the 2 m^2 domain
    length = float(np.hypot(0.4, 0.1))
    assert f"P21 = {length / 2.0:.4g} m/m^2" in result.output
    figure = tmp_path / "net.png"
    network = _network(file="o.csv")
    # o.csv repeats the inline fracture: "avoid" keeps the generated ones off it
    path = _case(tmp_path, network, inline=None)
    result = runner.invoke(cli, ["dfn", str(path), "--plot", str(figure)])
    assert result.exit_code == 0, result.output
    assert figure.stat().st_size > 10_000


def test_result_numbering_inline_then_file(tmp_path):
    """/fractures/<i> of result.h5: 0 the inline fracture, 1 and 2 the CSV
    ones in order of their first row (checked by where the points lie)."""
    import h5py

    from xfemslip.simulation import run_case

    csv = "fracture,x0,y0,x1,y1\nb,1.2,0.2,1.7,0.3\na,0.3,0.2,0.8,0.5\n"
    path = _case(tmp_path, {**FILE, "tip": "ramp"}, csv)
    spec = load_case(path)
    run_case(spec, tmp_path / "out")
    lines = {
        0: ((0.2, 0.8), (0.6, 0.9)),
        1: ((1.2, 0.2), (1.7, 0.3)),
        2: ((0.3, 0.2), (0.8, 0.5)),
    }
    with h5py.File(tmp_path / "out" / "result.h5") as f:
        assert sorted(f["fractures"].keys()) == ["0", "1", "2"]
        for i, (a, b) in lines.items():
            p = f[f"fractures/{i}/points"][()]
            a, b = np.array(a), np.array(b)
            t = b - a
            cross = (p[:, 0] - a[0]) * t[1] - (p[:, 1] - a[1]) * t[0]
            np.testing.assert_allclose(cross / np.linalg.norm(t), 0.0, atol=1e-12)
            along = (p - a) @ t / (t @ t)
            assert along.min() >= 0.0 and along.max() <= 1.0


# --------------------------------------------------------------------------- #
# Derived sizes of [network.generate], checked before anything is drawn
# --------------------------------------------------------------------------- #

POWER = {"distribution": "power_law", "exponent": 2.5, "min": 0.1, "max": 0.4}


def _power_law_mean(exponent, lo, hi, n=2_000_001) -> float:
    """E[L] of pdf ~ l^-exponent on [lo, hi] by the trapezoidal rule."""
    x = np.linspace(lo, hi, n)
    pdf = x**-exponent
    return float(np.trapezoid(x * pdf, x) / np.trapezoid(pdf, x))


def test_p21_count_is_p21_times_area_over_the_mean_length(tmp_path):
    """5005 fractures asked for through p21 (domain 2 m x 1 m): the refusal
    gives the count the closed form of E[L] implies, before any draw."""
    mean = _power_law_mean(2.5, 0.1, 0.4)
    p21 = 5005 * mean / 2.0
    keys = {"generate.count": None, "generate.p21": p21, "generate.length": POWER}
    message = _problems(tmp_path, _network(**keys))
    assert (
        "network.generate.p21: asks for 5005 fractures over the region, more than "
        "5000" in message
    ), message


@pytest.mark.parametrize(
    ("keys", "expected"),
    [
        (
            {"generate.count": None, "generate.p21": 1e308},
            "network.generate.p21: asks for inf fractures",
        ),
        # 1e308 per m^2 over 2 m^2
        (
            {"generate.count": None, "generate.p20": 1e308},
            "network.generate.p20: asks for inf fractures",
        ),
        (
            {"generate.length": {**POWER, "min": 1e-300}},
            "network.generate.length: the power_law law with exponent = 2.5, "
            "min = 1e-300, max = 0.4 cannot be drawn in floating point",
        ),
        (
            {
                "generate.length": {
                    "distribution": "lognormal",
                    "median": 1e308,
                    "sigma": 10.0,
                }
            },
            "network.generate.length: the lognormal law with median = 1e+308, "
            "sigma = 10.0 cannot be drawn",
        ),
        (
            {"generate.region": [[-1e308, 0.0], [1e308, 1.0]]},
            "network.generate.region: expected [[x0, y0], [x1, y1]] (lower-left and "
            "upper-right corners, m, within +-1e+150), got array of 2 items",
        ),
    ],
    ids=["p21-1e308", "p20-1e308", "power-law-min-1e-300", "lognormal-1e308", "region"],
)
def test_generate_values_whose_derived_sizes_overflow(tmp_path, keys, expected):
    message = _problems(tmp_path, _network(**keys))
    assert expected in message, message
    assert message.count(": ") >= 1 and "\n" not in message


def test_a_steep_power_law_within_the_float_range_is_drawn(tmp_path):
    """exponent 10 on [0.05, 0.4]: min**(1 - exponent) = 5e11, finite; the
    drawn lengths follow the law's inverse CDF (all within [min, max]; whole
    fractures, as outside = "reject" redraws those that leave the domain)."""
    law = {**POWER, "exponent": 10.0, "min": 0.05}
    keys = {
        "generate.length": law,
        "generate.intersections": "allow",
        "generate.outside": "reject",
    }
    spec = load_case(_case(tmp_path, _network(**keys)))
    generated = [f for f in spec.fractures if f.source.startswith("network.generate")]
    assert len(generated) == 5
    lengths = [float(np.hypot(*(f.points[-1] - f.points[0]))) for f in generated]
    assert all(0.05 - 1e-12 <= v <= 0.4 + 1e-12 for v in lengths), lengths


def test_a_header_of_a_million_columns_is_one_problem(tmp_path):
    header = ",".join(f"c{i}" for i in range(1_000_000))
    message = _problems(tmp_path, FILE, csv=header + "\n0.1,0.1,0.2,0.2\n")
    assert "line 1: 1000000 unknown columns ('c0', 'c1', 'c2', ...); allowed: x0" in (
        message
    )
    assert "missing column(s) x0, y0, x1, y1" in message
    assert len(message) < 2000


def test_rows_are_quoted_short_and_the_fracture_count_comes_first(tmp_path):
    wide = "a," + ",".join(["1"] * 100_000)
    message = _problems(tmp_path, FILE, csv="fracture,x0,y0,x1,y1\n" + wide + "\n")
    assert "line 2: expected 5 values (fracture,x0,y0,x1,y1), got 100001: " in message
    assert "... (200001 characters)" in message and len(message) < 1000
    rows = "".join(f"{i},0.1,{i * 1e-4!r},0.2,{i * 1e-4!r}\n" for i in range(5001))
    message = _problems(tmp_path, FILE, csv="fracture,x0,y0,x1,y1\n" + rows)
    assert message.endswith("seg.csv: 5001 fractures, more than 5000")
