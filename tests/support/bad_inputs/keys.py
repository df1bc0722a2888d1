"""Key families of the bad-input suite: every key of the shipped cases and of
a small case, mutated (wrong types, NaN, inf, extremes, integers beyond the
float range, deleted) or misspelt."""

from __future__ import annotations

import copy
import math
import random
import tomllib

from tests.support.bad_inputs.base import (
    BIG_INT_TEXT,
    OUT,
    RUN,
    SHIPPED,
    SMALL,
    Input,
    key_name,
    toml,
)

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
# keys whose table form has a number form too (a friction law or a constant)
NUMBER_OR_TABLE = ("friction",)
NOT_FINITE = ("nan", "inf", "-inf", "int-beyond-float")


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
    elif (
        not number
        and new_kind == "number"
        and not isinstance(old, list)
        and path[-1] not in NUMBER_OR_TABLE
    ):
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
