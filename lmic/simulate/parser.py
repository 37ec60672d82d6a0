"""A small, safe expression language for the ``simulation:`` section of a system file.

User text is tokenised and parsed by hand (recursive descent) into a tree of :class:`Node`
objects, then turned into a tree of Python closures over numpy functions. Nothing here calls
``eval``, ``exec``, ``compile``, ``sympify`` or ``parse_expr``: a string can only ever name the
numbers, variables, operators and functions listed below, and anything else is a
:class:`~lmic.errors.DataError` naming the offending token and its column (1-based).

Grammar (Python precedence: ``**`` binds tighter than unary minus and is right-associative,
so ``-x**2 == -(x**2)`` and ``2**-1 == 0.5``)::

    expr   := term (("+" | "-") term)*
    term   := unary (("*" | "/") unary)*
    unary  := ("+" | "-") unary | power
    power  := atom ("**" unary)?
    atom   := NUMBER | NAME | NAME "(" expr ("," expr)* ")" | "(" expr ")"

Numbers: ``12``, ``0.5``, ``.5``, ``1e-3``, ``2.5E+2`` (ASCII digits only). Variables are the
names the caller allows (``x1..xn``, ``u``, ``u1..um``, ``t``). Functions: ``sin``, ``cos``,
``tan``, ``exp``, ``log``, ``sqrt``, ``abs``, ``tanh`` (one argument); ``sat(v)`` (clip to
[-1, 1]) or ``sat(v, a)`` (clip to [-a, a]); ``min`` and ``max`` (two or more arguments).

Evaluation uses numpy with floating-point errors silenced: a division by zero or the log of a
negative number gives ``inf``/``nan``, which the simulator reports as a blow-up with its time.

Examples
--------
>>> f = parse("-0.333*sin(x3) + sat(2*u, 0.5)", {"x3", "u", "t"})
>>> round(float(f.evaluate({"x3": 1.0, "u": 1.0, "t": 0.0})), 6)
0.21979
>>> parse("1 + os.getcwd()", {"x1"}, where="nonlinearity[3]")
Traceback (most recent call last):
...
lmic.errors.DataError: nonlinearity[3]: unknown name 'os' at column 5 (allowed: x1)
>>> parse("x1 ^ 2", {"x1"}, where="nonlinearity[2]")
Traceback (most recent call last):
...
lmic.errors.DataError: nonlinearity[2]: unexpected character '^' at column 4 (write powers as **)
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lmic.errors import DataError

__all__ = [
    "Token",
    "Node",
    "Expression",
    "tokenize",
    "parse",
    "parse_vector",
    "FUNCTIONS",
    "MAX_LENGTH",
    "MAX_DEPTH",
]

#: longest accepted expression (characters)
MAX_LENGTH = 2000
#: deepest accepted nesting of parentheses, unary signs and powers
MAX_DEPTH = 60

Value = Any  # a float or a numpy array
Env = Mapping[str, Value]


def _sat(v: Value, a: Value = 1.0) -> Value:
    a = np.abs(a)
    return np.minimum(np.maximum(v, -a), a)


def _nary(fn: Callable[[Value, Value], Value]) -> Callable[..., Value]:
    def apply(*args: Value) -> Value:
        out = args[0]
        for a in args[1:]:
            out = fn(out, a)
        return out

    return apply


#: name -> (numpy implementation, min arity, max arity or None for unbounded)
FUNCTIONS: dict[str, tuple[Callable[..., Value], int, int | None]] = {
    "sin": (np.sin, 1, 1),
    "cos": (np.cos, 1, 1),
    "tan": (np.tan, 1, 1),
    "exp": (np.exp, 1, 1),
    "log": (np.log, 1, 1),
    "sqrt": (np.sqrt, 1, 1),
    "abs": (np.abs, 1, 1),
    "tanh": (np.tanh, 1, 1),
    "sat": (_sat, 1, 2),
    "min": (_nary(np.minimum), 2, None),
    "max": (_nary(np.maximum), 2, None),
}

_BINARY: dict[str, Callable[[Value, Value], Value]] = {
    "+": np.add,
    "-": np.subtract,
    "*": np.multiply,
    "/": np.divide,
    "**": np.power,
}

_TOKEN = re.compile(
    r"(?P<space>[ \t]+)"
    r"|(?P<number>(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)"
    r"|(?P<op>\*\*|[-+*/(),])"
)

_HINTS = {
    "^": " (write powers as **)",
    "[": " (use parentheses)",
    "]": " (use parentheses)",
    "=": " (an expression has no assignments or comparisons)",
    "<": " (an expression has no comparisons)",
    ">": " (an expression has no comparisons)",
    "!": " (an expression has no comparisons)",
    ".": " (attribute access is not allowed)",
    "'": " (strings are not allowed)",
    '"': " (strings are not allowed)",
}


@dataclass(frozen=True)
class Token:
    """One token: ``kind`` in ``number, name, op, bad, end``; ``col`` is 1-based."""

    kind: str
    text: str
    col: int


def tokenize(text: str, where: str = "expression") -> list[Token]:
    """Split ``text`` into tokens (ending with an ``end`` token).

    A character no token starts with becomes a ``bad`` token: the parser reports it when it
    reaches it, so the error named is always the leftmost one.

    >>> [t.text for t in tokenize("2*x1**-1")]
    ['2', '*', 'x1', '**', '-', '1', '']
    """
    if not isinstance(text, str):
        raise DataError(f"{where}: expected an expression string, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise DataError(f"{where}: expression is {len(text)} characters long (at most {MAX_LENGTH})")
    out: list[Token] = []
    pos = 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            out.append(Token("bad", text[pos], pos + 1))
            pos += 1
            continue
        kind = m.lastgroup or ""
        if kind != "space":
            out.append(Token(kind, m.group(), pos + 1))
        pos = m.end()
    out.append(Token("end", "", len(text) + 1))
    return out


@dataclass(frozen=True)
class Node:
    """A parsed expression: ``kind`` in ``num, var, neg, bin, call``.

    ``value`` is the number (``num``), the name (``var``, ``call``) or the operator (``bin``);
    ``args`` are the operands.
    """

    kind: str
    value: Any
    args: tuple[Node, ...] = ()

    def names(self) -> set[str]:
        """Variables the expression reads.

        >>> sorted(parse("x1*sin(t) + x2", {"x1", "x2", "t"}).node.names())
        ['t', 'x1', 'x2']
        """
        if self.kind == "var":
            return {self.value}
        out: set[str] = set()
        for a in self.args:
            out |= a.names()
        return out


class _Parser:
    def __init__(self, text: str, names: Collection[str], where: str) -> None:
        self.tokens = tokenize(text, where)
        self.pos = 0
        self.names = set(names)
        self.where = where
        self.depth = 0

    # -- helpers ---------------------------------------------------------------------------
    @property
    def tok(self) -> Token:
        tok = self.tokens[self.pos]
        if tok.kind == "bad":
            ch = tok.text
            shown = f"U+{ord(ch):04X}" if not ch.isprintable() else (repr(ch) if ch == "'" else f"'{ch}'")
            raise self.fail(f"unexpected character {shown}", tok, _HINTS.get(ch, ""))
        return tok

    def fail(self, message: str, tok: Token | None = None, suffix: str = "") -> DataError:
        tok = tok or self.tok
        return DataError(f"{self.where}: {message} at column {tok.col}{suffix}")

    def describe(self, tok: Token) -> str:
        return "the end of the expression" if tok.kind == "end" else f"'{tok.text}'"

    def expect(self, text: str) -> None:
        if self.tok.text != text or self.tok.kind == "end":
            raise self.fail(f"expected '{text}' but found {self.describe(self.tok)}")
        self.pos += 1

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.fail(f"expression nested more than {MAX_DEPTH} levels deep")

    def allowed(self) -> str:
        return ", ".join(sorted(self.names, key=_natural)) or "no variables"

    # -- grammar ---------------------------------------------------------------------------
    def parse(self) -> Node:
        if self.tok.kind == "end":
            raise self.fail("empty expression")
        node = self.expr()
        if self.tok.kind != "end":
            raise self.fail(f"unexpected {self.describe(self.tok)}")
        return node

    def expr(self) -> Node:
        node = self.term()
        while self.tok.kind == "op" and self.tok.text in "+-":
            op = self.tok.text
            self.pos += 1
            node = Node("bin", op, (node, self.term()))
        return node

    def term(self) -> Node:
        node = self.unary()
        while self.tok.kind == "op" and self.tok.text in ("*", "/"):
            op = self.tok.text
            self.pos += 1
            node = Node("bin", op, (node, self.unary()))
        return node

    def unary(self) -> Node:
        if self.tok.kind == "op" and self.tok.text in "+-":
            op = self.tok.text
            self.pos += 1
            self.enter()
            inner = self.unary()
            self.depth -= 1
            return inner if op == "+" else Node("neg", "-", (inner,))
        return self.power()

    def power(self) -> Node:
        base = self.atom()
        if self.tok.kind == "op" and self.tok.text == "**":
            self.pos += 1
            self.enter()
            exponent = self.unary()
            self.depth -= 1
            return Node("bin", "**", (base, exponent))
        return base

    def atom(self) -> Node:
        tok = self.tok
        if tok.kind == "number":
            self.pos += 1
            value = float(tok.text)
            if not math.isfinite(value):
                raise self.fail(f"number '{tok.text}' is too large", tok)
            return Node("num", value)
        if tok.kind == "name":
            self.pos += 1
            after = self.tokens[self.pos]  # look ahead without tripping over a bad character
            if after.kind == "op" and after.text == "(":
                return self.call(tok)
            if tok.text in FUNCTIONS:
                raise self.fail(f"'{tok.text}' is a function: write {tok.text}(...)", tok)
            if tok.text not in self.names:
                raise self.fail(f"unknown name '{tok.text}'", tok, f" (allowed: {self.allowed()})")
            return Node("var", tok.text)
        if tok.kind == "op" and tok.text == "(":
            self.pos += 1
            self.enter()
            node = self.expr()
            self.depth -= 1
            self.expect(")")
            return node
        if tok.kind == "end":
            raise self.fail("the expression ends too early", tok)
        raise self.fail(f"unexpected '{tok.text}'", tok)

    def call(self, name: Token) -> Node:
        if name.text not in FUNCTIONS:
            if name.text in self.names:
                raise self.fail(f"'{name.text}' is not a function", name)
            known = ", ".join(FUNCTIONS)
            raise self.fail(f"unknown function '{name.text}'", name, f" (functions: {known})")
        _fn, lo, hi = FUNCTIONS[name.text]
        self.pos += 1  # "("
        self.enter()
        args = [self.expr()]
        while self.tok.kind == "op" and self.tok.text == ",":
            self.pos += 1
            args.append(self.expr())
        self.depth -= 1
        self.expect(")")
        if len(args) < lo or (hi is not None and len(args) > hi):
            want = f"{lo}" if lo == hi else (f"{lo} or {hi}" if hi is not None else f"at least {lo}")
            raise self.fail(f"{name.text}() takes {want} argument{'s' if want != '1' else ''}, got {len(args)}", name)
        return Node("call", name.text, tuple(args))


def _natural(name: str) -> tuple[str, int]:
    m = re.match(r"([A-Za-z_]+)(\d*)$", name)
    if not m:
        return (name, 0)
    return (m.group(1), int(m.group(2) or 0))


def _closure(node: Node) -> Callable[[Env], Value]:
    """Turn a parse tree into nested closures over numpy functions (no code generation)."""
    if node.kind == "num":
        value = np.float64(node.value)
        return lambda env: value
    if node.kind == "var":
        name = node.value
        return lambda env: env[name]
    if node.kind == "neg":
        inner = _closure(node.args[0])
        return lambda env: np.negative(inner(env))
    if node.kind == "bin":
        fn = _BINARY[node.value]
        left, right = _closure(node.args[0]), _closure(node.args[1])
        return lambda env: fn(left(env), right(env))
    if node.kind == "call":
        fn = FUNCTIONS[node.value][0]
        parts = [_closure(a) for a in node.args]
        if len(parts) == 1:
            only = parts[0]
            return lambda env: fn(only(env))
        return lambda env: fn(*(p(env) for p in parts))
    raise AssertionError(f"unknown node kind {node.kind}")  # pragma: no cover


@dataclass
class Expression:
    """A parsed expression: its source text, parse tree and evaluator.

    Attributes
    ----------
    text : str
    node : Node
    where : str
        How error messages name it (e.g. ``nonlinearity[3]``).
    """

    text: str
    node: Node
    where: str
    _fn: Callable[[Env], Value]

    def evaluate(self, env: Env) -> Value:
        """The value for ``env`` (names -> floats or numpy arrays, broadcast together).

        Floating-point errors are silenced: the result may be ``inf`` or ``nan``.

        >>> float(parse("x1/x2", {"x1", "x2"}).evaluate({"x1": 1.0, "x2": 0.0}))
        inf
        """
        with np.errstate(all="ignore"):
            return self._fn(env)

    @property
    def constant(self) -> bool:
        """Whether the expression reads no variable."""
        return not self.node.names()


def parse(text: str, names: Collection[str], where: str = "expression") -> Expression:
    """Parse ``text``; only the variables in ``names`` may appear.

    Parameters
    ----------
    text : str
        The expression.
    names : collection of str
        Variable names the expression may read.
    where : str
        Prefix of error messages, e.g. ``"nonlinearity[3]"``.

    Raises
    ------
    DataError
        For anything outside the language, naming the token and its 1-based column.

    Examples
    --------
    >>> float(parse("max(x1, 0, -t)", {"x1", "t"}).evaluate({"x1": -2.0, "t": -1.0}))
    1.0
    >>> parse("sin x1", {"x1"}, where="f")
    Traceback (most recent call last):
    ...
    lmic.errors.DataError: f: 'sin' is a function: write sin(...) at column 1
    """
    if isinstance(text, bool) or not isinstance(text, str | int | float):
        raise DataError(f"{where}: expected an expression string, got {type(text).__name__} {text!r}")
    if not isinstance(text, str):
        text = repr(float(text))
        if not math.isfinite(float(text)):
            raise DataError(f"{where}: {text} is not a finite number")
    node = _Parser(text, names, where).parse()
    return Expression(text, node, where, _closure(node))


def parse_vector(texts: Sequence[Any], names: Collection[str], where: str) -> list[Expression]:
    """Parse a list of expressions, naming each ``where[i]`` (1-based) in errors.

    >>> [e.text for e in parse_vector(["x1", 0], {"x1"}, "nonlinearity")]
    ['x1', '0.0']
    """
    return [parse(s, names, f"{where}[{i + 1}]") for i, s in enumerate(texts)]
