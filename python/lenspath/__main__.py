"""The ``lenspath`` command (``python -m lenspath``, and the script ``pip install`` makes): the
command-line renderer, the same code as the ``lenspath`` binary ``cargo install`` builds."""

from __future__ import annotations

import signal
import sys

from lenspath._core import run_cli


def main() -> None:
    """Runs ``lenspath`` with this process's arguments and exits with its code."""
    # Ctrl-C as in the binary: a render catches it itself and saves what it has; anything else
    # stops at once (Python's own handler would wait for the native call to return).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.exit(run_cli(["lenspath", *sys.argv[1:]]))


if __name__ == "__main__":
    main()
