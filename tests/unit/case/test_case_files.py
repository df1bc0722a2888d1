"""Reading input files (xfemslip.case.files): size caps, special files,
encodings, TOML nesting, paths that no file system holds."""

from __future__ import annotations

import io
import os
import signal
import threading
from pathlib import Path

import pytest

from xfemslip.case import (
    MAX_NAME_BYTES,
    MAX_TOML_DEPTH,
    build,
    load_case,
    loads_case,
    parse_toml,
    path_problem,
)
from xfemslip.case.files import READ_CHUNK, UnreadableInput, input_folder, read_input
from xfemslip.errors import CaseError

TINY = {
    "name": "tiny",
    "domain": {"size": [1.0, 1.0]},
    "mesh": {"elements": [2, 2]},
    "material": {"E": 1.0e9, "nu": 0.25},
    "boundary": {"bottom": {"uy": 0.0}},
}
CASE = build.case_text(TINY)


def _refusal(path, limit=10**6) -> str:
    with pytest.raises(UnreadableInput) as info:
        read_input(path, limit)
    return str(info.value)


# --------------------------------------------------------------------------- #
# read_input
# --------------------------------------------------------------------------- #


def test_a_multi_chunk_file_reads_back_byte_for_byte(tmp_path):
    text = "".join(f"{i},{i * 0.5!r}\n" for i in range(400_000))
    assert len(text) > 3 * READ_CHUNK  # several chunks, the last one partial
    path = tmp_path / "big.csv"
    path.write_text(text)
    assert read_input(path, 2 * len(text)) == text


def test_a_byte_order_mark_is_dropped(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + CASE.encode())
    assert read_input(path, 10**6) == CASE
    assert load_case(path).name == "tiny"


@pytest.mark.parametrize(
    ("device", "kind"),
    [("/dev/zero", "character device"), ("/dev/urandom", "character device")],
)
def test_devices_are_refused_unread(device, kind):
    assert _refusal(device) == f"is a {kind}, not a regular file or a pipe"


def test_a_fifo_nobody_writes_to_is_refused_without_waiting(tmp_path):
    """Opened while nothing writes to it, a named pipe reads as its end at
    once; every reader (case, sweep base, CSV, DFN summary) refuses that."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    result = {}

    def read() -> None:
        try:
            result["r"] = read_input(fifo, 100)
        except UnreadableInput as exc:
            result["error"] = str(exc)

    reader = threading.Thread(target=read)
    reader.start()
    reader.join(timeout=10)  # the harness's bound: a blocking open never returns
    if reader.is_alive():  # unblock the reader so the test process can end
        with open(fifo, "w"):
            pass
        reader.join()
    assert "r" not in result
    assert "pipe that gave nothing" in result["error"]
    with pytest.raises(CaseError, match="pipe that gave nothing"):
        load_case(fifo)


def test_a_pipe_is_read_to_its_end_with_the_cap(tmp_path):
    """A process substitution ``<(...)``: the read end of a pipe, named by
    /proc/self/fd/N, whose writer writes in pieces and then closes it; its
    relative CSV paths resolve against the working directory."""
    read_end, write_end = os.pipe()
    data = CASE.encode() * 3

    def write() -> None:
        for k in range(0, len(data), 1000):
            os.write(write_end, data[k : k + 1000])
        os.close(write_end)

    writer = threading.Thread(target=write)
    writer.start()
    try:
        path = f"/proc/self/fd/{read_end}"
        assert read_input(path, 10**6) == data.decode()
        assert input_folder(path) == Path(".")
    finally:
        writer.join()
        os.close(read_end)
    read_end, write_end = os.pipe()
    writer = threading.Thread(
        target=lambda: (os.write(write_end, b"x" * 5000), os.close(write_end))
    )
    writer.start()
    try:
        assert _refusal(f"/proc/self/fd/{read_end}", limit=4000).startswith(
            "more than the limit"
        )
    finally:
        writer.join()
        os.close(read_end)


def test_standard_input_is_the_path_dash(monkeypatch, tmp_path):
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(CASE.encode())))
    assert read_input("-", 10**6) == CASE
    assert input_folder("-") == Path(".")
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(CASE.encode())))
    monkeypatch.chdir(tmp_path)
    spec = load_case("-")
    assert spec.name == "tiny" and str(spec.path) == "-"
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(b"x" * 5000)))
    assert _refusal("-", limit=4000) == "more than the limit of 0.00381 MB"


def test_a_directory_and_a_missing_file_are_refused(tmp_path):
    assert _refusal(tmp_path) == "is a directory, not a regular file or a pipe"
    assert _refusal(tmp_path / "nope") == "No such file or directory"


def test_a_file_over_the_cap_is_refused_from_its_size(tmp_path):
    path = tmp_path / "sparse.toml"
    with open(path, "wb") as fh:
        fh.truncate(3 * 2**20 + 1)  # sparse: nothing to read, only the size
    message = _refusal(path, limit=3 * 2**20)
    assert message == "the file is 3 MB, more than the limit of 3 MB"
    assert _refusal(path, limit=2**20).startswith("the file is 3 MB")


def test_a_file_that_reports_no_size_is_capped_while_read():
    # /proc files report size 0; /proc/self/maps of this process is > 1 kB
    message = _refusal("/proc/self/maps", limit=1000)
    assert message.startswith("more than the limit of 0.000954 MB")
    assert "does not report its size" in message


def test_invalid_utf8_names_the_byte(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'name = "sm\xe4ll"\n')
    assert (
        _refusal(path) == "not a UTF-8 text file: invalid continuation byte at byte 10"
    )


def test_a_nul_byte_in_the_path_is_refused():
    assert _refusal("ca\0se.toml") == "the path contains a NUL byte"


def test_load_case_names_the_file_and_the_reason(tmp_path):
    with pytest.raises(CaseError) as info:
        load_case(tmp_path)
    assert str(info.value) == (
        f"{tmp_path}: cannot read the case file: is a directory, not a regular "
        "file or a pipe"
    )


def test_signals_are_handled_between_chunks(tmp_path):
    """A signal that arrives while a file is read is handled inside the read
    loop, between two chunks, not once the whole file is in (one read() of
    /dev/zero never returned, so its signals were never handled)."""
    path = tmp_path / "big.csv"
    path.write_bytes(b"0" * (64 * READ_CHUNK))
    where = []

    def handler(signum, frame):
        where.append(frame.f_code.co_name)

    previous = signal.signal(signal.SIGALRM, handler)
    try:
        signal.setitimer(signal.ITIMER_REAL, 1e-4, 1e-4)  # every 0.1 ms
        for _ in range(20):
            read_input(path, 65 * READ_CHUNK)
            if "_read_capped" in where:
                break
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert "_read_capped" in where, sorted(set(where))


# --------------------------------------------------------------------------- #
# parse_toml
# --------------------------------------------------------------------------- #


def _nested_arrays(depth: int) -> str:
    return "a = " + "[" * depth + "1" + "]" * depth + "\n"


def test_nesting_up_to_the_cap_parses():
    # the array sits under the root table: depth + 1 levels
    doc = parse_toml(_nested_arrays(MAX_TOML_DEPTH - 1), "x.toml")
    node, levels = doc["a"], 1
    while isinstance(node, list):
        node, levels = node[0], levels + 1
    assert levels == MAX_TOML_DEPTH


@pytest.mark.parametrize("depth", [MAX_TOML_DEPTH, 100])
def test_nesting_past_the_cap_names_the_key(depth):
    with pytest.raises(CaseError) as info:
        parse_toml(_nested_arrays(depth), "x.toml")
    assert info.value.problems == [
        (
            "a[0][0][0]...",
            f"tables or arrays nested more than {MAX_TOML_DEPTH} levels deep",
        )
    ]


@pytest.mark.parametrize(
    "text",
    [
        _nested_arrays(5000),
        "a = " + "{ b = " * 5000 + "1" + " }" * 5000,
        ".".join(["k"] * 5000) + " = 1",  # parsed without recursion, then refused
        "[" + ".".join(["k"] * 5000) + "]",
    ],
    ids=["arrays", "inline-tables", "dotted-key", "table-header"],
)
def test_nesting_5000_deep_is_one_case_error(text):
    with pytest.raises(CaseError) as info:
        loads_case(text, "deep.toml")
    assert str(info.value).startswith("deep.toml: ")
    assert "nested" in str(info.value) and "32 levels" in str(info.value)


def test_an_integer_of_4301_digits_is_a_case_error():
    with pytest.raises(CaseError) as info:
        parse_toml("steps = " + "9" * 4301, "x.toml")
    message = info.value.problems[0][1]
    assert message.startswith("TOML value error: Exceeds the limit (4300 digits)")
    assert "set_int_max_str_digits" not in message  # Python's advice, not ours


# --------------------------------------------------------------------------- #
# Paths: name, output.directory
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    ("path", "problem"),
    [
        ("out/ok", None),
        ("a" * 255, None),
        ("a" * 256, "has a part of 256 bytes"),
        ("out/" + "\u00e9" * 128, "has a part of 256 bytes"),  # 2 bytes each
        ("/".join(["d"] * 2048), None),  # 4095 bytes
        ("/".join(["d"] * 2049), "is 4097 bytes long, more than 4095"),
        ("o\0ut", "contains a NUL byte"),
    ],
)
def test_path_problem(path, problem):
    found = path_problem(path)
    if problem is None:
        assert found is None
    else:
        assert found.startswith(problem)


def _case_with(name=None, directory=None) -> str:
    """The tiny case without a name, or with ``name``, and an output directory."""
    output = None if directory is None else {"directory": directory}
    return build.case_text(dict(TINY, name=name, output=output))


def test_name_of_255_bytes_is_accepted_and_256_refused():
    assert loads_case(_case_with(name="n" * MAX_NAME_BYTES)).name
    with pytest.raises(CaseError) as info:
        loads_case(_case_with(name="\u00e9" * 128))  # 256 bytes
    assert info.value.problems == [
        (
            "name",
            "is 256 bytes long, more than the 255 of a folder name (it names the "
            "output directory)",
        )
    ]


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ("o\u0000ut", "contains a NUL byte"),
        ("d" * 256, "has a part of 256 bytes"),
    ],
)
def test_output_directory_no_file_system_holds_is_refused(value, problem):
    with pytest.raises(CaseError) as info:
        loads_case(_case_with(directory=value))
    (key, message), *_ = info.value.problems
    assert key == "output.directory" and message.startswith(problem)


def test_case_error_spells_out_at_most_20_problems():
    text = build.case_text({**{f"k{i}": i for i in range(1000)}, **TINY})
    with pytest.raises(CaseError) as info:
        loads_case(text, "many.toml")
    err = info.value
    assert len(err.problems) == 1000
    message = str(err)
    assert message.startswith("many.toml: 1000 problems: k0: unknown key 'k0'")
    assert message.endswith("; and 980 more")
    assert message.count("unknown key") == 20
