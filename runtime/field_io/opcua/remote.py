"""One remote OPC UA server as remote I/O: the resource's client of it (asyncua), on the I/O
thread.

The server delivers the device's inputs (`%I`) and takes its outputs (`%Q`), each mapped to
one node. What it delivered goes to the cycle as one immutable `Delivery` (one reference
assignment); the cycle never waits for it.

- **Connecting.** Each attempt uses a new `asyncua.Client` (its own reconnection proved
  unreliable). With security `sign` or `sign_encrypt` the client asks the server for its
  Basic256Sha256 endpoint and certificate, and shows its own certificate: made once in the
  `pki` folder (`client-certificate.der`, `client-private-key.pem`, owner-only). A server
  that checks its clients lets it in once someone trusted that certificate there. A user
  logs in with the password in `password_file`, read at each attempt: a regular file,
  owner-only (0600 or stricter), at most 1 KiB, one trailing newline ignored.
- **Inputs.** `subscribe`: one subscription publishing every `period_ms`, a monitored item
  per input sampled every `period_ms`; every data change makes a new delivery of all inputs.
  Right after connecting one Read of all inputs makes the first delivery complete.
  `read`: one Read of all inputs every `period_ms`. A value with a Bad status, or one the
  variable cannot hold, gives that input its safe value; `last_error` names the node.
- **Outputs.** Every period one Write of the outputs whose value changed since the server
  took it (all of them after a reconnect); `sent` holds what the server took. A value it
  refused (a Bad status: `last_error` names the node) goes again when it changes or after
  a reconnect.
- **Lost.** No answer within `timeout_ms`, the connection refused, closed or broken, the
  client's health check failing (asyncua's supervisor reads the server's state every
  `timeout_ms` and waits `timeout_ms` for it: a frozen server is noticed within about twice
  `timeout_ms` when subscribed, within `timeout_ms` when polled), or the subscription
  ending: the inputs take their safe values marked bad at once, the client is closed
  (bounded by `timeout_ms`), and a new one tries again after `period_ms`, then twice as
  long each time up to 2 s, until the server answers. Each failed attempt counts in
  `failures`. (A subscription the server dropped while the connection stays up is made
  again by asyncua itself.)
- **Counted.** `requests` counts every service request the client completed or failed
  (Read, Write, Publish, the health check's Reads, and those that open and close the
  session and the subscription); `round_trip_ms` is the time of the last Read or Write
  answered.

Nothing is logged while it runs (asyncua's client logger is silenced): what goes wrong is
in `state` and `last_error`, which the driver turns into events.
"""

from __future__ import annotations

import asyncio
import contextlib
import datetime
import logging
import math
import os
import socket
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

from asyncua import ua
from asyncua.client.client import Client
from asyncua.common.subscription import (
    DataChangeEvent,
    DataChangeNotif,
    StatusChangeEvent,
    Subscription,
)
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from asyncua.observer import Observer
from asyncua.ua.attribute_ids import AttributeIds
from asyncua.ua.uaerrors import UaStatusCodeError
from cryptography.x509.oid import ExtendedKeyUsageOID

from runtime.contract.opcua import OpcuaDevice, OpcuaPoint
from runtime.contract.values import ValueRejected
from runtime.field_io.delivery import Delivery
from runtime.field_io.opcua.certificates import application_certificate
from runtime.field_io.opcua.types import from_opcua, to_opcua, variant_type

MAX_ITEMS = 1000  # monitored items per CreateMonitoredItems call
MAX_BACKOFF_S = 2.0  # between attempts to reach a lost server
MAX_PASSWORD_BYTES = 1024
SESSION_TIMEOUT_MS = 60_000  # a session left behind (a lost server) ends this soon after
CERTIFICATE = "client-certificate.der"
PRIVATE_KEY = "client-private-key.pem"
_MODES = {
    "sign": ua.MessageSecurityMode.Sign,
    "sign_encrypt": ua.MessageSecurityMode.SignAndEncrypt,
}
_USER_REFUSED = (
    "BadUserAccessDenied",
    "BadIdentityTokenInvalid",
    "BadIdentityTokenRejected",
    "BadUserSignatureInvalid",
)


class Refused(Exception):
    """What this host holds for the device cannot be used (its password file, the client's
    certificate)."""


class _Lost(Exception):
    """The server no longer answers as it should."""


class _Session:
    """One attempt's client, and how it ended."""

    def __init__(self, client: Client) -> None:
        self.client = client
        self.ended = False
        self.broken = asyncio.Event()  # set when it ended, from wherever that was noticed
        self.flush_pending = False
        self.notified: asyncio.Task[None] | None = None  # takes the subscription's changes


class RemoteServer:
    """One remote server of the device, as the driver sees it (as `DevicePoller` on Modbus):
    `state` connecting | connected | lost, `delivery` (the inputs), `sent` (the outputs the
    server took), `last_error`, `requests`, `failures`, `round_trip_ms`; `run()` on the I/O
    thread until cancelled. The cycle thread only reads them: `delivery` is written before
    `state`, so a state read first comes with its delivery."""

    def __init__(
        self, device: OpcuaDevice, outputs: Callable[[], dict[str, Any]], pki: Path
    ) -> None:
        # a lost server would log failed requests and attempts: what goes wrong is reported
        # as events and in the status instead
        logging.getLogger("asyncua.client").setLevel(logging.CRITICAL)
        self.device = device
        self._outputs = outputs  # the output image of the last cycle (replaced, never changed)
        self._pki = pki
        self._inputs = [p for p in device.points if p.is_input]
        self._writes = [p for p in device.points if not p.is_input]
        self._nodes: dict[str, ua.NodeId] = {}  # by variable, the node ids that parse
        self._unusable: dict[str, str] = {}  # by variable, why its point cannot be used
        for point in device.points:
            try:
                self._nodes[point.variable] = ua.NodeId.from_string(point.node)
            except Exception as exc:
                self._unusable[point.variable] = f"node id '{point.node}': {exc}"
        for point in self._writes:
            if variant_type(point.type) is None:
                self._unusable[point.variable] = f"{point.node}: type {point.type} is not carried"
        self._safe = {p.variable: p.input_safe_value for p in self._inputs}
        # until the server first answers, the inputs hold their safe values, marked bad
        self.delivery = Delivery(1, dict(self._safe), False)
        self.state = "connecting"
        self.last_error: str | None = None
        self.requests = 0
        self.failures = 0
        self.round_trip_ms = 0.0
        self.sent: dict[str, Any] = {}  # output values the server has taken
        self._values: dict[str, Any] = dict(self._safe)  # the inputs now (I/O thread)
        self._errors: dict[str, str] = {}  # by variable, what is wrong with its node now
        self._refused: dict[str, Any] = {}  # output values the server refused (not sent again)
        self._session: _Session | None = None
        self._certificate: tuple[Path, Path] | None = None
        self._uri = f"urn:padt:{socket.gethostname()}:client"

    async def run(self) -> None:
        """Connect, exchange, and connect again when lost, until cancelled."""
        period = self.device.period_ms / 1000
        backoff = min(period, MAX_BACKOFF_S)
        try:
            while True:
                try:
                    session = await self._connect()
                    backoff = min(period, MAX_BACKOFF_S)
                    await self._exchange(session)
                except Exception as exc:  # the connection, the server's refusals, and the rest
                    self._end(self._reason(exc))
                await self._close()
                await asyncio.sleep(backoff)
                backoff = min(backoff * 2, MAX_BACKOFF_S)
        finally:
            await self._close()

    # ---- connecting
    async def _connect(self) -> _Session:
        device, timeout = self.device, self.device.timeout_ms / 1000
        password = await asyncio.to_thread(read_password, device) if device.user else None
        client = Client(device.endpoint, timeout=timeout, watchdog_intervall=timeout)
        client.application_uri = self._uri
        client.name = client.description = "padt runtime"
        client.session_timeout = SESSION_TIMEOUT_MS
        client.uaclient.observer = _Meter(self)
        session = _Session(client)
        self._session = session

        async def connection_lost(exc: Exception) -> None:
            self._lose(session, self._reason(exc))

        client.connection_lost_callback = connection_lost
        if password is not None:
            client.set_user(device.user)
            client.set_password(password)
        if device.security != "none":
            if self._certificate is None:
                try:
                    self._certificate = await asyncio.to_thread(
                        client_certificate, self._pki, self._uri, socket.gethostname()
                    )
                except (OSError, ValueError) as exc:
                    raise Refused(f"the client certificate in {self._pki}: {exc}") from None
            certificate, key = self._certificate
            await asyncio.wait_for(
                client.set_security(
                    SecurityPolicyBasic256Sha256, certificate, key, mode=_MODES[device.security]
                ),
                timeout,
            )
        await asyncio.wait_for(client.connect(), timeout)
        self.sent, self._refused = {}, {}  # everything goes again after a reconnect
        self._errors = dict(self._unusable)
        await self._read(session)  # the first delivery is complete
        if device.mode == "subscribe" and self._inputs:
            await self._subscribe(session)
        if not session.ended:
            self.state = "connected"
        return session

    async def _subscribe(self, session: _Session) -> None:
        period = float(self.device.period_ms)
        keep_alive = max(1, (self.device.timeout_ms // 2) // self.device.period_ms)
        params = ua.CreateSubscriptionParameters(
            RequestedPublishingInterval=period,
            RequestedLifetimeCount=max(10 * keep_alive, math.ceil(30_000 / period)),
            RequestedMaxKeepAliveCount=keep_alive,
            MaxNotificationsPerPublish=0,
            PublishingEnabled=True,
            Priority=0,
        )
        # no handler: the changes come through the subscription's queue (unbounded: it is
        # emptied on this loop right after each Publish), taken by one task in order
        subscription = await session.client.create_subscription(params, None, queue_maxsize=0)
        session.notified = asyncio.create_task(self._take_changes(session, subscription))
        items = [
            ua.MonitoredItemCreateRequest(
                ItemToMonitor=ua.ReadValueId(
                    NodeId=self._nodes[p.variable], AttributeId=AttributeIds.Value
                ),
                MonitoringMode=ua.MonitoringMode.Reporting,
                RequestedParameters=ua.MonitoringParameters(
                    ClientHandle=handle + 1,  # 1 and up: each input's index, plus one
                    SamplingInterval=period,
                    QueueSize=1,
                    DiscardOldest=True,
                ),
            )
            for handle, p in enumerate(self._inputs)
            if p.variable in self._nodes
        ]
        for start in range(0, len(items), MAX_ITEMS):
            chunk = items[start : start + MAX_ITEMS]
            results = await _created(subscription, chunk, self.device.timeout_ms / 1000)
            for item, result in zip(chunk, results, strict=True):
                if isinstance(result, ua.StatusCode):
                    point = self._inputs[item.RequestedParameters.ClientHandle - 1]
                    self._take(point, None, result)
        self._deliver(session)

    # ---- exchanging
    async def _exchange(self, session: _Session) -> None:
        period = self.device.period_ms / 1000
        loop = asyncio.get_running_loop()
        while True:
            began = loop.time()
            if self.device.mode == "read":
                await self._read(session)
            await self._write(session)
            if session.ended:
                return
            try:
                remaining = max(0.0, period - (loop.time() - began))
                await asyncio.wait_for(session.broken.wait(), remaining)
                return
            except TimeoutError:
                pass

    async def _read(self, session: _Session) -> None:
        points = [p for p in self._inputs if p.variable in self._nodes]
        if not points:
            self._deliver(session)
            return
        params = ua.ReadParameters(
            NodesToRead=[
                ua.ReadValueId(NodeId=self._nodes[p.variable], AttributeId=AttributeIds.Value)
                for p in points
            ],
            TimestampsToReturn=ua.TimestampsToReturn.Neither,
        )
        timeout = self.device.timeout_ms / 1000
        results = await asyncio.wait_for(session.client.uaclient.read(params), timeout)
        if len(results) != len(points):
            raise _Lost(f"{len(results)} values read for {len(points)} nodes")
        for point, result in zip(points, results, strict=True):
            value = result.Value.Value if result.Value is not None else None
            self._take(point, value, result.StatusCode)
        self._deliver(session)

    async def _write(self, session: _Session) -> None:
        outputs = self._outputs()
        wanted: list[tuple[OpcuaPoint, Any]] = []
        for point in self._writes:
            name = point.variable
            if name not in outputs or name in self._unusable:
                continue
            value = outputs[name]
            if name in self.sent and self.sent[name] == value:
                continue
            if name in self._refused and self._refused[name] == value:
                continue
            wanted.append((point, value))
        if not wanted:
            return
        items: list[ua.WriteValue] = []
        taken: list[tuple[OpcuaPoint, Any]] = []
        for point, value in wanted:
            kind = variant_type(point.type)
            assert kind is not None  # the others are unusable
            try:
                variant = ua.Variant(to_opcua(point.type, value), kind)
            except Exception as exc:
                self._refused[point.variable] = value
                self._errors[point.variable] = f"{point.node}: {value!r}: {exc}"
                continue
            items.append(
                ua.WriteValue(
                    NodeId=self._nodes[point.variable],
                    AttributeId=AttributeIds.Value,
                    Value=ua.DataValue(variant),
                )
            )
            taken.append((point, value))
        if items:
            params = ua.WriteParameters(NodesToWrite=items)
            timeout = self.device.timeout_ms / 1000
            results = await asyncio.wait_for(session.client.uaclient.write(params), timeout)
            if len(results) != len(items):
                raise _Lost(f"{len(results)} results for writing {len(items)} nodes")
            for (point, value), status in zip(taken, results, strict=True):
                if status.is_good():
                    self.sent[point.variable] = value
                    self._refused.pop(point.variable, None)
                    self._errors.pop(point.variable, None)
                else:
                    self._refused[point.variable] = value
                    self._errors[point.variable] = f"{point.node}: write refused: {status.name}"
        if not session.ended:
            self.last_error = self._error()

    # ---- inputs in
    def _take(self, point: OpcuaPoint, value: Any, status: ua.StatusCode | None) -> None:
        """One input's value as read or notified: its safe value when it is not usable."""
        name = point.variable
        if status is not None and status.is_bad():
            self._values[name] = self._safe[name]
            self._errors[name] = f"{point.node}: {status.name}"
            return
        try:
            self._values[name] = from_opcua(point.type, value)
        except (ValueRejected, TypeError, ValueError, OverflowError) as exc:
            self._values[name] = self._safe[name]
            self._errors[name] = f"{point.node}: {exc}"
            return
        self._errors.pop(name, None)

    def _deliver(self, session: _Session) -> None:
        session.flush_pending = False
        if session.ended or session is not self._session:
            return
        self.delivery = Delivery(self.delivery.seq + 1, dict(self._values), True)
        self.last_error = self._error()

    async def _take_changes(self, session: _Session, subscription: Subscription) -> None:
        """The data changes and status changes of the session's subscription, until it ends
        (or the session's close cancels this)."""
        try:
            async for event in subscription:
                if session.ended:
                    return
                if isinstance(event, DataChangeEvent):
                    self._changed(session, event.data)
                elif isinstance(event, StatusChangeEvent):
                    status = event.notification.Status
                    if not status.is_good():
                        self._lose(session, f"the subscription ended: {status.name}")
        except Exception as exc:  # never expected: the server is taken as lost
            self._lose(session, self._reason(exc))

    def _changed(self, session: _Session, data: DataChangeNotif) -> None:
        handle = data.monitored_item.ClientHandle - 1  # the input's index
        if not 0 <= handle < len(self._inputs):
            return
        found = data.monitored_item.Value
        value = found.Value.Value if found is not None and found.Value is not None else None
        self._take(self._inputs[handle], value, found.StatusCode if found is not None else None)
        # one delivery for all changes of one Publish: they are all in the queue, and taken
        # without a pause before this runs
        if not session.flush_pending:
            session.flush_pending = True
            asyncio.get_running_loop().call_soon(self._deliver, session)

    def _error(self) -> str | None:
        if not self._errors:
            return None
        first = min(self._errors)
        more = len(self._errors) - 1
        return self._errors[first] + (f" (and {more} more)" if more else "")

    # ---- lost
    def _reason(self, exc: BaseException) -> str:
        """What an exception of the client says went wrong, for `last_error`."""
        if isinstance(exc, Refused | _Lost):
            return str(exc)
        if isinstance(exc, TimeoutError):
            return f"no answer within {self.device.timeout_ms} ms"
        if isinstance(exc, UaStatusCodeError):
            code = ua.StatusCode(exc.code).name
            if code in _USER_REFUSED:
                return f"the server refused user '{self.device.user}': {exc}"
            if code.startswith("BadCertificate") or code == "BadSecurityChecksFailed":
                where = self._pki / CERTIFICATE
                return f"the server refused the client's certificate ({where}): {exc}"
            return f"the server refused: {exc}"
        if isinstance(exc, OSError):  # ConnectionError among them
            what = "connection lost" if self.state == "connected" else "no connection"
            return f"{what}: {exc}" if str(exc) else what
        return str(exc) or type(exc).__name__

    def _lose(self, session: _Session, reason: str) -> None:
        """The server of `session` is lost (noticed by the client's tasks)."""
        if not session.ended and session is self._session:
            self._end(reason)

    def _end(self, reason: str) -> None:
        session = self._session
        if session is not None:
            if session.ended:
                return
            session.ended = True
            session.broken.set()
        self.failures += 1
        self.last_error = reason
        self.sent, self._refused, self._errors = {}, {}, {}
        self._values = dict(self._safe)
        if self.delivery.good:
            self.delivery = Delivery(self.delivery.seq + 1, dict(self._safe), False)
        self.state = "lost"  # after the delivery: the cycle reads them the other way round

    async def _close(self) -> None:
        session, self._session = self._session, None
        if session is None:
            return
        session.ended = True
        session.broken.set()
        client = session.client
        try:
            await asyncio.wait_for(client.disconnect(), self.device.timeout_ms / 1000)
        except Exception:  # lost already, or no answer: the socket goes anyway
            pass
        finally:
            with contextlib.suppress(Exception):
                client.disconnect_socket()
            if session.notified is not None:
                session.notified.cancel()
                await asyncio.wait({session.notified})  # raises nothing of the task's


class _Meter(Observer):
    """Counts the client's requests, and times its Reads and Writes."""

    def __init__(self, remote: RemoteServer) -> None:
        self._remote = remote

    def on_request(self, request_type: str, duration: float, error: BaseException | None) -> None:
        self._remote.requests += 1
        if error is None and request_type in ("ReadRequest", "WriteRequest"):
            self._remote.round_trip_ms = duration * 1000


async def _created(
    subscription: Subscription, items: list[ua.MonitoredItemCreateRequest], timeout: float
) -> list[int | ua.StatusCode]:
    return await asyncio.wait_for(subscription.create_monitored_items(items), timeout)


def read_password(device: OpcuaDevice) -> str:
    """The password of the device's user from its password file (Refused: not usable)."""
    if not device.password_file:
        raise Refused(f"user '{device.user}' has no password file")
    path = device.password_file
    try:
        # non-blocking: a FIFO in its place must not hang the attempt; it is refused below
        handle = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as exc:
        raise Refused(f"password file {path}: {exc.strerror or exc}") from None
    try:
        found = os.fstat(handle)
        if not stat.S_ISREG(found.st_mode):
            raise Refused(f"password file {path} is not a regular file")
        if stat.S_IMODE(found.st_mode) & ~0o600:
            raise Refused(
                f"password file {path} has mode {stat.S_IMODE(found.st_mode):04o}: "
                "it must be readable by its owner only (0600)"
            )
        if found.st_size > MAX_PASSWORD_BYTES:
            raise Refused(f"password file {path} is larger than {MAX_PASSWORD_BYTES} bytes")
        data = os.read(handle, MAX_PASSWORD_BYTES + 1)
    finally:
        os.close(handle)
    if len(data) > MAX_PASSWORD_BYTES:
        raise Refused(f"password file {path} is larger than {MAX_PASSWORD_BYTES} bytes")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise Refused(f"password file {path} is not UTF-8 text") from None
    if text.endswith("\r\n"):
        return text[:-2]
    return text[:-1] if text.endswith("\n") else text


def client_certificate(pki: Path, uri: str, host: str) -> tuple[Path, Path]:
    """The client's certificate (DER) and private key (PEM, owner-only) in `pki`, made
    there when missing, expiring within a day, not of `uri`, or not of each other."""
    made = application_certificate(
        pki, f"padt runtime client@{host}", uri, (host,),
        datetime.datetime.now(datetime.UTC), (CERTIFICATE, PRIVATE_KEY),
        (ExtendedKeyUsageOID.CLIENT_AUTH,),
    )  # fmt: skip
    return made.certificate, made.private_key
