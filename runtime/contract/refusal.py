"""A refusal: the one way a request is turned down, wherever it is turned down (the decoder,
the access check, the resource's state, the PADT's own checks) and on either side of the
bus. Its code is stable (docs/protocol.md lists the resource's codes); its message says why
in words a user can act on."""

from __future__ import annotations

from typing import Any


class Refusal(Exception):
    def __init__(self, code: str, message: str, **details: Any) -> None:
        super().__init__(message)
        self.code = code
        self.message = message
        self.details = details

    def __str__(self) -> str:
        return f"refused ({self.code}): {self.message}"

    def as_json(self) -> dict[str, Any]:
        """The error object of a reply: `{"code", "message", ...details}`."""
        return {"code": self.code, "message": self.message, **self.details}
