"""File families of the bad-input suite: TOML nesting depth, special and
oversized files wherever a file is read, bytes that are not clean UTF-8 TOML,
boundary and network CSV files."""

from __future__ import annotations

import random

from tests.support.bad_inputs.base import (
    BIG_INT_TEXT,
    OUT,
    RUN,
    SWEEP,
    Input,
    Special,
    _lazy,
    network_case,
    small,
    toml,
)

# --------------------------------------------------------------------------- #
# Nesting, bytes, special files
# --------------------------------------------------------------------------- #


def nested(kind: str, depth: int) -> str:
    """A TOML line (or header) nested ``depth`` levels deep."""
    if kind == "array":
        return "deep = " + "[" * depth + "1" + "]" * depth + "\n"
    if kind == "inline":
        return "deep = " + "{ a = " * depth + "1" + " }" * depth + "\n"
    if kind == "dotted":
        return ".".join(["deep"] * depth) + " = 1\n"
    if kind == "header":
        return "[" + ".".join(["deep"] * depth) + "]\nx = 1\n"
    if kind == "mixed":
        return "deep = " + "[{ a = " * (depth // 2) + "1" + "}]" * (depth // 2) + "\n"
    raise ValueError(kind)


def nesting_inputs() -> list[Input]:
    out = []
    base = toml(small())
    for kind in ("array", "inline", "dotted", "header", "mixed"):
        for depth in (31, 33, 100, 400, 1000, 5000):
            junk = nested(kind, depth)
            out.append(
                Input(
                    id=f"nesting/case/{kind}/{depth}",
                    family="nesting",
                    files={
                        "case.toml": junk + base if kind != "header" else base + junk
                    },
                    argv=(*RUN, "case.toml", "-o", OUT),
                    names=("case.toml",),
                )
            )
        for depth in (400, 5000):
            junk = nested(kind, depth)
            out.append(
                Input(
                    id=f"nesting/sweep/{kind}/{depth}",
                    family="nesting",
                    files={
                        "sweep.toml": junk + SWEEP
                        if kind != "header"
                        else SWEEP + junk,
                        "base.toml": base,
                    },
                    argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                    names=("sweep.toml",),
                )
            )
            out.append(
                Input(
                    id=f"nesting/sweep-base/{kind}/{depth}",
                    family="nesting",
                    files={
                        "sweep.toml": SWEEP,
                        "base.toml": junk + base if kind != "header" else base + junk,
                    },
                    argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                    names=("sweep.toml", "base"),
                )
            )
    # the varied value itself deeply nested
    out.append(
        Input(
            id="nesting/sweep-vary-value",
            family="nesting",
            files={
                "sweep.toml": SWEEP.replace(
                    "[0.2, 0.4]", "[" + "[" * 2000 + "]" * 2000 + "]"
                ),
                "base.toml": base,
            },
            argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
            names=("sweep.toml",),
        )
    )
    return out


def _big_toml(size: int) -> bytes:
    """A valid small case padded with comment lines to ``size`` bytes."""
    head = toml(small()).encode()
    line = b"# " + b"x" * 97 + b"\n"
    return head + line * ((size - len(head)) // len(line) + 1)


SPECIALS = {
    "dev-zero": Special("symlink", "/dev/zero"),
    "dev-urandom": Special("symlink", "/dev/urandom"),
    "dev-null": Special("symlink", "/dev/null"),
    "fifo": Special("fifo"),
    "directory": Special("dir"),
    "dangling-link": Special("symlink", "no-such-target"),
    "sparse-100MB": Special("sparse", 100 * 2**20),
    # mode 000 (root reads it anyway: then its content is refused)
    "unreadable": Special("unreadable", b"x = = 1\n"),
}


def special_file_inputs() -> list[Input]:
    """Every place a file is read gets a device, a FIFO, a directory, a huge
    file...; the case file itself also by its real path (/dev/zero)."""
    out = [
        Input(
            id=f"special/case-path/{name}",
            family="special-files",
            argv=(*RUN, name, "-o", OUT),
            names=(name,),
        )
        for name in ("/dev/zero", "/dev/urandom", "/dev/stdin", "/proc/self/status")
    ]
    places = {
        "case": ("case.toml", {}, (*RUN, "case.toml", "-o", OUT)),
        "boundary-csv": (
            "left.csv",
            {
                "case.toml": toml(
                    small(
                        boundary={"bottom": {"uy": 0.0}, "left": {"file": "left.csv"}}
                    )
                )
            },
            (*RUN, "case.toml", "-o", OUT),
        ),
        "network-csv": (
            "net.csv",
            {"case.toml": toml(network_case(file="net.csv"))},
            (*RUN, "case.toml", "-o", OUT),
        ),
        "sweep": (
            "sweep.toml",
            {"base.toml": toml(small())},
            ("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
        ),
        "sweep-base": (
            "base.toml",
            {"sweep.toml": SWEEP},
            ("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
        ),
    }
    oversized = {
        "toml-9MB": Special("lazy", lambda: _big_toml(9 * 2**20)),
        "csv-40MB": Special(
            "lazy", lambda: b"x,y,ux,uy\n" + b"0,0,0,0\n" * (5 * 2**20)
        ),
    }
    for place, (target, others, argv) in places.items():
        kinds = dict(SPECIALS)
        kinds["oversized"] = (
            oversized["csv-40MB"] if target.endswith(".csv") else oversized["toml-9MB"]
        )
        for kind, special in kinds.items():
            out.append(
                Input(
                    id=f"special/{place}/{kind}",
                    family="special-files",
                    files={**others, target: special},
                    argv=argv,
                    names=(target,),
                )
            )
    return out


def byte_inputs(rng: random.Random) -> list[Input]:
    """Case files that are not clean UTF-8 TOML, and clean ones in odd dress."""
    text = toml(small())
    raw = text.encode()
    cases = {
        "bom": (b"\xef\xbb\xbf" + raw, {0}),
        "crlf": (raw.replace(b"\n", b"\r\n"), {0}),
        "lone-cr": (raw.replace(b"\n", b"\r"), {2}),
        "utf16": (text.encode("utf-16"), {2}),
        "latin1-name": (raw.replace(b'"small"', b'"sm\xe4ll"'), {2}),
        "nul-byte": (raw.replace(b"[mesh]", b"[me\x00sh]"), {2}),
        "control-char": (raw.replace(b"[mesh]", b"[mesh]\x07"), {2}),
        "empty": (b"", {2}),
        "whitespace": (b" \n\t\n", {2}),
        "long-line-5MB": (lambda: raw + b"# " + b"y" * (5 * 2**20) + b"\n", {0}),
        "long-string-5MB": (
            lambda: raw.replace(b'"small"', b'"' + b"s" * (5 * 2**20) + b'"'),
            {2},
        ),
        "many-keys": (
            lambda: raw + b"".join(b"k%d = %d\n" % (i, i) for i in range(200_000)),
            {2},
        ),
        "nan-literal": (raw.replace(b"E = 1000000000.0", b"E = nan"), {2}),
        "inf-literal": (raw.replace(b"E = 1000000000.0", b"E = +inf"), {2}),
        "negzero-literal": (raw.replace(b"cohesion = 0.0", b"cohesion = -0.0"), {0}),
        "hex-int": (raw.replace(b"steps = 2", b"steps = 0x2"), {0}),
        "int-4301-digits": (raw.replace(b"steps = 2", b"steps = " + b"9" * 4301), {2}),
        "int-1e400": (
            raw.replace(b"steps = 2", b"steps = " + BIG_INT_TEXT.encode()),
            {2},
        ),
        "float-1e400": (raw.replace(b"E = 1000000000.0", b"E = 1e400"), {2}),
        "duplicate-key": (
            raw.replace(b"[mesh]\n", b"[mesh]\nelements = [2, 2]\n"),
            {2},
        ),
        "datetime": (
            raw.replace(b"E = 1000000000.0", b"E = 1979-05-27T07:32:00Z"),
            {2},
        ),
    }
    out = [
        Input(
            id=f"bytes/{name}",
            family="bytes",
            files={
                "case.toml": data if isinstance(data, bytes) else Special("lazy", data)
            },
            argv=(*RUN, "case.toml", "-o", OUT),
            expect=frozenset(expect),
            names=("case.toml",) if expect == {2} else (),
        )
        for name, (data, expect) in cases.items()
    ]
    for _ in range(12):  # truncated at a random byte
        cut = rng.randrange(1, len(raw))
        out.append(
            Input(
                id=f"bytes/truncated-{cut}",
                family="bytes",
                files={"case.toml": raw[:cut]},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}),
            )
        )
    for k in range(6):  # random bytes
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 4000)))
        out.append(
            Input(
                id=f"bytes/random-{k}",
                family="bytes",
                files={"case.toml": data},
                argv=(*RUN, "case.toml", "-o", OUT),
                names=("case.toml",),
            )
        )
    return out


# --------------------------------------------------------------------------- #
# CSV files
# --------------------------------------------------------------------------- #


def _edge_rows(n: int) -> list[str]:
    """n valid rows of the left edge (x = 0, y from 0 to 1)."""
    return [f"0.0,{i / (n - 1)!r},0.0,{-1e-4 * i / (n - 1)!r}" for i in range(n)]


def boundary_csv_inputs() -> list[Input]:
    header = "x,y,ux,uy"
    good = [header, *_edge_rows(5)]
    bodies = {
        "valid": ("\n".join(good), {0}),
        "valid-bom-crlf": ("\ufeff" + "\r\n".join(good), {0}),
        "valid-100k-rows": (lambda: "\n".join([header, *_edge_rows(100_000)]), {0}),
        "empty": ("", {2}),
        "header-only": (header, {2}),
        "wrong-header": ("a,b,c,d\n" + "\n".join(good[1:]), {2}),
        "semicolons": ("\n".join(r.replace(",", ";") for r in good), {2}),
        "quoted": ("\n".join([header] + [f'"{r}"' for r in good[1:]]), {2}),
        "nan": ("\n".join([*good, "0.0,0.5,nan,0.0"]), {2}),
        "inf": ("\n".join([*good, "0.0,0.5,0.0,inf"]), {2}),
        "off-edge": ("\n".join([*good, "0.5,0.5,0.0,0.0"]), {2}),
        "beyond-end": ("\n".join([*good, "0.0,1.5,0.0,0.0"]), {2}),
        "conflict": ("\n".join([*good, "0.0,0.5,1.0,1.0"]), {2}),
        "one-point": ("\n".join(good[:2]), {2}),
        "not-covering": ("\n".join([header, "0.0,0.0,0,0", "0.0,0.5,0,0"]), {2}),
        "extra-column": ("\n".join([*good, "0.0,0.5,0.0,0.0,9"]), {2}),
        "nul": ("\n".join([*good, "0.0,0.\x005,0.0,0.0"]), {2}),
        "1e6-columns": (lambda: header + "\n" + ",".join(["0"] * 1_000_000), {2}),
        "20MB-line": (lambda: header + "\n" + "0" * (20 * 2**20), {2}),
        "50MB-line": (lambda: header + "\n" + "0" * (50 * 2**20), {2}),
        "100k-bad-rows": (lambda: "\n".join([header] + ["a,b,c,d"] * 100_000), {2}),
        "1e308": ("\n".join([*good, "0.0,0.5,1e308,-1e308"]), {2}),
    }
    out = []
    for name, (body, expect) in bodies.items():
        doc = small(boundary={"bottom": {"uy": 0.0}, "left": {"file": "left.csv"}})
        out.append(
            Input(
                id=f"boundary-csv/{name}",
                family="boundary-csv",
                files={"case.toml": toml(doc), "left.csv": _lazy(body)},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset(expect) if expect != {0} else frozenset({0, 1}),
                names=("boundary.left.file",) if expect == {2} else (),
            )
        )
    return out


def network_csv_inputs() -> list[Input]:
    header = "fracture,x0,y0,x1,y1"
    good = [header, "a,0.2,0.3,0.5,0.5", "a,0.5,0.5,0.8,0.6", "b,0.2,0.8,0.7,0.7"]

    def many():
        rows = [
            f"f{i},{0.1 + 0.8 * (i % 50) / 50!r},{0.1 + 0.8 * (i // 50) / 120!r},"
            f"{0.1 + 0.8 * (i % 50) / 50 + 0.005!r},{0.1 + 0.8 * (i // 50) / 120!r}"
            for i in range(6000)
        ]
        return "\n".join([header, *rows])

    bodies = {
        "valid": ("\n".join(good), {0, 1}),
        "empty": ("", {2}),
        "header-only": (header, {2}),
        "unknown-column": ("fracture,x0,y0,x1,y1,frction\na,0.2,0.3,0.5,0.5,1", {2}),
        "duplicate-column": ("x0,y0,x1,y1,x0\n0.2,0.3,0.5,0.5,1", {2}),
        "1e6-columns": (lambda: ",".join(f"c{i}" for i in range(1_000_000)), {2}),
        "1e6-fields-row": (lambda: header + "\n" + ",".join(["1"] * 10**6), {2}),
        "20MB-line": (lambda: "x0,y0,x1,y1\n" + "1" * (20 * 2**20), {2}),
        "zero-length": (header + "\na,0.5,0.5,0.5,0.5", {2}),
        "broken-chain": (header + "\na,0.2,0.3,0.5,0.5\na,0.6,0.6,0.8,0.6", {2}),
        "outside": (header + "\na,2,2,3,3", {2}),
        "nan": (header + "\na,nan,0.3,0.5,0.5", {2}),
        "negative-friction": ("x0,y0,x1,y1,friction\n0.2,0.3,0.5,0.5,-1", {2}),
        "6000-fractures": (many, {2}),
        "600k-fractures-28MB": (
            lambda: "x0,y0,x1,y1\n" + "0.1,0.5,0.2,0.5\n" * 600_000,
            {2},
        ),
        "long-fracture-id": (
            header + "\n" + "f" * 100_000 + ",0.2,0.3,0.5,0.5",
            {0, 1},
        ),
        "self-crossing": (
            header + "\na,0.2,0.2,0.8,0.8\na,0.8,0.8,0.8,0.2\na,0.8,0.2,0.2,0.8",
            {2},
        ),
    }
    out = []
    for name, (body, expect) in bodies.items():
        out.append(
            Input(
                id=f"network-csv/{name}",
                family="network-csv",
                files={
                    "case.toml": toml(network_case(file="net.csv")),
                    "net.csv": _lazy(body),
                },
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset(expect),
                names=("network.file",) if expect == {2} else (),
            )
        )
    return out
