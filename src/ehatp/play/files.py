"""The files of ``ehatp play``: the problem and policy a session plays, with the hashes its log
records, and the log folder (one file per session). See docs/play.md."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..formats.policy import Policy
from ..formats.policy_check import check_policy_problem, read_policy
from ..formats.problem_toml import load
from ..model.options import ObjectiveKind
from ..model.problem import Problem
from .session import FileLog, Source, policy_hash, sha256
from .views import ViewHook, load_view, view_for

if TYPE_CHECKING:
    from ..search.planner import Relabeler


@dataclass
class Setup:
    """What every session of one ``ehatp play`` plays: the problem, the policy, where they
    come from (with their hashes), the view hook, and a preferences problem's explored graph
    (docs/concurrent.md C11: kept for the experimenter's profile switches; read only, shared
    by the sessions)."""

    problem: Problem
    policy: Policy
    source: Source
    view: ViewHook | None
    graph: Relabeler | None = None


def load_setup(problem_path: Path, policy_path: Path | None, view: str | None = None,
               *, want: dict[str, Any] | None = None, keep_graph: bool = True) -> Setup:
    """Return the setup of ``problem_path`` and ``policy_path`` (solved now when None) and
    the view hook ``view`` names (``none``, ``module:function``, or None: the domain's own).
    A preferences problem (``[objective] kind = "preferences"``) is searched once here with
    its graph kept (``solve(problem, keep_graph=True)``, C11), for the experimenter's profile
    switches (not with ``keep_graph`` False: no search with ``--policy``, and no switching);
    without ``--policy`` that search's policy is the one played. With ``want`` (a
    log's start record) the files' hashes must be the log's. :class:`InputError` (``file:
    problem; fix``) when a file cannot be read, the problem has no policy, or a hash differs."""
    try:
        raw = problem_path.read_bytes()
    except OSError as e:
        raise InputError(str(problem_path), "", f"cannot read ({e.strerror or e})",
                         "give a problem TOML file") from None
    problem = load(problem_path)
    p_hash = sha256(raw)
    if want is not None and want.get("problem_hash") != p_hash:
        raise InputError(str(problem_path), "", "is not the problem file the session played "
                         f"(its hash is {p_hash}, the log's {want.get('problem_hash')})",
                         "give the session's problem file as PROBLEM")
    prefs = keep_graph and problem.objective.kind == ObjectiveKind.PREFERENCES
    graph = None
    if policy_path is not None:
        policy = read_policy(policy_path)
        check_policy_problem(policy, policy_path, problem)
        if prefs:
            from ..search.planner import solve

            graph = solve(problem, keep_graph=True).graph  # None: stopped at a limit
    else:
        from ..search.planner import solve

        result = solve(problem, keep_graph=prefs)
        graph = result.graph
        if result.policy is None:
            raise InputError(str(problem_path), "", "has no policy to play: "
                             f"{result.reason or result.status}",
                             "fix the problem, or give a policy with --policy")
        policy = result.policy
    pol_hash = policy_hash(policy)
    if want is not None and want.get("policy_hash") != pol_hash:
        where = str(policy_path) if policy_path is not None else f"{problem_path} (solved now)"
        raise InputError(where, "", "is not the policy the session played (its hash is "
                         f"{pol_hash}, the log's {want.get('policy_hash')})",
                         "give the session's policy with --policy")
    if view == "none":
        hook, name = None, "none"
    elif view is not None:
        try:
            hook, name = load_view(view), view
        except ValueError as e:
            raise InputError("--view", "", str(e), "give module:function, or none") from None
    else:
        hook = view_for(problem.domain.name)
        name = "default" if hook is None else f"{hook.__module__}:{hook.__name__}"
    source = Source(str(problem_path.resolve()), p_hash,
                    None if policy_path is None else str(policy_path.resolve()), pol_hash, name)
    return Setup(problem, policy, source, hook, graph)


def log_folder(path: Path) -> Path:
    """Return ``path`` after making sure it is a folder (created with its parents)."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(str(path), "", f"cannot make the log folder ({e.strerror or e})",
                         "give a folder you can write to with --log-dir") from None
    if not path.is_dir():
        raise InputError(str(path), "", "is not a folder", "give a folder with --log-dir")
    return path


def session_log(folder: Path, session_id: str) -> FileLog:
    """Return a new log file for session ``session_id`` in ``folder``, named by the time the
    session starts and its id (``20261126T040937Z-<id>.jsonl``)."""
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
    return FileLog(folder / f"{stamp}-{session_id}.jsonl")


__all__ = ["Setup", "load_setup", "log_folder", "session_log"]
