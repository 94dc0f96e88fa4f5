"""A configuration arriving in pieces: an artifact is larger than one command may be, so a
download or reload sends it as `transfer_begin` (size and CRC-32 of the whole text), then
`transfer_chunk`s in order, then the command that uses it. Nothing is taken until the
text is whole and both CRCs agree (the transfer's, and the artifact's own). A resource has
one transfer at a time: a new `transfer_begin` drops the one before."""

from __future__ import annotations

import zlib

from runtime.contract.artifact import Artifact, ArtifactError, load_artifact
from runtime.contract.refusal import Refusal


class IncomingArtifact:
    def __init__(self) -> None:
        self._size = 0
        self._crc = ""
        self._parts: list[str] = []
        self._received = 0
        self._open = False

    def begin(self, size: int, crc: str) -> None:
        """Start a transfer (size and CRC checked by the protocol); one still open is
        dropped."""
        self._size, self._crc, self._parts, self._received = size, crc.upper(), [], 0
        self._open = True

    def chunk(self, offset: int, data: str) -> int:
        """Add the piece at `offset`; returns the characters received so far."""
        if not self._open:
            raise Refusal("transfer", "no transfer is open: transfer_begin first")
        if offset != self._received:
            raise Refusal("transfer", f"chunk at {offset}, expected {self._received}")
        if self._received + len(data) > self._size:
            raise Refusal("transfer", "chunk too large for the announced size")
        self._parts.append(data)
        self._received += len(data)
        return self._received

    def complete(self) -> Artifact:
        """The whole artifact, verified; the transfer is closed either way."""
        if not self._open:
            raise Refusal("transfer", "no transfer is open: transfer_begin first")
        self._open = False
        text, self._parts = "".join(self._parts), []
        if len(text) != self._size:
            raise Refusal("transfer", f"transfer incomplete: {len(text)} of {self._size} bytes")
        crc = f"{zlib.crc32(text.encode('utf-8')):08X}"
        if crc != self._crc:
            raise Refusal("transfer", f"transfer CRC {crc} is not the announced {self._crc}")
        try:
            return load_artifact(text)
        except ArtifactError as exc:
            raise Refusal("transfer", str(exc)) from None
