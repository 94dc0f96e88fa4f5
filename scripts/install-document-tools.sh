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
if [ ${#missing[@]} -gt 0 ]; then
    # shellcheck disable=SC2046  # one word per package
    bash "$(dirname "$0")/apt-install.sh" "the documentation export" \
        $(printf '%s\n' "${missing[@]}" | sort -u)
fi
