"""Naming a module in a problem file imports nothing that did not declare itself a domain
(docs/security.md): ``[domain] name`` is a declared name (ehatp's own, an entry point of group
``ehatp.domains``, or one registered from Python), ``"module:attribute"`` of a declared
domain's module, or a ``.py`` file beside the problem. Anything else is one line listing the
declared domains and saying how to declare one, and the module is never imported."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import ehatp
import ehatp.domains
from ehatp.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
P1 = ROOT / "examples" / "cubes" / "p1.toml"

DOMAIN_CODE = """\
import pathlib

pathlib.Path({marker!r}).touch()  # what importing this module does

from ehatp.domains.cubes import make_domain as cubes


def make(turn_before_move=False, human_reach="fetched"):
    return cubes(turn_before_move=turn_before_move, human_reach=human_reach)
"""


def problem_naming(tmp_path: Path, ref: str) -> Path:
    """P1, its ``[domain] name`` replaced by ``ref``."""
    text = P1.read_text(encoding="utf-8")
    assert 'name = "cubes"' in text
    f = tmp_path / "problem" / "p.toml"
    f.parent.mkdir(exist_ok=True)
    f.write_text(text.replace('name = "cubes"', f"name = {ref!r}".replace("'", '"'), 1),
                 encoding="utf-8")
    return f


@pytest.fixture
def side_effect_package(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A package ``sidefx_pkg`` on sys.path whose import creates the file it yields."""
    marker = tmp_path / "IMPORTED"
    lib = tmp_path / "lib"
    (lib / "sidefx_pkg").mkdir(parents=True)
    (lib / "sidefx_pkg" / "__init__.py").write_text(DOMAIN_CODE.format(marker=str(marker)),
                                                    encoding="utf-8")
    (lib / "sidefx_pkg" / "sub.py").write_text(DOMAIN_CODE.format(marker=str(marker)),
                                               encoding="utf-8")
    monkeypatch.syspath_prepend(str(lib))
    yield marker
    for name in ("sidefx_pkg", "sidefx_pkg.sub"):
        sys.modules.pop(name, None)


@pytest.fixture
def registered() -> Iterator[list[str]]:
    """Names the test registers, forgotten after it."""
    names: list[str] = []
    yield names
    for n in names:
        ehatp.domains.unregister(n)


def refusal(tmp_path: Path, ref: str) -> str:
    with pytest.raises(InputError) as e:
        ehatp.load(problem_naming(tmp_path, ref))
    line = str(e.value)
    assert "\n" not in line and "[domain] name" in line
    return line


# --- refused, and never imported -------------------------------------------------------------


@pytest.mark.parametrize("ref", ["sidefx_pkg:make", "sidefx_pkg.sub:make", "sidefx_pkg:x"])
def test_a_module_that_declared_no_domain_is_refused_and_never_imported(
        tmp_path: Path, side_effect_package: Path, ref: str) -> None:
    line = refusal(tmp_path, ref)
    assert "declared no domain, so it is not imported" in line
    assert "cooking, cubes" in line and "ehatp.domains" in line and "register" in line
    assert not side_effect_package.exists()
    assert "sidefx_pkg" not in sys.modules


@pytest.mark.parametrize("ref", ["antigravity:x", "this:x", "numpy.f2py.__main__:x",
                                 "trio.__main__:x", "matplotlib.pyplot:show", "os:mkdir",
                                 "ehatp.formats.problem_toml:load", "ehatp.cli.app:main"])
def test_an_installed_module_that_is_no_domain_is_never_imported(tmp_path: Path,
                                                                 ref: str) -> None:
    module = ref.partition(":")[0]
    before = module in sys.modules
    assert "declared no domain" in refusal(tmp_path, ref)
    assert (module in sys.modules) == before


def test_the_command_line_refuses_it_in_one_line_and_imports_nothing(
        tmp_path: Path, side_effect_package: Path) -> None:
    f = problem_naming(tmp_path, "sidefx_pkg:make")
    env = {"PYTHONPATH": str(tmp_path / "lib"), "PATH": "/usr/bin:/bin"}
    r = subprocess.run([sys.executable, "-m", "ehatp.cli", "solve", str(f)], env=env,
                       capture_output=True, text=True, timeout=120, check=False)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {f}:"), r.stderr
    assert "declared no domain" in lines[0] and "ehatp.domains" in lines[0]
    assert not side_effect_package.exists()


def test_an_unknown_name_lists_the_declared_domains(tmp_path: Path) -> None:
    line = refusal(tmp_path, "cubez")
    assert "unknown domain 'cubez'; the declared domains are cooking, cubes" in line


# --- what is declared is used ----------------------------------------------------------------


@pytest.mark.parametrize("ref", ["cubes", "ehatp.domains.cubes:make_domain"])
def test_a_declared_domain_loads_by_name_or_by_its_module(tmp_path: Path, ref: str) -> None:
    assert ehatp.load(problem_naming(tmp_path, ref)).domain.name == "cubes"


def test_ehatps_own_domains_are_entry_points_of_the_group() -> None:
    from importlib.metadata import entry_points

    eps = {ep.name: ep.value for ep in entry_points(group="ehatp.domains")}
    assert eps.get("cubes") == "ehatp.domains.cubes:make_domain", "pip install -e . again"
    assert eps.get("cooking") == "ehatp.domains.cooking:make_domain"


def test_a_domain_registered_from_python_is_imported_when_a_problem_names_it(
        tmp_path: Path, side_effect_package: Path, registered: list[str]) -> None:
    ehatp.domains.register("sidefx", "sidefx_pkg:make")
    registered.append("sidefx")
    assert not side_effect_package.exists()  # registering imports nothing
    assert ehatp.load(problem_naming(tmp_path, "sidefx")).domain.name == "cubes"
    assert side_effect_package.exists()
    # its module is now a declared domain's, by module:attribute too
    assert ehatp.load(problem_naming(tmp_path, "sidefx_pkg:make")).domain.name == "cubes"
    # another module of the same package is not
    assert "declared no domain" in refusal(tmp_path, "sidefx_pkg.sub:make")


def test_a_domain_object_or_factory_may_be_registered(tmp_path: Path,
                                                      registered: list[str]) -> None:
    from ehatp.domains.cubes import make_domain

    ehatp.domains.register("my_cubes", make_domain)
    registered.append("my_cubes")
    assert ehatp.load(problem_naming(tmp_path, "my_cubes")).domain.name == "cubes"


def test_register_refuses_a_bad_name_or_a_clash() -> None:
    with pytest.raises(ValueError, match="identifier"):
        ehatp.domains.register("not a name", "x:y")
    with pytest.raises(ValueError, match="declared already"):
        ehatp.domains.register("cubes", "sidefx_pkg:make")
    with pytest.raises(ValueError, match="module:attribute"):
        ehatp.domains.register("fine", "no_colon")


def test_a_third_party_package_declares_its_domain_with_an_entry_point(
        tmp_path: Path, side_effect_package: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # an installed distribution, as pip leaves it: metadata beside the package
    dist = tmp_path / "lib" / "sidefx_pkg-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: sidefx-pkg\nVersion: 1.0\n",
                                   encoding="utf-8")
    (dist / "entry_points.txt").write_text("[ehatp.domains]\nsidefx = sidefx_pkg.sub:make\n",
                                           encoding="utf-8")
    assert ehatp.domains.declared()["sidefx"] == "sidefx_pkg.sub:make"
    assert not side_effect_package.exists()  # listing entry points imports nothing
    assert "declared no domain" in refusal(tmp_path, "sidefx_pkg:make")
    assert "sidefx_pkg" not in sys.modules
    assert ehatp.load(problem_naming(tmp_path, "sidefx")).domain.name == "cubes"
    assert ehatp.load(problem_naming(tmp_path, "sidefx_pkg.sub:make")).domain.name == "cubes"


def test_a_domain_file_beside_the_problem_is_still_the_users_code(tmp_path: Path) -> None:
    marker = tmp_path / "RAN"
    f = problem_naming(tmp_path, "mydomain.py:make")
    (f.parent / "mydomain.py").write_text(
        DOMAIN_CODE.format(marker=str(marker)).replace(
            "def make(", "from ehatp import domain_factory\n\n\n@domain_factory\ndef make("),
        encoding="utf-8")
    assert ehatp.load(f).domain.name == "cubes" and marker.exists()
