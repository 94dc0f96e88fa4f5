#!/usr/bin/env bash
# The browser tests drive Debian's Chromium (never a downloaded browser build).
set -euo pipefail
if [ ! -x /usr/bin/chromium ]; then
    bash "$(dirname "$0")/apt-install.sh" "the browser tests" chromium fonts-dejavu-core
fi
