#!/usr/bin/env bash
# The one command that runs every test: the Rust workspace (`cargo test --workspace`),
# then the Python package's pytest suite (python/run-tests.sh: a virtual environment with
# maturin, pytest and numpy from PyPI, the package built with the same cargo profile).
# Extra arguments go to cargo test. `.ci/run` calls this after fmt and clippy.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== cargo test --workspace"
cargo test --workspace --locked "$@"
echo "== python/run-tests.sh"
python/run-tests.sh -q
