"""Hostile files for the file readers of padt: recordings (MCAP) and backups (zip), built
byte by byte in the test, with the parts a hostile run changes (attachments, messages,
chunks that decompress to far more than they say, archive entries that climb out of their
folder) and checksums and digests redone, as an attacker who read the code would."""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import zipfile
import zlib
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import (
    Attachment,
    Channel,
    Chunk,
    DataEnd,
    Footer,
    Header,
    Message,
    Metadata,
    Schema,
)

from backend.engineering.backup import BackupInfo, write_backup
from backend.engineering.project import compile_project, load_project
from runtime.clock import VirtualClock
from runtime.contract.artifact import Artifact
from runtime.contract.recording import (
    ARTIFACT_ATTACHMENT,
    INPUTS_SCHEMA,
    METADATA,
    START_ATTACHMENT,
    VALUES_SCHEMA,
    RecordingHeader,
    inputs_topic,
    values_topic,
)
from runtime.recorder import start_state
from runtime.resource import Resource
from tests.support.crafted_units import with_form

REPO = Path(__file__).resolve().parent.parent.parent
MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])
GIB = 1 << 30

PADT_TOML = """\
[project]
name = "Hostile"

[resource]
name = "Cell"

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
"""

MAIN_ST = """\
PROGRAM Main
VAR
  count : DINT := 0;
END_VAR
count := count + 1;
END_PROGRAM
"""


def project(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "padt.toml").write_text(PADT_TOML)
    (folder / "main.st").write_text(MAIN_ST)
    return folder


def compiled(folder: Path) -> Artifact:
    artifact = compile_project(load_project([folder])).artifact
    assert artifact is not None
    return artifact


def unloadable(artifact: Artifact) -> Artifact:
    """The artifact with a unit whose form its loader refuses (its CRCs redone, so only
    loading finds it)."""
    return with_form(artifact, artifact.pous[0].form[:-1])


def start_json(artifact: Artifact) -> bytes:
    """A genuine start state of `artifact`, as the recorder writes it."""
    resource = Resource(artifact.resource.name, VirtualClock(start_ns=0, epoch_ns=0))
    resource.load(artifact)
    return json.dumps(asdict(start_state(resource))).encode()


@dataclass(frozen=True)
class Part:
    """A message on the values or inputs channel, as raw bytes."""

    channel: str  # values | inputs
    data: bytes


def recording(
    artifact: Artifact,
    *,
    artifact_text: str | None = None,
    start: bytes | None = None,
    variables: Sequence[tuple[str, str]] = (("Main.count", "DINT"),),
    messages: Sequence[Part] = (),
    chunks: Sequence[Chunk] = (),
) -> bytes:
    """An all-inputs recording of `artifact` with no cycle of its own: its header, its
    two attachments (given or genuine), then `messages` and `chunks` as given."""
    header = RecordingHeader(
        resource=artifact.resource.name,
        project=artifact.project,
        crc=artifact.crc,
        variables=list(variables),
        all_inputs=True,
        started_ns=1,
        recording="hostile",
        part=1,
    )
    out = RecordBuilder()
    out.write(MAGIC)
    Header(profile="", library="hostile").write(out)
    Metadata(name=METADATA, metadata=header.metadata()).write(out)
    kinds = {"values": (1, VALUES_SCHEMA, values_topic), "inputs": (2, INPUTS_SCHEMA, inputs_topic)}
    for number, schema, topic in kinds.values():
        Schema(id=number, name=schema, encoding="jsonschema", data=b"{}").write(out)
        Channel(
            id=number,
            schema_id=number,
            topic=topic(header.resource),
            message_encoding="json",
            metadata={},
        ).write(out)
    text = (artifact_text if artifact_text is not None else artifact.to_json()).encode()
    attached = {ARTIFACT_ATTACHMENT: text, START_ATTACHMENT: start or start_json(artifact)}
    for name, data in attached.items():
        Attachment(1, 1, name, "application/json", data).write(out)
    for n, part in enumerate(messages, 1):
        Message(kinds[part.channel][0], n, part.data, n, n).write(out)
    for chunk in chunks:
        chunk.write(out)
    DataEnd(0).write(out)
    Footer(0, 0, 0).write(out)
    out.write(MAGIC)
    whole: bytes = out.end()  # type: ignore[no-untyped-call]
    return whole


def zeros_zstd(size: int, declared: int) -> Chunk:
    """A zstd chunk of `size` zero bytes (a few kB) that declares `declared` bytes."""
    compressor = zstandard.ZstdCompressor(level=3)
    writer = compressor.compressobj(size=size)
    block = bytes(1 << 20)
    pieces = [writer.compress(block) for _ in range(size // len(block))]
    pieces.append(writer.flush())
    return _chunk("zstd", b"".join(pieces), declared)


def zeros_lz4(size: int, declared: int) -> Chunk:
    import lz4.frame  # type: ignore[import-untyped]

    compressor = lz4.frame.LZ4FrameCompressor()
    block = bytes(1 << 20)
    pieces = [compressor.begin()]
    pieces += [compressor.compress(block) for _ in range(size // len(block))]
    pieces.append(compressor.flush())
    return _chunk("lz4", b"".join(pieces), declared)


def _chunk(compression: str, data: bytes, declared: int) -> Chunk:
    return Chunk(
        compression=compression,
        data=data,
        message_start_time=0,
        message_end_time=0,
        uncompressed_crc=0,
        uncompressed_size=declared,
    )


def backup(folder: Path, project_folder: Path) -> Path:
    """A genuine backup of the project, as `padt load` keeps it."""
    artifact = compiled(project_folder)
    sources = {"main.st": (project_folder / "main.st").read_text()}
    info = BackupInfo("Hostile", "1", "Cell", "load", "padt load")
    return write_backup(
        folder, info, artifact.to_json(), sources, (project_folder / "padt.toml").read_text()
    )


def rewritten(
    original: Path,
    target: Path,
    extra: dict[str, bytes],
    manifest: bytes | None = None,
    mode: int = 0o100644,
) -> Path:
    """The backup with `extra` entries (names as given, unchecked, of Unix `mode`) and the
    manifest's digests redone for them, or the manifest replaced by `manifest`."""
    with zipfile.ZipFile(original) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    recorded = json.loads(entries["MANIFEST.json"])
    for name, data in extra.items():
        recorded["files"][name.removeprefix("project/")] = hashlib.sha256(data).hexdigest()
    entries.update(extra)
    entries["MANIFEST.json"] = manifest if manifest is not None else json.dumps(recorded).encode()
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in entries.items():
            info = zipfile.ZipInfo(name)
            info.external_attr = (mode if name in extra else 0o100644) << 16
            archive.writestr(info, data, compress_type=zipfile.ZIP_DEFLATED)
    return target


def zip_bomb(original: Path, target: Path, size: int, declared: int | None = None) -> Path:
    """The backup with a source entry of `size` zero bytes (1 GB deflates to about 1 MB),
    its digest redone; with `declared`, its headers claim that size instead (a lying
    header)."""
    with zipfile.ZipFile(original) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    recorded = json.loads(entries["MANIFEST.json"])
    digest, deflated, crc = hashlib.sha256(), zlib.compressobj(9, zlib.DEFLATED, -15), 0
    block, pieces = bytes(1 << 20), []
    for _ in range(size // len(block)):
        digest.update(block)
        crc = zlib.crc32(block, crc)
        pieces.append(deflated.compress(block))
    pieces.append(deflated.flush())
    data = b"".join(pieces)
    recorded["files"]["bomb.st"] = digest.hexdigest()
    entries["MANIFEST.json"] = json.dumps(recorded).encode()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, content in entries.items():
            archive.writestr(name, content)
    body = buffer.getvalue()
    # the bomb's entry written by hand, so that nothing here holds the gigabyte
    stated = size if declared is None else declared
    bomb_name = b"project/bomb.st"
    local = (
        b"PK\x03\x04"
        + (20).to_bytes(2, "little")
        + bytes(2)
        + (8).to_bytes(2, "little")
        + bytes(4)
        + crc.to_bytes(4, "little")
        + len(data).to_bytes(4, "little")
        + stated.to_bytes(4, "little")
        + len(bomb_name).to_bytes(2, "little")
        + bytes(2)
        + bomb_name
    )
    directory_at = body.rindex(b"PK\x05\x06")
    end = body[directory_at:]
    first_entry = int.from_bytes(end[16:20], "little")
    files, directory = body[:first_entry], body[first_entry:directory_at]
    central = (
        b"PK\x01\x02"
        + (20).to_bytes(2, "little")
        + (20).to_bytes(2, "little")
        + bytes(2)
        + (8).to_bytes(2, "little")
        + bytes(4)
        + crc.to_bytes(4, "little")
        + len(data).to_bytes(4, "little")
        + stated.to_bytes(4, "little")
        + len(bomb_name).to_bytes(2, "little")
        + bytes(8)
        + (0o644 << 16).to_bytes(4, "little")
        + len(files).to_bytes(4, "little")
        + bomb_name
    )
    count = int.from_bytes(end[10:12], "little") + 1
    directory += central
    new_end = (
        b"PK\x05\x06"
        + bytes(4)
        + count.to_bytes(2, "little")
        + count.to_bytes(2, "little")
        + len(directory).to_bytes(4, "little")
        + (len(files) + len(local) + len(data)).to_bytes(4, "little")
        + bytes(2)
    )
    target.write_bytes(files + local + data + directory + new_end)
    return target


@dataclass(frozen=True)
class Run:
    returncode: int
    stdout: str
    stderr: str
    max_rss_mb: float  # the child's own peak resident memory


# Runs its arguments as a child and writes that child's peak memory (KiB) to the file named
# first. A child started by the test process itself would not do: Linux starts a child's
# peak at the peak of the process it was forked from, and a test process that has run the
# suite holds hundreds of MB; this launcher holds a few.
_MEASURING_LAUNCHER = """
import os, subprocess, sys
child = subprocess.Popen(sys.argv[2:])
_pid, status, usage = os.wait4(child.pid, 0)
with open(sys.argv[1], "w") as report:
    report.write(str(usage.ru_maxrss))
sys.exit(os.waitstatus_to_exitcode(status))
"""


def padt_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "padt.cli", *args]


def padt_measured(*args: str, env: dict[str, str] | None = None, timeout: float = 600) -> Run:
    """`padt ARGS` in a child process whose own peak memory is measured (through
    `_MEASURING_LAUNCHER`, so that it is that child's alone)."""
    with (
        tempfile.TemporaryFile() as out,
        tempfile.TemporaryFile() as err,
        tempfile.NamedTemporaryFile("r") as peak,
    ):
        process = subprocess.Popen(
            [sys.executable, "-c", _MEASURING_LAUNCHER, peak.name, *padt_command(*args)],
            cwd=REPO,
            env={**os.environ, **(env or {})},
            stdout=out,
            stderr=err,
            start_new_session=True,  # a timeout ends the launcher and padt alike
        )
        killer = threading.Timer(timeout, os.killpg, (process.pid, signal.SIGKILL))
        killer.start()
        try:
            _pid, status, _usage = os.wait4(process.pid, 0)
        finally:
            killer.cancel()
        process.returncode = os.waitstatus_to_exitcode(status)
        peak_kib = peak.read()
        out.seek(0)
        err.seek(0)
        return Run(
            process.returncode,
            out.read().decode(errors="replace"),
            err.read().decode(errors="replace"),
            int(peak_kib) / 1024 if peak_kib else math.inf,  # KiB on Linux
        )
