#!/usr/bin/env bash
# Builds the Python package `indentify` (release, abi3 wheel) into a virtual environment and
# runs its pytest suite; exits with pytest's status.
#
#   python/run-tests.sh [PYTEST ARGS...]      e.g. python/run-tests.sh -k identify -x
#
# Needs python3 (>= 3.9, with venv and pip), cargo and access to PyPI (maturin, pytest,
# numpy, and mypy: the type stub's test runs it on a probe, and here it must run, not skip).
# The virtual environment is ${INDENTIFY_VENV:-target/python-venv} (relative to the
# workspace root), kept between runs; the Rust build goes to CARGO_TARGET_DIR when set,
# else the workspace's own target/, so the release build is shared with `cargo build --release`.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd -P)"
root="$(cd "$here/.." && pwd -P)"
cd "$root"
venv="${INDENTIFY_VENV:-target/python-venv}"
case "$venv" in /*) ;; *) venv="$root/$venv" ;; esac
python="${PYTHON:-python3}"

command -v "$python" >/dev/null || { echo "run-tests.sh: $python not found" >&2; exit 2; }
command -v cargo >/dev/null || { echo "run-tests.sh: cargo not found (install Rust with rustup)" >&2; exit 2; }

if [ ! -x "$venv/bin/python" ]; then
    echo "== creating the virtual environment $venv"
    mkdir -p "$(dirname "$venv")"
    # Debian's python3 without python3-venv has no ensurepip: fall back to virtualenv from PyPI
    if ! "$python" -m venv "$venv" 2>/dev/null; then
        rm -rf "$venv"
        "$python" -m pip install --quiet --user virtualenv
        "$python" -m virtualenv --quiet "$venv"
    fi
fi
py="$venv/bin/python"
echo "== installing maturin, pytest, numpy, mypy (PyPI)"
"$py" -m pip install --quiet --disable-pip-version-check --upgrade pip
"$py" -m pip install --quiet --disable-pip-version-check "maturin>=1.5,<2" pytest numpy mypy

profile="${INDENTIFY_PY_PROFILE:-dev}"
echo "== building and installing the package (cargo profile $profile)"
# `maturin develop` builds the crate with cargo (CARGO_TARGET_DIR or the workspace's target/)
# and installs it into the active virtual environment. The dev profile (optimized
# dependencies, see the workspace's Cargo.toml) shares its build with `cargo test`, so the
# test command builds the workspace once; `pip install ./python` builds a release wheel.
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" \
    "$venv/bin/maturin" develop --profile "$profile" --manifest-path python/Cargo.toml --quiet

# the CLI's own binary, built by `cargo test` in the same target directory, for the tests
# that compare the package with the command line (they skip without it, fail under CI)
exe="${CARGO_TARGET_DIR:-$root/target}/debug/indentify"
if [ -z "${INDENTIFY_EXE:-}" ] && [ -x "$exe" ]; then
    export INDENTIFY_EXE="$exe"
fi

echo "== pytest"
set +e
INDENTIFY_REQUIRE_MYPY=1 "$py" -m pytest python/tests "$@"
status=$?
set -e
exit $status
