#!/usr/bin/env bash
# The whole test suite (the README's test command): the Rust workspace, then
# the Python package, installed with `pip install .` into a virtual
# environment made here (target/python-venv), tested with pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --workspace

# The viewer's browser tests drive Debian's Chromium through Playwright (whose
# own browser download is not used). Installed here when we may (root, apt);
# elsewhere they skip, saying so, unless CI is set.
if ! command -v chromium >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi

venv=target/python-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet ".[test]"
"$venv/bin/python" -m pytest -q tests/python
