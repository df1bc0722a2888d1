"""The picture of a case before it runs (``plot --case``), the numbered
labels of a crowded Mohr diagram, and the panel titles of sweep cases."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from xfemslip.case import load_case
from xfemslip.cli import cli
from xfemslip.plot.case import figure_case
from xfemslip.plot.data import parameter_label
from xfemslip.plot.mohr import LABEL_GAP_DEG, _circle_point, draw_mohr, spread

CASE = textwrap.dedent(
    """
    name = "picture"
    [domain]
    size = [2.0, 1.0]
    [mesh]
    elements = [8, 4]
    [material]
    E = 1.0e9
    nu = 0.25
    [[fractures]]
    points = [[0.5, 0.3], [1.5, 0.7]]
    friction = 0.4
    [loading]
    stress = { xx = -10.0e6, yy = -30.0e6, xy = 5.0e6 }
    [boundary]
    bottom = { uy = 0.0 }
    left = { ux = 0.0 }
    top = "traction"
    right = "traction"
    """
)


def vectors_of(quiver):
    return np.column_stack([quiver.U, quiver.V])


@pytest.fixture
def case(tmp_path):
    path = tmp_path / "picture.toml"
    path.write_text(CASE)
    return path


def test_case_figure_draws_tractions_rollers_and_fractures(case):
    fig = figure_case(load_case(case))
    ax = fig.axes[0]
    # the traction arrows are sigma . n of each traction edge (n outward)
    S = np.array([[-10.0e6, 5.0e6], [5.0e6, -30.0e6]])
    arrows = [c for c in ax.collections if type(c).__name__ == "Quiver"]
    assert len(arrows) == 2  # top and right
    expected = [S @ [0.0, 1.0], S @ [1.0, 0.0]]
    top = max(np.linalg.norm(t) for t in expected)
    for quiver, t in zip(arrows, expected, strict=True):
        vectors = np.column_stack([quiver.U, quiver.V])
        np.testing.assert_allclose(vectors, np.tile(0.07 * 2.0 * t / top, (9, 1)))
    # both edges are in compression: each arrow ends on its edge
    np.testing.assert_allclose((arrows[0].XY + vectors_of(arrows[0]))[:, 1], 1.0)
    np.testing.assert_allclose((arrows[1].XY + vectors_of(arrows[1]))[:, 0], 2.0)
    # rollers outside the bottom (uy = 0) and the left (ux = 0) edges
    markers = {
        ln.get_marker(): ln.get_xydata() for ln in ax.lines if ln.get_xydata().size
    }
    assert np.all(markers["^"][:, 1] < 0.0) and len(markers["^"]) == 9
    assert np.all(markers[">"][:, 0] < 0.0) and len(markers[">"]) == 9
    # the fracture as written in the case file
    fracture = [
        ln for ln in ax.lines if ln.get_linewidth() == 2.0 and len(ln.get_xdata())
    ]
    np.testing.assert_array_equal(fracture[0].get_xydata(), [[0.5, 0.3], [1.5, 0.7]])
    assert ax.get_title().startswith("picture")


def test_plot_case_command_writes_png_and_pdf(case, tmp_path, runner):
    out = tmp_path / "figs"
    result = runner.invoke(cli, ["plot", "--case", str(case), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["picture.pdf", "picture.png"]
    assert (out / "picture.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_without_results_or_case_is_refused(tmp_path, runner):
    result = runner.invoke(cli, ["plot", "-o", str(tmp_path / "x")])
    assert result.exit_code == 2
    assert not (tmp_path / "x").exists()
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.replace("E = 1.0e9", 'E = "soft"'))
    result = runner.invoke(cli, ["plot", "--case", str(bad), "-o", str(tmp_path / "y")])
    assert result.exit_code == 2 and "material.E" in result.stderr
    assert not (tmp_path / "y").exists()


def test_spread_keeps_order_and_gap_and_moves_little():
    angles = [10.0, 11.0, 12.0, 60.0, 61.0, 150.0]
    out = spread(angles, 8.0, 4.0, 176.0)
    assert np.all(np.diff(out) >= 8.0 - 1e-12)
    assert out.min() >= 4.0 and out.max() <= 176.0
    # the crowded three move apart about their own place (clipped at 4), the
    # close pair about its middle, the lone one stays
    np.testing.assert_allclose(out, [4.0, 12.0, 20.0, 56.5, 64.5, 150.0])
    # nothing to do: unchanged
    np.testing.assert_array_equal(spread([20.0, 40.0], 8.0, 4.0, 176.0), [20.0, 40.0])


def test_crowded_mohr_labels_do_not_overlap_and_point_at_their_points():
    """15 fractures within 30 degrees of each other: numbered labels whose
    boxes do not overlap, each joined to its point on the circle."""
    fig = Figure(figsize=(8, 5))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    thetas = np.linspace(20.0, 50.0, 15)
    fractures = [(str(k), t, 0.6, 0.0) for k, t in enumerate(thetas)]
    stress = (-20.0e6, -40.0e6, 0.0)
    draw_mohr(ax, stress, fractures=fractures)
    fig.canvas.draw()
    notes = [t for t in ax.texts if t.get_text().isdigit()]
    assert len(notes) == 15
    boxes = [t.get_bbox_patch().get_window_extent() for t in notes]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b)
    # each label points at the circle point of its fracture (sigma_1 along y)
    centre, radius = -30.0e6, 10.0e6
    for note in notes:
        theta = thetas[int(note.get_text())]
        beta = abs(90.0 - theta)  # angle between the plane and sigma_1 (y)
        np.testing.assert_allclose(
            note.xy, _circle_point(centre, radius, beta), rtol=1e-9, atol=1.0
        )
    angles = np.degrees(
        np.arctan2([n.xyann[1] for n in notes], [n.xyann[0] - centre for n in notes])
    )
    assert np.all(np.diff(np.sort(angles)) >= LABEL_GAP_DEG - 1e-9)


def test_sweep_parameters_read_with_units():
    assert parameter_label("E=5e9") == "E = 5 GPa"
    assert parameter_label("angle=27_friction=0.3") == "angle = 27 deg, f = 0.3"
    assert parameter_label("cohesion=2e6") == "c = 2 MPa"
    assert parameter_label("mystery=abc") == "mystery = abc"


def test_slip_vs_depletion_is_titled_by_the_case_and_draws_the_table(tmp_path):
    """deplete's slip figure: the case's name in its title, and its lines the
    report's rows (mm against the pressure drop in MPa); the PNG written."""
    from xfemslip.plot.depletion import figure_slip_vs_depletion, plot_slip_vs_depletion
    from xfemslip.studies.depletion import DepletionReport, FractureOnset

    report = DepletionReport(
        onsets=[FractureOnset(0, -12e6, -13e6)],
        rows=[
            (0, 0.0, 0.0, [(0.0, 0.0)]),
            (1, 0.5, -10e6, [(0.0, 0.0)]),
            (2, 1.0, -20e6, [(2.5e-3, 40.0)]),
        ],
    )
    path = plot_slip_vs_depletion(report, tmp_path, name="depleting-reservoir")
    assert path.read_bytes()[:4] == b"\x89PNG"
    fig = figure_slip_vs_depletion(report, name="depleting-reservoir")
    assert fig._suptitle.get_text() == "depleting-reservoir: slip against depletion"
    slip_axes = fig.axes[0]
    x, y = slip_axes.lines[0].get_data()
    assert list(x) == [0.0, 10.0, 20.0] and list(y) == [0.0, 0.0, 2.5]
    # the bracket's midpoint, 12.5 MPa of drop, as the vertical line
    assert slip_axes.lines[1].get_xdata()[0] == 12.5
