"""Shared fixtures: paths to the repository, ../shared and the CLI built by `cargo test`."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `lenspath` binary of this source tree (LENSPATH_CLI, else target/debug or target/release)."""
    candidates = [os.environ.get("LENSPATH_CLI"), REPO / "target/debug/lenspath", REPO / "target/release/lenspath"]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    found = shutil.which("lenspath")
    if found:
        return Path(found)
    pytest.skip("no lenspath CLI binary: run `cargo build` (scripts/test.sh does) or set LENSPATH_CLI")


@pytest.fixture(scope="session")
def shared() -> Path:
    """../shared beside the repository (lens tables, CS184 scenes, meshes)."""
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent: the shared assets are only beside the repository in CI")
    return SHARED
