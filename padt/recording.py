"""`padt record` and `padt recordings`: record variables of a running resource into MCAP
files and fetch them, from a terminal or a CI job (docs/cli.md). The resource records
into its state folder; `padt record` waits until the recording is done (its cycles or
seconds reached, or Ctrl-C), downloads its files and deletes them there. `padt
recordings` lists what the resource keeps, and downloads or deletes one of them."""

from __future__ import annotations

import argparse
import json
import sys
from datetime import UTC, datetime
from pathlib import Path

from backend.engineering import recordings
from backend.engineering.recordings import RecordingSpec, TriggerError
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from padt.online import Failed, resource_client, run, table
from runtime.contract.protocol import RecordingInfo
from runtime.contract.recording import read_recording
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
                f"recording {started.id}: {started.variables} "
                f"variable{'' if started.variables == 1 else 's'}"
                f"{' and all inputs' if started.all_inputs else ''}, {until}",
                file=sys.stderr,
                flush=True,
            )
            try:
                ended = recordings.wait_until_ended(client, started.id, stop_request.event.is_set)
            except ResourceUnreachable as exc:
                raise Failed(
                    f"{exc}; recording {started.id} goes on in the resource: fetch it later "
                    f"with padt recordings --download {started.id} -o {args.output}"
                ) from None
            written = _fetch(client, ended, args.output)
            if not args.keep:
                recordings.delete(client, ended.id)
        if not written:  # stopped before its first cycle, or its trigger never fired
            why = f"failed: {ended.error}" if ended.state == "failed" else "wrote no file"
            raise Failed(f"recording {ended.id} {why}: nothing was recorded")
        print(f"recorded {_counts(ended, written)} -> {_files(written)}")
        if ended.state == "failed":  # what it wrote before is kept all the same
            raise Failed(f"recording {ended.id} failed: {ended.error or 'no reason given'}")
        if ended.error:  # cut short, e.g. by a reload that removed a recorded variable
            print(f"padt record: {ended.error}", file=sys.stderr)
        return 0

    return run("record", args, body)


def _counts(recording: RecordingInfo, written: list[tuple[Path, int]]) -> str:
    """`50 cycles, 0 dropped`; for a recording the runtime knows by its files only (it
    restarted meanwhile: no start time, no counts) the cycles counted in the files."""
    if recording.started_ns > 0:
        return f"{recording.cycles} cycles, {recording.dropped} dropped"
    counted = sum(len(read_recording(path).rows) for path, _ in written)
    return f"{counted} cycles (the runtime restarted: dropped ones unknown)"


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
    """Every file of the recording to `output`, `output-2`...; each streamed to a `.part`
    file and renamed when whole, so a download that breaks off leaves no file that looks
    complete, and a file of gigabytes never sits in memory."""
    written: list[tuple[Path, int]] = []
    for name in recordings.file_names(client, recording.id):
        path = part_path(output, recordings.part_number(name))
        partial = path.with_name(path.name + ".part")
        try:
            size, pieces = recordings.download_chunks(client, name)
            with partial.open("wb") as stream:
                for piece in pieces:
                    stream.write(piece)
            partial.replace(path)
        except OSError as exc:
            partial.unlink(missing_ok=True)
            raise Failed(f"cannot write {path}: {exc.strerror or exc}") from None
        except BaseException:
            partial.unlink(missing_ok=True)
            raise
        written.append((path, size))
    return written


def _size(size: int) -> str:
    if size < 1000:
        return f"{size} bytes"
    if size < 1_000_000:
        return f"{size / 1000:.1f} kB"
    return f"{size / 1_000_000:.1f} MB"


def kept_recordings(args: argparse.Namespace) -> int:
    """The recordings a resource keeps; or one of them downloaded, or deleted."""

    def body() -> int:
        if args.download is not None and args.output is None:
            raise Failed("--download needs -o FILE.mcap", 2)
        with resource_client(args) as client:
            if args.download is not None:
                found = recordings.find(client, args.download)
                written = _fetch(client, found, args.output)
                if not written:
                    raise Failed(f"recording {found.id} has no file")
                print(f"downloaded {found.id} -> {_files(written)}")
                return 0
            if args.delete is not None:
                left = recordings.delete(client, args.delete)
                print(f"deleted {args.delete}; {len(left)} recordings left")
                return 0
            found_all = recordings.list_recordings(client)
        if args.json:
            print(json.dumps(encode(found_all), indent=2, sort_keys=True))
            return 0
        rows = [
            [
                r.id,
                r.state,
                str(r.variables) + (" + inputs" if r.all_inputs else ""),
                str(r.cycles),
                str(r.dropped),
                _calendar(r.started_ns),
                " ".join(f"{f.name} ({_size(f.size)})" for f in r.files),
            ]
            for r in found_all
        ]
        header = ["id", "state", "variables", "cycles", "dropped", "started (UTC)", "files"]
        print("\n".join(table(header, rows)))
        return 0

    return run("recordings", args, body)


def _calendar(time_ns: int) -> str:
    # a recording of an earlier run of the runtime is known by its files only
    if time_ns <= 0:
        return "-"
    return datetime.fromtimestamp(time_ns / 1e9, UTC).strftime("%Y-%m-%d %H:%M:%S")


def _files(written: list[tuple[Path, int]]) -> str:
    """`x.mcap, x-2.mcap (1.2 MB)`."""
    names = ", ".join(str(path) for path, _ in written)
    return f"{names} ({_size(sum(size for _, size in written))})"
