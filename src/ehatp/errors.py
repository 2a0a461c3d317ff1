"""Every error ehatp reports to its users, each as one clear line (the CLI exits with code 2 on
bad input; ``ehatp.cli.common.user_errors`` says how each one is worded).

One module, so that a caller catches :class:`EhatpError` for "the user's mistake or situation,
not a bug", and a subclass where it wants to tell one case apart.
"""

from __future__ import annotations

import re

# C0 controls, DEL and C1 controls: what a terminal may read as a command (ESC starts the
# escape codes that move the cursor, set the title, or write to the clipboard)
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")
_CONTROL_BUT_LINES = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def control_char(text: str) -> str | None:
    """Return the first control character in ``text`` (newline and tab included), or None."""
    m = _CONTROL.search(text)
    return None if m is None else m.group()


def printable(text: str, *, lines: bool = False) -> str:
    """Return ``text`` with every control character written as its Python escape (ESC as
    ``\\x1b``), so that printing it to a terminal shows it instead of obeying it. With
    ``lines`` newlines and tabs stay as they are (text of several lines)."""
    pattern = _CONTROL_BUT_LINES if lines else _CONTROL
    return pattern.sub(lambda m: repr(m.group())[1:-1], text)


class EhatpError(Exception):
    """Base of the errors ehatp reports to users."""


class InputError(EhatpError):
    """Bad input: names the file, the place in it, what is wrong and what to do."""

    def __init__(self, file: str, place: str, problem: str, fix: str = "") -> None:
        self.file, self.place, self.problem, self.fix = file, place, problem, fix
        super().__init__(self.line())

    def line(self) -> str:
        where = f"{self.file}:{self.place}" if self.place else self.file
        return f"{where}: {self.problem}" + (f"; {self.fix}" if self.fix else "")


# --- the model -------------------------------------------------------------------------------


class DomainError(EhatpError):
    """A mistake in a domain definition (raised while the domain module is built)."""


# --- execution (ehatp.run) -------------------------------------------------------------------


class ExecutionError(EhatpError):
    """The execution cannot go on (wrong turn, or the policy and the problem disagree)."""


class PolicyMismatch(ExecutionError):
    """The policy does not fit the problem: its nodes disagree with the semantics."""


class UncoveredHumanAction(ExecutionError):
    """The human did something the policy has no branch for.

    ``action`` is what was observed, ``expected`` the labels the policy covers here,
    ``possible`` every move the human model allows here, ``reason`` why it is not covered.
    """

    def __init__(self, action: str, expected: list[str], possible: list[str],
                 reason: str) -> None:
        self.action, self.expected, self.possible, self.reason = action, expected, possible, reason
        super().__init__(f"{reason}; the policy expects "
                         + (" or ".join(expected) if expected else "no human action here"))


# --- formats and experiments -----------------------------------------------------------------


class HddlUnsupported(EhatpError):
    """The HDDL input uses something ehatp cannot express; ``str(e)`` is one line saying
    what (docs/hddl.md lists what maps)."""


class HddlMissing(EhatpError):
    """unified-planning, which reads HDDL, is not installed."""


class PolicyTooLarge(EhatpError):
    """A lifted policy (format version 3) stands for more nodes over the real objects than a
    reader that needs them all was allowed to make (``limit``); ``canonical`` is the lifted
    policy's own node count. ``str(e)`` says so in words."""

    def __init__(self, limit: int, canonical: int) -> None:
        self.limit, self.canonical = limit, canonical
        super().__init__(f"the lifted policy ({canonical:,} canonical nodes) stands for more "
                         f"than {limit:,} nodes over the real objects")


class DotMissing(EhatpError):
    """Graphviz's ``dot`` program is not installed (``ehatp render --format svg``)."""


class ExamplesNotFound(EhatpError):
    """The example problems are neither in the package nor in a source checkout."""


__all__ = ["DomainError", "DotMissing", "EhatpError", "ExamplesNotFound", "ExecutionError",
           "HddlMissing", "HddlUnsupported", "InputError", "PolicyMismatch", "PolicyTooLarge",
           "UncoveredHumanAction", "control_char", "printable"]
