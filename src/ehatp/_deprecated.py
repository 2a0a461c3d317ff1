"""Old import paths, kept for one release: ``ehatp.tools.*`` and ``ehatp.policy_format``.

Each old module is three lines calling :func:`moved`: importing it warns once
(``DeprecationWarning``, naming the new home) and it then stands for the modules that hold its
code now. Its names are read from them and set on them, so ``from ehatp.tools.cli import app``
and ``monkeypatch.setattr(ehatp.tools.cli, "solve", ...)`` act on the code that runs. Delete the
old modules, and this one, in the release after 0.3.
"""

from __future__ import annotations

import importlib
import sys
import types
import warnings
from collections.abc import Callable, Iterable
from typing import Any

_TARGETS = "__ehatp_moved_to__"


class _Moved(types.ModuleType):
    """A module that moved: attributes it does not hold itself are those of its new homes."""

    def __getattr__(self, name: str) -> Any:
        for m in _targets(self):
            if hasattr(m, name):
                return getattr(m, name)
        raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")

    def __setattr__(self, name: str, value: Any) -> None:
        owner = _owner(self, name)
        if owner is None:
            super().__setattr__(name, value)
        else:
            setattr(owner, name, value)

    def __delattr__(self, name: str) -> None:
        owner = _owner(self, name)
        if owner is None:
            super().__delattr__(name)
        else:
            delattr(owner, name)

    def __dir__(self) -> list[str]:
        names = set(self.__dict__)
        for m in _targets(self):
            names.update(dir(m))
        return sorted(names)


def _targets(module: types.ModuleType) -> tuple[types.ModuleType, ...]:
    found: tuple[types.ModuleType, ...] = module.__dict__.get(_TARGETS, ())
    return found


def _owner(module: types.ModuleType, name: str) -> types.ModuleType | None:
    """The new home that holds ``name``, unless the old module holds it itself."""
    if name.startswith("__") or name in module.__dict__:
        return None
    return next((m for m in _targets(module) if hasattr(m, name)), None)


def _public(m: types.ModuleType) -> list[str]:
    names = getattr(m, "__all__", None)
    if names is None:
        names = [n for n in vars(m) if not n.startswith("_")]
    return list(names)


def moved(old: str, *new: str) -> None:
    """Make module ``old`` (call it with ``__name__``) stand for the modules ``new``, the first
    being its main new home; warn that ``old`` is deprecated."""
    module = sys.modules[old]
    homes = tuple(importlib.import_module(n) for n in new)
    module.__dict__[_TARGETS] = homes
    module.__dict__["__all__"] = sorted({n for m in homes for n in _public(m)})
    # files that sat beside the old module (the explorer's assets) are beside the new one
    module.__dict__["__file__"] = homes[0].__file__
    module.__class__ = _Moved
    name = module.__spec__.name if module.__spec__ is not None else old
    warnings.warn(f"{name} is deprecated and goes in the next release: import "
                  f"{' / '.join(new)} instead", DeprecationWarning, stacklevel=3)


def moved_names(old: str, new: str, names: Iterable[str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` (PEP 562) for ``old``, whose ``names`` moved to module ``new``:
    each is read from there, with a warning. The import is by name, when a name is asked for:
    ``new`` may import ``old``."""
    moved_here = frozenset(names)

    def __getattr__(name: str) -> Any:
        if name not in moved_here:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        warnings.warn(f"{old}.{name} is deprecated and goes in the next release: import it "
                      f"from {new}", DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(new), name)

    return __getattr__


def register_from(module: str) -> Callable[[Any], None]:
    """The old ``register(app)`` of a command's module: add the command (or group) that
    ``module`` (``ehatp.cli.<command>``) defines to another typer ``app``."""

    def register(app: Any) -> None:
        command_app = importlib.import_module(module).app
        if command_app.info.name:  # a group: bench, export
            app.add_typer(command_app)
        else:
            app.registered_commands.extend(command_app.registered_commands)

    return register


__all__ = ["moved", "moved_names", "register_from"]
