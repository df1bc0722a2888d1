"""The shape of the installed package, read from its source with ``ast``.

- no import cycle between modules, nor between subpackages (a top-level
  module counts as its own unit), counting imports inside functions too, so
  a lazy import cannot hide a cycle;
- no import of an underscored name from another module, and a private module
  (``kernels/_config.py``) imported only from inside its own subpackage;
- at most MAX_TOP_LEVEL modules at the top of the package;
- Numba imported only under ``kernels/``;
- the numerical subpackages (NUMERICAL) import nothing from the case reader
  (``case/``): they own their defaults, and the reader takes its defaults
  from them.

The checks are run on small hand-made graphs too, so that each can fail.
"""

from __future__ import annotations

import ast
import collections
from pathlib import Path

import pytest

import xfemslip

MAX_TOP_LEVEL = 8
NUMERICAL = ("solve", "contact", "fem", "kernels", "geometry")
PACKAGE = Path(xfemslip.__file__).parent


def module_files(root: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package at root."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports(name: str, path: Path, modules) -> list[tuple[str, str | None, str]]:
    """(imported module, imported name or None, top package) of every import
    statement of a module, at any depth (functions included)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                full = f"{target}.{alias.name}"
                if full in modules:  # ``from package import module``
                    out.append((full, None, target.split(".")[0]))
                else:
                    out.append((target, alias.name, target.split(".")[0]))
        elif isinstance(node, ast.Import):
            out.extend((a.name, None, a.name.split(".")[0]) for a in node.names)
    return out


def graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports."""
    edges = collections.defaultdict(set)
    for name, path in modules.items():
        for target, _, _ in imports(name, path, modules):
            if target in modules and target != name:
                edges[name].add(target)
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one node (Tarjan,
    iterative)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = 0
    nodes = set(edges) | {w for ws in edges.values() for w in ws}
    for root in sorted(nodes):
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def unit(name: str) -> str:
    """The subpackage of a module (``xfemslip.fem.mesh`` -> ``xfemslip.fem``),
    or the top-level module itself."""
    return ".".join(name.split(".")[:2])


def unit_graph(edges: dict[str, set[str]]) -> dict[str, set[str]]:
    out = collections.defaultdict(set)
    for v, ws in edges.items():
        for w in ws:
            if unit(v) != unit(w) and unit(w) != "xfemslip":
                out[unit(v)].add(unit(w))
    return out


def private_imports(modules: dict[str, Path]) -> list[str]:
    """Imports of an underscored name from another module, and of a private
    module from outside its subpackage."""
    bad = []
    for name, path in modules.items():
        for target, what, _ in imports(name, path, modules):
            if not target.startswith("xfemslip") or target == name:
                continue
            if what is not None and what.startswith("_") and not what.startswith("__"):
                bad.append(f"{name}: {what} from {target}")
            parts = target.split(".")
            for depth, part in enumerate(parts):
                private = part.startswith("_") and not part.startswith("__")
                owner = ".".join(parts[:depth])
                if private and not (name == owner or name.startswith(owner + ".")):
                    bad.append(f"{name}: private module {target}")
    return bad


def numba_outside_kernels(modules: dict[str, Path]) -> list[str]:
    return [
        name
        for name, path in modules.items()
        if not name.startswith("xfemslip.kernels")
        and any(top == "numba" for _, _, top in imports(name, path, modules))
    ]


def numerics_on_case(modules: dict[str, Path]) -> list[str]:
    """Imports of xfemslip.case (or anything under it) from the NUMERICAL
    subpackages."""
    inside = tuple(f"xfemslip.{sub}" for sub in NUMERICAL)
    bad = []
    for name, path in modules.items():
        if unit(name) not in inside:
            continue
        for target, what, _ in imports(name, path, modules):
            full = target if what is None else f"{target}.{what}"
            if full == "xfemslip.case" or full.startswith("xfemslip.case."):
                bad.append(f"{name}: {full}")
    return bad


def top_level(modules: dict[str, Path]) -> list[str]:
    return [
        name
        for name, path in modules.items()
        if name.count(".") == 1 and path.name != "__init__.py"
    ]


@pytest.fixture(scope="module")
def modules():
    found = module_files(PACKAGE)
    assert len(found) > 50  # the walk found the package
    return found


def test_no_module_cycle(modules):
    assert cycles(graph(modules)) == []


def test_no_subpackage_cycle(modules):
    assert cycles(unit_graph(graph(modules))) == []


def test_no_cross_module_private_import(modules):
    assert private_imports(modules) == []


def test_top_level_modules(modules):
    names = top_level(modules)
    assert "xfemslip.simulation" in names
    assert len(names) <= MAX_TOP_LEVEL, names


def test_numba_only_in_kernels(modules):
    users = [
        name
        for name, path in modules.items()
        if any(top == "numba" for _, _, top in imports(name, path, modules))
    ]
    assert "xfemslip.kernels.bulk" in users  # the walk sees the kernels' imports
    assert numba_outside_kernels(modules) == []


def test_numerics_import_nothing_from_case(modules):
    users = [
        name
        for name, path in modules.items()
        if any(top == "xfemslip" for _, _, top in imports(name, path, modules))
        and unit(name) in {f"xfemslip.{sub}" for sub in NUMERICAL}
    ]
    assert "xfemslip.solve.newton" in users  # the walk sees the numerics' imports
    assert numerics_on_case(modules) == []


def test_the_checks_fail_on_a_bad_package(tmp_path):
    """A small package with each defect: every check reports it."""
    root = tmp_path / "xfemslip"
    files = {
        "__init__.py": "",
        "a.py": "from xfemslip.b import thing\n",
        "b.py": "def f():\n    from xfemslip import a\n",
        "c.py": "import numba\nfrom xfemslip.sub.x import _hidden\n",
        "sub/__init__.py": "",
        "sub/x.py": "from xfemslip.d import y\n_hidden = 1\n",
        "sub/y.py": "",
        "sub/_conf.py": "",
        "d.py": "from xfemslip.sub import y\nfrom xfemslip.sub._conf import k\n",
        "case/__init__.py": "",
        "case/specs.py": "K = 1.0\n",
        "solve/__init__.py": "",
        "solve/newton.py": "from xfemslip.case.specs import K\n",
        "fem/__init__.py": "",
        "fem/mesh.py": "def f():\n    from xfemslip import case\n",
        "geometry/__init__.py": "from xfemslip.case import specs\n",
        "contact/__init__.py": "import xfemslip.case.specs\n",
        "kernels/__init__.py": "from xfemslip.sub import y\n",
        **{f"t{i}.py": "" for i in range(MAX_TOP_LEVEL)},
    }
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    mods = module_files(root)
    edges = graph(mods)
    assert cycles(edges) == [["xfemslip.a", "xfemslip.b"]]
    assert cycles(unit_graph(edges)) == [
        ["xfemslip.a", "xfemslip.b"],
        ["xfemslip.d", "xfemslip.sub"],
    ]
    assert private_imports(mods) == [
        "xfemslip.c: _hidden from xfemslip.sub.x",
        "xfemslip.d: private module xfemslip.sub._conf",
    ]
    assert numba_outside_kernels(mods) == ["xfemslip.c"]
    assert numerics_on_case(mods) == [
        "xfemslip.contact: xfemslip.case.specs",
        "xfemslip.fem.mesh: xfemslip.case",
        "xfemslip.geometry: xfemslip.case.specs",
        "xfemslip.solve.newton: xfemslip.case.specs.K",
    ]
    assert len(top_level(mods)) == MAX_TOP_LEVEL + 4
