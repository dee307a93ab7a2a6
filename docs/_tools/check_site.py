"""Opens every page of the built site in headless Chromium and fails on a blank page or a
broken internal link.

    python check_site.py SITE_DIR

Each Sphinx page (every .html under SITE_DIR but the Rust reference, rust/, which cargo doc
wrote and checks itself) is loaded with `chromium --headless --dump-dom`, so what is checked is
the page as a browser renders it, scripts run. A page is blank when its main element (Sphinx's
role="main") holds fewer than MIN_TEXT characters of text. Every href and src of the rendered
pages that is not a URL with a scheme must name a file of the site, and its #fragment an id
of that file's rendered page (pages outside the checked set, such as rust/..., are parsed from
their files). Exits 1 with one line per fault.
"""
import concurrent.futures
import html.parser
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from urllib.parse import unquote, urlsplit

MIN_TEXT = 40
SKIPPED = ("rust/", "_static/", "_sources/", "_images/")


class Page(html.parser.HTMLParser):
    """The links, ids and main text of one rendered page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.links, self.ids, self.main_text = [], set(), []
        self._depth_in_main = 0  # > 0 inside the role="main" element
        self._hidden = 0  # > 0 inside <script> or <style>

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for key in ("id", "name"):
            if attrs.get(key):
                self.ids.add(attrs[key])
        for key in ("href", "src"):
            if attrs.get(key) and tag in ("a", "img", "link", "script", "iframe", "object"):
                self.links.append(attrs[key])
        if tag in ("script", "style"):
            self._hidden += 1
        if self._depth_in_main:
            self._depth_in_main += tag not in VOID
        elif attrs.get("role") == "main":
            self._depth_in_main = 1

    def handle_endtag(self, tag):
        if tag in ("script", "style"):
            self._hidden = max(0, self._hidden - 1)
        if self._depth_in_main and tag not in VOID:
            self._depth_in_main -= 1

    def handle_data(self, data):
        if self._depth_in_main and not self._hidden:
            self.main_text.append(data)


VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}


def render(path: Path, profile: str) -> str:
    """The DOM of a page after Chromium loaded it and ran its scripts."""
    run = subprocess.run(
        ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
         f"--user-data-dir={profile}", "--dump-dom", path.as_uri()],
        capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        raise RuntimeError(f"chromium failed on {path} (exit {run.returncode}): {run.stderr[-2000:]}")
    return run.stdout


def parse(text: str) -> Page:
    page = Page()
    page.feed(text)
    page.close()
    return page


def check(site: Path) -> list:
    site = site.resolve()
    pages = sorted(p for p in site.rglob("*.html") if not str(p.relative_to(site)).startswith(SKIPPED))
    with tempfile.TemporaryDirectory() as tmp, concurrent.futures.ThreadPoolExecutor(2) as pool:
        doms = dict(zip(pages, pool.map(lambda ip: render(ip[1], f"{tmp}/{ip[0]}"), enumerate(pages))))
    rendered = {p: parse(d) for p, d in doms.items()}
    faults = []
    for path, page in [(p, rendered[p]) for p in pages]:
        name = path.relative_to(site)
        text = "".join(page.main_text).strip()
        if len(text) < MIN_TEXT:
            faults.append(f"{name}: blank page ({len(text)} characters of text in its main element)")
        for link in page.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc:
                continue  # http(s), mailto, data: not the site's
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if target.is_dir():
                target = target / "index.html"
            if not target.is_file() or site not in target.parents:
                faults.append(f"{name}: link {link!r} names no file of the site")
                continue
            if parts.fragment and target.suffix == ".html":
                if target not in rendered:
                    rendered[target] = parse(target.read_text(encoding="utf-8", errors="replace"))
                if unquote(parts.fragment) not in rendered[target].ids:
                    faults.append(f"{name}: link {link!r}: no id {parts.fragment!r} in {target.relative_to(site)}")
    print(f"check_site: {len(pages)} pages rendered, {sum(len(rendered[p].links) for p in pages)} links, "
          f"{len(faults)} faults", flush=True)
    return faults


if __name__ == "__main__":
    site = Path(sys.argv[1])
    faults = check(site)
    for fault in faults:
        print("check_site:", fault, file=sys.stderr)
    sys.exit(1 if faults else 0)
