"""Build the BehaviorTree.CPP tick program that tests/test_bt_cpp.py runs (``make bt-cpp``).

    .venv/bin/python benchmarks/bt_cpp.py [--prefix DIR] [--jobs N]

Builds ``tests/bt_cpp/tick.cpp`` against an installed BehaviorTree.CPP 4 and puts the program
in the cache folder, ``$EHATP_BTCPP_DIR`` or ``~/.cache/ehatp-btcpp`` (``$XDG_CACHE_HOME``
respected), as ``bin/ehatp-bt-tick``; the slow test ``tests/test_bt_cpp.py`` uses it when it is
there and is skipped, saying so, when it is not.

BehaviorTree.CPP itself is not built here: install version 4 as its README says (a CMake build
and install, conan, or the ROS 2 package ``ros-<distro>-behaviortree-cpp``). It is looked for in
``--prefix`` (or ``$BTCPP_PREFIX``), then in the cache folder's ``install/``, then where CMake
looks by default. CMake and a C++17 compiler are needed. Exit 0 when built, 2 with one line
saying what is missing otherwise.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCE = ROOT / "tests" / "bt_cpp"
PROGRAM = "ehatp-bt-tick"


def cache_dir() -> Path:
    """Return the folder the tick program is built into (and BehaviorTree.CPP may be in)."""
    if env := os.environ.get("EHATP_BTCPP_DIR"):
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ehatp-btcpp"


def program() -> Path:
    """Return where the built tick program is (it may not exist)."""
    return cache_dir() / "bin" / PROGRAM


def build(prefix: Path | None, jobs: int) -> int:
    """Return 0 once the tick program is built and installed in :func:`cache_dir`; 2, after
    one line on stderr saying what is missing, otherwise."""
    here = "benchmarks/bt_cpp.py"
    if shutil.which("cmake") is None:
        print(f"{here}: cmake is not installed; install CMake (and a C++17 compiler)",
              file=sys.stderr)
        return 2
    cache = cache_dir()
    prefixes = [p for p in (prefix, cache / "install") if p is not None and p.is_dir()]
    build_dir = cache / "tick-build"
    configure = ["cmake", "-S", str(SOURCE), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                 f"-DCMAKE_INSTALL_PREFIX={cache}",
                 f"-DCMAKE_PREFIX_PATH={';'.join(str(p) for p in prefixes)}"]
    steps = [configure, ["cmake", "--build", str(build_dir), "-j", str(jobs)],
             ["cmake", "--install", str(build_dir)]]
    for step in steps:
        r = subprocess.run(step, capture_output=True, text=True)
        if r.returncode != 0:
            sys.stderr.write(r.stdout[-4000:] + r.stderr[-4000:])
            if step is configure and "behaviortree_cpp" in r.stdout + r.stderr:
                looked = ", ".join(str(p) for p in prefixes) or "no prefix given"
                print(f"{here}: BehaviorTree.CPP 4 not found ({looked}, and CMake's default "
                      "places); install it as its README says and give --prefix DIR or "
                      "BTCPP_PREFIX", file=sys.stderr)
            else:
                print(f"{here}: {' '.join(step[:2])} failed (above); fix the C++ toolchain or "
                      "the BehaviorTree.CPP install", file=sys.stderr)
            return 2
    print(f"built {program()}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Return the exit status of building the tick program with the options ``argv``."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    ap.add_argument("--prefix", type=Path, default=os.environ.get("BTCPP_PREFIX") or None,
                    help="where BehaviorTree.CPP 4 is installed (default: $BTCPP_PREFIX, "
                         "then the cache folder's install/, then CMake's default places)")
    ap.add_argument("--jobs", type=int, default=1, help="compiler jobs (default 1)")
    args = ap.parse_args(argv)
    return build(args.prefix, args.jobs)


if __name__ == "__main__":
    sys.exit(main())
