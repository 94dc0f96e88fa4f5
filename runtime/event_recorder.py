"""Writing events of a resource: who acts (the user of the command being carried out), and
which events go to the long-term log too (user actions and configuration changes)."""

from __future__ import annotations

from typing import Any

from runtime.contract.values import jsonable
from runtime.event_log import EventLog

# of the long-term log's 10,000 places, the most that logins take within its 3 days (the
# rest is kept for the user actions and configuration changes; docs/event-log.md)
LONG_TERM_SHARES = {"login": 2_500}


class EventRecorder:
    def __init__(self, log: EventLog) -> None:
        self.log = log
        self.acting_user: str | None = None  # who sent the command being carried out

    def record(
        self,
        kind: str,
        message: str,
        user: str | None = None,
        long_term: bool | None = None,
        **details: Any,
    ) -> None:
        keep = long_term if long_term is not None else kind != "error"
        plain = {name: jsonable(value) for name, value in sorted(details.items())}
        who = user if user is not None else self.acting_user
        self.log.record(kind, message, user=who, long_term=keep, **plain)
