#!/usr/bin/env bash
# The files to publish: a manylinux wheel (glibc 2.17 and newer, stripped; the `lenspath`
# command and `import lenspath`) and the source distribution, in dist/, checked by twine.
# maturin links with zig against glibc 2.17, so this machine's newer glibc does not leak into
# the wheel; both come from PyPI into a virtual environment made here (target/release-venv).
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/release-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --upgrade pip "maturin>=1.9,<2" ziglang twine
rm -rf dist
# maturin finds zig through the ziglang package of the interpreter on PATH.
PATH="$PWD/$venv/bin:$PATH" CARGO_TARGET_DIR=target/release-wheel \
    "$venv/bin/maturin" build --profile dist --locked --zig --out dist
"$venv/bin/maturin" sdist --out dist
"$venv/bin/twine" check --strict dist/*
ls -l dist
