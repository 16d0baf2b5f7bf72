#!/usr/bin/env bash
# The whole test suite (the README's test command): the Rust workspace, then
# the Python package, installed with `pip install .` into a virtual
# environment made here (target/python-venv), tested with pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --workspace

venv=target/python-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet ".[test]"
"$venv/bin/python" -m pytest -q tests/python
