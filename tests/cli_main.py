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
