"""scalesynth.html_print (the datasheet's PDF/PNG print through headless Chromium) without a real browser: the
--print choice and a missing browser, $SCALESYNTH_CHROMIUM, what the browser is told (own profile, no network),
the checks of what it writes, and the timeout that kills it with its helpers. The prints of a real datasheet in
Chromium are in tests/test_design.py."""

import stat
import struct
import time
import zlib
from pathlib import Path

import pytest

from scalesynth import html_print
from scalesynth.errors import ConfigError, RunError

PAGE = "<!DOCTYPE html><html><head><meta charset='utf-8'></head><body><p>x</p></body></html>"


def _png(width: int, height: int) -> bytes:
    """A valid one-colour RGB PNG of width x height pixels (written by hand: signature, IHDR, IDAT, IEND)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    raw = b"".join(b"\0" + b"\xff" * (3 * width) for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def _fake_browser(tmp_path: Path, body: str) -> Path:
    """An executable shell script standing in for Chromium; it appends its arguments to args.txt."""
    exe = tmp_path / "fake-chromium"
    exe.write_text(f'#!/bin/sh\nfor a in "$@"; do echo "$a" >> "{tmp_path}/args.txt"; done\n{body}\n')
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return exe


def test_pdf_and_png_checks_can_fail():
    assert html_print.pdf_pages(b"<html>not a pdf /Type /Page</html>") == 0
    pdf = b"%PDF-1.4\n1 0 obj <</Type /Pages /Kids [2 0 R 3 0 R]>>\n2 0 obj <</Type /Page>>\n3 0 obj <</Type/Page>>"
    assert html_print.pdf_pages(pdf) == 2  # /Pages (the page tree) is not a page
    assert html_print.png_size(_png(3, 5)) == (3, 5)
    assert html_print.png_size(b"GIF89a" + bytes(40)) is None
    assert html_print.png_size(_png(3, 5)[:20]) is None


def test_print_choice_is_checked(no_browser):
    with pytest.raises(ConfigError, match=r"^--print: expected one of pdf, png, none, got 'jpeg'$"):
        html_print.plan("jpeg")
    assert html_print.plan("none") == html_print.PrintPlan(None)


def test_missing_browser_default_is_a_note_asked_for_is_an_error(no_browser):
    default = html_print.plan(None)
    assert default.kind is None and not default.explicit
    assert "no Chromium found" in default.note and "--print none" in default.note and len(default.note) < 200
    for kind in ("pdf", "png"):
        with pytest.raises(ConfigError, match=f"^--print {kind}: no Chromium found; install Chromium"):
            html_print.plan(kind)


def test_browser_from_the_environment(tmp_path, monkeypatch, no_browser):
    monkeypatch.setenv(html_print.BROWSER_ENV, str(tmp_path / "nowhere"))
    with pytest.raises(ConfigError, match=f"^{html_print.BROWSER_ENV}: .* is not an executable"):
        html_print.plan(None)
    exe = _fake_browser(tmp_path, "exit 0")
    monkeypatch.setenv(html_print.BROWSER_ENV, str(exe))
    assert html_print.plan(None) == html_print.PrintPlan("pdf", str(exe))
    assert html_print.plan("png") == html_print.PrintPlan("png", str(exe), explicit=True)


def test_the_browser_gets_its_own_profile_no_network_and_its_pdf_is_checked(tmp_path):
    # writes a one-page "PDF" where --print-to-pdf says
    exe = _fake_browser(tmp_path, 'for a in "$@"; do case "$a" in --print-to-pdf=*) '
                                  'printf "%%PDF-1.4 <</Type /Page>>" > "${a#--print-to-pdf=}";; esac; done')
    target = tmp_path / "out" / "sheet.pdf"
    target.parent.mkdir()
    assert html_print.print_html(PAGE, target, "pdf", str(exe)) == 1
    assert target.read_bytes() == b"%PDF-1.4 <</Type /Page>>"
    args = (tmp_path / "args.txt").read_text().splitlines()
    assert "--headless" in args and "--no-pdf-header-footer" in args
    assert "--host-resolver-rules=MAP * ~NOTFOUND" in args and "--proxy-server=127.0.0.1:9" in args
    profile = next(a for a in args if a.startswith("--user-data-dir="))
    assert not Path(profile.split("=", 1)[1]).exists()  # a temporary profile, gone afterwards
    assert args[-1].startswith("file://") and args[-1].endswith("page.html")


def test_a_browser_that_writes_no_pdf_or_a_wrong_png_is_an_error(tmp_path):
    target = tmp_path / "sheet.pdf"
    with pytest.raises(RunError, match="^--print pdf: the browser wrote no PDF"):
        html_print.print_html(PAGE, target, "pdf", str(_fake_browser(tmp_path, "exit 0")))
    assert not target.exists()
    # a browser that lays the page out 300 px high and writes a 10 x 10 PNG: not the size asked for
    png = tmp_path / "small.png"
    png.write_bytes(_png(10, 10))
    exe = _fake_browser(tmp_path, 'for a in "$@"; do case "$a" in --dump-dom) '
                                  'echo "<body data-scalesynth-height=\\"300\\">";; --screenshot=*) '
                                  f'cp "{png}" "${{a#--screenshot=}}";; esac; done')
    with pytest.raises(RunError, match=f"^--print png: the browser wrote no PNG of {html_print.PNG_WIDTH_PX} x 300"):
        html_print.print_html(PAGE, tmp_path / "sheet.png", "png", str(exe))
    assert not (tmp_path / "sheet.png").exists()


def _alive(pid: int) -> bool:
    """The process exists and is not a zombie (a killed child its parent has not reaped yet)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in status


def test_a_browser_past_its_timeout_is_killed_with_its_helpers(tmp_path):
    """A hung browser (a shell that started a helper, then waits) is killed, helper included, after timeout_s."""
    exe = _fake_browser(tmp_path, f'sleep 600 & echo $! > "{tmp_path}/helper.pid"\nwait')
    start = time.monotonic()
    with pytest.raises(RunError, match=r"^--print: the browser did not finish within 1 s$"):
        html_print.print_html(PAGE, tmp_path / "sheet.pdf", "pdf", str(exe), timeout_s=1.0)
    assert time.monotonic() - start < 300  # far below the helper's 600 s: nothing waited for it
    helper = int((tmp_path / "helper.pid").read_text())
    for _ in range(100):  # SIGKILL is delivered at once; its reaping by init may lag a moment
        if not _alive(helper):
            break
        time.sleep(0.1)
    assert not _alive(helper)
    assert not (tmp_path / "sheet.pdf").exists()


def test_print_target_is_beside_the_page():
    assert html_print.print_target(Path("a/sheet.html"), "pdf") == Path("a/sheet.pdf")
    assert html_print.print_target(Path("sheet"), "png") == Path("sheet.png")
