"""How many PLCopen TC6 XML files import and compile: `padt import` and `padt check` on
every `*.xml` under the folders given, each into a temporary folder of its own.

    .venv/bin/python scripts/plcopen_import_rate.py DIR... [--errors N]

For each file: the graphical and IL bodies it holds, whether it imported whole (else the
first import code and message), whether the imported project compiled (else its first
error), then the totals. A file that makes the importer or the compiler raise is counted as
failing with the exception named, so a crash is seen, not hidden. The files are only read.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.plcopen.issues import ImportFailed
from backend.engineering.project import ProjectError, compile_project, load_project

_BODY = re.compile(rb"<(FBD|LD|SFC|IL)>")


@dataclass(frozen=True)
class Outcome:
    name: str
    bodies: str  # e.g. "FBD 2, LD 1"
    imported: bool
    import_note: str  # the first import error, "" when imported whole
    compiled: bool
    compile_note: str  # the first compile error, "" when compiled; "-" when not tried


def bodies_in(data: bytes) -> str:
    found = [m.group(1).decode() for m in _BODY.finditer(data)]
    return ", ".join(f"{kind} {found.count(kind)}" for kind in sorted(set(found))) or "-"


def measure(xml: Path, name: str, scratch: Path) -> Outcome:
    bodies = bodies_in(xml.read_bytes())
    folder = scratch / "project"
    try:
        result = import_plcopen(xml, folder)
    except ImportFailed as failed:
        return Outcome(name, bodies, False, f"{failed.code.id} {failed.message}", False, "-")
    except Exception as exc:  # a crash of the importer is a finding, not the end of the run
        return Outcome(name, bodies, False, f"raised {type(exc).__name__}: {exc}", False, "-")
    errors = [d for d in result.diagnostics if d.severity == "error"]
    import_note = f"{errors[0].code} {errors[0].message}" if errors else ""
    try:
        compiled = compile_project(load_project([folder]))
    except ProjectError as exc:
        return Outcome(name, bodies, not errors, import_note, False, f"project: {exc}")
    except Exception as exc:
        return Outcome(name, bodies, not errors, import_note, False, f"raised {exc!r}")
    first = next((d for d in compiled.diagnostics if d.severity == "error"), None)
    compile_note = f"{first.code} {first.file}:{first.line}: {first.message}" if first else ""
    return Outcome(name, bodies, not errors, import_note, first is None, compile_note)


def _short(text: str, limit: int = 110) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path, help="folders searched for *.xml")
    options = parser.parse_args(argv)
    files: list[tuple[Path, str]] = []
    for folder in options.folders:
        if not folder.is_dir():
            parser.error(f"{folder}: no such folder")
        files += [
            (p, str(folder.name / p.relative_to(folder))) for p in sorted(folder.rglob("*.xml"))
        ]
    outcomes: list[Outcome] = []
    with tempfile.TemporaryDirectory(prefix="plcopen-rate-") as temporary:
        for number, (xml, name) in enumerate(files):
            scratch = Path(temporary) / str(number)
            scratch.mkdir()
            outcome = measure(xml, name, scratch)
            outcomes.append(outcome)
            imported = "yes" if outcome.imported else f"no ({_short(outcome.import_note)})"
            compiled = "yes" if outcome.compiled else f"no ({_short(outcome.compile_note)})"
            print(f"{name}  [{outcome.bodies}]\n  import: {imported}\n  compile: {compiled}")
    total = len(outcomes)
    imported_count = sum(o.imported for o in outcomes)
    both = sum(o.imported and o.compiled for o in outcomes)
    graphic = [o for o in outcomes if "FBD" in o.bodies or "LD" in o.bodies]
    graphic_both = sum(o.imported and o.compiled for o in graphic)

    def rate(part: int, whole: int) -> str:
        return f"{part}/{whole} ({100 * part / whole:.0f} %)" if whole else "0/0"

    print(
        f"\nfiles: {total}; imported whole: {rate(imported_count, total)}; "
        f"imported whole and compiled: {rate(both, total)}\n"
        f"files with FBD or LD bodies: {len(graphic)}; imported whole and compiled: "
        f"{rate(graphic_both, len(graphic))}"
    )
    # what stops the others, by the code of the first error (import first, then compile)
    stops = Counter(
        (o.import_note if not o.imported else o.compile_note).split(" ", 1)[0]
        for o in outcomes
        if not (o.imported and o.compiled)
    )
    if stops:
        listed = ", ".join(f"{code} {count}" for code, count in sorted(stops.items()))
        print(f"first error of the others, by code: {listed}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
