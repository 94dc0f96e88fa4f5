#!/usr/bin/env bash
# The Modbus tests check the served image with a client nobody here wrote: Debian's mbpoll
# (built on libmodbus).
set -euo pipefail
if [ -x /usr/bin/mbpoll ]; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" != "0" ]; then
    SUDO="sudo"
fi
echo "installing Debian mbpoll for the Modbus tests"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mbpoll >/dev/null
