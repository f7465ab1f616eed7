"""Open an HTML file in headless Chromium (Debian's `chromium` package): the DOM after its scripts ran, the errors
its scripts raised or logged, and a screenshot.

A copy of the page gets a first <script> that records uncaught errors, unhandled rejections and console.error
calls into a <pre id="__errors__"> element, so `--dump-dom` shows them (Chromium's own log does not tell a page's
console.error from console.log).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--enable-unsafe-swiftshader", "--hide-scrollbars", "--window-size=1280,1800")

_HOOK = """<script>(function(){var log=[];function put(m){log.push(String(m));
var e=document.getElementById('__errors__');
if(!e&&document.body){e=document.createElement('pre');e.id='__errors__';document.body.appendChild(e);}
if(e){e.textContent=log.join('\\n');}}
window.addEventListener('error',function(ev){put('error: '+ev.message);});
window.addEventListener('unhandledrejection',function(ev){put('rejection: '+ev.reason);});
var ce=console.error;console.error=function(){put('console.error: '+Array.prototype.join.call(arguments,' '));
return ce.apply(console,arguments);};
document.addEventListener('DOMContentLoaded',function(){put('__loaded__');});})();</script>"""


def chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def need_chromium() -> None:
    """Skip the calling test where Chromium is missing; fail it under CI=true (CI installs Debian's chromium)."""
    import pytest

    if chromium() is None:
        if os.environ.get("CI") == "true":
            pytest.fail("chromium is not installed (CI must install Debian's chromium package)")
        pytest.skip("chromium not installed (apt-get install chromium)")


def _run(exe: str, args: list[str], profile: str, timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run([exe, *FLAGS, f"--user-data-dir={profile}", *args], capture_output=True, text=True,
                          timeout=timeout, env=dict(os.environ, HOME=profile))


def open_page(html: Path, screenshot: Path, timeout: float = 120.0, budget_ms: int = 15000) -> dict:
    """{"dom": str, "errors": [str], "loaded": bool, "pixels": (h, w, 3) uint8 array} of the page."""
    exe = chromium()
    if exe is None:
        raise FileNotFoundError("chromium")
    text = Path(html).read_text(encoding="utf-8")
    hooked = text.replace("<head>", "<head>" + _HOOK, 1) if "<head>" in text else _HOOK + text
    with tempfile.TemporaryDirectory() as tmp:
        page = Path(tmp) / Path(html).name
        page.write_text(hooked, encoding="utf-8")
        url = page.resolve().as_uri()
        budget = f"--virtual-time-budget={budget_ms}"
        dom = _run(exe, [budget, "--dump-dom", url], str(Path(tmp) / "p1"), timeout).stdout
        _run(exe, [budget, f"--screenshot={screenshot}", url], str(Path(tmp) / "p2"), timeout)
    import matplotlib.image as mpimg

    pixels = (mpimg.imread(screenshot)[..., :3] * 255).astype(np.uint8) if Path(screenshot).is_file() else None
    errors = []
    start = dom.find('id="__errors__"')
    if start >= 0:
        body = dom[dom.index(">", start) + 1: dom.index("</pre>", start)]
        errors = [line for line in body.splitlines() if line and line != "__loaded__"]
    return {"dom": dom, "errors": errors, "loaded": "__loaded__" in dom, "pixels": pixels}
