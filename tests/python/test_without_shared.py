"""The switch that makes the suite behave as on a fresh clone without ../shared (CI's second
pass, .ci/run) hides the folder, and only when set."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from .conftest import REPO, WITHOUT_SHARED_SWITCH, shared_folder


def test_the_switch_hides_shared_and_only_when_set() -> None:
    assert shared_folder({}) == REPO.parent / "shared"
    assert shared_folder({WITHOUT_SHARED_SWITCH: "0"}) == REPO.parent / "shared"
    hidden = shared_folder({WITHOUT_SHARED_SWITCH: "1"})
    assert not hidden.exists() and hidden != REPO.parent / "shared"


def test_a_test_needing_shared_skips_naming_the_folder_when_hidden(tmp_path: Path) -> None:
    # A test asking for the `shared` fixture, run by pytest with the switch set: skipped, and the
    # reason names ../shared and the switch.
    probe = tmp_path / "test_probe.py"
    probe.write_text("def test_probe(shared):\n    assert shared.is_dir()\n")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "tests.python.conftest", "--rootdir", str(REPO), probe],
        cwd=REPO,
        env={**os.environ, WITHOUT_SHARED_SWITCH: "1"},
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 skipped" in done.stdout, done.stdout
    assert f"../shared ({REPO.parent / 'shared'}) is hidden by {WITHOUT_SHARED_SWITCH}=1" in done.stdout, done.stdout
