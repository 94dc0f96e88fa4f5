"""The other third-party ST of ../shared/corpus: OSCAT BASIC and BUILDING, matiec's standard
library, the IEC 61131-3 Annex F examples and matiec's syntax samples. Each must compile
with no error, or be listed with its reason in tests/compiler/corpus/iec_known_failures.tsv.

Files of one folder may use each other's POUs (Annex F's PID uses its INTEGRAL), so each
folder is compiled as one set; a listed file is left out of its set and must still fail."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import read_source
from tests.conftest import REPO
from tests.support.corpus_paths import CORPUS, corpus_dir, known_failures

KNOWN = known_failures("iec_known_failures.tsv")
# folder -> whether its files form one set (they refer to each other) or stand alone
FOLDERS = {
    "oscat/st": False,  # every chapter is complete in itself (and repeats shared POUs)
    "matiec/lib": True,
    "matiec/AnnexF": True,
    "matiec/tests/syntax/configuration": False,
    "matiec/tests/syntax/enumeration": False,
    "matiec/tests/syntax/sfc": False,
}


def name_of(path: Path) -> str:
    return str(path.relative_to(CORPUS))


def st_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.suffix in (".st", ".txt") and p.is_file())


def errors(paths: list[Path]) -> list[Diagnostic]:
    result = compile_sources([read_source(p, name_of(p)) for p in paths], programs=[])
    return [d for d in result.diagnostics if d.severity == "error"]


@pytest.mark.parametrize("folder", sorted(FOLDERS))
def test_corpus_folder_compiles(folder: str) -> None:
    root = corpus_dir(folder)
    files = [p for p in st_files(root) if p.name != "readme"]
    good = [p for p in files if name_of(p) not in KNOWN]
    if FOLDERS[folder]:
        found = errors(good)
        assert not found, "\n".join(str(d) for d in found)
    else:
        for path in good:
            found = errors([path])
            assert not found, "\n".join(str(d) for d in found)


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_known_failure_still_fails(name: str) -> None:
    path = CORPUS / name
    corpus_dir(str(Path(name).parent))
    folder = str(Path(name).parent)
    others = (
        [p for p in st_files(path.parent) if name_of(p) not in KNOWN] if FOLDERS[folder] else []
    )
    found = [d for d in errors([*others, path]) if d.file == name]
    assert found, f"{name} compiles now: remove it from iec_known_failures.tsv"


def test_oscat_chapters_all_accounted_for() -> None:
    files = st_files(corpus_dir("oscat/st"))
    assert len(files) == 22
    failing = [p for p in files if name_of(p) in KNOWN]
    assert len(failing) <= 1, "OSCAT: only genuinely faulty chapters may fail"


CRCS = REPO / "tests" / "compiler" / "corpus" / "crcs.tsv"


def corpus_crcs() -> list[str]:
    """`set<TAB>POU<TAB>CRC` of every set that compiles, `*` for its configuration CRC."""
    rows = []
    for folder, together in sorted(FOLDERS.items()):
        files = [p for p in st_files(corpus_dir(folder)) if name_of(p) not in KNOWN]
        sets = [(folder, files)] if together else [(name_of(p), [p]) for p in files]
        for name, paths in sets:
            result = compile_sources([read_source(p, name_of(p)) for p in paths], programs=[])
            assert result.artifact is not None, name
            rows.append(f"{name}\t*\t{result.artifact.crc}")
            rows += [f"{name}\t{pou.name}\t{pou.crc}" for pou in result.artifact.pous]
    return sorted(rows)


def test_the_corpus_compiles_to_the_same_crcs() -> None:
    """The same sources give the same code: a change of any CRC here is a change of the
    generated code, which docs/artifact.md must explain (see tests/compiler/corpus/crcs.tsv)."""
    found = corpus_crcs()
    if os.environ.get("PADT_WRITE_CRCS") == "1":
        CRCS.write_text(CRCS.read_text().split("\n\n")[0] + "\n\n" + "\n".join(found) + "\n")
    pinned = [line for line in CRCS.read_text().splitlines() if line and not line.startswith("#")]
    changed = sorted(set(found) ^ set(pinned))
    assert not changed, f"{len(changed)} CRC rows differ, first: {changed[:6]}"
