"""A plant network of Linux network namespaces: two `padt router`s meshed over TLS with
mutual authentication, user and password and access control on every link; three
runtimes (Ctl1 on router1, Ctl2 and Ctl3 on router2), the PADT in a namespace of its own
on router1, and a rogue host on router1 with a valid certificate and Zenoh account that
the access control gives no rights.

The PADT commissions, loads and starts all three resources across the mesh; Ctl1's level,
written online, reaches Ctl2 and Ctl3 through the variable exchange (docs/exchange.md);
the rogue gets no answer and its forged status reaches nobody; router2 killed, the
runtimes cycle on, Ctl2 and Ctl3 go stale, and once it is back the PADT sees all three
again and the exchange recovers; Ctl3's cable pulled, the rest of the plant exchanges on,
and once it is plugged in again Ctl3 takes the new value.

Run as a module, this file is also the probe the test starts inside the namespaces (a
Zenoh client there cannot be a session of the test's own process, which lives in the
host's namespace): `python -m tests.engineering.test_mesh_network listen|rogue ...`.
"""

from __future__ import annotations

import enum
import functools
import json
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import pytest

from tests.support.network_namespaces import Network, end, leftovers, network, require_namespaces
from tests.support.runtime_process import KNOWN_SETUP_SECRET, know_setup_secret

REPO = Path(__file__).resolve().parent.parent.parent
PORT = 7447
RESOURCES = ("Ctl1", "Ctl2", "Ctl3")
ROUTER_OF = {"padt": "router1", "rogue": "router1", "Ctl1": "router1", "Ctl2": "router2",
             "Ctl3": "router2"}  # fmt: skip
# host names are namespace names: lower case, the resource names are Zenoh user names
HOST_OF = {"padt": "padt", "rogue": "rogue", "Ctl1": "ctl1", "Ctl2": "ctl2", "Ctl3": "ctl3"}
HOSTS = ("padt", "router1", "router2", "ctl1", "ctl2", "ctl3", "rogue")
LINKS = (("padt", "router1"), ("ctl1", "router1"), ("rogue", "router1"),
         ("router1", "router2"), ("ctl2", "router2"), ("ctl3", "router2"))  # fmt: skip
USERS = ("Ctl1", "Ctl2", "Ctl3", "engineer", "router1", "router2", "rogue")


# --- certificates, accounts, access control -----------------------------------------


def openssl(*args: str) -> None:
    subprocess.run(["openssl", *args], check=True, capture_output=True)


def make_ca(folder: Path) -> None:
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(folder / "ca.key"),
            "-out", str(folder / "ca.pem"), "-days", "2", "-subj", "/CN=padt mesh test CA",
            "-addext", "basicConstraints=critical,CA:TRUE",
            "-addext", "keyUsage=critical,keyCertSign,cRLSign")  # fmt: skip


def make_certificate(folder: Path, name: str, addresses: list[str]) -> None:
    """`name`.pem and .key signed by the CA, common name `name` (the access control tells
    the routers' links apart by it). Every certificate may serve and be a client: with
    mutual TLS a router is both, towards its clients and towards the router it connects
    to; a router's carries the addresses it is reached on (TLS checks them)."""
    request, extensions = folder / f"{name}.csr", folder / f"{name}.ext"
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", str(folder / f"{name}.key"),
            "-out", str(request), "-subj", f"/CN={name}")  # fmt: skip
    alt_names = ",".join([f"DNS:{name.lower()}", *(f"IP:{a}" for a in addresses)])
    extensions.write_text(
        f"subjectAltName={alt_names}\nbasicConstraints=CA:FALSE\n"
        "extendedKeyUsage=serverAuth,clientAuth\n"
    )
    openssl("x509", "-req", "-in", str(request), "-CA", str(folder / "ca.pem"),
            "-CAkey", str(folder / "ca.key"), "-CAcreateserial",
            "-out", str(folder / f"{name}.pem"), "-days", "2",
            "-extfile", str(extensions))  # fmt: skip


def shipped_access_control() -> dict[str, Any]:
    """The access control of docs/examples/zenoh-router-acl.json5, read by Zenoh's own
    JSON5 parser (no JSON5 package here)."""
    import zenoh

    text = (REPO / "docs" / "examples" / "zenoh-router-acl.json5").read_text()
    shipped: dict[str, Any] = json.loads(zenoh.Config.from_json5(text).get_json("access_control"))
    return shipped


def for_each_resource(items: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The shipped example's items: those of its resource Tank1 once for each of ours
    (Tank1 renamed), the others (the PADT's, the rules all resources share) as they are."""
    out: list[dict[str, Any]] = []
    for item in items:
        text = json.dumps(item)
        if "Tank1" in text:
            out += [json.loads(text.replace("Tank1", resource)) for resource in RESOURCES]
        else:
            out.append(item)
    return out


def access_control() -> dict[str, Any]:
    """The shipped example's access control for the resources Ctl1..3 and the PADT user
    `engineer`, plus the variable exchange between resources and the links between the
    routers."""
    shipped = shipped_access_control()
    rules = for_each_resource(shipped["rules"])
    subjects = for_each_resource(shipped["subjects"])
    policies = for_each_resource(shipped["policies"])
    # the variable exchange, whether or not the example has it yet: a resource puts on
    # its own exchange keys only, subscribes to every resource's, and hears both
    resources = [f"resource {resource}" for resource in RESOURCES]
    for resource in RESOURCES:
        rules.append({
            "id": f"mesh: {resource} publishes its exchange", "permission": "allow",
            "flows": ["ingress"], "messages": ["put"],
            "key_exprs": [f"padt/v2/res/{resource}/exchange/*"],
        })  # fmt: skip
        policies.append({"rules": [f"mesh: {resource} publishes its exchange"],
                         "subjects": [f"resource {resource}"]})  # fmt: skip
    rules += [
        {"id": "mesh: resources subscribe to exchanges", "permission": "allow",
         "flows": ["ingress"], "messages": ["declare_subscriber"],
         "key_exprs": ["padt/v2/res/*/exchange/*"]},
        {"id": "mesh: resources hear exchanges", "permission": "allow", "flows": ["egress"],
         "messages": ["put", "declare_subscriber"], "key_exprs": ["padt/v2/res/*/exchange/*"]},
    ]  # fmt: skip
    exchange = ["mesh: resources subscribe to exchanges", "mesh: resources hear exchanges"]
    policies.append({"rules": exchange, "subjects": resources})
    every_message = ["put", "delete", "declare_subscriber", "query", "declare_queryable",
                     "reply", "liveliness_token", "declare_liveliness_subscriber",
                     "liveliness_query"]  # fmt: skip
    rules.append({
        # between the routers everything on the project's keys passes: each router has
        # already judged what its own clients sent
        "id": "mesh: routers relay", "permission": "allow", "flows": ["ingress", "egress"],
        "messages": every_message, "key_exprs": ["padt/**"],
    })  # fmt: skip
    # told apart by their certificates' common names: on the link router2 opens, router1
    # shows router2 no Zenoh user (usrpwd goes one way), only its certificate
    subjects.append({"id": "routers", "cert_common_names": ["router1", "router2"]})
    policies.append({"rules": ["mesh: routers relay"], "subjects": ["routers"]})
    return {**shipped, "rules": rules, "subjects": subjects, "policies": policies}


@dataclass(frozen=True)
class Credentials:
    folder: Path

    def config(self, name: str) -> Path:
        return self.folder / f"{name}.json5"

    def password(self, name: str) -> str:
        return f"{name}-Zenoh-secret-42"


def tls(folder: Path, name: str) -> dict[str, object]:
    pem, key = str(folder / f"{name}.pem"), str(folder / f"{name}.key")
    return {"root_ca_certificate": str(folder / "ca.pem"), "enable_mtls": True,
            "listen_certificate": pem, "listen_private_key": key,
            "connect_certificate": pem, "connect_private_key": key}  # fmt: skip


def write_credentials(folder: Path, net: Network) -> Credentials:
    """The CA, a certificate and a Zenoh configuration for every user, the routers'
    dictionary and access control."""
    folder.mkdir()
    credentials = Credentials(folder)
    make_ca(folder)
    for user in USERS:
        addresses = net.addresses(user) if user.startswith("router") else []
        make_certificate(folder, user, addresses)
    dictionary = folder / "zenoh-users.txt"
    dictionary.write_text("".join(f"{u}:{credentials.password(u)}\n" for u in USERS))
    dictionary.chmod(0o600)
    acl = access_control()
    for user in USERS:
        auth: dict[str, object] = {"user": user, "password": credentials.password(user)}
        transport = {"link": {"tls": tls(folder, user)}, "auth": {"usrpwd": auth}}
        config: dict[str, object] = {"transport": transport}
        if user.startswith("router"):
            # a router checks who connects to it, and gives its own user to the router it
            # connects to (whose dictionary must know it, or the link is refused)
            auth["dictionary_file"] = str(dictionary)
            config["access_control"] = acl
        else:
            # a client opened while its router is still starting waits for it
            config["connect"] = {"timeout_ms": 30_000}
        path = credentials.config(user)
        path.write_text(json.dumps(config, indent=1))  # JSON is JSON5
        path.chmod(0o600)
    return credentials


# --- the plant network ------------------------------------------------------------


@dataclass
class Mesh:
    """The running network: routers, runtimes and what the PADT's namespace reaches."""

    net: Network
    credentials: Credentials
    tmp: Path
    routers: dict[str, subprocess.Popen[str]]
    runtimes: dict[str, subprocess.Popen[str]]

    def endpoint(self, who: str) -> str:
        """The TLS endpoint of the router nearest to `who` (a resource, padt, rogue)."""
        router = ROUTER_OF[who]
        return f"tls/{self.net.address(router, HOST_OF[who])}:{PORT}"

    def padt(self, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
        """`padt` in the PADT's namespace, through router1, as user engineer."""
        options = ["--zenoh", self.endpoint("padt"), "--zenoh-config",
                   str(self.credentials.config("engineer"))]  # fmt: skip
        command = [sys.executable, "-m", "padt.cli", *args, *options]
        return self.net.run("padt", command, REPO, timeout)

    def status(self, resource: str) -> dict[str, object] | None:
        """The resource's status as the PADT sees it, or None without an answer."""
        shown = self.padt("status", "--resource", resource, "--json")
        return json.loads(shown.stdout) if shown.returncode == 0 else None


def start_router(
    net: Network, credentials: Credentials, name: str, tmp: Path
) -> subprocess.Popen[str]:
    args = [sys.executable, "-m", "padt.cli", "router"]
    for address in net.addresses(name):
        args += ["--listen", f"tls/{address}:{PORT}"]
    if name == "router2":
        # router2 opens the link to router1: the router that is killed and comes back is
        # the one that connects, so the mesh is whole again as soon as it is up
        args += ["--connect", f"tls/{net.address('router1', 'router2')}:{PORT}"]
    args += ["--zenoh-config", str(credentials.config(name))]
    process = net.start(name, args, REPO, log=tmp / f"{name}.log")
    assert process.stdout is not None
    line = process.stdout.readline()
    assert line.startswith("padt router: listening on "), (tmp / f"{name}.log").read_text()
    return process


def start_runtime(mesh: Mesh, resource: str) -> subprocess.Popen[str]:
    state = mesh.tmp / "state" / resource
    state.mkdir(parents=True)
    know_setup_secret(state)
    # no C compiles (--no-native-code): three runtimes share two cores here
    args = [sys.executable, "-m", "padt.cli", "runtime", "--resource", resource,
            "--state-dir", str(state), "--zenoh", mesh.endpoint(resource),
            "--zenoh-config", str(mesh.credentials.config(resource)),
            "--no-native-code"]  # fmt: skip
    return mesh.net.start(HOST_OF[resource], args, REPO, log=mesh.tmp / f"{resource}.log")


T = TypeVar("T")


def until(what: str, probe: Callable[[], T | None], timeout_s: float = 120) -> T:
    """Ask `probe` again until it gives something, within a deadline no machine should
    reach (no assertion on how long it took)."""
    deadline = time.monotonic() + timeout_s
    while True:
        found = probe()
        if found is not None:
            return found
        assert time.monotonic() < deadline, f"never: {what}"
        time.sleep(0.5)


# the variable exchange (docs/exchange.md): Ctl1 publishes its level, Ctl2 and Ctl3 take it
PUBLISHED = """
[[exchange.publish]]
name = "levels"
variables = ["gLevel"]
period_ms = 50
"""
SUBSCRIBED = """
[[exchange.subscribe]]
resource = "Ctl1"
publication = "levels"
timeout_ms = 500

[[exchange.subscribe.variable]]
variable = "gFromCtl1"
from = "gLevel"
safe_value = -1
"""
WRITTEN = 4711  # Ctl1's level, written online; the subscribers' safe value is -1


def small_project(folder: Path, resource: str) -> Path:
    project = folder / resource
    project.mkdir(parents=True)
    (project / "padt.toml").write_text(
        f'[project]\nname = "{resource}"\nversion = "1"\n\n'
        f'[resource]\nname = "{resource}"\ntarget_cycle_ms = 50\n'
        "safety_operation = false\n\n"  # the test writes Ctl1's level online
        '[[resource.program]]\nname = "Main"\npou = "Main"\nid = 1\npriority = 0\n'
        + (PUBLISHED if resource == "Ctl1" else SUBSCRIBED)
    )
    (project / "Main.st").write_text(
        "VAR_GLOBAL gLevel : DINT; gFromCtl1 : DINT; END_VAR\n"
        "PROGRAM Main\nVAR\n  n : DINT;\nEND_VAR\nn := n + 1;\nEND_PROGRAM\n"
    )
    return project


def cycle_of(mesh: Mesh, resource: str) -> int:
    status = until(f"{resource} answers", lambda: mesh.status(resource))
    assert status["state"] == "RUN", status
    cycle = status["cycle"]
    assert isinstance(cycle, int)
    return cycle


def cycling(mesh: Mesh, resource: str, after: int) -> int:
    """The cycle counter of `resource` once it is past `after` (it runs)."""
    return until(f"{resource} cycles past {after}",
                 lambda: (c if (c := cycle_of(mesh, resource)) > after else None))  # fmt: skip


# --- hooks for the variable exchange between resources ----------------------------


class Phase(enum.Enum):
    ALL_UP = "all routers up"
    ROUTER2_DOWN = "router2 killed"
    ROUTER2_BACK = "router2 restarted"
    CTL3_CUT = "Ctl3's link to router2 cut"
    CTL3_BACK = "Ctl3's link mended"


def check_variable_exchange(mesh: Mesh, phase: Phase) -> None:
    """The variable exchange between the resources in each phase of this test: with all
    routers up, a value written in Ctl1 arrives in Ctl2 and Ctl3 across both routers;
    with router2 down, Ctl2 and Ctl3 (out of the PADT's reach then) took their safe
    values, which their event logs show once router2 is back; then the exchange
    recovered by itself. The access control above lets the exchange's keys through
    (`padt/v2/res/<resource>/exchange/*`)."""
    consumers = ("Ctl2", "Ctl3")
    if phase is Phase.ALL_UP:
        written = mesh.padt("write", "--resource", "Ctl1", "gLevel", str(WRITTEN))
        assert written.returncode == 0, written.stderr
        for resource in consumers:
            until(f"{WRITTEN} in {resource}", functools.partial(exchanged, mesh, resource, WRITTEN))
    elif phase is Phase.ROUTER2_BACK:
        for resource in consumers:
            until(
                f"{WRITTEN} in {resource} again",
                functools.partial(exchanged, mesh, resource, WRITTEN),
            )
            shown = mesh.padt("events", "--resource", resource, "--json")
            io = [json.loads(line)["message"] for line in shown.stdout.splitlines()]
            io = [message for message in io if message.startswith("Exchange Ctl1/levels")]
            lost = next(i for i, m in enumerate(io) if "lost: no message for 500 ms" in m)
            assert "Exchange Ctl1/levels connected again" in io[lost:], io
    elif phase is Phase.CTL3_CUT:
        # the rest of the plant goes on: a new value reaches Ctl2, not the cut-off Ctl3
        written = mesh.padt("write", "--resource", "Ctl1", "gLevel", str(WRITTEN + 1))
        assert written.returncode == 0, written.stderr
        until("the new value in Ctl2", functools.partial(exchanged, mesh, "Ctl2", WRITTEN + 1))
    elif phase is Phase.CTL3_BACK:
        until("the new value in Ctl3", functools.partial(exchanged, mesh, "Ctl3", WRITTEN + 1))
        shown = mesh.padt("events", "--resource", "Ctl3", "--json")
        io = [json.loads(line)["message"] for line in shown.stdout.splitlines()]
        stale = [m for m in io if m.startswith("Exchange Ctl1/levels lost: no message for 500 ms")]
        assert len(stale) == 2, io  # with router2 down, then with its own link cut


def exchanged(mesh: Mesh, resource: str, value: int) -> bool | None:
    """Whether `resource` holds `value`, written in Ctl1 (None: not yet)."""
    shown = mesh.padt("values", "--resource", resource, "--json", "gFromCtl1")
    if shown.returncode != 0:
        return None
    return True if json.loads(shown.stdout)["values"].get("gFromCtl1") == value else None


# --- the probes inside the namespaces -----------------------------------------------


def probe(argv: list[str]) -> int:
    """`listen ENDPOINT CONFIG KEY`: print `ready`, then every sample's payload on KEY as
    a line, until ended by a signal. `forge ENDPOINT CONFIG RESOURCE`: put a forged status
    on the resource's key and ask its command key, a few times; print how many answers
    came, as JSON."""
    from runtime.contract.keyspace import command_key, status_key
    from runtime.contract.session import open_client

    verb, endpoint, config, name = argv
    session = open_client(endpoint, Path(config))
    if verb == "listen":
        session.declare_subscriber(
            name, lambda sample: print(sample.payload.to_string(), flush=True)
        )
        print("ready", flush=True)
        threading.Event().wait()  # until SIGTERM ends the process
    answers = 0
    for _ in range(3):
        session.put(status_key(name), json.dumps({"state": "FORGED", "resource": name}))
        replies = session.get(command_key(name), payload=json.dumps({"cmd": "status"}), timeout=2)
        answers += len([reply for reply in replies if reply.ok is not None])
    print(json.dumps({"answers": answers}), flush=True)
    session.close()
    return 0


def probe_command(mesh: Mesh, who: str, *args: str) -> list[str]:
    """The probe's command line for `who` (padt as engineer, or rogue)."""
    user = "engineer" if who == "padt" else who
    return [sys.executable, "-m", "tests.engineering.test_mesh_network", *args[:1],
            mesh.endpoint(who), str(mesh.credentials.config(user)), *args[1:]]  # fmt: skip


@dataclass
class Heard:
    """The lines a listener printed so far (read by a thread: a readline blocks)."""

    lines: list[str] = field(default_factory=list)

    def count(self) -> int:
        return len(self.lines)


@contextmanager
def listener(mesh: Mesh, key: str) -> Iterator[Heard]:
    """A subscriber to `key` in the PADT's namespace, once it is declared."""
    process = mesh.net.start("padt", probe_command(mesh, "padt", "listen", key), REPO,
                             log=mesh.tmp / "listener.log")  # fmt: skip
    heard = Heard()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            heard.lines.append(line.rstrip("\n"))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        until("the listener is ready", lambda: True if "ready" in heard.lines else None)
        yield heard
    finally:
        end(process)
        reader.join(timeout=20)


def forged(mesh: Mesh, who: str, resource: str) -> int:
    """How many answers `who` gets from `resource`'s command key, after putting a forged
    status on its key."""
    done = mesh.net.run(who, probe_command(mesh, who, "forge", resource), REPO)
    assert done.returncode == 0, done.stderr
    answers: int = json.loads(done.stdout.splitlines()[-1])["answers"]
    return answers


def check_the_rogue(mesh: Mesh) -> None:
    """The rogue's query on Ctl1's command key gets no answer (where the PADT's same
    query does), and its forged status never reaches a subscriber in the PADT's
    namespace, which hears Ctl1's own statuses before and after."""
    assert forged(mesh, "padt", "Ctl1") > 0, "the probe's query is no query the resource answers"
    with listener(mesh, "padt/v2/res/Ctl1/status") as heard:
        until("a status of Ctl1 heard", lambda: True if heard.count() >= 2 else None)
        assert forged(mesh, "rogue", "Ctl1") == 0, "the rogue got an answer from Ctl1"
        # Ctl1 publishes its status about once a second: three more heard after the
        # rogue's puts, which went out before them on the same path if at all
        enough = heard.count() + 3
        until("more statuses of Ctl1", lambda: True if heard.count() >= enough else None)
    assert not [line for line in heard.lines if "FORGED" in line], "the rogue's status arrived"


# --- the test -----------------------------------------------------------------------


# a minute of the suite's 25: run with `pytest -m slow tests/engineering/test_mesh_network.py`;
# the exchange, the router and the access control each have tests of their own in `make test`
@pytest.mark.slow
def test_a_meshed_plant_network_with_tls_access_control_and_a_router_lost(
    tmp_path: Path,
) -> None:
    require_namespaces()
    with network(HOSTS, LINKS) as net:
        run_the_plant(net, tmp_path)
    assert leftovers(net) == [], "the network was not cleaned up"


def run_the_plant(net: Network, tmp: Path) -> None:
    credentials = write_credentials(tmp / "credentials", net)
    routers = {name: start_router(net, credentials, name, tmp) for name in ("router1", "router2")}
    mesh = Mesh(net, credentials, tmp, routers, {})
    mesh.runtimes = {resource: start_runtime(mesh, resource) for resource in RESOURCES}
    secret = tmp / "setup-secret"
    secret.write_text(KNOWN_SETUP_SECRET)
    secret.chmod(0o600)
    for resource in RESOURCES:
        until(f"{resource} answers the PADT", functools.partial(mesh.status, resource))
        project = small_project(tmp / "projects", resource)
        loaded = mesh.padt("load", str(project), "--resource", resource,
                           "--setup-secret-file", str(secret),
                           "--backup-dir", str(tmp / "backups"))  # fmt: skip
        assert loaded.returncode == 0, loaded.stderr
        started = mesh.padt("start", "--resource", resource)
        assert started.returncode == 0, started.stderr
    before = {resource: cycling(mesh, resource, 0) for resource in RESOURCES}
    check_variable_exchange(mesh, Phase.ALL_UP)
    check_the_rogue(mesh)

    end(routers["router2"], signal.SIGKILL)
    until(
        "Ctl2 and Ctl3 out of the PADT's reach",
        lambda: True if mesh.status("Ctl2") is None and mesh.status("Ctl3") is None else None,
    )
    # Ctl1, on router1, is still there; wait for some of its cycles to pass with router2
    # down (counted, not timed)
    cycling(mesh, "Ctl1", cycle_of(mesh, "Ctl1") + 20)
    check_variable_exchange(mesh, Phase.ROUTER2_DOWN)
    for resource, process in mesh.runtimes.items():
        assert process.poll() is None, f"{resource} ended with router2 down"

    routers["router2"] = start_router(net, credentials, "router2", tmp)
    for resource in RESOURCES:
        cycling(mesh, resource, before[resource])
    check_variable_exchange(mesh, Phase.ROUTER2_BACK)

    # a controller host cut off: Ctl3's cable pulled, then plugged in again
    net.cut("ctl3", "router2")
    until("Ctl3 out of the PADT's reach", lambda: True if mesh.status("Ctl3") is None else None)
    check_variable_exchange(mesh, Phase.CTL3_CUT)
    cycling(mesh, "Ctl2", cycle_of(mesh, "Ctl2") + 20)
    net.mend("ctl3", "router2")
    cycling(mesh, "Ctl3", before["Ctl3"])
    check_variable_exchange(mesh, Phase.CTL3_BACK)
    assert mesh.runtimes["Ctl3"].poll() is None, "Ctl3 ended while cut off"


if __name__ == "__main__":
    sys.exit(probe(sys.argv[1:]))
