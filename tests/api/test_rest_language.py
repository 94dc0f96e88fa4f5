"""The language services over the REST API, on a real HTTP port: a file's diagnostics with
the text as the client has it, completion, hover, definition, references and the outline;
Read-only may ask; a file outside the project, an unknown project and a bad place are
structured refusals."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.api.test_rest_api import error
from tests.support.rest_plant import PROGRAM, Plant, plant

ROUTE = "/api/projects/plant/language/"
TEXT = PROGRAM.format(extra="")  # the file plant.st of project `plant` as saved
LINES = TEXT.splitlines()


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("rest-language")) as found:
        yield found


def ask(site: Plant, service: str, body: dict[str, Any], user: str = "reader") -> Any:
    reply = site.call("POST", ROUTE + service, site.token(user), json=body)
    assert reply.status_code == 200, reply.text
    return reply.json()


def at(line_start: str, word: str) -> dict[str, int]:
    """The place (from 1, in characters) of `word` in the line that starts so."""
    line = next(i for i, text in enumerate(LINES) if text.startswith(line_start))
    return {"line": line + 1, "col": LINES[line].index(word) + 1}


def test_diagnostics_of_the_saved_file_and_of_the_text_being_typed(site: Plant) -> None:
    assert ask(site, "diagnostics", {"file": "plant.st"}) == {"diagnostics": []}
    typed = TEXT.replace("flag := n > 10;", "flag := n + 10;")
    [found] = ask(site, "diagnostics", {"file": "plant.st", "text": typed})["diagnostics"]
    plus = at("flag :=", "flag")["line"], typed.splitlines()[4].index("+") + 1
    assert found["code"] == "E0209" and found["severity"] == "error"
    assert "DINT" in found["message"] and "BOOL" in found["message"]
    assert (found["line"], found["col"], found["end_col"]) == (*plus, plus[1] + 1)
    # the text was the client's only: the file and the next answer are as saved
    assert (site.projects / "plant" / "plant.st").read_text() == TEXT
    assert ask(site, "diagnostics", {"file": "plant.st"}) == {"diagnostics": []}


def test_padt_toml_as_the_client_has_it(site: Plant) -> None:
    saved = (site.projects / "plant" / "padt.toml").read_text()
    assert ask(site, "diagnostics", {"file": "padt.toml"}) == {"diagnostics": []}
    typed = saved.replace('pou = "P"', 'pou = "Q"')
    [found] = ask(site, "diagnostics", {"file": "padt.toml", "text": typed})["diagnostics"]
    assert found["code"] == "E0601" and "no PROGRAM 'Q'" in found["message"]
    [unread] = ask(site, "diagnostics", {"file": "padt.toml", "text": "[resource"})["diagnostics"]
    assert unread["severity"] == "error" and "padt.toml" in unread["message"]


def test_completion_hover_definition_references_and_outline(site: Plant) -> None:
    typed = TEXT.replace("flag := n > 10;", "flag := n > lim")
    place = at("flag :=", "flag")
    place["col"] += len("flag := n > lim")
    items = ask(site, "completion", {"file": "plant.st", "text": typed, **place})["items"]
    assert items[0]["label"] == "limit" and items[0]["kind"] == "variable"
    assert items[0]["detail"].endswith("DINT")

    used = {"file": "plant.st", **at("IF n > limit", "limit")}
    hover = ask(site, "hover", used)["hover"]
    assert "limit : DINT := 1000000" in hover["signature"]
    assert hover["declared"]["file"] == "plant.st" and hover["declared"]["line"] == 2

    named = at("VAR n", "limit")
    declared = ask(site, "definition", used)["location"]
    assert declared == {"file": "plant.st", **named, "end_line": 2, "end_col": named["col"] + 5}
    found = ask(site, "references", used)["locations"]
    assert [(f["line"], f["col"]) for f in found] == [
        (2, named["col"]),
        (used["line"], used["col"]),
    ]

    [program] = ask(site, "outline", {"file": "plant.st"})["symbols"]
    assert (program["name"], program["kind"]) == ("P", "program")
    assert [child["name"] for child in program["children"]] == ["n", "limit", "flag"]


def test_rename_gives_edits_and_writes_nothing(site: Plant) -> None:
    used = {"file": "plant.st", **at("IF n > limit", "limit")}
    found = ask(site, "rename", {**used, "new_name": "maximum"})
    [edits] = found["files"]
    assert edits["file"] == "plant.st"
    assert [(e["line"], e["new_text"]) for e in edits["edits"]] == [
        (2, "maximum"),
        (used["line"], "maximum"),
    ]
    assert (site.projects / "plant" / "plant.st").read_text() == TEXT
    reply = site.call(
        "POST", ROUTE + "rename", site.token("reader"), json={**used, "new_name": "n"}
    )
    assert "'n' already names a variable in P" in error(reply, 409, "rename")


def test_refusals(site: Plant) -> None:
    reader = site.token("reader")
    for file in ("../plant_v2/plant.st", "/etc/passwd", "missing.st", ""):
        reply = site.call("POST", ROUTE + "diagnostics", reader, json={"file": file})
        message = error(reply, 400, "path")
        assert "file" in message and str(site.projects) not in message
    reply = site.call("POST", "/api/projects/nope/language/outline", reader, json={"file": "a"})
    error(reply, 404, "unknown_project")
    error(site.call("POST", ROUTE + "outline", json={"file": "plant.st"}), 401, "unauthenticated")
    bad = {"file": "plant.st", "line": 0, "col": 1}
    error(site.call("POST", ROUTE + "hover", reader, json=bad), 400, "bad_request")
    huge = {"file": "plant.st", "line": 10**12, "col": 10**12}
    error(site.call("POST", ROUTE + "hover", reader, json=huge), 400, "bad_request")
    # a folder named like a source file: the project cannot be read, said so
    odd = site.projects / "plant_v2" / "folder.st"
    odd.mkdir()
    try:
        route = "/api/projects/plant_v2/language/outline"
        reply = site.call("POST", route, reader, json={"file": "plant.st"})
        assert "the project cannot be read" in error(reply, 422, "project")
    finally:
        odd.rmdir()
    far = {"file": "plant.st", "line": 9_999_999, "col": 9_999_999}
    assert ask(site, "hover", far) == {"hover": None}
    assert ask(site, "completion", far) == {"items": []}
