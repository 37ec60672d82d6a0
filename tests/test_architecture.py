"""The layer contract of lmic, checked on the source (docs/architecture.md explains it).

Every import between the project's modules is read with :mod:`ast` -- module-level and
function-local alike, also ``importlib.import_module("literal")``; only the body of an
``if TYPE_CHECKING:`` block is ignored (it never runs). From that graph three rules are checked:

1. no import cycles among the modules of ``lmic/`` and ``plugins/``;
2. a module never imports one of a higher layer (``LAYERS`` below, lowest first; within a layer
   any import is allowed as long as it makes no cycle);
3. no module over ``MAX_LINES`` lines.

The violations that exist today are listed in ``KNOWN_CYCLES``, ``KNOWN_UPWARD`` and
``KNOWN_OVERSIZE``, each with the issue that removes it. A test fails on any violation not listed
AND on any listed one that no longer occurs, so the lists can only shrink: when your change
removes a violation, delete its entry.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 600

# The layers, lowest first. A module may import modules of its own layer or of lower layers only.
# "pkg.*" stands for the package pkg and everything below it; a name without ".*" is that one
# module (so "lmic" is the package root, lmic/__init__.py, alone). Every module must match exactly
# one entry (a new module must be placed here). Entries that match nothing yet are the packages
# issue #10 and its sibling issues are creating (outcome, reductions, policy, studies, present).
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (
        "base",
        (
            "lmic._version",
            "lmic.cache",
            "lmic.errors",
            "lmic.limits",
            "lmic.output",
            "lmic.options",
            "lmic.jsonable",
            "lmic.formatting",
            "lmic.rational_rank",
            "lmic.progressbar",
            "lmic.schemas",
            "lmic.solution",
            "lmic.system",
        ),
    ),
    ("ir", ("lmic.ir.*",)),
    ("template", ("lmic.template.*",)),
    ("theorem plugins", ("lmic_observers.*",)),
    ("catalogue", ("lmic.registry", "lmic.plugin_index", "lmic.plant")),
    ("compile", ("lmic.compile.*",)),
    ("backends", ("lmic.backends.*",)),
    ("certify", ("lmic.certify.*",)),
    (
        "engine",
        (
            "lmic.outcome",
            "lmic.reductions.*",
            "lmic.policy",
            "lmic.rescue",
            "lmic.routes",
            "lmic.route_rule",
            "lmic.route_unbounded",
            "lmic.route_escalation",
            "lmic.backoff",
            "lmic.upper_end",
            "lmic.route_upper",
            "lmic.route_primal",
            "lmic.route_tighten",
            "lmic.route_cut",
            "lmic.testing.*",
        ),
    ),
    (
        "studies",
        ("lmic.api", "lmic.sweep", "lmic.crosscheck", "lmic.published", "lmic.studies.*"),
    ),
    ("facade", ("lmic",)),
    ("present", ("lmic.present.*", "lmic.display", "lmic.reproduce", "lmic.report.*", "lmic.simulate.*")),
    ("commands", ("lmic.commands.*",)),
    ("cli", ("lmic.cli",)),
)

# Violations present when this contract was written. Each names the issue whose work removes it;
# the test fails when an entry goes stale, so delete it in the change that fixes it.
KNOWN_CYCLES: dict[frozenset[str], str] = {}

KNOWN_UPWARD: dict[tuple[str, str], str] = {}

KNOWN_OVERSIZE: dict[str, str] = {}


# -- the checker ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Module:
    """One source file: its dotted name, path and whether it is a package's ``__init__``."""

    name: str
    path: Path
    is_package: bool


def collect_modules(packages: Iterable[Path]) -> dict[str, Module]:
    """Every ``.py`` file below each package directory, by dotted name (``pkg/__init__.py`` is ``pkg``).

    >>> sorted(collect_modules([ROOT / "lmic" / "ir"]))[:2]
    ['ir', 'ir.expr']
    """
    out: dict[str, Module] = {}
    for pkg in packages:
        base = pkg.resolve().parent
        for path in sorted(pkg.resolve().rglob("*.py")):
            parts = list(path.relative_to(base).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            if is_package:
                parts.pop()
            out[".".join(parts)] = Module(".".join(parts), path, is_package)
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _import_nodes(tree: ast.AST) -> Iterator[ast.AST]:
    """Import statements and literal ``import_module`` calls that run (the body of ``if TYPE_CHECKING:`` never does)."""
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name | ast.Attribute)
            and (node.func.id if isinstance(node.func, ast.Name) else node.func.attr) == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _targets(node: ast.AST, module: Module, known: Mapping[str, Module]) -> list[str]:
    """The project modules one import statement loads by name.

    ``from P import x`` is an edge to the submodule ``P.x`` when there is one, else to ``P``.
    Importing ``P.x`` also runs ``P/__init__.py`` first; that implicit parent import is not an
    edge (every module of ``P`` has it), an explicit ``import P`` or ``from P import name`` is.
    """
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name in known]
    if isinstance(node, ast.Call):
        name = node.args[0].value  # type: ignore[attr-defined]
        return [name] if name in known else []
    assert isinstance(node, ast.ImportFrom)
    if node.level:
        parts = module.name.split(".") if module.is_package else module.name.split(".")[:-1]
        parts = parts[: len(parts) - (node.level - 1)]
        source = ".".join(parts + ([node.module] if node.module else []))
    else:
        source = node.module or ""
    out = []
    for alias in node.names:
        sub = f"{source}.{alias.name}"
        if sub in known:  # `from pkg import submodule`
            out.append(sub)
        elif source in known:  # `from module import name`
            out.append(source)
    return out


def import_graph(modules: Mapping[str, Module]) -> dict[tuple[str, str], int]:
    """Every import edge ``(importer, imported)`` between the modules, with the line of its first occurrence.

    >>> g = import_graph(collect_modules([ROOT / "lmic"]))
    >>> ("lmic.compile.bind", "lmic.compile.inputs") in g
    True
    """
    edges: dict[tuple[str, str], int] = {}
    for mod in modules.values():
        tree = ast.parse(mod.path.read_text(encoding="utf-8"), str(mod.path))
        for node in _import_nodes(tree):
            for target in _targets(node, mod, modules):
                if target != mod.name:
                    line = getattr(node, "lineno", 0)
                    edges[(mod.name, target)] = min(line, edges.get((mod.name, target), line))
    return edges


def import_cycles(modules: Iterable[str], edges: Iterable[tuple[str, str]]) -> set[frozenset[str]]:
    """The import cycles: strongly connected components of more than one module.

    >>> sorted(sorted(c) for c in import_cycles("abcd", [("a", "b"), ("b", "a"), ("b", "c"), ("c", "d")]))
    [['a', 'b']]
    """
    names = sorted(modules)
    index = {m: i for i, m in enumerate(names)}
    pairs = [(index[a], index[b]) for a, b in edges]
    rows, cols = (np.array(v, dtype=int) for v in zip(*pairs, strict=True)) if pairs else (np.zeros(0, int),) * 2
    adj = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    _, labels = connected_components(adj, directed=True, connection="strong")
    groups: dict[int, set[str]] = {}
    for m, label in zip(names, labels, strict=True):
        groups.setdefault(int(label), set()).add(m)
    return {frozenset(g) for g in groups.values() if len(g) > 1}


def layer_of(module: str, layers: Sequence[tuple[str, Sequence[str]]]) -> list[int]:
    """Indices of the layers whose entries match ``module`` (exactly one for a well-placed module).

    >>> layer_of("lmic.ir.svec", LAYERS), layer_of("lmic", LAYERS), layer_of("lmic.nowhere", LAYERS)
    ([1], [10], [])
    """
    hits = []
    for i, (_, patterns) in enumerate(layers):
        for pat in patterns:
            if pat.endswith(".*"):
                if module == pat[:-2] or module.startswith(pat[:-1]):
                    hits.append(i)
            elif module == pat:
                hits.append(i)
    return hits


def upward_imports(
    edges: Iterable[tuple[str, str]], layers: Sequence[tuple[str, Sequence[str]]]
) -> set[tuple[str, str]]:
    """The edges whose imported module sits in a higher layer than its importer.

    >>> sorted(upward_imports([("lmic.ir.io", "lmic.api"), ("lmic.api", "lmic.ir.io")], LAYERS))
    [('lmic.ir.io', 'lmic.api')]
    """
    out = set()
    for a, b in edges:
        la, lb = layer_of(a, layers), layer_of(b, layers)
        if len(la) == 1 and len(lb) == 1 and lb[0] > la[0]:
            out.add((a, b))
    return out


def oversize_modules(modules: Mapping[str, Module], max_lines: int) -> dict[str, int]:
    """Modules with more than ``max_lines`` lines, with their line count."""
    counts = {m.name: len(m.path.read_text(encoding="utf-8").splitlines()) for m in modules.values()}
    return {name: n for name, n in counts.items() if n > max_lines}


def compare(found: Iterable[object], known: Iterable[object], what: str) -> list[str]:
    """Problems of ``found`` against an allowlist: new violations and stale (no longer found) entries.

    >>> compare({"a", "b"}, {"b", "c"}, "cycle")
    ['new cycle: a', "stale allowlist entry (cycle 'c' is gone): delete it"]
    """
    found, known = set(found), set(known)
    new = [f"new {what}: {_show(v)}" for v in sorted(found - known, key=_show)]
    stale = [
        f"stale allowlist entry ({what} {_show(v)!r} is gone): delete it" for v in sorted(known - found, key=_show)
    ]
    return new + stale


def _show(v: object) -> str:
    if isinstance(v, frozenset):
        return " <-> ".join(sorted(v))
    if isinstance(v, tuple):
        return " -> ".join(v)
    return str(v)


# -- the contract on lmic ------------------------------------------------------------------------
def _project_packages() -> list[Path]:
    plugins = sorted(p for p in (ROOT / "plugins").iterdir() if (p / "__init__.py").is_file())
    return [ROOT / "lmic", *plugins]


@pytest.fixture(scope="module")
def project() -> tuple[dict[str, Module], dict[tuple[str, str], int]]:
    modules = collect_modules(_project_packages())
    return modules, import_graph(modules)


def test_every_module_has_exactly_one_layer(project):
    modules, _ = project
    misplaced = {m: [LAYERS[i][0] for i in layer_of(m, LAYERS)] for m in modules if len(layer_of(m, LAYERS)) != 1}
    assert not misplaced, f"add each module to exactly one layer of LAYERS in {__file__}: {misplaced}"


def test_no_new_import_cycles(project):
    modules, edges = project
    problems = compare(import_cycles(modules, edges), KNOWN_CYCLES, "import cycle")
    assert not problems, "\n".join(problems)


def test_no_new_upward_imports(project):
    modules, edges = project
    found = upward_imports(edges, LAYERS)
    problems = compare(found, KNOWN_UPWARD, "upward import")
    where = {
        f"new upward import: {a} -> {b}": f" ({modules[a].path.relative_to(ROOT)}:{edges[(a, b)]}, "
        f"layer {LAYERS[layer_of(a, LAYERS)[0]][0]} imports layer {LAYERS[layer_of(b, LAYERS)[0]][0]})"
        for a, b in found
    }
    assert not problems, "\n".join(p + where.get(p, "") for p in problems)


def test_no_new_oversize_modules(project):
    modules, _ = project
    found = oversize_modules(modules, MAX_LINES)
    problems = compare(found, KNOWN_OVERSIZE, f"module over {MAX_LINES} lines")
    sizes = ", ".join(f"{name} {n}" for name, n in sorted(found.items()))
    assert not problems, "\n".join(problems) + f"\n(line counts: {sizes})"


def test_every_allowlist_entry_names_its_issue():
    for entries in (KNOWN_CYCLES, KNOWN_UPWARD, KNOWN_OVERSIZE):
        for key, reason in entries.items():
            assert re.search(r"issue #\d+", reason), f"{_show(key)}: name the issue that removes it"


def test_architecture_doc_lists_the_same_layers():
    doc = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = re.findall(r"^\| (\d+) \| ([^|]+?) \| ([^|]+?) \|", doc, flags=re.M)
    assert [(int(i), name) for i, name, _ in table] == list(enumerate(n for n, _ in LAYERS))
    for (_, cells), (_, _, listed) in zip(LAYERS, table, strict=True):
        assert sorted(re.findall(r"`([^`]+)`", listed)) == sorted(cells)


# -- the checker on a synthetic package ----------------------------------------------------------
SYNTHETIC_LAYERS = (("low", ("pkg.low.*",)), ("mid", ("pkg.mid",)), ("top", ("pkg", "pkg.top")))


def _write(root: Path, files: Mapping[str, str]) -> None:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


@pytest.fixture
def synthetic(tmp_path):
    _write(
        tmp_path,
        {
            "pkg/__init__.py": "from pkg.top import run\n",
            "pkg/top.py": "import os\nfrom . import mid\n\ndef run():\n    return mid.go()\n",
            # function-local upward import (mid -> top) closing the cycle top -> mid -> top
            "pkg/mid.py": "def go():\n    from pkg.top import run\n    return run\n",
            "pkg/low/__init__.py": "",
            # TYPE_CHECKING import ignored; its else branch runs and counts; a literal import_module counts
            "pkg/low/a.py": (
                "from typing import TYPE_CHECKING\nimport typing\n"
                "if TYPE_CHECKING:\n    from pkg.top import run\n"
                "if typing.TYPE_CHECKING:\n    import pkg.mid\nelse:\n    from .b import helper\n"
                "x = 1\n"
            ),
            "pkg/low/b.py": "import importlib\n\ndef helper():\n    return importlib.import_module('pkg.low.c')\n",
            "pkg/low/c.py": "from .. import mid\nfrom ..low import a\n" + "y = 2\n" * 8,
        },
    )
    modules = collect_modules([tmp_path / "pkg"])
    return modules, import_graph(modules)


def test_checker_reads_every_kind_of_import(synthetic):
    modules, edges = synthetic
    assert sorted(modules) == ["pkg", "pkg.low", "pkg.low.a", "pkg.low.b", "pkg.low.c", "pkg.mid", "pkg.top"]
    assert set(edges) == {
        ("pkg", "pkg.top"),
        ("pkg.top", "pkg.mid"),  # `from . import mid`: the submodule, not the package
        ("pkg.mid", "pkg.top"),  # function-local
        ("pkg.low.a", "pkg.low.b"),  # the else branch of `if TYPE_CHECKING`
        ("pkg.low.b", "pkg.low.c"),  # importlib.import_module('pkg.low.c')
        ("pkg.low.c", "pkg.mid"),  # `from .. import mid`
        ("pkg.low.c", "pkg.low.a"),  # `from ..low import a`
    }
    assert edges[("pkg.mid", "pkg.top")] == 2


def test_checker_finds_cycles_upward_imports_and_oversize(synthetic):
    modules, edges = synthetic
    cycles = import_cycles(modules, edges)
    assert cycles == {frozenset({"pkg.top", "pkg.mid"}), frozenset({"pkg.low.a", "pkg.low.b", "pkg.low.c"})}
    assert upward_imports(edges, SYNTHETIC_LAYERS) == {("pkg.mid", "pkg.top"), ("pkg.low.c", "pkg.mid")}
    assert oversize_modules(modules, 9) == {"pkg.low.c": 10}
    assert oversize_modules(modules, 10) == {}


def test_allowlist_fails_on_new_and_on_stale_entries(synthetic):
    modules, edges = synthetic
    found = upward_imports(edges, SYNTHETIC_LAYERS)
    assert compare(found, {("pkg.mid", "pkg.top"), ("pkg.low.c", "pkg.mid")}, "upward import") == []
    assert compare(found, {("pkg.mid", "pkg.top")}, "upward import") == ["new upward import: pkg.low.c -> pkg.mid"]
    stale = compare(found, found | {("pkg.low.a", "pkg.top")}, "upward import")
    assert stale == ["stale allowlist entry (upward import 'pkg.low.a -> pkg.top' is gone): delete it"]
    # a cycle that changes members is a new cycle and a stale entry, not a match
    grown = compare(import_cycles(modules, edges), {frozenset({"pkg.top", "pkg.mid", "pkg"})}, "import cycle")
    assert len(grown) == 3 and grown[-1].startswith("stale allowlist entry (import cycle 'pkg <-> pkg.mid <-> pkg.top'")


def test_unplaced_and_doubly_placed_modules_are_seen():
    layers = (("a", ("p.x.*",)), ("b", ("p.x.y", "p")))
    assert layer_of("p.x.y", layers) == [0, 1]
    assert layer_of("p.z", layers) == []
    assert layer_of("p", layers) == [1]
    assert layer_of("p.xy", layers) == []  # "p.x.*" is a package prefix, not a string prefix


if __name__ == "__main__":  # print today's violations, to update the allowlists after a merge
    _modules = collect_modules(_project_packages())
    _edges = import_graph(_modules)
    print("unplaced or doubly placed:", sorted(m for m in _modules if len(layer_of(m, LAYERS)) != 1))
    for _c in sorted(import_cycles(_modules, _edges), key=_show):
        print("cycle:", _show(_c))
    for _a, _b in sorted(upward_imports(_edges, LAYERS)):
        print(f"upward: {_a} -> {_b}  ({_modules[_a].path.relative_to(ROOT)}:{_edges[(_a, _b)]})")
    for _m, _n in sorted(oversize_modules(_modules, MAX_LINES).items()):
        print(f"oversize: {_m} {_n} lines")
