"""Property tests on small random domains: the planner never crashes, every policy it returns
passes the independent validator, the result does not depend on declaration order, and solving
twice gives byte-identical JSON."""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ehatp
from ehatp import HIDDEN, INFERABLE, Costs, Domain, Var, observable
from ehatp.model.formula import TRUE, Formula, conj

from .scenarios import problem

ATOMS = ["a0", "a1", "a2", "a3"]
ITEMS = ["x", "y"]
Lit = tuple[str, bool]


@dataclass(frozen=True)
class OpSpec:
    name: str
    pre: tuple[Lit, ...]
    eff: tuple[Lit, ...]
    cost: int


@dataclass(frozen=True)
class Spec:
    obs: tuple[str, ...]  # per atom: always | together | inferable | hidden
    robot_ops: tuple[OpSpec, ...]
    human_ops: tuple[OpSpec, ...]
    robot_methods: tuple[tuple[tuple[Lit, ...], tuple[str, ...]], ...]
    human_methods: tuple[tuple[tuple[Lit, ...], tuple[str, ...]], ...]
    init: tuple[str, ...]
    beliefs: tuple[tuple[str, ...], ...]  # per world, the atoms flipped
    K: int
    starts: str
    inform: int


lits = st.tuples(st.sampled_from(ATOMS), st.booleans())


def ops(prefix: str, max_pre: int) -> st.SearchStrategy[tuple[OpSpec, ...]]:
    one = st.builds(lambda i, pre, eff, c: OpSpec(f"{prefix}{i}", tuple(pre), tuple(eff), c),
                    st.just(0), st.lists(lits, max_size=max_pre, unique_by=lambda x: x[0]),
                    st.lists(lits, min_size=1, max_size=2, unique_by=lambda x: x[0]),
                    st.integers(1, 2))
    return st.lists(one, min_size=1, max_size=3).map(
        lambda xs: tuple(OpSpec(f"{prefix}{i}", o.pre, o.eff, o.cost) for i, o in enumerate(xs)))


@st.composite
def specs(draw: st.DrawFn) -> Spec:
    robot_ops = draw(ops("r", 1))
    human_ops = draw(ops("h", 2))
    r_names = [o.name for o in robot_ops] + ["mark(x)", "mark(y)"]
    h_names = [o.name for o in human_ops] + ["leave", "back", "look(x)"]

    def methods(names: list[str], trips: bool) -> st.SearchStrategy[tuple]:  # type: ignore[type-arg]
        body = st.lists(st.sampled_from(names), min_size=1, max_size=3).map(tuple)
        if trips:  # the human goes away, does something, comes back and finishes
            away = st.lists(st.sampled_from(names), max_size=2).map(tuple)
            body = st.one_of(body, st.tuples(away, body).map(
                lambda ab: ("leave", *ab[0], "back", *ab[1])))
        m = st.tuples(st.lists(lits, max_size=1).map(tuple), body)
        return st.lists(m, min_size=1, max_size=2).map(tuple)

    n_worlds = draw(st.integers(1, 2))
    return Spec(
        obs=tuple(draw(st.lists(st.sampled_from(["always", "together", "inferable", "hidden"]),
                                min_size=len(ATOMS), max_size=len(ATOMS)))),
        robot_ops=robot_ops, human_ops=human_ops,
        robot_methods=draw(methods(r_names, False)),
        human_methods=draw(methods([n for n in h_names if n not in ("leave", "back")], True)),
        init=tuple(draw(st.lists(st.sampled_from(ATOMS), unique=True))),
        beliefs=tuple(tuple(draw(st.lists(st.sampled_from(ATOMS), unique=True, max_size=1)))
                      for _ in range(n_worlds)),
        K=draw(st.integers(0, 2)), starts=draw(st.sampled_from(["human", "robot"])),
        inform=draw(st.integers(1, 3)),
    )


def build(spec: Spec, *, reverse: bool = False) -> ehatp.Problem:
    """The same problem, with declarations in the given or the reverse order."""
    order = (lambda xs: list(reversed(list(xs)))) if reverse else list
    d = Domain("random")
    Item = d.type("item")
    i = Var("i", Item)
    together = d.predicate("together")
    d.copresence = together()
    kinds = {"always": observable(), "together": observable(together()),
             "inferable": INFERABLE, "hidden": HIDDEN}
    preds = {}
    for name, kind in order(zip(ATOMS, spec.obs, strict=True)):
        preds[name] = d.predicate(name, observability=kinds[kind])
    marked = d.predicate("marked", i, observability=observable(together()))
    seen = d.predicate("seen", i)

    def formula(ls: tuple[Lit, ...]) -> Formula:
        return conj(*(preds[a]() if v else ~preds[a]() for a, v in ls)) if ls else TRUE

    def effects(ls: tuple[Lit, ...]) -> list:  # type: ignore[type-arg]
        return [preds[a]() if v else ~preds[a]() for a, v in ls]

    for model, op_specs in ((d.robot, spec.robot_ops), (d.human, spec.human_ops)):
        for o in order(op_specs):
            model.action(o.name, pre=formula(o.pre), effects=effects(o.eff), cost=o.cost)
    d.robot.action("mark", i, pre=~marked(i), effects=[marked(i)])
    d.human.action("leave", pre=together(), effects=[~together()])
    d.human.action("back", pre=~together(), effects=[together()])
    d.human.action("look", i, pre=marked(i), effects=[seen(i)])

    for model, ms in ((d.robot, spec.robot_methods), (d.human, spec.human_methods)):
        task = model.task("job")
        for k, (pre, subs) in order(list(enumerate(ms))):
            refs = []
            for s in subs:
                if s.endswith(")"):
                    name, arg = s[:-1].split("(")
                    refs.append(model.operators[name](arg))
                else:
                    refs.append(model.operators[s]())
            model.method(task, f"m{k}", pre=formula(pre), subtasks=refs)
    init = [*spec.init, "together"]
    beliefs = [([a for a in flips if a not in init], [a for a in flips if a in init])
               for flips in spec.beliefs]
    return problem(d, init=init, robot=["job"], human=["job"], K=spec.K, starts=spec.starts,
                   objects={"item": order(ITEMS)}, beliefs=beliefs,
                   costs=Costs(inform=spec.inform))


SETTINGS = settings(max_examples=200, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(specs())
def test_policies_pass_the_validator_and_do_not_depend_on_declaration_order(spec: Spec) -> None:
    p = build(spec)
    r = ehatp.solve(p, max_states=20_000, timeout=10)
    assert r.status in ("solved", "unsolvable"), r.reason
    if r.status == "unsolvable":
        assert r.reason.startswith("no policy exists")
        return
    assert r.policy is not None
    report = ehatp.validate(p, r.policy)
    assert report.ok, report.message
    again = ehatp.solve(build(spec, reverse=True), max_states=20_000, timeout=10)
    assert again.policy is not None
    assert again.policy.to_json() == r.policy.to_json()
    assert ehatp.solve(p).policy.to_json() == r.policy.to_json()  # type: ignore[union-attr]
