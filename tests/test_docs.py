"""The documentation site: built with warnings as errors, opened in headless Chromium.

The session fixture runs the Sphinx build of `make docs` (incremental: after `make docs`
it only checks that nothing changed), so the test never looks at a stale or missing
site. Then:

- every page's internal links (href, src) point to files of the site that exist, and
  every #fragment to an id of its page;
- every image a page shows is a valid PNG or SVG, and nothing is loaded from the network
  (the site works offline);
- Chromium opens the landing page, a demo page and the method page, takes a screenshot
  of each (kept in docs/_build/screenshots) and reports, from inside the page, that
  every image loaded (complete, natural width > 0), that MathJax typeset every
  equation without a TeX error, and that no script of the page failed.
"""
from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from conftest import ROOT

pytestmark = pytest.mark.slow  # builds the site: 1-4 minutes on 2 cores

DOCS = ROOT / "docs"
HTML = DOCS / "_build" / "html"
SHOTS = DOCS / "_build" / "screenshots"
#: The pages opened in Chromium, and whether each must show images.
PAGES = {"index.html": True, "demos/demo_signorini_square.html": True, "method.html": False}


@pytest.fixture(scope="module")
def site() -> Path:
    """The built site (the `make docs` command, incremental). Sphinx and Chromium are
    Debian packages that `make test` installs (DOCS_DEBS): their absence is a failure."""
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-n", "-q"]
    proc = subprocess.run(
        [*cmd, str(DOCS), str(HTML)], capture_output=True, text=True, cwd=ROOT, timeout=900
    )
    assert proc.returncode == 0, f"make docs failed:\n{proc.stderr[-6000:]}"
    return HTML


class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[tuple[str, str]] = []  # (tag, url)
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("name"):
            self.ids.add(a["name"])
        for key in ("href", "src"):
            if a.get(key) and not (tag == "link" and a.get("rel") in ("canonical",)):
                self.links.append((tag, a[key]))


def _parse(path: Path) -> _Links:
    parser = _Links()
    parser.feed(path.read_text(errors="replace"))
    return parser


def _is_image(path: Path) -> bool:
    head = path.read_bytes()[:512]
    if path.suffix.lower() == ".png":
        return head.startswith(b"\x89PNG\r\n\x1a\n")
    if path.suffix.lower() == ".svg":
        return b"<svg" in path.read_bytes()[:4096]
    return head.startswith((b"\xff\xd8", b"GIF8"))  # jpeg, gif


def test_internal_links_and_images_of_every_page(site):
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 50, "the API reference is missing"
    parsed = {p: _parse(p) for p in pages}
    broken, external, bad_images = [], [], []
    for page, parser in parsed.items():
        for tag, url in parser.links:
            parts = urlsplit(url)
            if parts.scheme in ("http", "https") or url.startswith("//"):
                if tag in ("script", "img", "link", "iframe"):
                    external.append(f"{page.relative_to(site)}: {url}")
                continue
            if parts.scheme in ("mailto", "data", "javascript"):
                continue
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.is_file():
                broken.append(f"{page.relative_to(site)}: {url}")
                continue
            if parts.fragment and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{page.relative_to(site)}: {url} (no such anchor)")
            if tag == "img" and not _is_image(target):
                bad_images.append(f"{page.relative_to(site)}: {url}")
    assert not broken, "broken internal links:\n" + "\n".join(broken[:40])
    assert not external, "resources loaded from the network:\n" + "\n".join(external[:40])
    assert not bad_images, "images that are not valid files:\n" + "\n".join(bad_images)


#: Injected into a copy of a page: after the load event and the MathJax queue, write
#: what the browser saw into the DOM, which Chromium then dumps.
_PROBE = """
<script type="text/x-mathjax-config">
window.fembemTexErrors = [];
MathJax.Hub.Register.MessageHook("TeX Jax - parse error", function (message) {
  window.fembemTexErrors.push(String(message[1]));
});
</script>
<script>
function fembemReport() {
  const images = Array.from(document.images).map(
    (img) => [img.getAttribute("src"), img.complete && img.naturalWidth > 0]);
  const report = {
    images: images,
    mathjax: typeof MathJax !== "undefined",
    typeset: document.querySelectorAll(".MathJax_SVG, .MathJax_SVG_Display").length,
    mathErrors: window.fembemTexErrors || [],
    rawMath: document.querySelectorAll(".math").length,
    text: document.body.innerText.length,
  };
  const out = document.createElement("pre");
  out.id = "fembem-report";
  // the markers are built here so that this script's own text does not contain them
  out.textContent = ["FEMBEM", "REPORT"].join("-") + JSON.stringify(report)
    + ["FEMBEM", "END"].join("-");
  document.body.appendChild(out);
}
window.addEventListener("load", function () {
  if (typeof MathJax !== "undefined" && MathJax.Hub) {
    MathJax.Hub.Register.StartupHook("End", fembemReport);  // after the first typeset
  } else {
    fembemReport();
  }
});
</script>
"""


def _chromium() -> str:
    exe = shutil.which("chromium")
    assert exe, "chromium not found: `make docs` installs it (Debian package chromium)"
    return exe


def _browser(*args: str) -> subprocess.CompletedProcess:
    cmd = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",  # containers have a small /dev/shm
        "--hide-scrollbars",
        "--allow-file-access-from-files",
        "--virtual-time-budget=20000",
        *args,
    ]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=180)


def _browser_report(page: Path) -> dict:
    probe = page.with_name(f"_probe_{page.name}")
    text = page.read_text()
    probe.write_text(text.replace("</body>", _PROBE + "</body>"))
    try:
        proc = _browser("--enable-logging=stderr", "--v=0", "--dump-dom", probe.as_uri())
    finally:
        probe.unlink()
    m = re.search(r"FEMBEM-REPORT(\{.*?\})FEMBEM-END", proc.stdout, re.S)
    assert m, f"no report from the page {page.name}:\n{proc.stderr[-3000:]}"
    report = json.loads(html.unescape(m.group(1)))
    # the page's own JavaScript errors (Chromium logs console messages as ":CONSOLE")
    report["scriptErrors"] = [
        line for line in proc.stderr.splitlines() if ":CONSOLE" in line and "Uncaught" in line
    ]
    return report


@pytest.mark.parametrize("name", PAGES)
def test_page_renders_in_chromium(site, name):
    page = site / name
    assert page.is_file(), name
    SHOTS.mkdir(parents=True, exist_ok=True)
    shot = SHOTS / (name.replace("/", "_").replace(".html", ".png"))
    shot.unlink(missing_ok=True)
    proc = _browser(f"--screenshot={shot}", "--window-size=1280,1600", page.as_uri())
    assert shot.is_file(), proc.stderr[-3000:]
    from PIL import Image  # python3-pil, a dependency of matplotlib

    with Image.open(shot) as image:
        assert image.size == (1280, 1600)
        gray = image.convert("L")
        lo, hi = gray.getextrema()
        histogram = gray.histogram()
    assert hi - lo > 100, "the screenshot is blank"
    # a rendered page: most pixels background, but a real share of text and pictures
    assert max(histogram) < 0.98 * sum(histogram), "the screenshot is (nearly) one colour"

    report = _browser_report(page)
    assert report["text"] > 500, report
    assert not report["scriptErrors"], report["scriptErrors"]
    assert bool(report["images"]) == PAGES[name], f"{name}: images {report['images']}"
    failed = [src for src, ok in report["images"] if not ok]
    assert not failed, f"images that did not load in {name}: {failed}"
    if report["rawMath"]:
        assert report["mathjax"], "MathJax did not load (offline copy missing?)"
        assert report["typeset"] >= report["rawMath"], report
        assert not report["mathErrors"], report["mathErrors"]


def test_a_demo_page_s_contents_box_holds_its_contents(tmp_path):
    """Issue 66, item 12: the box titled "On this page" held a note on how the page was
    run; it now links the page's sections, the note under its own title. (The page's
    text, without building the site.)"""
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        from fembem_docs.demo_pages import _page
    finally:
        sys.path.pop(0)
    demo = ROOT / "demos" / "demo_own_body.py"
    run = tmp_path / "run"
    (run / "out").mkdir(parents=True)
    (run / "stdout.txt").write_text("")
    text, _ = _page(demo, run, tmp_path / "figures", "_figures")
    box = text.index("```{admonition} On this page")
    note = text.index("```{admonition} How this page was run")
    entries = text[box:note].splitlines()[3:-2]
    assert entries == [
        "- {ref}`Build and mesh the body with gmsh (rank 0) <demo_own_body-section-1>`",
        "- {ref}`Read, solve, check <demo_own_body-section-2>`",
        "- {ref}`Outputs <demo_own_body-section-3>`",
        "- {ref}`The script <demo_own_body-source>`",
    ]
    assert "(demo_own_body-section-2)=\n## Read, solve, check" in text
    assert note < text.index("## Build and mesh the body") and text.count("On this page") == 1
