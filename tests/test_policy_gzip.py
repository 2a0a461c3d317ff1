"""Policy files written gzip-compressed: ``--out FILE.json.gz`` (docs/policy-format.md,
"Compressed files"). The human's worlds make a K=8 policy large (at 20 cubes / 3 boxes / K=8,
10.8 MB of JSON, 91 % of it the worlds' differences); gzip keeps the same JSON in a file a
twentieth of that size, and every command that reads a policy reads either."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import ehatp
from ehatp.cli.app import app
from ehatp.errors import InputError
from ehatp.experiments.examples import examples_dir
from ehatp.formats.policy import Policy
from ehatp.formats.policy_check import read_policy
from ehatp.run.walk import walk_policy
from ehatp.search.planner import solve

P2 = examples_dir() / "cubes" / "p2.toml"
runner = CliRunner()


def invoke(*args: str | Path) -> tuple[int, str]:
    r = runner.invoke(app, [str(a) for a in args])
    return r.exit_code, r.output


@pytest.fixture(scope="module")
def p2_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """P2's policy written twice by ``ehatp solve``: plain and gzip-compressed."""
    d = tmp_path_factory.mktemp("gz")
    plain, packed = d / "p2.json", d / "p2.json.gz"
    assert invoke("solve", P2, "--out", plain)[0] == 0
    assert invoke("solve", P2, "--out", packed)[0] == 0
    return plain, packed


def test_a_policy_written_to_a_gz_name_is_the_same_json_compressed(
        p2_files: tuple[Path, Path]) -> None:
    plain, packed = p2_files
    raw = packed.read_bytes()
    assert raw[:2] == b"\x1f\x8b"  # gzip's magic number, not JSON text
    assert gzip.decompress(raw) == plain.read_bytes()
    assert len(raw) * 5 < plain.stat().st_size


def test_the_compressed_file_is_deterministic_no_time_and_no_name_in_its_header(
        p2_files: tuple[Path, Path], tmp_path: Path) -> None:
    # RFC 1952: bytes 4-7 are the modification time, bit 3 of the flags byte (3) says a file
    # name follows the header; the file was written under a random temporary name, which must
    # not leak into it
    _, packed = p2_files
    raw = packed.read_bytes()
    assert raw[4:8] == b"\0\0\0\0"
    assert not raw[3] & 0b1000
    again = tmp_path / "again.json.gz"
    assert invoke("solve", P2, "--out", again)[0] == 0
    assert again.read_bytes() == raw


def test_a_compressed_policy_loads_as_the_plain_one_and_runs_on_every_branch(
        p2_files: tuple[Path, Path]) -> None:
    plain, packed = p2_files
    a, b = read_policy(plain), read_policy(packed)
    assert a.to_json() == b.to_json()
    report = walk_policy(ehatp.load(P2), b)
    assert report.ok and report.branches == 6, report  # P2's 6 leaves, as `show` says


def test_every_command_that_reads_a_policy_reads_a_compressed_one(
        p2_files: tuple[Path, Path], tmp_path: Path) -> None:
    plain, packed = p2_files
    for args in (("show",), ("validate", P2), ("render",), ("export", "bt")):
        head, *rest = args
        code_plain, out_plain = invoke(head, *rest, plain)
        code_packed, out_packed = invoke(head, *rest, packed)
        assert code_plain == code_packed == 0, (args, out_packed)
        assert out_packed == out_plain.replace(str(plain), str(packed)), args
    code, out = invoke("simulate", P2, "--policy", packed)
    assert code == 0 and "goal reached" in out
    expanded = tmp_path / "p2-expanded.json.gz"
    code, out = invoke("expand", packed, "--problem", P2, "--out", expanded)
    assert code == 0, out
    assert json.loads(gzip.decompress(expanded.read_bytes()))["version"] == 2


@pytest.mark.parametrize(("content", "why"), [
    (b"\x1f\x8b" + b"not a gzip stream", "not a readable gzip file"),
    (None, "not a readable gzip file (truncated)"),
    (gzip.compress(b'{"format": "something else"}', mtime=0), "not an ehatp policy"),
    (gzip.compress(bytes(range(256)), mtime=0), "not a text file"),
])
def test_a_damaged_or_foreign_compressed_file_is_one_line_naming_it_exit_2(
        p2_files: tuple[Path, Path], tmp_path: Path, content: bytes | None, why: str) -> None:
    _, packed = p2_files
    bad = tmp_path / "bad.json.gz"
    bad.write_bytes(packed.read_bytes()[:len(packed.read_bytes()) // 2] if content is None
                    else content)
    code, out = invoke("show", bad)
    assert code == 2
    line = out.strip()
    assert "\n" not in line and line.startswith(f"error: {bad}: ") and why in line, line


def test_decompressing_calls_the_limit_s_check_so_a_small_file_cannot_hold_a_huge_one(
        tmp_path: Path) -> None:
    # 3 MB of JSON (spaces are JSON whitespace) in a file of a few kB: the check is called
    # after each megabyte decompressed, and a limit's check stops the reading there
    big = tmp_path / "big.json.gz"
    big.write_bytes(gzip.compress(b" " * (3 << 20) + b"{}", mtime=0))
    assert big.stat().st_size < 10_000
    calls: list[int] = []

    class Stop(Exception):
        pass

    def check() -> None:
        calls.append(1)
        if len(calls) == 2:
            raise Stop

    with pytest.raises(Stop):
        Policy.load(big, check)
    assert len(calls) == 2
    with pytest.raises(InputError, match="not an ehatp policy"):
        Policy.load(big)  # without a limit it is read whole, and refused for what it is


def test_a_policy_written_by_the_api_to_a_gz_path_is_compressed_too(tmp_path: Path) -> None:
    pol = solve(ehatp.load(P2)).policy
    assert pol is not None
    out = tmp_path / "p2.json.gz"
    pol.write(out)
    assert gzip.decompress(out.read_bytes()).decode("utf-8") == pol.to_json()


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_compressed_policy_damaged_anywhere_is_refused_in_one_line_or_read_whole(
        p2_files: tuple[Path, Path], tmp_path: Path, data: st.DataObject) -> None:
    # gzip ends with the CRC-32 and the length of what it holds: a changed byte, a cut or
    # bytes added after the end are either caught there or leave a policy the reader checks
    # in full
    raw = bytearray(p2_files[1].read_bytes())
    at = data.draw(st.integers(0, len(raw) - 1))
    how = data.draw(st.sampled_from(["change", "cut", "append"]))
    if how == "change":
        raw[at] ^= data.draw(st.integers(1, 255))
    elif how == "cut":
        del raw[at:]
    else:
        raw += data.draw(st.binary(min_size=1, max_size=20))
    bad = tmp_path / "damaged.json.gz"
    bad.write_bytes(bytes(raw))
    try:
        pol = read_policy(bad)
    except InputError as e:
        assert "\n" not in e.line() and e.line().startswith(f"{bad}:")
    else:
        assert pol.to_json() == read_policy(p2_files[0]).to_json()
