"""Zip archives from outside (backups handed to `padt docs`, the REST API's backup folder),
read without trusting a byte of them.

Everything is checked before anything is read, and nothing is read past the limits:
- the archive itself: its size, the size of its central directory (which `zipfile` would
  load whole, one object per entry) and the number of entries;
- each entry's name: relative, `/`-separated, without `..`, `.`, empty segments, drive
  letters, backslashes or control characters, and unique even where case is not told
  apart (`A.st` and `a.st` would be one file on some disks);
- each entry's kind: a plain file (no link, device or pipe in the Unix mode bits), not
  encrypted, stored or deflated (other methods bring their own bombs);
- each entry's declared size, the total, and the compression ratio, against `Limits`;
- then the reading itself, in bounded pieces: a header that lies about the size cannot
  make it read more than the size it declared.
Every refusal is an `ArchiveRefused` naming the archive, the entry and the reason. Files
are unpacked (`unpack`) only after the whole archive passed, and only below their folder.
"""

from __future__ import annotations

import re
import stat
import struct
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

MIB = 1 << 20
_END_RECORD = b"PK\x05\x06"
_END_RECORD_SIZE = 22
_ZIP64_LOCATOR = b"PK\x06\x07"
_PIECE = 64 * 1024  # bytes unpacked at a time
_DRIVE = re.compile(r"^[A-Za-z]:")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


@dataclass(frozen=True)
class Limits:
    """What an archive may hold. The defaults fit a backup many times over: a project's
    sources and its artifact are a few megabytes."""

    archive_bytes: int = 256 * MIB  # the zip file itself
    directory_bytes: int = 4 * MIB  # its central directory
    entries: int = 10_000
    entry_bytes: int = 64 * MIB  # one entry unpacked
    total_bytes: int = 256 * MIB  # all entries unpacked
    ratio: int = 200  # unpacked / packed, of an entry larger than ratio_from
    ratio_from: int = MIB  # smaller entries may pack better (a file of blanks)


class ArchiveRefused(ValueError):
    """An archive, or one of its entries, that is not read; the message says which, why."""


def read_archive(path: Path, limits: Limits = Limits()) -> dict[str, bytes]:
    """Every file of the zip at `path` by its (checked) name, directories left out, after
    every check above; ArchiveRefused otherwise. OSError when the file cannot be read."""
    size = path.stat().st_size
    if size > limits.archive_bytes:
        raise ArchiveRefused(f"{path}: larger than {limits.archive_bytes:,} bytes")
    with path.open("rb") as stream:
        _check_directory(path, stream, size, limits)
        try:
            with zipfile.ZipFile(stream) as archive:
                infos = archive.infolist()
                files = _checked(path, infos, limits)
                return {name: _read(path, archive, info) for name, info in files.items()}
        except zipfile.BadZipFile as exc:
            raise ArchiveRefused(f"{path}: not a readable zip ({exc})") from None


def unpack(files: Mapping[str, bytes], folder: Path) -> None:
    """Write `files` (names from `read_archive`) below `folder`, and nowhere else: a
    name that would land outside (a link already in the folder) is refused."""
    root = folder.resolve()
    for name, data in files.items():
        target = (root / name).resolve()
        if not target.is_relative_to(root) or target == root:
            raise ArchiveRefused(f"{name}: would be written outside {folder}")
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)


def _check_directory(path: Path, stream: BinaryIO, size: int, limits: Limits) -> None:
    """The end record's sizes, before `zipfile` loads the central directory whole."""
    tail_size = min(size, _END_RECORD_SIZE + 0xFFFF)  # the record and its longest comment
    stream.seek(size - tail_size)
    tail = stream.read(tail_size)
    at = tail.rfind(_END_RECORD)
    if at < 0 or len(tail) - at < _END_RECORD_SIZE:
        raise ArchiveRefused(f"{path}: not a zip archive (no end record)")
    if at >= 20 and tail[at - 20 : at - 16] == _ZIP64_LOCATOR:
        raise ArchiveRefused(f"{path}: a ZIP64 archive (over 65,535 entries or 4 GiB)")
    entries, directory = struct.unpack("<HI", tail[at + 10 : at + 16])
    if entries > limits.entries:
        raise ArchiveRefused(f"{path}: {entries:,} entries, more than {limits.entries:,}")
    if directory > limits.directory_bytes:
        raise ArchiveRefused(
            f"{path}: a directory of {directory:,} bytes, more than {limits.directory_bytes:,}"
        )


def _checked(
    path: Path, infos: list[zipfile.ZipInfo], limits: Limits
) -> dict[str, zipfile.ZipInfo]:
    if len(infos) > limits.entries:
        raise ArchiveRefused(f"{path}: {len(infos):,} entries, more than {limits.entries:,}")
    files: dict[str, zipfile.ZipInfo] = {}
    seen: set[str] = set()
    total = 0
    for info in infos:
        name = info.orig_filename  # as stored: ZipInfo.filename has `\` made `/` on Windows
        problem = _name_problem(name) or _kind_problem(info) or _size_problem(info, limits)
        if problem:
            raise ArchiveRefused(f"{path}: entry {_shown(name)}: {problem}")
        folded = name.rstrip("/").casefold()
        if folded in seen:
            raise ArchiveRefused(f"{path}: entry {_shown(name)}: a second entry of that name")
        seen.add(folded)
        total += info.file_size
        if total > limits.total_bytes:
            raise ArchiveRefused(
                f"{path}: entry {_shown(name)}: the entries unpack to more than "
                f"{limits.total_bytes:,} bytes"
            )
        if not name.endswith("/"):  # a folder entry: nothing to read
            files[name] = info
    return files


def _shown(name: str) -> str:
    """A name as the user can find it in a listing; escaped only when it would garble."""
    return repr(name) if _CONTROL.search(name) else f"'{name}'"


def _name_problem(name: str) -> str:
    if not name:
        return "an empty name"
    if "\\" in name:
        return "a backslash in the name"
    if _CONTROL.search(name):
        return "a control character in the name"
    if name.startswith("/"):
        return "an absolute name"
    if _DRIVE.match(name):
        return "a drive letter in the name"
    parts = name.removesuffix("/").split("/")
    if any(part in ("", ".", "..") for part in parts):
        return "an empty, '.' or '..' part in the name"
    if any(_DRIVE.match(part) for part in parts):
        return "a drive letter in the name"
    return ""


def _kind_problem(info: zipfile.ZipInfo) -> str:
    mode = info.external_attr >> 16
    kind = stat.S_IFMT(mode)
    if info.filename.endswith("/"):
        return "" if kind in (0, stat.S_IFDIR) and info.file_size == 0 else "a folder with data"
    if kind not in (0, stat.S_IFREG):  # 0: no Unix mode recorded (made on Windows)
        return "a link" if kind == stat.S_IFLNK else "not a plain file"
    if info.flag_bits & 0x1:
        return "encrypted"
    if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        return f"packed with method {info.compress_type} (only stored or deflated are read)"
    return ""


def _size_problem(info: zipfile.ZipInfo, limits: Limits) -> str:
    if info.file_size > limits.entry_bytes:
        return f"unpacks to {info.file_size:,} bytes, more than {limits.entry_bytes:,}"
    packed = max(info.compress_size, 1)
    if info.file_size > limits.ratio_from and info.file_size > limits.ratio * packed:
        return (
            f"unpacks to {info.file_size // packed:,} times its packed size, more than "
            f"{limits.ratio}"
        )
    if info.compress_type == zipfile.ZIP_STORED and info.file_size != info.compress_size:
        return "stored, but its two sizes differ"
    return ""


def _read(path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo) -> bytes:
    """The entry, in pieces, never more than it declared (plus one byte to tell a lie)."""
    pieces: list[bytes] = []
    left = info.file_size + 1
    try:
        with archive.open(info) as entry:
            while left > 0 and (piece := entry.read(min(_PIECE, left))):
                pieces.append(piece)
                left -= len(piece)
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError) as exc:
        raise ArchiveRefused(
            f"{path}: entry {_shown(info.orig_filename)}: cannot be read ({exc})"
        ) from None
    data = b"".join(pieces)
    if len(data) != info.file_size:
        raise ArchiveRefused(
            f"{path}: entry {_shown(info.orig_filename)}: holds more or less than the "
            f"{info.file_size:,} bytes it declares"
        )
    return data
