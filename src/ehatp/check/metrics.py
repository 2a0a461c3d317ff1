"""Metrics a domain declares (docs/concurrent.md C11, "Metrics a domain declares") as the
validator reads them: from the declaration itself (the agent, the operators, the condition as
a formula over an operator's parameters) and from the policy's moves and recorded states.

Written again from the document: the condition is evaluated here, by walking its formula over
the node's recorded true atoms and the problem's initial facts (for what no action changes),
not by the test the planner compiled when it grounded the action.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ..model.domain import DomainMetric
from ..model.formula import And, Atom, Cmp, Eq, Exists, Forall, Formula, Is, Not, Or, Term, Var
from ..model.grounded import Grounded
from ..model.problem import Problem, call_str


class MetricReader:
    """C11: whether a step's action counts towards a metric of the problem's domain.

    An atom the validator's ground problem keeps as a fluent (a bit of its states) is read in
    the recorded state of the node (the policy's ``state``, which the replay checked against
    its own); any other atom never changes, so it is read in the problem's initial facts."""

    def __init__(self, problem: Problem, grounded: Grounded) -> None:
        self.problem = problem
        self.domain = problem.domain
        self.objects = problem.all_objects()
        self.init = frozenset(problem.init)
        self.fluent = frozenset(grounded.atom_index)
        self.counters = frozenset(grounded.unit_names[u] for u in grounded.counter_units)

    def counts(self, metric: DomainMetric, who: str, action: str, args: Sequence[str],
               state: frozenset[str]) -> bool:
        """Whether ``who``'s (``"robot"`` or ``"human"``) action ``action(args)``, done in a
        step that starts in ``state`` (the true atoms a policy node records), is one
        ``metric`` counts: ``who`` is among its agents, ``action`` among its operators, and
        its condition holds with the operator's parameters bound to ``args``."""
        if who not in metric.agents() or action not in metric.actions:
            return False
        model = self.domain.robot if who == "robot" else self.domain.human
        op = model.operators.get(action)
        if op is None or len(op.params) != len(args):
            return False
        return self.holds(metric.when, dict(zip(op.params, args, strict=True)), state)

    def holds(self, f: Formula, b: Mapping[Var, str], state: frozenset[str]) -> bool:
        """Whether ``f``, its variables bound by ``b``, holds in ``state``."""
        if isinstance(f, Is):  # a state variable's value: "loc(r, mt)", recorded "loc(r) = mt"
            args = self._terms(f.args, b)
            if call_str(f.pred, args) in self.fluent:
                return f"{call_str(f.pred, args[:-1])} = {args[-1]}" in state
            return (f.pred, args) in self.init
        if isinstance(f, Atom):
            args = self._terms(f.args, b)
            derived = self.domain.derived_predicates.get(f.pred)
            if derived is not None:
                return self.holds(derived.body, dict(zip(derived.params, args, strict=True)),
                                  state)
            if f.pred in self.domain.counters:  # the value view: balls(b1, 2)
                return self._counter(f.pred, args[:-1], state) == int(args[-1])
            name = call_str(f.pred, args)
            return name in state if name in self.fluent else (f.pred, args) in self.init
        if isinstance(f, Cmp):
            return f.holds(self._counter(f.counter, self._terms(f.args, b), state))
        if isinstance(f, Eq):
            return self._terms((f.left,), b) == self._terms((f.right,), b)
        if isinstance(f, Not):
            return not self.holds(f.arg, b, state)
        if isinstance(f, And):
            return all(self.holds(a, b, state) for a in f.args)
        if isinstance(f, Or):
            return any(self.holds(a, b, state) for a in f.args)
        if isinstance(f, Exists | Forall):
            found = (self.holds(f.body, {**b, **binding}, state)
                     for binding in self._bindings(f.vars))
            return any(found) if isinstance(f, Exists) else all(found)
        raise TypeError(f"not a formula of the domain: {f!r}")

    def _bindings(self, vs: Sequence[Var]) -> list[dict[Var, str]]:
        out: list[dict[Var, str]] = [{}]
        for v in vs:
            out = [{**x, v: o} for x in out for o in self.objects.get(v.type, [])]
        return out

    @staticmethod
    def _terms(ts: Sequence[Term], b: Mapping[Var, str]) -> tuple[str, ...]:
        return tuple(b[t] if isinstance(t, Var) else t for t in ts)

    def _counter(self, name: str, args: tuple[str, ...], state: frozenset[str]) -> int:
        """A counter's value: recorded in the state (``balls(b1) = 2``) when it changes,
        else its initial value (0 unless the problem gives one)."""
        head = call_str(name, args)
        if head in self.counters:
            for x in state:
                if x.startswith(head + " = "):
                    return int(x[len(head) + 3:])
            return 0
        for n, a in self.init:
            if n == name and a[:-1] == args:
                return int(a[-1])
        return 0


__all__ = ["MetricReader"]
