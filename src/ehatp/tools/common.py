"""What every command shares: how a user's mistake becomes one line and exit code 2."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

import typer

from ..errors import EhatpError, InputError
from ..model.domain import DomainError

EXIT_OK, EXIT_NO_POLICY, EXIT_BAD_INPUT = 0, 1, 2


def die(message: str, code: int = EXIT_BAD_INPUT) -> NoReturn:
    """One line on stderr, then exit; newlines are folded so the promise of one line holds."""
    typer.echo(f"error: {' '.join(message.split())}", err=True)
    raise typer.Exit(code)


@contextmanager
def user_errors(file: Path | str) -> Iterator[None]:
    """Turn the errors a user can cause with ``file`` into one line and exit code 2."""
    try:
        yield
    except InputError as e:
        die(e.line())
    except DomainError as e:
        die(f"{file}: the domain is malformed: {e}; fix the domain definition")
    except EhatpError as e:
        die(f"{file}: {e}")
