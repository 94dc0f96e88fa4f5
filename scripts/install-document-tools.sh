#!/usr/bin/env bash
# The documentation export renders PDF with WeasyPrint (Pango for text layout); its tests
# read the PDF back with poppler's pdftotext and pdftoppm. Debian packages only.
set -euo pipefail
missing=()
command -v pdftotext >/dev/null 2>&1 || missing+=(poppler-utils)
command -v pdftoppm >/dev/null 2>&1 || missing+=(poppler-utils)
libraries=$(ldconfig -p)  # read whole: `grep -q` on a pipe would fail it under pipefail
for lib in libpango-1.0.so.0 libpangoft2-1.0.so.0; do
    if ! grep -F "$lib" <<<"$libraries" >/dev/null; then
        missing+=(libpango-1.0-0 libpangoft2-1.0-0)
    fi
done
fonts=$(fc-list 2>/dev/null || true)
grep -i dejavu <<<"$fonts" >/dev/null || missing+=(fonts-dejavu-core)
if [ ${#missing[@]} -eq 0 ]; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" != "0" ]; then
    SUDO="sudo"
fi
packages=$(printf '%s\n' "${missing[@]}" | sort -u | tr '\n' ' ')
echo "installing Debian packages for the documentation export: $packages"
$SUDO apt-get update -qq
# shellcheck disable=SC2086  # one word per package
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $packages >/dev/null
