"""The files of the repository that the site shows but docs/ does not hold.

The pages of docs/ link to the paper's figures as ``../figures/NAME.png`` and to the README as
``../README.md`` (links that work where the repository itself is read); the site takes those
figures, the gallery's own pages and the changelog from the repository, and points the
README's links at the site's first page. MathJax is served from the site (no network).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
# repository files put into the site at the same relative path
SHOWN = ["figures/*.png", "gallery/*/README.md", "gallery/*/*.png"]
# MathJax 3's TeX-to-HTML component, its fonts and the TeX extensions it loads on demand
MATHJAX_FILES = ["tex-mml-chtml.js", "output/chtml/fonts/woff-v2/*", "input/**/*", "ui/**/*",
                 "a11y/**/*"]
OUT_OF_DOCS = re.compile(r"\]\(\.\./((?:figures|gallery)/[^)\s]+)\)")


def _mathjax_root() -> Path:
    import mathjax  # the package django-static-mathjax
    return Path(mathjax.__file__).parent / "static" / "mathjax" / "es5"


def on_files(files: Any, config: Any) -> Any:
    """MkDocs hook: the figures, the gallery's pages, the changelog and MathJax."""
    from mkdocs.structure.files import File

    for pattern in SHOWN:
        for path in sorted(ROOT.glob(pattern)):
            files.append(File.generated(config, path.relative_to(ROOT).as_posix(),
                                        abs_src_path=str(path)))
    # pdoc's pages name no icon, so a browser asks for the site's /favicon.ico
    import material
    files.append(File.generated(config, "favicon.ico", abs_src_path=str(
        Path(material.__file__).parent / "templates" / "assets" / "images" / "favicon.png")))
    files.append(File.generated(config, "changelog.md",
                                content=(ROOT / "CHANGELOG.md").read_text(encoding="utf-8")))
    mathjax = _mathjax_root()
    for pattern in MATHJAX_FILES:
        for path in sorted(mathjax.glob(pattern)):
            if path.is_file():
                files.append(File.generated(
                    config, "javascripts/mathjax/" + path.relative_to(mathjax).as_posix(),
                    abs_src_path=str(path)))
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """Links out of docs/ into the same files inside the site."""
    depth = page.file.src_uri.count("/")
    up = "../" * depth
    markdown = OUT_OF_DOCS.sub(lambda m: f"]({up}{m.group(1)})", markdown)
    return markdown.replace("](../README.md)", f"]({up}index.md)")


FORD_INTERFACE_LINK = re.compile(r'href="([^"]*)#moduleprocedure-')
FORD_MATHJAX = re.compile(
    r'<script src="https://cdnjs\.cloudflare\.com/ajax/libs/mathjax/[^"]*"></script>')


def on_post_build(config: Any) -> None:
    """FORD's (6.1) pages: its MathJax comes from a CDN, replaced here by the
    site's own copy with the site's configuration; and it links the procedures of a generic
    interface as ``#moduleprocedure-NAME`` while their headings carry ``id="proc-NAME"``; and
    its search page."""
    site = Path(config["site_dir"])
    # written even with `search: false` (docs/ford.md), without the script it calls: no page
    # links to it
    (site / "api" / "fortran" / "search.html").unlink(missing_ok=True)
    for page in (site / "api" / "fortran").rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        up = "../" * (len(page.relative_to(site).parts) - 1)
        fixed = FORD_MATHJAX.sub(
            f'<script src="{up}javascripts/mathjax-config.js"></script>\n'
            f'<script src="{up}javascripts/mathjax/tex-mml-chtml.js"></script>', text)
        fixed = FORD_INTERFACE_LINK.sub(r'href="\1#proc-', fixed)
        if fixed != text:
            page.write_text(fixed, encoding="utf-8")
