"""Errors that reach the user as one clear line (the CLI exits with code 2 on them)."""

from __future__ import annotations


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
