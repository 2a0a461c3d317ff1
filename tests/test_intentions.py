"""Hidden human intentions and the revised rules of docs/semantics.md §3-§6, on small
problems whose answers were derived by hand from the spec before the planner ran (the
derivations are in the docstrings)."""

from __future__ import annotations

from dataclasses import replace

import ehatp
from ehatp import HIDDEN, Communication, Costs, Domain, HumanModel, Var
from ehatp.model.options import Intentions, Passes, Speech

from .scenarios import problem


def shelves() -> Domain:
    """The shelf example (docs/semantics.md §3): the human grabs an item meaning to put it on
    the left or on the right shelf (two methods that start with the same ``grab``); the robot
    must clear the shelf the human means, which it can only do once the item is held."""
    d = Domain("shelves")
    Side = d.type("side")
    x = Var("x", Side)
    holding = d.predicate("holding")
    clear = d.predicate("clear", x)
    placed = d.predicate("placed")
    # co-presence is TRUE by default: they work side by side
    h = d.human
    grab = h.action("grab", pre=~holding(), effects=[holding()])
    place = h.action("place", x, pre=holding() & clear(x), effects=[placed(), ~holding()])
    stock = h.task("stock")
    h.method(stock, "left", subtasks=[grab(), place("l")])
    h.method(stock, "right", subtasks=[grab(), place("r")])
    r = d.robot
    clr = r.action("clr", x, pre=holding() & ~clear(x), effects=[clear(x)])
    helps = r.task("help")
    r.method(helps, "l", subtasks=[clr("l")])
    r.method(helps, "r", subtasks=[clr("r")])
    return d


def shelf_problem(**kw: object) -> ehatp.Problem:
    return problem(shelves(), init=[], robot=["help"], human=["stock"],
                   objects={"side": ["l", "r"]}, **kw)  # type: ignore[arg-type]


def runs(p: ehatp.Problem, result: ehatp.Result) -> None:
    """Whatever solves also runs: the policy validates and is walked through the Executor on
    every branch to the goal."""
    from ehatp.run.walk import walk_policy

    assert result.policy is not None
    assert ehatp.validate(p, result.policy).ok
    walked = walk_policy(p, result.policy)
    assert walked.ok and not walked.capped, walked.message


def test_the_robot_cannot_follow_a_human_method_it_cannot_see_so_the_shelf_has_no_policy() -> None:
    """By hand (§3-§4, hidden intentions): after ``grab`` the robot's node holds both
    hypotheses {place(l)}, {place(r)}; clearing one shelf leaves the other hypothesis blocked
    (it passes, the robot has nothing left, it passes again: three passive moves), waiting
    gains nothing; so no policy exists, and the reason names the hidden choice."""
    p = shelf_problem()
    r = ehatp.solve(p)
    assert r.status == "unsolvable" and r.policy is None
    assert "cannot see" in r.reason and "grab" in r.reason
    assert "place(l)" in r.reason and "place(r)" in r.reason


def test_visible_intentions_solve_the_shelf_at_worst_case_seven() -> None:
    """By hand (§4, ``intentions = "visible"``): root options ``grab [place(l)]``,
    ``grab [place(r)]`` and ``pass``. The worst branch: pass (1), the robot's forced wait (1)
    -- its methods need the item held --, grab (1), clr (1), the human's pass (1), the robot's
    forced wait (1), place (1): 7."""
    p = shelf_problem(human_model=HumanModel(intentions=Intentions.VISIBLE))
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert r.policy.worst_case == 7
    labels = {m.action for m in r.policy.root.moves}
    assert labels == {"grab [place(l)]", "grab [place(r)]", "pass"}
    runs(p, r)


def test_a_robot_that_may_ask_what_the_human_means_solves_the_shelf_at_nine() -> None:
    """By hand (§5, ``robot_asks``): pass (1), forced wait (1), grab (1), ask(intention) (1),
    the answer (0), the human still blocked passes (1), clr (1), pass (1), forced wait (1),
    place (1): 9. The robot's reply depends only on the answer it heard."""
    p = shelf_problem(communication=Communication(robot_asks=True))
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert r.policy.worst_case == 9
    pol = r.policy
    asked = [n for n in pol.nodes for m in n.moves if m.action == "ask(intention)"]
    assert asked and all(len(n.human_agendas) == 2 for n in asked)
    answers = sorted(m.action for n in pol.nodes for m in n.moves if m.kind == "answer")
    assert set(answers) == {"answer(place(l))", "answer(place(r))"}
    runs(p, r)


def test_one_branch_per_observed_label_keeps_every_fitting_hypothesis() -> None:
    """§4: the root's ``grab`` is one AND branch whose child holds both agendas."""
    from .scenarios import walk

    sem, es = walk(shelf_problem(), "grab")
    assert len(es.human_agendas) == 2
    assert sorted(sem.net.names_of(h)[0] for h in es.human_agendas) == ["place(l)", "place(r)"]


def vacuum() -> Domain:
    """The hidden chore: the robot vacuums (hidden) only while the human is out."""
    d = Domain("vacuum")
    Place = d.type("place")
    p, q = Var("p", Place), Var("q", Place)
    at = d.predicate("at", p)
    vacuumed = d.predicate("vacuumed", observability=HIDDEN)
    d.copresence = at("home")
    d.robot.action("vacuum", pre=at("out") & ~vacuumed(), effects=[vacuumed()])
    d.human.action("go", p, q, pre=at(p) & ~at(q), effects=[at(q), ~at(p)])
    return d


def vacuum_problem(**kw: object) -> ehatp.Problem:
    return problem(vacuum(), init=["at(home)"], robot=["vacuum"],
                   human=["go(home, out)", "go(out, home)"],
                   objects={"place": ["home", "out"]}, **kw)  # type: ignore[arg-type]


def test_a_hidden_finished_chore_is_told_when_the_other_world_blocks_the_robot() -> None:
    """By hand (§5, expectations per world): back home, the truth says the robot is done
    ({FINISH}); in the world where it did not vacuum its agenda is blocked (the human is home),
    which contributes "not done", so the divergence is relevant and ``inform(vacuumed)``
    is offered. Worst branch: pass (1), forced wait (1), go out (1), vacuum (1), go home (1),
    inform (1): 6, one communication on each branch."""
    p = vacuum_problem()
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None
    assert r.policy.worst_case == 6
    assert any(m.action == "inform(vacuumed)" for _, m in r.policy.edges())
    runs(p, r)


def test_the_robot_may_announce_that_it_has_nothing_left_to_do() -> None:
    """§5 ``announce``: at the same node the robot may say its (empty) agenda; the worlds
    keep the one whose attributed agenda is empty."""
    from .scenarios import walk

    p = vacuum_problem(communication=Communication(announce=True))
    sem, es = walk(p, "go(home, out)", "vacuum", "go(out, home)")
    said = [m for m in sem.moves(es) if m.kind == "announce"]
    assert [m.label for m in said] == ["announce()"]
    child = said[0].child
    assert child is not None and [ag for _, ag in child.worlds] == [()]
    r = ehatp.solve(p)
    assert r.status == "solved" and r.policy is not None and r.policy.worst_case == 6
    runs(p, r)


def car() -> Domain:
    """Refill then oil: the human drives once the washer is full, by the method its belief
    about the oil (hidden) selects; buying oil when the oil is fine is acting on a false
    belief."""
    d = Domain("car")
    full = d.predicate("washer_full")  # observable, always (and they are together)
    oil = d.predicate("oil_ok", observability=HIDDEN)
    driven = d.predicate("driven")
    d.robot.action("refill", pre=~full(), effects=[full()])
    h = d.human
    use = h.action("use_car", pre=full() & oil(), effects=[driven()])
    buy = h.action("buy_oil", pre=full() & ~oil(), effects=[oil()])
    drive = h.task("drive")
    h.method(drive, "ok", pre=full() & oil(), subtasks=[use()])
    h.method(drive, "low", pre=full() & ~oil(), subtasks=[buy(), use()])
    return d


def car_problem(**kw: object) -> ehatp.Problem:
    return problem(car(), init=["oil_ok"], robot=["refill"], human=["drive"], objects={},
                   starts="robot", beliefs=[([], ["oil_ok"])], **kw)  # type: ignore[arg-type]


def test_speech_with_an_action_says_in_time_what_the_action_makes_relevant() -> None:
    """By hand (§5, speech judged after its action): before the refill neither view of the
    human has an option, so the false belief about the oil is irrelevant; right after it the
    human would buy oil (a false belief) on its very next step. Said with the refill, on the
    state it leads to: ``inform(oil_ok) + refill`` (2), then pass (1), forced wait (1),
    use_car (1): 5. By default (speech takes a turn) there is no policy."""
    assert ehatp.solve(car_problem()).status == "unsolvable"
    for where in ("copresent", "anywhere"):
        comm = replace(Communication(speech=Speech.WITH_ACTION), inform=where)  # type: ignore[arg-type]
        p = car_problem(communication=comm)
        r = ehatp.solve(p)
        assert r.status == "solved" and r.policy is not None, r.reason
        first = r.policy.root.moves[0]
        assert first.action == "inform(oil_ok) + refill" and first.told == ["oil_ok"]
        assert r.policy.worst_case == 5
        runs(p, r)


def test_an_idle_human_passes_only_when_it_has_nothing_it_could_do() -> None:
    """§4 ``passes = "idle"``: at the shelf's root the human has ``grab``, so no ``pass``."""
    from .scenarios import labels, walk

    p = shelf_problem(human_model=HumanModel(passes=Passes.IDLE))
    sem, es = walk(p)
    assert labels(sem, es) == ["grab"]
    assert "pass" in labels(sem, walk(p, "grab")[1]._replace(turn=1))


def test_a_costlier_inform_does_not_change_the_hidden_chore_answer_shape() -> None:
    """The vacuum case with informing at cost 2: the worst case is 7 (6 with the inform's
    extra unit)."""
    p = vacuum_problem(costs=Costs(inform=2))
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.worst_case == 7
    runs(p, r)
