"""Generated bad and edge-case inputs of the whole CLI, for test_bad_inputs.py.

Each ``Input`` is a folder of files (case, sweep, CSV files, special files), a
command line, an environment, and what may come out: the allowed exit codes
(0 run, 1 clean failure, 2 refusal) and, where the input breaks one key, the
key the refusal must name.  The generators are deterministic (``random.Random``
with a fixed seed), so a failing input is found again by its id.

Families (``Input.family``): the keys of the shipped cases mutated one at a
time (``check``) and those of a small case (``run``); TOML nesting depth;
special and oversized files in every place a file is read; bytes that are not
a clean UTF-8 TOML file; boundary and network CSV files; sweeps; random
networks; depletion; command-line options; environment variables; sizes.
"""

from __future__ import annotations

import copy
import math
import random
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import tomli_w

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"
SHIPPED = sorted(CASES.glob("*.toml"))

RUN = ("run", "-q")
OUT = "out"


@dataclass(frozen=True)
class Special:
    """A file that is not plain bytes: ``kind`` in fifo, dir, symlink (to
    ``arg``), sparse (of ``arg`` bytes), lazy (``arg()`` gives the bytes),
    unreadable (``arg`` bytes, mode 000)."""

    kind: str
    arg: object = None


@dataclass
class Input:
    """One generated input and what it may end in."""

    id: str
    family: str
    files: dict = field(default_factory=dict)  # name -> bytes | str | Special
    argv: tuple = ()
    env: dict = field(default_factory=dict)  # name -> value, None = unset
    expect: frozenset = frozenset({2})
    names: tuple = ()  # text the Error line must hold (a key path, an option)
    out: str | None = OUT  # the folder that must stay empty on exit 2
    subprocess: bool = False  # run as `python -m xfemslip` (env read at import)
    timeout: float = 30.0


def toml(doc: dict) -> str:
    return tomli_w.dumps(doc)


def key_name(path) -> str:
    """fractures[0].points: the key path as the error messages spell it."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


# --------------------------------------------------------------------------- #
# Base cases
# --------------------------------------------------------------------------- #

SMALL = {
    "name": "small",
    "domain": {"size": [1.0, 1.0], "origin": [0.0, 0.0]},
    "mesh": {"elements": [4, 4]},
    "material": {"E": 1.0e9, "nu": 0.25, "model": "plane_strain"},
    "fractures": [
        {
            "points": [[0.2, 0.3], [0.8, 0.7]],
            "friction": 0.3,
            "cohesion": 0.0,
            "kn": 1.0e12,
            "kt": 1.0e12,
            "tip": "ramp",
        }
    ],
    "loading": {
        "stress": {"xx": -1.0e6, "yy": -2.0e6, "xy": 0.0},
        "initial_stress": {"xx": -1.0e6, "yy": -1.0e6, "xy": 0.0},
        "steps": 2,
    },
    "boundary": {"bottom": {"ux": 0.0, "uy": 0.0}, "top": "traction"},
    "solver": {
        "tolerance": 1.0e-8,
        "max_iterations": 30,
        "tangent": "consistent",
        "contact_patch": 1.5,
        "max_step_cuts": 5,
        "linear_solver": "superlu",
        "kernels": "numpy",
    },
    "output": {"formats": ["h5"]},
}

DEPLETION = {
    "name": "deplete-small",
    "domain": {"size": [1.0, 1.0]},
    "mesh": {"elements": [6, 6]},
    "material": {"E": 1.0e9, "nu": 0.25},
    "fractures": [
        {"center": [0.5, 0.5], "length": 0.5, "angle": 60.0, "friction": 0.5}
    ],
    "pore_pressure": {"initial": 1.0e6, "change": -1.0e6, "region": "all"},
    "loading": {
        "initial_stress": {"xx": -2.0e6, "yy": -4.0e6, "xy": 0.0},
        "stress": {"xx": -2.0e6, "yy": -4.0e6, "xy": 0.0},
        "steps": 2,
    },
    "boundary": {
        "left": {"ux": 0.0},
        "right": {"ux": 0.0},
        "bottom": {"uy": 0.0},
        "top": "traction",
    },
    "output": {"formats": ["h5"]},
}

GENERATE = {
    "seed": 3,
    "count": 4,
    "intersections": "allow",
    "outside": "clip",
    "orientation": {"distribution": "von_mises", "mean": 30.0, "kappa": 4.0},
    "length": {"distribution": "power_law", "exponent": 2.5, "min": 0.2, "max": 0.4},
}


def small(**changes) -> dict:
    doc = copy.deepcopy(SMALL)
    doc.update(changes)
    return doc


def network_case(generate: dict | None = None, file: str | None = None) -> dict:
    doc = small()
    del doc["fractures"]
    doc["mesh"] = {"elements": [8, 8]}
    doc["network"] = {"friction": 0.4, "tip": "ramp"}
    if generate is not None:
        doc["network"]["generate"] = generate
    if file is not None:
        doc["network"]["file"] = file
    return doc


# --------------------------------------------------------------------------- #
# Key mutations
# --------------------------------------------------------------------------- #

MUTATIONS = {
    "string": "oops",
    "bool": True,
    "table": {"zz": 1},
    "array": [1, "a"],
    "empty-array": [],
    "nan": math.nan,
    "inf": math.inf,
    "-inf": -math.inf,
    "negative": -1.0,
    "zero": 0,
    "negzero": -0.0,
    "huge": 1.0e308,
    "-huge": -1.0e308,
    "tiny": 1.0e-300,
    "bigint": 2**63 - 1,
    "int-beyond-float": None,  # written as text: 10**400 as a TOML integer
}
NON_NUMBERS = ("string", "bool", "table", "array", "empty-array")
NOT_FINITE = ("nan", "inf", "-inf", "int-beyond-float")
BIG_INT_TEXT = "1" + "0" * 400


def leaf_paths(node, path=()) -> list[tuple]:
    """Every key path of a document, tables and array items included."""
    out = [path] if path else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += leaf_paths(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += leaf_paths(v, (*path, i))
    return out


def get(doc, path):
    for part in path:
        doc = doc[part]
    return doc


def mutate(doc: dict, path: tuple, mutation: str) -> tuple[str, tuple]:
    """(TOML text of doc with path mutated, what the refusal must name)."""
    doc = copy.deepcopy(doc)
    parent = get(doc, path[:-1])
    old = parent[path[-1]]
    if mutation == "delete":
        del parent[path[-1]]
        return toml(doc), ()
    if mutation == "int-beyond-float":
        parent[path[-1]] = 12345
        text = toml(doc)
        # a unique placeholder value, then swapped for a 401-digit integer
        text = text.replace("12345", BIG_INT_TEXT, 1)
        new_kind = "number"
    else:
        parent[path[-1]] = MUTATIONS[mutation]
        text = toml(doc)
        new_kind = "number" if mutation not in NON_NUMBERS else "other"
    number = isinstance(old, int | float) and not isinstance(old, bool)
    # a 401-digit integer is a valid integer (a count may be refused as a
    # whole, e.g. mesh.elements), but no float holds it
    not_finite = mutation in NOT_FINITE and not (
        mutation == "int-beyond-float" and isinstance(old, int)
    )
    must = ()
    if number and (mutation in NON_NUMBERS or not_finite):
        must = (key_name(path),)
    elif not number and new_kind == "number" and not isinstance(old, list):
        must = (key_name(path),)
    return text, must


def shipped_key_inputs(rng: random.Random, per_key: int = 2) -> list[Input]:
    """Every key of every shipped case, ``per_key`` mutations each, ``check``."""
    out = []
    for case in SHIPPED:
        doc = tomllib.loads(case.read_text())
        assert "12345" not in toml(doc)  # the placeholder of int-beyond-float
        for path in leaf_paths(doc):
            choices = [*MUTATIONS, "delete"]
            for mutation in rng.sample(choices, per_key):
                text, must = mutate(doc, path, mutation)
                out.append(
                    Input(
                        id=f"shipped/{case.stem}/{key_name(path)}={mutation}",
                        family="shipped-keys",
                        files={"case.toml": text},
                        argv=("check", "case.toml"),
                        expect=frozenset({0, 2}) if not must else frozenset({2}),
                        names=("case.toml", *must),
                        out=None,
                        timeout=60.0,
                    )
                )
    return out


def small_key_inputs(rng: random.Random, count: int) -> list[Input]:
    """Random mutations of the small case, each run (complete output or none)."""
    out = []
    paths = leaf_paths(SMALL)
    for k in range(count):
        path = rng.choice(paths)
        mutation = rng.choice([*MUTATIONS, "delete"])
        text, must = mutate(SMALL, path, mutation)
        out.append(
            Input(
                id=f"small/{k:03d}/{key_name(path)}={mutation}",
                family="small-run",
                files={"case.toml": text},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}) if not must else frozenset({2}),
                names=("case.toml", *must),
            )
        )
    return out


SYSTEMATIC = ("string", "nan", "huge", "-huge", "int-beyond-float", "delete")


def small_systematic_inputs() -> list[Input]:
    """Every key of the small case with each of SYSTEMATIC, through ``check``
    (validation and geometry): the extremes of every type at every key."""
    out = []
    for path in leaf_paths(SMALL):
        for mutation in SYSTEMATIC:
            text, must = mutate(SMALL, path, mutation)
            out.append(
                Input(
                    id=f"systematic/{key_name(path)}={mutation}",
                    family="small-systematic",
                    files={"case.toml": text},
                    argv=("check", "case.toml"),
                    expect=frozenset({0, 2}) if not must else frozenset({2}),
                    names=("case.toml", *must),
                    out=None,
                )
            )
    return out


def unknown_key_inputs() -> list[Input]:
    """A misspelt key in every table of the small case."""
    out = []
    tables = [p for p in leaf_paths(SMALL) if isinstance(get(SMALL, p), dict)]
    for path in [(), *tables]:
        doc = copy.deepcopy(SMALL)
        get(doc, path)["frction"] = 0.1
        out.append(
            Input(
                id=f"unknown-key/{key_name(path) or 'top'}",
                family="unknown-keys",
                files={"case.toml": toml(doc)},
                argv=(*RUN, "case.toml", "-o", OUT),
                names=("case.toml", "frction"),
            )
        )
    return out


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


SWEEP = """\
name = "sw"
base = "base.toml"

[vary]
"fractures[0].friction" = [0.2, 0.4]
"""


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


def _lazy(body):
    """A file's text, or a Special that makes it when the input is written."""
    return body if isinstance(body, str) else Special("lazy", lambda: body().encode())


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


# --------------------------------------------------------------------------- #
# Sweeps
# --------------------------------------------------------------------------- #


# 26 keys, each with its base value: the case folders' names hold every key
MANY_KEYS = "\n".join(
    f'"{key}" = [{value}]'
    for key, value in [
        *[(f"fractures[0].{k}", v) for k, v in (("friction", 0.3), ("cohesion", 0.0))],
        *[(f"fractures[0].{k}", "1e12") for k in ("kn", "kt")],
        ("fractures[0].tip", '"ramp"'),
        *[(f"solver.{k}", v) for k, v in (("tolerance", 1e-8), ("max_iterations", 30))],
        *[
            (f"solver.{k}", v)
            for k, v in (("contact_patch", 1.5), ("max_step_cuts", 5))
        ],
        ("solver.tangent", '"consistent"'),
        ("solver.linear_solver", '"superlu"'),
        ("solver.kernels", '"numpy"'),
        ("material.E", "1e9"),
        ("material.nu", 0.25),
        ("material.model", '"plane_strain"'),
        ("loading.steps", 1),
        *[(f"loading.stress.{k}", v) for k, v in (("xx", -1e6), ("yy", -2e6))],
        ("loading.stress.xy", 0.0),
        ("domain.size[0]", 1.0),
        ("domain.size[1]", 1.0),
        ("domain.origin[0]", 0.0),
        ("domain.origin[1]", 0.0),
        ("mesh.elements[0]", 4),
        ("mesh.elements[1]", 4),
        ("boundary.top", '"traction"'),
    ]
)


def sweep_inputs() -> list[Input]:
    base = toml(small(loading={"stress": {"xx": -1e6, "yy": -2e6}, "steps": 1}))
    vary_1e12 = (
        "\n".join(
            f'"fractures[0].{k}" = {{ start = 0.0, stop = 99.0, step = 1.0 }}'
            for k in ("friction", "cohesion", "kn", "kt")
        )
        + '\n"material.E" = { start = 1.0, stop = 100.0, num = 100 }\n'
    )
    vary_1e12 += '"material.nu" = { start = 0.0, stop = 0.4, num = 100 }\n'
    sweeps = {
        "valid": ('"fractures[0].friction" = [0.2, 0.4]', {0, 1}, ()),
        "product-1e12": (vary_1e12, {2}, ("vary",)),
        "step-1e-300": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 1e-300 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-subnormal": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 5e-324 }',
            {2},
            ("fractures[0].friction",),
        ),
        "span-overflow": (
            '"fractures[0].friction" = { start = -1e308, stop = 1e308, step = 1e300 }',
            {2},
            ("fractures[0].friction",),
        ),
        "span-overflow-num": (
            '"fractures[0].friction" = { start = -1e308, stop = 1e308, num = 3 }',
            {2},
            ("fractures[0].friction",),
        ),
        "int-span-beyond-float": (
            f'"loading.steps" = {{ start = 1, stop = {BIG_INT_TEXT}, step = 1 }}',
            {2},
            ("loading.steps",),
        ),
        "num-1e9": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, num = 1000000000 }',
            {2},
            ("fractures[0].friction",),
        ),
        "num-0": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, num = 0 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-0": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 0.0 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-wrong-way": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = -0.1 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-nan": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = nan }',
            {2},
            ("fractures[0].friction",),
        ),
        "empty-list": ('"fractures[0].friction" = []', {2}, ()),
        "bad-key-path": ('"fractures[0]..friction" = [0.1]', {2}, ()),
        "missing-index": ('"fractures[7].friction" = [0.1]', {2}, ("fractures[7]",)),
        # the valid member runs, the other is refused alone (exit 1)
        "invalid-member": (
            '"fractures[0].friction" = [0.2, -1.0]',
            {1},
            ("fractures[0].friction: must be >= 0",),
        ),
        "overlap": (
            '"fractures[0]" = [{ points = [[0.2, 0.3], [0.8, 0.7]], friction = 0.3 }]'
            '\n"fractures[0].friction" = [0.2]',
            {2},
            ("overlaps",),
        ),
        "zip-unequal": (
            '"fractures[0].friction" = [0.2, 0.4]\n"material.E" = [1e9]',
            {2},
            ("zip",),
        ),
        "10k-single-keys": (
            "\n".join(f'"material.k{i}" = [1]' for i in range(10_000)),
            {2},
            (),
        ),
        "many-keys-long-case-id": (MANY_KEYS, {0, 1}, ()),
    }
    out = []
    for name, (vary, expect, names) in sweeps.items():
        combine = 'combine = "zip"\n' if name == "zip-unequal" else ""
        text = f'name = "sw"\nbase = "base.toml"\n{combine}\n[vary]\n{vary}\n'
        out.append(
            Input(
                id=f"sweep/{name}",
                family="sweep",
                files={"sweep.toml": text, "base.toml": base},
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                expect=frozenset(expect),
                names=("sweep.toml", *names) if expect == {2} else names,
                timeout=60.0,
            )
        )
    heads = {
        "name-slash": ('name = "a/b"\nbase = "base.toml"', ("name",)),
        "name-300": (f'name = "{"n" * 300}"\nbase = "base.toml"', ("name",)),
        "no-base": ('name = "sw"', ("base",)),
        "base-missing": ('name = "sw"\nbase = "nope.toml"', ("base",)),
        "base-number": ('name = "sw"\nbase = 5', ("base",)),
        "combine-bad": ('base = "base.toml"\ncombine = "cross"', ("combine",)),
        "dir-nul": (
            'base = "base.toml"\n[output]\ndirectory = "a\\u0000b"',
            ("output.directory",),
        ),
        "dir-long": (
            f'base = "base.toml"\n[output]\ndirectory = "{"d" * 300}"',
            ("output.directory",),
        ),
    }
    for name, (head, names) in heads.items():
        vary = '[vary]\n"fractures[0].friction" = [0.2]\n'
        if "[output]" in head:
            text = head.replace("[output]", vary + "\n[output]")
        else:
            text = f"{head}\n{vary}"
        out.append(
            Input(
                id=f"sweep/{name}",
                family="sweep",
                files={"sweep.toml": text, "base.toml": base},
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml")
                if "dir-" not in name
                else ("sweep", "-j", "1", "sweep.toml"),
                names=("sweep.toml", *names),
            )
        )
    big = small()
    big["fractures"] = [
        dict(big["fractures"][0], friction=0.3 + 1e-6 * i) for i in range(6000)
    ]
    out.append(
        Input(
            id="sweep/volume-1MB-base-x-10000",
            family="sweep",
            files={
                "sweep.toml": 'base = "base.toml"\n[vary]\n"material.nu" = '
                "{ start = 0.0, stop = 0.4, num = 10000 }\n",
                "base.toml": toml(big),
            },
            argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
            names=("sweep.toml", "vary"),
            timeout=60.0,
        )
    )
    return out


# --------------------------------------------------------------------------- #
# Random networks, depletion
# --------------------------------------------------------------------------- #


def generate_inputs() -> list[Input]:
    """[network.generate] values whose derived sizes overflow or degenerate."""
    power = {"distribution": "power_law", "exponent": 2.5, "min": 0.2, "max": 0.4}
    lognormal = {"distribution": "lognormal", "median": 0.3, "sigma": 0.5}
    changes = {
        "p21-1e308": ({"p21": 1e308}, ("count",), "p21"),
        "p20-1e308": ({"p20": 1e308}, ("count",), "p20"),
        "p21-tiny": ({"p21": 1e-300}, ("count",), None),
        "count-5001": ({"count": 5001}, (), "count"),
        "count-2**64": ({"count": 2**64}, (), "count"),
        "seed-2**64": ({"seed": 2**64}, (), None),
        "seed-negative": ({"seed": -1}, (), "seed"),
        "powerlaw-min-1e-300": (
            {"length": dict(power, min=1e-300)},
            (),
            "length",
        ),
        "powerlaw-max-1e308": ({"length": dict(power, max=1e308)}, (), None),
        "powerlaw-exp-10-min-1e-40": (
            {"length": dict(power, exponent=10.0, min=1e-40)},
            (),
            "length",
        ),
        "powerlaw-exp--10-max-1e300": (
            {"length": dict(power, exponent=-10.0, max=1e300)},
            (),
            "length",
        ),
        "powerlaw-min=max": ({"length": dict(power, min=0.3, max=0.3)}, (), "max"),
        "lognormal-median-1e308": (
            {"length": dict(lognormal, median=1e308, sigma=10.0)},
            (),
            "length",
        ),
        "lognormal-median-1e-300": (
            {"length": dict(lognormal, median=1e-300)},
            (),
            None,
        ),
        "lognormal-empty-window": (
            {"length": dict(lognormal, min=100.0, max=101.0)},
            (),
            "length",
        ),
        "constant-1e308": (
            {"length": {"distribution": "constant", "value": 1e308}},
            (),
            None,
        ),
        "region-huge": ({"region": [[-1e308, -1e308], [1e308, 1e308]]}, (), "region"),
        "region-point": ({"region": [[0.5, 0.5], [0.5, 0.5]]}, (), "region"),
        "region-away": (
            {"region": [[5.0, 5.0], [6.0, 6.0]], "outside": "reject"},
            (),
            None,
        ),
        "kappa-1e6": (
            {"orientation": {"distribution": "von_mises", "mean": 0.0, "kappa": 1e6}},
            (),
            None,
        ),
        "std-360": (
            {"orientation": {"distribution": "normal", "mean": 1e308, "std": 360.0}},
            (),
            None,
        ),
        "avoid-spacing-1e308": (
            {"intersections": "avoid", "min_spacing": 1e308, "count": 50},
            (),
            "generate",
        ),
        "clip-min-length-1e308": ({"min_length": 1e308}, (), "generate"),
        "sets-weights-extreme": (
            {
                "sets": [
                    {
                        "weight": 1e-300,
                        "orientation": {"distribution": "uniform"},
                        "length": power,
                    },
                    {
                        "weight": 1e308,
                        "orientation": {"distribution": "uniform"},
                        "length": power,
                    },
                ]
            },
            ("orientation", "length"),
            None,
        ),
    }
    out = []
    for name, (change, drop, must) in changes.items():
        generate = copy.deepcopy(GENERATE)
        for key in drop:
            generate.pop(key, None)
        generate.update(change)
        out.append(
            Input(
                id=f"generate/{name}",
                family="network-generate",
                files={"case.toml": toml(network_case(generate=generate))},
                argv=("check", "case.toml"),
                expect=frozenset({2}) if must else frozenset({0, 2}),
                names=("case.toml", "network.generate", *([must] if must else [])),
                out=None,
            )
        )
    return out


def depletion_inputs() -> list[Input]:
    out = []
    cases = {
        "change-0": ({"change": 0.0}, (), {2}, ("pore_pressure.change",)),
        "change--0.0": ({"change": -0.0}, (), {2}, ("pore_pressure.change",)),
        "change-nan": ({"change": math.nan}, (), {2}, ("pore_pressure.change",)),
        "change-1e308": ({"change": -1e308}, (), {0, 1, 2}, ()),
        "valid": ({}, (), {0, 1}, ()),
        "tolerance-0": ({}, ("--tolerance", "0"), {2}, ("--tolerance",)),
        "tolerance-negative": ({}, ("--tolerance", "-1"), {2}, ("--tolerance",)),
        "tolerance-nan": ({}, ("--tolerance", "nan"), {2}, ("--tolerance",)),
        "tolerance-text": ({}, ("--tolerance", "abc"), {2}, ("--tolerance",)),
        "tolerance-inf": ({}, ("--tolerance", "inf"), {0, 1, 2}, ()),
        "tolerance-huge": ({}, ("--tolerance", "1e300"), {0, 1}, ()),
    }
    for name, (change, options, expect, names) in cases.items():
        doc = copy.deepcopy(DEPLETION)
        doc["pore_pressure"].update(change)
        out.append(
            Input(
                id=f"deplete/{name}",
                family="deplete",
                files={"case.toml": toml(doc)},
                argv=("deplete", "-q", "case.toml", "-o", OUT, *options),
                expect=frozenset(expect),
                names=names,
            )
        )
    no_pp = copy.deepcopy(DEPLETION)
    del no_pp["pore_pressure"]
    no_fr = copy.deepcopy(DEPLETION)
    del no_fr["fractures"]
    for name, doc in (("no-pore-pressure", no_pp), ("no-fracture", no_fr)):
        out.append(
            Input(
                id=f"deplete/{name}",
                family="deplete",
                files={"case.toml": toml(doc)},
                argv=("deplete", "-q", "case.toml", "-o", OUT),
                names=("case.toml",),
            )
        )
    return out


# --------------------------------------------------------------------------- #
# Command line, environment, sizes
# --------------------------------------------------------------------------- #


def _empty_h5() -> bytes:
    """A valid HDF5 file that holds nothing."""
    import io

    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w"):
        pass
    return buffer.getvalue()


def cli_inputs() -> list[Input]:
    case = {
        "case.toml": toml(small()),
        "file.txt": "x",
        "fake.h5": "not HDF5\n",
        "empty.h5": Special("lazy", _empty_h5),
        "summary.csv": "status,slipping_fractures,fractures\nok,x,3\n",
        "pipe": Special("fifo"),
    }
    long_part = "p" * 300
    deep = "/".join(["d"] * 2100)
    lines = {
        "run-no-case": (("run",), ("CASE",)),
        "run-two-cases": (("run", "case.toml", "case.toml"), ()),
        "run-unknown-option": (("run", "--bogus", "case.toml"), ("--bogus",)),
        "run-missing-file": (("run", "nope.toml", "-o", OUT), ("nope.toml",)),
        "run-case-is-dir": (("run", ".", "-o", OUT), ()),
        "run-o-is-file": (("run", "case.toml", "-o", "file.txt"), ("--output",)),
        "run-o-nul": (("run", "case.toml", "-o", "a\0b"), ("--output",)),
        "run-o-long-part": (("run", "case.toml", "-o", long_part), ("--output",)),
        "run-o-long-path": (("run", "case.toml", "-o", deep), ("--output",)),
        "run-o-empty": (("run", "case.toml", "-o", ""), ()),
        "run-case-nul": (("run", "ca\0se.toml", "-o", OUT), ()),
        "run-case-long": (("run", long_part + ".toml", "-o", OUT), ()),
        "run-verbose-quiet": (("run", "-v", "-q", "case.toml", "-o", OUT), ()),
        "check-no-case": (("check",), ("CASE",)),
        "unknown-command": (("frobnicate",), ("frobnicate",)),
        "info-extra": (("info", "extra"), ()),
        "sweep-jobs-0": (("sweep", "-j", "0", "case.toml"), ("--jobs",)),
        "sweep-jobs-text": (("sweep", "-j", "many", "case.toml"), ("--jobs",)),
        "sweep-jobs-huge": (("sweep", "-j", "1" + "0" * 30, "case.toml"), ("--jobs",)),
        "sweep-jobs-1000": (("sweep", "-j", "1000", "case.toml"), ("--jobs",)),
        "sweep-missing": (("sweep", "nope.toml", "-o", OUT), ("nope.toml",)),
        "sweep-o-nul": (("sweep", "case.toml", "-o", "a\0b"), ("--output",)),
        "plot-missing": (("plot", "nope.h5", "-o", OUT), ()),
        "plot-fake-h5": (("plot", "fake.h5", "-o", OUT), ("fake.h5",)),
        "plot-empty-h5": (("plot", "empty.h5", "-o", OUT), ("empty.h5",)),
        "plot-dev-zero": (("plot", "/dev/zero", "-o", OUT), ("/dev/zero",)),
        "plot-dpi-1e9": (("plot", "empty.h5", "--dpi", "1e9", "-o", OUT), ("--dpi",)),
        "plot-scale-inf": (("plot", "empty.h5", "--scale", "inf", "-o", OUT), ()),
        "dfn-summary-dev-zero": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "/dev/zero"),
            ("/dev/zero",),
        ),
        "dfn-summary-fifo": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "pipe"),
            ("pipe",),
        ),
        "dfn-summary-not-integers": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "summary.csv"),
            ("summary.csv line 2",),
        ),
        "dfn-result-fake": (
            ("dfn", "case.toml", "--plot", "n.png", "--result", "fake.h5"),
            ("fake.h5",),
        ),
        "dfn-result-empty": (
            ("dfn", "case.toml", "--plot", "n.png", "--result", "empty.h5"),
            ("empty.h5",),
        ),
        "plot-not-h5": (("plot", "file.txt", "-o", OUT), ()),
        "plot-case-as-result": (("plot", "case.toml", "-o", OUT), ()),
        "plot-dpi-0": (("plot", "file.txt", "--dpi", "0", "-o", OUT), ("--dpi",)),
        "plot-figure-bad": (("plot", "file.txt", "--figure", "x", "-o", OUT), ()),
        "screen-no-input": (("screen",), ()),
        "screen-stress-nan": (
            ("screen", "--stress", "nan", "1", "0", "--friction", "0.5"),
            (),
        ),
        "screen-stress-arity": (("screen", "--stress", "1", "2"), ()),
        "screen-step-0": (
            ("screen", "--stress", "-1", "-2", "0", "--friction", "0.5", "--step", "0"),
            ("--step",),
        ),
        "screen-step-1e-300": (
            (
                "screen",
                "--stress",
                "-1",
                "-2",
                "0",
                "--friction",
                "0.5",
                "--step",
                "1e-300",
            ),
            ("--step",),
        ),
        "screen-friction-negative": (
            ("screen", "--stress", "-1", "-2", "0", "--friction", "-1"),
            ("--friction",),
        ),
        "dfn-csv-into-missing-dir": (
            ("dfn", "case.toml", "--csv", "no/such/dir/x.csv"),
            (),
        ),
        "dfn-plot-bad-suffix": (("dfn", "case.toml", "--plot", "net.xyz"), ()),
        "deplete-no-case": (("deplete",), ("CASE",)),
        "verify-penalty-text": (("verify", "--quick", "--penalty", "abc"), ()),
    }
    out = []
    for name, (argv, names) in lines.items():
        expect = {2}
        if name in ("dfn-csv-into-missing-dir",):
            expect = {1, 2}
        out.append(
            Input(
                id=f"cli/{name}",
                family="cli",
                files=dict(case),
                argv=argv,
                expect=frozenset(expect),
                names=names,
            )
        )
    return out


def environment_inputs() -> list[Input]:
    """Bad values of the variables xfemslip and Numba read: the memory limit
    and the kernel choice in-process, Numba's (read once, at import) in a
    fresh interpreter."""
    case = {"case.toml": toml(small())}
    runs = (*RUN, "case.toml", "-o", OUT)
    out = []
    for value in ("0", "-5", "abc", "nan", "inf", "1e400", "10Q", "5 G", "", " "):
        expect = {0} if value in ("", " ", "5 G") else {2}
        out.append(
            Input(
                id=f"env/XFEMSLIP_MEMORY_LIMIT={value!r}",
                family="environment",
                files=dict(case),
                argv=runs,
                env={"XFEMSLIP_MEMORY_LIMIT": value},
                expect=frozenset(expect),
                names=("XFEMSLIP_MEMORY_LIMIT",) if expect == {2} else (),
            )
        )
    out.append(
        Input(
            id="env/XFEMSLIP_MEMORY_LIMIT=1k",
            family="environment",
            files=dict(case),
            argv=runs,
            env={"XFEMSLIP_MEMORY_LIMIT": "1k"},
            names=("mesh", "XFEMSLIP_MEMORY_LIMIT"),
        )
    )
    for value, expect in (
        ("fortran", {2}),
        ("NUMBA", {0}),
        (" numpy ", {0}),
        ("", {0}),
    ):
        out.append(
            Input(
                id=f"env/XFEMSLIP_KERNELS={value!r}",
                family="environment",
                files=dict(case),
                argv=runs,
                env={"XFEMSLIP_KERNELS": value},
                expect=frozenset(expect),
                names=("XFEMSLIP_KERNELS",) if expect == {2} else (),
            )
        )
    numba_case = {"case.toml": toml(small(solver={"kernels": "numba"}))}
    for name, value in (
        ("NUMBA_NUM_THREADS", "0"),
        ("NUMBA_NUM_THREADS", "-1"),
        ("NUMBA_NUM_THREADS", "abc"),
        ("NUMBA_NUM_THREADS", "1.5"),
        ("NUMBA_DISABLE_JIT", "yes"),
    ):
        out.extend(
            Input(
                id=f"env/{name}={value}/{argv[0]}",
                family="environment",
                files=dict(numba_case),
                argv=argv,
                env={name: value},
                names=(name,),
                subprocess=True,
                timeout=120.0,
            )
            for argv in (("info",), runs)
        )
    out.append(
        Input(
            id="env/NUMBA_NUM_THREADS=1/run",
            family="environment",
            files=dict(numba_case),
            argv=runs,
            env={"NUMBA_NUM_THREADS": "1"},
            expect=frozenset({0}),
            subprocess=True,
            timeout=120.0,
        )
    )
    return out


def size_inputs() -> list[Input]:
    """Sizes that must be refused before anything of that size is allocated."""
    docs = {
        "elements-1e9x1e9": (small(mesh={"elements": [10**9, 10**9]}), ("mesh",)),
        "elements-2**63": (small(mesh={"elements": [2**63 - 1, 1]}), ("mesh",)),
        "elements-0": (small(mesh={"elements": [0, 4]}), ("mesh.elements",)),
        "elements-float": (small(mesh={"elements": [4.0, 4]}), ("mesh.elements",)),
        "elements-3": (small(mesh={"elements": [4, 4, 4]}), ("mesh.elements",)),
        "elements-memory": (small(mesh={"elements": [20000, 20000]}), ("mesh",)),
        # at the element-count limit: the memory estimate refuses it (4 GB)
        "elements-5000x5000": (small(mesh={"elements": [5000, 5000]}), ("mesh",)),
        "x-not-increasing": (
            small(mesh={"x": [0.0, 0.5, 0.4, 1.0], "y": [0.0, 0.5, 1.0]}),
            ("mesh.x",),
        ),
        "x-100k-nodes": (
            small(mesh={"x": [i / 100_000 for i in range(100_001)], "y": [0.0, 1.0]}),
            (),
        ),
        "steps-0": (
            small(loading=dict(SMALL["loading"], steps=0)),
            ("loading.steps",),
        ),
        "steps-1e6": (
            small(loading=dict(SMALL["loading"], steps=10**6)),
            ("loading.steps",),
        ),
        "fractures-0-points": (
            small(fractures=[dict(SMALL["fractures"][0], points=[])]),
            ("fractures[0].points",),
        ),
        "fractures-1-point": (
            small(fractures=[dict(SMALL["fractures"][0], points=[[0.5, 0.5]])]),
            ("fractures[0].points",),
        ),
        "fracture-3d-point": (
            small(
                fractures=[
                    dict(SMALL["fractures"][0], points=[[0.2, 0.2, 0], [0.8, 0.8]])
                ]
            ),
            ("fractures[0].points",),
        ),
        "5000-fractures": (
            small(
                fractures=[
                    dict(
                        SMALL["fractures"][0],
                        points=[[0.1, 0.1 + i * 1.6e-4], [0.9, 0.1 + i * 1.6e-4]],
                    )
                    for i in range(5000)
                ]
            ),
            (),
        ),
        "polygon-3-collinear": (
            small(
                reservoir={"polygon": [[0, 0], [0.5, 0.5], [1, 1]], "E": 1e9, "nu": 0.2}
            ),
            ("reservoir.polygon",),
        ),
        "formats-duplicate": (
            small(output={"formats": ["h5", "h5"]}),
            ("output.formats",),
        ),
        "formats-empty": (small(output={"formats": []}), ("output.formats",)),
        "name-dot": (small(name=".."), ("name",)),
        "name-single-dot": (small(name="."), ("name",)),
        "name-nul": (small(name="a\0b"), ("name",)),
        "name-300": (small(name="n" * 300), ("name",)),
        "name-unicode-200": (small(name="\u00e9" * 200), ("name",)),
        "dir-nul": (
            small(output={"directory": "o\0ut", "formats": ["h5"]}),
            ("output.directory",),
        ),
        "dir-long-part": (
            small(output={"directory": "d" * 256, "formats": ["h5"]}),
            ("output.directory",),
        ),
        "dir-long-path": (
            small(output={"directory": "/".join(["d"] * 2100), "formats": ["h5"]}),
            ("output.directory",),
        ),
    }
    out = []
    for name, (doc, names) in docs.items():
        refused = bool(names)
        argv = (
            (*RUN, "case.toml")
            if "name" in name or "dir-" in name
            else (*RUN, "case.toml", "-o", OUT)
        )
        out.append(
            Input(
                id=f"sizes/{name}",
                family="sizes",
                files={"case.toml": toml(doc)},
                argv=argv,
                env={"XFEMSLIP_MEMORY_LIMIT": "4G"},
                expect=frozenset({2}) if refused else frozenset({0, 1, 2}),
                names=("case.toml", *names),
                out=OUT if "-o" in argv else None,
                timeout=60.0,
            )
        )
    return out


# A run of these takes seconds once the geometry is simplified below the mesh
# resolution; walked point by point it takes minutes.  The bound leaves room
# for a loaded machine.
SHAPE_TIMEOUT = 60.0


def shape_inputs() -> list[Input]:
    """Geometry with many vertices: it must be simplified (with a warning),
    refused or run -- within the time bound, not walked point by point."""
    out = []

    def zigzag(n):
        return [[0.42 + 0.06 * (i % 2), 0.42 + 0.06 * i / n] for i in range(n)]

    def arc(n):
        t = [math.pi * i / (n - 1) for i in range(n)]
        return [[0.5 + 0.3 * math.cos(a), 0.5 + 0.3 * math.sin(a)] for a in t]

    def polygon(n):
        t = [2 * math.pi * i / n for i in range(n)]
        return [[0.5 + 0.25 * math.cos(a), 0.5 + 0.2 * math.sin(a)] for a in t]

    for name, points, cells in (
        ("zigzag-40-in-one-cell", zigzag(40), 10),
        ("zigzag-1000-in-one-cell", zigzag(1000), 10),
        ("arc-200", arc(200), 20),
        ("arc-2000", arc(2000), 50),
    ):
        doc = small(mesh={"elements": [cells, cells]})
        doc["fractures"][0]["points"] = points
        out.append(
            Input(
                id=f"shapes/{name}",
                family="shapes",
                files={"case.toml": toml(doc)},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}),
                timeout=SHAPE_TIMEOUT,
            )
        )

    def trace(n):  # a digitised fault trace: one fracture of n segments
        p = [
            (0.1 + 0.8 * i / n, 0.5 + 0.01 * math.sin(40 * i / n)) for i in range(n + 1)
        ]
        return "fracture,x0,y0,x1,y1\n" + "".join(
            f"a,{p[i][0]!r},{p[i][1]!r},{p[i + 1][0]!r},{p[i + 1][1]!r}\n"
            for i in range(n)
        )

    out.append(
        Input(
            id="shapes/network-csv-trace-20000",
            family="shapes",
            files={
                "case.toml": toml(network_case(file="net.csv")),
                "net.csv": _lazy(lambda: trace(20_000)),
            },
            argv=("check", "case.toml"),
            expect=frozenset({0, 2}),
            out=None,
            timeout=SHAPE_TIMEOUT,
        )
    )
    for n in (300, 5000):
        doc = copy.deepcopy(DEPLETION)
        doc["mesh"] = {"elements": [10, 10]}
        doc["reservoir"] = {"polygon": polygon(n), "E": 5.0e8, "nu": 0.2}
        doc["pore_pressure"]["region"] = "reservoir"
        out.append(
            Input(
                id=f"shapes/reservoir-polygon-{n}",
                family="shapes",
                files={"case.toml": toml(doc)},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}),
                timeout=SHAPE_TIMEOUT,
            )
        )
    out.append(
        Input(
            id="shapes/deplete-tolerance-1e-10",
            family="shapes",
            files={"case.toml": toml(DEPLETION)},
            argv=("deplete", "-q", "case.toml", "-o", OUT, "--tolerance", "1e-10"),
            expect=frozenset({0, 1, 2}),
            timeout=SHAPE_TIMEOUT,
        )
    )
    return out


# --------------------------------------------------------------------------- #
# The suites
# --------------------------------------------------------------------------- #

SEED = 20240613


def default_inputs() -> list[Input]:
    """The suite of the default test run (a few hundred inputs)."""
    rng = random.Random(SEED)
    inputs = [
        *shipped_key_inputs(rng, per_key=1),
        *small_key_inputs(rng, 80),
        *small_systematic_inputs(),
        *unknown_key_inputs(),
        *nesting_inputs(),
        *special_file_inputs(),
        *byte_inputs(rng),
        *boundary_csv_inputs(),
        *network_csv_inputs(),
        *sweep_inputs(),
        *generate_inputs(),
        *depletion_inputs(),
        *cli_inputs(),
        *environment_inputs(),
        *size_inputs(),
        *shape_inputs(),
    ]
    ids = [i.id for i in inputs]
    assert len(ids) == len(set(ids)), "input ids must be unique"
    return inputs


def slow_inputs() -> list[Input]:
    """The larger sweep behind --run-slow: every key of the shipped cases with
    three mutations, and many more runs of the small case."""
    rng = random.Random(SEED + 1)
    inputs = [*shipped_key_inputs(rng, per_key=3), *small_key_inputs(rng, 600)]
    return [Input(**{**i.__dict__, "id": f"slow/{i.id}"}) for i in inputs]
