"""Check the internal links of the built documentation site, offline.

Every relative ``href`` and ``src`` in every HTML page under the site folder must name a
file inside the site, and every ``#fragment`` must name an element id (or anchor name) of
the page it points to. Build into a clean folder first (``make docs`` does): pages left
over from an earlier build are checked too. External links (http, https, mailto, ...) are not fetched.

Run:  python tools/check_links.py [SITE]    (default docs/_build/html; exit status 1 on a
broken link, with one line per link)
"""

from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

LINK_ATTRIBUTES = {"a": "href", "link": "href", "img": "src", "script": "src", "source": "src", "iframe": "src"}


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.links: list[tuple[str, int]] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        values = dict(attrs)
        for key in ("id", "name") if tag == "a" else ("id",):
            if values.get(key):
                self.ids.add(values[key])
        attribute = LINK_ATTRIBUTES.get(tag)
        if attribute and values.get(attribute) is not None:
            self.links.append((values[attribute], self.getpos()[0]))
        if tag == "img" and values.get("srcset"):
            for part in values["srcset"].split(","):
                if part.strip():
                    self.links.append((part.split()[0], self.getpos()[0]))


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def _pages(site: Path) -> list[Path]:
    """The site's pages; ``_static`` holds the theme's assets and templates, not pages."""
    return sorted(p for p in site.rglob("*.html") if "_static" not in p.relative_to(site).parts)


def broken_links(site: Path) -> list[str]:
    """One line per broken internal link or image of the site at ``site``."""
    site = site.resolve()
    pages = {path: _parse(path) for path in _pages(site)}
    problems = []
    for path, page in pages.items():
        for link, line in page.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or link.startswith("//"):
                continue  # external: not checked offline
            where = f"{path.relative_to(site)}:{line}: {link}"
            if parts.path:
                target = (path.parent / unquote(parts.path)).resolve()
                if target.is_dir():
                    target = target / "index.html"
                if site not in target.parents and target != site:
                    problems.append(f"{where}: points outside the site")
                    continue
                if not target.is_file():
                    problems.append(f"{where}: no such file")
                    continue
            else:
                target = path
            fragment = unquote(parts.fragment)
            if fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if fragment not in ids:
                    problems.append(f"{where}: no anchor #{fragment} in {target.relative_to(site)}")
    return problems


def main(argv: list[str]) -> int:
    site = Path(argv[1]) if len(argv) > 1 else Path("docs/_build/html")
    if not (site / "index.html").is_file():
        print(f"error: {site} holds no built site (index.html); run make docs first", file=sys.stderr)
        return 2
    problems = broken_links(site)
    pages = len(_pages(site))
    for problem in problems:
        print(problem)
    print(f"{pages} pages checked: {len(problems)} broken internal link(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
