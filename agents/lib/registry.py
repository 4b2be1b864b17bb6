"""Extensions found through Python entry points: chronav's own planners, controllers, predictors
and metrics, and any installed package's, by one mechanism.

Why entry points: a researcher's package registers a planner in its own pyproject.toml
(``[project.entry-points."chronav.planners"] mine = "pkg.module:factory"``) and chronav finds it
once installed, without an edit to chronav; chronav registers its own the same way, so nothing
lists names by hand.  Why cached: the metadata scan reads every installed distribution's
``entry_points.txt`` (a few ms), done at most once per kind and process; a loaded object is
imported at most once.  Why no chronav import here: every layer (agents, tools) reads the
registry, so it sits below them all.

Each kind's own module says what an entry must be and checks it (``check`` below): planning's
planners, control's controllers, the perception predictors, the metrics.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib.metadata import Distribution, EntryPoint, entry_points
from typing import Any

#: kind -> entry point group
GROUPS: dict[str, str] = {
    "planner": "chronav.planners",
    "controller": "chronav.controllers",
    "predictor": "chronav.predictors",
    "metric": "chronav.metrics",
    "agent": "chronav.agents",
}


OWN_PACKAGE = "chronav"


class UnknownExtension(LookupError):
    """A name no installed package registers for that kind; the message lists the known ones."""


class RefusedExtension(RuntimeError):
    """An extension that failed to import or broke its kind's protocol (``str`` names the plug-in,
    its package and the reason); every other extension still works."""

    def __init__(self, kind: str, name: str, package: str, reason: str) -> None:
        super().__init__(f"{kind} plug-in {name!r} from package {package!r} refused: {reason}")
        self.kind, self.name, self.package, self.reason = kind, name, package, reason


@dataclass(frozen=True)
class Extension:
    """One registered entry: kind, name, the distribution that registers it and where it lives."""

    kind: str
    name: str
    package: str
    version: str
    target: str          # "module:attribute", the entry point's value
    entry_point: EntryPoint


@cache
def extensions(kind: str) -> dict[str, Extension]:
    """Every entry of ``kind`` by name (metadata only: nothing is imported).  Two packages
    registering one name: chronav's own keeps it (a plug-in cannot replace ``social`` behind a
    study's back), else the first found on sys.path; the other is listed by ``shadowed``."""
    found: dict[str, Extension] = {}
    for ep in entry_points(group=_group(kind)):
        package, version = _package(ep.dist)
        ext = Extension(kind, ep.name, package, version, ep.value, ep)
        if ep.name in found:
            if package == OWN_PACKAGE and found[ep.name].package != OWN_PACKAGE:
                ext, found[ep.name] = found[ep.name], ext
            _SHADOWED.setdefault(kind, []).append(ext)
            continue
        found[ep.name] = ext
    return dict(sorted(found.items()))


def _package(dist: Distribution | None) -> tuple[str, str]:
    """(name, version) of the distribution that registers an entry.  Cached per distribution (by its
    metadata directory; each scan makes new Distribution objects): a read parses its METADATA file,
    which was most of a scan's time when each of chronav's 20-odd entries read it twice."""
    if dist is None:
        return "?", "?"
    key: object = getattr(dist, "_path", None) or dist
    found = _PACKAGES.get(key)
    if found is None:
        metadata = dist.metadata
        found = _PACKAGES[key] = (metadata["Name"], metadata["Version"])
    return found


_PACKAGES: dict[object, tuple[str, str]] = {}
_SHADOWED: dict[str, list[Extension]] = {}
_LOADED: dict[tuple[str, str], Any] = {}


def shadowed(kind: str) -> list[Extension]:
    """Entries of ``kind`` hidden by another package's entry of the same name."""
    extensions(kind)
    return list(_SHADOWED.get(kind, ()))


def names(kind: str) -> tuple[str, ...]:
    """The registered names of ``kind``, sorted (metadata only)."""
    return tuple(extensions(kind))


def known(kind: str) -> str:
    """``name (package), ...`` for messages."""
    return ", ".join(f"{e.name} ({e.package})" for e in extensions(kind).values()) or "none"


def entry(kind: str, name: str) -> Extension:
    """The entry ``name`` of ``kind``, or UnknownExtension listing the known ones and their packages."""
    found = extensions(kind).get(name)
    if found is None:
        shown = name if len(name) <= 40 else name[:37] + "..."
        raise UnknownExtension(f"unknown {kind} {shown!r}; known: {known(kind)}")
    return found


def load(kind: str, name: str, check: Callable[[Any], None] | None = None) -> Any:
    """The object ``name`` of ``kind`` registers, imported once and checked once by ``check``
    (which raises TypeError or ValueError saying what is wrong).  Raises UnknownExtension, or
    RefusedExtension when the import or the check fails (the reason in the user's words)."""
    key = (kind, name)
    if key in _LOADED:
        return _LOADED[key]
    ext = entry(kind, name)
    try:
        obj = ext.entry_point.load()
    except Exception as exc:  # noqa: BLE001 - any import error of a plug-in is its refusal, reported
        raise RefusedExtension(kind, name, ext.package,
                               f"cannot import {ext.target}: {type(exc).__name__}: {exc}") from None
    if check is not None:
        try:
            check(obj)
        except (TypeError, ValueError) as exc:
            raise RefusedExtension(kind, name, ext.package, str(exc)) from None
    _LOADED[key] = obj
    return obj


def load_all(kind: str, check: Callable[[Any], None] | None = None
             ) -> tuple[dict[str, Any], list[RefusedExtension]]:
    """Every entry of ``kind`` loaded and checked: the good ones by name, and the refusals (so a
    broken plug-in is reported at start and the rest run)."""
    good: dict[str, Any] = {}
    refused: list[RefusedExtension] = []
    for name in extensions(kind):
        try:
            good[name] = load(kind, name, check)
        except RefusedExtension as exc:
            refused.append(exc)
    return good, refused


def summary(obj: Any) -> str:
    """The first line of ``obj``'s docstring: what an extension does, for ``chronav plugins``."""
    doc = getattr(obj, "__doc__", None) or ""
    return doc.strip().splitlines()[0].strip() if doc.strip() else ""


def describe(kind: str, name: str) -> str:
    """What the extension ``name`` does (its docstring's first line), or "" when it is not
    installed or cannot be loaded (a report made elsewhere still renders)."""
    try:
        return summary(load(kind, name))
    except (UnknownExtension, RefusedExtension):
        return ""


def check_callable(obj: Any) -> None:
    """The shared first check: an entry point must name a factory (a class or a function)."""
    if not callable(obj):
        raise TypeError(f"the entry point names a {type(obj).__name__}, not a factory (a class or a function)")


def build(kind: str, name: str, protocol: type, lacks: str, *args: Any) -> Any:
    """A new object from the factory ``name`` of ``kind`` registers, called with ``args``.

    RefusedExtension (plug-in, package, reason) when the factory raises or builds something that
    is not a ``protocol`` (a runtime-checkable Protocol; ``lacks`` names the methods it must have).
    One place for every kind's refusal, so they all read alike."""
    make = load(kind, name, check_callable)
    package = entry(kind, name).package
    try:
        built = make(*args)
    except Exception as exc:  # noqa: BLE001 - a plug-in's failing factory is its refusal, reported
        raise RefusedExtension(kind, name, package, f"its factory raised {type(exc).__name__}: {exc}") from None
    if not isinstance(built, protocol):
        raise RefusedExtension(kind, name, package, f"its factory returned a {type(built).__name__} without {lacks}")
    return built


_BUILT: dict[tuple[str, str, int], Any] = {}


def built_once(kind: str, name: str, protocol: type, lacks: str) -> Any:
    """``build(kind, name, protocol, lacks)`` once per process (planners, predictors, metrics hold no
    per-run state); keyed by the factory, so a cleared registry builds again."""
    key = (kind, name, id(load(kind, name, check_callable)))   # the load is cached: a dict read
    found = _BUILT.get(key)
    if found is None:
        found = _BUILT[key] = build(kind, name, protocol, lacks)
    return found


def clear() -> None:
    """Forget the scanned metadata and loaded objects (tests that register entries at run time)."""
    extensions.cache_clear()
    _PACKAGES.clear()
    _SHADOWED.clear()
    _LOADED.clear()


def _group(kind: str) -> str:
    try:
        return GROUPS[kind]
    except KeyError:
        raise ValueError(f"unknown extension kind {kind!r}; kinds: {', '.join(GROUPS)}") from None
