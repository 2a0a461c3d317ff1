"""The declared domains: what a problem file's ``[domain] name`` may name besides a ``.py`` file
in its own folder.

A problem file is data, so naming a module must not run it unless the module said it holds a
domain. A domain declares itself in one of two ways:

- an installed package lists it in the entry-point group ``ehatp.domains`` (``pyproject.toml``:
  ``[project.entry-points."ehatp.domains"] kitchen = "my_pkg.domains:make_kitchen"``); ehatp's
  own ``cubes``, ``cooking`` and ``stacking`` are declared so;
- a Python program calls :func:`register` (``ehatp.domains.register("kitchen", make_kitchen)``)
  before it loads the problems that name it.

A problem then names the declared name (``name = "kitchen"``), or ``"module:attribute"`` of a
module some declared domain lives in. Listing the entry points reads the installed packages'
metadata only: nothing is imported until a problem names a declared domain.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

GROUP = "ehatp.domains"

# ehatp's own domains: declared as entry points too (pyproject.toml); named here as well so
# that a source tree that was never installed still finds them
BUILTIN: dict[str, str] = {
    "cubes": "ehatp.domains.cubes:make_domain",
    "cooking": "ehatp.domains.cooking:make_domain",
    "stacking": "ehatp.domains.stacking:make_domain",
}

# name -> "module:attribute", a Domain or a function that returns one; filled by register()
_REGISTERED: dict[str, Any] = {}

HOW_TO_DECLARE = ('declare it as an entry point of group "ehatp.domains" in its package\'s '
                  'pyproject.toml ([project.entry-points."ehatp.domains"] NAME = '
                  '"package.module:attribute"), or call ehatp.domains.register(NAME, ...) '
                  "from Python; see docs/security.md")


def register(name: str, target: object) -> None:
    """Declare a domain under ``name`` for this process: ``target`` is ``"module:attribute"``
    (imported when a problem first names it), a ``Domain``, or a function that returns one
    (called with the ``[domain]`` table's other keys). Raise :class:`ValueError` when ``name``
    is not an identifier, or is declared already with another target."""
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"a domain name is an identifier, got {name!r}")
    if isinstance(target, str):
        module, _, attr = target.partition(":")
        if not module or not attr:
            raise ValueError(f"target {target!r} is not 'module:attribute'")
    known = declared().get(name)
    if known is not None and known is not target and known != target:
        raise ValueError(f"domain {name!r} is declared already (as {known!r}); "
                         "unregister it first, or choose another name")
    _REGISTERED[name] = target


def unregister(name: str) -> None:
    """Forget the domain :func:`register` declared under ``name`` (nothing if there is none)."""
    _REGISTERED.pop(name, None)


def declared(*, installed: bool = True) -> dict[str, Any]:
    """Return every declared domain by name: ehatp's own, then (``installed``) the entry points
    of group ``ehatp.domains``, then those registered from Python (a name declared twice keeps
    its first target; a registered one may not clash with ehatp's own). A target is
    ``"module:attribute"`` or the registered object."""
    from importlib.metadata import entry_points  # the packages' metadata; imports none of them

    out: dict[str, Any] = dict(BUILTIN)
    if installed:
        for ep in entry_points(group=GROUP):
            out.setdefault(ep.name, f"{ep.module}:{ep.attr}")
    for name, target in _REGISTERED.items():
        out.setdefault(name, target)
    return out


def declared_modules(targets: Mapping[str, Any]) -> set[str]:
    """Return the modules the ``"module:attribute"`` targets of :func:`declared` name."""
    return {t.partition(":")[0] for t in targets.values() if isinstance(t, str)}


__all__ = ["BUILTIN", "GROUP", "HOW_TO_DECLARE", "declared", "declared_modules", "register",
           "unregister"]
