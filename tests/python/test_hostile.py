"""The hostile-input suite: tests/hostile/EXPECTED.txt, one `lenspath` command a line with the one
error line it must give (exit code 2, never a panic), or `ok:` and what it must print."""

from __future__ import annotations

import itertools
import os
import shlex
import subprocess
from pathlib import Path

import pytest

from .conftest import REPO

HOSTILE = REPO / "tests/hostile"
CHAIN_DEPTH = 2000


def cases() -> list[tuple[str, str]]:
    lines = (HOSTILE / "EXPECTED.txt").read_text().splitlines()
    pairs = [line.split(" => ", 1) for line in lines if line.strip() and not line.startswith("#")]
    return [(args.strip(), expected.strip()) for args, expected in pairs]


@pytest.fixture(scope="module")
def made(cli: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The generated inputs EXPECTED.txt's {made} names."""
    folder = tmp_path_factory.mktemp("hostile")
    for i in range(CHAIN_DEPTH):
        (folder / f"chain{i:04}.toml").write_text(f'base = "chain{i + 1:04}.toml"\n')
    (folder / f"chain{CHAIN_DEPTH:04}.toml").write_text('builtin = "cornell-spheres"\n')
    checkpoint = folder / "render.ckpt"
    subprocess.run(
        [cli, "render", "--res", "8x8", "--spp", "1", "--checkpoint", checkpoint, "--out", folder / "first.png"],
        check=True,
        capture_output=True,
    )
    damaged = bytearray(checkpoint.read_bytes())
    damaged[-40] ^= 0x04
    checkpoint.write_bytes(bytes(damaged))
    return folder


@pytest.mark.parametrize(("args", "expected"), cases(), ids=[a for a, _ in cases()])
def test_hostile_input_gets_one_clear_answer(cli: Path, made: Path, args: str, expected: str) -> None:
    words = shlex.split(args.format(here=HOSTILE, made=made))
    # Leading NAME=VALUE words set the environment, as in a shell.
    settings = [w for w in itertools.takewhile(lambda w: "=" in w and not w.startswith("-"), words)]
    env = {**os.environ, **dict(s.split("=", 1) for s in settings)}
    command = [cli, *words[len(settings) :]]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, env=env)
    assert "panicked" not in run.stderr, run.stderr
    if expected.startswith("ok:"):
        assert run.returncode == 0, run.stderr
        assert expected.removeprefix("ok:").strip() in run.stdout, run.stdout
        return
    assert run.returncode == 2, (run.returncode, run.stderr)
    errors = [line for line in run.stderr.splitlines() if line.startswith("error")]
    assert len(errors) == 1, run.stderr
    assert expected in errors[0], run.stderr
