"""SDPA sparse format (``.dat-s``) import and export, so any SDPA problem (e.g. SDPLIB) is an IR.

The SDPA format
    A file holds, after optional comment lines starting with ``"`` or ``*``: ``m`` (the number
    of variables), ``nBlocks``, the block sizes (a negative size is a diagonal block), the
    vector ``c`` (``m`` numbers), then one line ``matno blkno i j value`` per non-zero entry
    (``matno`` 0 is ``F0``, ``1..m`` is ``F_1..F_m``; ``i, j`` are 1-based within the block).
    The characters ``, ( ) { }`` separate numbers like white space, and text after the number
    on the ``m`` and ``nBlocks`` lines (``3 = mDIM``) is ignored, as SDPA does. The problem is

        minimise c'x  subject to  F(x) = F_1 x_1 + ... + F_m x_m - F0 >= 0 (PSD),

    the convention of SDPLIB's published optima (its dual is ``max tr(F0 Y)`` s.t.
    ``tr(F_i Y) = c_i``, ``Y >= 0``).

Import (:func:`read_sdpa`) maps it to one IR variable ``x`` (kind ``full``, shape ``(m, 1)``),
    * each matrix block ``k`` to a non-strict LMI named ``block k`` whose constant column is
      ``-F0`` (the IR stores ``F0 + sum x_k F_k >= 0``);
    * each diagonal block ``k`` to linear ``ge`` rows named ``block k[i]``, one per diagonal entry;
    * the objective to ``min c'x``.
    Entries may be given in either triangle (``i > j`` is mirrored). An entry given twice with
    the same value is kept once; with different values it is an error. Explicit zeros are
    dropped. The file name, block structure and comment lines go to ``meta``.

Export (:func:`write_sdpa`) takes an IR with variables of any kind (``x`` is the IR's ``x``):
    * every LMI becomes a matrix block (a strict LMI is exported as non-strict: SDPA has no
      strict inequalities);
    * all linear rows go to one diagonal block, placed last: a ``ge`` row is one diagonal entry,
      an ``eq`` row ``a0 + a.x == 0`` becomes the pair of entries ``a0 + a.x >= 0`` and
      ``-(a0 + a.x) >= 0``;
    * a ``max`` objective is written as ``min`` of ``-c``; a feasibility problem as ``c = 0``.
      The sense and the objective constant ``c0`` go into a comment line
      ``* lmic: {"sense": ..., "c0": ...}`` that :func:`read_sdpa` understands, so re-importing
      an lmic-written file restores them; other readers ignore it.
    Numbers are written with ``repr`` so they read back bitwise equal.

Errors are :class:`~lmic.errors.IRError` naming the file and the line, e.g.
``hinf1.dat-s: line 7: expected 5 fields 'matno blkno i j value', got 3``.

Examples
--------
>>> text = '''"a 1x1 example: min x s.t. x - 2 >= 0"
... 1
... 1
... 1
... 1.0
... 0 1 1 1 2.0
... 1 1 1 1 1.0
... '''
>>> p = read_sdpa(text)
>>> p.lmis[0].name, p.lmis[0].matrix([5.0]), p.objective.sense
('block 1', array([[3.]]), 'min')
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from lmic.errors import IRError
from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
from lmic.ir.svec import tril_index, tril_rows_cols, tril_size
from lmic.limits import MAX_DIMENSION, MAX_INPUT_BYTES, MAX_NONZEROS, MAX_VARIABLES, check_alloc, load_json_text

__all__ = ["read_sdpa", "write_sdpa", "sdpa_text"]

_SEPARATORS = str.maketrans({",": " ", "(": " ", ")": " ", "{": " ", "}": " "})
_FIELDS = "'matno blkno i j value'"
_LMIC_TAG = "* lmic:"
# the number syntax of C's strtol / strtod (Python and numpy also take '1_000', non-ASCII digits)
_INT_RE = re.compile(r"[+-]?[0-9]+\Z")
# no nested or adjacent overlapping quantifiers ("[0-9]+(?:\.[0-9]*)?", not "[0-9]+\.?[0-9]*"):
# a long digit run followed by garbage fails in linear time
_FLOAT_RE = re.compile(
    r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z|[+-]?(?:nan|inf|infinity)\Z",
    re.IGNORECASE,
)
_WS = r"[^\S\n]"  # white space within a line
_ENTRY = (
    rf"{_WS}*(?:(?:[+-]?[0-9]+{_WS}+){{4}}"
    rf"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?{_WS}*)?"
)
# the first line that is neither blank nor a well-formed finite entry (after separators)
_BAD_ENTRY = re.compile(rf"^(?!{_ENTRY}$).*$", re.MULTILINE)


def _int(tok: str) -> int:
    """``int(tok)`` for C-style integer syntax of at most 19 digits only (ValueError otherwise)."""
    if len(tok) > 20 or not _INT_RE.match(tok):
        raise ValueError(tok)
    return int(tok)


def _float(tok: str) -> float:
    """``float(tok)`` for C-style decimal syntax only (ValueError otherwise)."""
    if not _FLOAT_RE.match(tok):
        raise ValueError(tok)
    return float(tok)


class _Header:
    """Token reader for the header lines (m, nBlocks, block sizes, c), tracking line numbers."""

    def __init__(self, lines: list[str], start: int, source: str) -> None:
        self.lines = lines
        self.pos = start  # index of the next unread line
        self.source = source

    def fail(self, lineno: int, msg: str) -> IRError:
        return IRError(f"{self.source}: line {lineno}: {msg}")

    def next_line(self, what: str) -> tuple[int, list[str]]:
        while self.pos < len(self.lines):
            self.pos += 1
            toks = self.lines[self.pos - 1].translate(_SEPARATORS).split()
            if toks:
                return self.pos, toks
        raise self.fail(self.pos + 1, f"unexpected end of file, expected {what}")

    def first_int(self, what: str) -> tuple[int, int]:
        """The integer starting a line (the rest of the line is a free annotation)."""
        lineno, toks = self.next_line(what)
        try:
            return lineno, _int(toks[0])
        except ValueError:
            raise self.fail(lineno, f"expected {what}, got '{_short(toks[0])}'") from None

    def numbers(self, count: int, what: str, conv: Any) -> list[tuple[int, Any]]:
        """``count`` numbers starting on the next line, possibly spread over several lines.

        After the last one, the rest of its line may hold a non-numeric annotation only.
        """
        out: list[tuple[int, Any]] = []
        while len(out) < count:
            lineno, toks = self.next_line(f"{count} {what}, got {len(out)}")
            for tok in toks:
                if len(out) == count:
                    if _is_number(tok):
                        raise self.fail(lineno, f"more than {count} {what}")
                    break
                try:
                    out.append((lineno, conv(tok)))
                except ValueError:
                    raise self.fail(lineno, f"expected {count} {what}; '{_short(tok)}' is not a valid number") from None
        return out


def _short(tok: str) -> str:
    return tok if len(tok) <= 24 else tok[:21] + "..."


def _diagnose(line: str) -> str:
    """What is wrong with one entry line (a line :data:`_BAD_ENTRY` found)."""
    toks = line.translate(_SEPARATORS).split()
    if len(toks) != 5:
        return f"expected 5 fields {_FIELDS}, got {len(toks)}"
    for tok in toks[:4]:
        if _INT_RE.match(tok) and len(tok.lstrip("+-")) > 18:
            return f"index '{tok[:24]}{'...' if len(tok) > 24 else ''}' is out of range"
        try:
            v = _int(tok)
        except ValueError:
            return f"index '{tok[:24]}' is not an integer"
        if abs(v) >= 2**63:
            return f"index '{tok}' is out of range"
    shown = toks[4] if len(toks[4]) <= 24 else toks[4][:21] + "..."
    try:
        value = _float(toks[4])
    except ValueError:
        return f"value '{shown}' is not a number"
    if not math.isfinite(value):
        return f"value {shown} is not finite"
    return f"malformed entry {line.strip()!r}"  # pragma: no cover - the regex and this agree


def _is_number(tok: str) -> bool:
    return bool(_FLOAT_RE.match(tok))


def _source_and_text(path_or_text: str | os.PathLike[str]) -> tuple[str, str]:
    if isinstance(path_or_text, str) and ("\n" in path_or_text or "\r" in path_or_text or not path_or_text.strip()):
        return "<sdpa text>", path_or_text
    source = os.fspath(path_or_text)
    try:
        size = os.stat(source).st_size
        if size > MAX_INPUT_BYTES:
            raise IRError(f"{source}: file of {size} bytes exceeds the input limit of {MAX_INPUT_BYTES}")
        raw = Path(source).read_bytes()
    except OSError as err:
        raise IRError(f"{source}: cannot read: {err.strerror or err}") from None
    try:
        return source, raw.decode("utf-8")
    except UnicodeDecodeError:
        return source, raw.decode("latin-1")


def _parse_lmic_comment(line: str, lineno: int, source: str) -> dict[str, Any]:
    info = load_json_text(line[len(_LMIC_TAG) :], f"{source}: line {lineno}: malformed lmic comment", IRError)
    if not isinstance(info, dict):
        raise IRError(f"{source}: line {lineno}: malformed lmic comment: not an object")
    if info.get("sense", "min") not in ("min", "max", "feasibility"):
        raise IRError(f"{source}: line {lineno}: lmic comment: unknown sense {info['sense']!r}")
    c0 = info.get("c0", 0.0)
    if isinstance(c0, bool) or not isinstance(c0, int | float) or not math.isfinite(c0):
        raise IRError(f"{source}: line {lineno}: lmic comment: c0 is not a finite number")
    return info


def read_sdpa(path_or_text: str | os.PathLike[str]) -> Problem:
    """Import an SDPA sparse (``.dat-s``) problem as an IR :class:`Problem`.

    Parameters
    ----------
    path_or_text : str or path-like
        A file path, or the file's text itself (a ``str`` containing a line break; an empty
        or blank ``str`` is text too).

    Returns
    -------
    Problem
        Variable ``x`` (``full``, ``m x 1``); one non-strict LMI ``block k`` per matrix block;
        linear ``ge`` rows ``block k[i]`` for diagonal blocks; ``min c'x`` (or the sense an
        lmic-written comment records). See the module docstring for the conventions.

    Raises
    ------
    IRError
        Naming the file and the line: missing or malformed header, wrong number of fields,
        non-integer indices, bad or non-finite numbers, matrix or block number out of range,
        index outside its block, off-diagonal entry in a diagonal block, conflicting
        duplicate entries.

    Examples
    --------
    >>> p = read_sdpa("1\\n1\\n-2\\n1.0\\n1 1 1 1 1.0\\n0 1 2 2 -3.0\\n")
    >>> [row for row in p.linear.A.toarray()]
    [array([0., 1.]), array([3., 0.])]
    >>> read_sdpa("1\\n1\\n2\\n1.0\\n1 1 3 1 1.0\\n")
    Traceback (most recent call last):
    ...
    lmic.errors.IRError: <sdpa text>: line 5: index (3, 1) out of range for block 1 of size 2
    """
    source, text = _source_and_text(path_or_text)
    lines = text.splitlines()

    # comments
    comments: list[str] = []
    info: dict[str, Any] = {}
    pos = 0
    while pos < len(lines):
        stripped = lines[pos].lstrip()
        if stripped.startswith(_LMIC_TAG):
            info = _parse_lmic_comment(stripped, pos + 1, source)
        elif stripped.startswith(('"', "*")):
            comments.append(lines[pos])
        elif stripped:
            break
        pos += 1

    head = _Header(lines, pos, source)
    line_m, m = head.first_int("m (the number of constraint matrices)")
    if m < 0:
        raise head.fail(line_m, f"m = {m} is negative")
    if m > MAX_VARIABLES:
        raise head.fail(line_m, f"m = {m} exceeds the limit of {MAX_VARIABLES} variables")
    line_nb, nblocks = head.first_int("nBlocks (the number of blocks)")
    if nblocks < 0:
        raise head.fail(line_nb, f"nBlocks = {nblocks} is negative")
    if nblocks > MAX_VARIABLES:
        raise head.fail(line_nb, f"nBlocks = {nblocks} exceeds the limit of {MAX_VARIABLES}")
    sizes_l = head.numbers(nblocks, "block sizes", _int)
    dense_bytes = 0
    diag_rows = 0
    for size_line, s in sizes_l:
        if s == 0:
            raise head.fail(size_line, "a block size of 0")
        if abs(s) > (MAX_DIMENSION if s > 0 else MAX_VARIABLES):
            limit = MAX_DIMENSION if s > 0 else MAX_VARIABLES
            raise head.fail(size_line, f"block size {s} exceeds the limit of {limit}")
        dense_bytes += 8 * s * s if s > 0 else 0
        diag_rows += -s if s < 0 else 0
    if diag_rows > MAX_VARIABLES:
        raise head.fail(sizes_l[-1][0], f"diagonal blocks of {diag_rows} rows in all exceed the limit {MAX_VARIABLES}")
    check_alloc(dense_bytes, "the matrix blocks (dense)", source, IRError)
    sizes = np.array([s for _, s in sizes_l], dtype=np.int64)
    c_l = head.numbers(m, "entries of the objective vector c", _float)
    c = np.array([v for _, v in c_l], dtype=float)
    bad = np.flatnonzero(~np.isfinite(c))
    if bad.size:
        raise head.fail(c_l[bad[0]][0], f"c[{bad[0] + 1}] = {c[bad[0]]} is not finite")

    # the entries: one per line, validated by one regular-expression pass, parsed in bulk
    start = head.pos
    body_lines = lines[start:]
    body = "\n".join(body_lines).translate(_SEPARATORS)
    bad_entry = _BAD_ENTRY.search(body)
    if bad_entry:
        k = body.count("\n", 0, bad_entry.start())
        raise IRError(f"{source}: line {start + k + 1}: {_diagnose(bad_entry.group(0))}")
    toks = body.split()
    rows = len(toks) // 5
    if rows > MAX_NONZEROS:
        raise IRError(f"{source}: {rows} entries exceed the limit of {MAX_NONZEROS}")

    def lineno(r: int) -> int:
        """Line number of the ``r``-th entry (blank lines are allowed between entries)."""
        if rows == len(body_lines):
            return start + r + 1
        nonblank = [i for i, ln in enumerate(body_lines) if ln.strip()]
        return start + nonblank[r] + 1

    try:
        matno, blkno, ii, jj = (np.array(toks[k::5], dtype=np.int64) for k in range(4))
    except (OverflowError, ValueError):
        huge = (r for r in range(rows) if any(len(t.lstrip("+-")) > 18 for t in toks[5 * r : 5 * r + 4]))
        r = next(huge, 0)
        entry = " ".join(toks[5 * r : 5 * r + 5])
        raise IRError(f"{source}: line {lineno(r)}: {_diagnose(entry)}") from None
    val = np.array(toks[4::5], dtype=float)

    def check(mask: np.ndarray, msg: Any) -> None:
        hits = np.flatnonzero(mask)
        if hits.size:
            r = int(hits[0])
            raise IRError(f"{source}: line {lineno(r)}: {msg(r)}")

    check(~np.isfinite(val), lambda r: f"value {toks[5 * r + 4][:24]} is not finite")
    check((matno < 0) | (matno > m), lambda r: f"matrix number {matno[r]} out of range 0..{m}")
    check(
        (blkno < 1) | (blkno > nblocks),
        lambda r: f"block number {blkno[r]} out of range 1..{nblocks}",
    )
    bsize = np.abs(sizes)[blkno - 1] if nblocks else np.zeros(0, dtype=np.int64)
    check(
        (ii < 1) | (jj < 1) | (ii > bsize) | (jj > bsize),
        lambda r: f"index ({ii[r]}, {jj[r]}) out of range for block {blkno[r]} of size {bsize[r]}",
    )
    diag = sizes[blkno - 1] < 0 if nblocks else np.zeros(0, dtype=bool)
    check(
        diag & (ii != jj),
        lambda r: f"off-diagonal entry ({ii[r]}, {jj[r]}) in diagonal block {blkno[r]}",
    )

    # 0-based lower-triangle position (r >= c); either triangle accepted
    lo = np.minimum(ii, jj) - 1
    hi = np.maximum(ii, jj) - 1

    # duplicates: the same value twice is harmless, different values are ambiguous
    key = np.stack([matno, blkno, lo, hi])
    order = np.lexsort(key[::-1])
    ks = key[:, order]
    same = np.all(ks[:, 1:] == ks[:, :-1], axis=0)
    if same.any():
        dup = np.flatnonzero(same)
        conflict = val[order][dup + 1] != val[order][dup]
        if conflict.any():
            d = int(dup[np.argmax(conflict)])
            a, b = sorted((int(order[d]), int(order[d + 1])))
            raise IRError(
                f"{source}: line {lineno(b)}: entry (matno {matno[b]}, block {blkno[b]}, "
                f"{lo[b] + 1}, {hi[b] + 1}) given again with a different value "
                f"(first on line {lineno(a)})"
            )
        keep = np.ones(len(val), dtype=bool)
        keep[order[dup + 1]] = False
        matno, blkno, lo, hi, val, diag = (matno[keep], blkno[keep], lo[keep], hi[keep], val[keep], diag[keep])

    # F0 enters the IR with a minus sign: F(x) = F0_ir + sum x_k F_k with F0_ir = -F0
    val = np.where(matno == 0, -val, val)
    nonzero = val != 0
    matno, blkno, lo, hi, val, diag = (
        matno[nonzero],
        blkno[nonzero],
        lo[nonzero],
        hi[nonzero],
        val[nonzero],
        diag[nonzero],
    )

    lmis: list[LMI] = []
    mat_blocks = [b for b in range(1, nblocks + 1) if sizes[b - 1] > 0]
    in_matrix = ~diag
    order = np.argsort(blkno[in_matrix], kind="stable")
    mb, ml, mh, mm, mv = (a[in_matrix][order] for a in (blkno, lo, hi, matno, val))
    bounds = np.searchsorted(mb, np.arange(1, nblocks + 2))
    for b in mat_blocks:
        s = int(sizes[b - 1])
        sl = slice(bounds[b - 1], bounds[b])
        rows = tril_index(mh[sl], ml[sl], s)
        coeffs = sp.csc_matrix((mv[sl], (rows, mm[sl])), shape=(tril_size(s), 1 + m))
        lmis.append(LMI(f"block {b}", s, coeffs, strict=False, relation=">=", block_sizes=(s,)))

    diag_blocks = [b for b in range(1, nblocks + 1) if sizes[b - 1] < 0]
    row0 = np.zeros(nblocks + 2, dtype=np.int64)
    names: list[str] = []
    for b in diag_blocks:
        s = int(-sizes[b - 1])
        row0[b] = len(names)
        names += [f"block {b}[{i}]" for i in range(1, s + 1)]
    drow = row0[blkno[diag]] + lo[diag]
    A = sp.csr_matrix((val[diag], (drow, matno[diag])), shape=(len(names), 1 + m))
    linear = LinearConstraints(A, ["ge"] * len(names), [False] * len(names), names)

    sense = info.get("sense", "min")
    cvec = np.concatenate([[float(info.get("c0", 0.0))], -c if sense == "max" else c])
    meta = {
        "format": "sdpa",
        "source": Path(source).name if source != "<sdpa text>" else source,
        "sdpa_block_struct": [int(s) for s in sizes],
    }
    if comments:
        meta["comments"] = comments
    return Problem(
        [Variable("x", "full", (m, 1), offset=0)],
        lmis,
        linear,
        Objective(sense, cvec),
        meta=meta,
    )


def _block_entries(M: sp.spmatrix, blkno: int, to_ij: Any) -> tuple[np.ndarray, ...]:
    """``(matno, blkno, i, j, value)`` arrays of one block (``M``: rows x (1 + m), IR signs)."""
    A = sp.csc_matrix(M, dtype=float, copy=True)
    A.sum_duplicates()
    A.eliminate_zeros()
    A.sort_indices()
    cols = np.repeat(np.arange(A.shape[1], dtype=np.int64), np.diff(A.indptr))
    vals = np.where(cols == 0, -A.data, A.data)  # SDPA's F0 is minus the IR's constant term
    i, j = to_ij(A.indices.astype(np.int64))
    return cols, np.full(len(cols), blkno, dtype=np.int64), i, j, vals


def sdpa_text(problem: Problem) -> str:
    """The SDPA sparse text of an IR problem (see :func:`write_sdpa`).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
    >>> t = Variable("t", "scalar", (1, 1))
    >>> lmi = LMI("t > 1", 1, sp.csc_matrix([[-1.0, 1.0]]), strict=True)
    >>> print(sdpa_text(Problem([t], [lmi], LinearConstraints.empty(1),
    ...                         Objective("min", [0.0, 1.0]))), end="")
    * lmic: {"sense": "min", "c0": 0.0}
    1
    1
    1
    1.0
    0 1 1 1 1.0
    1 1 1 1 1.0
    """
    problem.validate()
    m = problem.n
    out: list[str] = []
    comments = problem.meta.get("comments", []) if problem.meta.get("format") == "sdpa" else []
    for cmt in comments:
        cmt = " ".join(str(cmt).splitlines())
        ok = cmt.lstrip().startswith(('"', "*")) and not cmt.lstrip().startswith(_LMIC_TAG)
        out.append(cmt if ok else "* " + cmt)
    obj = problem.objective
    out.append(f"{_LMIC_TAG} " + json.dumps({"sense": obj.sense, "c0": float(obj.c[0])}))

    sizes: list[int] = []
    parts: list[tuple[np.ndarray, ...]] = []
    for lmi in problem.lmis:
        r_of, c_of = tril_rows_cols(lmi.dim)
        sizes.append(lmi.dim)
        # storage position k is (r, c) with r >= c; SDPA gets the upper triangle, 1-based
        parts.append(_block_entries(lmi.coeffs, len(sizes), lambda k, r=r_of, c=c_of: (c[k] + 1, r[k] + 1)))
    lin = problem.linear
    if len(lin):
        eq = np.flatnonzero(np.array(lin.kinds) == "eq")
        # every row once, every eq row a second time negated (a >= 0 and -a >= 0), in row order
        rows = np.sort(np.concatenate([np.arange(len(lin)), eq]), kind="stable")
        sign = np.ones(len(rows))
        sign[1:][rows[1:] == rows[:-1]] = -1.0
        D = sp.diags(sign) @ sp.csr_matrix(lin.A, dtype=float)[rows]
        sizes.append(-len(rows))
        parts.append(_block_entries(D, len(sizes), lambda k: (k + 1, k + 1)))

    if obj.sense == "feasibility":
        c = np.zeros(m)
    elif obj.sense == "max":
        c = -obj.c[1:]
    else:
        c = obj.c[1:]
    out.append(str(m))
    out.append(str(len(sizes)))
    out.append(" ".join(str(s) for s in sizes))
    out.append(" ".join(repr(v) for v in c.tolist()))
    if parts:
        matno, blk, i, j, val = (np.concatenate(a) for a in zip(*parts, strict=True))
        order = np.lexsort((j, i, blk, matno))  # by matrix number, block, row, column
        out.extend(
            f"{a} {b} {p} {q} {v!r}"
            for a, b, p, q, v in zip(
                matno[order].tolist(),
                blk[order].tolist(),
                i[order].tolist(),
                j[order].tolist(),
                val[order].tolist(),
                strict=True,
            )
        )
    return "\n".join(out) + "\n"


def write_sdpa(problem: Problem, path: str | os.PathLike[str]) -> None:
    """Export an IR problem to an SDPA sparse (``.dat-s``) file.

    Parameters
    ----------
    problem : Problem
        Any IR: variables of any kind (``x`` is the IR's ``x``), LMIs, linear rows, objective.
    path : str or path-like

    Notes
    -----
    Strict LMIs and strict linear rows are written as non-strict (SDPA has no strict
    inequalities); ``eq`` rows become two diagonal entries; a ``max`` objective is written as
    ``min -c`` with the sense kept in an ``* lmic:`` comment line. See the module docstring.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = read_sdpa("1\\n1\\n1\\n1.0\\n0 1 1 1 2.0\\n1 1 1 1 1.0\\n")
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.dat-s"
    >>> write_sdpa(p, f)
    >>> (read_sdpa(f).lmis[0].coeffs != p.lmis[0].coeffs).nnz
    0
    """
    from lmic.output import write_output

    write_output(path, sdpa_text(problem))  # atomic: nothing half-written
