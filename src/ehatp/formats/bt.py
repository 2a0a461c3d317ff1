"""A robot policy as a behaviour tree, for BehaviorTree.CPP v4 or py_trees (``ehatp export bt``).

The policy is a graph (docs/policy-format.md); the tree follows it from the root:

- a robot move becomes action nodes: ``RobotAction`` for an action, ``RobotWait`` for a wait,
  ``Say`` for an inform, a question to the human about its intention (``ask``) or an
  announcement of the robot's own (``announce``), ``Silence`` for the robot's silent move at a
  speech opening; an action (or wait) said with an inform is a ``Say`` then the
  ``RobotAction`` (or ``RobotWait``); the node that finishes a robot move says so in its
  ``completes`` port;
- a human choice becomes ``WaitHumanAction``, a stateful node that runs until the human acts
  and writes what it observed to a blackboard entry, then a ``Fallback`` with one branch per
  move the policy covers -- a ``HumanDid`` condition on that entry, a ``Say`` with the robot's
  answer when the move is a question, then the rest of the policy -- and a last branch for
  anything else: ``ReportUncovered`` then ``AlwaysFailure``; when the policy covers one move,
  the rest of the policy follows the ``Fallback`` instead of nesting in it;
- a goal is ``GoalReached``;
- in joint steps with the human first (docs/concurrent.md) a step is a human choice whose wait
  is ``WaitHumanStart`` (the human's action observed as it *starts*; a decision timeout is a
  ``pass``), then, in the branch of the human's move, the robot's compliant reply; joint steps
  with the robot first are refused (:class:`NotExpressible`);
- a node with more than one move into it (a state shared by several paths) becomes a tree of
  its own, defined once and used through ``<SubTree ID="Node_N"/>``; so does a branch below
  ``MAX_NESTED_CHOICES`` nested choices, so that no tree is nested deeper than
  BehaviorTree.CPP's parser allows, however long the policy.

One structure (:class:`Forest` of :class:`BTNode`) is built from the policy and then written as
BehaviorTree.CPP v4 XML (with a ``TreeNodesModel`` for Groot) or as a py_trees module; the
runnable py_trees behaviours live in :mod:`ehatp.formats.bt_py_trees` (``ehatp[bt]``). See
``docs/behaviour-trees.md``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from enum import StrEnum
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import escape

from .bt_tree import MAIN_TREE, SEP, BTNode, Forest, blackboard_key, tree_id
from .lifted import expanded
from .policy import Policy, PolicyMove

if TYPE_CHECKING:
    from ..model.problem import Problem
    from .bt_py_trees import HumanFn, OnGoal, OnUncovered, RobotFn

class BTFormat(StrEnum):
    btcpp4 = "btcpp4"
    py_trees = "py_trees"


# The custom nodes: (kind, ID, description, ports). A port is (direction, name, description,
# default): every port is a std::string, and one with a default (None: none) is optional -- the
# export leaves it out where the default is meant -- so that BehaviorTree.CPP's generated
# schema (writeTreeXSD) does not require it.
Port = tuple[str, str, str, str | None]
_COMPLETES: Port = (
    "input", "completes", "the robot's policy move this node finishes, as the policy prints "
    "it; empty: none (a Say before the action it is said with, or an answer)", "")
CUSTOM_NODES: tuple[tuple[str, str, str, tuple[Port, ...]], ...] = (
    ("Action", "RobotAction", "The robot does one action of its domain.", (
        ("input", "action", "the action as the policy prints it, e.g. place(r, box1)", None),
        ("input", "action_name", "the action's name, e.g. place", None),
        ("input", "args", "its arguments, separated by ';'", ""),
        _COMPLETES,
    )),
    ("Action", "RobotWait", "The robot waits: it lets the human take a turn.", (_COMPLETES,)),
    ("Action", "Say", "The robot speaks: it informs the human of literals, answers the "
     "human's question truthfully, asks the human what it is about to do, or announces what "
     "it is doing itself.", (
        ("input", "kind", "inform, answer, ask or announce", None),
        ("input", "literals", "inform: the literals told, separated by ';'", ""),
        ("input", "question", "answer: the question asked; ask: what the robot asks about "
         "(intention)", ""),
        ("input", "answer", "answer: yes or no (empty when the export did not know: the "
         "robot answers from what it knows)", ""),
        ("input", "intention", "announce: the robot's tasks as it announces them, e.g. "
         "clean(room), tidy(desk)", ""),
        _COMPLETES,
    )),
    ("Action", "Silence", "The robot stays silent where it could speak (the speech opening "
     "before the human's first move); it does nothing.", (_COMPLETES,)),
    ("Action", "WaitHumanAction", "Runs until the human acts, then writes the action observed "
     "(as the policy prints it) to its output port.", (
        ("output", "action", "the human's action, e.g. pick(w) or pass", None),
        ("input", "expected", "the actions the policy covers here, separated by ';'", None),
    )),
    ("Condition", "HumanDid", "Succeeds when the observed human action is this one (spaces "
     "ignored).", (
        ("input", "observed", "the action WaitHumanAction observed", None),
        ("input", "action", "the action of this branch", None),
    )),
    ("Action", "ReportUncovered", "Reports that the human did something the policy does not "
     "cover (unless the observed action is one of expected: a branch for it ran and failed "
     "below, where that was reported), then succeeds.", (
        ("input", "observed", "the action WaitHumanAction observed", None),
        ("input", "expected", "the actions the policy covers here, separated by ';'", None),
    )),
    ("Action", "GoalReached", "The task is done (a goal of the policy); succeeds.", (
        ("input", "node", "the policy node reached", None),
    )),
)
CUSTOM_IDS = frozenset(c[1] for c in CUSTOM_NODES)
# joint steps only (declared in the model of a joint policy's export, after CUSTOM_NODES, so
# that every turn-taking export stays as it was)
JOINT_NODES: tuple[tuple[str, str, str, tuple[Port, ...]], ...] = (
    ("Action", "WaitHumanStart", "Joint steps: runs until the human starts an action, or "
     "until the decision timeout, which is a pass; then writes the action observed (as the "
     "policy prints it) to its output port. The robot's reply, in the branch of that action, "
     "runs while the human acts; the step ends when both are done.", (
         ("output", "action", "the human's action, e.g. pick(c1) or pass", None),
         ("input", "expected", "the actions the policy covers here, separated by ';'", None),
     )),
)
JOINT_IDS = frozenset(c[1] for c in JOINT_NODES)


class NotExpressible(ValueError):
    """A policy a behaviour tree of BehaviorTree.CPP v4 or py_trees cannot express: the
    message says why, ``fix`` what to do."""

    def __init__(self, why: str, fix: str) -> None:
        super().__init__(why)
        self.fix = fix


def joint(policy: Policy) -> bool:
    """Whether ``policy`` is one of joint steps (docs/concurrent.md). Raises
    :class:`NotExpressible` for joint steps with the robot first."""
    steps = policy.step_options
    if steps is None or steps.get("mode") != "concurrent":
        return False
    if steps.get("first", "human") != "human":
        raise NotExpressible(
            'a joint-step policy with the robot first ([steps] first = "robot") has no '
            "behaviour tree: the robot's action and the human's move run at once and the "
            "policy branches on the human's move while the robot acts, which neither "
            "BehaviorTree.CPP's nor py_trees' Parallel can branch on",
            'plan with [steps] first = "human" (the compliant robot) to export a tree, or '
            "follow this policy with ehatp execute")
    return True


def shared_nodes(policy: Policy) -> list[int]:
    """The ids of the nodes with more than one move into them, ascending."""
    into = [0] * len(policy.nodes)
    for _, m in policy.edges():
        into[m.to] += 1
    return [i for i, n in enumerate(into) if n > 1]


# BehaviorTree.CPP refuses a tree nested deeper than 256 elements (its XML parser's limit). A
# human choice with several covered moves nests its branches two levels deeper (Fallback, then
# the branch's Sequence); past MAX_NESTED_CHOICES of them in one tree, a branch goes on in a
# tree of its own (a SubTree), so that no tree is deeper than MAX_DEPTH however long the policy.
BTCPP_MAX_DEPTH = 256
MAX_NESTED_CHOICES = 60
# BehaviorTree 0, its Sequence 1, a choice's Fallback 2 + 2k below k choices, at the last one
# its branch's Sequence and that Sequence's children
MAX_DEPTH = 4 + 2 * MAX_NESTED_CHOICES


def from_policy(policy: Policy, answers: dict[tuple[int, str], bool] | None = None,
                expand_limit: int | None = None) -> Forest:
    """Return the behaviour tree of ``policy``. ``answers`` maps (policy node, question asked
    there) to the robot's truthful answer (:func:`answers_of`); without it the ``Say`` of an
    answer leaves the answer to the robot. A lifted policy (format version 3) is expanded first
    (:func:`~ehatp.formats.lifted.expanded`; give the expansion of
    :func:`ehatp.run.expand.expand_policy` when ``answers`` come from :func:`answers_of`):
    past ``expand_limit`` nodes over the real objects, :class:`~ehatp.errors.PolicyTooLarge`
    (a tree holds every branch).

    A human choice with one covered move does not nest: its ``Fallback`` holds the check of
    that move (and the robot's answer), and the policy goes on after it in the same
    ``Sequence``. Past ``MAX_NESTED_CHOICES`` nested choices with several moves, a branch goes
    on in a tree of its own, so every tree is at most ``MAX_DEPTH`` elements deep."""
    policy = expanded(policy, expand_limit)
    wait_human = "WaitHumanStart" if joint(policy) else "WaitHumanAction"
    own = set(shared_nodes(policy))  # the nodes with a tree of their own
    robot = policy.agents["robot"]
    answers = answers or {}

    def chain(n: int, top: int, nested: int) -> list[BTNode]:
        """Return the nodes that execute the policy from node ``n``, in a sequence, within the
        tree of node ``top``, below ``nested`` human choices of several moves."""
        out: list[BTNode] = []
        while True:
            if n != top and n in own:
                out.append(BTNode("SubTree", {"ID": tree_id(n)}))
                return out
            node = policy.nodes[n]
            if not node.moves:
                out.append(BTNode("GoalReached", {"node": str(n)}) if node.goal else
                           BTNode("AlwaysFailure", {"name": f"dead end at node {n}"}))
                return out
            if len(node.moves) == 1 and node.moves[0].agent == robot:
                out.extend(robot_nodes(node.moves[0]))
                n = node.moves[0].to
                continue
            key = "{" + blackboard_key(n) + "}"
            expected = port_list([m.action for m in node.moves], n)
            flat = len(node.moves) == 1
            if not flat and nested == MAX_NESTED_CHOICES:  # the branches go on in trees of
                own.update(m.to for m in node.moves if policy.nodes[m.to].moves)  # their own
            branches = []
            for m in node.moves:
                said = []
                if m.kind == "ask" and m.agent != robot:
                    attrs = {"kind": "answer", "question": m.args[0] if m.args else m.action}
                    yes = answers.get((n, m.action))
                    if yes is not None:
                        attrs["answer"] = "yes" if yes else "no"
                    said.append(BTNode("Say", attrs))
                rest = [] if flat else chain(m.to, top, nested + 1)
                branches.append(BTNode("Sequence", {"name": f"{m.agent} {m.action}"}, [
                    BTNode("HumanDid", {"observed": key, "action": m.action}), *said, *rest]))
            branches.append(BTNode("Sequence", {"name": "uncovered"}, [
                BTNode("ReportUncovered", {"observed": key, "expected": expected}),
                BTNode("AlwaysFailure")]))
            who = node.to_move or node.moves[0].agent
            out.append(BTNode(wait_human, {"action": key, "expected": expected}))
            out.append(BTNode("Fallback", {"name": f"{who}'s choice at node {n}"}, branches,
                              node=n))
            if not flat:
                return out
            n = node.moves[0].to

    trees = {MAIN_TREE: BTNode("Sequence", {"name": "node 0"}, chain(0, 0, 0))}
    done: set[int] = set()
    while todo := sorted(own - done):  # a tree may send branches to trees of their own
        for s in todo:
            trees[tree_id(s)] = BTNode("Sequence", {"name": f"node {s}"}, chain(s, s, 0))
        done.update(todo)
    ordered = {MAIN_TREE: trees[MAIN_TREE]}
    ordered.update((tree_id(s), trees[tree_id(s)]) for s in sorted(done))
    return Forest(MAIN_TREE, ordered, policy)


def port_list(items: Sequence[str], where: int | PolicyMove) -> str:
    """Return ``items`` as one list port value, separated by ``SEP``. Raises
    :class:`NotExpressible` when an item holds ``SEP`` itself: BehaviorTree.CPP splits a list
    port on every ``;`` and has no escape for it, so the robot's program would read other
    items than the policy's (``where``: the policy node of a human choice, or the move)."""
    for item in items:
        if SEP in item:
            place = (f"the human's choice at policy node {where}" if isinstance(where, int)
                     else f"the robot's move {where.action!r}")
            raise NotExpressible(
                f"{item!r} in {place} holds {SEP!r}, which BehaviorTree.CPP's list ports "
                "split on (there is no escape for it)",
                f"rename the object or literal without {SEP!r}, or follow this policy with "
                "ehatp execute")
    return SEP.join(items)


def robot_nodes(m: PolicyMove) -> list[BTNode]:
    """The nodes of one robot move; the last one ``completes`` it."""
    out: list[BTNode] = []
    if m.kind == "inform":
        out.append(BTNode("Say", {"kind": "inform", "literals": port_list(m.args, m)}))
    elif m.kind == "ask":  # the robot asks the human's intention (§5)
        out.append(BTNode("Say", {"kind": "ask", "question": m.args[0] if m.args else
                                  m.action.removeprefix("ask(").removesuffix(")")}))
    elif m.kind == "announce":  # the robot tells its own intention (§5)
        out.append(BTNode("Say", {"kind": "announce", "intention": m.action.removeprefix(
            "announce(").removesuffix(")")}))
    elif m.kind == "silence":
        out.append(BTNode("Silence"))
    elif m.kind in ("action", "wait"):
        if m.told:
            out.append(BTNode("Say", {"kind": "inform", "literals": port_list(m.told, m)}))
        if m.kind == "wait":
            out.append(BTNode("RobotWait"))
        else:
            action = m.action.rsplit(" + ", 1)[-1] if m.told else m.action
            out.append(BTNode("RobotAction", {"action": action, "action_name": m.name,
                                              "args": port_list(m.args, m)}))
    else:
        raise ValueError(f"a robot move of kind {m.kind!r} ({m.action}) has no behaviour")
    out[-1].completes = m.action
    return out


def answers_of(problem: Problem, policy: Policy) -> dict[tuple[int, str], bool]:
    """The robot's truthful answer to every question the policy's human may ask, by (policy
    node, question label): the policy is walked with the problem's semantics (each node once).
    Raises :class:`~ehatp.errors.PolicyMismatch` when the policy does not fit. A lifted policy
    (format version 3) is expanded first (:func:`ehatp.run.expand.expand_policy`: the nodes
    are that graph's)."""
    from ..run.executor import Executor
    from ..run.expand import expand_policy

    policy = expand_policy(problem, policy)
    ex = Executor(problem, policy)
    ex.replay_opening()
    states = {0: ex.state}
    out: dict[tuple[int, str], bool] = {}
    for i in policy.topological_order():
        es, node = states[i], policy.nodes[i]
        for m in node.moves:
            if m.kind == "ask" and m.agent != policy.agents["robot"]:
                yes = ex.answer(es, m.action)
                if yes is not None:
                    out[(i, m.action)] = yes
            if m.to not in states:
                # the move the edge records (one label may stand for several moves)
                child = ex.edge_move(node, m, es).child
                assert child is not None
                states[m.to] = child
    return out


# --------------------------------------------------------------------------- BehaviorTree.CPP


# XML 1.0 has no way to write these characters, not even as a character reference
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _xml_safe(v: str) -> str:
    """Return ``v``; raise :class:`ValueError` when it holds a character XML cannot carry (a
    problem or policy file with one is refused when it is read)."""
    if (m := _NOT_XML.search(v)) is not None:
        raise ValueError(f"{v!r} holds the control character {m.group()!r}, which XML cannot "
                         "carry; remove it from the name")
    return v


def _attr(v: str) -> str:
    """Return ``v`` as a quoted XML attribute value that parses back to ``v`` exactly: markup
    characters and quotes as entities, and newlines and tabs as character references (an
    XML reader turns them into spaces otherwise)."""
    return '"' + escape(_xml_safe(v), {'"': "&quot;", "\n": "&#10;", "\r": "&#13;",
                                        "\t": "&#9;"}) + '"'


def _comment(text: str) -> str:
    """Return ``text`` as an XML comment: an XML comment may hold no ``--`` and may not end
    with ``-``, so a space goes between two dashes and after the last one."""
    body = re.sub(r"-(?=-|$)", "- ", escape(_xml_safe(text)))
    return f"<!-- {body} -->"


def _write(node: BTNode, depth: int, out: list[str]) -> None:
    pad = "  " * depth
    attrs = "".join(f" {k}={_attr(v)}" for k, v in node.attrs.items())
    if node.completes is not None:
        attrs += f" completes={_attr(node.completes)}"
    if not node.children:
        out.append(f"{pad}<{node.tag}{attrs}/>")
        return
    out.append(f"{pad}<{node.tag}{attrs}>")
    for c in node.children:
        _write(c, depth + 1, out)
    out.append(f"{pad}</{node.tag}>")


def to_btcpp(forest: Forest) -> str:
    """BehaviorTree.CPP v4 XML: every tree, then the ``TreeNodesModel`` Groot reads. The same
    policy always gives the same bytes."""
    p = forest.policy
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           f'<root BTCPP_format="4" main_tree_to_execute={_attr(forest.main)}>',
           "  " + _comment(f"ehatp policy for {p.problem} ({p.domain}): robot "
                           f"{p.agents['robot']}, human {p.agents['human']}, cost {p.cost}, "
                           f"{len(p.nodes)} nodes; written by ehatp export bt")]
    for tid, root in forest.trees.items():
        out.append(f"  <BehaviorTree ID={_attr(tid)}>")
        _write(root, 2, out)
        out.append("  </BehaviorTree>")
    out.append("  <TreeNodesModel>")
    for kind, nid, desc, ports in CUSTOM_NODES + (JOINT_NODES if joint(p) else ()):
        out.append(f"    <{kind} ID={_attr(nid)}>")
        out.append(f"      {_comment(desc)}")
        for direction, name, pdesc, default in ports:
            dflt = "" if default is None else f" default={_attr(default)}"
            out.append(f'      <{direction}_port name={_attr(name)} type="std::string"{dflt}>'
                       f"{escape(pdesc)}</{direction}_port>")
        out.append(f"    </{kind}>")
    out.append("  </TreeNodesModel>")
    out.append("</root>")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------- py_trees


def build_py_tree(policy: Policy, *, robot: RobotFn, human: HumanFn,
                  on_goal: OnGoal | None = None, on_uncovered: OnUncovered | None = None,
                  problem: Problem | None = None) -> Any:
    """The policy's behaviour tree as py_trees behaviours, ready to tick (needs ``py_trees``:
    ``pip install 'ehatp[bt]'``). ``robot(command)`` does the robot's part and ``human(turn)``
    says what the human did; see :mod:`ehatp.formats.bt_py_trees`. With ``problem`` the robot's
    answers to questions are worked out in advance (:func:`answers_of`). Returns the root
    behaviour (a ``py_trees.behaviour.Behaviour``)."""
    try:
        from . import bt_py_trees
    except ImportError as e:
        raise ImportError(f"build_py_tree needs py_trees ({e}): pip install 'ehatp[bt]'"
                          ) from None

    if problem is not None and policy.symmetry is not None:  # lifted: expanded on the problem
        from ..run.expand import expand_policy

        policy = expand_policy(problem, policy)
    forest = from_policy(policy, None if problem is None else answers_of(problem, policy))
    return bt_py_trees.build(forest, bt_py_trees.Interface(robot, human, on_goal, on_uncovered))


def _py(v: str) -> str:
    """Return ``v`` as a Python string literal (``repr`` escapes quotes, backslashes, control
    and line-separating characters)."""
    return repr(str(v))


def _expr(node: BTNode, depth: int, out: list[str], choices: list[BTNode] | None = None) -> None:
    """Append the py_trees expression of ``node`` (one call per line, nested by indent). A
    human choice is a call of its own function (``choice_N()``), added to ``choices`` to be
    written apart, so that nesting stays shallow however deep the policy."""
    pad = "    " * depth
    a = node.attrs
    if node.tag == "Fallback" and choices is not None and node.node is not None:
        choices.append(node)
        out.append(f"{pad}choice_{node.node}(),")
        return
    if node.tag in ("Sequence", "Fallback"):
        cls = "Sequence" if node.tag == "Sequence" else "Selector"
        out.append(f"{pad}{cls}({_py(a.get('name', node.tag))}, memory=True, children=[")
        for c in node.children:
            _expr(c, depth + 1, out, choices)
        out.append(f"{pad}]),")
        return
    if node.tag == "SubTree":
        fn = a["ID"].lower()
        out.append(f"{pad}SubTree({_py(a['ID'])}, {fn}),")
        return
    if node.tag == "AlwaysFailure":
        out.append(f"{pad}Failure({_py(a.get('name', 'AlwaysFailure'))}),")
        return
    args = ["io", *(f"{k}={_py(v)}" for k, v in a.items() if k != "name")]
    if node.completes is not None:
        args.append(f"completes={_py(node.completes)}")
    out.append(f"{pad}{node.tag}({', '.join(args)}),")


def to_py_trees_source(forest: Forest) -> str:
    """A Python module whose ``make_tree(robot, human, ...)`` builds the same behaviours as
    :func:`build_py_tree` (with ``ehatp[bt]`` installed). Every string of the policy is in the
    module as a Python literal (``repr``), never in a docstring or a comment: a module written
    for any policy file runs nothing but the tree's construction when imported. The policy's
    header is the module's ``POLICY`` dict."""
    p = forest.policy
    header = {"problem": p.problem, "domain": p.domain, "robot": p.agents["robot"],
              "human": p.agents["human"], "cost": str(p.cost)}
    out = ['"""Behaviour tree of an ehatp policy (its header: ``POLICY``), for py_trees.',
           "",
           "Written by `ehatp export bt --format py_trees`; needs ehatp[bt]. Build it with",
           "``make_tree(robot, human)`` and tick it (see docs/behaviour-trees.md).",
           '"""', "",
           "from py_trees.behaviour import Behaviour",
           "from py_trees.behaviours import Failure",
           "from py_trees.composites import Selector, Sequence",
           "",
           "from ehatp.formats.bt_py_trees import (",
           "    GoalReached, HumanDid, HumanFn, Interface, OnGoal, OnUncovered, ReportUncovered,",
           "    RobotAction, RobotFn, RobotWait, Say, Silence, SubTree, WaitHumanAction,",
           *(["    WaitHumanStart,"] if joint(p) else []),
           ")", "",
           "POLICY = {" + ", ".join(f"{_py(k)}: {_py(v)}" for k, v in header.items()) + "}",
           "", "",
           "def make_tree(robot: RobotFn, human: HumanFn, on_goal: OnGoal | None = None,",
           "              on_uncovered: OnUncovered | None = None) -> Behaviour:",
           '    """Return the tree of the policy ``POLICY`` describes."""',
           "    io = Interface(robot, human, on_goal, on_uncovered)"]

    def function(name: str, root: BTNode) -> None:
        # a choice written inside this one gets its function after it (a queue: the order
        # is that of the policy, and every name is defined before make_tree returns)
        choices: list[BTNode] = []
        out.extend(["", f"    def {name}() -> Behaviour:", "        return ("])
        _expr(root, 3, out, choices)
        out[-1] = out[-1].rstrip(",")
        out.append("        )")
        for c in choices:
            # the choice's own Selector, its branches' choices deferred in turn
            function(f"choice_{c.node}", BTNode("Fallback", c.attrs, c.children))

    for tid, root in forest.trees.items():
        function(tid.lower(), root)
    out += ["", f"    return {forest.main.lower()}()"]
    return "\n".join(out) + "\n"


__all__ = ["BTCPP_MAX_DEPTH", "CUSTOM_IDS", "CUSTOM_NODES", "JOINT_IDS", "JOINT_NODES",
           "MAIN_TREE", "MAX_DEPTH", "MAX_NESTED_CHOICES", "BTFormat", "BTNode", "Forest",
           "NotExpressible", "Port",
           "answers_of", "blackboard_key", "build_py_tree", "from_policy", "joint", "shared_nodes",
           "to_btcpp", "to_py_trees_source", "tree_id"]
