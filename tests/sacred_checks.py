"""Helpers of the "a user's files are sacred" tests (issue 27): a byte snapshot of a directory, a CLI refusal that
writes nothing, and a failing atomic write."""

import os
from pathlib import Path

from cli_main import run_main


def snapshot(directory: Path) -> dict[str, bytes]:
    """Every entry under ``directory`` (hidden ones too) with its bytes; links by their target."""
    out = {}
    for p in sorted(directory.rglob("*")):
        key = str(p.relative_to(directory))
        if p.is_symlink():
            out[key] = b"-> " + os.readlink(p).encode()
        else:
            out[key] = p.read_bytes() if p.is_file() else b"<dir>"
    return out


def refused(argv, needle, workdir, capsys, monkeypatch, code=2) -> str:
    """Run argv in ``workdir``: exit ``code``, exactly one stderr line naming --out and ``needle``, nothing written
    anywhere under ``workdir`` (hidden lock and staging paths included); returns that line."""
    monkeypatch.chdir(workdir)
    before = snapshot(workdir)
    got, out, err = run_main(argv, capsys)
    lines = err.strip().splitlines()
    assert got == code, (argv, got, err)
    assert len(lines) == 1 and lines[0].startswith("error: --out: ") and needle in lines[0], err
    assert len(lines[0]) <= 200 and "Traceback" not in err and out == ""
    assert snapshot(workdir) == before, "something was written"
    return lines[0]


def fail_on(monkeypatch, name: str, exc: BaseException):
    """Make the atomic write of the file called ``name`` raise ``exc`` (a full disk, an interrupt)."""
    import scalesynth.io as rio

    real = os.replace

    def replace(src, dst, *a, **k):
        if Path(dst).name == name:
            raise exc
        return real(src, dst, *a, **k)

    monkeypatch.setattr(rio.os, "replace", replace)
