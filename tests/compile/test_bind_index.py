"""lmic.compile.bind_index against independent constructions (the IR's sparse basis, a loop)."""

from __future__ import annotations

import numpy as np
import pytest

from lmic.compile.bind_index import basis_entries, index_dtype, storage_map
from lmic.ir.problem import Variable


@pytest.mark.parametrize(
    ("kind", "shape", "blocks"),
    [
        ("symmetric", (1, 1), ()),
        ("symmetric", (2, 2), ()),
        ("symmetric", (9, 9), ()),
        ("full", (3, 4), ()),
        ("scalar", (1, 1), ()),
        ("diagonal", (4, 4), ()),
        ("blockdiag", (5, 5), (2, 3)),
    ],
)
def test_basis_entries_are_the_ir_basis_in_csc_order(kind, shape, blocks):
    var = Variable("V", kind, shape, 0, blocks)
    coo = var.basis().tocoo()  # the IR's own construction, scipy's CSC order
    rows, cols = basis_entries(var)
    assert rows.tolist() == coo.row.tolist() and cols.tolist() == coo.col.tolist()


@pytest.mark.parametrize("mirrored", [False, True])
def test_storage_map_places_every_entry_by_a_loop(mirrored):
    d, row0, col0, ri, cj = 7, 3, 1, 4, 2  # a 4 x 2 block of a 7 x 7 LMI, below the diagonal block
    smap = storage_map(row0, col0, ri, cj, d, mirrored)
    # storage order: the lower triangle column by column
    where = {}
    for j in range(d):
        for i in range(j, d):
            where[(i, j)] = len(where)
    src_rows = cj if mirrored else ri  # the values' own entry (its transpose when mirrored)
    for r in range(ri * cj):
        a, b = r % src_rows, r // src_rows
        gi, gj = (row0 + b, col0 + a) if mirrored else (row0 + a, col0 + b)
        assert smap[r] == (where[(gi, gj)] if gi >= gj else -1)


def test_diagonal_block_drops_the_upper_triangle():
    smap = storage_map(0, 0, 3, 3, 3, False)
    assert (smap < 0).sum() == 3 and sorted(smap[smap >= 0].tolist()) == list(range(6))


def test_index_dtype_widens_when_needed():
    assert index_dtype(1000) is np.int32
    assert index_dtype(2**30) is np.int64
