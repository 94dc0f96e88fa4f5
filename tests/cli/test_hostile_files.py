"""`padt docs` of hostile backups and `padt replay` of hostile recordings, through the real
command line: entries that climb out of their folder, archives and chunks that unpack to a
gigabyte, JSON nested a hundred thousand deep, headers that disagree with their rows, code
that does not load. Each ends in a clear message and a non-zero exit, never a traceback,
a file outside its place or a gigabyte of memory."""

from __future__ import annotations

from pathlib import Path

import pytest

from runtime.contract.artifact import Artifact
from tests.conftest import padt
from tests.support import hostile_files as hostile

MEMORY_BOUND_MB = 300  # a refused gigabyte must not be read: padt itself needs about 100


def files_below(folder: Path) -> set[Path]:
    return {path for path in folder.rglob("*") if path.is_file()}


@pytest.fixture
def plain_backup(tmp_path: Path) -> Path:
    return hostile.backup(tmp_path / "backups", hostile.project(tmp_path / "project"))


def test_the_genuine_backup_is_documented(plain_backup: Path, tmp_path: Path) -> None:
    run = padt("docs", str(plain_backup), "-o", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "out" / "Hostile.html").is_file()


@pytest.mark.parametrize("entry", ["project/../../escaped.st", "project//{tmp}/abs/escaped.st"])
def test_a_backup_entry_that_climbs_out_is_refused_and_writes_nothing(
    entry: str, plain_backup: Path, tmp_path: Path
) -> None:
    name = entry.format(tmp=str(tmp_path).lstrip("/"))
    crafted = hostile.rewritten(plain_backup, tmp_path / "crafted.zip", {name: b"(* out *)\n"})
    scratch = tmp_path / "a" / "b" / "tmp"  # where padt docs unpacks: `../..` of it is here
    scratch.mkdir(parents=True)
    before = files_below(tmp_path)
    run = padt("docs", str(crafted), "-o", str(tmp_path / "out"), env={"TMPDIR": str(scratch)})
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert name in run.stderr and "crafted.zip" in run.stderr, run.stderr
    assert files_below(tmp_path) == before
    assert not Path("/escaped.st").exists()


@pytest.mark.parametrize(
    "entries",
    [
        {"project/a\\..\\..\\x.st": b"x"},
        {"project/C:/x.st": b"x"},
        {"project/./x.st": b"x"},
        {"project/x.st": b"x", "project/X.ST": b"y"},
    ],
    ids=["backslashes", "drive", "dot", "same-name"],
)
def test_other_crafted_names_are_refused(
    entries: dict[str, bytes], plain_backup: Path, tmp_path: Path
) -> None:
    crafted = hostile.rewritten(plain_backup, tmp_path / "crafted.zip", entries)
    run = padt("docs", str(crafted), "-o", str(tmp_path / "out"))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "crafted.zip" in run.stderr and list(entries)[-1] in run.stderr, run.stderr


def test_a_link_entry_is_refused(plain_backup: Path, tmp_path: Path) -> None:
    link = {"project/lib.st": b"/etc/passwd"}
    crafted = hostile.rewritten(plain_backup, tmp_path / "link.zip", link, mode=0o120777)
    run = padt("docs", str(crafted), "-o", str(tmp_path / "out"))
    assert run.returncode == 2, run.stderr
    assert "'project/lib.st': a link" in run.stderr, run.stderr


def test_ten_thousand_and_one_entries_are_refused(plain_backup: Path, tmp_path: Path) -> None:
    many = {f"project/f{n}.st": b"" for n in range(10_001)}
    crafted = hostile.rewritten(plain_backup, tmp_path / "many.zip", many)
    run = padt("docs", str(crafted), "-o", str(tmp_path / "out"))
    assert run.returncode == 2, run.stderr
    assert "more than 10,000" in run.stderr, run.stderr


@pytest.mark.parametrize("declared", [None, 1000], ids=["honest", "lying"])
def test_a_gigabyte_zip_bomb_is_refused_without_reading_it(
    declared: int | None, plain_backup: Path, tmp_path: Path
) -> None:
    bomb = hostile.zip_bomb(plain_backup, tmp_path / "bomb.zip", hostile.GIB, declared)
    assert bomb.stat().st_size < 2_000_000
    run = hostile.padt_measured("docs", str(bomb), "-o", str(tmp_path / "out"))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "project/bomb.st" in run.stderr, run.stderr
    assert run.max_rss_mb < MEMORY_BOUND_MB, run.max_rss_mb


def test_a_manifest_nested_a_hundred_thousand_deep_is_refused(
    plain_backup: Path, tmp_path: Path
) -> None:
    crafted = hostile.rewritten(plain_backup, tmp_path / "deep.zip", {}, b"[" * 100_000)
    run = padt("docs", str(crafted), "-o", str(tmp_path / "out"))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "MANIFEST.json" in run.stderr and "deep" in run.stderr, run.stderr


# ---- padt replay


@pytest.fixture
def cell(tmp_path: Path) -> tuple[Path, Artifact]:
    folder = hostile.project(tmp_path / "project")
    return folder, hostile.compiled(folder)


def replay(tmp_path: Path, folder: Path, data: bytes) -> hostile.Run:
    path = tmp_path / "hostile.mcap"
    path.write_bytes(data)
    return hostile.padt_measured("replay", str(path), str(folder))


def test_the_genuine_crafted_recording_replays(cell: tuple[Path, Artifact], tmp_path: Path) -> None:
    folder, artifact = cell
    run = replay(tmp_path, folder, hostile.recording(artifact))
    assert run.returncode == 0, run.stderr
    assert "identical" in run.stdout


def test_recorded_code_that_does_not_load_is_refused(
    cell: tuple[Path, Artifact], tmp_path: Path
) -> None:
    folder, artifact = cell
    text = hostile.unloadable(artifact).to_json()
    run = replay(tmp_path, folder, hostile.recording(artifact, artifact_text=text))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "recorded configuration is damaged: the form of PROGRAM Main" in run.stderr


def test_a_start_state_nested_fifty_thousand_deep_is_refused(
    cell: tuple[Path, Artifact], tmp_path: Path
) -> None:
    folder, artifact = cell
    run = replay(tmp_path, folder, hostile.recording(artifact, start=b"[" * 50_000))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "start.json" in run.stderr and "deep" in run.stderr, run.stderr


@pytest.mark.parametrize("channel", ["values", "inputs"])
def test_a_message_nested_a_hundred_thousand_deep_is_refused(
    channel: str, cell: tuple[Path, Artifact], tmp_path: Path
) -> None:
    folder, artifact = cell
    deep = hostile.Part(channel, b"[" * 100_000)
    run = replay(tmp_path, folder, hostile.recording(artifact, messages=[deep]))
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "deep" in run.stderr, run.stderr


def test_a_header_of_two_hundred_thousand_variables_that_the_rows_lack_is_refused(
    cell: tuple[Path, Artifact], tmp_path: Path
) -> None:
    folder, artifact = cell
    variables = [(f"Main.v{n}", "INT") for n in range(200_000)]
    row = hostile.Part("values", b'{"cycle": 1, "values": {"Main": {"v0": 1}}}')
    inputs = hostile.Part(
        "inputs",
        b'{"cycle": 1, "begin_ns": 1, "wall_ns": 1, "before": [], "after": [], '
        b'"system": {}, "programs": {}}',
    )
    data = hostile.recording(artifact, variables=variables, messages=[row, inputs])
    run = replay(tmp_path, folder, data)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "Main.v1" in run.stderr, run.stderr


@pytest.mark.parametrize(
    ("make", "declared"),
    [
        (hostile.zeros_zstd, hostile.GIB),
        (hostile.zeros_zstd, 1000),
        (hostile.zeros_lz4, hostile.GIB),
        (hostile.zeros_lz4, 1000),
    ],
    ids=["zstd-honest", "zstd-lying", "lz4-honest", "lz4-lying"],
)
def test_a_chunk_that_decompresses_to_a_gigabyte_is_refused_without_reading_it(
    make: object, declared: int, cell: tuple[Path, Artifact], tmp_path: Path
) -> None:
    folder, artifact = cell
    chunk = make(hostile.GIB, declared)  # type: ignore[operator]
    data = hostile.recording(artifact, chunks=[chunk])
    assert len(data) < 8_000_000
    run = replay(tmp_path, folder, data)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert "chunk" in run.stderr, run.stderr
    assert run.max_rss_mb < MEMORY_BOUND_MB, run.max_rss_mb
