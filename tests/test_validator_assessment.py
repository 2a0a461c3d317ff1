"""The validator's situation assessment (docs/semantics.md §2, ``check/rules.py``): when some
world agrees with the truth on every unit seen, it keeps exactly the worlds that agree on all
of them, which is what learning the units one at a time gives (no unit then revises
anything); otherwise it revises unit by unit."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

import ehatp
from ehatp.check.rules import Rules, _bits

from .conftest import EXAMPLES_DIR

RULES = {name: Rules(ehatp.load(EXAMPLES_DIR / f"{name}.toml"))
         for name in ("cubes/p2", "sally-anne/inform", "cooking/cooking1")}


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.sampled_from(sorted(RULES)), st.data())
def test_assessment_is_learning_each_unit_seen_in_turn(name: str, data: st.DataObject) -> None:
    rules = RULES[name]
    g = rules.grounded
    n = len(g.atoms)
    state = st.integers(0, (1 << n) - 1)
    t = data.draw(state)
    agenda = g.robot_agenda
    worlds = frozenset((data.draw(state), agenda)
                       for _ in range(data.draw(st.integers(1, 4))))
    if data.draw(st.booleans()):  # often, a world that agrees on everything seen
        worlds |= {(t ^ (data.draw(state) & ~g.visible_mask(t)), agenda)}
    want = rules.observe(worlds, t, _bits(g.visible_mask(t)))
    assert rules.sa(worlds, t) == want


def test_with_no_world_agreeing_assessment_revises_what_is_seen() -> None:
    """Derived by hand: in P2 the human sees the robot's table while together; a single world
    that disagrees with the truth on one atom seen takes the truth's value of it."""
    rules = RULES["cubes/p2"]
    g = rules.grounded
    t = g.init
    seen = g.visible_mask(t)
    i = _bits(seen)[0]
    wrong = t ^ (1 << i)
    assert rules.sa(frozenset({(wrong, g.robot_agenda)}), t) == frozenset({(t, g.robot_agenda)})
