"""ehatp: the Epistemic Human-Aware Task Planner.

>>> import ehatp
>>> problem = ehatp.load("examples/cubes/p2.toml")      # doctest: +SKIP
>>> result = ehatp.solve(problem)                       # doctest: +SKIP
>>> result.policy.cost, result.stats["distinct"]        # doctest: +SKIP
>>> ehatp.validate(problem, result.policy)              # doctest: +SKIP
"""

from .check.validator import Report
from .check.validator import validate as _validate
from .errors import EhatpError, InputError
from .model.domain import (
    HIDDEN,
    INFERABLE,
    AgentModel,
    Domain,
    DomainError,
    for_each,
    observable,
    when,
)
from .model.formula import FALSE, TRUE, Var, eq, exists, forall
from .model.problem import BeliefWorld, Costs, Limits, Options, Problem, load
from .search.planner import Result, solve
from .search.policy import Policy

__version__ = "0.1.0"


def validate(problem: Problem, policy: Policy) -> Report:
    """Check ``policy`` against ``problem`` with the independent validator."""
    return _validate(problem, policy)


_TOOLS = {"Executor", "UncoveredHumanAction", "ExecutionError", "PolicyMismatch"}


def __getattr__(name: str) -> object:
    # the execution API lives in tools/; import it only when asked for
    if name in _TOOLS:
        from .tools import executor

        return getattr(executor, name)
    raise AttributeError(f"module 'ehatp' has no attribute {name!r}")


__all__ = [
    "FALSE", "HIDDEN", "INFERABLE", "TRUE", "AgentModel", "BeliefWorld", "Costs", "Domain",
    "DomainError", "EhatpError", "ExecutionError", "Executor", "InputError", "Limits", "Options",
    "Policy", "PolicyMismatch", "Problem", "Result", "UncoveredHumanAction", "Var", "eq", "exists",
    "for_each", "forall", "load", "observable", "solve", "validate", "when",
]
