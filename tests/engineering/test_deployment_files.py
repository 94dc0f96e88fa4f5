"""The deployment files (deploy/systemd, docker/compose.yaml, docs/deployment.md) against
the real `padt` parser: every command they run parses; the units are hardened, each runs
as a user of its own, and only the runtime holds a capability; the compose file publishes
to 127.0.0.1 only. And the example access control's exchange rules on a real router."""

from __future__ import annotations

import re
import shlex
import time
from pathlib import Path
from typing import Any

import pytest

from padt.cli import build_parser
from runtime.contract.session import open_client, open_router
from tests.conftest import REPO, free_port

UNITS = REPO / "deploy" / "systemd"
COMPOSE = REPO / "docker" / "compose.yaml"
GUIDE = REPO / "docs" / "deployment.md"
HARDENING = {
    "NoNewPrivileges": "yes",
    "ProtectSystem": "strict",
    "ProtectHome": "yes",
    "PrivateTmp": "yes",
    "PrivateDevices": "yes",
    "SystemCallFilter": "@system-service",
    "Restart": "on-failure",
}
FAMILIES = {"AF_INET", "AF_INET6", "AF_UNIX", "AF_NETLINK"}
SHELL_END = {"||", "&&", "|", ";"}


def unit(path: Path) -> dict[str, list[str]]:
    """A unit file's `Key=value` lines (every section, keys may repeat)."""
    keys: dict[str, list[str]] = {}
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith(("#", ";", "[")):
            continue
        key, _, value = line.partition("=")
        keys.setdefault(key.strip(), []).append(value.strip())
    return keys


def services() -> dict[str, dict[str, list[str]]]:
    found = {path.name: unit(path) for path in sorted(UNITS.glob("*.service"))}
    assert set(found) == {
        "padt-router.service", "padt-runtime@.service", "padt-api.service", "padt-ui.service"
    }  # fmt: skip
    return found


def parses(words: list[str]) -> None:
    """`padt WORDS...` as padt's own parser takes it (argparse exits on an unknown
    command or option)."""
    try:
        build_parser().parse_args(words)
    except SystemExit as exc:
        raise AssertionError(f"padt {' '.join(words)}: does not parse") from exc


def padt_words(words: list[str]) -> list[str] | None:
    """The arguments after the `padt` program in a command line, up to a shell operator or
    redirection; None when it runs no padt."""
    for i, word in enumerate(words):
        if Path(word).name == "padt" and i + 1 < len(words) and words[i - 1 : i] != ["-u"]:
            rest = []
            for arg in words[i + 1 :]:
                if arg in SHELL_END or ">" in arg or "<" in arg:
                    break
                rest.append(arg)
            return rest
    return None


def exec_start(name: str, keys: dict[str, list[str]]) -> list[str]:
    """The unit's ExecStart as padt gets it: %i a resource, each `$VAR` the options of the
    environment files that docs/deployment.md shows."""
    (line,) = keys["ExecStart"]
    assert line.startswith("/opt/padt/bin/padt "), line
    words = []
    for word in shlex.split(line.replace("%i", "Tank1")):
        if word.startswith("$"):
            words += shlex.split(documented_environment()[word.strip("${}")])
        else:
            words.append(word)
    assert not [w for w in words if "$" in w or "%" in w], f"{name}: {words}"
    return words[1:]


def documented_environment() -> dict[str, str]:
    """The `PADT_*_ARGS=...` lines of docs/deployment.md (the last of each name)."""
    found = {}
    for name, value in re.findall(r"^(PADT_[A-Z]+_ARGS)=(.*)$", GUIDE.read_text(), re.M):
        found[name] = shlex.split(value)[0] if value else ""
    return found


def test_every_exec_start_parses_with_padt() -> None:
    commands = {name: exec_start(name, keys) for name, keys in services().items()}
    for words in commands.values():
        parses(words)
    assert commands["padt-runtime@.service"][:3] == ["runtime", "--resource", "Tank1"]
    assert commands["padt-router.service"][0] == "router"
    for name in ("padt-api.service", "padt-ui.service"):
        args = build_parser().parse_args(commands[name])
        assert args.host == "127.0.0.1", f"{name} binds beyond loopback"


def test_units_are_hardened_and_run_as_their_own_users() -> None:
    users = set()
    for name, keys in services().items():
        for key, value in HARDENING.items():
            assert keys.get(key) == [value], f"{name}: {key}={value}"
        assert set(keys["RestrictAddressFamilies"][0].split()) <= FAMILIES, name
        user = keys.get("User", [""])[0]
        assert user and user != "root", f"{name} runs as root"
        users.add(user)
        if name == "padt-runtime@.service":
            assert keys["StateDirectory"] == ["padt/%i"]
            assert keys["StateDirectoryMode"] == ["0700"]
            assert keys["AmbientCapabilities"] == ["CAP_SYS_NICE"]
            assert keys["CapabilityBoundingSet"] == ["CAP_SYS_NICE"]
            assert "LimitRTPRIO" in keys
            assert "RestrictRealtime" not in keys  # it would refuse SCHED_FIFO
        else:
            assert keys["CapabilityBoundingSet"] == [""], f"{name} has a capability"
            assert keys.get("AmbientCapabilities", [""]) == [""], name
    assert users == {"padt-router", "padt-runtime", "padt"}
    made = (UNITS / "sysusers-padt.conf").read_text()
    for user in users:
        assert re.search(rf"^u {re.escape(user)} ", made, re.M), f"sysusers makes no {user}"


def compose() -> dict[str, Any]:
    # PyYAML comes with the dev extra (through schemathesis) and ships no type information
    yaml = pytest.importorskip("yaml")
    loaded = yaml.safe_load(COMPOSE.read_text())
    assert isinstance(loaded, dict)
    return loaded


def test_compose_services_ports_capabilities_and_volumes() -> None:
    loaded = compose()
    services_ = loaded["services"]
    assert {"router", "runtime", "api", "ui"} <= set(services_)
    named = set(loaded["volumes"])
    for name, service in services_.items():
        for port in service.get("ports", []):
            assert str(port).startswith("127.0.0.1:"), f"{name} publishes {port} beyond loopback"
        runs = padt_words(service["command"])
        assert runs is not None, f"{name} runs no padt"
        caps = service.get("cap_add", [])
        if runs[0] in ("runtime", "demo"):
            assert caps == ["SYS_NICE"], name
        else:
            assert caps == [], f"{name} has a capability"
        for volume in service.get("volumes", []):
            assert volume.split(":")[0] in named, f"{name}: {volume} is no named volume"
        if name != "padt-demo":
            assert service["cap_drop"] == ["ALL"], name
            assert service["healthcheck"]["test"], name
            assert "profiles" not in service, name
    assert {p.split(":")[-1] for s in services_.values() for p in s.get("ports", [])} >= {
        "8080", "8000", "5020"
    }  # fmt: skip
    assert not services_["router"].get("ports"), "the router is published"


def test_every_compose_command_parses_with_padt() -> None:
    checked = 0
    for service in compose()["services"].values():
        parses(padt_words(service["command"]) or [])
        checked += 1
        test = service.get("healthcheck", {}).get("test", [])
        if test and test[0] == "CMD-SHELL":
            words = padt_words(shlex.split(test[1]))
        elif test:
            words = padt_words(test[1:])
        else:
            continue
        if words is not None:
            parses(words)
            checked += 1
    runtime_health = padt_words(
        shlex.split(compose()["services"]["runtime"]["healthcheck"]["test"][1])
    )
    assert runtime_health is not None and runtime_health[0] == "status"
    assert checked >= 6


def test_every_padt_command_of_the_guide_parses() -> None:
    """Each line of docs/deployment.md's code blocks that runs padt (continuations
    joined), and each PADT_*_ARGS line with the command it is given to."""
    text = GUIDE.read_text()
    blocks: list[list[str] | None] = []
    fence = None
    for line in text.splitlines():
        if line.strip().startswith("```"):
            if fence is None:
                fence = line.strip()[3:]
                blocks.append([] if fence in ("sh", "") else None)
            else:
                fence = None
        elif fence is not None and blocks[-1] is not None:
            blocks[-1].append(line)
    seen = 0
    for block in ("\n".join(lines) for lines in blocks if lines is not None):
        for line in block.replace("\\\n", " ").splitlines():
            if line.lstrip().startswith(("#", "/etc", "{", "}")) or "padt" not in line:
                continue
            try:
                words = shlex.split(line)
            except ValueError:
                continue
            runs = padt_words(words)
            if runs:
                parses(runs)
                seen += 1
    command = {"ROUTER": "router", "RUNTIME": "runtime", "API": "api", "UI": "ui"}
    fixed = {"runtime": ["--resource", "Tank1", "--state-dir", "/tmp/x"]}
    for role, value in re.findall(r"^PADT_([A-Z]+)_ARGS=(.*)$", text, re.M):
        parses([command[role], *fixed.get(command[role], []), *shlex.split(shlex.split(value)[0])])
        seen += 1
    assert seen >= 8


def test_a_resource_publishes_only_its_own_exchange(tmp_path: Path) -> None:
    """The example access control (docs/examples/zenoh-router-acl.json5): Tank1 publishes
    on its own exchange keys and every subscriber gets it; what Tank1 puts on another
    resource's exchange, or a PADT user on Tank1's, reaches nobody."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    users = tmp_path / "users.txt"
    users.write_text("Tank1:Res-secret-1\nengineer:Eng-secret-2\n")
    shipped = (REPO / "docs" / "examples" / "zenoh-router-acl.json5").read_text()
    router_config = tmp_path / "router.json5"
    router_config.write_text(shipped.replace("/etc/padt/zenoh-users.txt", str(users)))

    def login(name: str, secret: str) -> Path:
        path = tmp_path / f"{name}.json5"
        path.write_text(
            f'{{transport: {{auth: {{usrpwd: {{user: "{name}", password: "{secret}"}}}}}}}}'
        )
        return path

    router = open_router(endpoint, router_config)
    sessions = []
    try:
        tank = open_client(endpoint, login("Tank1", "Res-secret-1"))
        engineer = open_client(endpoint, login("engineer", "Eng-secret-2"))
        # a session of its own: a session hears its own puts without the router
        watcher = open_client(endpoint, login("engineer", "Eng-secret-2"))
        sessions += [tank, engineer, watcher]
        heard_by_engineer: list[str] = []
        heard_by_tank: list[str] = []
        watcher.declare_subscriber(
            "padt/v2/res/*/exchange/*", lambda s: heard_by_engineer.append(str(s.key_expr))
        )
        tank.declare_subscriber(
            "padt/v2/res/*/exchange/*", lambda s: heard_by_tank.append(str(s.key_expr))
        )
        time.sleep(1)  # the subscriptions reach the router and the publishers
        for _ in range(3):
            tank.put("padt/v2/res/Tank1/exchange/levels", b"1")
            tank.put("padt/v2/res/Mixer/exchange/levels", b"forged by Tank1")
            engineer.put("padt/v2/res/Tank1/exchange/forged", b"forged by the PADT")
            time.sleep(0.2)
        time.sleep(1)
        assert set(heard_by_engineer) == {"padt/v2/res/Tank1/exchange/levels"}
        assert "padt/v2/res/Tank1/exchange/forged" not in heard_by_tank
    finally:
        for session in sessions:
            session.close()
        router.close()
