"""A resource on virtual time, driven the way a client drives it: through the command
handler (the same code that answers Zenoh requests), one CPU cycle at a time."""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeTier
from runtime.commands import execute
from runtime.contract import scram
from runtime.contract.artifact import (
    Artifact,
    ProgramConfig,
    ResourceConfig,
    UserAccount,
    crc32_hex,
)
from runtime.contract.protocol import pieces
from runtime.resource import Resource

# what tests mostly want: single step, forcing and writes allowed
OPEN_RESOURCE: dict[str, Any] = {"safety_operation": False, "global_forcing_allowed": True}


@dataclass
class Harness:
    resource: Resource
    clock: VirtualClock
    cycle_ns: int
    trace: list[dict[str, Any]] = field(default_factory=list)
    token: str | None = None  # sent with every command, as a logged-in client does

    logins: dict[str, tuple[bytes, Iterator[int]]] = field(default_factory=dict)

    def cmd(self, command: str, /, **args: Any) -> dict[str, Any]:
        """A command as a client sends it, signed with its session's key (`token`: the
        harness's own, or one given); the reply as it would get it."""
        token = args.pop("token", self.token)
        session: dict[str, Any] = {}
        key = None
        if token in self.logins:
            key, numbers = self.logins[token]
            session = {"token": token, "seq": next(numbers)}
        elif token is not None:  # a token this harness did not log in with: unsigned
            session = {"token": token}
        payload = json.dumps({"cmd": command, **session, **args}).encode()
        mac = scram.request_mac(key, payload) if key is not None else None
        crossed: dict[str, Any] = json.loads(execute(self.resource, payload, mac))
        return crossed

    def login(self, user: str, password: str) -> str:
        """Log in as a client does (runtime/contract/scram.py); returns the token, whose
        requests this harness then signs."""
        challenge, exchange = self._challenge(user, password)
        assert exchange is not None, challenge
        proof = exchange.proof
        reply = self.ok("login", token=None, user=user, nonce=challenge["nonce"], proof=proof)
        assert exchange.server_proven(reply["server_signature"], reply["publication_key"])
        token = str(reply["token"])
        self.logins[token] = (exchange.session_key, itertools.count(1))
        return token

    def failed_login(self, user: str, password: str) -> str:
        """A login that does not succeed: the code of its refusal."""
        challenge, exchange = self._challenge(user, password)
        if exchange is None:
            return str(challenge["error"]["code"])
        proof = exchange.proof
        return self.refused("login", token=None, user=user, nonce=challenge["nonce"], proof=proof)

    def _challenge(
        self, user: str, password: str
    ) -> tuple[dict[str, Any], scram.ClientExchange | None]:
        client_nonce = scram.new_nonce()
        challenge = self.cmd("login_begin", token=None, user=user, nonce=client_nonce)
        if not challenge["ok"]:
            return challenge, None
        exchange = scram.ClientExchange.answer(
            self.resource.name, user, password, client_nonce, challenge["nonce"],
            scram.unb64(challenge["salt"]), challenge["n"], challenge["r"], challenge["p"],
        )  # fmt: skip
        return challenge, exchange

    def ok(self, command: str, /, **args: Any) -> dict[str, Any]:
        reply = self.cmd(command, **args)
        assert reply["ok"], reply
        return reply

    def refused(self, command: str, /, **args: Any) -> str:
        reply = self.cmd(command, **args)
        assert not reply["ok"], reply
        return str(reply["error"]["code"])

    def send(self, artifact: Artifact) -> None:
        """Transfer an artifact in chunks, as the PADT does before a load or reload."""
        text = artifact.to_json()
        self.ok("transfer_begin", size=len(text), crc=crc32_hex(text))
        for offset, piece in pieces(text):
            self.ok("transfer_chunk", offset=offset, data=piece)

    def cycle(self, count: int = 1) -> dict[str, Any]:
        """`count` CPU cycles, the clock one target interval further after each."""
        for _ in range(count):
            self.resource.cycle()
            self.clock.advance(self.cycle_ns)
            self.trace.append(self.resource.variables.values())
        return self.resource.variables.values()

    def value(self, name: str) -> Any:
        return self.resource.variables.value(name)

    def state(self, program: str | None = None) -> str:
        status = self.resource.status()
        if program is None:
            return str(status.state)
        return next(str(p.state) for p in status.programs if p.name == program)


def compiled(
    text: str,
    programs: list[Any] | None = None,
    safe_values: dict[str, Any] | None = None,
    users: list[UserAccount] | None = None,
    **resource: Any,
) -> Artifact:
    """Compile `text` with the given resource parameters and user programs (dicts of
    ProgramConfig fields; `name` doubles as `pou` unless given)."""
    params = {**OPEN_RESOURCE, "target_cycle_ms": 10, **resource}
    config = ResourceConfig(name="R", **params)
    configs = None
    if programs is not None:
        configs = [
            ProgramConfig(**{"pou": p["name"], "program_id": i, **p})
            for i, p in enumerate(programs, 1)
        ]
    result = compile_sources(
        [SourceFile("test.st", text)],
        resource=config,
        programs=configs,
        safe_values=safe_values,
        users=users,
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def harness(
    text: str,
    programs: list[Any] | None = None,
    start: bool = True,
    safe_values: dict[str, Any] | None = None,
    users: list[UserAccount] | None = None,
    native: NativeTier | None = None,
    **resource: Any,
) -> Harness:
    """A resource with `compiled(text, programs, safe_values, users, **resource)` loaded
    (and started); with `native`, its native bodies in place."""
    artifact = compiled(text, programs, safe_values, users, **resource)
    clock = VirtualClock()
    res = Resource("R", clock)
    res.native = native
    res.load(artifact)
    res.tier_up(wait=True)
    h = Harness(res, clock, (artifact.resource.target_cycle_ms or 10) * 1_000_000)
    if start:  # as at power-up with Autostart (no client, so no login needed)
        h.resource.start()
    return h
