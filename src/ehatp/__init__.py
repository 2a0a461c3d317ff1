"""ehatp: the Epistemic Human-Aware Task Planner.

>>> import ehatp
>>> problem = ehatp.load("examples/cubes/p2.toml")      # doctest: +SKIP
>>> result = ehatp.solve(problem)                       # doctest: +SKIP
>>> result.policy.cost, result.stats["distinct"]        # doctest: +SKIP
>>> ehatp.validate(problem, result.policy)              # doctest: +SKIP
"""

from typing import TYPE_CHECKING

from .check.validator import Report
from .check.validator import validate as _validate
from .errors import EhatpError, InputError
from .model.domain import (
    HIDDEN,
    INFERABLE,
    AgentModel,
    Domain,
    DomainError,
    assign,
    domain_factory,
    for_each,
    observable,
    when,
)
from .model.formula import FALSE, TRUE, Var, eq, exists, forall
from .model.options import (
    Communication,
    HumanModel,
    InformWhere,
    Objective,
    ObjectiveKind,
    Passes,
    Relevance,
    Speech,
)
from .model.problem import BeliefWorld, Costs, Limits, Problem, load
from .policy_format import Policy

if TYPE_CHECKING:
    from .search.planner import Result, solve
    from .tools.executor import ExecutionError, Executor, PolicyMismatch, UncoveredHumanAction

__version__ = "0.2.0"


def validate(problem: Problem, policy: Policy) -> Report:
    """Check ``policy`` against ``problem`` with the independent validator."""
    return _validate(problem, policy)


_LAZY = {"solve": "search.planner", "Result": "search.planner", "Executor": "tools.executor",
         "UncoveredHumanAction": "tools.executor", "ExecutionError": "tools.executor",
         "PolicyMismatch": "tools.executor"}


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
    "Relevance", "Speech",
    "FALSE", "HIDDEN", "INFERABLE", "TRUE", "AgentModel", "BeliefWorld", "Costs", "Domain",
    "DomainError", "EhatpError", "ExecutionError", "Executor", "InputError", "Limits",
    "Policy", "PolicyMismatch", "Problem", "Result", "UncoveredHumanAction", "Var", "eq", "exists",
    "domain_factory", "for_each", "forall", "load", "observable", "solve", "validate", "when",
    "assign",
]
