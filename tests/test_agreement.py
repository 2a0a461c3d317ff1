"""Planner and validator agree on a few hundred random problems (the code path of
``benchmarks/agreement.py``), and the random generator draws what it promises."""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import replace

import pytest

from ehatp.tools import randomgen

SEEDS = range(1000)
# Where benchmarks/agreement.py found planner and validator disagreeing (the first seed of each
# kind in 40,000, with this version of the generator): checked on every run until fixed.
FOUND = (2189, 2593, 10015, 14732, 31044, 38051)


def test_planner_and_validator_agree_on_random_problems() -> None:
    seeds = [*SEEDS, *FOUND]
    outcomes = randomgen.run(seeds, jobs=min(2, os.cpu_count() or 1))
    assert [o.seed for o in outcomes] == sorted(seeds)
    bad = [f"seed {o.seed}: {o.kind} (planner: {o.status or '-'}) {{{', '.join(o.options)}}}: "
           f"{o.detail}" for o in outcomes if o.failed]
    assert not bad, "\n".join(bad)
    counts = randomgen.summary(outcomes)
    # a generator whose problems all fail to solve would prove nothing
    assert counts["solved"] >= len(seeds) // 3, counts
    assert sum(o.checked_determinism for o in outcomes) >= len(seeds) // 20


def test_a_seed_is_the_same_problem_every_time() -> None:
    assert randomgen.draw(7) == randomgen.draw(7)
    assert randomgen.draw(7) != randomgen.draw(8)
    a, b = randomgen.problem(7), randomgen.problem(7)
    assert (a.init, a.beliefs, a.costs, a.K) == (b.init, b.beliefs, b.costs, b.K)


def test_a_new_setting_changes_no_other_draw(monkeypatch: pytest.MonkeyPatch) -> None:
    before = randomgen.draw(11)
    monkeypatch.setitem(randomgen.SETTINGS, "options.some_new_option", lambda r: r.random())
    after = randomgen.draw(11)
    new = dict(after.settings).pop("options.some_new_option")
    assert after.settings == tuple(sorted((*before.settings, ("options.some_new_option", new))))
    assert replace(after, settings=before.settings) == before


def test_the_generator_draws_every_feature() -> None:
    """Over the seeds of the agreement test, every kind of draw the module promises occurs."""
    seen: Counter[str] = Counter()
    for seed in SEEDS:
        s = randomgen.draw(seed)
        seen.update(f"obs:{k}" for _, k in s.atoms)
        seen.update(f"mutation:{m}" for m in s.mutations)
        seen[f"rh:{'same' if s.robot_seen is None else 'copy' if not s.mutations else 'diff'}"] += 1
        seen[f"K:{s.setting('problem.K')}"] += 1
        seen[f"starts:{s.setting('problem.starts')}"] += 1
        seen[f"inform:{s.setting('costs.inform')}"] += 1
        seen["door"] += s.door is not None
        seen["items"] += s.items
        seen["goal"] += bool(s.goal)
        seen["action costs"] += bool(s.action_costs)
        seen["starts away"] += "home" not in s.init
        seen["false belief"] += len(s.worlds) == 1 and bool(s.worlds[0].flips)
        seen["uncertainty"] += len(s.worlds) > 1
        seen["world agenda"] += any(w.robot_agenda is not None for w in s.worlds)
        seen["trip"] += any("leave" in m.subtasks or "back" in m.subtasks
                            for m in s.human.methods)
        seen["conditional effect"] += any(o.cond for o in s.robot.ops + s.human.ops)
        seen["op done"] += any(o.done for o in s.robot.ops + s.human.ops)
        seen["task done"] += any(t.done for t in s.robot.tasks + s.human.tasks)
        seen["method pre"] += any(m.pre for m in s.robot.methods + s.human.methods)
        seen["free method"] += any(m.free for m in s.robot.methods)
    kinds = [k for k, _ in randomgen.OBS_KINDS] + [k for k, _ in randomgen.MARK_KINDS]
    want = ([f"obs:{k}" for k in kinds] + [f"K:{k}" for k in range(5)]
            + [f"mutation:{m}" for m, _ in randomgen.MUTATIONS]
            + ["rh:same", "rh:copy", "rh:diff", "starts:human", "starts:robot", "inform:1",
               "inform:5", "door", "items", "goal", "action costs", "starts away",
               "false belief", "uncertainty", "world agenda", "trip", "conditional effect",
               "op done", "task done", "method pre", "free method"])
    missing = [w for w in want if seen[w] == 0]
    assert not missing, (missing, seen)


def test_every_setting_varies_and_some_problems_keep_every_default() -> None:
    values: dict[str, set[str]] = {k: set() for k in randomgen.SETTINGS}
    plain = 0
    for seed in SEEDS:
        s = randomgen.draw(seed)
        for k, v in s.settings:
            values[k].add(repr(v))
        plain += not s.options()
    assert all(len(v) >= 2 for v in values.values()), values
    assert len(SEEDS) // 4 <= plain <= 3 * len(SEEDS) // 4
