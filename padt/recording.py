"""`padt record` and `padt recordings`: record variables of a running resource into MCAP
files and fetch them, from a terminal or a CI job (docs/cli.md, docs/recording.md). The
resource records into its state folder; this waits until the recording is done (its
cycles or seconds reached, or Ctrl-C), downloads its files and deletes them there."""

from __future__ import annotations

import argparse
import json
import sys
from datetime import UTC, datetime
from pathlib import Path

from backend.engineering import recordings
from backend.engineering.recordings import RecordingSpec, TriggerError
from backend.engineering.resource_client import ResourceClient
from padt.online import Failed, resource_client, run, table
from runtime.contract.protocol import RecordingInfo
from runtime.contract.stop_request import StopRequest
from runtime.contract.wire import encode


def spec_of(args: argparse.Namespace) -> RecordingSpec:
    if not args.var and not args.all_inputs:
        raise Failed("nothing to record: name variables with --var, or give --all-inputs", 2)
    if args.pre_cycles and args.trigger is None:
        raise Failed("--pre-cycles needs a --trigger", 2)
    spec = RecordingSpec(
        variables=tuple(args.var),
        all_inputs=args.all_inputs,
        trigger=args.trigger,
        pre_cycles=args.pre_cycles,
        cycles=args.cycles,
        seconds=args.seconds,
        rotate_mb=args.rotate_mb,
        rotate_s=args.rotate_s,
    )
    try:
        spec.command()
    except TriggerError as exc:
        raise Failed(f"--trigger: {exc}", 2) from None
    return spec


def part_path(output: Path, part: int) -> Path:
    """FILE.mcap for the first file of a recording, FILE-2.mcap, FILE-3.mcap... after it."""
    if part == 1:
        return output
    return output.with_name(f"{output.stem}-{part}{output.suffix}")


def record(args: argparse.Namespace) -> int:
    def body() -> int:
        spec = spec_of(args)  # bad options end the command before anything starts
        stop_request = StopRequest()
        with resource_client(args) as client:
            started = recordings.start(client, spec)
            until = _until(args)
            print(
                f"recording {started.id}: {started.variables} variables"
                f"{' and all inputs' if started.all_inputs else ''}, {until}",
                file=sys.stderr,
                flush=True,
            )
            ended = recordings.wait_until_ended(client, started.id, stop_request.event.is_set)
            written = _fetch(client, ended, args.output)
            if not args.keep:
                recordings.delete(client, ended.id)
        if not written:  # stopped before its first cycle, or its trigger never fired
            why = f"failed: {ended.error}" if ended.state == "failed" else "wrote no file"
            raise Failed(f"recording {ended.id} {why}: nothing was recorded")
        names = ", ".join(str(path) for path, _ in written)
        size = sum(size for _, size in written)
        print(f"recorded {ended.cycles} cycles, {ended.dropped} dropped -> {names} ({_size(size)})")
        if ended.state == "failed":  # what it wrote before is kept all the same
            raise Failed(f"recording {ended.id} failed: {ended.error or 'no reason given'}")
        if ended.error:  # cut short, e.g. by a reload that removed a recorded variable
            print(f"padt record: {ended.error}", file=sys.stderr)
        return 0

    return run("record", args, body)


def _until(args: argparse.Namespace) -> str:
    trigger = f"after {args.trigger} becomes true, " if args.trigger else ""
    if args.cycles is not None:
        return f"{trigger}for {args.cycles} cycles (Ctrl-C stops it)"
    if args.seconds is not None:
        return f"{trigger}for {args.seconds} s (Ctrl-C stops it)"
    return f"{trigger}until Ctrl-C"


def _fetch(
    client: ResourceClient, recording: RecordingInfo, output: Path
) -> list[tuple[Path, int]]:
    """Every file of the recording to `output`, `output-2`...; each written whole or not at
    all (a download that breaks off leaves no file that looks complete)."""
    written: list[tuple[Path, int]] = []
    for name, data in recordings.download_recording(client, recording.id):
        path = part_path(output, recordings.part_number(name))
        partial = path.with_name(path.name + ".part")
        try:
            partial.write_bytes(data)
            partial.replace(path)
        except OSError as exc:
            raise Failed(f"cannot write {path}: {exc.strerror or exc}") from None
        written.append((path, len(data)))
    return written


def _size(size: int) -> str:
    if size < 1000:
        return f"{size} bytes"
    if size < 1_000_000:
        return f"{size / 1000:.1f} kB"
    return f"{size / 1_000_000:.1f} MB"


def recordings_list(args: argparse.Namespace) -> int:
    def body() -> int:
        with resource_client(args) as client:
            found = recordings.list_recordings(client)
        if args.json:
            print(json.dumps(encode(found), indent=2, sort_keys=True))
            return 0
        rows = [
            [
                r.id,
                r.state,
                str(r.variables) + (" + inputs" if r.all_inputs else ""),
                str(r.cycles),
                str(r.dropped),
                datetime.fromtimestamp(r.started_ns / 1e9, UTC).strftime("%Y-%m-%d %H:%M:%S"),
                " ".join(f"{f.name} ({_size(f.size)})" for f in r.files),
            ]
            for r in found
        ]
        header = ["id", "state", "variables", "cycles", "dropped", "started (UTC)", "files"]
        print("\n".join(table(header, rows)))
        return 0

    return run("recordings", args, body)
