"""No import circle between the library's files (scripts/module_graph.py finds them)."""

from __future__ import annotations

import sys
from pathlib import Path

from .conftest import REPO

sys.path.insert(0, str(REPO / "scripts"))
from module_graph import Graph, circles  # noqa: E402


def test_the_library_has_no_import_circle() -> None:
    assert circles(Graph(REPO / "crates/lenspath/src")) == [], "an import circle between the library's files"


def crate(tmp_path: Path, files: dict[str, str]) -> Graph:
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    return Graph(tmp_path)


def test_a_circle_through_uses_paths_and_re_exports_is_found(tmp_path: Path) -> None:
    graph = crate(
        tmp_path,
        {
            "lib.rs": "pub mod a;\npub mod b;\npub mod c;\npub mod d;\n",
            "a/mod.rs": "pub mod x;\npub use x::Thing;\nuse crate::{b::Bee, c};\n",
            "a/x.rs": "pub struct Thing;\nfn f() -> super::super::d::Dee { todo!() }\n",
            "b.rs": "pub mod measures;\npub use measures::FocusMeasure;\npub struct Bee;\n",
            "b/measures.rs": "pub struct FocusMeasure;\n",
            # Through a's re-export the edge is to a::x, through b's (of a name with "as" in it)
            # to b::measures; an alias names what is before it (b's Bee).
            "c.rs": "use crate::b::Bee as Honey;\nfn g(t: crate::a::Thing, s: crate::b::FocusMeasure) {}\n",
            "d.rs": 'pub struct Dee;\n// use crate::a::x;\nconst S: &str = "crate::a::x";\n',
        },
    )
    assert sorted("::".join(m[1:]) for m in graph.edges(("crate", "a"))) == ["b", "c"]
    assert graph.edges(("crate", "c")) == {("crate", "a", "x"), ("crate", "b"), ("crate", "b", "measures")}
    assert circles(graph) == []  # comments and strings in d.rs name a::x, but they are no edge
    (tmp_path / "d.rs").write_text("use crate::c;\n")
    (tmp_path / "c.rs").write_text("use crate::a::x::Thing;\n")
    (tmp_path / "a/x.rs").write_text("use crate::d::Dee;\n#[cfg(test)]\nmod tests {\n    use crate::b::Bee;\n}\n")
    graph = Graph(tmp_path)
    assert circles(graph) == [["a::x", "c", "d"]]
    assert ("crate", "b") not in graph.edges(("crate", "a", "x"))  # a unit test may reach anywhere
