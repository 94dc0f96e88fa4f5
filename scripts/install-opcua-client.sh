#!/usr/bin/env bash
# The OPC UA server tests talk to it with a client nobody here wrote and that is not the
# library the server is built with (asyncua): node-opcua under node. Pinned by
# scripts/opcua-client/package-lock.json, installed into .tools/opcua-client/ (git-ignored);
# tests/support/opcua_client.cjs is the script that uses it. node-opcua 2.186.4 declares
# node >= 22.13 but runs on node 20 (npm warns EBADENGINE; --loglevel=error keeps that quiet).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
spec="$repo/scripts/opcua-client"
target="$repo/.tools/opcua-client"
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    bash "$repo/scripts/apt-install.sh" "the OPC UA interoperability tests" nodejs npm
fi
if [ -f "$target/node_modules/.package-lock.json" ] && cmp -s "$spec/package-lock.json" "$target/package-lock.json"; then
    exit 0  # installed, and from this lock file
fi
mkdir -p "$target"
cp "$spec/package.json" "$spec/package-lock.json" "$target/"
(cd "$target" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
