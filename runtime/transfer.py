"""A configuration arriving in pieces: an artifact is larger than one command may be, so a
download or reload sends it as `transfer_begin` (size and CRC-32 of the whole text), then
`transfer_chunk`s in order, then the command that uses it. Nothing is taken until the
text is whole and both CRCs agree (the transfer's, and the artifact's own). A resource has
one transfer at a time: a new `transfer_begin` drops the one before."""

from __future__ import annotations

import re
import zlib

from runtime.contract.artifact import Artifact, ArtifactError, load_artifact

# characters per chunk: escaped inside a JSON request it may double, and must still fit
# the 64 KiB request limit
MAX_CHUNK = 24 * 1024
MAX_SIZE = 64 * 1024 * 1024


class TransferError(ValueError):
    """The transfer is incomplete, out of order or corrupted; the message says how."""


class IncomingArtifact:
    def __init__(self) -> None:
        self._size = 0
        self._crc = ""
        self._parts: list[str] = []
        self._received = 0
        self._open = False

    def begin(self, size: int, crc: str) -> None:
        """Start a transfer; one still open is dropped."""
        if not 0 < size <= MAX_SIZE:
            raise TransferError(f"size must be from 1 to {MAX_SIZE} bytes")
        if not re.fullmatch(r"[0-9A-Fa-f]{8}", crc):
            raise TransferError(f"crc must be 8 hex digits, not {crc!r}")
        self._size, self._crc, self._parts, self._received = size, crc.upper(), [], 0
        self._open = True

    def chunk(self, offset: int, data: str) -> int:
        """Add the piece at `offset`; returns the characters received so far."""
        if not self._open:
            raise TransferError("no transfer is open: transfer_begin first")
        if offset != self._received:
            raise TransferError(f"chunk at {offset}, expected {self._received}")
        if len(data) > MAX_CHUNK or self._received + len(data) > self._size:
            raise TransferError("chunk too large for the announced size")
        self._parts.append(data)
        self._received += len(data)
        return self._received

    def complete(self) -> Artifact:
        """The whole artifact, verified; the transfer is closed either way."""
        if not self._open:
            raise TransferError("no transfer is open: transfer_begin first")
        self._open = False
        text, self._parts = "".join(self._parts), []
        if len(text) != self._size:
            raise TransferError(f"transfer incomplete: {len(text)} of {self._size} bytes")
        crc = f"{zlib.crc32(text.encode('utf-8')):08X}"
        if crc != self._crc:
            raise TransferError(f"transfer CRC {crc} is not the announced {self._crc}")
        try:
            return load_artifact(text)
        except ArtifactError as exc:
            raise TransferError(str(exc)) from None


def pieces(text: str, size: int = MAX_CHUNK) -> list[tuple[int, str]]:
    """An artifact text cut for sending: (offset, data) of each `transfer_chunk`."""
    return [(offset, text[offset : offset + size]) for offset in range(0, len(text), size)]
