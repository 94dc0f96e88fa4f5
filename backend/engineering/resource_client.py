"""The engineering side's session with a running resource over Zenoh: typed commands with
their checked replies, the login it keeps, and subscriptions to the resource's status,
events, liveliness and watch sets. The CLI, the REST API and the UI reach resources only
through this client."""

from __future__ import annotations

import contextlib
import itertools
import json
import logging
import queue
import secrets
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import zenoh

from backend.engineering.known_resources import KnownResources
from runtime.contract import scram, signatures
from runtime.contract.keyspace import (
    alive_key,
    command_key,
    events_key,
    status_key,
    watch_key,
    watcher_key,
)
from runtime.contract.outside_json import MIB, JsonRefused, read_json
from runtime.contract.protocol import (
    MAX_WATCHED,
    QUALITY_LETTERS,
    Command,
    Event,
    GetStatus,
    Login,
    LoginBegin,
    LoginChallenge,
    Logout,
    Status,
    Unwatch,
    Watch,
    WatchedValue,
    WatchPublication,
    WatchValues,
    decode_publication,
    decode_reply,
    decode_request,
    encode_request,
)
from runtime.contract.refusal import Refusal

COMMAND_TIMEOUT_S = 5.0
MAX_REPLY_BYTES = 256 * MIB  # a reply read as plain JSON (`command`): 100,000 values fit
# how long a client waits, after the first answer, for another one: a second answerer on a
# resource's command key is another party (the resource's own query is done at once)
SECOND_ANSWER_S = 0.5
WATCH_BATCH = 1000  # variable names per watch request (paths are short; 64 KiB is the limit)
R = TypeVar("R")
P = TypeVar("P")
log = logging.getLogger("padt.client")


class ResourceUnreachable(Exception):
    """No runtime answered the command."""


class WatchHandle:
    """A registered watch set: its values arrive until `close`."""

    def __init__(
        self, watch_id: str, token: zenoh.LivelinessToken, subscriber: zenoh.Subscriber[None]
    ) -> None:
        self.watch_id = watch_id
        self.variables: list[str] = []  # canonical paths, as the runtime names them
        self.revision = 0  # of the set as last registered: older values are not taken
        self._token = token
        self._subscriber = subscriber

    def close(self) -> None:
        """Withdraw the token: the runtime drops the set."""
        self._token.undeclare()
        self._subscriber.undeclare()


@dataclass
class ResourceLogin:
    """What a login to a resource gives its client: the session token, the key that signs
    every request of the session, and the key the resource signs its publications with
    (runtime/contract/scram.py, signatures.py)."""

    token: str
    key: bytes
    publication_key: str
    user: str
    level: str
    _numbers: Iterator[int] = field(default_factory=lambda: itertools.count(1), repr=False)

    def next_seq(self) -> int:
        return next(self._numbers)  # one counter for all threads of a client (atomic)


class ResourceClient:
    def __init__(
        self, session: zenoh.Session, resource: str, known: KnownResources | None = None
    ) -> None:
        self.session = session
        self.resource = resource
        # the resources' keys, pinned at their first login (known_resources.py)
        self.known = known if known is not None else KnownResources()
        self._subscribers: list[zenoh.Subscriber[None]] = []
        self.logged_in: ResourceLogin | None = None  # after `login`: signs every request
        # a publication key known from elsewhere (the API learns it from its users' logins)
        self.trusted_key: str | None = None
        self._credentials: tuple[str, str] | None = None
        self._sent = 0  # requests sent: the sequence number of their source information

    def ask(self, command: Command[R], timeout_s: float = COMMAND_TIMEOUT_S) -> R:
        """Send a command; its reply, checked against the protocol. Raises the resource's
        Refusal, or ResourceUnreachable when no runtime answered. A command the resource's
        decoder would refuse (a value nested too deep, an argument out of its range: it may
        come from a REST body or a browser) is refused here, before it is sent."""
        decode_request(encode_request(command, None))
        reply = self._exchange(
            command.NAME,
            lambda seq: encode_request(command, self._token(), seq),
            timeout_s,
            relogin=not isinstance(command, LoginBegin | Login | Logout),
        )
        return decode_reply(command, reply)

    def command(
        self, cmd: str, /, timeout_s: float = COMMAND_TIMEOUT_S, **args: Any
    ) -> dict[str, Any]:
        """The wire form, for tools and tests that speak JSON: a command by its name and
        arguments as they are (unchecked), the reply as JSON data with its `ok`."""

        def payload(seq: int | None) -> bytes:
            session = {"token": self._token(), "seq": seq} if self.logged_in else {}
            return json.dumps({"cmd": cmd, **session, **args}).encode()

        reply = self._exchange(cmd, payload, timeout_s, relogin=not cmd.startswith("log"))
        try:
            data: dict[str, Any] = read_json(reply, "the reply", MAX_REPLY_BYTES)
        except JsonRefused as exc:
            raise Refusal("bad_reply", str(exc)) from None
        return data

    def login(self, user: str, password: str) -> ResourceLogin:
        """Log in by challenge and response: the password never leaves this process, and
        nothing derived from it leaves before the challenge proves to be the resource's
        (signed with the key it is known by, `known_resources.py`, for this login's nonce,
        at a cost no weaker than our own verifiers'). The resource must then prove that it
        holds the user's verifier. Refusal `impostor` or `bad_challenge` otherwise, or the
        resource's own."""
        client_nonce = scram.new_nonce()
        challenge = self._plain(LoginBegin(user, client_nonce))
        auth = self._checked(challenge, user, client_nonce)
        try:
            salted = scram.salted_password(
                password, scram.unb64(challenge.salt), challenge.n, challenge.r, challenge.p
            )
        except (ValueError, MemoryError) as exc:  # a cost this machine cannot pay
            raise Refusal(
                "bad_challenge", f"the login challenge of {self.resource}: {exc}"
            ) from None
        exchange = scram.ClientExchange(salted, auth)
        reply = self._plain(Login(user, challenge.nonce, exchange.proof))
        if reply.publication_key != challenge.publication_key or not exchange.server_proven(
            reply.server_signature, reply.publication_key
        ):
            raise Refusal(
                "impostor",
                f"the answer to the login does not prove that it comes from {self.resource}",
            )
        self.known.remember(self.resource, reply.publication_key)
        self.logged_in = ResourceLogin(
            reply.token, exchange.session_key, reply.publication_key, reply.user, reply.level
        )
        return self.logged_in

    def _checked(self, challenge: LoginChallenge, user: str, client_nonce: str) -> bytes:
        """The AuthMessage of a challenge that is the resource's, for this login, at a cost
        this client pays; Refusal otherwise, before anything is derived from a password."""
        if not challenge.nonce.startswith(client_nonce):
            raise Refusal("impostor", f"a login challenge not from resource {self.resource}")
        self.known.check(self.resource, challenge.publication_key)
        salt = scram.unb64(challenge.salt)
        auth = scram.auth_message(
            self.resource, user, client_nonce, challenge.nonce, salt,
            challenge.n, challenge.r, challenge.p,
        )  # fmt: skip
        signature = scram.unb64(challenge.signature)
        key = challenge.publication_key
        if not signatures.verifies(key, scram.challenge_message(auth), signature):
            raise Refusal(
                "impostor", f"the login challenge is not signed by resource {self.resource}"
            )
        problem = scram.cost_problem(challenge.n, challenge.r, challenge.p)
        if problem is not None:
            raise Refusal("bad_challenge", f"the login challenge of {self.resource}: {problem}")
        return auth

    def use_credentials(self, user: str, password: str) -> None:
        """Log in whenever the resource asks for it (at the first command, after a runtime
        restart or an expired session)."""
        self._credentials = (user, password)

    def wait_until_answering(self, timeout_s: float = 30) -> None:
        """Wait for the resource to answer (a runtime that is still starting)."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self.ask(GetStatus())
                return
            except Refusal:  # an answer all the same
                return
            except ResourceUnreachable:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)

    def _token(self) -> str | None:
        return self.logged_in.token if self.logged_in is not None else None

    def _plain(self, command: Command[R]) -> R:
        """A login step: no session, no second try."""
        reply = self._exchange(
            command.NAME, lambda seq: encode_request(command, None), relogin=False
        )
        return decode_reply(command, reply)

    def _exchange(
        self,
        name: str,
        payload: Callable[[int | None], bytes],
        timeout_s: float = COMMAND_TIMEOUT_S,
        relogin: bool = True,
    ) -> bytes:
        """Send a request, signed with the session key when logged in; log in again once
        when the session is gone (its expiry or a restart of the runtime) and the client
        has credentials. `payload` makes the request with the session and sequence number
        of the moment."""
        reply = self._send(name, payload, timeout_s)
        if not relogin or self._credentials is None or not _unauthenticated(reply):
            return reply
        try:
            self.login(*self._credentials)
        except Refusal:
            return reply
        return self._send(name, payload, timeout_s)

    def _send(self, name: str, payload: Callable[[int | None], bytes], timeout_s: float) -> bytes:
        """The one answer to a request. Asked of every queryable on the command key (a
        queryable declared `complete` would otherwise take every query from the resource):
        a second answer is another party's, and refused as `impostor`."""
        login = self.logged_in
        request = payload(login.next_seq() if login is not None else None)
        mac = scram.request_mac(login.key, request) if login is not None else None
        self._sent += 1
        arrived: queue.Queue[zenoh.Reply | None] = queue.Queue()
        self.session.get(
            command_key(self.resource),
            zenoh.handlers.Callback(arrived.put, lambda: arrived.put(None)),
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
            payload=request,
            attachment=mac,
            timeout=timeout_s,
            source_info=zenoh.SourceInfo(self.session.id, self._sent),
        )
        answers = _answers(arrived, time.monotonic() + timeout_s + 1)
        if len(answers) > 1:
            raise Refusal(
                "impostor",
                f"another party answers on {self.resource}'s command key "
                f"({len(answers)} answers to '{name}')",
            )
        if not answers:
            raise ResourceUnreachable(f"resource '{self.resource}' did not answer '{name}'")
        return answers[0]

    # ---- publications
    def on_status(self, callback: Callable[[Status], None]) -> None:
        self._subscribers.append(self._declare(status_key(self.resource), Status, callback))

    def on_events(self, callback: Callable[[Event], None]) -> None:
        """Every event of the resource's log from now on, in order."""
        self._subscribers.append(self._declare(events_key(self.resource), Event, callback))

    def on_alive(self, callback: Callable[[bool], None]) -> None:
        """Told True when the runtime process is (or comes back) there, False when it goes;
        at once for a runtime already running."""

        def handler(sample: zenoh.Sample) -> None:
            callback(sample.kind == zenoh.SampleKind.PUT)

        self._subscribers.append(
            self.session.liveliness().declare_subscriber(
                alive_key(self.resource), handler, history=True
            )
        )

    def watch(
        self,
        variables: list[str],
        callback: Callable[[WatchValues], None],
        period_ms: int = 100,
    ) -> WatchHandle:
        """Receive the values of `variables` (with their quality) once per period. The set
        lives as long as this session holds its liveliness token (until `close`). Raises
        the resource's Refusal (an unknown variable, a bad period) or ResourceUnreachable."""
        watch_id = secrets.token_hex(8)
        token = self.session.liveliness().declare_token(watcher_key(self.resource, watch_id))
        handles: list[WatchHandle] = []

        def by_path(message: WatchPublication) -> None:
            """The values named by the set's paths, when they are of the set as it is."""
            if not handles:
                return
            paths = handles[0].variables
            if message.revision != handles[0].revision or len(message.values) != len(paths):
                return  # of a set that has changed since: the next period brings the new
            if len(message.qualities) != len(paths):
                log.warning("watch values on %s dropped: qualities do not match", watch_id)
                return
            qualities = message.qualities
            callback(
                WatchValues(
                    message.cycle,
                    {
                        path: WatchedValue(value, QUALITY_LETTERS[letter])
                        for path, value, letter in zip(
                            paths, message.values, qualities, strict=True
                        )
                    },
                )
            )

        subscriber = self._declare(watch_key(self.resource, watch_id), WatchPublication, by_path)
        handle = WatchHandle(watch_id, token, subscriber)
        handles.append(handle)
        try:
            self.change_watch(handle, variables, period_ms)
        except (Refusal, ResourceUnreachable):
            handle.close()
            with contextlib.suppress(Refusal, ResourceUnreachable):  # only tidying up
                self.ask(Unwatch(watch_id))
            raise
        return handle

    def change_watch(self, handle: WatchHandle, variables: list[str], period_ms: int = 100) -> None:
        """Make `variables` the whole set of `handle` (what a screen shows now). Raises
        the resource's Refusal or ResourceUnreachable; the set is then left as it was or
        partly registered, and the caller tries again or closes it."""
        # a large set goes in several requests, each well inside the request limit
        size = min(WATCH_BATCH, MAX_WATCHED)
        batches = [variables[i : i + size] for i in range(0, len(variables), size)]
        for number, batch in enumerate(batches or [[]]):
            reply = self.ask(Watch(handle.watch_id, batch, period_ms, append=number > 0))
        # values of the set only once it is whole: those of a part are not passed on
        handle.variables, handle.revision = reply.variables, reply.revision

    def _declare(
        self, key_expr: str, kind: type[P], callback: Callable[[P], None]
    ) -> zenoh.Subscriber[None]:
        """A subscription that hands on what the resource signed, each message once and
        in order: one that is not newer than the last taken (a replay) is dropped."""
        freshness = signatures.Freshness()

        def handler(sample: zenoh.Sample) -> None:
            payload = sample.payload.to_bytes()
            stamp = self._authentic(payload, sample.attachment)
            if stamp is None:
                log.warning("%s on %s dropped: not signed by the resource", kind.__name__, key_expr)
                return
            if stamp and not freshness.newer(key_expr, stamp):
                log.warning("%s on %s dropped: sent again (a replay)", kind.__name__, key_expr)
                return
            try:
                message = decode_publication(kind, payload)
            except Refusal as wrong:  # not from a runtime that speaks our protocol
                log.warning("%s on %s dropped: %s", kind.__name__, key_expr, wrong.message)
                return
            callback(message)

        return self.session.declare_subscriber(key_expr, handler)

    def _authentic(
        self, payload: bytes, attachment: zenoh.ZBytes | None
    ) -> signatures.Stamp | tuple[()] | None:
        """The stamp of a publication the resource signed, for a client that logs in (or
        knows the resource's key); () for what comes to one without any (a resource
        without accounts: it takes what comes); None for what it does not take."""
        key = self.logged_in.publication_key if self.logged_in is not None else self.trusted_key
        if key is None:
            return () if self._credentials is None else None
        signed = attachment.to_bytes() if attachment is not None else None
        return signatures.verified_stamp(key, payload, signed)

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers.clear()


def _answers(arrived: queue.Queue[zenoh.Reply | None], deadline: float) -> list[bytes]:
    """The answers to a query until it is done (None), or until SECOND_ANSWER_S after the
    first one: a party that holds the query without answering delays no answer long."""
    answers: list[bytes] = []
    while (left := deadline - time.monotonic()) > 0:
        try:
            reply = arrived.get(timeout=left)
        except queue.Empty:
            break
        if reply is None:
            break
        if reply.ok is not None:
            answers.append(bytes(reply.ok.payload.to_bytes()))
            deadline = min(deadline, time.monotonic() + SECOND_ANSWER_S)
    return answers


def _unauthenticated(reply: bytes) -> bool:
    if b"unauthenticated" not in reply:  # most replies, some of them large: not parsed twice
        return False
    try:
        data = read_json(reply, "the reply", MAX_REPLY_BYTES)
    except JsonRefused:
        return False
    return isinstance(data, dict) and data.get("error", {}).get("code") == "unauthenticated"
