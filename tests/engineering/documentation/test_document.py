"""The printable documentation of a project, read back from the PDF as a reader sees it
(pdftotext from poppler-utils, page by page)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from backend.engineering.backup import BackupInfo, write_backup
from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.export import DocumentError, document
from backend.engineering.documentation.subject import load_subject
from backend.engineering.documentation.xref import xref_rows
from backend.engineering.project import compile_project, load_project
from padt.cli import main
from padt.demo import demo_project_with_accounts
from tests.conftest import REPO
from tests.engineering.documentation.filling_line import write_filling_line


def pages(pdf: Path) -> list[str]:
    """The text of each page, in reading order."""
    assert shutil.which("pdftotext"), "poppler-utils missing: run scripts/install-document-tools.sh"
    text = subprocess.run(
        ["pdftotext", "-layout", str(pdf), "-"], check=True, capture_output=True, text=True
    ).stdout
    return text.split("\f")[:-1]  # every page ends with a form feed


@pytest.fixture(scope="module")
def project(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_filling_line(tmp_path_factory.mktemp("docs") / "filling-line")


@pytest.fixture(scope="module")
def written(project: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    out = tmp_path_factory.mktemp("out")
    assert main(["docs", str(project), "-o", str(out)]) == 0
    return out / "Filling_line.html", out / "Filling_line.pdf"


def test_every_page_names_project_crc_and_page_n_of_m(project: Path, written) -> None:
    crc = compile_project(load_project([project])).artifact.crc  # type: ignore[union-attr]
    texts = pages(written[1])
    assert len(texts) >= 8
    for number, text in enumerate(texts, 1):
        assert "Filling line" in text, f"page {number}"
        assert f"CRC {crc}" in text, f"page {number}"
        assert f"page {number} of {len(texts)}" in text, f"page {number}"


def test_cover_and_contents(written) -> None:
    cover, contents = pages(written[1])[:2]
    for fact in ("Filling line", "2.1", "A. Engineer", "2026-11-20", "Line1"):
        assert fact in cover
    assert re.search(r"Filler\s+1\s+Filler\s+[0-9A-F]{8}", cover)  # a program's CRC
    # the contents give the page each part starts on (the leader, repeated whole, may
    # stop short of the title: spaces before the dots)
    found = {
        title: int(page)
        for title, page in re.findall(r"^ *(\S[^.\n]*?) *\.{3,}\s*(\d+)$", contents, re.M)
    }
    texts = pages(written[1])
    for title in ("Signal list", "Cross-reference", "Logic", "Users"):
        assert title in texts[found[title] - 1], title


def test_users_show_names_and_levels_never_hashes(project: Path, written) -> None:
    html = written[0].read_text()
    text = "".join(pages(written[1]))
    assert re.search(r"admin\s+administrator", text)
    assert re.search(r"op\s+operator", text)
    assert "scrypt" not in html and "scrypt" not in text


def test_signal_list_has_type_initial_address_and_comment(written) -> None:
    text = " ".join("".join(pages(written[1])).split())
    assert "start_button BOOL %IX0.0 globals.st:8 operator start, NO contact" in text
    assert "bottles DINT globals.st:12 bottles filled since the cold start" in text
    # I/O: the safe value of an output
    assert re.search(r"%QX0.1 conveyor_run BOOL output FALSE", text)


def test_logic_is_numbered_highlighted_and_the_sfc_drawn(written) -> None:
    html = written[0].read_text()
    assert '   25 conveyor_run := <span class="k">NOT</span> bottle_present;' in html
    svg = re.search(r'<svg[^>]*class="sfc".*?</svg>', html, re.S)
    assert svg is not None
    for shown in ("Wait", "Fill", "Settle", "OpenValve", "Count", ">P</text>", "fill_timer.Q"):
        assert shown in svg.group(0)
    text = "".join(pages(written[1]))
    assert "SFC chart of Filler" in text and "OpenValve" in text


# what the sources of the Filling line declare, read and write, line by line
EXPECTED_XREF = [
    ("bottles", "filler.st:6; globals.st:12", "filler.st:26", "filler.st:26"),
    (
        "bottle_present",
        "conveyor.st:18; filler.st:4; globals.st:9",
        "conveyor.st:25; filler.st:13, 17",
        "-",
    ),
    ("conveyor_run", "conveyor.st:19; globals.st:11", "-", "conveyor.st:25"),
    ("recipe", "filler.st:7; globals.st:13", "filler.st:20", "-"),
    ("start_button", "filler.st:3; globals.st:8", "filler.st:13", "-"),
    ("valve_open", "filler.st:5; globals.st:10", "-", "filler.st:19, 23"),
    ("Conveyor.clipped", "conveyor.st:23", "conveyor.st:26", "conveyor.st:26"),
    ("Conveyor.speed", "conveyor.st:22", "conveyor.st:26", "conveyor.st:26"),
    ("Filler.Fill", "filler.st:14", "filler.st:20", "-"),
    ("Filler.fill_timer", "filler.st:10", "filler.st:15", "filler.st:20"),
    ("Filler.Settle", "filler.st:16", "-", "-"),
    ("Filler.Wait", "filler.st:12", "-", "-"),
    ("Limit100.clipped", "conveyor.st:6", "conveyor.st:9", "conveyor.st:8"),
    ("Limit100.Limit100", "conveyor.st:1", "-", "conveyor.st:10, 12"),
    ("Limit100.x", "conveyor.st:3", "conveyor.st:8, 12", "-"),
]


def test_cross_reference_line_by_line(project: Path, written) -> None:
    rows = xref_rows(load_subject([project]))
    assert [(r[0], r[2], r[3], r[4]) for r in rows] == EXPECTED_XREF
    # and the reader finds them: each variable's row starts a line with its name, type and
    # first declaration (a long cell wraps onto the next lines of its column)
    start = next(i for i, t in enumerate(pages(written[1])) if "Every variable with" in t)
    lines = [" ".join(line.split()) for line in pages(written[1])[start].splitlines()]
    for name, declared, _, _ in EXPECTED_XREF:
        row = next(r for r in rows if r[0] == name)
        first = declared.split(";")[0].split(",")[0]
        assert any(line.startswith(f"{name} {row[1]} {first}") for line in lines), name
    text = " ".join(lines)
    assert "Filler.fill_timer TON filler.st:10 filler.st:15 filler.st:20" in text


def test_same_project_same_bytes(project: Path, written) -> None:
    again = document([project])
    assert again.html == written[0].read_text()
    assert again.pdf == written[1].read_bytes()
    info = subprocess.run(
        ["pdfinfo", str(written[1])], check=True, capture_output=True, text=True
    ).stdout
    # the project's date, never the clock
    assert re.search(r"CreationDate:\s+Fri Nov 20 00:00:00 2026 UTC", info)
    assert re.search(r"ModDate:\s+Fri Nov 20 00:00:00 2026 UTC", info)


def test_comparison_names_each_change_and_both_crcs(project: Path, tmp_path: Path) -> None:
    old = tmp_path / "old"
    shutil.copytree(project, old)
    config = (old / "padt.toml").read_text()
    config = config.replace('version = "2.1"', 'version = "2.0"')
    config = config.replace("watchdog_ms = 150", "watchdog_ms = 200")
    config = config.replace('level = "operator"', 'level = "read"')
    (old / "padt.toml").write_text(config)
    conveyor = (old / "conveyor.st").read_text().replace("speed + 5", "speed + 2")
    (old / "conveyor.st").write_text(conveyor.replace("speed : INT := 40", "speed : INT := 30"))
    old_crc = compile_project(load_project([old])).artifact.crc  # type: ignore[union-attr]
    new_crc = compile_project(load_project([project])).artifact.crc  # type: ignore[union-attr]
    assert main(["docs", str(project), "-o", str(tmp_path / "out"), "--compare", str(old)]) == 0
    texts = pages(tmp_path / "out" / "Filling_line.pdf")
    start = next(i for i, t in enumerate(texts) if "Version comparison" in t and "previous" in t)
    text = " ".join("".join(texts[start:]).split())
    assert f"configuration CRC {old_crc} {new_crc}" in text
    assert "version 2.0 2.1" in text
    assert re.search(r"POU Conveyor CRC changed [0-9A-F]{8} [0-9A-F]{8}", text)
    assert re.search(r"program Conveyor CRC changed [0-9A-F]{8} [0-9A-F]{8}", text)
    assert "parameter watchdog_ms changed 200 150" in text
    assert "user op level changed read operator" in text
    assert "variable Conveyor.speed declaration changed VAR INT := 30 VAR INT := 40" in text
    assert "-26 speed := Limit100(x := speed + 2" in text
    assert "+26 speed := Limit100(x := speed + 5" in text
    assert "-22 speed : INT := 30" in text and "+22 speed : INT := 40" in text
    assert "Filler" not in text.split("Changed source lines")[1]  # unchanged POUs stay out


def test_a_project_that_does_not_compile_is_refused(tmp_path: Path, capsys) -> None:
    (tmp_path / "bad.st").write_text("PROGRAM P\nx := 1;\nEND_PROGRAM\n")
    assert main(["docs", str(tmp_path / "bad.st"), "-o", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert "does not compile" in error and "bad.st:2:1: error: 'x' is not declared" in error
    assert not (tmp_path / "out").exists()
    with pytest.raises(DocumentError, match="no such file"):
        document([tmp_path / "missing.st"])


def test_a_backup_is_documented_and_compared(project: Path, tmp_path: Path) -> None:
    loaded = load_project([project])
    artifact = compile_project(loaded).artifact
    assert artifact is not None
    info = BackupInfo(loaded.name, loaded.version, "Line1", "load", "padt load")
    zip_path = write_backup(
        tmp_path,
        info,
        artifact.to_json(),
        {s.name: s.text for s in loaded.sources},
        (project / "padt.toml").read_text(),
        clock=lambda: 1_700_000_000_000_000_000,
    )
    from_backup = document([zip_path])
    assert from_backup.crc == artifact.crc
    assert from_backup.html == document([project]).html  # the same configuration, the same text
    compared = document([project], compare=zip_path)
    assert "No change: both versions are the same configuration." in compared.html


def test_a_tampered_backup_is_refused(project: Path, tmp_path: Path) -> None:
    loaded = load_project([project])
    artifact = compile_project(loaded).artifact
    assert artifact is not None
    sources = {s.name: s.text for s in loaded.sources}
    sources["conveyor.st"] = sources["conveyor.st"].replace("speed + 5", "speed + 6")
    info = BackupInfo(loaded.name, loaded.version, "Line1", "load", "padt load")
    zip_path = write_backup(tmp_path, info, artifact.to_json(), sources, None)
    with pytest.raises(DocumentError, match=f"the backup holds {artifact.crc}"):
        document([zip_path])


def test_the_same_bytes_in_processes_with_other_hash_seeds(project: Path, written) -> None:
    """Nothing of a set's or a dict's order leaks into the document."""
    for seed in ("1", "4242"):
        out = project.parent / f"seed-{seed}"
        subprocess.run(
            [sys.executable, "-m", "padt.cli", "docs", str(project), "-o", str(out)],
            check=True,
            capture_output=True,
            cwd=REPO,
            env={**os.environ, "PYTHONHASHSEED": seed},
        )
        assert (out / "Filling_line.html").read_bytes() == written[0].read_bytes()
        assert (out / "Filling_line.pdf").read_bytes() == written[1].read_bytes()


def test_a_hostile_project_name_and_comment_stay_text(project: Path, tmp_path: Path) -> None:
    hostile = tmp_path / "hostile"
    shutil.copytree(project, hostile)
    name = 'CRC "B" \\\\ </style><script>x()</script> PROJECT'
    config = (hostile / "padt.toml").read_text()
    (hostile / "padt.toml").write_text(config.replace('name = "Filling line"', f"name = '{name}'"))
    globals_st = (hostile / "globals.st").read_text()
    (hostile / "globals.st").write_text(
        globals_st.replace("(* filling valve *)", "(* <b>valve</b> </pre></svg> *)")
    )
    made = document([hostile])
    assert "<script>" not in made.html and "<b>valve" not in made.html
    pdf = tmp_path / "hostile.pdf"
    pdf.write_bytes(made.pdf)
    texts = pages(pdf)
    assert all(name in text for text in texts)  # in the running header, as written
    assert "<b>valve</b> </pre></svg>" in "".join(texts)


def test_the_modbus_maps_of_the_demo(tmp_path: Path) -> None:
    """The served image and each remote device with its points, as docs/modbus.md maps them."""
    assert main(["docs", str(REPO / "backend" / "projects" / "demo"), "-o", str(tmp_path)]) == 0
    text = "\n".join(pages(tmp_path / "Demo_tank.pdf"))
    field_bus = text[text.index("Field bus (Modbus TCP)") :]
    assert "served on 127.0.0.1:5020" in field_bus
    assert re.search(r"input register\s+0\s+%IW0\s+tankLevel\s+INT", field_bus)
    assert re.search(r"coil\s+0\s+%QX0\.0\s+pumpCommand\s+BOOL", field_bus)
    device = field_bus[field_bus.index("Remote device plant") :]
    assert "127.0.0.1:5021 unit 1, polled every 100 ms, lost after 500 ms" in device
    assert re.search(r"input register\s+0\s+%IW0\s+tankLevel\s+INT\s+big/big\s+-1", device)


def test_the_opcua_server_and_a_remote_server_of_the_demo(tmp_path: Path) -> None:
    """The demo's OPC UA server as `padt demo` configures it, and a remote server."""
    folder = demo_project_with_accounts(tmp_path / "state", [], opcua=True)
    with (folder / "padt.toml").open("a") as config:
        config.write(
            '\n[[opcua.device]]\nname = "filler"\nendpoint = "opc.tcp://192.168.0.20:4840"\n'
            'user = "padt"\npassword_file = "/etc/padt/filler.password"\nmode = "read"\n'
        )
    assert main(["docs", str(folder), "-o", str(tmp_path)]) == 0
    text = "\n".join(pages(tmp_path / "Demo_tank.pdf"))
    opcua = text[text.index("OPC UA\n") :]
    assert "Served on opc.tcp://127.0.0.1:4840" in opcua
    assert re.search(r"TankControl\.highLevel\s+yes", opcua)
    assert re.search(r"TankControl\s+TankControl\.highLevel", opcua)  # sorted, each once
    remote = opcua[opcua.index("Remote OPC UA server filler") :]
    described = "opc.tcp://192.168.0.20:4840, Basic256Sha256, signed and encrypted, as user padt"
    assert described in remote
    assert "/etc/padt" not in remote  # where the password is kept is the runtime's business


def test_the_exchange_with_other_resources(tmp_path: Path) -> None:
    """What a resource publishes and takes from others, with keys, periods and safe values."""
    folder = tmp_path / "packer"
    folder.mkdir()
    (folder / "main.st").write_text(
        "VAR_GLOBAL speed : REAL; fillerLevel : REAL; END_VAR\n"
        "PROGRAM Main VAR_EXTERNAL speed : REAL; END_VAR speed := 1.0; END_PROGRAM\n"
    )
    (folder / "padt.toml").write_text(
        '[project]\nname = "packer"\n[resource]\nname = "Packer"\n'
        '[[exchange.publish]]\nname = "line"\nvariables = ["speed"]\nperiod_ms = 50\n'
        '[[exchange.subscribe]]\nresource = "Filler"\npublication = "levels"\n'
        "timeout_ms = 400\n"
        '[[exchange.subscribe.variable]]\nvariable = "fillerLevel"\nfrom = "tankLevel"\n'
        "safe_value = -1.0\n"
    )
    assert main(["docs", str(folder), "-o", str(tmp_path)]) == 0
    text = "\n".join(pages(tmp_path / "packer.pdf"))
    exchange = text[text.index("Exchange with other resources") :]
    assert "On padt/v2/res/Packer/exchange/line every 50 ms" in exchange
    assert re.search(r"speed\s+REAL", exchange)
    taken = exchange[exchange.index("From Filler/levels") :]
    assert "stale after 400 ms" in " ".join(taken.split())
    assert re.search(r"fillerLevel\s+REAL\s+tankLevel\s+-1\.0", taken)


def test_loose_files_are_named_without_their_folder(project: Path) -> None:
    # given by absolute path (as `padt docs /path/a.st /path/b.st` does), the folder they
    # share is no part of the program: the cross-reference and the listings leave it out
    subject = load_subject(sorted(project.resolve().glob("*.st")))
    rows = {row[0]: row for row in xref_rows(subject)}
    assert rows["bottles"][2:] == ["filler.st:6; globals.st:12", "filler.st:26", "filler.st:26"]
    html = document_html(subject)
    assert str(project.resolve()) not in html
    assert "filler.st, lines 1 to" in html


def test_one_file_cross_reference_gives_bare_line_numbers(tmp_path: Path) -> None:
    source = tmp_path / "count.st"
    source.write_text(
        "PROGRAM Count\nVAR n : INT; on : BOOL; END_VAR\nIF on THEN\n  n := n + 1;\nEND_IF;\n"
        "END_PROGRAM\n"
    )
    subject = load_subject([source])
    assert {row[0]: row[2:] for row in xref_rows(subject)}["Count.n"] == ["2", "4", "4"]
    assert "All lines are lines of <code>count.st</code>." in document_html(subject)


OOP_SOURCE = """INTERFACE I_Device
METHOD Start : BOOL
VAR_INPUT speed : INT; END_VAR
END_METHOD
PROPERTY Level : INT
END_PROPERTY
END_INTERFACE
FUNCTION_BLOCK FB_Pump IMPLEMENTS I_Device
VAR running : BOOL; target : INT; lvl : INT; END_VAR
METHOD PUBLIC Start : BOOL
VAR_INPUT speed : INT; END_VAR
target := speed;
Start := TRUE;
END_METHOD
METHOD Clamp : INT
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT clipped : BOOL; END_VAR
Clamp := MIN(v, 50);
END_METHOD
PROPERTY PUBLIC Level : INT
GET
  Level := lvl;
END_GET
END_PROPERTY
lvl := lvl + Clamp(v := target);
END_FUNCTION_BLOCK
FUNCTION_BLOCK FINAL FB_FastPump EXTENDS FB_Pump
METHOD PUBLIC OVERRIDE Start : BOOL
VAR_INPUT speed : INT; END_VAR
Start := SUPER^.Start(speed := speed * 2);
END_METHOD
SUPER^();
END_FUNCTION_BLOCK
PROGRAM Main
VAR pump : FB_FastPump; dev : I_Device; ok : BOOL; END_VAR
dev := pump;
ok := dev.Start(speed := 5);
pump();
END_PROGRAM
"""


def test_blocks_show_lineage_methods_and_properties_and_interfaces_their_own(
    tmp_path: Path,
) -> None:
    source = tmp_path / "pumps.st"
    source.write_text(OOP_SOURCE)
    assert main(["docs", str(source), "-o", str(tmp_path / "out")]) == 0
    text = "\n".join(pages(tmp_path / "out" / "pumps.pdf"))
    interfaces = text[text.index("POU interfaces\n") : text.index("\n Logic\n")]
    fast = interfaces[interfaces.index("FUNCTION_BLOCK FB_FastPump\n") :]
    assert "none" not in fast.split("FUNCTION_BLOCK FB_Pump")[0]
    assert "FINAL · extends FB_Pump" in fast.splitlines()[1]
    assert re.search(r"Start +PUBLIC OVERRIDE +BOOL +IN speed : INT", fast)
    pump = interfaces[interfaces.index("FUNCTION_BLOCK FB_Pump\n") :]
    assert "implements I_Device" in pump.splitlines()[1]
    # a method without an access specifier is PROTECTED, as the compiler reads it
    assert re.search(r"Clamp +PROTECTED +INT +IN v : INT; OUT clipped : BOOL", pump)
    assert re.search(r"Level +PUBLIC +INT +GET\n", pump)
    device = interfaces[interfaces.index("INTERFACE I_Device\n") :]
    assert re.search(r"Start +PUBLIC +BOOL +IN speed : INT", device)
    assert re.search(r"Level +PUBLIC +INT +GET, SET \(prototype\)", device)
    # the interface's source is listed with the POUs', and in the contents
    logic = text[text.index("\n Logic\n") :]
    assert re.search(r"INTERFACE I_Device\n pumps.st, lines 1 to 7\n +1 INTERFACE I_Device", logic)
    contents = text[text.index("Contents") : text.index("POU interfaces\n")]
    assert contents.count("INTERFACE I_Device") == 2
