"""Prints of a self-contained HTML page (the datasheet) through headless Chromium: a PDF (``--print-to-pdf``; the
page's own ``@page`` CSS sets the paper, A4, with no header or footer) or a PNG of the whole page
(``--screenshot``, twice the CSS pixel density).

The browser is ``$SCALESYNTH_CHROMIUM`` when set, else the first of BROWSER_NAMES on PATH. Each print runs one
browser with its own temporary profile and home, network off (no DNS, a dead proxy), in its own process group,
killed after ``timeout_s``. What it writes is checked (a PDF with at least one page, a PNG of the asked size)
before it is written atomically to its target.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import struct
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from scalesynth.errors import ConfigError, RunError

KINDS = ("pdf", "png", "none")
BROWSER_ENV = "SCALESYNTH_CHROMIUM"
BROWSER_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
INSTALL_HINT = f"install Chromium (Debian: apt-get install chromium) or set {BROWSER_ENV} to its executable"
TIMEOUT_S = 120.0  # one browser run; a datasheet prints in about 2 s on an idle machine
PNG_WIDTH_PX = 1040  # CSS pixels: the datasheet's 980 px column and its margins
PNG_SCALE = 2  # device pixels per CSS pixel (a print-sharp image)
PNG_MAX_HEIGHT_PX = 12000  # CSS pixels: a longer page is cut there (the PNG stays a few MB at most)
# the browser renders only our own page: no network (every host name fails to resolve; any connection goes to a
# closed local port), no first-run, sync, extension or update traffic. --no-sandbox: the sandbox needs user
# namespaces that containers (CI) often lack, and the page is ours with the network off.
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--no-default-browser-check",
         "--disable-extensions", "--disable-sync", "--disable-background-networking", "--disable-component-update",
         "--disable-default-apps", "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
         "--proxy-bypass-list=<-loopback>", "--hide-scrollbars", "--mute-audio")
PDF_FLAGS = ("--no-pdf-header-footer", "--print-to-pdf-no-header")  # the second: Chromium before 111
_HEIGHT_ATTR = "data-scalesynth-height"
_MEASURE = (f"<script>document.body.setAttribute('{_HEIGHT_ATTR}', "
            "Math.ceil(document.documentElement.scrollHeight));</script>")


@dataclass(frozen=True)
class PrintPlan:
    """What a command prints: ``kind`` 'pdf' or 'png' with the ``browser`` to use, or None (no print); ``explicit``:
    the user asked for it (a failure is an error, not a note); ``note``: why a default print is skipped."""

    kind: str | None
    browser: str | None = None
    explicit: bool = False
    note: str | None = None


def find_browser() -> str | None:
    """The Chromium executable: $SCALESYNTH_CHROMIUM (ConfigError if it is not an executable file), else the
    first of BROWSER_NAMES on PATH, else None."""
    given = os.environ.get(BROWSER_ENV)
    if given:
        path = shutil.which(given)
        if path is None:
            raise ConfigError(f"{BROWSER_ENV}: {given[:80]!r} is not an executable (give Chromium's path, or unset "
                              "it to search PATH)")
        return path
    return next((p for p in map(shutil.which, BROWSER_NAMES) if p), None)


def plan(option: str | None, flag: str = "--print") -> PrintPlan:
    """The print a command makes for ``--print option``: None (the default) prints a PDF when a browser is found,
    else none with a note; 'none' prints nothing; 'pdf'/'png' need a browser (ConfigError, exit 2, before any
    work, when none is found)."""
    if option is not None and option not in KINDS:
        raise ConfigError(f"{flag}: expected one of {', '.join(KINDS)}, got {option[:40]!r}")
    if option == "none":
        return PrintPlan(None)
    browser = find_browser()
    if option is None:
        if browser is None:
            return PrintPlan(None, note=f"no print of the datasheet: no Chromium found; {INSTALL_HINT} (or "
                                        f"{flag} none: no print, no note)")
        return PrintPlan("pdf", browser)
    if browser is None:
        raise ConfigError(f"{flag} {option}: no Chromium found; {INSTALL_HINT}")
    return PrintPlan(option, browser, explicit=True)


def print_target(html_path: Path, kind: str) -> Path:
    """Where the print of ``html_path`` goes: beside it, with the kind as its suffix."""
    return Path(html_path).with_suffix("." + kind)


def pdf_pages(data: bytes) -> int:
    """Number of page objects (``/Type /Page``, not ``/Pages``) in a PDF's bytes; 0 if it is not a PDF."""
    if not data.startswith(b"%PDF-"):
        return 0
    return len(re.findall(rb"/Type\s*/Page(?![A-Za-z])", data))


def png_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) pixels of a PNG's bytes from its header; None if it is not a PNG."""
    if len(data) < 24 or not data.startswith(b"\x89PNG\r\n\x1a\n") or data[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", data[16:24])


def _run(browser: str, args: list[str], tmp: Path, timeout_s: float, flag: str) -> str:
    """Run the browser once (own profile and home under ``tmp``, own process group); its stdout."""
    profile = tmp / f"profile{len(list(tmp.glob('profile*')))}"
    home = str(tmp / "home")
    env = dict(os.environ, HOME=home, XDG_CONFIG_HOME=home, XDG_CACHE_HOME=home)
    try:
        proc = subprocess.Popen([browser, *FLAGS, f"--user-data-dir={profile}", *args], stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL, env=env, text=True,
                                start_new_session=True)
    except OSError as err:
        raise RunError(f"{flag}: cannot start {browser} ({err.strerror or err})") from None
    try:
        out, _ = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        _kill(proc)
        raise RunError(f"{flag}: the browser did not finish within {timeout_s:g} s") from None
    finally:
        if proc.poll() is None:  # interrupted (Ctrl-C): no browser left behind
            _kill(proc)
    return out


def _kill(proc: subprocess.Popen) -> None:
    """Kill the browser and its helpers (renderer, zygote: its process group), then reap it."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.communicate()


def print_html(text: str, target: Path, kind: str, browser: str, timeout_s: float = TIMEOUT_S,
               flag: str = "--print") -> tuple[int, int] | int:
    """Print the HTML ``text`` to ``target`` (written atomically): 'pdf' returns its page count, 'png' its
    (width, height) pixels. RunError (exit 1) when the browser fails, times out or writes no valid file."""
    from scalesynth import io as rio

    with tempfile.TemporaryDirectory(prefix="scalesynth-print-") as name:
        tmp = Path(name)
        page = tmp / "page.html"
        out = tmp / f"page.{kind}"
        if kind == "pdf":
            page.write_text(text, encoding="utf-8")
            _run(browser, [*PDF_FLAGS, f"--print-to-pdf={out}", page.as_uri()], tmp, timeout_s, flag)
            data = out.read_bytes() if out.is_file() else b""
            result: tuple[int, int] | int = pdf_pages(data)
            if not result:
                raise RunError(f"{flag} pdf: the browser wrote no PDF ({browser})")
        elif kind == "png":
            height = _page_height(text, page, browser, tmp, timeout_s, flag)
            page.write_text(text, encoding="utf-8")
            _run(browser, [f"--window-size={PNG_WIDTH_PX},{height}", f"--force-device-scale-factor={PNG_SCALE}",
                           f"--screenshot={out}", page.as_uri()], tmp, timeout_s, flag)
            data = out.read_bytes() if out.is_file() else b""
            result = png_size(data)
            if result != (PNG_WIDTH_PX * PNG_SCALE, height * PNG_SCALE):
                raise RunError(f"{flag} png: the browser wrote no PNG of {PNG_WIDTH_PX} x {height} px ({browser})")
        else:
            raise ConfigError(f"{flag}: expected pdf or png, got {kind[:40]!r}")
        rio.write_atomic(Path(target), lambda fh: fh.write(data), mode="wb")
    return result


def _page_height(text: str, page: Path, browser: str, tmp: Path, timeout_s: float, flag: str) -> int:
    """CSS pixel height of the page laid out PNG_WIDTH_PX wide (a measuring copy's script reports it)."""
    at = text.rfind("</body>")
    page.write_text(text[:at] + _MEASURE + text[at:] if at >= 0 else text + _MEASURE, encoding="utf-8")
    dom = _run(browser, [f"--window-size={PNG_WIDTH_PX},200", "--dump-dom", page.as_uri()], tmp, timeout_s, flag)
    found = re.search(_HEIGHT_ATTR + r'="(\d+)"', dom)
    if found is None:
        raise RunError(f"{flag} png: the browser did not lay the page out ({browser})")
    return max(1, min(int(found.group(1)), PNG_MAX_HEIGHT_PX))
