"""``ehatp play`` on the command line: ``--replay``, and bad input as one line (exit 2)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ehatp.cli.app import app
from ehatp.play.session import PlaySession

from .conftest import ROOT
from .play_check import PROBLEMS, branches
from .test_play import needs_web


def run(*args: Any) -> Any:
    return CliRunner().invoke(app, [str(a) for a in args])


def test_play_replay_prints_the_session_and_checks_it(tmp_path: Path) -> None:
    from ehatp.play.files import load_setup, session_log

    setup = load_setup(ROOT / PROBLEMS["p2"], None)
    log = session_log(tmp_path, "abc")
    s = PlaySession(setup.problem, setup.policy, setup.source, session_id="abc", log=log)
    s.start()
    s.run_robot()
    for m in branches(s.ex)[0]:
        s.choose(m)
        s.run_robot()
    log.close()
    r = run("play", "--replay", log.path)
    assert r.exit_code == 0, r.output
    assert "1. H move(mt, ot)  (node 1)" in r.output
    assert "R is out of sight." in r.output
    assert r.output.rstrip().endswith("goal after 7 steps, cost 7")
    # another problem file than the session's: one line, exit 2
    bad = run("play", "--replay", log.path, ROOT / "examples/cubes/p1.toml")
    assert bad.exit_code == 2 and "is not the problem file the session played" in bad.output
    # a log edited by hand differs: exit 1
    lines = log.path.read_text(encoding="utf-8").splitlines()
    i = next(i for i, line in enumerate(lines) if '"type": "message"' in line)
    lines[i] = lines[i].replace("You: ", "You did: ")
    log.path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    differs = run("play", "--replay", log.path)
    assert differs.exit_code == 1 and "replay differs from the log at record" in differs.output


def test_play_without_the_web_extra_says_how_to_install_it(monkeypatch: pytest.MonkeyPatch
                                                            ) -> None:
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "starlette" else real(name, *a))
    r = run("play", ROOT / PROBLEMS["p2"], "--no-browser")
    assert r.exit_code == 2
    assert r.output.strip() == ("error: ehatp play needs Starlette and uvicorn, which are not "
                                "installed; install them with: pip install 'ehatp[play]'")


@needs_web
def test_play_on_a_port_in_use_is_one_line(tmp_path: Path) -> None:
    from ehatp.play.server import listen

    sock = listen("127.0.0.1", 0)
    try:
        r = run("play", ROOT / PROBLEMS["p2"], "--no-browser", "--port",
                sock.getsockname()[1], "--log-dir", tmp_path / "logs")
    finally:
        sock.close()
    assert r.exit_code == 2
    assert re.fullmatch(r"error: --port \d+: cannot listen on 127\.0\.0\.1:\d+ \(.*\); choose "
                        r"another port with --port, or --port 0 for any free one\n", r.output)
    assert (tmp_path / "logs").is_dir()


def test_play_with_bad_input_is_one_line() -> None:
    assert run("play").exit_code == 2
    r = run("play", ROOT / "nope.toml", "--no-browser")
    assert r.exit_code == 2 and r.output.startswith("error: ") and r.output.count("\n") == 1
    r = run("play", ROOT / PROBLEMS["p2"], "--view", "nomodule", "--no-browser")
    assert r.exit_code == 2 and "--view" in r.output and r.output.count("\n") == 1
