"""The resource's OPC UA server (asyncua), on the I/O thread: the exposed variables as nodes
(`address_space.py`), their values from the cycle's snapshots, client writes as online
writes, and who may do what.

- **Who gets in.** Only over Basic256Sha256, signed or signed and encrypted, with a client
  certificate the trust list admits (`certificates.py`), and with a user name and password
  of one of the resource's accounts (anonymous only where the configuration allows it, and
  then to read). asyncua also opens a channel without security for discovery; a session
  on it is refused here (`_Accounts.get_user`), else a password would cross the network
  in clear.
- **Values.** The cycle thread hands over one snapshot of the exposed variables when this
  side asks for one (`after_cycle`), at most every cycle and at least MIN_SAMPLING_MS
  apart; only the values that changed are written to their nodes, with the snapshot's
  time as their source timestamp. Subscriptions are served from those writes.
- **Writes.** asyncua's Write service is replaced (`_write`): each value is checked here
  (the node exposed writable, the user of level operator or above, the value of the
  variable's type and range), then carried out on the cycle thread as an online write
  with its event naming the user (`before_cycle`); the client gets the outcome as its
  status.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import queue
import socket
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, cast

from asyncua import ua
from asyncua.common.callback import CallbackType, ServerItemCallback
from asyncua.common.connection import TransportLimits
from asyncua.common.utils import Buffer, NotEnoughData
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server import binary_server_asyncio
from asyncua.server.binary_server_asyncio import OPCUAProtocol
from asyncua.server.monitored_item_service import MonitoredItemValues
from asyncua.server.server import Server
from asyncua.server.user_managers import UserManager
from asyncua.ua.attribute_ids import AttributeIds
from asyncua.ua.object_ids import ObjectIds
from asyncua.ua.status_codes import StatusCodes
from asyncua.ua.ua_binary import header_from_binary, uatcp_to_binary
from cryptography import x509

from runtime.code.instances import BoundVariable
from runtime.collector import COLLECTOR
from runtime.contract.artifact import UserAccount
from runtime.contract.opcua import OpcuaServer
from runtime.contract.refusal import Refusal
from runtime.contract.scram import parse_verifier, password_matches
from runtime.contract.values import ValueRejected
from runtime.field_io.opcua.address_space import Plan, PlannedNode, plan
from runtime.field_io.opcua.certificates import (
    ApplicationCertificate,
    TrustList,
    application_certificate,
    thumbprint,
)
from runtime.field_io.opcua.types import (
    data_type,
    dimensions,
    from_opcua,
    to_opcua,
    variant_type,
)
from runtime.memory import Memory

log = logging.getLogger(__name__)
# asyncua tells every request at INFO: what goes wrong is reported as events instead
logging.getLogger("asyncua").setLevel(logging.WARNING)

MIN_SAMPLING_MS = 10  # the fastest the served values follow the cycle
IDLE_SAMPLING_MS = 100  # how they follow it while no client subscribes
WRITE_TIMEOUT_S = 2.0  # a write the cycle did not take by then is answered BadTimeout
MAX_PENDING_WRITES = 1000
# What a hostile client may make the server hold (tests/runtime/test_opcua_hostile.py).
# A connection costs a file descriptor and some 10 KB; asyncua takes 1,000 of them.
MAX_CONNECTIONS = 64
CHUNK_BYTES = 65535  # the largest chunk, either way (asyncua's)
# The largest request. A resource takes no array writes, so a request only names nodes:
# 4 MiB names some 50,000 at once. asyncua holds a message's chunks until its last one
# comes, up to 100 MiB by default, each connection.
MAX_MESSAGE_BYTES = 4 << 20
# What all the connections together hold of messages whose last chunk has not come.
UNFINISHED_BYTES = 16 << 20
NODES_PER_BATCH = 500  # nodes added between two turns of the I/O loop
WRITERS = ("operator", "read-write", "administrator")  # the levels that may write
_READ = ua.AccessLevel.CurrentRead.mask
_READ_WRITE = _READ | ua.AccessLevel.CurrentWrite.mask
# what a refused online write answers, by the refusal's code
_REFUSED = {
    "bad_value": StatusCodes.BadOutOfRange,
    "constant": StatusCodes.BadNotWritable,
    "safety_operation": StatusCodes.BadUserAccessDenied,
    "read_only": StatusCodes.BadNotWritable,
}


_INTERNAL = User(role=UserRole.Admin)  # who asyncua's own writes come from
# asyncua types a header's message and chunk type as its classes MessageType and ChunkType,
# whose attributes are in fact the bytes on the wire
_INTERMEDIATE = cast(ua.ChunkType, ua.ChunkType.Intermediate)
_ERROR = cast(ua.MessageType, ua.MessageType.Error)


@dataclass(frozen=True)
class Snapshot:
    seq: int  # counted by the cycle thread
    at: ua.DateTime  # when the cycle ended
    values: list[Any]  # of `variables`, in their order
    variables: tuple[PlannedNode, ...]


@dataclass
class PendingWrite:
    node: PlannedNode
    value: Any
    user: str
    done: asyncio.Future[tuple[ua.StatusCode, int]]  # with the snapshot that shows it
    loop: asyncio.AbstractEventLoop


@dataclass
class ServerCounts:
    requests: int = 0  # Read and Write service calls
    refused: int = 0  # logins, certificates and writes refused
    writes: int = 0  # values written by clients
    sessions: int = 0  # sessions activated


@dataclass(frozen=True)
class Notice:
    """What the cycle thread records as an event."""

    message: str
    long_term: bool
    details: dict[str, Any] = field(default_factory=dict)


class ResourceServer:
    def __init__(
        self,
        config: OpcuaServer,
        resource: str,
        folder: Path,
        port: int,
        accounts: Callable[[], tuple[UserAccount, ...]],
    ) -> None:
        self.config, self.resource, self.folder = config, resource, folder
        self.host, self.requested_port = config.host, port
        self.port = 0  # where it listens; 0 while it does not
        self.error: str | None = None
        self.certificate: ApplicationCertificate | None = None
        self.counts = ServerCounts()
        self.notices: queue.SimpleQueue[Notice] = queue.SimpleQueue()
        self.writes: queue.SimpleQueue[PendingWrite] = queue.SimpleQueue()
        self._pending = 0  # writes queued and not yet taken (only the I/O thread's)
        self._accounts = accounts
        self._server: Server | None = None
        self._internal_write: Callable[..., Awaitable[list[ua.StatusCode]]] | None = None
        self._namespace = 0
        self._plan = Plan((), ())
        self._built_plan: Plan | None = None  # the plan whose nodes are there (I/O thread)
        self._by_node: dict[ua.NodeId, PlannedNode] = {}
        self._built: dict[str, tuple[str, bool]] = {}  # path -> (type, writable) of its node
        # the cycle thread's side of the hand-over
        self._read: Callable[[], list[Any]] = list
        self._read_plan: Plan | None = None
        self.wanted = False  # set here, taken by the cycle thread
        self.snapshot: Snapshot | None = None
        self.taken = 0  # snapshots taken (cycle thread)
        self.shown_seq = 0  # the last one the nodes show (I/O thread)
        self._prompt = False  # a write waits to show: wake the I/O thread (cycle thread)
        self._wake = asyncio.Event()
        self._shown: list[Any] = []  # the values the nodes show, in the plan's order
        self._tasks: list[asyncio.Task[None]] = []
        self._plan_changed = asyncio.Event()
        # the fastest sampling interval asked for, by subscription (ms)
        self._sampling: dict[int, float] = {}

    @property
    def endpoint(self) -> str:
        return f"opc.tcp://{self.host}:{self.port or self.requested_port}"

    @property
    def uri(self) -> str:
        return f"urn:padt:{self.resource}"

    # ---- the cycle thread
    def rebind(self, bound: list[BoundVariable], memory: Memory) -> None:
        """The variables were bound anew (`memory` holds their values): the nodes follow
        (on the I/O thread)."""
        self._plan = plan(bound, self.config)
        nodes = [node.variable for node in self._plan.variables if node.variable is not None]
        self._read = memory.reader(nodes)
        self._read_plan = self._plan
        self.snapshot = None
        loop = self._loop
        if loop is not None:
            loop.call_soon_threadsafe(self._plan_changed.set)

    def after_cycle(self) -> None:
        if not self.wanted or self._read_plan is None:
            return
        self.wanted = False
        self.taken += 1
        values = self._read()
        self.snapshot = Snapshot(
            self.taken, ua.DateTime.now(UTC), values, self._read_plan.variables
        )
        if self._prompt:  # clients wait for their writes to show: the I/O thread, now
            self._prompt = False
            loop = self._loop
            if loop is not None:
                loop.call_soon_threadsafe(self._wake.set)

    def take_writes(self, write: Callable[[str, Any, str], None]) -> None:
        """The writes the clients made, as online writes (`write(path, value, user)`)."""
        while True:
            try:
                pending = self.writes.get_nowait()
            except queue.Empty:
                return
            variable = pending.node.variable
            assert variable is not None
            try:
                write(variable.path.path, pending.value, pending.user)
                status = _status(StatusCodes.Good)
                # the snapshot after this cycle shows it: taken at once, not when sampled
                self.wanted = self._prompt = True
            except Refusal as refused:
                code = _REFUSED.get(refused.code, StatusCodes.BadNotWritable)
                status = _status(code)
            pending.loop.call_soon_threadsafe(_settle, pending.done, (status, self.taken + 1))

    def shown(self) -> list[tuple[str, str, bool, Any, str]]:
        """Each variable node: its path, type, whether it is writable, the value it shows
        (None before the first snapshot) and its node id."""
        variables, shown = self._plan.variables, self._shown
        if len(shown) != len(variables):  # a new plan, its nodes not built yet
            shown = [None] * len(variables)
        return [
            (node.path, node.variable.path.type, node.writable, value,
             self._node_id(node.path).to_string())
            for node, value in zip(variables, shown, strict=True)
            if node.variable is not None
        ]  # fmt: skip

    # ---- the I/O thread
    @property
    def _loop(self) -> asyncio.AbstractEventLoop | None:
        return self._tasks[0].get_loop() if self._tasks else None

    async def start(self) -> None:
        try:
            # asyncua's start makes some 450,000 objects: no collection walks them while
            # it does, and they are frozen after it (runtime/collector.py)
            with COLLECTOR.held_back(arrival=False):
                self._server = await self._listen()
        except Exception as exc:  # the port taken, no such address: never the runtime's end
            self.error = f"cannot listen on {self.endpoint}: {exc}"
            self.notices.put(Notice(f"OPC UA server: {self.error}", long_term=True))
            return
        self._tasks = [asyncio.create_task(self._follow())]

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks = []
        if self._server is not None:
            try:
                await self._server.stop()
            except Exception:  # stopping: what is left goes with the server
                log.exception("OPC UA server stop")
            self._server = None
        self.port = 0

    async def _listen(self) -> Server:
        accounts = _Accounts(self)
        server = Server(user_manager=accounts)
        await server.init()
        server.limits = TransportLimits(
            max_recv_buffer=CHUNK_BYTES,
            max_send_buffer=CHUNK_BYTES,
            max_chunk_count=-(-MAX_MESSAGE_BYTES // CHUNK_BYTES),
            max_message_size=MAX_MESSAGE_BYTES,
        )
        server.iserver.max_connections = MAX_CONNECTIONS
        # what asyncua's BinaryServer makes a connection of, by this name
        binary_server_asyncio.OPCUAProtocol = _Connection  # type: ignore[misc]
        server.allow_remote_admin(False)
        server.set_server_name(f"padt {self.resource}")
        await server.set_application_uri(self.uri)
        certificate = await asyncio.to_thread(
            application_certificate,
            self.folder,
            f"padt {self.resource}",
            self.uri,
            _hosts(self.host),
            datetime.now(UTC),
        )
        self.certificate = certificate
        await server.load_certificate(str(certificate.certificate))
        await server.load_private_key(str(certificate.private_key))
        trust = TrustList(self.folder / "pki", self.config.trust_unknown_clients)
        server.set_certificate_validator(_validator(self, trust))
        server.set_security_policy(
            [
                ua.SecurityPolicyType.Basic256Sha256_Sign,
                ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
            ]
        )
        tokens: list[type] = [ua.UserNameIdentityToken]
        if self.config.anonymous:
            tokens.append(ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)
        port = self.requested_port or _free_port(self.host)
        server.set_endpoint(f"opc.tcp://{self.host}:{port}/")
        # the variables' namespace, after the server's own (1): index 2
        self._namespace = await server.register_namespace(f"{self.uri}:variables")
        iserver = server.iserver
        self._internal_write = iserver.attribute_service.write
        iserver.attribute_service.write = self._write  # type: ignore[method-assign]
        server.subscribe_server_callback(CallbackType.PreRead, self._counted)
        server.subscribe_server_callback(CallbackType.PostRead, self._user_access)
        server.subscribe_server_callback(CallbackType.ItemSubscriptionCreated, self._sampled)
        _share_monitored_values()
        await self._add_resource_object(server)
        await server.start()
        self.port = port
        if certificate.created:
            self.notices.put(
                Notice(
                    f"OPC UA server certificate made: SHA-1 {certificate.thumbprint}",
                    long_term=True,
                    details={"thumbprint": certificate.thumbprint},
                )
            )
        self.notices.put(
            Notice(
                f"OPC UA server listening on {self.endpoint} (certificate SHA-1 "
                f"{certificate.thumbprint})",
                long_term=False,
            )
        )
        return server

    async def _add_resource_object(self, server: Server) -> None:
        item = _object_item(
            self._node_id(""), _standard(ObjectIds.ObjectsFolder), self.resource, ""
        )
        item.ReferenceTypeId = _standard(ObjectIds.Organizes)
        server.iserver.node_mgt_service.add_nodes([item])

    def _node_id(self, path: str) -> ua.NodeId:
        text = f"{self.resource}.{path}" if path else self.resource
        return ua.NodeId(ua.String(text), ua.Int16(self._namespace))

    async def _follow(self) -> None:
        """Keep the nodes as the plan says, and their values as the snapshots say."""
        while True:
            try:
                await self._follow_once()
            except asyncio.CancelledError:
                raise
            except Exception:  # a defect here must not end the serving of values
                log.exception("OPC UA server: following the cycle")
                await asyncio.sleep(IDLE_SAMPLING_MS / 1000)

    async def _follow_once(self) -> None:
        if self._plan_changed.is_set() or self._built_plan is None:
            self._plan_changed.clear()
            planned = self._plan
            await self._build(planned)
            self._built_plan = planned
        self.wanted = True
        with contextlib.suppress(TimeoutError):  # woken early for a write to show
            await asyncio.wait_for(self._wake.wait(), self._sampling_ms() / 1000)
        self._wake.clear()
        snapshot = self.snapshot
        # only a snapshot of the variables whose nodes are built (a rebind may have come
        # meanwhile: its nodes are built first, at the next turn)
        built = self._built_plan
        if snapshot is not None and built is not None and snapshot.variables is built.variables:
            self.snapshot = None
            await self._show(snapshot)
            self.shown_seq = snapshot.seq

    async def _build(self, planned: Plan) -> None:
        """The nodes of `planned`: those of variables gone (or changed in type or access)
        deleted, the new ones added; a node that stays keeps its subscriptions."""
        assert self._server is not None
        iserver = self._server.iserver
        wanted = {node.path: node for node in (*planned.objects, *planned.variables)}
        keep = {path for path, node in wanted.items() if self._built.get(path) == _kind(node)}
        gone = [path for path in self._built if path not in keep]
        for n in range(0, len(gone), NODES_PER_BATCH):
            items = [
                ua.DeleteNodesItem(self._node_id(path), True)
                for path in gone[n : n + NODES_PER_BATCH]
            ]
            iserver.node_mgt_service.delete_nodes(ua.DeleteNodesParameters(items))
            await asyncio.sleep(0)
        built = {path: self._built[path] for path in keep}
        new = [node for node in (*planned.objects, *planned.variables) if node.path not in keep]
        for n in range(0, len(new), NODES_PER_BATCH):
            batch = new[n : n + NODES_PER_BATCH]
            with COLLECTOR.held_back(arrival=False):  # the nodes out of the collector's sight
                iserver.node_mgt_service.add_nodes([self._item(node) for node in batch])
            built.update((node.path, _kind(node)) for node in batch)
            await asyncio.sleep(0)
        self._built = built
        self._by_node = {self._node_id(node.path): node for node in planned.variables}
        self._shown = [None] * len(planned.variables)

    def _item(self, node: PlannedNode) -> ua.AddNodesItem:
        parent = self._node_id(node.parent)
        if node.variable is None:
            return _object_item(self._node_id(node.path), parent, node.name, node.description)
        kind = node.variable.path.type
        item = ua.AddNodesItem()
        item.RequestedNewNodeId = self._node_id(node.path)
        item.BrowseName = ua.QualifiedName(node.name, ua.UInt16(self._namespace))
        item.NodeClass = ua.NodeClass.Variable
        item.ParentNodeId = parent
        item.ReferenceTypeId = _standard(ObjectIds.HasComponent)
        item.TypeDefinition = _standard(ObjectIds.BaseDataVariableType)
        attrs = ua.VariableAttributes()
        attrs.DisplayName = ua.LocalizedText(node.name)
        attrs.Description = ua.LocalizedText(node.description)
        attrs.DataType = data_type(kind)
        lengths = dimensions(kind)
        attrs.ValueRank = len(lengths) if lengths else ua.ValueRank.Scalar
        if lengths:
            attrs.ArrayDimensions = [ua.UInt32(n) for n in lengths]
        # no value until the first snapshot (null, without a source timestamp), never a
        # made-up initial value
        attrs.Value = ua.Variant(None, ua.VariantType.Null)
        attrs.AccessLevel = _READ_WRITE if node.writable else _READ
        attrs.UserAccessLevel = _READ  # raised per user (`_user_access`)
        attrs.MinimumSamplingInterval = float(MIN_SAMPLING_MS)
        item.NodeAttributes = attrs
        return item

    async def _show(self, snapshot: Snapshot) -> None:
        """The values that changed since the last snapshot, written to their nodes."""
        assert self._server is not None
        aspace = self._server.iserver.aspace
        shown = self._shown
        for index, value in enumerate(snapshot.values):
            if value == shown[index] and type(value) is type(shown[index]):
                continue
            shown[index] = value
            node = snapshot.variables[index]
            variable = node.variable
            assert variable is not None
            kind = variable.path.type
            variant_kind = variant_type(kind)
            assert variant_kind is not None  # planned only with one
            data = ua.DataValue(
                ua.Variant(to_opcua(kind, value), variant_kind, _dimensions(kind, value)),
                SourceTimestamp=snapshot.at,
                ServerTimestamp=snapshot.at,
            )
            await aspace.write_attribute_value(self._node_id(node.path), AttributeIds.Value, data)
            if index % NODES_PER_BATCH == NODES_PER_BATCH - 1:
                await asyncio.sleep(0)

    # ---- asyncua's hooks (the I/O thread)
    async def _write(
        self, params: ua.WriteParameters, user: User = _INTERNAL
    ) -> list[ua.StatusCode]:
        # every session from the network has the role User (`login`); the others are the
        # server's own (its internal session writes as Admin)
        if user.role != UserRole.User:
            assert self._internal_write is not None
            return await self._internal_write(params, user)
        self.counts.requests += 1
        loop = asyncio.get_running_loop()
        results: list[ua.StatusCode | asyncio.Future[tuple[ua.StatusCode, int]]] = []
        for item in params.NodesToWrite:
            results.append(self._checked_write(item, user, loop))
        statuses = []
        showing = 0  # the snapshot that shows the values written
        for result in results:
            if isinstance(result, ua.StatusCode):
                statuses.append(result)
                continue
            try:
                status, seq = await asyncio.wait_for(asyncio.shield(result), WRITE_TIMEOUT_S)
            except TimeoutError:
                status, seq = _status(StatusCodes.BadTimeout), 0
            statuses.append(status)
            showing = max(showing, seq if status.is_good() else 0)
        # the answer after the nodes show what was written: a read that follows sees it
        deadline = loop.time() + WRITE_TIMEOUT_S
        while self.shown_seq < showing and loop.time() < deadline:
            await asyncio.sleep(0.002)
        for status in statuses:
            if status.is_good():
                self.counts.writes += 1
            else:
                self.counts.refused += 1
        return statuses

    def _checked_write(
        self, item: ua.WriteValue, user: User, loop: asyncio.AbstractEventLoop
    ) -> ua.StatusCode | asyncio.Future[tuple[ua.StatusCode, int]]:
        node = self._by_node.get(item.NodeId)
        if node is None or item.AttributeId != AttributeIds.Value or not node.writable:
            return _status(
                StatusCodes.BadNotWritable if node is not None else StatusCodes.BadUserAccessDenied
            )
        name = user.name
        if name is None or self._level(name) not in WRITERS:
            return _status(StatusCodes.BadUserAccessDenied)
        if item.IndexRange:
            return _status(StatusCodes.BadWriteNotSupported)
        variable = node.variable
        assert variable is not None
        given = item.Value.Value if item.Value is not None else None
        if given is None or given.VariantType != variant_type(variable.path.type):
            return _status(StatusCodes.BadTypeMismatch)
        try:
            value = from_opcua(variable.path.type, given.Value)
        except ValueRejected:
            return _status(StatusCodes.BadOutOfRange)
        if self._pending >= MAX_PENDING_WRITES:
            return _status(StatusCodes.BadTooManyOperations)
        done: asyncio.Future[tuple[ua.StatusCode, int]] = loop.create_future()
        self._pending += 1
        done.add_done_callback(self._taken)
        self.writes.put(PendingWrite(node, value, name, done, loop))
        return done

    def _taken(self, _: asyncio.Future[tuple[ua.StatusCode, int]]) -> None:
        self._pending -= 1

    def _counted(self, event: ServerItemCallback, _: Any) -> None:
        if event.is_external:  # not the server's own reads
            self.counts.requests += 1

    def _sampled(self, event: ServerItemCallback, _: Any) -> None:
        """Monitored items made: their subscription's fastest sampling interval."""
        params: ua.CreateMonitoredItemsParameters = event.request_params
        subscriptions = self._subscriptions()
        subscription = subscriptions.get(params.SubscriptionId)
        if subscription is None or not params.ItemsToCreate:
            return
        publishing = float(subscription.data.RevisedPublishingInterval)
        asked = [item.RequestedParameters.SamplingInterval for item in params.ItemsToCreate]
        # 0 or less: as fast as the server samples, or at the publishing interval
        fastest = min(ms if ms > 0 else publishing for ms in asked)
        self._sampling[params.SubscriptionId] = min(
            fastest, self._sampling.get(params.SubscriptionId, fastest)
        )
        COLLECTOR.settled()  # thousands of monitored items: no collection walks them

    def _sampling_ms(self) -> float:
        """How often a snapshot is taken: as fast as a subscription samples (at least
        every MIN_SAMPLING_MS, at most once a cycle), IDLE_SAMPLING_MS without one."""
        subscriptions = self._subscriptions()
        for gone in [key for key in self._sampling if key not in subscriptions]:
            del self._sampling[gone]
        if not self._sampling:
            return IDLE_SAMPLING_MS
        return max(MIN_SAMPLING_MS, min(self._sampling.values()))

    def _subscriptions(self) -> dict[int, Any]:
        if self._server is None:
            return {}
        return self._server.iserver.subscription_service.subscriptions

    def _user_access(self, event: ServerItemCallback, _: Any) -> None:
        """A writable node's UserAccessLevel, as read: writable for the users who may."""
        params: ua.ReadParameters = event.request_params
        results: list[ua.DataValue] = event.response_params
        user: User | None = event.user
        if user is None or user.name is None or self._level(user.name) not in WRITERS:
            return
        for index, item in enumerate(params.NodesToRead):
            if item.AttributeId != AttributeIds.UserAccessLevel:
                continue
            node = self._by_node.get(item.NodeId)
            if node is not None and node.writable:
                results[index] = ua.DataValue(ua.Variant(_READ_WRITE, ua.VariantType.Byte))

    def _level(self, name: str) -> str | None:
        for account in self._accounts():
            if account.name == name:
                return account.level
        return None

    def login(self, username: str | None, password: str | None) -> User | None:
        """The user of a session, or None: refused."""
        if username is None:
            if self.config.anonymous:
                self.counts.sessions += 1
                return User(role=UserRole.User, name=None)
            return None
        account = next((a for a in self._accounts() if a.name == username), None)
        verifier = parse_verifier(account.password_hash) if account is not None else None
        if account is None or verifier is None or not password_matches(password or "", verifier):
            self.counts.refused += 1
            self.notices.put(Notice(f"OPC UA login of '{username[:64]}' refused", long_term=True))
            return None
        self.counts.sessions += 1
        return User(role=UserRole.User, name=account.name)


class _Accounts(UserManager):
    """The resource's accounts, to asyncua."""

    def __init__(self, server: ResourceServer) -> None:
        self._server = server

    def get_user(
        self,
        iserver: Any,
        username: str | None = None,
        password: str | None = None,
        certificate: Any = None,
    ) -> User | None:
        if not certificate:  # a channel without security: no session at all (see above)
            return None
        return self._server.login(username, password)


class _Connection(OPCUAProtocol):
    """asyncua's connection, against hostile clients: what it does not take gets an
    ErrorMessage and the connection closed, never a traceback in the log; it holds no more
    than a chunk of what it has not yet parsed, and all connections together no more than
    UNFINISHED_BYTES of unfinished messages. (asyncua is pinned at the version this was
    read in.)"""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        if len(self.clients) >= self.iserver.max_connections:
            # those that never log in make room for a new one: else a client that opens
            # connections and says nothing shuts everyone out until they time out
            idle = next((c for c in self.clients if not _activated(c)), None)
            if idle is None:
                _refuse(transport, StatusCodes.BadTcpServerTooBusy, "too many connections")
                return
            _refuse(idle.transport, StatusCodes.BadTcpServerTooBusy, "too many connections")
            self.clients.remove(idle)
        super().connection_made(transport)

    def data_received(self, data: bytes) -> None:
        """The chunks that came, each queued with its own bytes. asyncua's own holds a
        chunk up to the 4 GB its header may announce (copying it whole at every read),
        and queues each chunk with a copy of all that followed it in the read: up to
        500 copies of up to 256 KiB."""
        if self.transport is None or self.transport.is_closing():
            return  # refused: what still comes is not read
        self._buffer += data
        start = 0
        while len(self._buffer) - start >= 8:
            size = int.from_bytes(self._buffer[start + 4 : start + 8], "little")
            if size > self.limits.max_recv_buffer:
                _refuse(self.transport, StatusCodes.BadTcpMessageTooLarge, "chunk too large")
                break
            if len(self._buffer) - start < size:
                break
            chunk = Buffer(self._buffer[start : start + size])
            start += size
            try:
                header = header_from_binary(chunk)
            except NotEnoughData:  # shorter than its header
                header = None
            if header is None or header.body_size < 0:
                _refuse(self.transport, StatusCodes.BadDecodingError, "chunk too short")
                break
            try:
                self.messages.put_nowait((header, chunk))
            except asyncio.QueueFull:  # faster than they are answered
                _refuse(self.transport, StatusCodes.BadTcpServerTooBusy, "too many requests")
                break
        refused = self.transport is None or self.transport.is_closing()
        self._buffer = b"" if refused else self._buffer[start:]

    def connection_lost(self, exc: BaseException | None) -> None:
        # the chunks of a message it had not finished go now: asyncua keeps a connection
        # until its cleanup, every 10 s, and with it those chunks (some 16 MiB for each
        # round of connections that fill UNFINISHED_BYTES and close)
        if self.processor is not None:
            self.processor._connection._drop_incoming_parts()
        super().connection_lost(exc)

    async def _process_one_msg(self, header: ua.Header, buf: Buffer) -> bool:
        if header.ChunkType == _INTERMEDIATE:
            held = sum(_unfinished(c) for c in self.clients)
            if held + header.body_size > UNFINISHED_BYTES:
                _refuse(self.transport, StatusCodes.BadRequestTooLarge, "too many chunks")
                return False
        try:
            return await super()._process_one_msg(header, buf)
        except Exception as exc:  # asyncua fails on what it cannot decode
            log.info("OPC UA connection from %s closed: %s", self.peer_name, type(exc).__name__)
            _refuse(self.transport, StatusCodes.BadDecodingError, "cannot decode")
            return False


def _activated(connection: OPCUAProtocol) -> bool:
    session = connection.processor.session if connection.processor is not None else None
    return session is not None and session.is_activated()


def _unfinished(connection: OPCUAProtocol) -> int:
    """The bytes of the chunks `connection` holds of a message whose last has not come."""
    if connection.processor is None:
        return 0
    return connection.processor._connection._incoming_size


def _refuse(transport: asyncio.BaseTransport | None, code: int, reason: str) -> None:
    """Tell the client why, and close its connection without waiting for it to read."""
    if transport is None or transport.is_closing():
        return
    error = ua.ErrorMessage(_status(code), ua.String(reason))
    assert isinstance(transport, asyncio.WriteTransport)
    transport.write(uatcp_to_binary(_ERROR, error))
    if transport.get_write_buffer_size():  # a client that does not read: not waited for
        transport.abort()
    else:
        transport.close()


def _validator(server: ResourceServer, trust: TrustList) -> Callable[..., Any]:
    async def validate(
        certificate: x509.Certificate, description: ua.ApplicationDescription
    ) -> None:
        if trust.admits(certificate):
            return
        server.counts.refused += 1
        print_ = thumbprint(certificate)
        server.notices.put(
            Notice(
                f"OPC UA client certificate {print_} ({description.ApplicationUri}) refused: "
                f"not trusted; to trust it, move it from {trust.rejected} to {trust.trusted}",
                long_term=True,
                details={"thumbprint": print_},
            )
        )
        raise ua.uaerrors.BadSecurityChecksFailed

    return validate


def _object_item(
    node_id: ua.NodeId, parent: ua.NodeId, name: str, description: str
) -> ua.AddNodesItem:
    item = ua.AddNodesItem()
    item.RequestedNewNodeId = node_id
    item.BrowseName = ua.QualifiedName(name, node_id.NamespaceIndex)
    item.NodeClass = ua.NodeClass.Object
    item.ParentNodeId = parent
    item.ReferenceTypeId = _standard(ObjectIds.HasComponent)
    item.TypeDefinition = _standard(ObjectIds.BaseObjectType)
    attrs = ua.ObjectAttributes()
    attrs.DisplayName = ua.LocalizedText(name)
    attrs.Description = ua.LocalizedText(description)
    item.NodeAttributes = attrs
    return item


def _kind(node: PlannedNode) -> tuple[str, bool]:
    return (node.variable.path.type if node.variable is not None else "", node.writable)


def _dimensions(kind: str, value: Any) -> list[ua.Int32] | None:
    if not isinstance(value, list):
        return None
    return [ua.Int32(n) for n in dimensions(kind)] or None


def _share_monitored_values() -> None:
    """asyncua copies a value deeply for every monitored item each time it changes: with
    10,000 monitored items, 55 % of the server's time (make bench). The server makes a new
    DataValue for every write and never changes one afterwards, so the monitored items
    may share it. (asyncua is pinned at the version this was read in.)"""

    def keep(self: MonitoredItemValues, value: ua.DataValue) -> None:
        self.old_dvalue = self.current_dvalue
        self.current_dvalue = value

    MonitoredItemValues.set_current_datavalue = keep  # type: ignore[method-assign,assignment]


def _status(code: int) -> ua.StatusCode:
    return ua.StatusCode(ua.UInt32(code))


def _standard(object_id: int) -> ua.NodeId:
    """A node of OPC UA's own namespace."""
    return ua.NodeId(ua.Int32(object_id))


def _settle(
    done: asyncio.Future[tuple[ua.StatusCode, int]], outcome: tuple[ua.StatusCode, int]
) -> None:
    if not done.done():
        done.set_result(outcome)


def _hosts(host: str) -> tuple[str, ...]:
    names = [host, "localhost", "127.0.0.1", socket.gethostname()]
    return tuple(dict.fromkeys(name for name in names if name not in ("", "0.0.0.0")))


def _free_port(host: str) -> int:
    with socket.socket() as probe:
        probe.bind((host, 0))
        return int(probe.getsockname()[1])
