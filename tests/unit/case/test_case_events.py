"""``[events]``: the out-of-plane extent of a moment magnitude."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from tests.unit.case.test_case import base, write
from xfemslip.case import describe, load_case
from xfemslip.cli import cli
from xfemslip.errors import CaseError


def test_without_events_the_spec_has_none_and_check_says_which_w(tmp_path):
    spec = load_case(write(tmp_path, base(), "plain.toml"))
    assert spec.events is None
    assert (
        "events: moment magnitudes for W = each fracture's slipping length "
        "(no events.extent)" in describe(spec)
    )


def test_extent_is_read_in_metres_and_printed_by_check(tmp_path):
    doc = base()
    doc["events"] = {"extent": 350.0}
    path = write(tmp_path, doc, "ev.toml")
    assert load_case(path).events.extent == 350.0
    result = CliRunner().invoke(cli, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "events: moment magnitudes for an out-of-plane extent W = 350 m" in (
        result.output
    )


def test_an_empty_events_table_leaves_the_extent_to_the_slipping_length(tmp_path):
    doc = base()
    doc["events"] = {}
    spec = load_case(write(tmp_path, doc, "empty.toml"))
    assert spec.events is not None and spec.events.extent is None


@pytest.mark.parametrize(
    "events, message",
    [
        ({"extent": 0.0}, "events.extent"),
        ({"extent": -5.0}, "events.extent"),
        ({"extent": 1e300}, "events.extent: must satisfy 0.001 <= extent <= 1e+07"),
        ({"extent": 5e-324}, "events.extent: must satisfy 0.001 <= extent <= 1e+07"),
        ({"extent": "100 MPa"}, "events.extent"),
        ({"extent": 100.0, "width": 3.0}, "events.width"),
    ],
)
def test_bad_events_name_the_key_and_exit_2(tmp_path, events, message):
    doc = base()
    doc["events"] = events
    path = write(tmp_path, doc, "bad.toml")
    with pytest.raises(CaseError) as info:
        load_case(path)
    assert message in str(info.value)
    result = CliRunner().invoke(cli, ["check", str(path)])
    assert result.exit_code == 2
    assert message in result.output and len(result.output.strip().splitlines()) == 1
