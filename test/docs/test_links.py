"""Every internal link and anchor of the built site resolves: each href and src that points
into site/ names a file there, and each #fragment an id (or a name) on the page it names."""

from __future__ import annotations

from functools import cache
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from builtsite import SITE, pages


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.anchors: set[str] = set()
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        for name in ("id", "name") if tag != "meta" else ():
            if values.get(name):
                self.anchors.add(values[name])
        for name in ("href", "src"):
            if values.get(name) and tag in ("a", "img", "link", "script", "iframe", "source"):
                self.links.append(values[name])


@cache
def _parsed(page: Path) -> _Page:
    parser = _Page()
    parser.feed((SITE / page).read_text(encoding="utf-8", errors="replace"))
    return parser


def _internal(link: str) -> bool:
    parts = urlsplit(link)
    return not parts.scheme and not parts.netloc and not link.startswith("//")


def broken_links(page: Path) -> list[str]:
    """The internal links of ``page`` that name no file, or no anchor on that file."""
    broken = []
    for link in _parsed(page).links:
        if not _internal(link):
            continue
        parts = urlsplit(link)
        if not parts.path:
            target = SITE / page
        elif parts.path.startswith("/"):                  # from the site's root (404.html)
            target = SITE / unquote(parts.path).lstrip("/")
        else:
            target = (SITE / page).parent / unquote(parts.path)
        target = target.resolve()
        if target.is_dir():
            target = target / "index.html"
        if SITE.resolve() not in target.parents or not target.is_file():
            broken.append(f"{link} (no file)")
        elif parts.fragment and target.suffix == ".html":
            anchor = unquote(parts.fragment)
            if anchor not in _parsed(target.relative_to(SITE.resolve())).anchors:
                broken.append(f"{link} (no anchor '{anchor}')")
    return broken


@pytest.mark.parametrize("page", pages(), ids=str)
def test_every_internal_link_resolves(page: Path) -> None:
    assert not broken_links(page), f"{page}: {broken_links(page)}"
