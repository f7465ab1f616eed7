"""Run the CLI's ``main`` in this process, as a user's shell would: (exit code, stdout, stderr)."""

import pytest

from scalesynth.cli import main


def run_main(argv, capsys) -> tuple[int, str, str]:
    """``main(argv)`` with pytest's ``capsys``: its exit code (SystemExit's: None is 0, a message 1), stdout, stderr."""
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    code = exc.value.code
    return (code if isinstance(code, int) else (0 if code is None else 1)), out, err


def error_lines(err: str) -> list[str]:
    """stderr's lines without the one-time "note: compiling ..." line, which a process prints when its first
    compilation starts (whether a test sees it depends on which tests ran in its process before)."""
    return [line for line in err.strip().splitlines() if not line.startswith("note: compiling")]
