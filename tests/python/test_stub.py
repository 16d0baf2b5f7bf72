"""The type stub `_core.pyi` matches the native module: every function, class,
parameter and default (mypy's stubtest), and the package's own code type-checks
against it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from .conftest import REPO

pytest.importorskip("mypy", reason="the stub checks need mypy (pip install .[test])")


def test_the_stub_matches_the_native_module() -> None:
    # PEP 800 disjoint bases are left out: type checkers do not use them yet.
    result = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "lenspath._core", "--ignore-disjoint-bases"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_package_and_example_type_check() -> None:
    targets = [str(REPO / "python" / "lenspath"), str(REPO / "examples")]
    result = subprocess.run([sys.executable, "-m", "mypy", "--strict", *targets], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
