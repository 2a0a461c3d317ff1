"""``ehatp import-hddl``: an HDDL domain and problem as one agent's task model, written as a
Python domain module and a problem TOML (:mod:`ehatp.formats.hddl`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import HddlMissing, HddlUnsupported, printable
from ..formats.hddl import import_hddl
from .common import command_app, die, user_errors

app = command_app()


@app.command("import-hddl")
def import_hddl_cmd(
    domain: Path = typer.Argument(..., help="the HDDL domain file"),
    problem: Path = typer.Argument(..., help="the HDDL problem file"),
    agent: str = typer.Option("robot", "--agent", help="whose HTN it is: robot or human"),
    sidecar: Path | None = typer.Option(
        None, "--sidecar", help="observability, co-presence, the other agent (TOML or .py)"),
    out: Path | None = typer.Option(
        None, "--out", help="the domain module to write (default: DOMAIN-NAME.py here); "
        "the problem is written beside it with the suffix .toml"),
) -> None:
    """Import an HDDL domain and problem as one agent's task model: writes a Python domain
    module and a problem TOML that `ehatp solve` reads (docs/hddl.md). Exit 2 when the
    HDDL uses something ehatp cannot express (the line says what)."""
    for f in (domain, problem, *([sidecar] if sidecar else [])):
        if not f.is_file():
            die(f"{f}: no such file; give an existing file")
    with user_errors(domain):
        try:
            imp = import_hddl(domain, problem, agent=agent, sidecar=sidecar,
                              module_file=out.name if out else None)
        except HddlUnsupported as e:  # its message names the file (and place) at fault
            die(str(e))
        except HddlMissing as e:
            die(f"{domain}: {e}")
        target = out or Path(imp.module_file)
        imp.domain(target.resolve())  # the module must build before it is written
        mod, prob = imp.write(target)
    typer.echo(f"wrote {mod} (the domain, {agent}'s HTN) and {prob} (the problem)")
    for n in imp.notes:
        typer.echo(f"  note: {printable(n)}")
    typer.echo(f"next: ehatp solve {prob}")
