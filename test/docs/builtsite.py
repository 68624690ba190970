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


def is_generated_api(page: Path) -> bool:
    """A page of FORD's Fortran API (``api/fortran/``): some 400 pages of procedures and types
    from a few templates, opened like every page but not kept as screenshots."""
    return page.parts[:2] == ("api", "fortran")


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:  # noqa: A002
        pass

    def end_headers(self) -> None:
        # the site does not change while it is served: without this, each page's scripts
        # and styles are fetched again (a third of a FORD page's time in the browser test)
        self.send_header("Cache-Control", "max-age=3600")
        super().end_headers()


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
