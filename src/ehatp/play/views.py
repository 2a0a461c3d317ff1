"""What a participant of ``ehatp play`` is shown, and the per-domain view hooks that draw it.

:class:`Perspective` is the human's side of the situation only (docs/semantics.md §2-§5): the
facts true in every world the human entertains (*believed*), the units its worlds disagree on
(*unsure*, with the values they take), the facts it sees now, the facts no action changes, and
whether the robot is in sight. It holds nothing of the true state beyond what the human sees:
a view hook receives a perspective and nothing else, so a hook cannot show the participant what
the human cannot perceive.

A view hook is a function ``hook(p: Perspective) -> Scene``: a scene is plain data, a list of
areas (a table, a box, a hand, a room), each with a title and items (a cube, an ingredient),
each item ``unsure`` when the human is not sure it is there. The page draws it with text only.
The cube and cooking domains have hooks here (:func:`cubes_view`, :func:`cooking_view`); a
domain of yours registers one with :func:`register_view` or ``ehatp play --view
module:function``. Without a hook the page shows the facts, grouped by predicate.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypedDict


class Item(TypedDict):
    """One thing drawn in an area: its text, whether the human is unsure it is there, and its
    kind (``cube``, ``agent``, ``ingredient``, ``state``: a style, never markup)."""

    text: str
    unsure: bool
    kind: str


class Area(TypedDict):
    title: str
    kind: str
    items: list[Item]


class Scene(TypedDict):
    areas: list[Area]


@dataclass(frozen=True)
class Unsure:
    """A unit the human's worlds disagree on: an atom (``options`` its two literals) or a state
    variable or counter (``options`` the values its worlds give it, ``loc(r) = mt``)."""

    name: str
    options: tuple[str, ...]


@dataclass(frozen=True)
class Perspective:
    """The situation as the human perceives it (see the module's docstring)."""

    human: str
    robot: str
    believed: tuple[str, ...]
    unsure: tuple[Unsure, ...]
    seeing: tuple[str, ...]
    fixed: tuple[str, ...]
    robot_here: bool
    objects: dict[str, list[str]] = field(default_factory=dict)

    def holds(self, fact: str) -> bool | None:
        """Return True when the human believes ``fact``, None when it is unsure of it, False
        when it believes it false."""
        if fact in self.believed or fact in self.fixed:
            return True
        if any(fact in u.options for u in self.unsure):
            return None
        return False


ViewHook = Callable[[Perspective], Scene]

_CALL = re.compile(r"^([^\s(=\[]+)(?:\(([^)]*)\))?(?:\s*=\s*(\S+))?$")


def parse_fact(text: str) -> tuple[str, tuple[str, ...]]:
    """Return ``on(r, mt)`` as ``("on", ("r", "mt"))``; a variable's ``loc(r) = mt`` as
    ``("loc", ("r", "mt"))`` (the value last, as a problem file's facts); a nullary atom as its
    name and no arguments."""
    m = _CALL.match(text.strip())
    if m is None:
        return text, ()
    args = tuple(a.strip() for a in m.group(2).split(",")) if m.group(2) else ()
    return m.group(1), args + ((m.group(3),) if m.group(3) else ())


def predicate_of(text: str) -> str:
    """Return the predicate (or variable, or counter) a fact is about."""
    return parse_fact(text)[0]


# --- the shipped domains ---------------------------------------------------------------------


def _facts(p: Perspective) -> list[tuple[tuple[str, tuple[str, ...]], bool]]:
    """Every fact the human holds possible, with whether it is unsure of it."""
    out = [(parse_fact(f), False) for f in (*p.fixed, *p.believed)]
    for u in p.unsure:
        out += [(parse_fact(o), True) for o in u.options if not o.startswith("not ")]
    return out


def _add(areas: dict[str, Area], where: str, text: str, unsure: bool, kind: str) -> None:
    area = areas.get(where)
    if area is None:
        return
    shown = text + ("?" if unsure else "")
    if all(i["text"] != shown for i in area["items"]):
        area["items"].append({"text": shown, "unsure": unsure, "kind": kind})


def cubes_view(p: Perspective) -> Scene:
    """Return the cube domain (docs/domains/) as the human perceives it: each table with the
    agents at it and the cubes on it, each box with its cubes, each hand with its cube; a cube
    the human is unsure of is drawn with a question mark wherever it may be."""
    objs = p.objects
    tables = objs.get("table", [])
    boxes = objs.get("box", [])
    agents = [p.human, p.robot]
    areas: dict[str, Area] = {}
    for t in tables:
        areas[t] = {"title": f"table {t}", "kind": "table", "items": []}
    for b in boxes:
        areas[b] = {"title": b, "kind": "box", "items": []}
    for a in agents:
        areas[a] = {"title": f"{a}'s hand", "kind": "hand", "items": []}
    for (name, args), unsure in _facts(p):
        if name == "at" and len(args) == 2:
            _add(areas, args[1], args[0], unsure, "agent")
        elif name in ("on", "in", "loc") and len(args) == 2:
            _add(areas, args[1], args[0], unsure, "cube")
        elif name == "holding" and len(args) == 2:
            _add(areas, args[0], args[1], unsure, "cube")
    return {"areas": list(areas.values())}


_COOKING_STEPS = ("cut", "washed", "seasoned", "boiling", "food_ready")


def cooking_view(p: Perspective) -> Scene:
    """Return the cooking domain as the human perceives it: each place with the agents there,
    where the ingredient is (pantry, a hand, the pan), and the dish's steps done."""
    places = p.objects.get("place", [])
    areas: dict[str, Area] = {pl: {"title": pl, "kind": "place", "items": []} for pl in places}
    areas["hand"] = {"title": f"{p.human}'s hand", "kind": "hand", "items": []}
    areas["pan"] = {"title": "pan", "kind": "pan", "items": []}
    areas["dish"] = {"title": "the vegetables", "kind": "dish", "items": []}
    for (name, args), unsure in _facts(p):
        if name == "at" and len(args) == 2:
            _add(areas, args[1], args[0], unsure, "agent")
        elif name == "in_pantry" and "pantry" in areas:
            _add(areas, "pantry", "ingredient", unsure, "ingredient")
        elif name == "in_hand":
            _add(areas, "hand", "ingredient", unsure, "ingredient")
        elif name == "in_pan":
            _add(areas, "pan", "ingredient", unsure, "ingredient")
        elif name in _COOKING_STEPS:
            _add(areas, "dish", name.replace("_", " "), unsure, "state")
    return {"areas": list(areas.values())}


_VIEWS: dict[str, ViewHook] = {"cubes": cubes_view, "cooking": cooking_view}


def register_view(domain: str, hook: ViewHook) -> None:
    """Draw the domains named ``domain`` (or ``domain-<variant>``, as ``cubes-turn``) with
    ``hook`` in ``ehatp play``, in this process."""
    _VIEWS[domain] = hook


def view_for(domain: str) -> ViewHook | None:
    """Return the view hook of the domain named ``domain`` (its own, else that of the name it
    is a variant of: ``cooking-turn`` is drawn as ``cooking``), None when it has none."""
    hook = _VIEWS.get(domain)
    while hook is None and "-" in domain:
        domain = domain.rpartition("-")[0]
        hook = _VIEWS.get(domain)
    return hook


def load_view(target: str) -> ViewHook:
    """Return the function ``module:function`` names (``ehatp play --view``); ValueError
    saying why when it cannot be imported or is not callable."""
    module, _, name = target.partition(":")
    if not module or not name:
        raise ValueError(f"{target!r} is not module:function")
    try:
        hook: Any = getattr(importlib.import_module(module), name)
    except ImportError as e:
        raise ValueError(f"cannot import {module}: {e}") from None
    except AttributeError:
        raise ValueError(f"{module} has no {name}") from None
    if not callable(hook):
        raise ValueError(f"{target} is not a function")
    return hook  # type: ignore[no-any-return]


def check_scene(scene: Any) -> Scene:
    """Return ``scene`` when it is a scene a hook may return (areas of text items); raise
    ValueError naming what is wrong otherwise, so a broken hook fails loudly."""
    if not isinstance(scene, dict) or not isinstance(scene.get("areas"), list):
        raise ValueError("a view hook returns {'areas': [...]}")
    for a in scene["areas"]:
        if not (isinstance(a, dict) and isinstance(a.get("title"), str)
                and isinstance(a.get("kind", ""), str) and isinstance(a.get("items"), list)):
            raise ValueError("an area is {'title': str, 'kind': str, 'items': [...]}")
        for i in a["items"]:
            if not (isinstance(i, dict) and isinstance(i.get("text"), str)
                    and isinstance(i.get("unsure", False), bool)
                    and isinstance(i.get("kind", ""), str)):
                raise ValueError("an item is {'text': str, 'unsure': bool, 'kind': str}")
    return scene  # type: ignore[return-value]


__all__ = ["Area", "Item", "Perspective", "Scene", "Unsure", "ViewHook", "check_scene",
           "cooking_view", "cubes_view", "load_view", "parse_fact", "predicate_of",
           "register_view", "view_for"]
