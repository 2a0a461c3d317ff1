"""ehatp: the Epistemic Human-Aware Task Planner.

>>> import ehatp
>>> problem = ehatp.load("examples/cubes/p2.toml")      # doctest: +SKIP
>>> result = ehatp.solve(problem)                       # doctest: +SKIP
>>> result.policy.cost, result.stats["distinct"]        # doctest: +SKIP
>>> ehatp.validate(problem, result.policy)              # doctest: +SKIP
>>> ehatp.explore(result.policy)                        # doctest: +SKIP

The layers, from the bottom: ``model`` (the DSL, problems, grounding, HTN: data), ``epistemic``
(the semantics), ``search`` (the planner) and ``check`` (the validator), then ``formats`` (files
in and out), ``run`` (executing a policy), ``experiments`` and ``cli`` (docs/architecture.md).
"""

import sys
from typing import TYPE_CHECKING, Any

from .errors import (
    DomainError,
    EhatpError,
    ExecutionError,
    InputError,
    PolicyMismatch,
    UncoveredHumanAction,
)
from .formats.policy import Policy
from .formats.problem_toml import load
from .model.domain import (
    HIDDEN,
    INFERABLE,
    AgentModel,
    Domain,
    DomainMetric,
    assign,
    domain_factory,
    for_each,
    observable,
    when,
)
from .model.formula import FALSE, TRUE, Var, eq, exists, forall
from .model.options import (
    Communication,
    Commute,
    Estimate,
    HumanModel,
    InformWhere,
    Metric,
    Objective,
    ObjectiveKind,
    Passes,
    Relevance,
    Speech,
    StepFirst,
    StepMode,
    Steps,
    Witness,
)
from .model.problem import BeliefWorld, Costs, Limits, Problem

if TYPE_CHECKING:
    from collections.abc import Callable

    from .check.validator import Report
    from .formats.render import Explorer
    from .run.executor import Executor
    from .search.planner import Result, solve

__version__ = "0.3.0"


def validate(problem: Problem, policy: Policy, *,
             check: "Callable[[], None] | None" = None) -> "Report":
    """Check ``policy`` against ``problem`` with the independent validator (loaded on first
    use, so that ``import ehatp`` and ``ehatp --help`` stay quick). ``check``, e.g. a
    ``Budget``'s, is called now and then and may raise to stop the check (no verdict)."""
    from .check.validator import validate as _validate

    return _validate(problem, policy, check=check)


def explore(policy: Policy) -> "Explorer":
    """``policy`` as the offline explorer (``ehatp render --format html``), for a notebook to
    show: the last value of a cell, or ``display(ehatp.explore(policy))``. Inside IPython a
    Policy shows itself so already (docs/notebook.md)."""
    from .formats.render import Explorer

    return Explorer(policy)


def _policy_html(policy: Policy) -> str:
    from .formats.render import notebook_html

    return notebook_html(policy)


def _show_policies_in_notebooks() -> None:
    """Inside IPython (a Jupyter kernel), display every Policy as the explorer: an HTML
    formatter for the type, registered by name so that nothing is imported until a policy is
    shown. Outside IPython, nothing (IPython is never imported here)."""
    ipython: Any = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is None:
        return
    try:
        html = shell.display_formatter.formatters["text/html"]
        html.for_type_by_name("ehatp.formats.policy", "Policy", _policy_html)
    except (AttributeError, KeyError):  # an IPython without HTML display: keep its repr
        pass


_show_policies_in_notebooks()

_LAZY = {"solve": "search.planner", "Result": "search.planner", "Executor": "run.executor",
         "Report": "check.validator"}


def __getattr__(name: str) -> object:
    # the planner and the execution API load only when asked for, so that importing the
    # validator (or reading a policy file) never loads the search
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module 'ehatp' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f".{where}", __name__), name)


__all__ = [
    "Communication", "HumanModel", "InformWhere", "Objective", "ObjectiveKind", "Passes",
    "Relevance", "Speech", "Steps", "StepMode", "StepFirst", "Witness", "Commute",
    "Estimate", "Metric", "DomainMetric",
    "FALSE", "HIDDEN", "INFERABLE", "TRUE", "AgentModel", "BeliefWorld", "Costs", "Domain",
    "DomainError", "EhatpError", "ExecutionError", "Executor", "InputError", "Limits",
    "Policy", "PolicyMismatch", "Problem", "Result", "UncoveredHumanAction", "Var", "eq", "exists",
    "domain_factory", "explore", "for_each", "forall", "load", "observable", "solve", "validate",
    "when", "assign",
]
