#!/usr/bin/env bash
# The recording tests open our MCAP files with a reader nobody here wrote: the TypeScript
# @mcap/core under node, with the decompressors its stream reader needs (fzstd for zstd,
# lz4js for lz4). Pinned by scripts/mcap-reader/package-lock.json, installed into
# .tools/mcap-reader/ (git-ignored); tests/support/mcap_reader.cjs is the script that uses it.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
spec="$repo/scripts/mcap-reader"
target="$repo/.tools/mcap-reader"
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    bash "$repo/scripts/apt-install.sh" "the MCAP interoperability tests" nodejs npm
fi
if [ -f "$target/node_modules/.package-lock.json" ] && cmp -s "$spec/package-lock.json" "$target/package-lock.json"; then
    exit 0  # installed, and from this lock file
fi
mkdir -p "$target"
cp "$spec/package.json" "$spec/package-lock.json" "$target/"
(cd "$target" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
