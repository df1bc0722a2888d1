"""The event table that ends ``xfemslip run`` and ``xfemslip summary``.

The numbers of the table are checked against the result's arrays, computed
here independently: the slip is the one that slid (``plastic_slip``), each
contact point weighs the stretch between the midpoints to its neighbours,
the ends of a fracture inside the domain at s = 0 and s = its length;
mu = E / (2 (1 + nu)); Mw = (2/3) (log10 M0 - 9.1) (IASPEI).
"""

from __future__ import annotations

import math
import shutil

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import xfemslip
from xfemslip.cli import cli

E, NU = 10.0e9, 0.25
MU = E / (2 * (1 + NU))
# two fractures at 45 degrees, |tau| = 10 MPa on sigma_n = -30 MPa: with
# friction 0.1 the first slips, with 0.6 the second sticks; a third, at
# 0 degrees with no shear on it, sticks too.  The top edge then moves down
# by 0.2 mm over the two steps (about 1 MPa more vertical compression): the
# first slips further, the others keep stuck.
FRACTURES = (
    ([[0.3, 0.3], [0.6, 0.6]], 0.1),
    ([[1.3, 0.3], [1.6, 0.6]], 0.6),
    ([[0.4, 1.5], [1.6, 1.5]], 0.1),
)
HEAD = f"""name = "events-unit"
[domain]
size = [2.0, 2.0]
[mesh]
elements = [40, 40]
[material]
E = {E!r}
nu = {NU!r}
[loading]
stress = {{ xx = -20.0e6, yy = -40.0e6 }}
initial_stress = {{ xx = -20.0e6, yy = -40.0e6 }}
steps = 2
[boundary]
bottom = {{ uy = 0.0 }}
top = {{ uy = -2.0e-4 }}
left = {{ ux = 0.0 }}
right = {{ ux = 0.0 }}
[output]
formats = ["h5"]
"""


def _fractures_toml() -> str:
    return "".join(
        f"[[fractures]]\npoints = {points}\nfriction = {f}\ncohesion = 0.0\n"
        for points, f in FRACTURES
    )


def _write(tmp_path, extra: str = "") -> str:
    path = tmp_path / "case.toml"
    path.write_text(HEAD + extra + _fractures_toml(), encoding="utf-8")
    return str(path)


def _expected(result, extent=None):
    """(slipped, max slip [mm], slipping length [m], M0', Mw, W) per fracture
    of the final step, from the arrays."""
    rows = []
    for (points, _), ff in zip(FRACTURES, result.fractures, strict=True):
        length = math.dist(*points)
        mid = 0.5 * (ff.s[1:] + ff.s[:-1])
        stretch = np.diff(np.concatenate([[0.0], mid, [length]]))
        slipping = ff.state == 2
        m0 = MU * float(np.sum(stretch * np.abs(ff.plastic_slip)))
        lslip = float(np.sum(stretch[slipping]))
        w = extent if extent is not None else lslip
        mw = (2 / 3) * (math.log10(m0 * w) - 9.1) if m0 * w > 0 else -math.inf
        max_mm = np.abs(ff.plastic_slip).max() * 1e3
        rows.append((bool(slipping.any()), max_mm, lslip, m0, mw, w))
    return rows


def _table(output: str) -> list[list[str]]:
    lines = output.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("fracture "))
    return [line.split() for line in lines[start + 1 : start + 1 + len(FRACTURES)]]


def _check_table(output, result, extent=None):
    for row, exp in zip(_table(output), _expected(result, extent), strict=True):
        slipped, max_mm, lslip, m0, mw, w = exp
        assert row[1] == ("yes" if slipped else "no")
        assert float(row[2]) == pytest.approx(max_mm, rel=1e-3)
        assert float(row[3]) == pytest.approx(lslip, rel=1e-3, abs=1e-12)
        assert float(row[4]) == pytest.approx(m0, rel=1e-3)
        if math.isfinite(mw):
            assert float(row[6]) == pytest.approx(mw, abs=0.006)
            assert float(row[7]) == pytest.approx(w, rel=1e-3)
        else:
            assert row[6] == "-" and row[7] == "-"


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    """The case run once through the CLI: (output, result folder)."""
    tmp = tmp_path_factory.mktemp("events")
    out = tmp / "out"
    result = CliRunner().invoke(cli, ["run", _write(tmp), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return result.output, out


def test_run_ends_with_the_table_of_the_result_arrays(ran):
    output, out = ran
    result = xfemslip.read_result(out)
    expected = _expected(result)
    assert [e[0] for e in expected] == [True, False, False]  # as designed
    _check_table(output, result)
    last = output.strip().splitlines()[-1]
    slipped = expected[0]
    assert last == (
        f"1 of 3 fractures slipped; max slip {slipped[1]:.3g} mm on fracture 0 "
        f"over {slipped[2]:.3g} m; Mw {slipped[4]:.2f} for W = {slipped[5]:.3g} m "
        "(the slipping length)"
    )


def test_summary_prints_the_same_table_for_the_result_folder(ran):
    output, out = ran
    result = CliRunner().invoke(cli, ["summary", str(out)])
    assert result.exit_code == 0, result.output
    assert result.output.startswith("events-unit: converged, 2 converged step(s)")
    tail = output.splitlines()[-(len(FRACTURES) + 3) :]
    assert result.output.splitlines()[-(len(FRACTURES) + 3) :] == tail
    again = CliRunner().invoke(cli, ["summary", str(out / "result.h5")])
    assert again.output == result.output


def test_summary_steps_prints_a_table_per_load_step(ran):
    """The table of each step is that step's arrays (the slip grows from
    step 1 to step 2 as the top edge moves down)."""
    _, out = ran
    result = CliRunner().invoke(cli, ["summary", str(out), "--steps"])
    assert result.exit_code == 0, result.output
    read = xfemslip.read_result(out)
    blocks = result.output.split("fractures at step ")[1:]
    assert [b.split(" ", 1)[0] for b in blocks] == ["1", "2"]
    first, second = (np.abs(s.fractures[0].plastic_slip).max() for s in read.steps)
    assert second > 1.01 * first
    for block, step in zip(blocks, read.steps, strict=True):
        rows = _table("\n".join(block.splitlines()[1:]))
        for row, ff in zip(rows, step.fractures, strict=True):
            slid = np.abs(ff.plastic_slip).max() * 1e3
            assert float(row[2]) == pytest.approx(slid, rel=1e-3, abs=1e-12)
    # each step ends with what its own slip added (fracture 0 slips in both)
    one, two = (step.fractures[0].plastic_slip for step in read.steps)
    grow = np.abs(two - one)
    last = blocks[1].splitlines()[-1]
    assert last.startswith("this step alone: fracture 0 +")
    assert float(last.split("+", 1)[1].split(" mm")[0]) == pytest.approx(
        grow.max() * 1e3, rel=1e-2
    )


def test_quiet_run_leaves_the_table_out(tmp_path):
    result = CliRunner().invoke(
        cli, ["run", _write(tmp_path), "-o", str(tmp_path / "o"), "-q"]
    )
    assert result.exit_code == 0, result.output
    assert "fractures slipped" not in result.output
    assert "M0'" not in result.output


def test_events_extent_is_the_w_of_every_magnitude(tmp_path):
    path = _write(tmp_path, "[events]\nextent = 300.0\n")
    result = CliRunner().invoke(cli, ["run", path, "-o", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    _check_table(result.output, xfemslip.read_result(tmp_path / "o"), 300.0)
    assert result.output.strip().endswith("for W = 300 m (events.extent)")


def _as_written_before(folder, keep_events: bool) -> None:
    """Strip from a result.h5 what an older version did not write: the
    plastic slip, the fractures' elastic constants and ends, the elastic
    model, and /events unless ``keep_events``."""
    with h5py.File(folder / "result.h5", "r+") as h5:
        del h5.attrs["material_model"]
        if not keep_events:
            del h5["events"]
        groups = [h5["fractures"]]
        groups += [h5[f"steps/{k}/fractures"] for k in h5["steps"]]
        for parent in groups:
            for g in parent.values():
                for name in ("plastic_slip", "shear_modulus", "poisson_ratio"):
                    if name in g:
                        del g[name]
                if "ends" in g.attrs:
                    del g.attrs["ends"]


def test_summary_of_an_older_result_counts_the_jump_and_says_so(ran, tmp_path):
    """A result written before the plastic slip, the elastic constants and
    the event sizes were kept: the max slip is that of the tangential jump,
    the slipping length uses ends estimated from the contact points, no
    moment or magnitude (mu unknown), and the summary says all of it."""
    _, out = ran
    older = tmp_path / "older"
    shutil.copytree(out, older)
    _as_written_before(older, keep_events=False)
    read = xfemslip.read_result(older)
    assert read.events is None and read.fracture_properties is None
    assert read.fractures[0].plastic_slip is None
    result = CliRunner().invoke(cli, ["summary", str(older)])
    assert result.exit_code == 0, result.output
    assert "the elastic give of stuck points included" in result.output
    assert "fracture ends estimated from the contact points" in result.output
    for row, ff in zip(_table(result.output), read.fractures, strict=True):
        s = ff.s
        ends = (s[0] - 0.5 * (s[1] - s[0]), s[-1] + 0.5 * (s[-1] - s[-2]))
        mid = 0.5 * (s[1:] + s[:-1])
        stretch = np.diff(np.concatenate([[ends[0]], mid, [ends[1]]]))
        assert float(row[2]) == pytest.approx(np.abs(ff.slip).max() * 1e3, 1e-3)
        assert float(row[3]) == pytest.approx(
            np.sum(stretch[ff.state == 2]), rel=1e-3, abs=1e-12
        )
        assert row[4] == "-" and row[6] == "-"


def test_summary_of_an_older_result_with_events_shows_them_with_a_note(ran, tmp_path):
    """An older result that kept /events: its stored table, and the note that
    its slip is the tangential jump."""
    _, out = ran
    older = tmp_path / "older"
    shutil.copytree(out, older)
    _as_written_before(older, keep_events=True)
    runner = CliRunner()
    original = runner.invoke(cli, ["summary", str(out)])
    result = runner.invoke(cli, ["summary", str(older)])
    assert result.exit_code == 0, result.output
    assert _table(result.output) == _table(original.output)
    assert "note: this result has no plastic_slip" in result.output
    assert "note:" not in original.output


def test_summary_of_a_missing_file_or_not_a_result_exits_2(tmp_path):
    runner = CliRunner()
    missing = runner.invoke(cli, ["summary", str(tmp_path / "nope.h5")])
    assert missing.exit_code == 2
    assert missing.output.strip().splitlines() == [
        f"Error: {tmp_path / 'nope.h5'}: no such file (expected a result.h5)"
    ]
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as h5:
        h5["data"] = np.arange(3)
    result = runner.invoke(cli, ["summary", str(other)])
    assert result.exit_code == 2
    assert len(result.output.strip().splitlines()) == 1
    assert "not a result.h5 of xfemslip" in result.output


def test_result_h5_keeps_the_event_sizes_of_every_step(ran):
    """/events holds, per step and fracture, the numbers computed here from
    the arrays (the final step against _expected; the step numbers)."""
    _, out = ran
    result = xfemslip.read_result(out)
    with h5py.File(out / "result.h5", "r") as h5:
        group = h5["events"]
        assert list(group["step"][()]) == [1, 2]
        assert group["moment"].attrs["units"] == "N m"
        assert group["max_slip"].shape == (2, len(FRACTURES))
        moment = group["moment"][()]
        stress_drop = group["stress_drop"][()]
    events = result.events
    assert not events.extent_given
    for i, exp in enumerate(_expected(result)):
        slipped, max_mm, lslip, m0, _, w = exp
        assert bool(events.slipped[-1, i]) == slipped
        assert events.max_slip[-1, i] * 1e3 == pytest.approx(
            max_mm, rel=1e-12, abs=1e-300
        )
        assert events.slipping_length[-1, i] == pytest.approx(lslip, rel=1e-12)
        assert events.moment_per_length[-1, i] == pytest.approx(
            m0, rel=1e-12, abs=1e-300
        )
        assert moment[-1, i] == pytest.approx(m0 * w, rel=1e-12, abs=1e-300)
        # the stress drop is undefined without slip: NaN, in memory and in the file
        assert math.isnan(events.stress_drop[-1, i]) == (lslip == 0.0)
        assert math.isnan(stress_drop[-1, i]) == (lslip == 0.0)
    # the increments of step 2: mu int |s2 - s1| ds, and step 1's are its own
    for i, (points, _) in enumerate(FRACTURES):
        s1, s2 = (step.fractures[i] for step in result.steps)
        mid = 0.5 * (s2.s[1:] + s2.s[:-1])
        stretch = np.diff(np.concatenate([[0.0], mid, [math.dist(*points)]]))
        added = s2.plastic_slip - s1.plastic_slip
        inc = MU * float(np.sum(stretch * np.abs(added)))
        assert events.moment_per_length_increment[1, i] == pytest.approx(
            inc, rel=1e-12, abs=1e-300
        )
        assert events.max_slip_increment[1, i] == pytest.approx(
            np.abs(added).max(), rel=1e-12, abs=1e-300
        )
        assert events.moment_per_length_increment[0, i] == pytest.approx(
            events.moment_per_length[0, i], rel=1e-12
        )


def test_summary_reads_the_stored_event_sizes(ran, tmp_path):
    """The table comes from /events when the file has it: a number changed
    there shows; the same file without /events gives the recomputed table."""
    _, out = ran
    edited, stripped = tmp_path / "edited", tmp_path / "stripped"
    shutil.copytree(out, edited)
    shutil.copytree(out, stripped)
    with h5py.File(edited / "result.h5", "r+") as h5:
        h5["events/max_slip"][-1, 1] = 0.123456  # m
    with h5py.File(stripped / "result.h5", "r+") as h5:
        del h5["events"]
    runner = CliRunner()
    original = runner.invoke(cli, ["summary", str(out)])
    assert "123.5" in runner.invoke(cli, ["summary", str(edited)]).output
    again = runner.invoke(cli, ["summary", str(stripped)])
    assert again.exit_code == 0, again.output
    assert _table(again.output) == _table(original.output)
    # a group lacking one of its datasets is not trusted: recomputed as well
    partial = tmp_path / "partial"
    shutil.copytree(out, partial)
    with h5py.File(partial / "result.h5", "r+") as h5:
        del h5["events/moment_per_length_increment"]
    assert xfemslip.read_result(partial).events is None
    third = runner.invoke(cli, ["summary", str(partial)])
    assert _table(third.output) == _table(original.output)
