"""Input limits, in one place: every reader of a user file checks them before any allocation.

lmic reads system files (YAML/JSON), ``simulation:`` sections, SDPA ``.dat-s`` files, IR JSON
and certificate JSON. A hostile file must give one line and exit code 2, never a crash, a hang
or a multi-gigabyte allocation. The readers share these limits and helpers:

=======================  ==================  ==================================================
limit                    value               why
=======================  ==================  ==================================================
MAX_INPUT_BYTES          256 MiB             a file is read whole; SDPLIB's largest is 30 MB
MAX_DEPTH                64                  nesting of JSON/YAML collections (lmic's deepest
                                             is 5: an IR's matrices inside its sections)
MAX_YAML_NODES           2,000,000           nodes of a YAML document *after* alias expansion
                                             (a "billion laughs" bomb expands to 10^9)
MAX_INT_DIGITS           308                 digits of an integer literal: every such integer
                                             converts to a finite float64 (< 1e308)
MAX_DIMENSION            20,000              a matrix side or an SDPA block size
MAX_VARIABLES            1,000,000           variables of an IR or SDPA problem
MAX_NONZEROS             50,000,000          entries of a sparse IR / SDPA problem
MEMORY_BUDGET_BYTES      2 GiB               dense allocations a reader may make (the sum
                                             of 8 d^2 over the blocks it densifies)
MAX_SIM_STEPS            200,000             points of a simulation (horizon / dt; the
                                             simulator's ``MAX_POINTS``)
=======================  ==================  ==================================================

Numbers: only ASCII digits are digits (``"١٢"`` is text, not 12), integers longer than
:data:`MAX_INT_DIGITS` are refused before any conversion, ``NaN``/``Infinity`` are refused in
JSON, and YAML mappings may not repeat a key. Regular expressions over user text use no nested
quantifiers (linear time).

Examples
--------
>>> load_json_text('{"a": [1, 2.5]}', "f.json")
{'a': [1, 2.5]}
>>> load_yaml_text("a: &x [1, 2]\\nb: *x\\n", "f.yaml")
{'a': [1, 2], 'b': [1, 2]}
>>> load_yaml_text("a: 1\\na: 2\\n", "f.yaml")
Traceback (most recent call last):
...
lmic.errors.DataError: f.yaml: line 2: key 'a' appears twice
"""

from __future__ import annotations

import functools
import json
import re
from typing import Any

from lmic.errors import DataError, LmicError

__all__ = [
    "MAX_INPUT_BYTES",
    "MAX_DEPTH",
    "MAX_YAML_NODES",
    "MAX_INT_DIGITS",
    "MAX_DIMENSION",
    "MAX_VARIABLES",
    "MAX_NONZEROS",
    "MEMORY_BUDGET_BYTES",
    "MAX_SIM_STEPS",
    "LIMITS",
    "load_json_text",
    "load_yaml_text",
    "check_depth",
    "check_size",
    "check_alloc",
    "read_text",
    "ASCII_NUMBER",
]

MAX_INPUT_BYTES = 256 * 2**20
MAX_DEPTH = 64
MAX_YAML_NODES = 2_000_000
MAX_INT_DIGITS = 308
MAX_DIMENSION = 20_000
MAX_VARIABLES = 1_000_000
MAX_NONZEROS = 50_000_000
MEMORY_BUDGET_BYTES = 2 * 2**30
MAX_SIM_STEPS = 200_000

#: every limit by name (``lmic`` documents them in the README's security section)
LIMITS = {
    "MAX_INPUT_BYTES": MAX_INPUT_BYTES,
    "MAX_DEPTH": MAX_DEPTH,
    "MAX_YAML_NODES": MAX_YAML_NODES,
    "MAX_INT_DIGITS": MAX_INT_DIGITS,
    "MAX_DIMENSION": MAX_DIMENSION,
    "MAX_VARIABLES": MAX_VARIABLES,
    "MAX_NONZEROS": MAX_NONZEROS,
    "MEMORY_BUDGET_BYTES": MEMORY_BUDGET_BYTES,
    "MAX_SIM_STEPS": MAX_SIM_STEPS,
}

#: a decimal number in ASCII, no nested quantifiers (linear time on any input)
ASCII_NUMBER = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?", re.ASCII)


def read_text(path: Any, where: str, error: type[LmicError] = DataError) -> str:
    """Read a UTF-8 text file of at most :data:`MAX_INPUT_BYTES` (one-line errors).

    >>> read_text("/nonexistent/x.yaml", "x.yaml")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: x.yaml: no such file
    """
    import os

    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_INPUT_BYTES:
                raise error(f"{where}: file of {size} bytes exceeds the input limit of {MAX_INPUT_BYTES}")
            data = fh.read(MAX_INPUT_BYTES + 1)
    except FileNotFoundError:
        raise error(f"{where}: no such file") from None
    except IsADirectoryError:
        raise error(f"{where}: is a directory") from None
    except OSError as err:
        raise error(f"{where}: cannot be read ({err.strerror or err})") from None
    if len(data) > MAX_INPUT_BYTES:
        raise error(f"{where}: exceeds the input limit of {MAX_INPUT_BYTES} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(f"{where}: not UTF-8 text (byte {err.start})") from None


#: element types that are never containers (a fast test for rows of numbers)
_LEAVES = {int, float, str, bool, type(None)}


def check_depth(obj: Any, where: str, error: type[LmicError] = DataError, limit: int = MAX_DEPTH) -> None:
    """Refuse collections nested deeper than ``limit`` (iterative: no recursion).

    >>> check_depth([[[1]]], "f", limit=2)
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f: nested deeper than 2 levels
    """
    stack: list[tuple[Any, int]] = [(obj, 1)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict | list):
            if depth > limit:
                raise error(f"{where}: nested deeper than {limit} levels")
            children = node.values() if isinstance(node, dict) else node
            if set(map(type, children)) <= _LEAVES:
                continue  # numbers and strings only (a matrix row): nothing nested below
            stack.extend((c, depth + 1) for c in children if isinstance(c, dict | list))


def _parse_int(text: str, where: str, error: type[LmicError]) -> int:
    digits = len(text.lstrip("+-"))
    if digits > MAX_INT_DIGITS:
        raise error(f"{where}: an integer of {digits} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def _parse_float(text: str, where: str, error: type[LmicError]) -> float:
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise error(f"{where}: the number {text[:20]}{'...' if len(text) > 20 else ''} overflows float64")
    return value


def load_json_text(
    text: str,
    where: str,
    error: type[LmicError] = DataError,
    *,
    object_pairs_hook: Any = None,
) -> Any:
    """``json.loads`` within the limits: no NaN/Infinity, no huge integers, bounded nesting.

    >>> load_json_text("[" * 100 + "]" * 100, "f.json")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f.json: nested deeper than 64 levels
    >>> load_json_text("1" * 400, "f.json")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f.json: an integer of 400 digits (at most 308)
    """
    if len(text) > MAX_INPUT_BYTES:
        raise error(f"{where}: exceeds the input limit of {MAX_INPUT_BYTES} bytes")

    def constant(name: str) -> Any:
        raise error(f"{where}: {name} is not allowed (write finite numbers)")

    try:
        obj = json.loads(
            text,
            parse_constant=constant,
            parse_int=lambda s: _parse_int(s, where, error),
            parse_float=lambda s: _parse_float(s, where, error),
            object_pairs_hook=object_pairs_hook,
        )
    except RecursionError:
        raise error(f"{where}: nested deeper than {MAX_DEPTH} levels") from None
    except json.JSONDecodeError as err:
        raise error(f"{where}: malformed JSON at line {err.lineno} column {err.colno}: {err.msg}") from None
    check_depth(obj, where, error)
    return obj


@functools.cache
def _loader_class() -> type:
    """The limited YAML loader class, built on first use (PyYAML is imported only for YAML input)."""
    import yaml

    class _LimitedLoader(yaml.SafeLoader):
        """PyYAML's safe loader with a depth limit, an alias-expansion budget, no duplicate keys,
        and integers checked before conversion."""

        def __init__(self, stream: str) -> None:
            super().__init__(stream)
            self._depth = 0
            self._sizes: dict[int, int] = {}

        def compose_node(self, parent: Any, index: Any) -> Any:
            self._depth += 1
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise yaml.YAMLError(f"__limit__line {mark.line + 1}: nested deeper than {MAX_DEPTH} levels")
            try:
                node = super().compose_node(parent, index)
            finally:
                self._depth -= 1
            key = id(node)
            if key not in self._sizes:
                if isinstance(node, yaml.SequenceNode):
                    size = 1 + sum(self._sizes.get(id(c), 1) for c in node.value)
                elif isinstance(node, yaml.MappingNode):
                    size = 1 + sum(self._sizes.get(id(k), 1) + self._sizes.get(id(v), 1) for k, v in node.value)
                else:
                    size = 1
                if size > MAX_YAML_NODES:
                    line = node.start_mark.line + 1
                    raise yaml.YAMLError(
                        f"__limit__line {line}: expands to more than {MAX_YAML_NODES} nodes (alias bomb?)"
                    )
                self._sizes[key] = size
            return node

        def construct_mapping(self, node: Any, deep: bool = False) -> Any:
            seen: set[Any] = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue  # '<<: *base' merges; explicit keys may override merged ones
                key = self.construct_object(key_node, deep=True)
                try:
                    dup = key in seen
                except TypeError:
                    line = key_node.start_mark.line + 1
                    raise yaml.YAMLError(f"__limit__line {line}: a key must be a name") from None
                if dup:
                    raise yaml.YAMLError(f"__limit__line {key_node.start_mark.line + 1}: key {key!r} appears twice")
                seen.add(key)
            return super().construct_mapping(node, deep=deep)

        def construct_yaml_int(self, node: Any) -> int:
            text = str(node.value).replace("_", "")
            digits = len(text.lstrip("+-"))
            if digits > MAX_INT_DIGITS:
                line = node.start_mark.line + 1
                raise yaml.YAMLError(f"__limit__line {line}: an integer of {digits} digits (at most {MAX_INT_DIGITS})")
            return super().construct_yaml_int(node)

    _LimitedLoader.add_constructor("tag:yaml.org,2002:int", _LimitedLoader.construct_yaml_int)
    return _LimitedLoader


def load_yaml_text(text: str, where: str, error: type[LmicError] = DataError) -> Any:
    """``yaml.safe_load`` within the limits (depth, alias expansion, duplicate keys, integers).

    >>> bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\\n" + "".join(
    ...     f"{c}: &{c} [" + ", ".join([f"*{p}"] * 10) + "]\\n" for p, c in zip("abcdefgh", "bcdefghi"))
    >>> load_yaml_text(bomb, "bomb.yaml")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: bomb.yaml: line 7: expands to more than 2000000 nodes (alias bomb?)
    """
    if len(text) > MAX_INPUT_BYTES:
        raise error(f"{where}: exceeds the input limit of {MAX_INPUT_BYTES} bytes")
    import yaml

    loader = None
    try:
        loader = _loader_class()(text)  # the reader checks the characters here already
        return loader.get_single_data()
    except RecursionError:
        raise error(f"{where}: nested deeper than {MAX_DEPTH} levels") from None
    except yaml.YAMLError as err:
        msg = str(err)
        if msg.startswith("__limit__"):
            raise error(f"{where}: {msg[len('__limit__') :]}") from None
        mark = getattr(err, "problem_mark", None)
        line = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or msg.splitlines()[0]
        raise error(f"{where}: malformed YAML{line}: {problem}") from None
    except (ValueError, OverflowError) as err:  # a scalar the constructors cannot convert
        raise error(f"{where}: {' '.join(str(err).split())}") from None
    finally:
        if loader is not None:
            loader.dispose()


def check_size(value: int, limit: int, what: str, where: str, error: type[LmicError] = DataError) -> int:
    """Refuse a declared size outside ``0..limit`` (before anything is allocated for it).

    >>> check_size(-3, 10, "block size", "f.dat-s")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f.dat-s: block size -3 is out of range (0..10)
    """
    if not isinstance(value, int) or isinstance(value, bool) or value < 0 or value > limit:
        raise error(f"{where}: {what} {value} is out of range (0..{limit})")
    return value


def check_alloc(nbytes: int, what: str, where: str, error: type[LmicError] = DataError) -> None:
    """Refuse an allocation above :data:`MEMORY_BUDGET_BYTES`.

    >>> check_alloc(3 * 2**30, "dense blocks", "f.dat-s")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f.dat-s: dense blocks need 3.2 GB, over the 2.1 GB memory budget
    """
    if nbytes > MEMORY_BUDGET_BYTES:
        raise error(
            f"{where}: {what} need {nbytes / 1e9:.1f} GB, over the {MEMORY_BUDGET_BYTES / 1e9:.1f} GB memory budget"
        )
