"""What ``lmic theorems`` lists, without importing every plugin (and sympy) each time.

:func:`theorem_index` returns each installed theorem's metadata (:class:`TheoremInfo`: id,
title, citation, kind, objective, provider), the plugins that failed to load and the ambiguous
ids -- exactly what the full registry (:mod:`lmic.registry`) gives. The full registry imports
every plugin module; its answer is stored in lmic's on-disk cache (:mod:`lmic.cache`, kind
``theorems``), keyed by a *fingerprint* of everything that answer depends on:

* lmic's version and the Python version;
* every entry point of the ``lmic.theorems`` group (name, target, distribution and version);
* size and modification time of every ``.py`` file of each plugin's top-level package and of
  lmic itself (editable installs change files, not versions);
* the modification time of every folder on ``sys.path`` but the working folder (installing or
  removing a distribution changes its folder).

Only a clean answer is stored (no broken plugin, no ambiguous id): a failure is re-examined by
the full registry on every run, so ``lmic theorems`` keeps failing CI until it is fixed. Any
plugin works unchanged (nothing is declared by the plugin); ``LMIC_NO_CACHE=1`` forces the full
registry. ``LMIC_DISABLE_PLUGIN_AUTOLOAD`` bypasses the index (nothing is discovered).

Examples
--------
>>> infos, broken, clashes = theorem_index()
>>> any(i.id == "qib.thm1" for i in infos), broken, clashes
(True, [], [])
"""

from __future__ import annotations

import importlib.util
import os
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from lmic import cache
from lmic._version import __version__

if TYPE_CHECKING:  # the registry imports the template layer (sympy): only on a miss
    from lmic.registry import BrokenPlugin, Conflict
    from lmic.template.theorem import Theorem

__all__ = ["TheoremInfo", "theorem_index", "fingerprint", "KIND", "EntryPointRecord", "group_entry_points"]

#: the cache kind of the index
KIND = "theorems"
GROUP = "lmic.theorems"
#: the cache kind of the installed distributions' lmic entry points, and the groups it holds
EP_KIND = "entry-points"
EP_GROUPS = ("lmic.theorems", "lmic.backends")
_KIND_WORDS = {"S": "synthesis", "A": "analysis"}


@dataclass(frozen=True)
class TheoremInfo:
    """A theorem's metadata as ``lmic theorems`` prints it (no build function, no sympy).

    >>> TheoremInfo("a.b", "t", "c", "A", "feasibility", None).kind_word
    'analysis'
    """

    id: str
    title: str
    citation: str
    kind: str
    objective: str
    provider: dict[str, str] | None

    @property
    def kind_word(self) -> str:
        """``synthesis`` or ``analysis``."""
        return _KIND_WORDS.get(self.kind, self.kind)

    @classmethod
    def of(cls, thm: Theorem) -> TheoremInfo:
        """The metadata of a registered theorem."""
        provider = thm.provider.to_dict() if thm.provider else None
        return cls(thm.id, thm.title, thm.citation, thm.kind, thm.objective, provider)


@dataclass(frozen=True)
class EntryPointRecord:
    """One entry point of an lmic group and its distribution (what lmic reads of it).

    >>> EntryPointRecord("qib", "lmic_observers.qib", "lmic.theorems", "lmic", "0.1.0", "/x").value
    'lmic_observers.qib'
    """

    name: str
    value: str
    group: str
    dist_name: str
    dist_version: str
    dist_path: str


def _distribution_signature() -> list[Any] | None:
    """What the entry points of the installed distributions depend on, by ``stat`` alone.

    For every ``sys.path`` entry (as :mod:`importlib.metadata` scans it; ``""`` is the working
    folder), every ``*.dist-info`` / ``*.egg-info`` / ``*.egg`` in it with the modification
    time and size of its ``entry_points.txt``; a path entry that is no folder (a zip) by its own
    modification time. Installing, removing or re-installing a distribution, or editing its
    entry points, changes it. ``None`` when another distribution finder is installed on
    ``sys.meta_path`` (its distributions cannot be seen this way): no caching.
    """
    from importlib.machinery import PathFinder

    if any(f is not PathFinder and getattr(f, "find_distributions", None) is not None for f in sys.meta_path):
        return None
    out: list[Any] = []
    for entry in sys.path:
        folder = entry or "."
        try:
            with os.scandir(folder) as it:
                dists = []
                for de in it:
                    low = de.name.lower()
                    if not low.endswith((".dist-info", ".egg-info", ".egg")):
                        continue
                    inner = "EGG-INFO" if low.endswith(".egg") else ""
                    try:
                        st = os.stat(os.path.join(de.path, inner, "entry_points.txt"))
                        dists.append([de.name, st.st_mtime_ns, st.st_size])
                    except OSError:
                        dists.append([de.name, None, None])
            out.append([entry, os.path.abspath(folder), sorted(dists)])
        except NotADirectoryError:
            try:
                out.append([entry, os.stat(folder).st_mtime_ns])
            except OSError:
                out.append([entry, None])
        except OSError:
            out.append([entry, None])
    return out


def _scan_entry_points() -> list[EntryPointRecord]:
    """The entry points of :data:`EP_GROUPS` from :mod:`importlib.metadata` (a full scan)."""
    from importlib.metadata import entry_points

    out = []
    dists: dict[str, tuple[str, str]] = {}  # a distribution's metadata is parsed once, not per entry point
    every = entry_points()
    for group in EP_GROUPS:
        for ep in every.select(group=group):
            dist = getattr(ep, "dist", None)
            where = str(getattr(dist, "_path", None) or id(dist))
            if where not in dists:
                meta = getattr(dist, "metadata", None) if dist is not None else None
                dists[where] = (str(meta["Name"] or ""), str(meta["Version"] or "")) if meta is not None else ("", "")
            path = str(getattr(dist, "_path", "") or "")
            out.append(EntryPointRecord(ep.name, ep.value, group, *dists[where], path))
    return out


#: this process's entry points: (sys.path when read, records)
_EP_MEMO: list[tuple[tuple[str, ...], list[EntryPointRecord]]] = []


def group_entry_points(group: str) -> list[EntryPointRecord]:
    """The entry points of an lmic group (``lmic.theorems``, ``lmic.backends``), in scan order.

    :mod:`importlib.metadata` reads every installed distribution's metadata (~20 ms of import
    and 5-30 ms per scan in a one-shot process); the answer is kept in lmic's cache (kind
    ``entry-points``) under :func:`_distribution_signature`; a process reads them once per
    ``sys.path`` (a distribution installed into a folder already on it while the process runs
    is seen by the next process). Any doubt (cache off or
    unreadable, a foreign distribution finder) is a full scan.

    >>> any(r.name == "scs" for r in group_entry_points("lmic.backends"))
    True
    """
    if group not in EP_GROUPS:
        raise ValueError(f"not an lmic entry-point group: {group}")
    if _EP_MEMO and _EP_MEMO[0][0] == tuple(sys.path):  # read once per process (and sys.path)
        return [r for r in _EP_MEMO[0][1] if r.group == group]
    sig = _distribution_signature()
    records: list[EntryPointRecord] | None = None
    key = None if sig is None else {"python": list(sys.version_info[:3]), "signature": sig}
    payload = cache.load(EP_KIND, key) if key is not None else None
    if isinstance(payload, dict) and isinstance(payload.get("records"), list):
        try:
            records = [EntryPointRecord(*(str(v) for v in rec)) for rec in payload["records"]]
        except TypeError:  # a record of another shape (not 6 fields, not a list): a full scan
            records = None
    if records is None:
        records = _scan_entry_points()
        if key is not None and _distribution_signature() == sig:  # nothing installed meanwhile
            cache.store(EP_KIND, key, {"records": [list(asdict(r).values()) for r in records]})
    _EP_MEMO[:] = [(tuple(sys.path), records)]
    return [r for r in records if r.group == group]


def _files(root: Path) -> list[list[Any]]:
    """``[relative path, size, mtime_ns]`` of every ``.py`` file below ``root`` (or of ``root``)."""
    if root.is_file():
        st = root.stat()
        return [[root.name, st.st_size, st.st_mtime_ns]]
    out: list[list[Any]] = []
    for folder, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__" and not d.startswith("."))
        for name in sorted(names):
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                st = os.stat(path)
                out.append([os.path.relpath(path, root), st.st_size, st.st_mtime_ns])
    return out


def _package_root(top: str) -> Path | None:
    """The folder (or single file) of the top-level module ``top``, found without importing it."""
    spec = importlib.util.find_spec(top)
    if spec is None:
        return None
    if spec.submodule_search_locations:
        return Path(list(spec.submodule_search_locations)[0])
    return Path(spec.origin) if spec.origin else None


def fingerprint() -> dict[str, Any] | None:
    """The key of the index: what the registry's answer depends on (module docstring).

    ``None`` when it cannot be computed (a plugin's module cannot be located): no caching.

    >>> fp = fingerprint(); fp["lmic"] == __import__("lmic").__version__
    True
    """
    try:
        eps = []
        tops: set[str] = set()
        for rec in group_entry_points(GROUP):
            eps.append([rec.name, rec.value, rec.dist_name, rec.dist_version])
            tops.add(rec.value.split(":")[0].split(".")[0].strip())
        files: dict[str, Any] = {"lmic": _files(Path(__file__).resolve().parent)}
        for top in sorted(tops):
            root = _package_root(top)
            if root is None:
                return None
            files[top] = [str(root), _files(root)]
        paths = []
        cwd = os.getcwd()
        for entry in sys.path:
            if entry in ("", ".") or os.path.abspath(entry) == cwd:
                continue  # the working folder (python -m): files written there do not install anything
            try:
                paths.append([entry, os.stat(entry or ".").st_mtime_ns])
            except OSError:
                paths.append([entry, None])
    except (OSError, ValueError, ImportError):
        return None
    return {
        "lmic": __version__,
        "python": list(sys.version_info[:3]) + [sys.implementation.name],
        "entry_points": sorted(eps),
        "files": files,
        "sys_path": paths,
    }


def _from_payload(payload: Any) -> list[TheoremInfo] | None:
    """The index stored in the cache, checked field by field; ``None`` if anything is off."""
    if not isinstance(payload, dict) or not isinstance(payload.get("theorems"), list):
        return None
    out = []
    for rec in payload["theorems"]:
        if not isinstance(rec, dict) or set(rec) != {"id", "title", "citation", "kind", "objective", "provider"}:
            return None
        if not all(isinstance(rec[k], str) for k in ("id", "title", "citation", "kind", "objective")):
            return None
        prov = rec["provider"]  # [key, value] pairs: the cache sorts keys, the order is the dict's
        if prov is not None:
            if not isinstance(prov, list) or not all(
                isinstance(kv, list) and len(kv) == 2 and isinstance(kv[0], str) for kv in prov
            ):
                return None
            prov = {k: v for k, v in prov}
        out.append(TheoremInfo(**{**rec, "provider": prov}))
    if [i.id for i in out] != sorted({i.id for i in out}):
        return None
    return out


def full_index() -> tuple[list[TheoremInfo], list[BrokenPlugin], list[Conflict]]:
    """The answer of the full registry (imports every plugin)."""
    from lmic.registry import broken_plugins, conflicts, list_theorems

    return [TheoremInfo.of(t) for t in list_theorems()], broken_plugins(), conflicts()


def theorem_index() -> tuple[list[TheoremInfo], list[BrokenPlugin], list[Conflict]]:
    """Installed theorems (sorted by id), broken plugins and ambiguous ids; cached (see above)."""
    registry = sys.modules.get("lmic.registry")
    if registry is not None and getattr(registry.REGISTRY, "_loaded", False):
        return full_index()  # already loaded in this process (theorems registered from Python too)
    if os.environ.get("LMIC_DISABLE_PLUGIN_AUTOLOAD") or cache.cache_dir() is None:
        return full_index()
    key = fingerprint()
    if key is not None:
        infos = _from_payload(cache.load(KIND, key))
        if infos is not None:
            return infos, [], []
    infos, broken, clashes = full_index()
    # stored under the state *after* loading (importing a plugin may write __pycache__ into a
    # folder of sys.path), provided no source file or entry point changed meanwhile
    after = fingerprint() if key is not None else None
    if key is None or after is None or any(after[k] != key[k] for k in ("entry_points", "files")):
        return infos, broken, clashes
    key = after
    if not broken and not clashes:
        records = [
            {**asdict(i), "provider": None if i.provider is None else [list(kv) for kv in i.provider.items()]}
            for i in infos
        ]
        cache.store(KIND, key, {"theorems": records})
    return infos, broken, clashes
