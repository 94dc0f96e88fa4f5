#!/usr/bin/env bash
# `padt test --junit` writes JUnit XML; its test validates it with libxml2's xmllint against
# the JUnit schema of Jenkins' xUnit plugin (junit-10.xsd), as pytest's own source
# distribution ships it for its tests. Pinned: pytest's sdist by version and hash, installed
# into .tools/junit-schema/ (git-ignored). Usage: install-junit-schema.sh [PYTHON with pip]
set -euo pipefail
PYTHON=${1:-python3}
repo=$(cd "$(dirname "$0")/.." && pwd)
target="$repo/.tools/junit-schema"
sdist=pytest-9.2.0.tar.gz
sdist_sha256=97c4f3b1f3c7414aa36465e09b8220f1d03627993bd51b1282e193753c80557b
member=pytest-9.2.0/testing/example_scripts/junit-10.xsd
if ! command -v xmllint >/dev/null; then
    bash "$repo/scripts/apt-install.sh" "the JUnit XML test of padt test" libxml2-utils
fi
if [ -f "$target/junit-10.xsd" ] && [ "$(cat "$target/from" 2>/dev/null)" = "$sdist_sha256" ]; then
    exit 0  # installed, and from this sdist
fi
download=$(mktemp -d)
trap 'rm -rf "$download"' EXIT
"$PYTHON" -m pip download -q --no-deps --no-binary :all: "pytest==9.2.0" -d "$download"
echo "$sdist_sha256  $download/$sdist" | sha256sum --check --quiet
mkdir -p "$target"
tar -xzf "$download/$sdist" -O "$member" >"$target/junit-10.xsd"
echo "$sdist_sha256" >"$target/from"
