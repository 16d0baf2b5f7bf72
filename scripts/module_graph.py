"""Which of the library's files use which, and the circles among them.

    python scripts/module_graph.py [--src crates/lenspath/src]

Prints each circle (a strongly connected set of files, each reaching every other by `use`s and
paths) on a line, and exits 1 if there is one. A file's edges are the items it names through
`crate::`, `super::`, `self::` or a child module, each resolved to the file that defines the item:
through the `pub use` re-exports of a module (which are its interface, so they add no edge of
their own), and to the deepest module the path names. Unit tests (`#[cfg(test)]` to the end of
the file) are left out: a test may reach anywhere. `tests/python/test_module_graph.py` runs it.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Iterator
from pathlib import Path

Module = tuple[str, ...]  # ("crate", "lens", "system")

USE = re.compile(r"\buse\s+([^;]+);")
PUB_USE = re.compile(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);")
PATH = re.compile(r"\b((?:crate|super|self)(?:::\w+)+)")
CHILD = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", re.MULTILINE)


def module_of(file: Path, src: Path) -> Module:
    """The module a source file is: lib.rs the crate, a/mod.rs and a.rs `a`, a/b.rs `a::b`."""
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("lib", "mod"):
        parts.pop()
    return ("crate", *parts)


def code_of(text: str) -> str:
    """The text without comments, string literals and the unit tests."""
    text = re.sub(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{.*", "", text, flags=re.DOTALL)
    text = re.sub(r'r#*"(?:.|\n)*?"#*|"(?:\\.|[^"\\])*"', '""', text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)
    return re.sub(r"//[^\n]*", "", text)


def expand(tree: str) -> Iterator[list[str]]:
    """The paths of a `use` tree: `a::{b, c::{d, e as f}}` gives a::b, a::c::d, a::c::e."""
    # An alias renames the last segment only: what it names is the path before it.
    tree = re.sub(r"\s+", "", re.sub(r"\s+as\s+\w+", "", tree))
    depth, start, parts = 0, 0, []
    brace = tree.find("{")
    if brace < 0:
        yield [p for p in tree.split("::") if p]
        return
    head = [p for p in tree[:brace].split("::") if p]
    inner = tree[brace + 1 : tree.rindex("}")]
    for i, ch in enumerate(inner):
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            parts.append(inner[start:i])
            start = i + 1
    parts.append(inner[start:])
    for part in parts:
        if part:
            for rest in expand(part):
                yield head + rest


class Graph:
    """The library's modules, their children and re-exports, and the edges between files."""

    def __init__(self, src: Path) -> None:
        self.files = {module_of(f, src): f for f in sorted(src.rglob("*.rs"))}
        self.code = {m: code_of(f.read_text()) for m, f in self.files.items()}
        self.children = {m: set(CHILD.findall(code)) for m, code in self.code.items()}
        self.reexports: dict[Module, dict[str, list[str]]] = {}
        for m, code in self.code.items():
            names: dict[str, list[str]] = {}
            for tree in PUB_USE.findall(code):
                for path in expand(tree):
                    names[path[-1]] = path
            self.reexports[m] = names

    def absolute(self, here: Module, path: list[str]) -> list[str] | None:
        """`path` as written in `here`, from the crate root; None for another crate's."""
        if path[0] == "crate":
            return path
        if path[0] in ("self", "super"):
            base = list(here)
            while path and path[0] in ("self", "super"):
                if path.pop(0) == "super":
                    base.pop()
            return base + path
        if path[0] in self.children.get(here, ()):
            return [*here, *path]
        return None

    def defining_file(self, path: list[str], seen: int = 0) -> Module | None:
        """The module that defines what an absolute path names (re-exports followed)."""
        for n in range(len(path), 0, -1):
            module = tuple(path[:n])
            if module in self.files:
                rest = path[n:]
                if rest and rest[0] in self.reexports[module] and seen < 16:
                    target = self.absolute(module, list(self.reexports[module][rest[0]]))
                    if target and tuple(target) != tuple(path):
                        return self.defining_file(target + rest[1:], seen + 1) or module
                return module
        return None

    def edges(self, here: Module) -> set[Module]:
        """The files `here` uses, re-exports aside."""
        code = PUB_USE.sub("", self.code[here])
        paths = [p for tree in USE.findall(code) for p in expand(tree)]
        code = USE.sub("", code)
        paths += [m.split("::") for m in PATH.findall(code)]
        found = set()
        for path in paths:
            absolute = self.absolute(here, list(path)) if path else None
            target = self.defining_file(absolute) if absolute else None
            if target and target != here and target != ("crate",):
                found.add(target)
        return found


def circles(graph: Graph) -> list[list[str]]:
    """The strongly connected sets of more than one file (Tarjan), each sorted, as `a::b` names."""
    edges = {m: graph.edges(m) for m in graph.files}
    index: dict[Module, int] = {}
    low: dict[Module, int] = {}
    stack: list[Module] = []
    on_stack: set[Module] = set()
    found: list[list[str]] = []

    def visit(m: Module) -> None:
        index[m] = low[m] = len(index)
        stack.append(m)
        on_stack.add(m)
        for n in sorted(edges[m]):
            if n not in index:
                visit(n)
                low[m] = min(low[m], low[n])
            elif n in on_stack:
                low[m] = min(low[m], index[n])
        if low[m] == index[m]:
            members = []
            while True:
                n = stack.pop()
                on_stack.discard(n)
                members.append("::".join(n[1:]))
                if n == m:
                    break
            if len(members) > 1:
                found.append(sorted(members))

    sys.setrecursionlimit(10_000)
    for m in sorted(graph.files):
        if m not in index:
            visit(m)
    return sorted(found)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", type=Path, default=Path(__file__).resolve().parent.parent / "crates/lenspath/src")
    args = parser.parse_args()
    found = circles(Graph(args.src))
    for circle in found:
        print(" <-> ".join(circle))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
