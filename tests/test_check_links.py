"""scripts/check_links.py finds broken relative links and anchors; the pages have none."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("check_links", ROOT / "scripts/check_links.py")
cl = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cl)


def test_github_slugs() -> None:
    assert cl.github_slug("Live app (`athenakin app`)") == "live-app-athenakin-app"
    assert cl.github_slug("2.1 Parallel module (`parallel_jacobian`)") == \
        "21-parallel-module-parallel_jacobian"


def test_broken_links_and_anchors_are_reported(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(cl, "ROOT", tmp_path)
    (tmp_path / "b.md").write_text("# Title\n\n## Live app (`x`)\n\n```\n# not a heading\n```\n")
    a = tmp_path / "a.md"
    a.write_text("[ok](b.md#live-app-x) [file](c.md) [anchor](b.md#not-a-heading) "
                 "[web](https://example.org/x) `[code](nothing.md)` ![img](fig.png)\n")
    errors = cl.check_markdown([a])
    assert len(errors) == 3, errors
    assert any("c.md: no such file" in e for e in errors)
    assert any("#not-a-heading" in e for e in errors)
    assert any("fig.png: no such file" in e for e in errors)


def test_broken_html_fragment_is_reported(tmp_path) -> None:
    (tmp_path / "a.html").write_text('<a href="b.html#x">x</a><a href="b.html#y">y</a>'
                                     '<img src="missing.png">')
    (tmp_path / "b.html").write_text('<h1 id="x">x</h1>')
    errors = cl.check_html(tmp_path)
    assert len(errors) == 2, errors


def test_the_repository_pages_have_no_broken_link() -> None:
    pages = sorted({p for pattern in cl.MARKDOWN for p in ROOT.glob(pattern)})
    assert len(pages) >= 10
    assert cl.check_markdown(pages) == []
