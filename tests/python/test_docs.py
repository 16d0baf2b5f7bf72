"""Every fenced Python and shell example in README.md and docs/ runs, so a snippet that stops
working fails here.

How they are run:
- In a scratch folder laid out like the repository (`scenes`, `docs`, `examples` linked in, and
  `../shared` beside it when it exists), so the paths the examples use resolve and what they
  write lands there.
- Shell blocks with bash (`set -e`), the `lenspath` on PATH being the installed package's;
  `cargo run --release --` is read as `lenspath`. Python blocks in order, one namespace per
  document, so a block may use what an earlier one made.
- Small sizes: `--spp N`, `spp=N` and `"spp": N` become 2, `--res WxH` and `resolution=(W, H)` become 48x36,
  and a `lenspath render` or `autofocus` that gives neither gets them (the substitution is all
  that changes; `SMALL` and `Block.small` below).
- A block after a `<!-- not run: REASON -->` line is skipped, for that reason (a server that
  runs until stopped, a cluster, the test suite itself).
- A block that names `../shared` is skipped when the folder is absent (or hidden: conftest's
  `LENSPATH_TESTS_WITHOUT_SHARED`), as a user without it would skip it; so a Python block that
  does not name it may not use a name that only such a block defines
  (`test_no_example_depends_on_one_that_needs_shared`), and the document runs either way.
"""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import pytest

from .conftest import REPO, SHARED, absent_shared_reason

DOCUMENTS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
LANGUAGES = {"python": "python", "sh": "shell", "bash": "shell"}
NOT_RUN = re.compile(r"<!-- not run: (.+?) -->")

#: The substitutions that make an example small: (pattern, replacement) per language.
SMALL = {
    "shell": [
        (re.compile(r"\bcargo run --release --"), "lenspath"),
        (re.compile(r"--spp \d+"), "--spp 2"),
        (re.compile(r"--res \d+x\d+"), "--res 48x36"),
    ],
    "python": [
        (re.compile(r"\bspp=\d+"), "spp=2"),
        (re.compile(r'"spp": \d+'), '"spp": 2'),
        (re.compile(r"resolution=\(\d+, \d+\)"), "resolution=(48, 36)"),
    ],
}


@dataclass
class Block:
    """One fenced example: where it is, its language, its code, and why it is not run (if so)."""

    document: Path
    line: int
    language: str
    code: str
    not_run: str | None

    @property
    def needs_shared(self) -> bool:
        """Whether the block names ../shared (and so is skipped without it)."""
        return "../shared" in self.code

    def small(self) -> str:
        code = self.code
        for pattern, replacement in SMALL[self.language]:
            code = pattern.sub(replacement, code)
        if self.language == "shell":
            code = "\n".join(with_small_flags(line) for line in code.splitlines())
        return code


def with_small_flags(line: str) -> str:
    """A `lenspath render` or `autofocus` line with `--spp 2` and `--res 48x36` where it gives none."""
    command = re.search(r"\blenspath (render|autofocus)\b", line)
    if not command:
        return line
    missing = [flag for flag in ("--spp 2", "--res 48x36") if not re.search(rf"{flag.split()[0]}(?:[\s=]|$)", line)]
    return line[: command.end()] + "".join(f" {flag}" for flag in missing) + line[command.end() :]


def blocks(document: Path) -> list[Block]:
    """The Python and shell blocks of a Markdown document, in order."""
    found = []
    lines = document.read_text().splitlines()
    i = 0
    while i < len(lines):
        fence = re.match(r"^```(\w+)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        language = LANGUAGES.get(fence.group(1))
        if language:
            before = next((lines[j] for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            reason = NOT_RUN.search(before)
            found.append(
                Block(document, i + 1, language, "\n".join(lines[i + 1 : end]), reason.group(1) if reason else None)
            )
        i = end + 1
    return found


def where(block: Block) -> str:
    document = block.document
    return f"{document.relative_to(REPO) if document.is_relative_to(REPO) else document}:{block.line}"


@pytest.fixture
def scratch(tmp_path: Path) -> Path:
    """A folder laid out like the repository, with ../shared beside it when there is one."""
    root = tmp_path / "repo"
    root.mkdir()
    for name in ("scenes", "docs", "examples"):
        (root / name).symlink_to(REPO / name)
    if SHARED.is_dir():
        (tmp_path / "shared").symlink_to(SHARED)
    return root


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda d: str(d.relative_to(REPO)))
def test_every_example_runs(document: Path, scratch: Path, monkeypatch) -> None:
    examples = blocks(document)
    if not examples:
        pytest.skip(f"{document.name} has no Python or shell examples")
    monkeypatch.chdir(scratch)
    # The `lenspath` the package installed beside this interpreter: the command users run.
    monkeypatch.setenv("PATH", f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict[str, object] = {"__name__": "__doc_example__"}
    for block in examples:
        if block.not_run:
            continue
        if block.needs_shared and not SHARED.is_dir():
            warnings.warn(f"{where(block)} not run: {absent_shared_reason()}", stacklevel=1)
            continue
        code = block.small()
        if block.language == "shell":
            done = subprocess.run(["bash", "-e", "-c", code], capture_output=True, text=True, timeout=600)
            assert done.returncode == 0, f"{where(block)} failed:\n{code}\n{done.stdout}{done.stderr}"
        else:
            try:
                exec(compile(code, where(block), "exec"), namespace)
            except Exception as e:
                raise AssertionError(f"{where(block)} failed:\n{code}") from e


def names_bound_and_read(code: str) -> tuple[set[str], set[str]]:
    """The names a Python block binds (assignments, imports, definitions) and those it reads."""
    bound: set[str] = set()
    read: set[str] = set()
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Name):
            (read if isinstance(node.ctx, ast.Load) else bound).add(node.id)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            bound.update((alias.asname or alias.name).split(".")[0] for alias in node.names)
    return bound, read


def names_only_shared_blocks_define(document: Path) -> list[str]:
    """Where a Python block that runs without ../shared reads a name only a block needing it bound."""
    only_shared: set[str] = set()
    found = []
    for block in blocks(document):
        if block.language != "python" or block.not_run:
            continue
        bound, read = names_bound_and_read(block.code)
        if block.needs_shared:
            only_shared |= bound
        else:
            found += [f"{where(block)} reads {name}" for name in sorted(read & only_shared)]
            only_shared -= bound
    return found


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda d: str(d.relative_to(REPO)))
def test_no_example_depends_on_one_that_needs_shared(document: Path) -> None:
    # Without ../shared the blocks naming it are skipped: what runs after them must not need them.
    assert names_only_shared_blocks_define(document) == []


def test_the_dependency_check_finds_a_name_from_a_skipped_block(tmp_path: Path) -> None:
    # docs/python.md's fault on a fresh clone: a later block used a name the skipped block made.
    document = tmp_path / "doc.md"
    document.write_text(
        "```python\nscene = load('a.toml')\nlens = Lens('x', root='../shared')\n```\n\n"
        "```python\nplot(lens)\nscene.render()\n```\n\n"
        "```python\nlens = Lens('y')\n```\n\n```python\nplot(lens)\n```\n"
    )
    assert names_only_shared_blocks_define(document) == [f"{document}:6 reads lens", f"{document}:6 reads scene"]


def test_every_skipped_example_says_why() -> None:
    # The marker needs a reason, and a skipped block must be one the runner would otherwise run.
    for document in DOCUMENTS:
        text = document.read_text()
        for match in re.finditer(r"<!-- not run:?(.*?)-->", text):
            assert match.group(1).strip(), f"{document.name}: a 'not run' marker without a reason"
        marked = len(NOT_RUN.findall(text))
        assert marked == sum(1 for b in blocks(document) if b.not_run), f"{document.name}: a marker not before a block"


def test_the_substitution_only_shrinks() -> None:
    block = Block(REPO, 1, "shell", "cargo run --release -- render --spp 512 --res 640x480 --out a.png", None)
    assert block.small() == "lenspath render --spp 2 --res 48x36 --out a.png"
    block = Block(REPO, 1, "shell", "lenspath autofocus --patch 0.5,0.5,0.1,0.1  # a comment", None)
    assert block.small() == "lenspath autofocus --spp 2 --res 48x36 --patch 0.5,0.5,0.1,0.1  # a comment"
    block = Block(REPO, 1, "shell", "lenspath render a.toml --spp 8 --resume a.ckpt", None)
    assert block.small() == "lenspath render --res 48x36 a.toml --spp 2 --resume a.ckpt"
    block = Block(REPO, 1, "python", 'lenspath.render("x", spp=64, resolution=(640, 480))', None)
    assert block.small() == 'lenspath.render("x", spp=2, resolution=(48, 36))'
