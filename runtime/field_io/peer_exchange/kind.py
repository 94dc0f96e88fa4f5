"""The exchange between resources as the field I/O knows it (`drivers.py`): its section of
the configuration, and its driver, made only for a configuration that exchanges something
and a runtime on the bus. The driver's module (and Zenoh with it) is imported then and not
before: every padt command builds its parser with the runtime's options, and Zenoh takes
a third of a second to import."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from runtime.contract.artifact import Artifact
from runtime.contract.exchange import ExchangeConfig
from runtime.contract.signatures import Freshness
from runtime.field_io.driver import DriverContext, DriverKind, FieldDriver
from runtime.field_io.peer_exchange.peer_keys import PeerKeys

if TYPE_CHECKING:
    import zenoh

    from runtime.identity import Identity


@dataclass(frozen=True)
class ExchangeOptions:
    """What the runtime gives the exchange: its Zenoh session and signing key (None: a
    resource off the bus, which exchanges nothing), and where the pinned keys of the
    resources it subscribes to are kept (None: in memory)."""

    session: zenoh.Session | None = None
    identity: Identity | None = None
    peer_keys: Path | None = None


def exchange_kind(options: ExchangeOptions) -> DriverKind:
    # one for the process: a driver made anew keeps the pins and the stamps taken
    keys, freshness = PeerKeys(options.peer_keys), Freshness()

    def make(config: ExchangeConfig, context: DriverContext) -> FieldDriver | None:
        if not config or options.session is None or options.identity is None:
            return None
        from runtime.field_io.peer_exchange.driver import PeerExchangeDriver  # Zenoh: above

        return PeerExchangeDriver(
            config, context, options.session, options.identity, keys, freshness
        )

    return DriverKind("exchange", _config_of, make)


def _config_of(artifact: Artifact | None) -> ExchangeConfig:
    found = artifact.exchange if artifact is not None else None
    return found if found is not None else ExchangeConfig()
