"""The address a request comes from, as the login lock counts failures by it (REST API and
browser UI).

A request's `X-Forwarded-For` is written by whoever sends it: taken from anyone, a caller
could dodge the lock with made-up addresses, or aim it at a victim's address. So the peer
of the connection is the address, unless it is a proxy the operator named
(`--trusted-proxy`): then the chain is read from the right, each trusted hop giving way to
the address it says it saw, and the first hop that is no trusted proxy is the client. What
a client wrote itself lies further left and is never read. `Forwarded` and `X-Real-IP`
are not read at all: a proxy in front of padt must set `X-Forwarded-For`."""

from __future__ import annotations

import argparse
import ipaddress
from collections.abc import Iterable
from dataclasses import dataclass

Network = ipaddress.IPv4Network | ipaddress.IPv6Network
MAX_ADDRESS = 64  # characters of an address kept (it is a key of the login lock)


@dataclass(frozen=True)
class TrustedProxies:
    """The proxies whose `X-Forwarded-For` counts; none by default."""

    networks: tuple[Network, ...] = ()

    def trusts(self, address: str) -> bool:
        try:
            ip = ipaddress.ip_address(address.strip())
        except ValueError:
            return False
        if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
            ip = ip.ipv4_mapped  # a dual-stack socket shows IPv4 peers as ::ffff:a.b.c.d
        return any(ip in network for network in self.networks)


NO_PROXIES = TrustedProxies()


def trusted_proxy(text: str) -> Network:
    """`--trusted-proxy ADDR` or `ADDR/PREFIX` (argparse type)."""
    try:
        return ipaddress.ip_network(text.strip(), strict=False)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is no IP address or network (e.g. 127.0.0.1, 10.0.0.0/8)"
        ) from None


def add_trusted_proxy_option(parser: argparse.ArgumentParser) -> None:
    """`--trusted-proxy` of `padt api`, `padt ui` and `padt demo`."""
    parser.add_argument(
        "--trusted-proxy",
        type=trusted_proxy,
        action="append",
        default=[],
        metavar="ADDR[/PREFIX]",
        help="a reverse proxy whose X-Forwarded-For names the client, for the lock on failed "
        "logins (repeatable; default: none, the connection's own address counts)",
    )


def client_address(peer: str, forwarded_for: Iterable[str], trusted: TrustedProxies) -> str:
    """Who sent a request that reached us from `peer`, given its `X-Forwarded-For` header
    lines (several lines count as one list, in order)."""
    hops = [hop.strip() for line in forwarded_for for hop in line.split(",")]
    address = peer
    while trusted.trusts(address) and hops:
        address = hops.pop()
    return address[:MAX_ADDRESS] or peer
