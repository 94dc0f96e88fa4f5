"""Requests off the bus, checked before the cycle thread sees them.

Zenoh hands a query's whole payload to our callback (a 50 MB one too). Its size is looked
at there, before a byte is copied: a request larger than the protocol allows, or with an
attachment larger than that, is refused at once, unread. The rest is decoded and checked
whole by the contract's decoder on a thread of its own; what it refuses is answered from
there. The cycle thread gets only requests that decoded (`inbox`), so a flood of oversize
or malformed requests costs it no work at all, and the other threads' work per request is
small and bounded by the request's size.

At most MAX_WAITING requests wait, received or decoded: past that a request is refused
`busy` at once, so a flood holds neither memory nor the answers of everyone else.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from runtime.contract.protocol import MAX_REQUEST_BYTES, Request, encode_refusal
from runtime.contract.refusal import Refusal

log = logging.getLogger(__name__)

MAX_WAITING = 1024
_STOP = None  # put on the decoder's queue when the link closes


@dataclass(frozen=True)
class Received:
    """A query and its request, decoded and checked whole; or the defect of the runtime
    that decoding met (the cycle thread records it, as it records every defect)."""

    query: zenoh.Query
    decoded: Request | Exception


class RequestIntake:
    def __init__(self, decode: Callable[[zenoh.Query], Request]) -> None:
        self._decode = decode
        self.inbox: queue.Queue[Received] = queue.Queue()
        self._waiting = threading.BoundedSemaphore(MAX_WAITING)  # received or decoded
        self._received: queue.SimpleQueue[zenoh.Query | None] = queue.SimpleQueue()
        self._decoder = threading.Thread(target=self._decode_loop, name="padt-requests")
        self._decoder.daemon = True
        self._decoder.start()

    def receive(self, query: zenoh.Query) -> None:
        """Zenoh's callback: sizes only (a length, no copy), then on to the decoder."""
        payload, attachment = query.payload, query.attachment
        size = len(payload) if payload is not None else 0
        attached = len(attachment) if attachment is not None else 0
        if size > MAX_REQUEST_BYTES or attached > MAX_REQUEST_BYTES:
            what = "request" if size > MAX_REQUEST_BYTES else "attachment"
            _refuse(
                query,
                Refusal(
                    "too_large",
                    f"{what} of {max(size, attached)} bytes is larger than "
                    f"{MAX_REQUEST_BYTES} bytes: refused unread",
                ),
            )
            return
        if not self._waiting.acquire(blocking=False):
            _refuse(query, Refusal("busy", "too many requests waiting: try again"))
            return
        self._received.put(query)

    def done(self) -> None:
        """A request taken from the inbox (or refused by the decoder) waits no more."""
        self._waiting.release()

    def _decode_loop(self) -> None:
        while True:
            query = self._received.get()
            if query is _STOP:
                return
            try:
                self._take(query)
            except Exception:  # a defect here must not end the intake: nothing would answer
                log.exception("internal error while taking a request")
            del query  # a Zenoh query is finalised when its last reference goes

    def _take(self, query: zenoh.Query) -> None:
        try:
            received = Received(query, self._decode(query))
        except Refusal as refusal:
            _refuse(query, refusal)
            self.done()
            return
        except Exception as exc:  # a defect of the decoder: the cycle thread records it
            received = Received(query, exc)
        self.inbox.put(received)

    def close(self) -> None:
        self._received.put(_STOP)
        self._decoder.join(timeout=5)


def _refuse(query: zenoh.Query, refusal: Refusal) -> None:
    try:
        query.reply(query.key_expr, encode_refusal(refusal))
    except zenoh.ZError as exc:  # the sender went away: nobody to tell
        log.debug("refusal not sent: %s", exc)
