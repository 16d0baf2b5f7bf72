"""Shared fixtures: paths to the repository, ../shared and the CLI built by `cargo test`."""

from __future__ import annotations

import os
import shutil
from collections.abc import Mapping
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: Set to 1, the tests behave as on a fresh clone with no ../shared beside the repository, even
#: where there is one (CI's second pass over the tests that read it: .ci/run).
WITHOUT_SHARED_SWITCH = "LENSPATH_TESTS_WITHOUT_SHARED"


def shared_folder(environ: Mapping[str, str] = os.environ) -> Path:
    """../shared beside the repository, or a folder that does not exist when the switch hides it."""
    if environ.get(WITHOUT_SHARED_SWITCH) == "1":
        return REPO / "target" / f"no-shared-{WITHOUT_SHARED_SWITCH}"
    return REPO.parent / "shared"


#: What the tests read ../shared as: every test that needs it checks `SHARED.is_dir()` or asks
#: for the `shared` fixture, and passes this path (not its own) to the scripts it runs.
SHARED = shared_folder()


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
        pytest.skip(absent_shared_reason())
    return SHARED


def absent_shared_reason() -> str:
    """Why a test that needs ../shared is skipped: the folder it looked for, and why it is not there."""
    beside = REPO.parent / "shared"
    if SHARED != beside:
        return f"../shared ({beside}) is hidden by {WITHOUT_SHARED_SWITCH}=1"
    return f"../shared ({beside}) is absent: the shared assets are only beside the repository in CI"


def scene_needs_shared(scene: str | Path) -> bool:
    """Whether a scene argument is a TOML scene file naming files in ../shared (cbdragon, cblucy)."""
    path = Path(scene)
    return path.suffix == ".toml" and "shared/" in path.read_text()
