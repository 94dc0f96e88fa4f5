"""How many Modbus requests the served image answers per second, whoever sends them.

pymodbus decodes and answers each frame in Python, on the I/O thread: about 70 us of
the interpreter lock each here, which the cycle thread then waits for. A flood of 5,000 to
14,000 requests a second kept that lock busy and stretched the periods of a 20 ms cycle
to 25-55 ms. The meter is a token bucket over every connection of the server: past its rate, the
connection that asked is not read (its requests wait in its socket, and TCP slows the
sender) until the bucket has a token for it. Nothing is refused or lost: a flood is just
answered no faster than the rate, and an HMI polling beside it waits its turn.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field

REQUESTS_PER_SECOND = 2000  # an HMI reads 10 times a second; SCADA polls some hundreds
QUIET_S = 10.0  # a wait after this long without one begins a new flood (one event each)


@dataclass
class RequestMeter:
    rate: int = REQUESTS_PER_SECOND
    floods: int = 0  # times the meter began to hold requests back (I/O thread)
    _tokens: float = field(default=0.0, init=False)
    _at: float = field(default=0.0, init=False)
    _last_wait: float = field(default=-QUIET_S, init=False)

    def __post_init__(self) -> None:
        self._tokens = self.burst

    @property
    def burst(self) -> float:
        """Requests answered at once after a quiet spell: 25 ms worth."""
        return max(1.0, self.rate / 40)

    def take(self, loop: asyncio.AbstractEventLoop, transport: asyncio.BaseTransport) -> None:
        """A request was received on `transport` (on the I/O thread): one token; when
        none is left, the connection is read again once there is one for it."""
        now = loop.time()
        self._tokens = min(self.burst, self._tokens + (now - self._at) * self.rate)
        self._at = now
        self._tokens -= 1
        if self._tokens >= 0 or not isinstance(transport, asyncio.ReadTransport):
            return
        if now - self._last_wait > QUIET_S:
            self.floods += 1
        self._last_wait = now
        transport.pause_reading()
        loop.call_later(-self._tokens / self.rate, transport.resume_reading)
