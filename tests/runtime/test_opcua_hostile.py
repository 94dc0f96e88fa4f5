"""The resource's OPC UA server against hostile clients: raw TCP on 127.0.0.1 carrying what
no well-behaved client sends (random bytes, cut headers, absurd sizes, a channel opened
without security and then garbage, one message built up of endless chunks, connections
held open and silent). After each attack the runtime is alive, in RUN and cycling, a
genuine client still gets in with its certificate and password and reads the count, the
runtime's memory stayed within BOUND_KIB of what it was before the attacks, and its log
has no traceback.
"""

from __future__ import annotations

import asyncio
import random
import socket
import struct
import time
from collections.abc import Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import pytest
from asyncua import ua
from asyncua.common.utils import Buffer
from asyncua.ua.ua_binary import struct_from_binary, struct_to_binary

from runtime.field_io.opcua.resource_server import (
    CHUNK_BYTES,
    MAX_CONNECTIONS,
    MAX_MESSAGE_BYTES,
    UNFINISHED_BYTES,
)
from tests.runtime.test_opcua_server import Served, connected, node, serving

# what the attacks may grow the runtime's memory by: the 16 MiB of unfinished messages
# it holds at most (UNFINISHED_BYTES), with room to spare
BOUND_KIB = 32 * 1024
SEED = 20261203
NO_SECURITY = "http://opcfoundation.org/UA/SecurityPolicy#None"
TYPES = (b"HELF", b"ACKF", b"ERRF", b"OPNF", b"MSGF", b"MSGC", b"MSGA", b"CLOF", b"XYZF")


@dataclass
class Target:
    served: Served
    log: Path
    baseline_kib: int  # the runtime's memory after genuine clients' visits
    log_seen: int = 0  # how much of the log earlier checks read


@pytest.fixture(scope="module")
def target(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Target]:
    tmp = tmp_path_factory.mktemp("opcua-hostile")
    log = tmp / "runtime.log"
    with log.open("wb") as sink, serving(tmp, sink) as served:
        for _ in range(3):  # the first visits make what the server keeps for them all
            genuine_read(served)
        baseline = memory_kib(served.pid)
        print(f"RSS before the attacks: {baseline} KiB")
        reset_peak(served.pid)
        yield Target(served, log, baseline)


def memory_kib(pid: int, kind: str = "VmRSS") -> int:
    """The process's memory now (VmRSS) or at most since `reset_peak` (VmHWM)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(f"{kind}:"):
            return int(line.split()[1])
    raise AssertionError(f"process {pid} is gone")


def reset_peak(pid: int) -> None:
    Path(f"/proc/{pid}/clear_refs").write_text("5")


def genuine_read(served: Served) -> int:
    """The count, as a client with a trusted certificate and a password reads it."""

    async def read() -> int:
        client = await connected(served, "viewer")
        try:
            value: int = await client.get_node(node("Main.count")).read_value()
            return value
        finally:
            await client.disconnect()

    return asyncio.run(read())


def unharmed(target: Target) -> None:
    """Alive, in RUN and cycling, serving a genuine client a count that moves, its memory
    (now and at its peak during the attack) within the bound, no traceback."""
    served = target.served
    rss, peak = memory_kib(served.pid), memory_kib(served.pid, "VmHWM")
    print(f"RSS {rss} KiB, at most {peak} KiB")
    assert peak - target.baseline_kib < BOUND_KIB, (peak, target.baseline_kib)
    status = served.client.command("status")["status"]
    assert status["state"] == "RUN"
    first = genuine_read(served)
    deadline = time.monotonic() + 30
    while genuine_read(served) <= first:
        assert time.monotonic() < deadline, "the count no longer moves"
    assert served.client.command("status")["status"]["cycle"] > status["cycle"]
    text = target.log.read_bytes()
    fresh, target.log_seen = text[target.log_seen :], len(text)
    assert b"Traceback" not in fresh, fresh.decode(errors="replace")[-3000:]
    reset_peak(served.pid)  # for the next attack


def opened(target: Target) -> socket.socket:
    return socket.create_connection(("127.0.0.1", target.served.port), timeout=30)


def send(sock: socket.socket, data: bytes) -> bool:
    """False: the server had closed the connection."""
    try:
        sock.sendall(data)
    except OSError:
        return False
    return True


def answer(sock: socket.socket, wait_s: float = 1.0) -> bytes:
    """What the server sends until it closes the connection or is silent for `wait_s`."""
    got = b""
    sock.settimeout(wait_s)
    try:
        while more := sock.recv(1 << 16):
            got += more
    except OSError:  # silent for wait_s, or reset
        pass
    sock.settimeout(30)
    return got


def closed_by_server(sock: socket.socket) -> bool:
    """Whether the server closed `sock`, whatever it sent before."""
    sock.setblocking(False)
    try:
        while sock.recv(1 << 16):
            pass
    except BlockingIOError:
        return False
    except OSError:
        return True
    finally:
        sock.settimeout(30)
    return True


def hello(
    receive: int = CHUNK_BYTES,
    send: int = CHUNK_BYTES,
    message: int = 0,
    chunks: int = 0,
    url: str = "opc.tcp://127.0.0.1/",
) -> bytes:
    params = ua.Hello()
    params.ReceiveBufferSize, params.SendBufferSize = ua.UInt32(receive), ua.UInt32(send)
    params.MaxMessageSize, params.MaxChunkCount = ua.UInt32(message), ua.UInt32(chunks)
    params.EndpointUrl = ua.String(url)
    body = struct_to_binary(params)
    return b"HELF" + struct.pack("<I", 8 + len(body)) + body


def opening() -> bytes:
    """An OpenSecureChannel request without security, as asyncua takes it for discovery:
    no certificate, no signature."""
    request = ua.OpenSecureChannelRequest()
    request.Parameters.SecurityMode = ua.MessageSecurityMode.None_
    request.Parameters.RequestedLifetime = ua.UInt32(60_000)
    policy = ua.AsymmetricAlgorithmHeader()
    policy.SecurityPolicyURI = ua.String(NO_SECURITY)
    sequence = ua.SequenceHeader()
    sequence.SequenceNumber, sequence.RequestId = ua.UInt32(1), ua.UInt32(1)
    body = b"".join(struct_to_binary(part) for part in (policy, sequence, request))
    return b"OPNF" + struct.pack("<II", 12 + len(body), 0) + body


def received(sock: socket.socket) -> Buffer:
    """One message from the server, whole."""
    head = sock.recv(8, socket.MSG_WAITALL)
    size = struct.unpack("<I", head[4:])[0]
    return Buffer(head + sock.recv(size - 8, socket.MSG_WAITALL))


def open_channel(sock: socket.socket) -> tuple[int, int]:
    """A secure channel without security on `sock`: its id and its token's."""
    assert send(sock, hello())
    assert received(sock).read(3) == b"ACK"
    assert send(sock, opening())
    answer = received(sock)
    assert answer.read(3) == b"OPN"
    answer.skip(9)  # chunk type, size, channel
    struct_from_binary(ua.AsymmetricAlgorithmHeader, answer)
    struct_from_binary(ua.SequenceHeader, answer)
    response = struct_from_binary(ua.OpenSecureChannelResponse, answer)
    token = response.Parameters.SecurityToken
    return int(token.ChannelId), int(token.TokenId)


def chunk(kind: bytes, channel: int, token: int, sequence: int, body: bytes) -> bytes:
    """A message chunk on a channel without security: header, token, sequence number,
    request id (1), body."""
    head = struct.pack("<IIIII", 24 + len(body), channel, token, sequence, 1)
    return b"MSG" + kind + head + body


def test_random_bytes_of_many_sizes_and_frames(target: Target) -> None:
    rng = random.Random(SEED)
    sizes = (1, 3, 7, 8, 9, 12, 24, 100, 1000, 8192, CHUNK_BYTES, CHUNK_BYTES + 1, 1 << 20)
    attacks = [rng.randbytes(size) for size in sizes]
    for size in sizes:  # well framed, of every type, garbage inside
        for kind in TYPES:
            attacks.append(kind + struct.pack("<I", 8 + size) + rng.randbytes(size))
    for kind in TYPES:  # sizes that do not fit their frame: too small, zero, the largest
        for announced in (0, 1, 7, 8, 11, 12, 2**32 - 1):
            attacks.append(kind + struct.pack("<I", announced) + rng.randbytes(64))
    rng.shuffle(attacks)
    answered = 0
    for data in attacks:
        with opened(target) as sock:
            send(sock, data)
            answered += bool(answer(sock, 0.05))
    with opened(target) as sock:  # a flood of 10,000 garbage messages on one connection
        flood = b"".join(
            b"MSGF" + struct.pack("<I", 8 + 40) + rng.randbytes(40) for _ in range(10_000)
        )
        send(sock, flood)
        answer(sock, 0.5)
    print(f"{len(attacks)} attacks, {answered} answered")
    unharmed(target)


def test_truncated_headers_closed_or_held(target: Target) -> None:
    cuts = [kind[:n] for kind in TYPES for n in range(1, 8)]
    cuts += [b"MSGF" + struct.pack("<I", 100) + b"\x01\x02"]  # a body that never comes
    with ExitStack() as stack:
        held = []
        for data in cuts:
            sock = stack.enter_context(opened(target))
            send(sock, data)
            held.append(sock)
        time.sleep(0.5)
        print(f"{sum(not closed_by_server(s) for s in held)} of {len(held)} held")
    for data in cuts:  # and the same, closed at once
        with opened(target) as sock:
            send(sock, data)
    unharmed(target)


def test_a_header_announcing_two_gigabytes(target: Target) -> None:
    header = b"MSGF" + struct.pack("<I", 2**31)
    with opened(target) as sock:  # then silence
        send(sock, header)
        answer(sock, 0.5)
    with opened(target) as sock:  # then close
        send(sock, header)
    streamed = 0
    with opened(target) as sock:  # then bytes, as long as the server takes them
        send(sock, b"HELF" + struct.pack("<I", 2**31))
        junk = random.Random(SEED).randbytes(1 << 20)
        while streamed < 256 << 20 and send(sock, junk):
            streamed += len(junk)
    print(f"streamed {streamed >> 20} MiB into one message")
    assert streamed < 256 << 20, "the server took 256 MiB of one message"
    unharmed(target)


@pytest.mark.parametrize(
    "sizes",
    [
        {"receive": 0, "send": 0},
        {"receive": 1, "send": 1},
        {"receive": 8, "send": 8},
        {"receive": 2**32 - 1, "send": 2**32 - 1},
        {"message": 1, "chunks": 1},
        {"message": 2**32 - 1, "chunks": 2**32 - 1},
        {"url": "opc.tcp://" + "x" * (1 << 20)},
    ],
    ids=["zero", "one", "eight", "largest", "tiny-message", "largest-message", "1MB-url"],
)
def test_a_hello_with_absurd_sizes(target: Target, sizes: dict[str, object]) -> None:
    with opened(target) as sock:
        send(sock, hello(**sizes))  # type: ignore[arg-type]
        acknowledged = answer(sock, 0.5)[:4]
        if acknowledged == b"ACKF":  # then a channel, whose answer must fit those sizes
            send(sock, opening())
            answer(sock, 0.5)
    print(f"{sizes if len(str(sizes)) < 200 else '1 MB URL'}: {acknowledged!r}")
    unharmed(target)


def test_a_channel_without_security_then_garbage(target: Target) -> None:
    rng = random.Random(SEED)
    for size in (0, 1, 8, 100, 4000):
        with opened(target) as sock:
            channel, token = open_channel(sock)
            send(sock, chunk(b"F", channel, token, 2, rng.randbytes(size)))
            answer(sock, 0.3)
    with opened(target) as sock:  # a wrong channel, token, sequence
        channel, token = open_channel(sock)
        send(sock, chunk(b"F", channel + 1, token + 1, 99, rng.randbytes(100)))
        answer(sock, 0.3)
    with opened(target) as sock:  # an abort chunk with garbage for its error
        channel, token = open_channel(sock)
        send(sock, chunk(b"A", channel, token, 2, rng.randbytes(30)))
        answer(sock, 0.3)
    unharmed(target)


@pytest.mark.parametrize("message", [100 << 20, MAX_MESSAGE_BYTES], ids=["100MiB", "4MiB"])
def test_endless_intermediate_chunks(target: Target, message: int) -> None:
    """Each of 8 channels builds up one message to just below `message` bytes (asyncua's
    own limit, the server's) and holds it unfinished: all those the server does not
    hold are refused."""
    body = random.Random(SEED).randbytes(CHUNK_BYTES - 24)
    most = message // len(body) - 1  # chunks
    taken = []
    with ExitStack() as stack:
        socks = [stack.enter_context(opened(target)) for _ in range(8)]
        for sock in socks:
            channel, token = open_channel(sock)
            sent = 0
            while sent < most and send(sock, chunk(b"C", channel, token, 2 + sent, body)):
                sent += 1
            taken.append(sent)
        time.sleep(1)  # the server reads what is on its way
        refused = sum(answer(sock, 0.2).startswith(b"ERRF") for sock in socks)
    print(f"chunks of {[n * len(body) >> 20 for n in taken]} MiB sent, {refused} refused")
    held = min(MAX_MESSAGE_BYTES, message) // len(body) * len(body)  # by each it holds
    assert refused >= len(socks) - (UNFINISHED_BYTES // held + 1)
    unharmed(target)


def test_unfinished_messages_go_with_their_connections(target: Target) -> None:
    """Round after round, 4 channels each build up a message to just below the server's
    limit and close: what they held is not kept after them."""
    body = random.Random(SEED).randbytes(CHUNK_BYTES - 24)
    most = MAX_MESSAGE_BYTES // len(body) - 1  # chunks
    for _ in range(8):
        with ExitStack() as stack:
            socks = [stack.enter_context(opened(target)) for _ in range(4)]
            for sock in socks:
                channel, token = open_channel(sock)
                for sent in range(most):
                    send(sock, chunk(b"C", channel, token, 2 + sent, body))
            for sock in socks:  # the server took them all: it answers what follows
                assert send(sock, hello())
                assert received(sock).read(3) == b"ACK"
    unharmed(target)


def test_many_connections_held_half_open(target: Target) -> None:
    """More connections than the server takes, held silent or after a Hello: those beyond
    its limit are closed, and a genuine client still gets in while they are held."""
    many = MAX_CONNECTIONS + 100
    started = time.monotonic()
    with ExitStack() as stack:
        held = []
        for n in range(many):
            try:
                sock = stack.enter_context(opened(target))
            except OSError:
                break
            if n % 2:
                send(sock, hello())
            held.append(sock)
        print(f"opened in {time.monotonic() - started:.1f} s")
        time.sleep(1)
        open_ = sum(not closed_by_server(s) for s in held)
        fds = len(list(Path(f"/proc/{target.served.pid}/fd").iterdir()))
        print(f"{len(held)} opened, {open_} held by the server; {fds} fds")
        assert open_ <= MAX_CONNECTIONS
        genuine_read(target.served)
    unharmed(target)
