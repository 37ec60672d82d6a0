"""Seeded random plants whose data fit a theorem's data declarations.

The shapes come from the theorem's template (``t.data("C", p, n)`` with ``dims: {n: 3, p: 1}``
gives a 1 x 3 ``C``); optional data (declared with a default) are left out unless fixed in
``data:``. Entries are independent normals of standard deviation ``scale``; symmetric data are
symmetrised, positive-definite data are ``G G^T / k + I``. ``spectral_radius: {A: r}`` rescales a
square matrix to spectral radius ``r`` (discrete-time plants), ``spectral_abscissa: {A: a}``
shifts it so that its largest real eigenvalue part is ``a`` (continuous time), ``shift: {A: c}``
adds ``c I``. Plant ``k`` of a
seed is the same whatever the count (``numpy.random.SeedSequence(seed).spawn``).

Examples
--------
>>> from lmic.registry import get_theorem
>>> t = get_theorem("qib.thm1").template()
>>> plants = random_plants(t, {"count": 2, "seed": 7, "dims": {"n": 3, "p": 1},
...                            "spectral_radius": {"A": 0.9}}, "s")
>>> [len(plants[0]["data"]["A"]), len(plants[0]["data"]["C"][0])]
[3, 3]
>>> import numpy as np
>>> round(float(max(abs(np.linalg.eigvals(plants[1]["data"]["A"])))), 6)
0.9
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lmic.compile.frozen import Dim
from lmic.errors import DataError

__all__ = ["random_plants", "data_shapes"]


def data_shapes(template: Any, dims: dict[str, int], fixed: set[str], where: str) -> dict[str, tuple[int, int]]:
    """``name -> (rows, cols)`` of every required data matrix of ``template`` for ``dims``.

    Raises :class:`DataError` when a dimension the data need is missing from ``dims`` or
    ``dims`` names one the theorem does not have.

    >>> from lmic.registry import get_theorem
    >>> data_shapes(get_theorem("qib.thm1").template(), {"n": 4, "p": 2}, set(), "s")
    {'A': (4, 4), 'C': (2, 4)}
    """
    known = {str(s) for s in template.dimensions}
    for name in dims:
        if name not in known:
            raise DataError(
                f"{where}: random: dims '{name}' is not a dimension of {template.theorem_id} "
                f"(its dimensions: {', '.join(sorted(known)) or 'none'})"
            )
    subs = {s: int(dims[str(s)]) for s in template.dimensions if str(s) in dims}
    out: dict[str, tuple[int, int]] = {}
    for decl in template.data_decls:
        if decl.default is not None or decl.name in fixed:
            continue
        shape = []
        for d in decl.shape:
            value, missing = _size(d, subs)
            if value is None:
                raise DataError(
                    f"{where}: random: data '{decl.name}' needs dims {', '.join(missing)} (give them in dims:)"
                )
            if value < 1:
                raise DataError(f"{where}: random: data '{decl.name}' would have a dimension {value}")
            shape.append(value)
        out[decl.name] = (shape[0], shape[1])
    return out


def _size(d: Any, subs: dict[Any, int]) -> tuple[int | None, list[str]]:
    """The value of a data size under ``subs`` and the dimensions it still misses.

    A frozen plan's size (:class:`~lmic.compile.frozen.Dim`) is evaluated without sympy.
    """
    if isinstance(d, Dim):
        missing = sorted(d.names() - {str(k) for k in subs})
        return (None, missing) if missing else (d.value(subs), [])
    from lmic.template.convert import as_expr

    v = as_expr(as_expr(d).xreplace(subs))
    if not v.is_Integer:
        return None, sorted(str(s) for s in v.free_symbols)
    return int(v), []


def random_plants(template: Any, spec: dict[str, Any], where: str) -> list[dict[str, Any]]:
    """``spec["count"]`` system dicts (``lmic: 1, name, data``) for ``template``.

    Parameters
    ----------
    template : lmic.template.builder.Template
        The theorem's declarations (its data shapes).
    spec : dict
        The study's ``systems: random:`` mapping (schema ``study.schema.json``).
    where : str
        The study file's name, for error messages.
    """
    fixed_data = spec.get("data") or {}
    shapes = data_shapes(template, spec["dims"], set(fixed_data), where)
    decls = {d.name: d for d in template.data_decls}
    for key in ("spectral_radius", "spectral_abscissa", "shift"):
        for name in spec.get(key) or {}:
            if name not in shapes or shapes[name][0] != shapes[name][1]:
                raise DataError(f"{where}: random: {key} '{name}' is not a square data matrix of {template.theorem_id}")
    scale = float(spec.get("scale", 1.0))
    seq = np.random.SeedSequence(int(spec.get("seed", 0)))
    plants = []
    for k, child in enumerate(seq.spawn(int(spec["count"]))):
        rng = np.random.default_rng(child)
        data: dict[str, Any] = {}
        for name, (r, c) in shapes.items():
            m = rng.normal(0.0, scale, size=(r, c))
            decl = decls[name]
            if decl.positive_definite:
                m = m @ m.T / max(c, 1) + np.eye(r)
            elif decl.symmetric:
                m = 0.5 * (m + m.T)
            if name in (spec.get("spectral_radius") or {}):
                rho = float(max(abs(np.linalg.eigvals(m))))
                if rho > 0:
                    m = m * (float(spec["spectral_radius"][name]) / rho)
            if name in (spec.get("spectral_abscissa") or {}):
                alpha = float(max(np.linalg.eigvals(m).real))
                m = m + (float(spec["spectral_abscissa"][name]) - alpha) * np.eye(r)
            if name in (spec.get("shift") or {}):
                m = m + float(spec["shift"][name]) * np.eye(r)
            data[name] = m.tolist()
        data.update(fixed_data)
        plants.append({"lmic": 1, "name": f"random plant {k} (seed {spec.get('seed', 0)})", "data": data})
    return plants
