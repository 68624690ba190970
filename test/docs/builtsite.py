"""The built site (site/, `make docs`) for the tests of this folder: its pages, a local
server (the search's web worker and the notebooks' scripts need http, not file://)."""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SITE = ROOT / "site"


def pages() -> list[Path]:
    """Every HTML page of the site, relative to it."""
    if not (SITE / "index.html").is_file():
        raise FileNotFoundError(f"no site in {SITE}: build it with `make docs`")
    return sorted(p.relative_to(SITE) for p in SITE.rglob("*.html"))


def pages_to_open() -> list[Path]:
    """The pages the browser test opens: every page but FORD's, whose 400 pages of procedures
    and types share a few templates (minutes on a loaded machine): of those, the index and
    the first page of each kind (module, procedure, type, interface, list). test_links.py
    reads every page."""
    chosen = []
    seen: set[Path] = set()
    for page in pages():
        if page.parts[:2] != ("api", "fortran") or page.parent == Path("api/fortran"):
            chosen.append(page)
        elif page.parent not in seen:
            seen.add(page.parent)
            chosen.append(page)
    return chosen


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:  # noqa: A002
        pass


@contextmanager
def served() -> Iterator[str]:
    """The site on a local port: its base URL."""
    handler = functools.partial(_Quiet, directory=str(SITE))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
