"""Backend discovery through the ``lmic.backends`` entry-point group (built-ins included).

Every backend, built-in or third-party, is a class registered as an entry point::

    [project.entry-points."lmic.backends"]
    clarabel = "lmic.backends.clarabel:ClarabelBackend"

Discovery loads each entry point and validates the class (a :class:`Backend` subclass whose
``name`` is the entry-point name, with a ``STATUS_MAP`` into the shared vocabulary). A plugin
that fails to import or validate is reported by name (:func:`broken_backends`, ``lmic
backends``) without breaking the others; a second plugin claiming a name already taken is
rejected. Plugin code that raises anything while loading (``SystemExit`` included; only
``KeyboardInterrupt`` passes) marks that plugin broken: it never ends lmic or decides its exit
code. ``LMIC_DISABLE_PLUGIN_AUTOLOAD=1`` skips third-party entry points (only lmic's own
load); :func:`register` adds a backend class explicitly.

Examples
--------
>>> backend = get_backend("clarabel")
>>> backend.name
'clarabel'
>>> get_backend("cvxpy:SCS").label
'cvxpy:SCS'
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass
from typing import Any

from lmic.backends.base import Backend
from lmic.errors import BackendUnavailable
from lmic.solution import STATUSES

__all__ = [
    "ENTRY_POINT_GROUP",
    "DISABLE_AUTOLOAD_ENV",
    "BUILTIN_BACKENDS",
    "BackendInfo",
    "get_backend",
    "backend_classes",
    "broken_backends",
    "backend_infos",
    "available_backend_names",
    "register",
    "reset",
]

ENTRY_POINT_GROUP = "lmic.backends"
DISABLE_AUTOLOAD_ENV = "LMIC_DISABLE_PLUGIN_AUTOLOAD"

#: the built-in backends (the same table as pyproject's entry points; used only when lmic
#: runs without being installed, so that no entry point of its own is visible)
BUILTIN_BACKENDS = {
    "clarabel": "lmic.backends.clarabel:ClarabelBackend",
    "scs": "lmic.backends.scs:SCSBackend",
    "cvxopt": "lmic.backends.cvxopt:CVXOPTBackend",
    "sdpa": "lmic.backends.sdpa:SDPABackend",
    "cvxpy": "lmic.backends.cvxpy:CVXPYBackend",
    "picos": "lmic.backends.picos:PICOSBackend",
    "auto": "lmic.backends.auto:AutoBackend",
}

_classes: dict[str, type[Backend]] | None = None
_broken: dict[str, str] = {}
_sources: dict[str, str] = {}


@dataclass
class BackendInfo:
    """One row of ``lmic backends``."""

    name: str
    available: bool
    missing: list[str]
    description: str
    source: str
    error: str = ""

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {
            "name": self.name,
            "available": self.available,
            "missing_packages": self.missing,
            "description": self.description,
            "source": self.source,
            "error": self.error,
        }


def entry_points(group: str) -> list[Any]:
    """The entry points of ``group`` (objects with ``name`` and ``value``), in scan order.

    Read through :func:`lmic.plugin_index.group_entry_points`, which keeps the scan of the
    installed distributions in lmic's cache: a one-shot process neither imports
    :mod:`importlib.metadata` nor reads every distribution's metadata (~25-50 ms).

    >>> any(ep.name == "scs" for ep in entry_points(ENTRY_POINT_GROUP))
    True
    """
    from lmic.plugin_index import group_entry_points

    return list(group_entry_points(group))


def _validate(name: str, obj: object, source: str) -> type[Backend]:
    if not (isinstance(obj, type) and issubclass(obj, Backend)):
        raise TypeError(f"{source} is not a subclass of lmic.backends.backend.Backend")
    if getattr(obj, "__abstractmethods__", None):
        missing = ", ".join(sorted(obj.__abstractmethods__))
        raise TypeError(f"{source} does not implement {missing}")
    if obj.name != name:
        raise TypeError(f"{source} has name '{obj.name}' but is registered as '{name}'")
    bad = sorted({v for v in obj.STATUS_MAP.values() if v not in STATUSES})
    if bad:
        raise TypeError(f"{source} maps statuses into unknown words {bad}")
    return obj


def _load(spec: str) -> object:
    module, _, attr = spec.partition(":")
    obj: object = importlib.import_module(module)
    for part in attr.split(".") if attr else []:
        obj = getattr(obj, part)
    return obj


def _discover() -> dict[str, type[Backend]]:
    global _classes
    if _classes is not None:
        return _classes
    classes: dict[str, type[Backend]] = {}
    _broken.clear()
    _sources.clear()
    autoload = not os.environ.get(DISABLE_AUTOLOAD_ENV)
    eps = list(entry_points(group=ENTRY_POINT_GROUP))
    candidates = [(ep.name, ep.value) for ep in eps]
    own = [c for c in candidates if c[1].startswith("lmic.")]
    if not own:  # running from a source tree without installed metadata
        candidates = list(BUILTIN_BACKENDS.items()) + candidates
    for name, value in candidates:
        builtin = value.startswith("lmic.")
        if not builtin and not autoload:
            continue
        if name in classes or name in _broken:
            if _sources.get(name) == value:
                continue  # the same entry point seen twice (e.g. two installs of one dist)
            _broken[f"{name} ({value})"] = (
                f"duplicate backend name '{name}': already registered by {_sources.get(name)}"
            )
            continue
        try:
            classes[name] = _validate(name, _load(value), value)
            _sources[name] = value
        except KeyboardInterrupt:
            raise
        except BaseException as err:  # noqa: BLE001 - plugin code never decides lmic's fate (SystemExit too)
            _broken[name] = f"plugin '{name}' ({value}) failed to load: {_one_line(err)}"
            _sources[name] = value
    _classes = classes
    return classes


def reset() -> None:
    """Forget the discovered backends (the next call rediscovers them)."""
    global _classes
    _classes = None
    _broken.clear()
    _sources.clear()


def register(cls: type[Backend], *, replace: bool = False) -> None:
    """Register a backend class explicitly (validated like an entry point).

    >>> from lmic.backends.clarabel import ClarabelBackend
    >>> register(ClarabelBackend, replace=True)
    """
    classes = _discover()
    if cls.name in classes and classes[cls.name] is not cls and not replace:
        raise BackendUnavailable(f"duplicate backend name '{cls.name}'")
    classes[cls.name] = _validate(cls.name, cls, f"{cls.__module__}:{cls.__qualname__}")
    _sources[cls.name] = f"{cls.__module__}:{cls.__qualname__}"


def backend_classes() -> dict[str, type[Backend]]:
    """Every successfully loaded backend class by name (available here or not)."""
    return dict(_discover())


def broken_backends() -> dict[str, str]:
    """Plugins that failed to load or validate: name -> message."""
    _discover()
    return dict(_broken)


def _one_line(err: BaseException) -> str:
    if isinstance(err, SystemExit):
        return f"SystemExit({err.code!r}) raised by plugin code"
    return f"{type(err).__name__}: {' '.join(str(err).split())}"


def _instance(cls: type[Backend]) -> Backend | None:
    try:
        return cls()
    except KeyboardInterrupt:
        raise
    except BaseException:  # noqa: BLE001 - plugin code (SystemExit included) never ends lmic
        return None


def backend_infos() -> list[BackendInfo]:
    """One :class:`BackendInfo` per discovered or broken backend, sorted by name."""
    rows = []
    for name, cls in _discover().items():
        inst = _instance(cls)
        try:
            missing = inst.missing_packages() if inst is not None else []
        except KeyboardInterrupt:
            raise
        except BaseException:  # noqa: BLE001 - plugin code (SystemExit included) never ends lmic
            inst, missing = None, []
        rows.append(
            BackendInfo(
                name=name,
                available=inst is not None and not missing,
                missing=missing,
                description=cls.description,
                source=_sources.get(name, ""),
                error="" if inst is not None else "cannot be instantiated",
            )
        )
    for name, msg in _broken.items():
        rows.append(BackendInfo(name, False, [], "", _sources.get(name, ""), msg))
    return sorted(rows, key=lambda r: r.name)


def available_backend_names(expand_variants: bool = False) -> list[str]:
    """Names of the backends usable here (``auto`` excluded); with variants as ``name:V``.

    >>> "clarabel" in available_backend_names()
    True
    """
    names = []
    for info in backend_infos():
        if not info.available or info.name == "auto":
            continue
        cls = _discover()[info.name]
        if expand_variants and cls.variants:
            for v in cls.variants:
                try:
                    inst = cls(v)
                    if inst.is_available():
                        names.append(inst.label)
                except KeyboardInterrupt:
                    raise
                except BaseException:  # noqa: BLE001 - plugin code (SystemExit included) never ends lmic
                    continue
        else:
            names.append(info.name)
    return names


def get_backend(spec: str) -> Backend:
    """An instance of the backend ``spec`` (``"name"`` or ``"name:VARIANT"``).

    Raises :class:`BackendUnavailable` naming the known backends for an unknown name, the pip
    package for a backend whose solver is not installed, and the load error for a broken one.
    """
    name, _, variant = spec.strip().partition(":")
    name = name.lower()
    classes = _discover()
    if name not in classes:
        for key, msg in _broken.items():
            if key == name or key.startswith(name + " "):
                raise BackendUnavailable(msg)
        known = ", ".join(sorted(classes)) or "none"
        raise BackendUnavailable(f"unknown backend '{spec}'; available backends: {known}")
    cls = classes[name]
    if variant and not cls.variants:
        raise BackendUnavailable(f"backend '{name}' takes no ':{variant}' variant")
    try:
        backend = cls(variant or None)
        missing = backend.missing_packages()
    except KeyboardInterrupt:
        raise
    except BaseException as err:  # noqa: BLE001 - plugin code (SystemExit included) never ends lmic
        raise BackendUnavailable(
            f"backend '{name}' ({_sources.get(name, '?')}) failed to start: {_one_line(err)}"
        ) from None
    if missing:
        pkgs = " ".join(missing)
        raise BackendUnavailable(
            f"backend '{backend.label}' needs the Python package(s) {', '.join(missing)}: pip install {pkgs}"
        )
    return backend
