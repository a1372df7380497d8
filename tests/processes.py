"""drydem run as a real process and interrupted by a real signal, as at a terminal."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

#: the command line of ``drydem`` in this interpreter
DRYDEM = [sys.executable, "-c", "from drydem.cli import console; console()"]


def interrupted_drydem(arguments: list[str], path: Path, lines: int, signal_name: str = "SIGINT") -> tuple[int, str]:
    """Run ``drydem ARGUMENTS``, wait (at most 120 s) until ``path`` holds ``lines`` lines, send
    it ``signal_name`` and return its exit code and standard error.

    SIGINT stays at its default in the child, as in a terminal: a test runner started in the
    background (``cmd &``) ignores SIGINT, its children inherit that, and Python then installs no
    KeyboardInterrupt."""
    process = subprocess.Popen([*DRYDEM, *arguments], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (path.is_file() and len(path.read_text().splitlines()) >= lines):
        time.sleep(0.2)
    process.send_signal(getattr(signal, signal_name))
    _, err = process.communicate(timeout=60)
    return process.returncode, err
