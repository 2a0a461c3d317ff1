"""The policy file format: the robot policy as data, its JSON form, and nothing else.

A policy is an acyclic AND/OR graph that branches on every human choice (docs/semantics.md §3,
§7). A :class:`PolicyNode` is a *state*: what holds there (co-presence, the K-counter, the
human's worlds and how they differ from the truth, the agendas), who moves next and the cost to
go. A :class:`PolicyMove` is an *edge*: who moved, the move in the domain's vocabulary and its
cost, and the node it leads to. Each distinct state of the policy is stored once, and every
path that reaches it shares it, so a file is proportional to the policy's distinct states, not
to its branches. See ``docs/policy-format.md`` (version 2; version 1 files, which stored the
tree unfolding, are still read and turned into this graph).

This module imports neither the planner nor the validator: both use it, and so can any tool that
only reads policy files. Nor does it import the renderer: a policy shows itself in a notebook
through :mod:`ehatp.formats.render` (``ehatp.explore(policy)``, or inline once ``ehatp`` is
imported in IPython; docs/notebook.md).
"""

from __future__ import annotations

import contextlib
import gzip
import io
import json
import os
import re
import secrets
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from ..errors import InputError

Cost = int | Fraction

POLICY_FIX = "give a policy JSON written by `ehatp solve --out FILE`"
FORMAT = "ehatp-policy"
VERSION = 2  # the version written for a policy over real states; READS lists every version read
VERSION_LIFTED = 3  # the version written for a lifted policy (canonical nodes, renamings)
READS = (1, 2, 3)
COMM_KINDS = ("inform", "ask", "announce")
GZIP_SUFFIX = ".gz"  # a policy file named so is written gzip-compressed (Policy.write)
_GZIP_MAGIC = b"\x1f\x8b"  # how a gzip file starts: Policy.load reads it whatever its name
_CHUNK = 1 << 20  # bytes decompressed between two calls of a limit's check

# a control character in a JSON string: an escape (\u001b, \n, ...) after an even number of
# backslashes, or DEL / a C1 character written raw (JSON refuses raw C0 characters itself)
_CONTROL_IN_JSON = re.compile(r'\\(?:u00[0189][0-9a-fA-F]|u007[fF]|[bfnrt])|[\x7f-\x9f]')



def _gunzip(name: str, data: bytes, check: Callable[[], None] | None) -> bytearray:
    """Return the decompressed bytes of the gzip file ``data`` (named ``name``), a megabyte at
    a time with ``check`` called between (a small file may hold a large policy: a limit's
    check stops it); a damaged or truncated file is one :class:`InputError` line."""
    out = bytearray()
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(data), mode="rb") as gz:
            while piece := gz.read(_CHUNK):
                out += piece
                if check is not None:
                    check()
    except (OSError, EOFError, zlib.error) as e:  # gzip.BadGzipFile is an OSError
        what = "truncated" if isinstance(e, EOFError) else str(e) or type(e).__name__
        raise InputError(name, "", f"not a readable gzip file ({what})",
                         "write it again with `ehatp solve --out FILE.json.gz`") from None
    return out

def _no_control_characters(name: str, text: str) -> None:
    """Raise :class:`InputError` when a string of the policy JSON ``text`` holds a control
    character: no name or label ehatp writes has one, and printed to a terminal one could be
    an escape code (a policy edited by hand must not reach a terminal with it)."""
    for m in _CONTROL_IN_JSON.finditer(text):
        start = m.start()
        if m.group()[0] == "\\":
            before = start
            while before > 0 and text[before - 1] == "\\":
                before -= 1
            if (start - before) % 2:  # an escaped backslash followed by letters
                continue
        line = text.count("\n", 0, start) + 1
        col = start - text.rfind("\n", 0, start)
        char = json.loads(f'"{m.group()}"') if m.group()[0] == "\\" else m.group()
        raise InputError(name, f"{line}:{col}", f"a string holds the control character "
                         f"{char!r}, which no policy name or label has (printed, it could be a "
                         "terminal escape code)", "remove it from the file")

@dataclass
class PolicyMove:
    """One move of the policy: an edge from the node where it is played to node ``to``."""

    agent: str  # who moves (the domain's name for the robot or the human)
    kind: str  # action | wait | pass | inform | ask | silence | answer | announce
    action: str  # the move as printed: place(w, box2), inform(empty(box2)), wait
    name: str  # the action's name (inform, ask, wait, pass, silence for the others)
    args: list[str]  # its arguments (inform: the literals told; ask: the question)
    cost: Cost
    to: int  # the id of the node the move leads to
    told: list[str] = field(default_factory=list)  # literals said with an action (speech)
    # version 3: the renaming (an index into the policy's symmetry table) that maps the move's
    # child, seen from this node, onto the node ``to``; 0 (the identity) is not written
    renaming: int = 0
    # joint steps (docs/concurrent.md): "human" (the human's move that starts a step),
    # "reply" (the robot's compliant reply that ends it), "ask" (a question: a whole step,
    # the robot's answer implied); "" in turn-taking, and not written
    step: str = ""

    @property
    def communicates(self) -> bool:
        """An ``inform`` or ``ask``, or an action said with an inform (docs/semantics.md §5)."""
        return self.kind in COMM_KINDS or bool(self.told)

    def to_dict(self) -> dict[str, Any]:
        return {"agent": self.agent, "kind": self.kind, "action": self.action,
                "name": self.name, "args": self.args, "cost": num(self.cost), "to": self.to,
                "told": self.told, **({"renaming": self.renaming} if self.renaming else {}),
                **({"step": self.step} if self.step else {})}


@dataclass
class PolicyNode:
    """One distinct state of the policy, and the moves the policy plays or covers there: one
    (the robot's choice) where the robot moves, one per human option where the human moves,
    none at a goal."""

    id: int
    copresent: bool
    k: int  # robot turns taken since the agents were last co-present
    worlds: int
    divergence: list[str]  # truth's literals on which some world disagrees
    world_diffs: list[dict[str, list[str]]]  # per world: atoms true / false unlike the truth
    state: list[str]  # true fluent atoms
    robot_agenda: list[str]
    human_agenda: list[str]
    to_move: str | None  # who moves next (None at a goal leaf)
    value: Cost  # cost from here to the end, under the policy's objective
    goal: bool
    moves: list[PolicyMove] = field(default_factory=list)
    # the human agendas the robot cannot tell apart here (docs/semantics.md §3), when more
    # than one; ``human_agenda`` is then the first of them
    hypotheses: list[list[str]] = field(default_factory=list)

    @property
    def human_agendas(self) -> list[list[str]]:
        """Every human agenda consistent with what the robot observed (at least one)."""
        return self.hypotheses if len(self.hypotheses) > 1 else [self.human_agenda]

    @property
    def children(self) -> list[int]:
        """The ids the moves lead to, in move order (an id may repeat: two moves, one state)."""
        return [m.to for m in self.moves]

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.id, "copresent": self.copresent, "k": self.k, "worlds": self.worlds,
                "divergence": self.divergence, "world_diffs": self.world_diffs,
                "state": self.state, "robot_agenda": self.robot_agenda,
                "human_agenda": self.human_agenda, "to_move": self.to_move,
                "value": num(self.value), "goal": self.goal,
                "moves": [m.to_dict() for m in self.moves],
                **({"hypotheses": self.hypotheses} if len(self.hypotheses) > 1 else {})}


@dataclass(frozen=True)
class PathStep:
    """One step of a branch: the move played (None at the root) and the node it reaches. Reads
    like a node of the version 1 tree: the move's fields and the node's."""

    move: PolicyMove | None
    node: PolicyNode

    @property
    def id(self) -> int:
        return self.node.id

    @property
    def agent(self) -> str | None:
        return None if self.move is None else self.move.agent

    @property
    def kind(self) -> str:
        return "start" if self.move is None else self.move.kind

    @property
    def action(self) -> str:
        return "start" if self.move is None else self.move.action

    @property
    def name(self) -> str:
        return "start" if self.move is None else self.move.name

    @property
    def args(self) -> list[str]:
        return [] if self.move is None else self.move.args

    @property
    def cost(self) -> Cost:
        return 0 if self.move is None else self.move.cost

    @property
    def told(self) -> list[str]:
        return [] if self.move is None else self.move.told

    @property
    def goal(self) -> bool:
        return self.node.goal

    @property
    def copresent(self) -> bool:
        return self.node.copresent

    @property
    def worlds(self) -> int:
        return self.node.worlds

    @property
    def k(self) -> int:
        return self.node.k

    @property
    def value(self) -> Cost:
        return self.node.value

    @property
    def to_move(self) -> str | None:
        return self.node.to_move

    @property
    def state(self) -> list[str]:
        return self.node.state


Branch = list[PathStep]


@dataclass
class Policy:
    problem: str
    domain: str
    agents: dict[str, str]
    K: int
    costs: dict[str, Any]
    nodes: list[PolicyNode]
    cost: Cost
    communications: int  # communication moves in the tree unfolding (count_communications)
    leaves: int  # root-to-leaf branches (count_branches)
    optimal: bool = True
    stats: dict[str, Any] = field(default_factory=dict)
    after: list[str] = field(default_factory=list)  # the fixed opening the root follows
    # {"kind": "worst-case" | "expected", "weights": {...}, "ties": [...]}
    objective: dict[str, Any] = field(default_factory=lambda: {"kind": "worst-case"})
    worst_case: Cost | None = None  # the policy's worst-case cost (None: not recorded)
    expected: Cost | None = None  # its expected cost over human choices
    # version 3, a lifted policy: {"objects": [...], "classes": [[...], ...], "renamings":
    # [[int, ...], ...], "root": int}; None for a policy over real states (version 2)
    symmetry: dict[str, Any] | None = None
    # joint steps (docs/concurrent.md): the problem's [steps] table ({"mode": "concurrent",
    # "first", "witness", "commute", "cost"}); None in turn-taking, and not written
    step_options: dict[str, Any] | None = None

    @property
    def lifted(self) -> bool:
        """Whether this is a lifted policy (version 3): its nodes are canonical states, its
        moves carry renamings (:mod:`ehatp.formats.lifted` realises it)."""
        return self.symmetry is not None

    @property
    def version(self) -> int:
        """The format version this policy is written in."""
        return VERSION_LIFTED if self.symmetry is not None else VERSION

    def __repr__(self) -> str:
        """Return a one-line summary (the whole graph is :meth:`to_json`)."""
        return (f"Policy({self.problem!r}, domain={self.domain!r}, version={self.version}, "
                f"nodes={len(self.nodes)}, leaves={self.leaves}, cost={self.cost!r})")

    # -- the graph ----------------------------------------------------------------------------

    @property
    def root(self) -> PolicyNode:
        return self.nodes[0]

    def children(self, n: PolicyNode) -> list[PolicyNode]:
        return [self.nodes[m.to] for m in n.moves]

    def steps(self, n: PolicyNode) -> list[PathStep]:
        """The moves out of ``n``, each with the node it reaches."""
        return [PathStep(m, self.nodes[m.to]) for m in n.moves]

    def edges(self) -> Iterator[tuple[PolicyNode, PolicyMove]]:
        """Every move once, as (node it is played at, move), in node then move order."""
        for n in self.nodes:
            for m in n.moves:
                yield n, m

    def topological_order(self) -> list[int]:
        """The node ids reachable from the root, parents before children. Raises
        ValueError on a cycle (:meth:`load` refuses such files)."""
        return topological_order(self.nodes)

    def path_counts(self) -> list[int]:
        """Per node, the number of root-to-node paths: its copies in the tree unfolding."""
        paths = [0] * len(self.nodes)
        paths[0] = 1
        for i in self.topological_order():
            for m in self.nodes[i].moves:
                paths[m.to] += paths[i]
        return paths

    def count_branches(self) -> int:
        """Root-to-leaf branches (one per combination of human choices), by counting paths
        over the graph: linear in its size, however many branches there are."""
        paths = self.path_counts()
        return sum(paths[n.id] for n in self.nodes if not n.moves)

    def count_communications(self) -> int:
        """Communication moves in the tree unfolding: each ``inform``/``ask`` move, or move
        said with an inform, once per root path that reaches it (version 1 counted the tree's
        nodes; the number is the same)."""
        paths = self.path_counts()
        return sum(paths[n.id] for n, m in self.edges() if m.communicates)

    def tree_size(self) -> int:
        """Nodes in the tree unfolding (what version 1 files stored)."""
        return sum(self.path_counts())

    # -- branches, for small policies ---------------------------------------------------------

    def iter_branches(self) -> Iterator[Branch]:
        """Every root-to-leaf path, lazily, in move order. There are :attr:`leaves` of them,
        which can be exponentially many more than nodes: stop early on a large policy."""
        stack: list[Branch] = [[PathStep(None, self.root)]]
        while stack:
            path = stack.pop()
            moves = path[-1].node.moves
            if not moves:
                yield path
            for m in reversed(moves):
                stack.append([*path, PathStep(m, self.nodes[m.to])])

    def branches(self) -> list[Branch]:
        """Every root-to-leaf path (a list: for small policies, see :meth:`iter_branches`)."""
        return list(self.iter_branches())

    def timelines(self) -> list[dict[str, Any]]:
        """One timeline per branch (:func:`timeline`), for small policies."""
        return [timeline(self, b) for b in self.iter_branches()]

    # -- JSON ---------------------------------------------------------------------------------

    def _header(self) -> dict[str, Any]:
        """The file's JSON object without its nodes."""
        return {
            "format": FORMAT, "version": self.version, "problem": self.problem,
            "domain": self.domain,
            "agents": self.agents, "K": self.K, "costs": self.costs, "cost": num(self.cost),
            "communications": self.communications, "leaves": self.leaves,
            "optimal": self.optimal, "stats": self.stats, "after": self.after,
            "objective": self.objective,
            "worst_case": None if self.worst_case is None else num(self.worst_case),
            "expected": None if self.expected is None else num(self.expected),
            **({"symmetry": self.symmetry} if self.symmetry is not None else {}),
            **({"steps": self.step_options} if self.step_options is not None else {}),
        }

    def to_dict(self, check: Callable[[], None] | None = None) -> dict[str, Any]:
        """The file's JSON object; ``check`` (e.g. a time limit's) is called every few
        hundred nodes and may raise to stop the work."""
        return {**self._header(),
                "nodes": [n.to_dict() for n in _checked(self.nodes, check)]}

    def iter_json(self, check: Callable[[], None] | None = None) -> Iterator[str]:
        """The file's text in pieces, a node at a time, so a writer never holds the whole text:
        keys sorted, one node per line, so the same policy always gives the same bytes.
        ``check`` as in :meth:`to_dict`."""
        head = self._header()
        keys = sorted([*head, "nodes"])
        yield "{\n"
        for i, key in enumerate(keys):
            end = ",\n" if i + 1 < len(keys) else "\n"
            if key != "nodes":
                yield f" {json.dumps(key)}: {_dumps(head[key])}{end}"
                continue
            yield ' "nodes": [\n'
            last = len(self.nodes) - 1
            for j, n in enumerate(_checked(self.nodes, check)):
                yield f"  {_dumps(n.to_dict())}{',' if j < last else ''}\n"
            yield f" ]{end}"
        yield "}\n"

    def to_json(self, check: Callable[[], None] | None = None) -> str:
        """The file's text (:meth:`iter_json` joined). ``check`` as in :meth:`to_dict`."""
        return "".join(self.iter_json(check))

    def write(self, path: str | Path, check: Callable[[], None] | None = None) -> None:
        """Write :meth:`iter_json` to ``path`` atomically: streamed, a node at a time, into a
        new file beside it that then replaces ``path``, so a reader never sees half a policy
        and the text is never held whole. A ``path`` ending in ``.gz`` is written
        gzip-compressed, deterministically (no time and no file name in the gzip header: the
        same policy gives the same bytes); :meth:`load` reads either. ``check`` as in
        :meth:`to_dict`: when it stops the work, ``path`` is left as it was and the partial
        file removed."""
        path = Path(path)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
        try:
            with open(tmp, "xb") as raw:
                if path.name.endswith(GZIP_SUFFIX):
                    with gzip.GzipFile(filename="", mode="wb", compresslevel=6,
                                       fileobj=raw, mtime=0) as gz, \
                            io.TextIOWrapper(gz, encoding="utf-8", newline="") as fh:
                        for piece in self.iter_json(check):
                            fh.write(piece)
                else:
                    with io.TextIOWrapper(raw, encoding="utf-8", newline="") as fh:
                        for piece in self.iter_json(check):
                            fh.write(piece)
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise

    @classmethod
    def from_dict(cls, d: dict[str, Any], check: Callable[[], None] | None = None) -> Policy:
        """A policy from its JSON object, version 3, 2 or 1 (a version 1 tree becomes a graph
        with one node per tree node; a version 3 policy stays lifted). Trusts the shapes:
        :meth:`load` checks them. ``check`` as in :meth:`to_dict`."""
        if d.get("format") != FORMAT:
            raise ValueError(f"not an ehatp policy (format is {d.get('format')!r})")
        version = d.get("version")
        if version not in READS or isinstance(version, bool):
            raise ValueError(f"policy format version {version} is not one this ehatp reads "
                             f"({', '.join(map(str, READS))})")
        raw = d["nodes"]
        if not isinstance(raw, list):
            raise TypeError("nodes must be a list")
        nodes = _nodes_v1(raw) if version == 1 else [_node(n) for n in _checked(raw, check)]
        return cls(d["problem"], d["domain"], d["agents"], d["K"], d["costs"], nodes, d["cost"],
                   d["communications"], d["leaves"], d.get("optimal", True), d.get("stats", {}),
                   d.get("after", []), d.get("objective", {"kind": "worst-case"}),
                   d.get("worst_case"), d.get("expected"),
                   _symmetry(d["symmetry"]) if version == VERSION_LIFTED else None,
                   d.get("steps"))

    @classmethod
    def read(cls, path: str | Path) -> Policy:
        return cls.from_dict(json.loads(Path(path).read_text(encoding="utf-8")))

    @classmethod
    def load(cls, path: str | Path, check: Callable[[], None] | None = None,
             inspect: Callable[[Any], None] | None = None) -> Policy:
        """Read a policy file written by ``ehatp solve``, checking its graph; anything else is
        one :class:`~ehatp.errors.InputError` line naming the file (``NaN`` and ``Infinity``,
        which JSON does not allow, included). ``check`` as in :meth:`to_dict`; ``inspect`` is
        given the parsed JSON before anything reads it (a schema's check, which raises)."""
        name = str(path)
        try:
            data = Path(path).read_bytes()
        except FileNotFoundError:
            raise InputError(name, "", "no such file", POLICY_FIX) from None
        except OSError as e:
            raise InputError(name, "", f"cannot read the file ({e.strerror or e})",
                             "check the path") from None
        try:
            text = (_gunzip(name, data, check) if data.startswith(_GZIP_MAGIC)
                    else data).decode("utf-8")
        except UnicodeDecodeError:
            raise InputError(name, "", "not a text file", POLICY_FIX) from None
        try:
            raw = json.loads(text, parse_constant=_no_constant, parse_float=_finite)
        except json.JSONDecodeError as e:
            raise InputError(name, f"{e.lineno}:{e.colno}", f"not valid JSON ({e.msg})",
                             POLICY_FIX) from None
        except ValueError as e:  # NaN, Infinity
            raise InputError(name, "", str(e), POLICY_FIX) from None
        except RecursionError:
            raise InputError(name, "", "nested too deeply for a policy", POLICY_FIX) from None
        _no_control_characters(name, text)
        if inspect is not None:
            inspect(raw)
        if not isinstance(raw, dict):
            raise InputError(name, "", "not an ehatp policy (expected a JSON object)",
                             POLICY_FIX)
        try:
            policy = cls.from_dict(raw, check)
        except ValueError as e:
            raise InputError(name, "", str(e), POLICY_FIX) from None
        except KeyError as e:
            raise InputError(name, "", f"not an ehatp policy (missing field {e})",
                             POLICY_FIX) from None
        except (TypeError, AttributeError) as e:
            place, what = malformed(raw) or ("", f"malformed policy node ({e})")
            raise InputError(name, place, what, POLICY_FIX) from None
        policy._check_graph(name)
        return policy

    def _check_graph(self, name: str) -> None:
        # readers follow moves blindly; a hand-edited file must not send them into a loop
        n = len(self.nodes)
        renamings = len(self.symmetry["renamings"]) if self.symmetry is not None else 1
        if n == 0:
            raise InputError(name, "nodes", "the policy has no nodes", POLICY_FIX)
        if not isinstance(self.agents, dict) or not {"robot", "human"} <= self.agents.keys():
            raise InputError(name, "agents", "agents must name the robot and the human",
                             POLICY_FIX)
        for i, node in enumerate(self.nodes):
            if node.id != i:
                raise InputError(name, f"nodes[{i}]", f"node id {node.id} is not its position",
                                 POLICY_FIX)
            if not isinstance(node.moves, list):
                raise InputError(name, f"nodes[{i}].moves", "moves must be a list",
                                 POLICY_FIX)
            for j, m in enumerate(node.moves):
                if not isinstance(m.to, int) or isinstance(m.to, bool) or not 0 < m.to < n:
                    raise InputError(name, f"nodes[{i}].moves[{j}].to",
                                     f"{m.to!r} is not the id of a node other than the root",
                                     POLICY_FIX)
                if not isinstance(m.renaming, int) or isinstance(m.renaming, bool) \
                        or not 0 <= m.renaming < renamings:
                    raise InputError(name, f"nodes[{i}].moves[{j}].renaming",
                                     f"{m.renaming!r} is not the index of a renaming in the "
                                     "symmetry table", POLICY_FIX)
            if not isinstance(node.world_diffs, list) or not isinstance(node.state, list):
                raise InputError(name, f"nodes[{i}]", "world_diffs and state must be lists",
                                 POLICY_FIX)
        try:
            reached = len(self.topological_order())
        except ValueError as e:
            raise InputError(name, "nodes", str(e), POLICY_FIX) from None
        if reached != n:
            raise InputError(name, "nodes", f"{n - reached} node(s) are not below the root",
                             POLICY_FIX)


def _symmetry(table: Any) -> dict[str, Any]:
    """A version 3 file's ``symmetry`` table, its shape checked (ValueError naming what is
    wrong): objects, classes, renamings (permutations of the objects' indices, the first
    the identity) and the root's renaming."""
    if not isinstance(table, dict) or set(table) != {"objects", "classes", "renamings", "root"}:
        raise ValueError("symmetry must be an object with objects, classes, renamings, root")
    objects, renamings, root = table["objects"], table["renamings"], table["root"]
    if not isinstance(objects, list) or not all(isinstance(o, str) for o in objects):
        raise ValueError("symmetry.objects must be a list of names")
    n = len(objects)
    if not isinstance(renamings, list) or not renamings:
        raise ValueError("symmetry.renamings must be a non-empty list")
    for i, p in enumerate(renamings):
        if not isinstance(p, list) or sorted(p) != list(range(n)) \
                or any(isinstance(x, bool) for x in p):
            raise ValueError(f"symmetry.renamings[{i}] is not a permutation of the "
                             f"{n} objects' indices")
    if renamings[0] != list(range(n)):
        raise ValueError("symmetry.renamings[0] must be the identity")
    if not isinstance(root, int) or isinstance(root, bool) or not 0 <= root < len(renamings):
        raise ValueError(f"symmetry.root {root!r} is not the index of a renaming")
    classes = table["classes"]
    if not isinstance(classes, list) or not all(
            isinstance(c, list) and all(isinstance(o, str) for o in c) for c in classes):
        raise ValueError("symmetry.classes must be a list of lists of names")
    return table


def topological_order(nodes: list[PolicyNode]) -> list[int]:
    """The ids reachable from node 0, parents before children (reverse DFS postorder, moves in
    order); ValueError naming a node on a cycle."""
    state = [0] * len(nodes)  # 0 new, 1 on the DFS stack, 2 done
    post: list[int] = []
    stack: list[tuple[int, int]] = [(0, 0)]
    state[0] = 1
    while stack:
        i, j = stack[-1]
        moves = nodes[i].moves
        if j == len(moves):
            stack.pop()
            state[i] = 2
            post.append(i)
            continue
        stack[-1] = (i, j + 1)
        c = moves[j].to
        if state[c] == 1:
            raise ValueError(f"the moves form a cycle through node {c}: a policy is acyclic")
        if state[c] == 0:
            state[c] = 1
            stack.append((c, 0))
    post.reverse()
    return post


def malformed(raw: Any) -> tuple[str, str] | None:
    """Where a policy's JSON has the wrong shape for the reader, in the file's own terms
    (``(place, what)``), or None."""
    nodes = raw.get("nodes") if isinstance(raw, dict) else None
    if not isinstance(nodes, list):
        return "nodes", "nodes must be a list of node objects"
    for i, n in enumerate(nodes):
        if not isinstance(n, dict):
            return f"nodes[{i}]", f"a node must be an object, got {n!r:.40}"
        moves = n.get("moves", [])
        if not isinstance(moves, list):
            return f"nodes[{i}].moves", "moves must be a list of move objects"
        for j, m in enumerate(moves):
            if not isinstance(m, dict):
                return f"nodes[{i}].moves[{j}]", f"a move must be an object, got {m!r:.40}"
    return None


def _finite(text: str) -> float:
    """Return the number ``text``, refusing one too large for a float (``1e999``), which
    Python's JSON reader would otherwise read as infinity."""
    x = float(text)
    if x in (float("inf"), float("-inf")):
        raise ValueError(f"{text[:40]} is too large a number for a policy")
    return x


def _no_constant(name: str) -> Any:
    """Refuse ``NaN`` and ``Infinity``, which Python's JSON reader would otherwise accept."""
    raise ValueError(f"{name} is not a number JSON allows")


def _checked(xs: list[Any], check: Callable[[], None] | None) -> Iterator[Any]:
    """``xs``, calling ``check`` every 256 items (a limit may stop a long write)."""
    if check is None:
        yield from xs
        return
    for i, x in enumerate(xs):
        if not i & 255:
            check()
        yield x


def _dumps(x: Any) -> str:
    return json.dumps(x, sort_keys=True)


_NODE_KEYS = ("id", "copresent", "k", "worlds", "divergence", "world_diffs", "state",
              "robot_agenda", "human_agenda", "to_move", "value", "goal")


def _node(n: dict[str, Any]) -> PolicyNode:
    extra = set(n) - {*_NODE_KEYS, "moves", "hypotheses"}
    if extra:
        raise TypeError(f"unexpected field(s) {', '.join(sorted(extra))} in a node")
    moves = n["moves"]
    if not isinstance(moves, list):
        raise TypeError("moves must be a list")
    hyps = n.get("hypotheses", [])
    if not isinstance(hyps, list) or not all(
            isinstance(h, list) and all(isinstance(x, str) for x in h) for h in hyps):
        raise TypeError("hypotheses must be a list of lists of strings")
    return PolicyNode(**{k: n[k] for k in _NODE_KEYS},
                      moves=[PolicyMove(**m) for m in moves], hypotheses=hyps)


def _nodes_v1(raw: list[Any]) -> list[PolicyNode]:
    """Version 1: the tree in preorder, each node holding the move into it. The moves go onto
    the edges; every tree node stays a node of its own."""
    move_keys = ("agent", "kind", "action", "name", "args", "cost")
    nodes = []
    for n in raw:
        extra = set(n) - {*_NODE_KEYS, *move_keys, "children", "told"}
        if extra:
            raise TypeError(f"unexpected field(s) {', '.join(sorted(extra))} in a node")
        nodes.append(PolicyNode(**{k: n[k] for k in _NODE_KEYS}))
    for i, n in enumerate(raw):
        children = n["children"]
        if not isinstance(children, list):
            raise TypeError(f"nodes[{i}].children must be a list")
        for c in children:
            if not isinstance(c, int) or isinstance(c, bool) or not 0 <= c < len(raw):
                raise ValueError(f"nodes[{i}].children: child {c!r} is out of range")
            kid = raw[c]
            nodes[i].moves.append(PolicyMove(**{k: kid[k] for k in move_keys}, to=c,
                                             told=kid.get("told", [])))
    return nodes


def label_key(label: str) -> str:
    """A move label as labels are compared: spaces do not count (``place(r,box1)`` is
    ``place(r, box1)``)."""
    return "".join(label.split())


def num(c: Cost | float) -> int | float:
    if isinstance(c, Fraction):
        return int(c) if c.denominator == 1 else float(c)
    return c


def timeline(policy: Policy, branch: Branch) -> dict[str, Any]:
    """Turn-taking steps while together; parallel lanes between separation and reunion."""
    r_name, h_name = policy.agents["robot"], policy.agents["human"]
    steps: list[dict[str, Any]] = []
    lanes: dict[str, list[str]] | None = None
    prev = branch[0]
    for n in branch[1:]:
        assert n.move is not None
        agent, action = n.move.agent, n.move.action
        if prev.copresent:
            steps.append({"agent": agent, "action": action})
        else:
            if lanes is None:
                lanes = {r_name: [], h_name: []}
                steps.append({"parallel": lanes})
            lanes[agent].append(action)
        if n.copresent:
            lanes = None
        prev = n
    return {"leaf": branch[-1].id, "steps": steps}


__all__ = ["COMM_KINDS", "FORMAT", "POLICY_FIX", "READS", "VERSION", "VERSION_LIFTED", "Branch",
           "Cost", "malformed",
           "PathStep", "Policy", "PolicyMove", "PolicyNode", "label_key", "num", "timeline",
           "topological_order"]
