#!/usr/bin/env bash
# The native tier (docs/native-code.md) compiles program bodies with the machine's C compiler
# against the headers of the Python that runs the runtime. Debian's gcc when there is no cc;
# the headers of a python.org or pyenv build come with it, Debian's python3 needs python3-dev.
set -euo pipefail
PYTHON=${1:-python3}
if ! command -v cc >/dev/null && ! command -v gcc >/dev/null; then
    bash "$(dirname "$0")/apt-install.sh" "the native tier" gcc libc6-dev
fi
include=$("$PYTHON" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
if [ ! -f "$include/Python.h" ]; then
    bash "$(dirname "$0")/apt-install.sh" "the native tier (Python.h)" python3-dev
fi
