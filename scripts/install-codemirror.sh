#!/usr/bin/env bash
# The browser's code editor: CodeMirror 6 and our entry source (scripts/codemirror/src/),
# bundled by esbuild into .tools/codemirror/editor.bundle.js (git-ignored), which the UI
# sends to each browser once. Every package is pinned by scripts/codemirror/package-lock.json.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
spec="$repo/scripts/codemirror"
target="$repo/.tools/codemirror"
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    bash "$repo/scripts/apt-install.sh" "the browser's code editor" nodejs npm
fi
if ! { [ -f "$target/node_modules/.package-lock.json" ] && cmp -s "$spec/package-lock.json" "$target/package-lock.json"; }; then
    mkdir -p "$target"
    cp "$spec/package.json" "$spec/package-lock.json" "$target/"
    (cd "$target" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
fi
# bundled again whenever the entry source is newer than the bundle
bundle="$target/editor.bundle.js"
if [ -f "$bundle" ] && [ -z "$(find "$spec/src" -newer "$bundle" -type f)" ] && [ "$bundle" -nt "$spec/package-lock.json" ]; then
    exit 0
fi
NODE_PATH="$target/node_modules" "$target/node_modules/.bin/esbuild" "$spec/src/editor.js" \
    --bundle --minify --format=iife --target=es2020 --legal-comments=none \
    --outfile="$bundle.tmp" --log-level=warning
mv "$bundle.tmp" "$bundle"
