#!/usr/bin/env bash
# The Modbus tests check the served image with a client nobody here wrote: Debian's mbpoll
# (built on libmodbus).
set -euo pipefail
if [ ! -x /usr/bin/mbpoll ]; then
    bash "$(dirname "$0")/apt-install.sh" "the Modbus tests" mbpoll
fi
