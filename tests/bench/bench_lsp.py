"""`padt lsp` as an editor waits for it: the real command started as a subprocess, spoken
to over stdio by an LSP client. After one keystroke (a character typed, then deleted: two
incremental changes, each awaited), the time until the diagnostics of that very version
arrive (the server's pause for typing, DEBOUNCE_S, included); and a completion request's
round trip. In the 2,000-line file of bench_language_services and in OSCAT BUILDING.

Run with `python -m tests.bench.bench_lsp`. It prints figures and asserts nothing about
time (machines are shared and noisy)."""

from __future__ import annotations

import asyncio
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

from lsprotocol import types
from pygls.lsp.client import LanguageClient

from padt.lsp_server import DEBOUNCE_S
from tests.bench.bench_language_services import OSCAT, two_thousand_lines

KEYSTROKES = 30
TIMEOUT_S = 120.0


class _Published:
    """The versions whose diagnostics arrived, and when."""

    def __init__(self) -> None:
        self.arrived: dict[int, float] = {}
        self.event = asyncio.Event()

    async def wait(self, version: int) -> float:
        deadline = time.perf_counter() + TIMEOUT_S
        while version not in self.arrived:
            self.event.clear()
            await asyncio.wait_for(self.event.wait(), max(0.0, deadline - time.perf_counter()))
        return self.arrived[version]


def _percentile(samples: list[float], fraction: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(len(ordered) * fraction))]


async def _measure(label: str, folder: Path, file: str) -> None:
    client = LanguageClient("bench", "1")
    published = _Published()

    @client.feature(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)  # type: ignore[untyped-decorator]
    def _arrived(params: types.PublishDiagnosticsParams) -> None:
        if params.uri.endswith(file) and params.version is not None:
            published.arrived[params.version] = time.perf_counter()
            published.event.set()

    await client.start_io(sys.executable, "-m", "padt.cli", "lsp", str(folder))
    await client.initialize_async(
        types.InitializeParams(capabilities=types.ClientCapabilities(), process_id=None)
    )
    client.initialized(types.InitializedParams())
    path = folder / file
    text = path.read_text(encoding="utf-8", errors="replace")
    uri = path.as_uri()
    started = time.perf_counter()
    client.text_document_did_open(
        types.DidOpenTextDocumentParams(types.TextDocumentItem(uri, "iecst", 1, text))
    )
    first = await published.wait(1) - started
    lines = text.splitlines()
    statements = [i for i, line in enumerate(lines) if ":=" in line and line.rstrip().endswith(";")]
    rng = random.Random(2026)
    waits: list[float] = []
    completions: list[float] = []
    version = 1
    for _ in range(KEYSTROKES):
        row = rng.choice(statements)
        col = lines[row].index(":=") - 1
        at, after = types.Position(row, col), types.Position(row, col + 1)
        for change in (
            types.TextDocumentContentChangePartial(range=types.Range(at, at), text="x"),
            types.TextDocumentContentChangePartial(range=types.Range(at, after), text=""),
        ):
            version += 1
            sent = time.perf_counter()
            client.text_document_did_change(
                types.DidChangeTextDocumentParams(
                    types.VersionedTextDocumentIdentifier(uri=uri, version=version), [change]
                )
            )
            waits.append((await published.wait(version) - sent) * 1e3)
        sent = time.perf_counter()
        await client.text_document_completion_async(
            types.CompletionParams(types.TextDocumentIdentifier(uri), at)
        )
        completions.append((time.perf_counter() - sent) * 1e3)
    await client.shutdown_async(None)
    client.exit(None)
    await client.stop()  # type: ignore[no-untyped-call]
    print(
        f"padt lsp, {label} ({len(lines):,} lines): diagnostics of a keystroke's version "
        f"p50 {statistics.median(waits):.0f} ms, p95 {_percentile(waits, 0.95):.0f} ms "
        f"({len(waits)} changes; {DEBOUNCE_S * 1e3:.0f} ms of it the pause for typing); "
        f"completion round trip p50 {statistics.median(completions):.0f} ms, "
        f"p95 {_percentile(completions, 0.95):.0f} ms; first diagnostics after opening "
        f"{first * 1e3:.0f} ms"
    )


def main() -> None:
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        (folder / "plant.st").write_text(two_thousand_lines())
        asyncio.run(_measure("a 2,000-line file", folder, "plant.st"))
    if not OSCAT.is_dir():
        print(f"OSCAT corpus absent ({OSCAT}): padt lsp OSCAT figures skipped")
        return
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        source = OSCAT / "BUILDING_1.0.st"
        (folder / source.name).write_bytes(source.read_bytes())
        asyncio.run(_measure("OSCAT BUILDING", folder, source.name))


if __name__ == "__main__":
    main()
