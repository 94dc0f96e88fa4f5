"""A private network of Linux network namespaces for tests: one namespace per host, veth
links between them, processes started inside them; everything removed again on exit,
also when the test fails (needs root and iproute2's `ip`).

The namespaces are named `padt-<pid>-<host>`, so that runs side by side and leftovers of
a killed run never clash. A link is made with both of its ends already inside their
namespaces (`ip link add ... netns A type veth peer ... netns B`): no interface ever
appears in the host's own namespace, so the test cannot send a packet anywhere but inside
the namespaces it made (and each one's own loopback).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest


def require_namespaces() -> None:
    """Skip the test where namespaces cannot be made (not root, no `ip`), with the
    reason; under CI (CI=true) fail instead: there the test must run."""
    reason = _why_not_namespaces()
    if reason is None:
        return
    message = f"needs Linux network namespaces: {reason}"
    if os.environ.get("CI") == "true":
        pytest.fail(f"{message} (CI=true: not skipped)")
    pytest.skip(message)


def _why_not_namespaces() -> str | None:
    if shutil.which("ip") is None:
        return "no `ip` command (iproute2)"
    if os.geteuid() != 0:
        return "not root"
    probe = f"padt-{os.getpid()}-probe"
    made = subprocess.run(["ip", "netns", "add", probe], capture_output=True, text=True)
    if made.returncode != 0:
        return f"`ip netns add` failed: {made.stderr.strip()}"
    subprocess.run(["ip", "netns", "del", probe], capture_output=True)
    return None


@dataclass(frozen=True)
class Link:
    """A veth link between two hosts with the addresses of its two ends (a /30 each)."""

    a: str
    b: str
    a_address: str
    b_address: str


@dataclass
class Network:
    """The namespaces of one test, their links and the processes started in them."""

    prefix: str
    hosts: tuple[str, ...]
    links: list[Link] = field(default_factory=list)
    processes: list[subprocess.Popen[str]] = field(default_factory=list)

    def namespace(self, host: str) -> str:
        return f"{self.prefix}-{host}"

    def address(self, host: str, towards: str) -> str:
        """`host`'s address on its link to `towards`."""
        for link in self.links:
            if (link.a, link.b) == (host, towards):
                return link.a_address
            if (link.b, link.a) == (host, towards):
                return link.b_address
        raise KeyError(f"no link {host}-{towards}")

    def addresses(self, host: str) -> list[str]:
        """Every address of `host`, one per link."""
        found = [link.a_address for link in self.links if link.a == host]
        return found + [link.b_address for link in self.links if link.b == host]

    def cut(self, host: str, towards: str) -> None:
        """The link of `host` to `towards` down at `host`'s end: a cable pulled."""
        _ip("-n", self.namespace(host), "link", "set", _interface(towards), "down")

    def mend(self, host: str, towards: str) -> None:
        _ip("-n", self.namespace(host), "link", "set", _interface(towards), "up")

    def command(self, host: str, args: Sequence[str]) -> list[str]:
        # `ip netns exec` execs the command in place: the process started is the command
        # itself, so its pid is the one to signal (no wrapper left in between)
        return ["ip", "netns", "exec", self.namespace(host), *args]

    def start(
        self, host: str, args: Sequence[str], cwd: Path, log: Path | None = None
    ) -> subprocess.Popen[str]:
        """A process in `host`'s namespace, ended at the network's end at the latest;
        stdout piped (a `readline` away), stderr to `log` (or piped)."""
        with contextlib.ExitStack() as files:
            errors = files.enter_context(log.open("w")) if log is not None else subprocess.PIPE
            process = subprocess.Popen(
                self.command(host, args),
                cwd=cwd,
                stdout=subprocess.PIPE,
                stderr=errors,
                text=True,
                env=dict(os.environ),
            )  # (the child keeps its own copy of the log file open)
        self.processes.append(process)
        return process

    def run(
        self, host: str, args: Sequence[str], cwd: Path, timeout: float = 120
    ) -> subprocess.CompletedProcess[str]:
        """A command in `host`'s namespace, to its end."""
        return subprocess.run(
            self.command(host, args),
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=timeout,
            env=dict(os.environ),
        )


def _interface(towards: str) -> str:
    """The name of a host's end of its link to `towards` (inside its namespace only)."""
    return f"to-{towards}"[:15]


def _ip(*args: str) -> None:
    done = subprocess.run(["ip", *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip()}")


@contextmanager
def network(hosts: Sequence[str], links: Sequence[tuple[str, str]]) -> Iterator[Network]:
    """The namespaces of `hosts`, each with its loopback up, and a veth link for each pair
    of `links` (10.91.<n>.1/30 and .2/30, n counting the links: private addresses that
    exist only inside these namespaces), all removed on exit, processes first: `ip netns
    del` only removes a namespace's name, and a process still inside keeps the namespace
    and its links alive."""
    net = Network(prefix=f"padt-{os.getpid()}", hosts=tuple(hosts))
    made: list[str] = []
    try:
        for host in hosts:
            _ip("netns", "add", net.namespace(host))
            made.append(net.namespace(host))
            _ip("-n", net.namespace(host), "link", "set", "lo", "up")
        for number, (a, b) in enumerate(links, start=1):
            # the interface names live inside the namespaces only: short and readable
            a_name, b_name = _interface(b), _interface(a)
            _ip("link", "add", "name", a_name, "netns", net.namespace(a), "type", "veth",
                "peer", "name", b_name, "netns", net.namespace(b))  # fmt: skip
            link = Link(a, b, f"10.91.{number}.1", f"10.91.{number}.2")
            for host, name, address in ((a, a_name, link.a_address), (b, b_name, link.b_address)):
                _ip("-n", net.namespace(host), "addr", "add", f"{address}/30", "dev", name)
                _ip("-n", net.namespace(host), "link", "set", name, "up")
            net.links.append(link)
        yield net
    finally:
        for process in net.processes:
            end(process)
            for stream in (process.stdout, process.stderr):
                if stream is not None:
                    stream.close()
        for namespace in made:
            # anything a process of ours started in its namespace (a C compiler run by a
            # runtime), so that the namespace and its links really go away
            for pid in _pids_in(namespace):
                _kill(pid)
            subprocess.run(["ip", "netns", "del", namespace], capture_output=True)


def end(process: subprocess.Popen[str], signal_number: int = signal.SIGTERM) -> int:
    """End one process of the network (SIGTERM, then SIGKILL after a generous wait)."""
    if process.poll() is None:
        process.send_signal(signal_number)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    return process.returncode


def _pids_in(namespace: str) -> list[int]:
    listed = subprocess.run(["ip", "netns", "pids", namespace], capture_output=True, text=True)
    return [int(pid) for pid in listed.stdout.split()]


def _kill(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + 20
    while Path(f"/proc/{pid}").exists() and time.monotonic() < deadline:
        time.sleep(0.05)


def leftovers(net: Network) -> list[str]:
    """What of `net` is still there after its end: namespaces, links in the host's
    namespace that carry one of its names, processes of its own still alive."""
    left: list[str] = []
    listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    left += [f"namespace {line.split()[0]}" for line in listed.splitlines()
             if line.startswith(f"{net.prefix}-")]  # fmt: skip
    links = subprocess.run(["ip", "-o", "link"], capture_output=True, text=True).stdout
    names = {f"to-{host}"[:15] for host in net.hosts}
    left += [f"link {line.split(':')[1].strip()}" for line in links.splitlines()
             if line.split(":")[1].strip().split("@")[0] in names]  # fmt: skip
    left += [f"process {p.pid} {p.args!r}" for p in net.processes if p.poll() is None]
    return left
