"""Every kind of figure drawn on a shipped case (coarsened to run in seconds)
and checked as a reader looks at it (tests.support.figure_checks): labels
that do not overlap and sit beside, not on, the lines they name; ticks
labelled on every axis, short log axes included; limits that span the data
and not much more; legends over no data point; colour ranges that a tip
singularity does not set; one convention for pressure-change axes."""

from __future__ import annotations

import logging
import tomllib
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import TwoSlopeNorm

from tests.support.figure_checks import (
    assert_legend_covers_no_point,
    assert_legend_inside,
    assert_limits_span,
    assert_no_overlap,
    assert_off_lines,
    assert_ticks_labelled,
    drawn,
    tick_labels,
)
from xfemslip.case import build, load_case, loads_case
from xfemslip.plot.style import (
    MIN_SPAN_FRACTION,
    line_styles,
    pressure_change_axis,
    robust_norm,
)

ROOT = Path(__file__).resolve().parents[3]
CASES = ROOT / "cases"


def coarse(name: str, tmp: Path, **keys) -> Path:
    """cases/<name>.toml with ``keys`` changed, written into ``tmp``."""
    case = tomllib.loads((CASES / f"{name}.toml").read_text())
    keys.setdefault("output.directory", str(tmp / "unused"))
    path = tmp / f"{name}.toml"
    path.write_text(build.case_text(build.with_keys(case, **keys)))
    return path


@pytest.fixture(scope="session")
def depleted(tmp_path_factory):
    """cases/permeability.toml on 20 m cells in 4 steps of 5 MPa, through
    ``deplete --plot``: (result folder, report, depletion-field figure).
    Fractures 0 and 1 slip at 13.7 MPa of depletion, 2 stays stuck."""
    from xfemslip.plot import depletion as plots
    from xfemslip.studies.depletion import deplete

    root = tmp_path_factory.mktemp("depleted")
    path = coarse(
        "permeability",
        root,
        **{
            "mesh.elements": [40, 25],
            "loading.steps": 4,
            "output.formats": ["h5", "vtu"],
        },
    )
    kept = {}
    draw = plots.figure_field
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(
            plots, "figure_field", lambda m, r: kept.setdefault("field", draw(m, r))
        )
        report = deplete(load_case(path), root / "out", plot=True)
    return root / "out", report, kept["field"]


# --------------------------------------------------------------------------- #
# What every figure shares
# --------------------------------------------------------------------------- #


def test_line_styles_tell_neighbours_and_repeats_apart():
    """Neighbouring curves differ in hue; no two of 40 share hue and dash
    (tab20 gave pairs of near-identical hues side by side)."""
    for n in (3, 15, 40):
        styles = line_styles(n)
        pairs = {(s["color"], s["linestyle"]) for s in styles}
        assert len(pairs) == n
        assert all(a["color"] != b["color"] for a, b in pairwise(styles))
    dashed = line_styles(3, dashes=True)
    assert len({s["linestyle"] for s in dashed}) == 3


def test_pressure_change_axes_run_as_magnitude_to_the_right():
    x, label = pressure_change_axis([0.0, -5e6, -20e6])
    np.testing.assert_array_equal(x, [0.0, 5.0, 20.0])
    assert "drop" in label and "[MPa]" in label
    x, label = pressure_change_axis([0.0, 3e6])
    np.testing.assert_array_equal(x, [0.0, 3.0])
    assert "rise" in label


def test_robust_colour_range_ignores_a_tip_and_does_not_magnify_noise():
    """A field of -20 +- 3 MPa with a few cells at -65 MPa (a tip): the range
    is the 1st to 99th percentile, the -65 clipped and said; a uniform
    field with 1e-6 noise keeps a range of MIN_SPAN_FRACTION of its size."""
    rng = np.random.default_rng(1)
    field = -20.0 + rng.uniform(-3.0, 3.0, 1000)
    field[:5] = -65.0
    scale = robust_norm(field)
    lo, hi = np.percentile(field, [1.0, 99.0])
    assert scale.norm.vmin == pytest.approx(lo) and scale.norm.vmax == pytest.approx(hi)
    assert scale.norm.vmin > -24.0 and scale.extend == "both"
    assert "clipped" in scale.note and scale.cmap == "viridis"
    flat = robust_norm(-20.0 + 1e-6 * rng.standard_normal(1000))
    assert flat.norm.vmax - flat.norm.vmin == pytest.approx(MIN_SPAN_FRACTION * 20.0)
    both = robust_norm(np.linspace(-1.0, 3.0, 101))
    assert isinstance(both.norm, TwoSlopeNorm) and both.norm.vcenter == 0.0


def test_short_log_axes_have_labelled_ticks():
    """verify.png: h from a/10 to a/40 and wall times of 0.4 to 2 s span
    less than a decade; both axes are labelled, and the legends lie below
    the panels over no data point."""
    from xfemslip.verify.problems import Report, Row
    from xfemslip.verify.report import figure_verify

    rows = [
        Row(name, n, slip_error=e * k, kii_error=2 * e * k, wall_s=t)
        for k, name in enumerate(("inclined-30", "inclined-60", "cohesion-30"), 1)
        for n, e, t in ((10, 0.03, 0.4), (20, 0.012, 0.9), (40, 0.006, 2.1))
    ]
    fig = figure_verify(Report(rows, [], [], None))
    renderer = drawn(fig)
    for ax in fig.axes:
        assert_ticks_labelled(ax)
        assert_legend_covers_no_point(ax.get_legend(), fig.axes, renderer)
    assert "0.05" in tick_labels(fig.axes[0].xaxis)


def test_log_axes_of_one_to_two_decades_have_ticks_apart():
    """verify.png of the full set: wall times of 0.12 to 1.1 s span just over
    a decade, where matplotlib names the minor ticks in scientific notation
    ("3 x 10^-1" against "4 x 10^-1"); the tick labels of both panels lie
    apart, in plain numbers."""
    from xfemslip.verify.problems import Report, Row
    from xfemslip.verify.report import figure_verify

    rows = [
        Row(name, n, slip_error=e * k, kii_error=2 * e * k, wall_s=t * k)
        for k, name in enumerate(("inclined-30", "inclined-60", "cohesion-30"), 1)
        for n, e, t in (
            (5, 0.016, 0.12),
            (10, 0.008, 0.2),
            (20, 0.004, 0.35),
            (40, 0.0015, 0.37),
        )
    ]
    fig = figure_verify(Report(rows, [], [], None))
    renderer = drawn(fig)
    for ax in fig.axes:
        assert_ticks_labelled(ax)
        for axis in (ax.xaxis, ax.yaxis):
            texts = [t for t in axis.get_ticklabels(which="both") if t.get_text()]
            texts = [t for t in texts if t.get_visible()]
            assert_no_overlap(texts, renderer, "tick labels")
            assert not any("times" in t.get_text() for t in texts)


# --------------------------------------------------------------------------- #
# Labels of fractures at one point or angle
# --------------------------------------------------------------------------- #


def test_screen_mohr_joins_fractures_at_one_angle():
    """Three fractures at 45 degrees and one at 50: one label names the
    three, and no label overlaps another or covers a point."""
    from xfemslip.plot.figures import figure_screen

    fractures = [(f"fractures[{k}]", 45.0, 0.6, 0.0) for k in range(3)]
    fractures.append(("fractures[3]", 50.0, 0.6, 0.0))
    fig = figure_screen((-20e6, -40e6, 0.0), 15e6, 0.6, 0.0, fractures)
    renderer = drawn(fig)
    ax = fig.axes[0]
    texts = [t for t in ax.texts if "fractures[" in t.get_text()]
    assert sorted(t.get_text().split(" ($")[0] for t in texts) == [
        "fractures[0], fractures[1], fractures[2]",
        "fractures[3]",
    ]
    assert_no_overlap(texts, renderer)
    assert_ticks_labelled(ax)


def test_mohr_of_the_permeability_case_labels_fractures_apart(depleted):
    """Fractures 0 and 1 end on the failure line side by side: their labels
    share one or do not overlap; fracture 2 has its own."""
    from xfemslip.plot.data import figure_data
    from xfemslip.plot.figures import figure_mohr

    fig = figure_mohr([figure_data(depleted[0])])
    renderer = drawn(fig)
    ax = fig.axes[0]
    texts = [t for t in ax.texts if t.get_text().startswith("fracture")]
    named = " ".join(t.get_text() for t in texts)
    assert all(str(i) in named for i in range(3))
    assert_no_overlap(texts, renderer)
    assert_ticks_labelled(ax)


def test_case_figure_numbers_sit_beside_their_fractures():
    """plot --case of the 15-fracture network: each number lies off every
    fracture line, on no other number, and near its own fracture."""
    from xfemslip.plot.case import figure_case

    spec = load_case(CASES / "fracture_network.toml")
    fig = figure_case(spec)
    renderer = drawn(fig)
    ax = fig.axes[0]
    numbers = [t for t in ax.texts if t.get_text().isdigit()]
    assert sorted(int(t.get_text()) for t in numbers) == list(range(15))
    lines = [np.asarray(fr.points, float) for fr in spec.fractures]
    assert_no_overlap(numbers, renderer, "fracture numbers")
    assert_off_lines(numbers, lines, ax, renderer)
    for t in numbers:
        box = t.get_window_extent(renderer)
        line = ax.transData.transform(lines[int(t.get_text())])
        centre = np.array([box.x0 + box.x1, box.y0 + box.y1]) / 2.0
        seg = np.linspace(line[0], line[-1], 200)
        assert np.min(np.linalg.norm(seg - centre, axis=1)) < 40.0  # pixels


# --------------------------------------------------------------------------- #
# Depletion figures
# --------------------------------------------------------------------------- #


def test_slip_vs_depletion_joins_coincident_onsets_and_steps_the_length():
    """Fractures 0 and 1 at one critical depletion (12.5 MPa): one line,
    annotated with both and the value; fracture 2 at 16.5 MPa its own.  The
    slipping length is a step: 0 up to the critical depletion, then the
    length of the next sample; legends over no point, limits the data's."""
    from xfemslip.plot.depletion import figure_slip_vs_depletion
    from xfemslip.studies.depletion import DepletionReport, FractureOnset

    report = DepletionReport(
        onsets=[
            FractureOnset(0, -12e6, -13e6),
            FractureOnset(1, -12e6, -13e6),
            FractureOnset(2, -16e6, -17e6),
        ],
        rows=[
            (0, 0.0, 0.0, [(0.0, 0.0)] * 3),
            (1, 0.5, -10e6, [(0.0, 0.0)] * 3),
            (2, 1.0, -20e6, [(2.5e-3, 40.0), (2.5e-3, 40.0), (1e-3, 10.0)]),
        ],
    )
    fig = figure_slip_vs_depletion(report, "case")
    renderer = drawn(fig)
    a1, a2 = fig.axes
    notes = sorted(t.get_text() for t in a1.texts)
    assert notes == ["fracture 2: 16.5 MPa", "fractures 0, 1: 12.5 MPa"]
    vertical = [ln for ln in a1.lines if ln.get_transform() is not a1.transData]
    assert sorted(ln.get_xdata()[0] for ln in vertical) == [12.5, 16.5]
    x, y = a2.lines[0].get_data()
    np.testing.assert_allclose(x, [0, 10, 10, 10, 12.5, 12.5, 20])
    np.testing.assert_allclose(y, [0, 0, 0, 0, 0, 40, 40])
    for ax in (a1, a2):
        assert_ticks_labelled(ax)
        assert_limits_span(ax, "x", [0.0, 20.0], slack=1.0)
        assert "drop" in ax.get_xlabel()
    assert_legend_inside(a2.get_legend(), a2, renderer)
    assert [t.get_text() for t in a2.get_legend().get_texts()] == [
        "fracture 0",
        "fracture 1",
        "fracture 2",
    ]
    assert not fig.legends
    assert_no_overlap(a1.texts, renderer)


def test_slip_vs_depletion_marks_where_the_slip_turns_seismic():
    """A path that ends at a loss of equilibrium (dp_seismic = -18 MPa, the
    last sample): a star on the last point of both panels, inside the axes,
    its value written beside it; no star for a fracture without one."""
    from xfemslip.plot.depletion import figure_slip_vs_depletion
    from xfemslip.studies.depletion import DepletionReport, FractureOnset

    seismic = FractureOnset(0, -12e6, -13e6, at_singularity=True)
    seismic.dp_seismic = -18e6
    report = DepletionReport(
        onsets=[seismic, FractureOnset(1, -16e6, -17e6)],
        rows=[
            (0, 0.0, 0.0, [(0.0, 0.0)] * 2),
            (1, 0.5, -10e6, [(0.0, 0.0)] * 2),
            (2, 0.8, -16e6, [(2e-3, 40.0), (0.0, 0.0)]),
            (3, 0.9, -18e6, [(6e-3, 90.0), (1e-3, 10.0)]),
        ],
    )
    fig = figure_slip_vs_depletion(report, "case")
    renderer = drawn(fig)
    a1, a2 = fig.axes
    for ax, value in ((a1, 6.0), (a2, 90.0)):
        stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
        assert len(stars) == 1
        np.testing.assert_allclose(stars[0].get_xydata(), [[18.0, value]])
        assert ax.get_xlim()[1] > 18.0  # room for the star
    assert [t.get_text() for t in a2.texts] == ["seismic at 18 MPa"]
    # the first slip of fracture 0 sits at a singular point, and says so
    assert sorted(t.get_text() for t in a1.texts) == [
        "fracture 0: 12.5 MPa (singular point)",
        "fracture 1: 16.5 MPa",
    ]
    assert "seismic" in a1.get_title()
    assert_no_overlap(a2.texts, renderer)


def _many_onsets(count: int):
    """A depletion report of ``count`` fractures, fracture i slipping from
    5 + i MPa with a largest slip of (i + 1) mm and a length of i + 1 m."""
    from xfemslip.studies.depletion import DepletionReport, FractureOnset

    onsets = [FractureOnset(i, -(5 + i) * 1e6, -(6 + i) * 1e6) for i in range(count)]
    rows = [
        (
            k,
            k / 10,
            -2e6 * k,
            [
                ((i + 1) * 1e-3 if 2 * k > 5 + i else 0.0, float(i + 1))
                for i in range(count)
            ],
        )
        for k in range(11)
    ]
    return DepletionReport(onsets=onsets, rows=rows)


@pytest.mark.parametrize("count", [3, 6, 7, 15])
def test_slip_vs_depletion_legend_inside_with_six_entries_at_most(count):
    """With many fractures the legend stays inside its panel, over no point,
    with six entries: the five largest slips and "n more", whose fracture
    numbers are written on the slip panel, apart from each other."""
    from xfemslip.plot.depletion import figure_slip_vs_depletion

    fig = figure_slip_vs_depletion(_many_onsets(count), "case")
    renderer = drawn(fig)
    a1, a2 = fig.axes
    legend = a2.get_legend()
    assert_legend_inside(legend, a2, renderer)
    entries = [t.get_text() for t in legend.get_texts()]
    if count <= 6:
        assert entries == [f"fracture {i}" for i in range(count)]
        return
    largest = [f"fracture {i}" for i in range(count - 5, count)]
    assert entries == [*largest, f"{count - 5} more: numbered on their curves"]
    numbers = [t for t in a1.texts if ":" not in t.get_text()]
    written = sorted(int(n) for t in numbers for n in t.get_text().split(", "))
    assert written == list(range(count - 5))
    assert_no_overlap(numbers, renderer)
    assert_limits_span(a1, "y", [0.0, float(count)], slack=1.5)


@pytest.mark.parametrize("count", [1, 4, 15])
def test_slip_along_fractures_legend_inside_with_six_entries_at_most(count):
    """figure_slip of a network of ``count`` fractures: the legend inside
    the axes over no point, at most six entries, the others' numbers at
    their largest slip."""
    from types import SimpleNamespace

    from xfemslip.plot.figures import figure_slip

    s = np.linspace(0.0, 2.0, 41)
    fractures = [
        SimpleNamespace(
            index=i,
            s=s,
            slid=(i + 1) * 1e-3 * np.sqrt(np.clip(1 - (s - 1) ** 2, 0, None)),
            slip=(i + 1.1) * 1e-3 * np.sqrt(np.clip(1 - (s - 1) ** 2, 0, None)),
            state=np.full(s.size, 2),
        )
        for i in range(count)
    ]
    data = SimpleNamespace(fractures=fractures, label="net", name="net")
    fig = figure_slip([data])
    renderer = drawn(fig)
    (ax,) = fig.axes
    assert_legend_inside(ax.get_legend(), ax, renderer)
    entries = [t.get_text() for t in ax.get_legend().get_texts()]
    if count == 1:
        assert entries == ["net"]
    elif count <= 6:
        assert entries == [f"fracture {i}" for i in range(count)]
    else:
        assert entries[:5] == [f"fracture {i}" for i in range(count - 5, count)]
        assert entries[5] == f"{count - 5} more: numbered on their curves"
        written = sorted(int(n) for t in ax.texts for n in t.get_text().split(", "))
        assert written == list(range(count - 5))
        assert_no_overlap(ax.texts, renderer)


def test_depletion_field_bars_fit_their_panels_and_centre_white_on_zero(depleted):
    """Colour bars as high as their equal-aspect panels; the change map
    white at zero (TwoSlopeNorm at 0) and said; the ranges clipped to the
    1st-99th percentile; no zoom row when the fractures fill the section."""
    fig = depleted[2]
    drawn(fig)
    panels = fig.axes
    bars = [child for ax in panels for child in ax.child_axes]
    assert len(panels) == 2 and len(bars) == 2
    for panel, bar in zip(panels, bars, strict=True):
        # the outline holds the extend arrows
        a, b = panel.get_window_extent(), bar.spines["outline"].get_window_extent()
        assert b.y0 == pytest.approx(a.y0, abs=1.0)
        assert b.y1 == pytest.approx(a.y1, abs=1.0)
        assert b.x0 > a.x1  # beside the panel, not over it
        assert_ticks_labelled(panel)
    norm = panels[0].collections[0].norm
    assert isinstance(norm, TwoSlopeNorm) and norm.vcenter == 0.0
    assert "white: 0" in bars[0].get_ylabel()
    assert "clipped" in bars[0].get_ylabel()
    assert [ax.get_title() for ax in panels].count("zoom on the fractures") == 0


def test_depletion_field_zooms_on_a_small_fault_in_a_large_section(tmp_path):
    """A 100 m fault in a 2 km section: a second row shows the fault, its
    limits around the fault's ends."""
    from xfemslip.plot.depletion import figure_field
    from xfemslip.simulation import solve_and_write

    path = coarse(
        "depleting_reservoir",
        tmp_path,
        **{
            "domain.size": [2000.0, 1000.0],
            "mesh.elements": [40, 20],
            "loading.steps": 1,
            "output.formats": ["h5"],
        },
    )
    case = tomllib.loads(path.read_text())
    case["fractures"] = [
        {"center": [1000.0, 250.0], "length": 100.0, "angle": 60.0, "friction": 0.5}
    ]
    case.pop("reservoir", None)
    case["pore_pressure"]["region"] = "all"
    spec = loads_case(build.case_text(case), path)
    done = solve_and_write(
        spec, None, False, lambda solver, _: solver.run(spec.loading.steps)
    )
    fig = figure_field(done.model, done.results[-1])
    drawn(fig)
    panels = fig.axes
    assert len(panels) == 4
    ends = np.asarray(spec.fractures[0].points, float)
    for ax in panels[2:]:
        assert ax.get_title() == "zoom on the fractures"
        x0, x1 = ax.get_xlim()
        assert x0 <= ends[:, 0].min() and ends[:, 0].max() <= x1
        assert x1 - x0 < 0.2 * 2000.0


def test_permeability_figure_legend_off_the_curves_and_drop_to_the_right(depleted):
    """permeability.png: one legend below the panels, over no curve; the
    ratio panel against the pressure drop, growing to the right as in
    slip_vs_depletion.png."""
    from xfemslip.plot.permeability import figure_permeability

    fig = figure_permeability(depleted[0])
    renderer = drawn(fig)
    ax_a, ax_t, ax_k = fig.axes
    assert not any(ax.get_legend() for ax in fig.axes)
    assert_legend_covers_no_point(fig.legends[0], fig.axes, renderer)
    x = ax_k.lines[0].get_xdata()
    assert x[0] == 0.0 and x[-1] == pytest.approx(20.0) and np.all(np.diff(x) > 0)
    assert "drop" in ax_k.get_xlabel()
    for ax in fig.axes:
        assert_ticks_labelled(ax)


def test_probability_steps_span_the_data_and_show_coincident_curves():
    """The shipped study (screen, 20,000 samples): P as steps, y axis to the
    largest upper bound (0.25, not 1), fracture 1's curve on fracture 0's
    said in the legend and drawn in another dash; the legend beside the
    axes; the title says whether the Wilson bands are visible."""
    from xfemslip.plot.probability import figure_probability
    from xfemslip.studies.reactivation import evaluate_screen
    from xfemslip.studies.uncertainty import load_uncertainty

    result = evaluate_screen(
        load_uncertainty(CASES / "sweeps" / "slip_probability.toml")
    )
    fig = figure_probability(result)
    renderer = drawn(fig)
    ax = fig.axes[0]
    lines = [ln for ln in ax.lines if ln.get_label().startswith("fracture")]
    assert all(ln.get_drawstyle() == "steps-post" for ln in lines)
    assert lines[0].get_linestyle() != lines[1].get_linestyle()
    assert "on fracture 0's curve" in lines[1].get_label()
    assert_limits_span(ax, "y", result.ci_high, include=[0.0], slack=1.15)
    assert ax.get_ylim()[1] < 0.3
    assert_legend_covers_no_point(ax.get_legend(), [ax], renderer)
    assert_ticks_labelled(ax)
    assert "Wilson bands" in ax.get_title()
    assert "drop" in ax.get_xlabel()


# --------------------------------------------------------------------------- #
# The figures of plot
# --------------------------------------------------------------------------- #


@pytest.fixture(scope="session")
def inclined(tmp_path_factory):
    """The small case of the studies (tests.support.casegen) at 45 degrees:
    a slipping crack with its two tips in the field (result.h5)."""
    from tests.support.casegen import SWEEP_CASE
    from xfemslip.simulation import run_case

    root = tmp_path_factory.mktemp("inclined")
    case = build.with_keys(
        SWEEP_CASE, **{"fractures.0.angle": 45.0, "output.formats": ["h5"]}
    )
    run_case(loads_case(build.case_text(case), root / "case.toml"), root / "out")
    return root / "out"


def test_principal_stress_range_is_not_set_by_the_tips(inclined):
    """Each row's colours span the 1st-99th percentile of its stresses, the
    colour bar says clipped and has arrows where values lie beyond."""
    from xfemslip.plot.data import figure_data
    from xfemslip.plot.figures import figure_principal

    data = figure_data(inclined)
    fig = figure_principal([data])
    drawn(fig)
    bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    for k, (ax, col) in enumerate(zip(panels, (1, 0), strict=True)):
        values = 1e-6 * data.principal[:, col]
        norm = ax.collections[0].norm
        lo, hi = np.percentile(values, [1.0, 99.0])
        span = max(hi - lo, MIN_SPAN_FRACTION * max(abs(lo), abs(hi)))
        mid = 0.5 * (lo + hi) if span > hi - lo else None
        if mid is None:
            assert (norm.vmin, norm.vmax) == pytest.approx((lo, hi))
        else:  # nearly uniform: widened about the middle
            assert (norm.vmin, norm.vmax) == pytest.approx(
                (mid - span / 2, mid + span / 2)
            )
        clipped = values.min() < norm.vmin or values.max() > norm.vmax
        assert ("clipped" in bars[k].get_ylabel()) == clipped
        assert_ticks_labelled(ax)
    # the tip sets neither row's range: the most compressive stress lies
    # beyond the first row's colours
    assert 1e-6 * data.principal[:, 1].min() < panels[0].collections[0].norm.vmin


def test_thinned_mesh_keeps_every_other_grid_line_and_the_cut():
    """A 4 x 4 grid of unit cells: every other line keeps x = 0, 2, 4 and
    y = 0, 2, 4 (3 lines of 4 edges each way, 24 of the 40 edges) and the
    slanted edge of a cut piece."""
    from xfemslip.plot.figures import _thinned_edges

    xy = np.array([(x, y) for y in range(5) for x in range(5)], float)
    node = {(x, y): 5 * y + x for y in range(5) for x in range(5)}
    edges = [(node[x, y], node[x + 1, y]) for y in range(5) for x in range(4)]
    edges += [(node[x, y], node[x, y + 1]) for y in range(4) for x in range(5)]
    edges.append((node[1, 1], node[2, 2]))  # a piece's edge along a fracture
    kept = _thinned_edges(xy, np.array(edges), 1.0, 2)
    assert len(kept) == 24 + 1
    ends = xy[kept]
    straight = ends[:-1]
    on_line = np.where(
        straight[:, 0, 1] == straight[:, 1, 1], straight[:, 0, 1], straight[:, 0, 0]
    )
    assert set(on_line) == {0.0, 2.0, 4.0}
    np.testing.assert_array_equal(_thinned_edges(xy, np.array(edges), 1.0, 1), edges)


def test_deformed_mesh_zoom_frame_lies_between_grid_lines(depleted):
    """The zoom's frame lies half a cell from the grid lines (a mesh line
    along the frame looked like a second frame); the overview draws no more
    lines than the zoom's full mesh, and says when it thins them."""
    from xfemslip.plot.data import figure_data
    from xfemslip.plot.figures import _line_stride, figure_deformed

    data = figure_data(depleted[0])
    fig = figure_deformed([data], scale=1.0)
    drawn(fig)
    overview, zoom = fig.axes[:2]
    h = 20.0
    for lo, hi, axis in ((*zoom.get_xlim(), 0), (*zoom.get_ylim(), 1)):
        for edge in (lo, hi):
            offset = (edge - data.points[:, axis].min()) / h
            assert abs(offset - np.floor(offset) - 0.5) < 0.05
    stride = _line_stride(data)
    drawn_lines = len(overview.collections[0].get_segments())
    all_lines = len(zoom.collections[0].get_segments())
    assert (drawn_lines < all_lines) == (stride > 1)
    assert ("mesh line" in overview.get_title()) == (stride > 1)
    assert_ticks_labelled(overview)
    assert_ticks_labelled(zoom)


def test_plot_logs_one_line_per_figure(depleted, tmp_path, caplog):
    """A plot of several figures reports each as it is written: number, of
    how many, file name and seconds."""
    from xfemslip.plot.figures import plot_results

    with caplog.at_level(logging.INFO, logger="xfemslip.plot.figures.progress"):
        plot_results([depleted[0]], tmp_path, kinds=["slip", "mohr"], formats=["png"])
    lines = [r.getMessage() for r in caplog.records if r.name.endswith("progress")]
    heads = [ln.split(": ")[0] for ln in lines]
    names = sorted(ln.split(": ")[1].split(" (")[0] for ln in lines)
    assert heads == ["figure 1/2", "figure 2/2"]
    assert names == ["mohr.png", "slip.png"]
    assert all(ln.endswith(" s)") for ln in lines)


def test_network_figures_have_metres_mm_a_rose_and_lengths(depleted):
    """dfn figure of the permeability case's three fractures: axes in [m],
    slip in mm (no offset text by the colour bar), a rose diagram counting
    every fracture twice (a line has no direction) and a length histogram
    counting each once."""
    from xfemslip.plot.dfn import figure_network, orientations_and_lengths

    spec = load_case(CASES / "permeability.toml")
    fig = figure_network(spec, depleted[0] / "result.h5")
    renderer = drawn(fig)
    (bar,) = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    ax_net, rose, lengths = [ax for ax in fig.axes if ax is not bar]
    assert ax_net.get_xlabel() == "x [m]" and ax_net.get_ylabel() == "y [m]"
    assert bar.get_ylabel() == "|slip| that slid [mm]"
    assert bar.yaxis.get_offset_text().get_text() == ""
    assert rose.name == "polar"
    assert sum(p.get_height() for p in rose.patches) == 2 * len(spec.fractures)
    assert sum(p.get_height() for p in lengths.patches) == len(spec.fractures)
    angles, sizes = orientations_and_lengths(spec)
    np.testing.assert_allclose(sorted(angles), [60.0, 60.0, 120.0])
    np.testing.assert_allclose(sorted(sizes), [60.0, 60.0, 80.0])
    top = max(float(np.abs(f).max()) for f in _slid(depleted[0]))
    assert bar.get_ylim()[1] == pytest.approx(1e3 * top)
    for ax in (ax_net, lengths):
        assert_ticks_labelled(ax)
    assert_no_overlap([ax.title for ax in (ax_net, rose, lengths)], renderer, "titles")


def test_length_histogram_of_equal_lengths_is_one_bar():
    """Lengths equal to rounding (a corrupted or regular network): one bar
    holding them all, not numpy's refusal to make bins of zero width."""
    from matplotlib.figure import Figure

    from xfemslip.plot.dfn import _draw_lengths

    for lengths in ([1.0, 1.0, 1.0 + 1e-15], [0.0, 0.0], [2.0], [np.nan, 3.0]):
        ax = Figure().subplots()
        _draw_lengths(ax, np.array(lengths))
        heights = [p.get_height() for p in ax.patches]
        finite = int(np.isfinite(lengths).sum())
        assert heights == [finite]
    ax = Figure().subplots()
    _draw_lengths(ax, np.array([1.0, 2.0, 3.0, 4.0]))
    assert [p.get_height() for p in ax.patches] == [2, 2]


def _slid(out: Path) -> list[np.ndarray]:
    from xfemslip import read_result

    return [f.slid for f in read_result(out).fractures]
