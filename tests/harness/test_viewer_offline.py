"""The inline Rerun viewer of notebook 08 works offline: its JavaScript and WebAssembly come from the
installed rerun-notebook, served on localhost by the kernel (glu.machine.viewer_class), never from
app.rerun.io."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest
from browser import browser, console_errors, needs_browser, wait_loaded

pytest.importorskip("rerun_notebook", reason="rerun-notebook is not installed (the lab extra installs it)")

_KERNEL = """
import sys
from glu.machine import viewer_class
assert viewer_class() is not None
import rerun_notebook
print("viewer:", rerun_notebook.ESM_MOD, rerun_notebook.__version__, flush=True)
sys.stdin.read()  # serve the viewer's files until the test is done
"""

_PAGE = """<!DOCTYPE html><html><head><meta charset="utf-8"><title>viewer</title></head><body>
<script type="module">
async function load(url) {
  const out = {url: url};
  try {
    const m = await import(url);
    out.render = typeof m.default.render;
    const r = await fetch(new URL("re_viewer_bg.wasm", url));
    const bytes = new Uint8Array(await r.arrayBuffer());
    out.wasm = [bytes.length, Array.from(bytes.slice(0, 4))];
  } catch (e) {
    out.error = String(e);
  }
  return out;
}
window.results = [await load(LOCAL), await load(WEB)];
</script></body></html>
"""


@needs_browser
def test_the_inline_viewer_loads_its_files_from_the_installed_package_without_a_network(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "RERUN_NOTEBOOK_ASSET"}
    kernel = subprocess.Popen(
        [sys.executable, "-c", _KERNEL],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=env,
    )
    try:
        line = ""
        while not line.startswith("viewer:"):  # rerun-notebook says a few words of its own first
            line = kernel.stdout.readline()
            assert line, "the kernel-like process ended before naming the viewer's files"
        _, local, version = line.split()
        assert local.startswith("http://localhost:") and local.endswith("/widget.js"), local
        # rerun-notebook's default, as a control: the same files from the web, which this browser cannot reach
        web = f"https://app.rerun.io/version/{version}/notebook/widget.js"
        page = tmp_path / "viewer.html"
        page.write_text(_PAGE.replace("LOCAL", json.dumps(local)).replace("WEB", json.dumps(web)))
        with browser(tmp_path / "profile") as driver:
            driver.get(page.as_uri())
            wait_loaded(driver)
            results = None
            deadline = time.monotonic() + 120
            while results is None and time.monotonic() < deadline:
                results = driver.execute_script("return window.results || null")
                time.sleep(0.2)
            errors = console_errors(driver)
    finally:
        kernel.stdin.close()
        kernel.terminate()
        kernel.wait(timeout=30)
    assert results is not None, "the page never finished loading the viewer"
    served, fetched = results
    assert served.get("error") is None, served
    assert served["render"] == "function"  # the anywidget module of the viewer
    assert served["wasm"][0] > 10**6 and served["wasm"][1] == [0, 97, 115, 109]  # "\0asm": the viewer itself
    assert "error" in fetched, "the web was reachable: this test cannot tell offline from online"
    assert not [e for e in errors if "localhost" in e], errors
