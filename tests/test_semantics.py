"""One test (or a few) per rule of docs/semantics.md, on hand-built scenarios."""

from __future__ import annotations

from fractions import Fraction

import ehatp
from ehatp import Costs, HumanModel, Passes
from ehatp.epistemic.semantics import INFORM

from .scenarios import lab_domain, labels, problem, walk, world_atoms

HOME = ["human_at(lab)"]


# -- co-presence ------------------------------------------------------------------------------

def test_robot_action_in_front_of_the_human_is_witnessed() -> None:
    p = problem(lab_domain(), init=HOME, robot=["set_secret(a)"], starts="robot")
    sem, es = walk(p, "set_secret(a)")
    assert world_atoms(sem, es) == [{"human_at(lab)", "secret(a)"}]


def test_unseen_robot_action_leaves_the_human_unsure() -> None:
    p = problem(lab_domain(), init=HOME, robot=["set_secret(a)"], human=["trip(s1)"])
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)")
    assert sorted(map(sorted, world_atoms(sem, es))) == [
        ["human_at(hall)"], ["human_at(hall)", "secret(a)"]]
    assert es.k == 1


def test_unanticipated_witnessed_action_is_revised_into_belief() -> None:
    p = problem(lab_domain(human_expects_robot=False), init=HOME, robot=["set_secret(a)"],
                starts="robot")
    sem, es = walk(p, "set_secret(a)")
    assert world_atoms(sem, es) == [{"human_at(lab)", "secret(a)"}]
    assert es.worlds[0][1] == es.robot_agenda  # the human now attributes the real agenda


def test_a_task_the_humans_model_of_the_robot_lacks_is_not_attributed() -> None:
    """§4: the human holds only the tasks M_R^H has an operator, a method or a done-condition
    for: ``set_secret`` is no action of its model (dropped), ``light`` has a done-condition
    (kept), also in the initial worlds; the validator reads it alike."""
    p = problem(lab_domain(human_expects_robot=False), init=HOME,
                robot=["set_secret(a)", "light"], starts="robot")
    sem, es = walk(p)
    assert [sem.g.task_names[t] for _, ag in es.worlds for t in ag] == ["light"]
    r = ehatp.solve(p)
    assert r.policy is not None and ehatp.validate(p, r.policy).ok


# -- K ----------------------------------------------------------------------------------------

def test_worlds_grow_with_each_unseen_robot_turn_up_to_K_and_not_beyond() -> None:
    p = problem(lab_domain(), init=HOME, K=2, human=["long_trip"],
                robot=["set_secret(a)", "set_secret(b)", "set_secret(s1)"])
    sem, es = walk(p, "go(lab, hall)")
    assert len(es.worlds) == 1
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)")
    assert len(es.worlds) == 2  # nothing done / a done
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "set_secret(b)")
    assert len(es.worlds) == 3 and es.k == 2  # + a and b done
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "set_secret(b)",
                   "stroll(s2)")
    assert labels(sem, es) == ["wait"]  # K used: the robot can only wait
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "set_secret(b)",
                   "stroll(s2)", "wait")
    assert len(es.worlds) == 3 and es.k == 2


def test_an_unseen_wait_is_an_event_the_human_imagines() -> None:
    p = problem(lab_domain(), init=HOME, K=2, human=["trip(s1)"], robot=["set_secret(a)"])
    sem, es = walk(p, "go(lab, hall)", "wait")
    assert len(es.worlds) == 2 and es.k == 1


def test_k_counter_resets_when_together_again() -> None:
    p = problem(lab_domain(), init=HOME, K=2, human=["trip(s1)"], robot=["set_secret(a)"])
    sem, es = walk(p, "go(lab, hall)", "wait", "stroll(s1)", "wait", "go(hall, lab)")
    assert es.k == 0


# -- situation assessment ---------------------------------------------------------------------

def test_observable_atom_eliminates_worlds_when_back() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_lamp(a)"])
    sem, es = walk(p, "go(lab, hall)", "set_lamp(a)", "stroll(s1)")
    assert len(es.worlds) == 2  # lamps are not visible from the hall
    sem, es = walk(p, "go(lab, hall)", "set_lamp(a)", "stroll(s1)", "wait", "go(hall, lab)")
    assert world_atoms(sem, es) == [{"human_at(lab)", "lamp(a)", "strolled(s1)"}]


def test_hidden_atom_stays_uncertain_when_back() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_secret(a)"])
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "wait", "go(hall, lab)")
    assert len(es.worlds) == 2


def test_inferable_atom_is_learned_only_by_witnessing() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_note(a)"])
    sem, es = walk(p, "go(lab, hall)", "set_note(a)", "stroll(s1)", "wait", "go(hall, lab)")
    assert len(es.worlds) == 2  # written unseen: still unsure afterwards
    p = problem(lab_domain(human_expects_robot=False), init=HOME, robot=["set_note(a)"],
                starts="robot", beliefs=[([], [])])
    sem, es = walk(p, "set_note(a)")
    assert world_atoms(sem, es) == [{"human_at(lab)", "note(a)"}]


def test_situation_assessment_revises_a_false_belief_no_world_agrees_with() -> None:
    # the human wrongly believes lamp(a) is on; at the lab it sees it is off
    p = problem(lab_domain(), init=["human_at(hall)"], human=["trip(s1)"],
                beliefs=[(["lamp(a)"], [])])
    sem, es = walk(p)
    assert world_atoms(sem, es) == [{"human_at(hall)", "lamp(a)"}]  # not visible from the hall
    p = problem(lab_domain(), init=HOME, beliefs=[(["lamp(a)"], [])])
    sem, es = walk(p)
    assert world_atoms(sem, es) == [{"human_at(lab)"}]


def test_situation_assessment_keeps_only_agreeing_worlds() -> None:
    p = problem(lab_domain(), init=HOME, beliefs=[(["lamp(a)"], []), ([], []),
                                                 (["lamp(a)", "secret(b)"], [])])
    sem, es = walk(p)
    assert world_atoms(sem, es) == [{"human_at(lab)"}]


# -- the human's options ----------------------------------------------------------------------

def test_human_acts_only_on_actions_applicable_in_every_world() -> None:
    p = problem(lab_domain(), init=HOME, human=["use_it(a)"],
                beliefs=[([], []), (["secret(a)"], [])])
    sem, es = walk(p)
    assert labels(sem, es) == ["ask(secret(a))", "pass"]


def test_human_acting_on_a_false_belief_fails() -> None:
    p = problem(lab_domain(), init=HOME, human=["use_it(a)"], beliefs=[(["secret(a)"], [])])
    sem, es = walk(p)
    use = next(m for m in sem.moves(es) if m.label == "use(a)")
    assert use.child is None and "false belief" in use.failure and "secret(a)" in use.failure
    r = ehatp.solve(p)
    assert r.status == "unsolvable" and "use(a)" in r.reason and "false belief" in r.reason


def test_robot_moving_first_can_make_the_belief_true() -> None:
    p = problem(lab_domain(), init=HOME, human=["use_it(a)"], robot=["set_secret(a)"],
                beliefs=[(["secret(a)"], [])], starts="robot")
    r = ehatp.solve(p)
    assert r.policy is not None
    assert r.policy.root.moves[0].action == "set_secret(a)"


def test_pass_after_a_forced_robot_wait_is_not_covered_when_the_human_can_act() -> None:
    # the robot has nothing to do: its wait is forced, and the human does not idle (§4)
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], starts="robot")
    sem, es = walk(p, "wait")
    assert es.forced and labels(sem, es) == ["go(lab, hall)"]
    sem, es = walk(p)
    assert "wait" in labels(sem, es)


def test_a_voluntary_robot_wait_takes_nothing_from_the_human() -> None:
    # the robot could light a lamp; if it waits instead, the human may still pass (fair), so
    # idling never gains the robot anything; the prototype rule takes the pass away
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_lamp(a)"],
                starts="robot")
    sem, es = walk(p, "wait")
    assert not es.forced and labels(sem, es) == ["go(lab, hall)", "pass"]
    proto = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_lamp(a)"],
                    starts="robot", human_model=HumanModel(passes=Passes.PROTOTYPE))
    sem, es = walk(proto, "wait")
    assert es.forced and labels(sem, es) == ["go(lab, hall)"]


def test_blocked_human_may_pass_after_a_wait_unless_told_to_ask() -> None:
    base = dict(init=HOME, human=["use_it(a)"], beliefs=[([], []), (["secret(a)"], [])],
                starts="robot")
    sem, es = walk(problem(lab_domain(), **base), "wait")  # type: ignore[arg-type]
    assert labels(sem, es) == ["ask(secret(a))", "pass"]
    sem, es = walk(problem(lab_domain(), human_model=HumanModel(passes_when_blocked=False),
                           **base), "wait")  # type: ignore[arg-type]
    assert labels(sem, es) == ["ask(secret(a))"]


def test_human_away_passes_only_with_nothing_else_to_do() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"])
    sem, es = walk(p, "go(lab, hall)", "wait")
    assert labels(sem, es) == ["stroll(s1)"]


# -- communication ----------------------------------------------------------------------------

def test_ask_filters_the_worlds_on_the_truth() -> None:
    p = problem(lab_domain(), init=[*HOME, "secret(a)"], human=["use_it(a)"],
                beliefs=[([], ["secret(a)"]), ([], [])])
    sem, es = walk(p, "ask(secret(a))")
    assert world_atoms(sem, es) == [{"human_at(lab)", "secret(a)"}]


def test_inform_tells_a_smallest_relevant_set_only() -> None:
    # the worlds differ on secret(a) (which the human needs) and secret(b) (which it does not)
    p = problem(lab_domain(), init=[*HOME, "secret(a)", "secret(b)"], human=["use_it(a)"],
                beliefs=[([], []), ([], ["secret(a)", "secret(b)"])], starts="robot")
    sem, es = walk(p)
    assert len(es.worlds) == 2
    informs = [m for m in sem.moves(es) if m.kind == INFORM]
    assert [m.label for m in informs] == ["inform(secret(a))"]
    assert world_atoms(sem, informs[0].child)[0] >= {"secret(a)"}


def test_no_inform_of_what_the_human_already_believes_or_of_irrelevant_divergence() -> None:
    # the human is wrong about secret(b), which none of its options depend on
    p = problem(lab_domain(), init=[*HOME, "secret(a)", "secret(b)"], human=["use_it(a)"],
                beliefs=[([], ["secret(b)"])], starts="robot")
    sem, es = walk(p)
    assert [m for m in sem.moves(es) if m.kind == INFORM] == []
    p = problem(lab_domain(), init=[*HOME, "secret(a)"], human=["use_it(a)"], starts="robot")
    sem, es = walk(p)
    assert [m for m in sem.moves(es) if m.kind == INFORM] == []


def test_inform_only_when_together() -> None:
    p = problem(lab_domain(), init=["human_at(hall)", "secret(a)"], human=["use_it(a)"],
                beliefs=[([], ["secret(a)"])], starts="robot")
    sem, es = walk(p)
    assert labels(sem, es) == ["wait"]


# -- goal and dead ends -----------------------------------------------------------------------

def test_goal_requires_the_human_to_believe_the_robot_is_done() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_secret(a)"])
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "wait", "go(hall, lab)")
    assert sem.robot_done(es) and sem.human_done(es)
    assert not sem.human_believes_robot_done(es) and not sem.is_goal(es)
    sem, es = walk(p, "go(lab, hall)", "set_secret(a)", "stroll(s1)", "wait", "go(hall, lab)",
                   "inform(secret(a))")
    assert sem.is_goal(es)


def test_inactivity_deadlock_makes_a_problem_unsolvable() -> None:
    # the human needs secret(b), which nobody can set
    p = problem(lab_domain(), init=HOME, human=["use_it(b)"], starts="robot")
    r = ehatp.solve(p)
    assert r.status == "unsolvable" and r.policy is None
    assert "inactivity deadlock" in r.reason


def test_cycles_never_count_as_solved() -> None:
    # wait/pass loops exist, but only three passive moves in a row are allowed and the node
    # key includes the count: the search terminates and finds nothing
    p = problem(lab_domain(), init=HOME, human=[], robot=["set_secret(b)"],
                goal=["used(a)"], starts="human")
    r = ehatp.solve(p)
    assert r.status == "unsolvable"


# -- costs and tie-breaks ---------------------------------------------------------------------

def test_worst_case_cost_is_the_maximum_over_human_branches() -> None:
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_secret(a)"])
    r = ehatp.solve(p)
    assert r.policy is not None
    sums = [sum(n.cost for n in b) for b in r.policy.branches()]
    assert r.policy.cost == max(sums)
    assert r.policy.root.value == r.policy.cost


def test_costs_change_the_robots_choice() -> None:
    # lighting either lamp finishes `light`; making set_lamp expensive changes nothing about
    # which lamp (both cost the same), but the cost is accounted exactly
    p = problem(lab_domain(), init=HOME, robot=["light"], starts="robot",
                costs=Costs(actions={"set_lamp": Fraction(5, 2)}))
    r = ehatp.solve(p)
    assert r.policy is not None
    assert r.policy.root.moves[0].action == "set_lamp(a)"  # canonical tie-break
    assert r.policy.cost == Fraction(5, 2)


def test_ties_prefer_fewer_communications() -> None:
    # after an unseen set_secret the robot can inform, or the human can ask: both end the
    # same; a policy that never creates the uncertainty (acting in front) is preferred
    p = problem(lab_domain(), init=HOME, human=["trip(s1)"], robot=["set_secret(a)"])
    r = ehatp.solve(p)
    assert r.policy is not None and r.policy.communications == 0
