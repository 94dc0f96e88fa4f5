#!/usr/bin/env bash
# Installs Debian packages, as root or through sudo: apt-install.sh "what for" PACKAGE...
# The install-*.sh scripts decide what is missing; this is the one way they install it.
set -euo pipefail
why=$1
shift
SUDO=""
if [ "$(id -u)" != "0" ]; then
    SUDO="sudo"
fi
echo "installing Debian packages for $why: $*"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "$@" >/dev/null
