#!/usr/bin/env bash
# The whole test suite (the README's test command): the Rust workspace, then
# the Python package, built as a wheel by pip (what `pip install .` does) and
# installed into a virtual environment made here (target/python-venv), tested
# with pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

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

# The package's wheel is built with the dev profile (optimised: Cargo.toml),
# whose settings the test profile shares, into the same target directory as
# the Rust tests: cargo then compiles the dependencies and the library once
# for both (the crates' features are equal: crates/lenspath-py/Cargo.toml),
# and the tests measure no speed. `strip` (pyproject.toml) still drops the
# line tables. The shipping wheel (`pip install .`, scripts/build-wheel.sh)
# is the release profile's. The wheel is kept in target/wheels: the packaging
# tests check it (twine, stripped, its files).
pip_log=target/pip-install.log
rm -rf target/wheels
echo "building the package's wheel (log: $pip_log)" >&2
if ! MATURIN_PEP517_ARGS="--profile dev" "$venv/bin/python" -m pip wheel --quiet --no-deps -w target/wheels . >"$pip_log" 2>&1 ||
    ! "$venv/bin/python" -m pip uninstall --quiet -y lenspath >>"$pip_log" 2>&1 ||
    ! "$venv/bin/python" -m pip install --quiet "$(ls target/wheels/lenspath-*.whl)[test]" >>"$pip_log" 2>&1; then
    cat "$pip_log" >&2
    echo "building or installing the wheel failed (log above, also in $pip_log)" >&2
    exit 1
fi

cargo test --workspace

# Two worker processes: a render fills both cores, but much of the suite waits (on a browser,
# a subprocess, Python between renders), and a second worker fills those gaps.
"$venv/bin/python" -m pytest -q --numprocesses 2 tests/python
