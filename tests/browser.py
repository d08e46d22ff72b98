"""A real browser for the tests: Debian's headless Chromium, driven by Selenium through Debian's chromedriver.

Without a network: every request but to 127.0.0.1/localhost goes to a proxy that does not exist, so a page
that fetched anything from the web would show it as a console error. The tests that use it skip with the
reason when Chromium, its driver or Selenium is absent (``apt-get install chromium chromium-driver``).
"""

from __future__ import annotations

import shutil
from contextlib import contextmanager
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
try:
    import selenium  # noqa: F401

    SELENIUM = True
except ImportError:  # pragma: no cover - the test extra installs it
    SELENIUM = False

NO_BROWSER = (
    "Debian's chromium is not installed (apt-get install chromium chromium-driver)"
    if CHROMIUM is None
    else "Debian's chromedriver is not installed (apt-get install chromium-driver)"
    if CHROMEDRIVER is None
    else "selenium is not installed (the test extra installs it)"
    if not SELENIUM
    else ""
)
needs_browser = pytest.mark.skipif(bool(NO_BROWSER), reason=NO_BROWSER or "a browser is here")


@contextmanager
def browser(profile: Path, width: int = 1400, height: int = 1000):
    """A headless Chromium without a network (localhost only), its console logged; closed on exit."""
    from selenium import webdriver

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-quic",
        "--proxy-server=http://127.0.0.1:9",  # nothing listens there: no network but localhost
        f"--user-data-dir={profile}",
        f"--window-size={width},{height}",
        "--allow-file-access-from-files",
    ):
        opts.add_argument(arg)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=opts, service=webdriver.ChromeService(executable_path=CHROMEDRIVER))
    try:
        driver.set_page_load_timeout(60)
        yield driver
    finally:
        driver.quit()


def console_errors(driver) -> list[str]:
    """The console's errors since the last call (Chromium's SEVERE entries)."""
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def wait_loaded(driver, timeout: float = 30) -> None:
    """Wait until the page's load event has fired."""
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, timeout).until(
        lambda d: d.execute_script("return document.readyState") == "complete"
    )


_OPEN_EACH_FIGURE = """
const done = arguments[arguments.length - 1];
const imgs = Array.from(document.querySelectorAll(".bd-article img"));
const out = [];
(async () => {
  for (const img of imgs) {
    img.scrollIntoView();
    img.click();
    const box = document.querySelector(".glu-lightbox");
    const big = box ? box.querySelector("img") : null;
    for (let i = 0; i < 100 && big && !(big.complete && big.naturalWidth > 0); i++) {
      await new Promise((r) => setTimeout(r, 20));
    }
    const r = big ? big.getBoundingClientRect() : null;
    out.push({
      src: img.getAttribute("src"),
      inline: img.complete && img.naturalWidth > 0,
      open: !!(box && box.classList.contains("open")),
      natural: big ? [big.naturalWidth, big.naturalHeight] : null,
      shown: r ? [Math.round(r.width), Math.round(r.height)] : null,
      caption: box ? box.querySelector("figcaption").textContent.trim() : "",
      in_figure: !!img.closest("figure"),
    });
    document.dispatchEvent(new KeyboardEvent("keydown", { key: "Escape" }));
  }
  done(out);
})();
"""


_CLIPPED = r"""
const article = document.querySelector(".bd-article");
if (!article) { return []; }
const right = article.getBoundingClientRect().right;
const out = [];
article.querySelectorAll("table, pre").forEach((el) => {
  if (el.closest(".cell_input")) { return; }  // a notebook's code scrolls, as code does
  const box = el.parentElement;
  const r = el.getBoundingClientRect();
  if (el.scrollWidth > el.clientWidth + 1 || box.scrollWidth > box.clientWidth + 1 || r.right > right + 1) {
    out.push(el.tagName.toLowerCase() + " " + Math.round(el.scrollWidth) + " px: " +
             (el.innerText || "").trim().slice(0, 50).replace(/\s+/g, " "));
  }
});
return out;
"""


def _static_hrefs(page: Path) -> list[str]:
    """The links of a page read from its HTML, as the browser would resolve them (file URLs)."""
    import re
    from urllib.parse import urljoin

    hrefs = re.findall(r'<a\b[^>]*\bhref="([^"]+)"', page.read_text(encoding="utf-8"))
    return [urljoin(page.as_uri(), h.replace("&amp;", "&")) for h in hrefs]


def walk_site(driver, site: Path, browse=lambda name: True) -> dict:
    """Open every page of the built site ``site`` in ``driver``; return what went wrong, by kind.

    For each page: its console errors; its internal links whose file (or ``#anchor``) does not exist; each
    figure of the page clicked open: an image that did not render, or that did not open at its natural
    size, or a captioned figure opened without its caption; and every table, example and printed output
    that does not fit the page (scrolls, or runs past the article), a notebook's code cells aside. Also
    the pages no link reaches. A page for which ``browse(its name)`` is false is not opened: only its links
    are checked, read from its HTML (the API reference's modules, alike and many).
    """
    import re
    from urllib.parse import unquote, urlsplit

    problems: dict[str, list[str]] = {
        "console": [],
        "links": [],
        "images": [],
        "clipped": [],
        "unreachable": [],
    }
    pages = sorted(p for p in site.rglob("*.html") if "_static" not in p.relative_to(site).parts)
    ids: dict[Path, set[str]] = {}

    def anchors(page: Path) -> set[str]:
        if page not in ids:
            ids[page] = set(re.findall(r'\bid="([^"]+)"', page.read_text(encoding="utf-8")))
        return ids[page]

    linked: set[Path] = {site / "index.html"}
    n_images = 0
    for page in pages:
        name = page.relative_to(site).as_posix()
        if not browse(name):
            hrefs = _static_hrefs(page)
        else:
            driver.get(page.as_uri())
            wait_loaded(driver)
            hrefs = driver.execute_script(
                "return Array.from(document.querySelectorAll('a[href]')).map(a => a.href)"
            )
        for href in hrefs:
            parts = urlsplit(href)
            if parts.scheme != "file":
                continue
            target = Path(unquote(parts.path))
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                problems["links"].append(f"{name}: {href} (no such file)")
            elif target.suffix == ".html":
                linked.add(target)
                if parts.fragment and unquote(parts.fragment) not in anchors(target):
                    problems["links"].append(f"{name}: {href} (no such anchor)")
        if not browse(name):
            continue
        figures = driver.execute_async_script(_OPEN_EACH_FIGURE)
        n_images += len(figures)
        for f in figures:
            if not f["inline"]:
                problems["images"].append(f"{name}: {f['src']} did not render")
            elif not f["open"] or f["natural"] != f["shown"] or not f["natural"][0]:
                problems["images"].append(
                    f"{name}: {f['src']} opened at {f['shown']}, natural {f['natural']}"
                )
            elif f["in_figure"] and not f["caption"]:
                problems["images"].append(f"{name}: {f['src']} opened without its caption")
        problems["clipped"] += [f"{name}: {m}" for m in driver.execute_script(_CLIPPED)]
        problems["console"] += [f"{name}: {m}" for m in console_errors(driver)]
    problems["unreachable"] = [p.relative_to(site).as_posix() for p in pages if p not in linked]
    problems["unreachable"] = [
        p for p in problems["unreachable"] if p not in ("genindex.html", "search.html")
    ]
    return {"problems": problems, "pages": len(pages), "images": n_images}


def search(driver, site: Path, words: str, timeout: float = 30) -> list[str]:
    """The pages (relative to ``site``) the site's own search lists for ``words``."""
    from urllib.parse import quote, unquote, urlsplit

    from selenium.webdriver.support.ui import WebDriverWait

    driver.get((site / "search.html").as_uri() + f"?q={quote(words)}")
    wait_loaded(driver)
    script = "return Array.from(document.querySelectorAll('#search-results li a')).map(a => a.href)"
    WebDriverWait(driver, timeout).until(lambda d: d.execute_script(script))
    hrefs = driver.execute_script(script)
    return sorted({Path(unquote(urlsplit(h).path)).relative_to(site).as_posix() for h in hrefs})
