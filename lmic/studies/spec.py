"""Study files: load, validate and expand into jobs (before any job runs).

A study (``schemas/study.schema.json``) names theorems, systems (files, globs, random plants),
a parameter grid or random samples, a task and backends. :func:`load_study` reads it with the
same safe YAML loader as system files, validates it against the schema, checks every name it
can without solving (theorems exist, parameters are the theorem's, files exist and are valid
system files, grids are well formed) and expands the jobs, each with a content hash of
(theorem template, system data, parameters, task, backend, task options). Anything wrong is one
:class:`~lmic.errors.DataError` line naming the study file and the key.

Warm runs (lmic's cache, :mod:`lmic.cache`): a document that passed the schema before is not
validated again, and a theorem an earlier process analysed is read from its frozen plan
(:mod:`lmic.compile.warm`): a warm study loads without jsonschema, sympy or the plugin module.

Examples
--------
>>> study = load_study({"theorem": "thesis.lyapunov",
...                     "systems": {"random": {"count": 3, "seed": 1, "dims": {"n": 2},
...                                            "spectral_abscissa": {"A": -0.5}}}})
>>> len(study.jobs), study.jobs[0].task, len(study.jobs[0].hash)
(3, 'solve', 64)
>>> load_study({"theorem": "no.such", "systems": {"files": ["x.yaml"]}})
Traceback (most recent call last):
...
lmic.errors.DataError: <study>: theorem 'no.such' is not registered (see lmic theorems)
"""

from __future__ import annotations

import glob as globmod
import hashlib
import inspect
import itertools
import json
import math
import os
from dataclasses import dataclass, field
from fnmatch import fnmatch
from pathlib import Path
from typing import Any

import numpy as np

from lmic._version import __version__
from lmic.errors import DataError, LmicError
from lmic.formatting import domain_text
from lmic.system import canonical_json, load_system

__all__ = ["Job", "Study", "load_study", "TASKS", "template_hash", "expand_axis"]

TASKS = ("solve", "crosscheck", "maximize", "audit-published", "audit")
BY_FILENAME = "by-filename"


@dataclass
class Job:
    """One unit of work: everything a worker needs (JSON-able numbers, no paths but for audits)."""

    hash: str
    task: str
    theorem: str | None
    system: dict[str, Any] | None
    system_label: str
    params: dict[str, Any]
    point: dict[str, Any]
    backend: str | None
    backends: list[str] | None = None
    exact: bool = False
    maximize: dict[str, Any] | None = None
    certificate_file: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The JSON form sent to a worker."""
        return {
            "hash": self.hash,
            "task": self.task,
            "theorem": self.theorem,
            "system": self.system,
            "system_label": self.system_label,
            "params": self.params,
            "point": self.point,
            "backend": self.backend,
            "backends": self.backends,
            "exact": self.exact,
            "maximize": self.maximize,
            "certificate_file": self.certificate_file,
        }

    def meta(self) -> dict[str, Any]:
        """What the manifest keeps of a job (no system numbers)."""
        d = self.to_dict()
        d.pop("system")
        return d


@dataclass
class Study:
    """A validated study: its settings and its (deduplicated) jobs in a stable order."""

    name: str
    path: str | None
    task: str
    jobs: list[Job]
    time_limit: float | None = None
    retries: int = 1
    grid_axes: list[str] = field(default_factory=list)
    map_axes: tuple[str, str] | None = None
    maximize: dict[str, Any] | None = None
    duplicates: int = 0


def template_hash(theorem_id: str) -> str:
    """SHA-256 of a theorem's id, its template's source code and the lmic version.

    Two jobs of the same theorem share it; editing the theorem's template changes it, so a
    resumed study re-runs jobs whose theorem changed.

    >>> template_hash("qib.thm1") == template_hash("qib.thm1")
    True
    """
    from lmic.registry import get_theorem

    thm = get_theorem(theorem_id)
    try:
        source = inspect.getsource(thm.build)
    except (OSError, TypeError):
        source = repr(thm.build)
    h = hashlib.sha256(b"lmic-template-v1")
    h.update(canonical_json([thm.id, __version__, source]).encode())
    return h.hexdigest()


def expand_axis(name: str, spec: Any, where: str) -> list[Any]:
    """The values of one grid axis: a list, ``{linspace: [a, b, n]}`` or ``{logspace: [a, b, n]}``.

    ``logspace`` runs from ``a`` to ``b`` themselves (not ``10**a``), both positive.

    >>> expand_axis("eps", {"logspace": [0.01, 1, 3]}, "s")
    [0.01, 0.1, 1.0]
    >>> expand_axis("eps", {"linspace": [1, 0, 2]}, "s")
    [1.0, 0.0]
    """
    if isinstance(spec, list):
        return [float(v) if isinstance(v, int | float) else v for v in spec]
    ((kind, (a, b, n)),) = spec.items()
    a, b, n = float(a), float(b), int(n)
    if not (math.isfinite(a) and math.isfinite(b)):
        raise DataError(f"{where}: grid '{name}': {kind} bounds must be finite numbers")
    if kind == "logspace":
        if a <= 0 or b <= 0:
            raise DataError(f"{where}: grid '{name}': logspace bounds must be positive (got {a:g}, {b:g})")
        values = np.geomspace(a, b, n)
    else:
        values = np.linspace(a, b, n)
    return [float(f"{v:.12g}") for v in values]  # 0.1, not 0.10000000000000009


def _read(path: Path) -> Any:
    import yaml

    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DataError(f"{path}: no such study file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise DataError(f"{path}: cannot be read ({err})") from None
    try:
        return json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except json.JSONDecodeError as err:
        raise DataError(f"{path.name}: malformed JSON at line {err.lineno}: {err.msg}") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        line = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise DataError(f"{path.name}: malformed YAML{line}: {problem}") from None


#: the cache kind of study documents known to pass the schema (lmic.cache)
VALID_KIND = "study-valid"


def _validation_key(raw: Any, schema: Any) -> dict[str, Any] | None:
    """What a successful validation of ``raw`` depends on: the document, the schema, jsonschema's
    version (``None`` when the document is not plain JSON: then it is always validated)."""
    from importlib import metadata

    try:
        doc = json.dumps(raw, sort_keys=True, separators=(",", ":"), allow_nan=False)
        version = metadata.version("jsonschema")
    except (TypeError, ValueError, metadata.PackageNotFoundError):
        return None
    digest = hashlib.sha256(doc.encode()).hexdigest()
    return {
        "document": digest,
        "schema": hashlib.sha256(canonical_json(schema).encode()).hexdigest(),
        "jsonschema": version,
    }


def _validate(raw: Any, where: str) -> None:
    from lmic import cache
    from lmic.schemas import load_schema

    if not isinstance(raw, dict):
        raise DataError(f"{where}: a study file is a mapping with keys theorem, systems, grid, task ...")
    schema = load_schema("study")
    key = _validation_key(raw, schema)
    if key is not None and cache.load(VALID_KIND, key) is True:
        return  # this very document passed this very schema before: jsonschema is not imported
    import jsonschema

    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(raw), key=lambda e: (len(e.absolute_path), list(map(str, e.absolute_path))))
    if errors:
        err = errors[0]
        loc = "/".join(str(p) for p in err.absolute_path) or "(top level)"
        msg = err.message if len(err.message) < 160 else err.message[:157] + "..."
        raise DataError(f"{where}: {loc}: {msg}")
    if key is not None:
        cache.store(VALID_KIND, key, True)


def _jsonable(obj: Any) -> Any:
    return json.loads(json.dumps(obj, default=str))


def _number(v: Any) -> Any:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v


#: the warm path's cache kind of a theorem's study template hash (lmic.compile.warm.load_extra)
HASH_KIND = "study-template-hash"


class _TheoremInfo:
    """Declarations of one theorem (built once, default options plus the study's).

    When an earlier process analysed the theorem, its frozen plan (:mod:`lmic.compile.warm`)
    gives the declarations and the cache the template hash: no plugin module, no sympy.
    """

    def __init__(self, theorem_id: str, options: dict[str, Any], where: str) -> None:
        from lmic.compile.warm import load_extra, store_extra, warm_plan

        self.id = theorem_id
        chosen = {k: v for k, v in options.items() if isinstance(v, str)}
        plan = warm_plan(theorem_id, chosen)
        cached = load_extra(HASH_KIND, theorem_id) if plan is not None else None
        if plan is not None and isinstance(cached, dict) and isinstance(cached.get("hash"), str):
            self.template: Any = plan.template
            self.hash = cached["hash"]
        else:
            from lmic.registry import get_theorem

            try:
                theorem = get_theorem(theorem_id)
            except LmicError:
                raise DataError(f"{where}: theorem '{theorem_id}' is not registered (see lmic theorems)") from None
            self.template = theorem.template(chosen)
            self.hash = template_hash(theorem_id)
            if theorem.provider is not None and not theorem.provider.is_api:
                store_extra(HASH_KIND, theorem_id, {"hash": self.hash})
                _freeze_for_next_time(theorem, chosen)
        self.param_names = {p.name for p in self.template.params} | {o.name for o in self.template.options}

    def check_values(self, values: dict[str, Any], where: str, what: str) -> None:
        """Numbers outside a parameter's declared domain are bad input (before any job runs)."""
        from lmic.compile.frozen import Domain

        decls = {p.name: p for p in self.template.params}
        for name, v in values.items():
            decl = decls.get(name)
            if decl is None or not isinstance(v, float):
                continue
            if isinstance(decl.domain, Domain):  # a frozen plan's (decisive)
                if not decl.domain.contains_number(v):
                    dom = domain_text(decl.domain)
                    raise DataError(f"{where}: {what} '{name}' = {v:g} is outside its domain {dom} in {self.id}")
                continue
            import sympy

            inside = decl.domain.contains(sympy.Float(v))
            if inside not in (sympy.true, sympy.false) and v.is_integer():
                inside = decl.domain.contains(sympy.Integer(int(v)))
            if inside == sympy.false:
                raise DataError(
                    f"{where}: {what} '{name}' = {v:g} is outside its domain {domain_text(decl.domain)} in {self.id}"
                )

    def check_names(self, names: list[str], where: str, what: str) -> None:
        for name in names:
            if name not in self.param_names:
                known = ", ".join(sorted(self.param_names)) or "none"
                raise DataError(f"{where}: {what} '{name}' is not a parameter of {self.id} (its parameters: {known})")


def _freeze_for_next_time(theorem: Any, options: dict[str, Any]) -> None:
    """Store the theorem's frozen plan under this process's fingerprint (the next study loads
    without sympy); the runners store theirs too, but a runner's ``sys.path`` may differ."""
    from lmic.compile import plan_for
    from lmic.compile.freeze import remember

    try:
        remember(plan_for(theorem, options))
    except LmicError:  # a template that does not analyse: its jobs report it
        pass


def _files(spec: dict[str, Any], base: Path, where: str) -> list[Path]:
    out: list[Path] = []
    exclude = spec.get("exclude") or []
    for pattern in spec.get("files") or []:
        full = pattern if os.path.isabs(pattern) else str(base / pattern)
        if globmod.has_magic(pattern):
            found = sorted(Path(p) for p in globmod.glob(full))
            if not found:
                raise DataError(f"{where}: systems: '{pattern}' matches no file")
        else:
            if not Path(full).is_file():
                raise DataError(f"{where}: systems: '{pattern}': no such file")
            found = [Path(full)]
        out.extend(p for p in found if not any(fnmatch(p.name, x) for x in exclude))
    seen: set[str] = set()
    unique = []
    for p in out:
        if str(p.resolve()) not in seen:
            seen.add(str(p.resolve()))
            unique.append(p)
    if spec.get("files") and not unique:
        raise DataError(f"{where}: systems: every file is excluded")
    return unique


def load_study(src: str | os.PathLike[str] | dict[str, Any], label: str | None = None) -> Study:
    """Read, validate and expand a study (path to YAML/JSON, or a dict).

    Parameters
    ----------
    src : path or dict
    label : str, optional
        How errors name a dict study (default ``<study>``).

    Returns
    -------
    Study

    Raises
    ------
    DataError
        One line naming the study file, the key and what is wrong.

    Examples
    --------
    >>> s = load_study({"theorem": "qib.thm1", "params": {"gamma": 0},
    ...                 "grid": {"beta": {"linspace": [0.0, 0.01, 3]}},
    ...                 "systems": {"random": {"count": 2, "dims": {"n": 2, "p": 1}}}})
    >>> len(s.jobs), sorted(s.jobs[0].params)
    (6, ['beta', 'gamma'])
    """
    if isinstance(src, dict):
        raw, where, base, path = src, label or "<study>", Path.cwd(), None
    else:
        p = Path(src)
        raw, where, base, path = _read(p), p.name, p.parent, str(p)
    _validate(raw, where)
    task = raw.get("task", "solve")
    if task == "maximize" and "maximize" not in raw:
        raise DataError(f"{where}: task maximize needs maximize: {{param: NAME}}")
    fixed = {k: _number(v) for k, v in (raw.get("params") or {}).items()}
    axes = {name: expand_axis(name, spec, where) for name, spec in (raw.get("grid") or {}).items()}
    points = [dict(zip(axes, combo, strict=True)) for combo in itertools.product(*axes.values())] if axes else [{}]
    if raw.get("samples"):
        samples = raw["samples"]
        rng = np.random.default_rng(samples.get("seed", 0))
        drawn = []
        for _ in range(samples["count"]):
            pt: dict[str, Any] = {}
            for name, dist in samples["params"].items():
                ((kind, (a, b)),) = dist.items()
                if kind == "loguniform":
                    if a <= 0 or b <= 0:
                        raise DataError(f"{where}: samples '{name}': loguniform bounds must be positive")
                    pt[name] = float(math.exp(rng.uniform(math.log(a), math.log(b))))
                else:
                    pt[name] = float(rng.uniform(a, b))
            drawn.append(pt)
        points = [{**g, **s} for g in points for s in drawn]
    overlap = set(fixed) & set(points[0])
    if overlap:
        raise DataError(f"{where}: '{sorted(overlap)[0]}' is both a fixed parameter and a grid/sample axis")

    # -- theorems -------------------------------------------------------------------------------
    if raw.get("theorem") and raw.get("theorems"):
        raise DataError(f"{where}: give 'theorem' or 'theorems', not both")
    theorem_ids = list(raw.get("theorems") or ([raw["theorem"]] if raw.get("theorem") else []))
    if task != "audit" and not theorem_ids:
        raise DataError(f"{where}: task '{task}' needs a theorem (theorem: ID)")
    by_filename = theorem_ids == [BY_FILENAME]
    if BY_FILENAME in theorem_ids and not by_filename:
        raise DataError(f"{where}: theorem '{BY_FILENAME}' cannot be combined with other theorems")
    if by_filename and raw["systems"].get("random"):
        raise DataError(f"{where}: random plants need a theorem id, not '{BY_FILENAME}'")
    infos: dict[str, _TheoremInfo] = {}

    def info(tid: str) -> _TheoremInfo:
        if tid not in infos:
            infos[tid] = _TheoremInfo(tid, fixed, where)
            infos[tid].check_names(list(fixed), where, "params:")
            infos[tid].check_names(list(points[0]), where, "grid/sample axis")
            infos[tid].check_values(fixed, where, "params:")
            for pt in points:
                infos[tid].check_values(pt, where, "grid/sample value")
            if task == "maximize":
                infos[tid].check_names([raw["maximize"]["param"]], where, "maximize: param")
        return infos[tid]

    if task == "audit":
        theorem_ids = []
    elif not by_filename:
        for tid in theorem_ids:
            info(tid)

    # -- task options ---------------------------------------------------------------------------
    maximize = None
    if task == "maximize":
        if "maximize" not in raw:
            raise DataError(f"{where}: task maximize needs maximize: {{param: NAME}}")
        maximize = dict(raw["maximize"])
        if maximize["param"] in points[0] or maximize["param"] in fixed:
            raise DataError(f"{where}: maximize: '{maximize['param']}' is also fixed or a grid axis")
        lo, hi = maximize.get("lo"), maximize.get("hi")
        if lo is not None and hi is not None and not lo < hi:
            raise DataError(f"{where}: maximize: lo {lo:g} must be below hi {hi:g}")
    elif "maximize" in raw:
        raise DataError(f"{where}: 'maximize' applies to task maximize only (task is {task})")
    if raw.get("backend") and raw.get("backends"):
        raise DataError(f"{where}: give 'backend' or 'backends', not both")
    backends: list[str | None] = list(raw.get("backends") or ([raw["backend"]] if raw.get("backend") else [None]))
    if any(b is not None for b in backends) and task != "audit":
        from lmic.backends.registry import get_backend

        for b in backends:
            try:
                get_backend(str(b))
            except LmicError as err:
                raise DataError(f"{where}: backends: {' '.join(str(err).split())}") from None
    exact = bool(raw.get("exact", False))

    # -- systems --------------------------------------------------------------------------------
    systems: list[tuple[str | None, dict[str, Any] | None, str, str | None]] = []  # theorem, raw, label, cert
    files = _files(raw["systems"], base, where)
    if task == "audit":
        if raw["systems"].get("random"):
            raise DataError(f"{where}: task audit reads certificate files, not random plants")
        systems = [(None, None, f.name, str(f.resolve())) for f in files]
    else:
        from lmic.studies.reproduce import theorem_of

        for f in files:
            system = load_system(f)
            sysraw = _jsonable(system.raw)
            if by_filename:
                tid = theorem_of(f.name)
                info(tid)
                systems.append((tid, sysraw, f.name, None))
            else:
                systems.extend((tid, sysraw, f.name, None) for tid in theorem_ids)
        if raw["systems"].get("random"):
            from lmic.studies.plants import random_plants

            for tid in theorem_ids:
                for k, plant in enumerate(random_plants(info(tid).template, raw["systems"]["random"], where)):
                    systems.append((tid, plant, f"random#{k}", None))
    if not systems:
        raise DataError(f"{where}: systems: no system to study")
    if task == "audit-published":
        for _tid, sysraw, lab, _ in systems:
            if not (sysraw or {}).get("published"):
                raise DataError(f"{where}: systems: {lab} has no 'published:' section to audit")

    # -- jobs -----------------------------------------------------------------------------------
    jobs: list[Job] = []
    seen: set[str] = set()
    duplicates = 0
    data_hashes: dict[int, str] = {}
    for idx, (tid, sysraw, lab, cert) in enumerate(systems):
        if sysraw is not None and idx not in data_hashes:
            data_hashes[idx] = load_system(sysraw, lab).data_hash()
        if cert is not None:
            data_hashes[idx] = hashlib.sha256(Path(cert).read_bytes()).hexdigest()
        for pt in points:
            params = {**fixed, **pt}
            for b in backends if task not in ("audit-published", "audit") else backends[:1]:
                job_backend = None if task == "crosscheck" else b
                job_backends = ([str(x) for x in backends if x is not None] or None) if task == "crosscheck" else None
                key = {
                    "template": infos[tid].hash if tid else None,
                    "data": data_hashes[idx],
                    "params": params,
                    "task": task,
                    "backend": job_backend,
                    "backends": job_backends,
                    "exact": exact,
                    "maximize": maximize,
                }
                h = hashlib.sha256(canonical_json(key).encode()).hexdigest()
                if h in seen:
                    duplicates += 1
                    continue
                seen.add(h)
                jobs.append(
                    Job(h, task, tid, sysraw, lab, params, dict(pt), job_backend, job_backends, exact, maximize, cert)
                )
                if task == "crosscheck":
                    break
    grid_axes = list(axes)
    map_axes = None
    if raw.get("map"):
        mx, my = raw["map"].get("x"), raw["map"].get("y")
        for a in (mx, my):
            if a is not None and a not in grid_axes:
                raise DataError(f"{where}: map: '{a}' is not a grid axis ({', '.join(grid_axes) or 'no grid'})")
        if mx and my:
            map_axes = (mx, my)
    elif len(grid_axes) == 2:
        map_axes = (grid_axes[0], grid_axes[1])
    return Study(
        name=str(raw.get("name") or (Path(path).stem if path else "study")),
        path=path,
        task=task,
        jobs=jobs,
        time_limit=raw.get("time_limit"),
        retries=int(raw.get("retries", 1)),
        grid_axes=grid_axes,
        map_axes=map_axes,
        maximize=maximize,
        duplicates=duplicates,
    )
