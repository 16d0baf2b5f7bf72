"""What a user and a packager meet first: the installed package gives the `lenspath` command, and
one version number runs through the crates, the package metadata, `--version` and
`__version__`; the licence files travel with the package."""

from __future__ import annotations

import importlib.metadata
import os
import struct
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

import lenspath

from .conftest import REPO

#: The one version, as the workspace manifest gives it (the crates inherit it, maturin reads it).
VERSION = tomllib.loads((REPO / "Cargo.toml").read_text())["workspace"]["package"]["version"]


def installed_command() -> Path:
    """The `lenspath` script pip installed beside this interpreter."""
    script = Path(sys.executable).parent / "lenspath"
    if not script.is_file():
        pytest.fail(f"pip install made no `lenspath` command in {script.parent}")
    return script


def elf_sections(elf: bytes) -> list[str]:
    """The section names of a 64-bit little-endian ELF file (the ELF-64 Object File Format)."""
    assert elf[:4] == b"\x7fELF" and elf[4] == 2 and elf[5] == 1
    (table,) = struct.unpack_from("<Q", elf, 0x28)
    entry, count, names_index = struct.unpack_from("<HHH", elf, 0x3A)
    headers = [struct.unpack_from("<IIQQQQ", elf, table + i * entry) for i in range(count)]
    names_at = headers[names_index][4]
    return [elf[names_at + h[0] : elf.index(b"\0", names_at + h[0])].decode() for h in headers]


def test_one_version_everywhere(cli: Path) -> None:
    assert lenspath.__version__ == VERSION
    assert importlib.metadata.version("lenspath") == VERSION
    for crate in ("lenspath", "lenspath-cli", "lenspath-py"):
        manifest = tomllib.loads((REPO / "crates" / crate / "Cargo.toml").read_text())
        assert manifest["package"]["version"] == {"workspace": True}, crate
    for command in ([str(cli)], [str(installed_command())], [sys.executable, "-m", "lenspath"]):
        out = subprocess.run([*command, "--version"], capture_output=True, text=True, check=True)
        assert out.stdout.strip() == f"lenspath {VERSION}", command


@pytest.mark.parametrize("how", ["script", "module"])
def test_the_package_gives_the_command(how: str, tmp_path: Path) -> None:
    command = [str(installed_command())] if how == "script" else [sys.executable, "-m", "lenspath"]
    out = subprocess.run([*command, "info", "cornell-spheres", "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert '"spheres": 2' in out.stdout
    # Errors as the binary gives them: clap's whole message, exit code 2.
    out = subprocess.run([*command, "render", "--sp", "2"], capture_output=True, text=True)
    assert out.returncode == 2
    assert "a similar argument exists: '--spp'" in out.stderr
    # A render through the default lens, written where asked.
    image = tmp_path / "small.png"
    env = {**os.environ, "RAYON_NUM_THREADS": "2"}
    out = subprocess.run(
        [*command, "render", "--res", "32x24", "--spp", "1", "--out", str(image)], capture_output=True, env=env
    )
    assert out.returncode == 0, out.stderr
    assert image.stat().st_size > 0


def test_the_licences_travel_with_the_package() -> None:
    files = importlib.metadata.files("lenspath") or []
    names = {Path(str(f)).name for f in files}
    assert {"LICENSE-MIT", "LICENSE-APACHE", "THIRD-PARTY-NOTICES.md"} <= names, sorted(names)
    meta = importlib.metadata.metadata("lenspath")
    assert meta["License-Expression"] == "MIT OR Apache-2.0"


def test_the_wheel_is_stripped_and_publishable() -> None:
    wheels = sorted((REPO / "target" / "wheels").glob("lenspath-*.whl"))
    if not wheels:
        pytest.skip("no wheel in target/wheels: scripts/test.sh builds one there")
    wheel = wheels[-1]
    out = subprocess.run(
        [sys.executable, "-m", "twine", "check", "--strict", str(wheel)], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stdout + out.stderr
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        native = next(n for n in names if n.startswith("lenspath/_core") and n.endswith(".so"))
        module = z.read(native)
    assert "lenspath/__main__.py" in names
    assert any(n.endswith("dist-info/entry_points.txt") for n in names)
    # Stripped: no DWARF sections (the dev profile it is built with here keeps line tables).
    assert not [name for name in elf_sections(module) if name.startswith(".debug")]
    assert wheel.stat().st_size < 8e6, wheel.stat().st_size
