"""Figures (xfemslip.plot.figures): what they draw is the data of result.h5 / .vtu,
the Mohr geometry is the closed form, ``run`` without ``--plot`` never
imports matplotlib, and the commands write PNG and PDF."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from tests.support.casegen import SWEEP_BASE as BASE
from tests.support.casegen import SWEEP_CASE as CASE
from xfemslip.case import build
from xfemslip.cli import cli
from xfemslip.errors import UsageError
from xfemslip.plot.data import (
    FractureData,
    _piece_outlines,
    distinct_labels,
    figure_data,
)
from xfemslip.plot.figures import KINDS, auto_scale, figure_slip, plot_results
from xfemslip.plot.mohr import _circle_point
from xfemslip.reference.closed_form import angle_to_sigma1, principal
from xfemslip.reference.screen import plane_stresses

ROOT = Path(__file__).resolve().parents[3]
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """The small case at 45 and 63 degrees (result.h5 + vtu)."""
    root = tmp_path_factory.mktemp("plots")
    runner = CliRunner()
    outs = []
    for angle in (45.0, 63.0):
        case = root / f"a{angle:g}.toml"
        keys = {"fractures.0.angle": angle, "output.formats": ["h5", "vtu"]}
        case.write_text(build.case_text(build.with_keys(CASE, **keys)))
        out = root / f"{int(angle):03d}_angle={angle:g}"
        result = runner.invoke(cli, ["run", str(case), "-o", str(out)])
        assert result.exit_code == 0, result.output
        outs.append(out)
    return outs


def test_run_plot_writes_every_figure_as_png_and_pdf(two_runs, tmp_path):
    case = two_runs[0].parent / "a45.toml"
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["run", str(case), "-o", str(out), "--plot"])
    assert result.exit_code == 0, result.output
    figures = out / "figures"
    for kind in KINDS:
        assert (figures / f"{kind}.png").read_bytes()[:8] == PNG
        assert (figures / f"{kind}.pdf").read_bytes()[:4] == b"%PDF"
        assert (figures / f"{kind}.png").stat().st_size < 400_000


def test_slip_figure_draws_the_result_data(two_runs):
    results = [figure_data(out / "result.h5") for out in two_runs]
    # labelled by the case's name; two runs of one case by their folders,
    # here named like sweep cases: the parameter with its unit
    assert [r.label for r in results] == ["tiny", "tiny"]
    distinct_labels(results)
    assert [r.label for r in results] == [
        "tiny (angle = 45 deg)",
        "tiny (angle = 63 deg)",
    ]
    fig = figure_slip(results)
    lines = [ln for ln in fig.axes[0].lines if ln.get_linestyle() == "-"]
    assert len(lines) == 2
    dashed = [ln for ln in fig.axes[0].lines if ln.get_linestyle() == "--"]
    for line, jump, out in zip(lines, dashed, two_runs, strict=True):
        with h5py.File(out / "result.h5") as f:
            s, slip = f["fractures/0/s"][()], f["fractures/0/slip"][()]
            slid = f["fractures/0/plastic_slip"][()]
        np.testing.assert_array_equal(line.get_xdata(), s - s.min())
        # solid: what slid, dashed: the jump (mm)
        np.testing.assert_array_equal(line.get_ydata(), 1e3 * np.abs(slid))
        np.testing.assert_array_equal(jump.get_ydata(), 1e3 * np.abs(slip))
        assert line.get_label() == f"tiny (angle = {out.name[-2:]} deg)"


def test_plot_command_several_results(two_runs, tmp_path, runner):
    out = tmp_path / "figs"
    args = ["plot", *map(str, two_runs), "-o", str(out), "--figure", "slip"]
    result = runner.invoke(cli, [*args, "--figure", "mohr", "--format", "png"])
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["mohr.png", "slip.png"]
    assert result.stdout.split() == [str(out / "slip.png"), str(out / "mohr.png")]
    missing = runner.invoke(cli, ["plot", str(tmp_path / "none.h5")])
    assert missing.exit_code == 2
    assert missing.stderr.startswith("Error: ") and "no such file" in missing.stderr


def test_deformed_mesh_uses_the_split_mesh(two_runs):
    data = figure_data(two_runs[0] / "result.h5")
    assert data.vis_edges is not None and data.vis_points.shape[0] > len(data.points)
    # the jump: the vis mesh holds points at the same place with different
    # displacements (one copy per side of the fracture)
    keys = np.round(data.vis_points / 1e-9).astype(np.int64)
    _, inverse, counts = np.unique(
        keys, axis=0, return_inverse=True, return_counts=True
    )
    jump = 0.0
    for group in np.nonzero(counts > 1)[0][:400]:
        u = data.vis_displacement[inverse.ravel() == group]
        jump = max(jump, float(np.ptp(np.linalg.norm(u, axis=1))))
    slip = np.abs(data.fractures[0].slip).max()
    assert jump > 0.5 * slip


def test_a_result_vtu_of_another_run_is_not_drawn_and_said(two_runs, tmp_path, runner):
    """result.vtu beside result.h5 carries its run's run_id: one of another
    run (here the 63-degree run's) is named in a warning and left out (the
    figures draw result.h5's own mesh), never drawn as if it belonged."""
    folder = tmp_path / "mixed"
    folder.mkdir()
    shutil.copy(two_runs[0] / "result.h5", folder / "result.h5")
    shutil.copy(two_runs[1] / "result.vtu", folder / "result.vtu")
    assert figure_data(folder / "result.h5").vis_edges is None
    own = figure_data(two_runs[0] / "result.h5")
    assert own.vis_edges is not None
    args = ["plot", str(folder), "-o", str(tmp_path / "f"), "--format", "png"]
    result = runner.invoke(cli, [*args, "--figure", "deformed_mesh"])
    assert result.exit_code == 0, result.stderr
    warnings = [ln for ln in result.stderr.splitlines() if ln.startswith("WARNING:")]
    assert len(warnings) == 1 and str(folder / "result.vtu") in warnings[0]
    assert "is not of the run that wrote" in warnings[0]


def test_piece_outlines_drop_inner_edges_of_one_side():
    """A unit square fanned into 4 triangles about its centre, cut along y = x:
    each side is two triangles; their shared edge is inner, the rest remain."""
    c = [0.5, 0.5]
    corners = [[0, 0], [1, 0], [1, 1], [0, 1]]
    tri_pts = [
        [corners[k], corners[(k + 1) % 4], c] for k in range(4)
    ]  # bottom, right, top, left
    pts = np.array(tri_pts, dtype=float).reshape(-1, 2)
    tris = np.arange(12).reshape(4, 3)
    diag = np.column_stack([np.linspace(0, 1, 5), np.linspace(0, 1, 5)])
    fracture = FractureData(
        index=0,
        s=np.linspace(0, 1, 5),
        points=diag,
        slip=np.zeros(5),
        slid=np.zeros(5),
        normal_traction=np.zeros(5),
        shear_traction=np.zeros(5),
        state=np.zeros(5),
        theta=45.0,
        friction=0.1,
        cohesion=0.0,
    )
    edges = _piece_outlines(pts, tris, np.zeros(4, int), [fracture])
    assert edges.shape == (8, 2)
    segments = {tuple(sorted(map(tuple, pts[e]))) for e in edges}
    # the two inner edges (corner (1,0)-centre and (0,1)-centre) are gone
    assert ((0.5, 0.5), (1.0, 0.0)) not in segments
    assert ((0.0, 1.0), (0.5, 0.5)) not in segments
    # the diagonal pieces on the fracture are there (each side has its own)
    assert ((0.0, 0.0), (0.5, 0.5)) in segments and ((0.5, 0.5), (1.0, 1.0)) in segments


def test_auto_scale(two_runs):
    data = figure_data(two_runs[0] / "result.h5")
    size = 1.0
    slip = np.abs(data.fractures[0].slip).max()
    u_max = np.abs(data.displacement).max()
    expected = max(1.0, min(0.05 * size / slip, 0.15 * size / u_max))
    assert auto_scale(data) == pytest.approx(expected)
    assert auto_scale(data) * u_max <= 0.15 * size + 1e-12


@pytest.mark.parametrize(
    "stress", [(-20e6, -40e6, 0.0), (-31e6, -12e6, 9e6), (-5e6, -5.5e6, -3e6)]
)
def test_mohr_circle_point_is_the_plane_traction(stress):
    """The point drawn for a plane at theta (beta from sigma_1 on the circle)
    is (sigma_n, |tau|) of that plane, computed directly."""
    s1, s3, dir1 = principal(stress)
    centre, radius = -(s1 + s3) / 2, (s1 - s3) / 2
    for theta in np.linspace(0.0, 180.0, 19):
        x, y = _circle_point(centre, radius, angle_to_sigma1(theta, dir1))
        sn, tau = plane_stresses(stress, theta)
        assert x == pytest.approx(float(sn), abs=1e-6 * s1)
        assert y == pytest.approx(abs(float(tau)), abs=1e-6 * s1)


def test_figure_data_errors(tmp_path):
    with pytest.raises(UsageError, match="no such file"):
        figure_data(tmp_path / "result.h5")
    (tmp_path / "result.h5").write_text("not hdf5")
    with pytest.raises(UsageError, match="not a readable result.h5"):
        figure_data(tmp_path)
    with pytest.raises(UsageError, match="2 labels for 1 results"):
        plot_results([tmp_path], tmp_path / "f", labels=["a", "b"])


@pytest.mark.slow
def test_run_and_sweep_do_not_import_matplotlib(tmp_path):
    case = tmp_path / "c.toml"
    case.write_text(BASE)
    sweep = tmp_path / "s.toml"
    sweep.write_text('base = "c.toml"\n[vary]\n"material.E" = [5e9]\n')
    run = ["run", str(case), "-o", str(tmp_path / "o")]
    sweep_args = ["sweep", str(sweep), "-j", "1", "-o", str(tmp_path / "s")]
    code = "\n".join(
        [
            "import sys",
            "from click.testing import CliRunner",
            "from xfemslip.cli import cli",
            f"for args in ({run!r}, {sweep_args!r}):",
            "    r = CliRunner().invoke(cli, args)",
            "    assert r.exit_code == 0, r.output",
            "top = {m.split('.')[0] for m in sys.modules}",
            "print(sorted(top & {'matplotlib', 'distributed', 'dask'}))",
        ]
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_generated_network_gets_its_slip_mohr_and_network_figures(tmp_path, runner):
    """A result whose fractures come from [network.generate] (no [[fractures]]
    tables): every fracture is in the figure data with the friction of the
    network and the angle of its own chord, and slip, mohr and network are
    drawn."""
    import math

    from tests.support.casegen import sweep_member
    from xfemslip.case import loads_case

    text = sweep_member(
        index=0, **{"network.generate.count": 8, "mesh.elements": [30, 30]}
    )
    case = tmp_path / "net.toml"
    case.write_text(text)
    out = tmp_path / "out"
    assert runner.invoke(cli, ["run", "-q", str(case), "-o", str(out)]).exit_code == 0
    spec = loads_case(text, case)
    data = figure_data(out / "result.h5")
    assert len(data.fractures) == len(spec.fractures) > 0
    for fd, fr in zip(data.fractures, spec.fractures, strict=True):
        d = fr.points[-1] - fr.points[0]
        assert fd.theta == pytest.approx(math.degrees(math.atan2(d[1], d[0])))
        assert fd.friction == fr.friction and fd.cohesion == fr.cohesion
    figs = tmp_path / "figs"
    kinds = ["--figure", "slip", "--figure", "mohr", "--figure", "network"]
    result = runner.invoke(
        cli, ["plot", str(out), "-o", str(figs), "--format", "png", *kinds]
    )
    assert result.exit_code == 0, result.stderr
    for name in ("slip", "mohr", "network"):
        assert (figs / f"{name}.png").stat().st_size > 10_000


def test_panels_of_a_study_share_their_colour_scale(two_runs):
    """The columns of one figure compare by colour: each row's panels have
    the same limits, which span the 1st-99th percentile of every result's
    stresses (MPa; tips clipped) and all of their displacements (mm)."""
    from xfemslip.plot.figures import figure_displacement, figure_principal

    results = [figure_data(out / "result.h5") for out in two_runs]
    fig = figure_principal(results)
    axes = fig.axes[:4]  # the 2 x 2 panels, row by row; the colour bars follow
    for row, col in ((0, 1), (1, 0)):  # sigma_min, then sigma_max
        norms = [ax.collections[0].norm for ax in axes[2 * row : 2 * row + 2]]
        assert norms[0].vmin == norms[1].vmin and norms[0].vmax == norms[1].vmax
        values = np.concatenate([1e-6 * r.principal[:, col] for r in results])
        lo, hi = np.percentile(values, [1.0, 99.0])
        assert norms[0].vmin <= lo + 1e-9 and norms[0].vmax >= hi - 1e-9
    fig = figure_displacement(results)
    panels = fig.axes[:4]
    for row in range(2):
        levels = [ax.collections[0].levels for ax in panels[2 * row : 2 * row + 2]]
        np.testing.assert_array_equal(levels[0], levels[1])
        u = np.concatenate([1e3 * r.displacement[:, row] for r in results])
        assert levels[0][0] <= u.min() + 1e-12 and levels[0][-1] >= u.max() - 1e-12


def test_realization_histogram_has_whole_number_ticks(tmp_path):
    """Counts of fractures and of realizations are whole numbers, and so are
    the histogram's ticks (matplotlib's default locator gives 0.5 steps
    for a handful of realizations)."""
    from xfemslip.case import load_case
    from xfemslip.plot.dfn import figure_network

    summary = tmp_path / "summary.csv"
    rows = ["case_id,status,slipping_fractures,fractures"]
    rows += [f"{i:03d},ok,{n},15" for i, n in enumerate([1, 2, 2, 3])]
    summary.write_text("\n".join(rows) + "\n")
    spec = load_case(ROOT / "cases" / "fracture_network.toml")
    hist = figure_network(spec, None, summary).axes[-1]
    for ticks in (hist.get_xticks(), hist.get_yticks()):
        assert len(ticks) >= 2 and np.all(ticks == np.round(ticks))


def test_permeability_figure_draws_the_apertures_and_the_ratio(tmp_path, runner):
    """--figure permeability: the aperture [mm] and transmissivity curves are
    those of result.h5, the ratio panel starts at 1 in situ and ends at the
    stored tensor's ratio; a result without [permeability] is refused (2)."""
    case = tmp_path / "k.toml"
    case.write_text(BASE + "[permeability]\naperture = 1.0e-4\ndilation_angle = 5.0\n")
    out = tmp_path / "out"
    assert runner.invoke(cli, ["run", str(case), "-o", str(out)]).exit_code == 0
    result = runner.invoke(
        cli, ["plot", str(out), "--figure", "permeability", "--format", "png"]
    )
    assert result.exit_code == 0, result.output
    assert (out / "figures" / "permeability.png").read_bytes()[:8] == PNG
    from xfemslip import read_result
    from xfemslip.plot.permeability import figure_permeability

    read = read_result(out)
    fig = figure_permeability(out)
    ax_a, ax_t, ax_k = fig.axes
    ff = read.fractures[0]
    np.testing.assert_allclose(ax_a.lines[0].get_ydata(), ff.aperture * 1e3)
    np.testing.assert_allclose(ax_a.lines[1].get_ydata(), [0.1, 0.1])  # a0 [mm]
    np.testing.assert_allclose(ax_t.lines[0].get_ydata(), ff.transmissivity)
    kxx = ax_k.lines[0].get_ydata()
    assert kxx[0] == 1.0 and kxx[-1] == pytest.approx(read.permeability.ratio()[0])
    assert "tiny" in fig._suptitle.get_text()
    plain = tmp_path / "plain"
    case.write_text(BASE)
    assert runner.invoke(cli, ["run", str(case), "-o", str(plain)]).exit_code == 0
    refused = runner.invoke(cli, ["plot", str(plain), "--figure", "permeability"])
    assert refused.exit_code == 2
    assert "no permeability in this result" in refused.output


@pytest.fixture(scope="module")
def depleted(tmp_path_factory):
    """cases/depleting_reservoir.toml on 20 m cells in two steps (20 MPa of
    depletion): fractures 0 and 1 slip in the reservoir layer, 2 stays."""
    import tomllib

    root = tmp_path_factory.mktemp("depleted")
    case = tomllib.loads((ROOT / "cases" / "depleting_reservoir.toml").read_text())
    keys = {"mesh.elements": [40, 25], "loading.steps": 2, "output.formats": ["h5"]}
    (root / "case.toml").write_text(build.case_text(build.with_keys(case, **keys)))
    result = CliRunner().invoke(
        cli, ["run", str(root / "case.toml"), "-o", str(root / "out"), "-q"]
    )
    assert result.exit_code == 0, result.output
    return root / "out" / "result.h5"


def test_mohr_of_a_depletion_run_is_the_state_at_the_end(depleted):
    """The circle is the effective stress sigma + p I of the reservoir layer
    at the final step: the uniaxial-strain closed form (docs/depletion.md),
    sigma'_xx = -44 + 0.75 * 20 + 10 = -19 MPa, sigma'_yy = -62 + 10 = -52
    MPa, to the mesh's accuracy; the in-situ circle (-14, -32) MPa is drawn
    beside it; the points drawn are the fractures' stored effective
    tractions, red exactly where their state is slip; the text says which
    fractures slipped and never that no orientation slips."""
    from xfemslip.conventions import SLIP
    from xfemslip.plot.figures import figure_mohr

    data = figure_data(depleted)
    assert data.changed_cells == 40 * 5  # the layer's cells
    np.testing.assert_allclose(data.changed_stress, (-19e6, -52e6, 0.0), atol=0.05e6)
    assert data.in_situ_stress == (-14e6, -32e6, 0.0)
    fig = figure_mohr([data])
    ax = fig.axes[0]
    circles = {
        ln.get_label().split(":")[0]: ln
        for ln in ax.lines
        if ln.get_label().endswith("(compressive)")
    }
    assert set(circles) == {
        "in situ",
        "where the pore pressure changed, final step (median of 200 cells)",
    }
    end = circles["where the pore pressure changed, final step (median of 200 cells)"]
    assert end.get_xdata().min() == pytest.approx(-52e6, abs=0.05e6)
    assert end.get_xdata().max() == pytest.approx(-19e6, abs=0.05e6)
    assert circles["in situ"].get_xdata().min() == pytest.approx(-32e6)
    red = [ln for ln in ax.lines if ln.get_color() == "C3" and ln.get_marker() == "."]
    assert red[0].get_label() == "contact points in slip $(p_N, |p_T|)$"
    xs = np.concatenate([ln.get_xdata() for ln in red])
    ys = np.concatenate([ln.get_ydata() for ln in red])
    with h5py.File(depleted) as f:
        slip = [f[f"fractures/{i}/state"][()] == SLIP for i in range(3)]
        pn = [f[f"fractures/{i}/effective_normal_traction"][()] for i in range(3)]
        pt = [f[f"fractures/{i}/shear_traction"][()] for i in range(3)]
    assert [int(s.sum()) for s in slip][2] == 0 and all(s.any() for s in slip[:2])
    np.testing.assert_array_equal(
        xs, np.concatenate([p[s] for p, s in zip(pn, slip, strict=True)])
    )
    np.testing.assert_array_equal(
        ys, np.abs(np.concatenate([p[s] for p, s in zip(pt, slip, strict=True)]))
    )
    # the slipping points lie on the failure line |tau| = -0.5 sigma_n'
    np.testing.assert_allclose(ys, -0.5 * xs, rtol=1e-6)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert not any("no orientation slips" in t for t in texts)
    assert any(t.startswith("slips: $\\beta$") for t in texts)
    assert ax.get_title().endswith("fractures 0, 1 slip")


def test_mohr_never_says_no_orientation_slips_without_the_slipping_points():
    """A circle below the failure line whose run has slipping points (stress
    transferred around a reservoir, say): the legend counts them."""
    from matplotlib.figure import Figure

    from xfemslip.plot.mohr import add_legend, draw_mohr

    for states, words in (
        ([1, 2, 2, 0], "; 2 contact points of the run slip (red)"),
        ([1, 1, 1, 0], ""),
    ):
        fig = Figure()
        ax = fig.subplots()
        contact = [(np.full(4, -20e6), np.full(4, 12e6), np.array(states))]
        fracture = [("f", 45.0, 0.6, 0.0)]
        draw_mohr(ax, (-20e6, -40e6, 0.0), fractures=fracture, contact=contact)
        add_legend(fig)
        texts = [t.get_text() for t in fig.legends[0].get_texts()]
        line = [t for t in texts if "no orientation slips" in t]
        assert line == [
            f"f = 0.6: no orientation slips under this circle's stress{words}"
        ]
