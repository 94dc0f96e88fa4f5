"""A resource's name is part of its Zenoh keys (`padt/v2/res/<name>/cmd`): names such as
`*`, `Lk1/**` and `$*` would make key expressions that reach every resource. They are
refused where a name enters: the compiler (E0620 at the line that names it), the runtime
(it does not start), every client (before it asks anything), and the key space itself."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
import zenoh

from runtime.contract import keyspace
from runtime.contract.refusal import Refusal
from tests.conftest import padt
from tests.support.runtime_process import client_session, router

WILD_NAMES = ["*", "Lk1/**", "$*", "Tank1/cmd", "a b", "", "x" * 65]
PROGRAM = "PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"


def _project(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True)
    toml_name = name.replace("\\", "\\\\").replace('"', '\\"')
    (folder / "padt.toml").write_text(
        f'[project]\nname = "p"\n\n[resource]\nname = "{toml_name}"\n\n'
        '[[resource.program]]\nname = "Main"\nid = 1\n'
    )
    (folder / "main.st").write_text(PROGRAM)
    return folder


@pytest.mark.parametrize("name", ["*", "Lk1/**", "$*", "Tank 1"])
def test_the_compiler_refuses_a_name_that_is_no_plain_identifier(tmp_path: Path, name: str) -> None:
    compiled = padt("compile", str(_project(tmp_path / "p", name)))
    assert compiled.returncode == 1
    assert "padt.toml:5:1: error: resource name" in compiled.stdout, compiled.stdout
    assert "is not a plain identifier" in compiled.stdout and "[E0620]" in compiled.stdout


def test_the_compiler_refuses_it_in_a_configuration_too(tmp_path: Path) -> None:
    source = tmp_path / "main.st"
    name = "R" * 70  # an identifier to ST, but longer than a key chunk may be
    source.write_text(
        f"{PROGRAM}CONFIGURATION C\nRESOURCE {name} ON PLC\nTASK t(INTERVAL := T#10ms);\n"
        "PROGRAM Main WITH t : Main;\nEND_RESOURCE\nEND_CONFIGURATION\n"
    )
    compiled = padt("compile", str(source))
    assert compiled.returncode == 1
    assert "main.st:6:10: error: resource name" in compiled.stdout, compiled.stdout
    assert "[E0620]" in compiled.stdout
    assert padt("compile", str(_project(tmp_path / "fine", "Line1_Tank-2"))).returncode == 0


def test_the_runtime_does_not_start_under_such_a_name(tmp_path: Path) -> None:
    for name in ["*", "Lk1/**", "$*"]:
        state = tmp_path / "state"
        started = padt("runtime", "--resource", name, "--state-dir", str(state), timeout=60)
        assert started.returncode == 2
        assert f"resource name '{name}' is not a plain identifier" in started.stderr
        assert "Traceback" not in started.stderr
        assert not state.exists()  # refused before it made anything


def test_clients_refuse_it_before_asking_anything(zenoh_endpoint: str) -> None:
    asked: list[str] = []
    lock = threading.Lock()

    def listen(query: zenoh.Query) -> None:
        with lock:
            asked.append(str(query.key_expr))

    with router(zenoh_endpoint), client_session(zenoh_endpoint) as session:
        queryable = session.declare_queryable("padt/v2/**", listen)
        try:
            for name in ["*", "Lk1/**", "$*"]:
                for command in (["status"], ["stop"], ["values"], ["events"]):
                    done = padt(*command, "--resource", name, "--zenoh", zenoh_endpoint)
                    assert done.returncode == 2, done.stderr
                    assert "is not a plain identifier" in done.stderr
                    assert "Traceback" not in done.stderr
            # the listener hears a genuine client, so its silence above means something
            padt("status", "--resource", "Tank1", "--zenoh", zenoh_endpoint, timeout=120)
        finally:
            queryable.undeclare()
    assert asked == ["padt/v2/res/Tank1/cmd"] * len(asked) and asked


@pytest.mark.parametrize("name", WILD_NAMES)
def test_no_key_of_the_key_space_is_made_for_such_a_name(name: str) -> None:
    keys = [keyspace.command_key, keyspace.status_key, keyspace.events_key, keyspace.alive_key]
    for key_for in [*keys, keyspace.watches_key_expr]:
        with pytest.raises(Refusal) as refused:
            key_for(name)
        assert refused.value.code == "bad_name"
    for make in (keyspace.watch_key, keyspace.watcher_key):
        with pytest.raises(Refusal):
            make(name, "ab12")
        with pytest.raises(Refusal):
            make("Tank1", name or "*")  # a watch set id is one plain chunk as well
    assert keyspace.any_resource(keyspace.alive_key) == "padt/v2/res/*/alive"
    assert keyspace.watches_key_expr("Tank1") == "padt/v2/res/Tank1/watch/*"
