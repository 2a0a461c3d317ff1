"""An error inside a domain factory called with options from the problem file is the domain's
own: reported at its file and line, with the options it was called with; "bad domain options"
is kept for the call refusing them before any of the domain's code ran."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from ehatp.errors import InputError
from ehatp.formats.problem_toml import load

DOMAIN = '''\
import ehatp


def colour_of(size):
    return {"small": "red"}[size]  # line 5: a KeyError the domain raises itself


@ehatp.domain_factory
def make(size="small", strict=False):
    if strict:
        raise ValueError("strict domains are not written yet")  # line 11
    colour_of(size)
    return None


@ehatp.domain_factory
def wraps(**options):
    return make(**options, extra=1)  # line 18: a TypeError of the domain's own making


class Opaque:
    __signature__ = "not a signature"  # the loader cannot check the options beforehand

    def __call__(self, *, size):
        return None


opaque = ehatp.domain_factory(Opaque())
'''

PROBLEM = '''\
[problem]
name = "t"
K = 2

[domain]
name = "domain.py:{factory}"
{options}

[objects]
thing = ["a"]

[agenda]
robot = ["x"]
human = ["y"]
'''


def problem(tmp_path: Path, factory: str, options: str) -> Path:
    """Return a problem file naming ``factory`` of the test domain with ``options``."""
    (tmp_path / "domain.py").write_text(DOMAIN, encoding="utf-8")
    f = tmp_path / "t.toml"
    f.write_text(PROBLEM.format(factory=factory, options=options), encoding="utf-8")
    return f


def error_of(f: Path) -> str:
    with pytest.raises(InputError) as e:
        load(f)
    return e.value.line()


def test_a_key_error_deep_in_the_domain_is_reported_at_its_line(tmp_path: Path) -> None:
    f = problem(tmp_path, "make", 'size = "large"')
    domain = (tmp_path / "domain.py").resolve()
    assert error_of(f) == (
        f"{f}:6: [domain] name: domain 'domain.py:make' failed at {domain}:5, called with "
        "size = 'large': KeyError: 'large'; that is the domain's own error: fix its code "
        "there, or the [domain] option it refuses")


def test_a_value_error_the_factory_raises_is_not_blamed_on_the_option(tmp_path: Path) -> None:
    f = problem(tmp_path, "make", "strict = true")
    domain = (tmp_path / "domain.py").resolve()
    line = error_of(f)
    assert "bad domain option" not in line
    assert line == (
        f"{f}:6: [domain] name: domain 'domain.py:make' failed at {domain}:11, called with "
        "strict = True: ValueError: strict domains are not written yet; that is the domain's "
        "own error: fix its code there, or the [domain] option it refuses")


def test_a_type_error_inside_the_domain_is_the_domains_at_its_line(tmp_path: Path) -> None:
    f = problem(tmp_path, "wraps", 'size = "small"')
    domain = (tmp_path / "domain.py").resolve()
    line = error_of(f)
    assert "bad domain option" not in line
    assert line.startswith(f"{f}:6: [domain] name: domain 'domain.py:wraps' failed at "
                           f"{domain}:18, called with size = 'small': TypeError: ")
    assert "unexpected keyword argument 'extra'" in line


def test_an_unknown_option_is_still_a_bad_domain_option(tmp_path: Path) -> None:
    f = problem(tmp_path, "make", "colour = 1")
    assert error_of(f) == (
        f"{f}:7: [domain] colour: bad domain options for 'domain.py:make': got an unexpected "
        "keyword argument 'colour'; its options are size, strict")


def test_options_the_call_itself_refuses_are_bad_domain_options(tmp_path: Path) -> None:
    # no signature to check beforehand: the call raises before any of the domain's code runs
    f = problem(tmp_path, "opaque", "colour = 1")
    line = error_of(f)
    assert line.startswith(f"{f}:5: [domain]: bad domain options for 'domain.py:opaque': "
                           "TypeError: ")
    assert "unexpected keyword argument 'colour'" in line
    assert line.endswith("; fix the option")


def test_the_command_line_says_the_domains_error_in_one_line(tmp_path: Path) -> None:
    f = problem(tmp_path, "make", 'size = "large"')
    script = Path(sys.executable).with_name("ehatp")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "ehatp.cli"]
    done = subprocess.run([*cmd, "solve", str(f)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    domain = (tmp_path / "domain.py").resolve()
    assert done.stderr == textwrap.dedent(f"""\
        error: {f}:6: [domain] name: domain 'domain.py:make' failed at {domain}:5, called with \
size = 'large': KeyError: 'large'; that is the domain's own error: fix its code there, or the \
[domain] option it refuses
        """)
