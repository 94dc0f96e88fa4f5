"""Backup archives of what was loaded into a resource.

After every successful download or reload the PADT keeps one zip: the artifact text
exactly as sent, the project sources it was compiled from, and a manifest. With it, the
configuration running in a resource can be proven (its CRC) and rebuilt (its sources)
long after the project folder has moved on.

The archive is reproducible: entries sorted by name, fixed timestamps and attributes, so
the same load gives the same bytes apart from the time in the name and the manifest.
"""

from __future__ import annotations

import hashlib
import json
import re
import tempfile
import time
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path, PurePosixPath
from typing import Any

from backend.engineering.archive_reader import ArchiveRefused, read_archive
from runtime.contract.artifact import Artifact, ArtifactError, load_artifact
from runtime.contract.outside_json import MIB, JsonRefused, read_json
from runtime.contract.private_files import write_private

DEFAULT_BACKUP_DIR = Path("padt-backups")
ARTIFACT_ENTRY = "artifact.json"
MANIFEST_ENTRY = "MANIFEST.json"
SOURCES_PREFIX = "project/"  # project files keep their relative paths below this folder
FORMAT = "padt-backup"
VERSION = 1
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)  # the earliest time a zip can hold: no clock in the bytes
MAX_MANIFEST_BYTES = 16 * MIB  # a digest per project file
_UNSAFE = re.compile(r"[^A-Za-z0-9_-]+")


class BackupError(ValueError):
    """The backup cannot be written, or a backup read back is not intact."""


@dataclass(frozen=True)
class BackupInfo:
    """What the manifest records besides the artifact: who loaded what, and how."""

    project: str
    version: str
    resource: str
    action: str  # load | reload
    command: str  # the padt command line that loaded it


def safe_name(project: str) -> str:
    """A project name for a file name: [A-Za-z0-9_-] only, never empty."""
    return _UNSAFE.sub("_", project).strip("_") or "project"


def utc_stamp(time_ns: int) -> str:
    """YYYYMMDDTHHMMSSZ of a wall-clock time in nanoseconds since the epoch."""
    moment = datetime.fromtimestamp(time_ns // 1_000_000_000, UTC)
    return moment.strftime("%Y%m%dT%H%M%SZ")


def backup_name(project: str, crc: str, time_ns: int) -> str:
    return f"{safe_name(project)}_{crc}_{utc_stamp(time_ns)}.zip"


def archive_path(name: str, taken: set[str]) -> str:
    """Where a project file goes in the archive: its relative path below `project/`. A
    loose .st file given by an absolute or an upward path keeps only its file name."""
    path = PurePosixPath(name.replace("\\", "/"))
    if path.is_absolute() or ".." in path.parts or not path.parts:
        path = PurePosixPath(path.name or "source.st")
    candidate, number = str(path), 2
    while candidate.upper() in taken:  # two loose files of the same name
        candidate = str(path.with_name(f"{number}_{path.name}"))
        number += 1
    taken.add(candidate.upper())
    return SOURCES_PREFIX + candidate


def project_files(sources: Mapping[str, str], config_text: str | None) -> dict[str, bytes]:
    """Archive entry name -> content: padt.toml (when the project has one) and the ST
    sources exactly as they were compiled."""
    taken: set[str] = set()
    files: dict[str, bytes] = {}
    if config_text is not None:
        files[archive_path("padt.toml", taken)] = config_text.encode("utf-8")
    for name in sorted(sources):
        files[archive_path(name, taken)] = sources[name].encode("utf-8")
    return files


def manifest(
    info: BackupInfo, artifact: Artifact, files: Mapping[str, bytes], time_ns: int
) -> dict[str, Any]:
    return {
        "format": FORMAT,
        "version": VERSION,
        "project": info.project,
        "project_version": info.version,
        "resource": info.resource,
        "action": info.action,
        "command": info.command,
        "time_utc": datetime.fromtimestamp(time_ns // 1_000_000_000, UTC).strftime(
            "%Y-%m-%dT%H:%M:%SZ"
        ),
        "crc": {
            "configuration": artifact.crc,
            "pous": {p.name: p.crc for p in artifact.pous},
            "programs": {p.name: p.crc for p in artifact.programs},
        },
        # to prove the sources later: a changed byte changes the digest
        "files": {
            name.removeprefix(SOURCES_PREFIX): hashlib.sha256(data).hexdigest()
            for name, data in sorted(files.items())
        },
    }


def _entry(name: str) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.create_system = 3  # Unix, on every platform: the bytes must not depend on it
    info.external_attr = 0o644 << 16
    return info


def archive_bytes(entries: Mapping[str, bytes]) -> bytes:
    """A zip of `entries`, sorted by name, with nothing in it that varies between runs."""
    with tempfile.SpooledTemporaryFile() as buffer:
        with zipfile.ZipFile(buffer, "w") as archive:
            for name in sorted(entries):
                archive.writestr(_entry(name), entries[name], compresslevel=9)
        buffer.seek(0)
        return buffer.read()


def write_backup(
    folder: Path,
    info: BackupInfo,
    artifact_text: str,
    sources: Mapping[str, str],
    config_text: str | None,
    clock: Callable[[], int] = time.time_ns,
) -> Path:
    """Store a backup of `artifact_text` (exactly the text sent) with its project files;
    returns the archive's path. Written to a temporary file and renamed, so a backup that
    exists is whole."""
    now = clock()
    files = project_files(sources, config_text)
    try:
        artifact = load_artifact(artifact_text)
    except ArtifactError as exc:
        raise BackupError(f"not a valid artifact: {exc}") from None
    content = manifest(info, artifact, files, now)
    entries = {
        **files,
        ARTIFACT_ENTRY: artifact_text.encode("ascii"),
        MANIFEST_ENTRY: (json.dumps(content, indent=2, sort_keys=True) + "\n").encode("utf-8"),
    }
    data = archive_bytes(entries)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        name = backup_name(info.project, artifact.crc, now)
        path, number = folder / name, 2
        while path.exists():  # the same configuration twice within a second
            path = folder / f"{name.removesuffix('.zip')}-{number}.zip"
            number += 1
        write_private(path, data)  # the project's accounts are in it (verifiers)
    except OSError as exc:
        raise BackupError(f"cannot write the backup in {folder}: {exc}") from None
    return path


def restore_backup(zip_path: Path) -> tuple[str, dict[str, str]]:
    """The artifact text and the project files (relative path -> text) of a backup, after
    proving them: the artifact's own CRC, the manifest's configuration CRC and every
    file's SHA-256 must match. The archive is read within `archive_reader`'s limits and
    the manifest within those of outside JSON. Raises BackupError otherwise."""
    try:
        entries = read_archive(zip_path)
    except ArchiveRefused as exc:  # names the archive itself
        raise BackupError(f"not a readable backup: {exc}") from None
    except OSError as exc:
        raise BackupError(f"{zip_path}: not a readable backup: {exc}") from None
    for required in (ARTIFACT_ENTRY, MANIFEST_ENTRY):
        if required not in entries:
            raise BackupError(f"{zip_path}: no {required}")
    try:
        recorded = read_json(entries[MANIFEST_ENTRY], MANIFEST_ENTRY, MAX_MANIFEST_BYTES)
        artifact_text = entries[ARTIFACT_ENTRY].decode("ascii")
        artifact = load_artifact(artifact_text)
    except (JsonRefused, UnicodeDecodeError, ArtifactError) as exc:
        raise BackupError(f"{zip_path}: {exc}") from None
    if not isinstance(recorded, dict) or recorded.get("format") != FORMAT:
        raise BackupError(f"{zip_path}: the manifest is not a {FORMAT} manifest")
    crcs = recorded.get("crc")
    manifest_crc = crcs.get("configuration") if isinstance(crcs, dict) else None
    if manifest_crc != artifact.crc:
        raise BackupError(
            f"{zip_path}: the manifest names CRC {manifest_crc}, the artifact is {artifact.crc}"
        )
    raw = {
        name.removeprefix(SOURCES_PREFIX): data
        for name, data in sorted(entries.items())
        if name.startswith(SOURCES_PREFIX)
    }
    digests = {name: hashlib.sha256(data).hexdigest() for name, data in raw.items()}
    if digests != recorded.get("files"):
        raise BackupError(f"{zip_path}: the project files do not match the manifest")
    try:
        return artifact_text, {name: data.decode("utf-8") for name, data in raw.items()}
    except UnicodeDecodeError as exc:
        raise BackupError(f"{zip_path}: a project file is not UTF-8 text ({exc})") from None
