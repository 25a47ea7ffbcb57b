"""Check every relative link and anchor of the Markdown pages and of the built HTML site.

Usage (from the repository root)::

    python scripts/check_links.py                 # README.md, CHANGELOG.md, docs/*.md
    python scripts/check_links.py --html docs/_build/html   # and the built site

No network: links with a scheme (``https://``, ``mailto:``) are not followed (CI has no
network); every other link must name a file that exists, and its ``#anchor``, if any, must
be a heading of that page (GitHub's slugs for Markdown, ``id=`` for HTML). Exit status 1
and one line per broken link otherwise. ``scripts/docs.sh`` runs it after the build.
"""

from __future__ import annotations

import argparse
import html.parser
import re
import sys
import unicodedata
from pathlib import Path
from urllib.parse import unquote, urlsplit

ROOT = Path(__file__).resolve().parents[1]
MARKDOWN = ["README.md", "CHANGELOG.md", "docs/*.md"]
_LINK = re.compile(r"(?<!\\)\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_FENCE = re.compile(r"^(```|~~~)")


def github_slug(title: str) -> str:
    """The anchor GitHub (and MyST's ``myst_heading_anchors``) gives a Markdown heading."""
    text = re.sub(r"`([^`]*)`", r"\1", title)           # code spans keep their text
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links keep their text
    text = unicodedata.normalize("NFKC", text).strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def markdown_anchors(path: Path) -> set[str]:
    """The anchors of a Markdown page: one per heading, duplicates numbered as on GitHub."""
    seen: dict[str, int] = {}
    out: set[str] = set()
    fenced = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if _FENCE.match(line):
            fenced = not fenced
            continue
        m = None if fenced else _HEADING.match(line)
        if m:
            slug = github_slug(m.group(2))
            n = seen.get(slug, 0)
            out.add(slug if n == 0 else f"{slug}-{n}")
            seen[slug] = n + 1
        out.update(re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", line))
    return out


def markdown_links(path: Path) -> list[tuple[int, str]]:
    """``(line, target)`` of every inline link and image outside code blocks and spans."""
    out = []
    fenced = False
    for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            continue
        bare = re.sub(r"`[^`]*`", "", line)
        out += [(i, m.group(1)) for m in _LINK.finditer(bare)]
    return out


def _external(target: str) -> bool:
    return bool(urlsplit(target).scheme) or target.startswith("//")


def check_markdown(paths: list[Path]) -> list[str]:
    """Broken relative links and anchors of Markdown pages."""
    errors = []
    anchors: dict[Path, set[str]] = {}
    for page in paths:
        for line, target in markdown_links(page):
            if _external(target):
                continue
            parts = urlsplit(target)
            dest = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            where = f"{page.relative_to(ROOT)}:{line}: {target}"
            if not dest.exists():
                errors.append(f"{where}: no such file")
                continue
            if parts.fragment and dest.suffix == ".md":
                if dest not in anchors:
                    anchors[dest] = markdown_anchors(dest)
                if parts.fragment not in anchors[dest]:
                    errors.append(f"{where}: no heading with the anchor #{parts.fragment}")
    return errors


class _Collector(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[tuple[int, str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key):
                self.ids.add(str(a[key]))
        for key in ("href", "src"):
            if a.get(key) and not (tag == "link" and key == "href" and "preload" in
                                   str(a.get("rel", ""))):
                self.links.append((self.getpos()[0], str(a[key])))


def check_html(site: Path) -> list[str]:
    """Broken relative links and fragments of a built HTML site."""
    parsed: dict[Path, _Collector] = {}

    def parse(path: Path) -> _Collector:
        if path not in parsed:
            c = _Collector()
            c.feed(path.read_text(encoding="utf-8", errors="replace"))
            parsed[path] = c
        return parsed[path]

    errors = []
    for page in sorted(site.rglob("*.html")):
        if "_static" in page.parts or "_modules" in page.parts:
            continue
        for line, target in parse(page).links:
            if _external(target) or target.startswith(("javascript:", "data:")):
                continue
            parts = urlsplit(target)
            dest = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            where = f"{page.relative_to(site)}:{line}: {target}"
            if dest.is_dir():
                dest = dest / "index.html"
            if not dest.exists():
                errors.append(f"{where}: no such file")
                continue
            if parts.fragment and dest.suffix == ".html" and \
                    unquote(parts.fragment) not in parse(dest).ids:
                errors.append(f"{where}: no element with id {parts.fragment!r}")
    return errors


def main(argv: list[str] | None = None) -> int:
    """Check the Markdown pages (and the site with ``--html``); print what is broken."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--html", type=Path, default=None, metavar="DIR",
                    help="also check the built site in DIR (docs/_build/html)")
    args = ap.parse_args(argv)
    pages = sorted({p for pattern in MARKDOWN for p in ROOT.glob(pattern)})
    errors = check_markdown(pages)
    n_html = 0
    if args.html is not None:
        if not args.html.is_dir():
            print(f"--html: {args.html} is not a folder (build the site first)", file=sys.stderr)
            return 2
        errors += check_html(args.html.resolve())
        n_html = sum(1 for _ in args.html.rglob("*.html"))
    for e in errors:
        print(e)
    print(f"checked {len(pages)} Markdown pages" + (f" and {n_html} HTML pages" if n_html else "")
          + f": {len(errors)} broken link(s)", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
