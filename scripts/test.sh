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

# The package's wheel is a release build, so it builds in its own target
# directory while the Rust tests build and run, not after them. Built here
# with thin LTO and 16 codegen units (then stripped, as pyproject says): the tests measure no
# speed, and the shipping profile's fat LTO over one codegen unit (4-10%
# faster renders, BENCHMARKS.md) costs minutes of the suite's time.
# The wheel is kept in target/wheels: the packaging tests check it (twine, stripped, its files).
pip_log=target/pip-install.log
build_and_install() {
    export CARGO_PROFILE_RELEASE_LTO=thin CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16
    rm -rf target/wheels
    CARGO_TARGET_DIR=target/wheel "$venv/bin/python" -m pip wheel --quiet --no-deps -w target/wheels . &&
        "$venv/bin/python" -m pip uninstall --quiet -y lenspath &&
        "$venv/bin/python" -m pip install --quiet "$(ls target/wheels/lenspath-*.whl)[test]"
}
build_and_install >"$pip_log" 2>&1 &
pip_pid=$!
trap 'kill "$pip_pid" 2>/dev/null || true' EXIT

cargo test --workspace

if ! wait "$pip_pid"; then
    cat "$pip_log" >&2
    echo "building or installing the wheel failed (log above, also in $pip_log)" >&2
    exit 1
fi
trap - EXIT
"$venv/bin/python" -m pytest -q tests/python
