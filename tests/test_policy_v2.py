"""Policy format version 2 (docs/policy-format.md): the policy as a graph of distinct states
with the moves on its edges; its size, its counts, its schema, version 1 files, and the
validator's walk over shared nodes."""

from __future__ import annotations

import copy
import json
import re
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from typer.testing import CliRunner

import ehatp
from ehatp import Policy
from ehatp.check.validator import validate
from ehatp.cli.app import app
from ehatp.cli.common import read_policy
from ehatp.formats.policy import PolicyMove

from .conftest import DATA, EXAMPLES, EXAMPLES_DIR, ROOT, Example, solved_v2
from .policy_v1 import tree_dict

V1 = DATA / "p4-v1.json"  # written by the version 1 writer (the tree, timelines included)
CUBES8 = DATA / "cubes-8.toml"
SCHEMA = ROOT / "src" / "ehatp" / "formats" / "policy.schema.json"
P4 = EXAMPLES_DIR / "cubes" / "p4.toml"
MAX_BYTES_PER_NODE = 2048


def written(policy: Policy, tmp_path: Path, name: str = "policy.json") -> Path:
    f = tmp_path / name
    policy.write(f)
    return f


def invoke(*args: object) -> Any:
    return CliRunner().invoke(app, [str(a) for a in args])


# -- the format --------------------------------------------------------------------------------

def test_a_policy_with_shared_nodes_round_trips_byte_identically(tmp_path: Path) -> None:
    problem, policy = solved_v2("cubes/p4")
    copies = policy.path_counts()
    assert max(copies) > 1  # some nodes are reached by several paths
    f = written(policy, tmp_path)
    text = f.read_text(encoding="utf-8")
    again = Policy.load(f)
    assert again.to_json() == text
    assert [n.to_dict() for n in again.nodes] == [n.to_dict() for n in policy.nodes]
    # one line per node, and the same problem gives the same bytes
    assert sum(line.startswith('  {"copresent"') for line in text.splitlines()) == len(
        policy.nodes)
    assert ehatp.solve(problem, expand=True).policy.to_json() == text  # type: ignore[union-attr]


def test_nodes_are_states_and_moves_are_edges(tmp_path: Path) -> None:
    _, policy = solved_v2("cubes/p4")
    data = json.loads(written(policy, tmp_path).read_text(encoding="utf-8"))
    assert data["version"] == 2 and "timelines" not in data
    for i, node in enumerate(data["nodes"]):
        assert node["id"] == i
        assert not {"agent", "kind", "action", "cost", "told", "children"} & node.keys()
        for move in node["moves"]:
            assert set(move) == {"agent", "kind", "action", "name", "args", "cost", "to",
                                 "told"}
    # a node entered by two different moves: the moves carry what differs
    into: dict[int, set[str]] = {}
    for _, m in policy.edges():
        into.setdefault(m.to, set()).add(m.action)
    assert any(len(labels) > 1 for labels in into.values())


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_counts_over_the_graph_equal_the_tree_unfolding(example: Example) -> None:
    _, policy = solved_v2(example)
    branches = policy.branches()
    assert len(branches) == policy.leaves == policy.count_branches()
    if policy.step_options is not None:  # joint steps: version 1 has no "step" on a move
        return
    tree = tree_dict(policy)["nodes"]  # the version 1 tree, enumerated node by node
    assert len(tree) == policy.tree_size() >= len(policy.nodes)
    assert sum(1 for n in tree if not n["children"]) == policy.leaves
    assert sum(1 for n in tree if n["kind"] in ("inform", "ask") or n["told"]) == \
        policy.communications == policy.count_communications()
    assert len(policy.timelines()) == policy.leaves


@pytest.mark.parametrize("example", EXAMPLES, ids=str)
def test_every_example_validates_from_its_file(example: Example, tmp_path: Path) -> None:
    problem, policy = solved_v2(example)
    loaded = Policy.load(written(policy, tmp_path))
    read_policy(written(policy, tmp_path))  # its counts match its graph
    r = ehatp.validate(problem, loaded)
    assert r.ok, "\n".join(r.violations)
    assert r.nodes_checked == len(loaded.nodes)  # each node once
    assert r.branches_checked == loaded.leaves


# -- size --------------------------------------------------------------------------------------

@pytest.mark.parametrize("problem", [*EXAMPLES, CUBES8], ids=lambda p: p.stem)
def test_file_size_is_proportional_to_distinct_nodes(problem: Example | Path,
                                                     tmp_path: Path) -> None:
    _, policy = solved_v2(problem)
    size = written(policy, tmp_path).stat().st_size
    assert size <= MAX_BYTES_PER_NODE * len(policy.nodes), (size, len(policy.nodes))


def test_a_large_policy_is_a_small_graph(tmp_path: Path) -> None:
    problem, policy = solved_v2(CUBES8)
    nodes, tree = len(policy.nodes), policy.tree_size()
    assert tree > 20 * nodes  # the tree unfolding repeats the shared states many times
    assert policy.leaves > nodes
    f = written(policy, tmp_path)
    assert f.stat().st_size <= MAX_BYTES_PER_NODE * nodes
    # reading, checking and validating it are linear in the graph, not in its branches
    loaded = read_policy(f)
    r = validate(problem, loaded)
    assert r.ok and r.nodes_checked == nodes and r.branches_checked == policy.leaves
    # show prints each node once and only the first timelines
    out = invoke("show", f).stdout
    refs = len(re.findall(r"-> see node \d", out))
    assert refs == sum(len(n.moves) for n in policy.nodes) - nodes + 1
    assert f"Timelines ({policy.leaves} branches; the first 100 are shown)" in out
    assert out.count("\nbranch ") == 100


# -- the schema --------------------------------------------------------------------------------

def test_the_schema_accepts_every_shipped_examples_policy(tmp_path: Path) -> None:
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    check = jsonschema.Draft202012Validator(schema)
    for example in EXAMPLES:
        _, policy = solved_v2(example)
        data = json.loads(written(policy, tmp_path).read_text(encoding="utf-8"))
        errors = [f"{list(e.absolute_path)}: {e.message}" for e in check.iter_errors(data)]
        assert errors == [], (example.name, errors[:3])
    # and it is strict: a version 1 file, a move without its target, a stray field
    assert list(check.iter_errors(json.loads(V1.read_text(encoding="utf-8"))))
    data = json.loads(written(solved_v2(EXAMPLES[0]).policy, tmp_path).read_text(encoding="utf-8"))
    bad = copy.deepcopy(data)
    del bad["nodes"][0]["moves"][0]["to"]
    assert list(check.iter_errors(bad))
    bad = copy.deepcopy(data)
    bad["nodes"][0]["action"] = "start"
    assert list(check.iter_errors(bad))


# -- version 1 files ---------------------------------------------------------------------------

def test_version_1_files_still_load_show_validate_and_render(tmp_path: Path) -> None:
    raw = json.loads(V1.read_text(encoding="utf-8"))
    assert raw["version"] == 1
    policy = read_policy(V1)  # the tree becomes a graph: one node per tree node
    assert len(policy.nodes) == len(raw["nodes"]) == policy.tree_size()
    assert (policy.leaves, policy.communications) == (raw["leaves"], raw["communications"])
    assert policy.count_branches() == len(raw["timelines"])
    assert [t["steps"] for t in policy.timelines()] == [t["steps"] for t in raw["timelines"]]
    assert tree_dict(policy) == raw  # nothing lost (and tests.policy_v1 writes that shape)
    problem = ehatp.load(P4)
    r = validate(problem, policy)
    assert r.ok, r.violations
    assert r.nodes_checked == len(raw["nodes"]) and r.branches_checked == raw["leaves"]
    shown = invoke("show", V1)
    assert shown.exit_code == 0 and not re.search(r"see node \d", shown.stdout)  # a tree
    assert invoke("validate", P4, V1).exit_code == 0
    assert invoke("render", V1).exit_code == 0
    # written again, it is version 2 with the same tree unfolding
    again = Policy.load(written(policy, tmp_path))
    assert again.to_dict()["version"] == 2
    assert again.tree_size() == len(raw["nodes"]) and again.leaves == raw["leaves"]


# -- the validator over shared nodes -----------------------------------------------------------

def _same_facts_pair(policy: Policy) -> tuple[tuple[int, int], int]:
    """A move (node id, move index) and another node than its own, entered by the same move
    label, whose recorded facts are the same: the states differ only in what the file does
    not record (the count of passive moves, a forced wait)."""
    def facts(i: int) -> str:
        d = policy.nodes[i].to_dict()
        return json.dumps({k: v for k, v in d.items() if k not in ("id", "moves", "value")},
                          sort_keys=True)

    seen: dict[tuple[str, str], int] = {}
    for n in policy.nodes:
        for j, m in enumerate(n.moves):
            other = seen.setdefault((m.action, facts(m.to)), m.to)
            if other != m.to:
                return (n.id, j), other
    raise LookupError("no such pair")


def _below_the_root(data: dict[str, Any]) -> None:
    """Drop the nodes no move leads to any more, renumber, and recount (as a file would be)."""
    nodes = data["nodes"]
    keep, stack = {0}, [0]
    while stack:
        for m in nodes[stack.pop()]["moves"]:
            if m["to"] not in keep:
                keep.add(m["to"])
                stack.append(m["to"])
    new = {old: i for i, old in enumerate(sorted(keep))}
    data["nodes"] = [nodes[old] for old in sorted(keep)]
    for n in data["nodes"]:
        n["id"] = new[n["id"]]
        for m in n["moves"]:
            m["to"] = new[m["to"]]
    policy = Policy.from_dict(data)
    data.update(leaves=policy.count_branches(), communications=policy.count_communications())


def test_the_validator_rejects_a_shared_node_reached_in_two_states(tmp_path: Path) -> None:
    problem, policy = solved_v2("cubes/p4")
    (at, j), other = _same_facts_pair(policy)
    data = policy.to_dict()
    data["nodes"][at]["moves"][j]["to"] = other  # two paths, two states, one node
    _below_the_root(data)
    f = tmp_path / "merged.json"
    f.write_text(json.dumps(data), encoding="utf-8")
    r = validate(problem, Policy.load(f))
    assert not r.ok
    shared = [v for v in r.violations if "is shared, but this path reaches it in another "
              "state than its first one" in v]
    assert shared, r.violations
    assert "passive count" in shared[0] or "forced" in shared[0]
    # the recorded facts agree, so only the recomputed state tells them apart
    assert not any("recorded facts differ" in v for v in r.violations)


def test_a_shared_node_is_checked_once(tmp_path: Path) -> None:
    problem, policy = solved_v2("cubes/p4")
    shared = max(range(len(policy.nodes)), key=lambda i: (policy.path_counts()[i], -i))
    data = policy.to_dict()
    data["nodes"][shared]["worlds"] += 5
    r = validate(problem, Policy.from_dict(data))
    facts = [v for v in r.violations if "recorded facts differ" in v]
    assert len(facts) == 1 and f"node {shared} " in facts[0]
    # a wrong cost on one move into it is that move's fault only
    data = policy.to_dict()
    into = [(n.id, k) for n in policy.nodes for k, m in enumerate(n.moves) if m.to == shared]
    assert len(into) > 1
    n, k = into[-1]
    data["nodes"][n]["moves"][k]["cost"] = 9
    r = validate(problem, Policy.from_dict(data))
    costs = [v for v in r.violations if "cost is 9, but the move costs" in v]
    assert len(costs) == 1


def test_a_cycle_or_an_orphan_is_refused_when_read(tmp_path: Path) -> None:
    _, policy = solved_v2("cubes/p2")
    data = policy.to_dict()
    leaf = next(n for n in data["nodes"] if not n["moves"])
    leaf["moves"].append({**PolicyMove("H", "pass", "pass", "pass", [], 1, 1).to_dict()})
    f = tmp_path / "cycle.json"
    f.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ehatp.InputError, match="cycle through node 1"):
        Policy.load(f)
    data = policy.to_dict()
    data["nodes"].append({**data["nodes"][-1], "id": len(data["nodes"])})
    f.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ehatp.InputError, match="1 node"):
        Policy.load(f)
