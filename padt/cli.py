"""`padt`: the command line. Each subcommand lives with the part it belongs to.

Subcommands import their parts when they run: `padt --help` and the light commands must
not pay for the compiler, Zenoh or the UI. docs/cli.md documents every command.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from runtime.contract.keyspace import resource_argument
from runtime.contract.session_options import RouterUnreachable, add_zenoh_options


def _compile(args: argparse.Namespace) -> int:
    from backend.engineering.project import (
        ProjectError,
        compile_project,
        for_resource,
        load_project,
    )

    try:
        project = for_resource(load_project(args.paths), args.as_resource)
    except ProjectError as exc:
        print(f"padt compile: {exc}", file=sys.stderr)
        return 2
    result = compile_project(project)
    artifact = result.artifact
    if args.json:
        print(json.dumps(result.as_json(), indent=2, sort_keys=True))
    else:
        for diagnostic in result.diagnostics:
            print(diagnostic)
        if artifact is not None:
            for pou in artifact.pous:
                print(f"POU {pou.name}: CRC {pou.crc}")
            for program in artifact.programs:
                print(f"program {program.name}: CRC {program.crc}")
            print(f"configuration CRC {artifact.crc}")
    if args.output is not None and artifact is not None:
        args.output.write_text(artifact.to_json())
    return 0 if result.ok else 1


def _docs(args: argparse.Namespace) -> int:
    from backend.engineering.documentation.batch import (
        DocumentError,
        default_jobs,
        document_all,
        requests_of,
        write_all,
    )

    try:
        requests = requests_of(args.paths, args.each, args.compare)
    except DocumentError as exc:
        print(f"padt docs: {exc}", file=sys.stderr)
        return 2
    outcomes = document_all(requests, args.jobs or default_jobs())
    told = write_all(outcomes, args.output)
    for written, text in told:
        print(text if written else f"padt docs: {text}", file=sys.stdout if written else sys.stderr)
    failed = sum(not written for written, _ in told)
    if failed and len(told) > 1:
        print(f"padt docs: {failed} of {len(told)} not documented", file=sys.stderr)
    return 2 if failed else 0


# `padt replay` exit codes
REPLAY_DIFFERS, REPLAY_CANNOT, REPLAY_COMPILE_ERRORS = 1, 2, 3


def _replay(args: argparse.Namespace) -> int:
    from backend.engineering.project import ProjectError, compile_project, load_project
    from backend.engineering.replay import ReplayError, read_parts, replay
    from backend.engineering.tiers import one_tier
    from runtime.contract.recording import RecordingUnreadable

    try:
        recording = read_parts(args.recording)
        project = load_project(args.paths)
    except (OSError, RecordingUnreadable, ProjectError) as exc:
        print(f"padt replay: {exc}", file=sys.stderr)
        return REPLAY_CANNOT
    result = compile_project(project)
    for diagnostic in result.diagnostics:
        print(diagnostic, file=sys.stderr)
    if result.artifact is None:
        return REPLAY_COMPILE_ERRORS
    if result.artifact.resource.name != recording.header.resource:
        print(
            f"padt replay: the recording is of resource {recording.header.resource}, "
            f"the project's is {result.artifact.resource.name}",
            file=sys.stderr,
        )
        return REPLAY_CANNOT
    native, note = one_tier(args.tier)
    if note:
        print(f"padt replay: {note}", file=sys.stderr)
    try:
        outcome = replay(recording, result.artifact, native)
    except ReplayError as exc:
        print(f"padt replay: {exc}", file=sys.stderr)
        return REPLAY_CANNOT
    for line in outcome.left_as_python:
        print(f"padt replay: {line}", file=sys.stderr)
    if outcome.reloaded:
        print(
            f"padt replay: recorded configuration {outcome.recorded_crc}, replayed with "
            f"{outcome.replayed_crc} (values carried over as by a reload)",
            file=sys.stderr,
        )
    if not recording.complete:
        print(
            f"padt replay: the file was cut short ({recording.problem}); "
            "compared up to its last whole chunk",
            file=sys.stderr,
        )
    print(outcome.summary())
    return 0 if outcome.difference is None else REPLAY_DIFFERS


def _exec(args: argparse.Namespace) -> int:
    from backend.engineering.run_once import run_entry
    from backend.engineering.tiers import one_tier

    native, note = one_tier(args.tier)
    if note:
        print(f"padt exec: {note}", file=sys.stderr)
    return run_entry(args.file, args.entry, native)


# `padt sim` exit codes past 0 (ran), 1 (compile errors) and 2 (bad options or project)
SIM_PROGRAM_ERROR = 3  # a program went to ERROR (run-time error, program watchdog)
SIM_ERROR_STOP = 4  # the resource went to ERROR STOP (its watchdog: an endless loop)


def _sim(args: argparse.Namespace) -> int:
    import logging

    from backend.engineering.project import ProjectError, compile_project, load_project
    from backend.engineering.simulation import (
        Plan,
        SimulationError,
        parse_setting,
        prepare,
        run,
        trace_names,
    )
    from backend.engineering.tiers import left_as_python, one_tier

    try:
        project = load_project(args.paths)
        plan = Plan(
            cycles=args.cycles,
            cycle_ms=args.cycle_ms,
            settings=tuple(parse_setting(text) for text in args.set),
            trace=trace_names(args.trace),
        )
    except (ProjectError, SimulationError) as exc:
        print(f"padt sim: {exc}", file=sys.stderr)
        return 2
    result = compile_project(project)
    for diagnostic in result.diagnostics:
        print(diagnostic, file=sys.stderr)
    if result.artifact is None:
        return 1
    native, note = one_tier(args.tier)
    if note:
        print(f"padt sim: {note}", file=sys.stderr)
    try:
        simulation = prepare(result.artifact, plan, native)
    except SimulationError as exc:
        print(f"padt sim: {exc}", file=sys.stderr)
        return 2
    for line in left_as_python(simulation.resource.native_report):
        print(f"padt sim: {line}", file=sys.stderr)
    # sim reports program faults itself, one line each; the resource's log would repeat them
    resource_log = logging.getLogger("runtime.resource")
    resource_log.addHandler(logging.NullHandler())
    resource_log.propagate = False
    faulted = False
    for record in run(simulation):
        print(record.as_json())
        if record.faults or record.stopped:
            sys.stdout.flush()  # keep stdout and stderr in cycle order on a terminal
            for fault in record.faults:
                print(f"padt sim: cycle {record.cycle}: program {fault}", file=sys.stderr)
            faulted = True
        if record.stopped:
            name = simulation.resource.name
            print(
                f"padt sim: cycle {record.cycle}: resource {name}: ERROR STOP, {record.stopped}",
                file=sys.stderr,
            )
            return SIM_ERROR_STOP
    return SIM_PROGRAM_ERROR if faulted else 0


# `padt import` exit codes past 0 (all imported)
IMPORT_INCOMPLETE = 1  # written, but POUs (IL, a broken drawing) or a structure's EXTENDS were not
IMPORT_NOTHING = 2  # nothing written: the file cannot be imported or DIR cannot take it


def _import(args: argparse.Namespace) -> int:
    from backend.engineering.plcopen.importer import FolderRefused, import_plcopen
    from backend.engineering.plcopen.issues import ImportFailed

    try:
        result = import_plcopen(args.file, args.output, force=args.force)
    except ImportFailed as exc:
        print(exc.diagnostic(str(args.file)), file=sys.stderr)
        print("padt import: nothing written", file=sys.stderr)
        return IMPORT_NOTHING
    except FolderRefused as exc:
        print(f"padt import: {exc}; nothing written", file=sys.stderr)
        return IMPORT_NOTHING
    except OSError as exc:  # the folder could not be written (a full disk, no permission)
        print(f"padt import: {exc}; {args.output} may be incomplete", file=sys.stderr)
        return IMPORT_NOTHING
    for diagnostic in result.diagnostics:
        print(diagnostic, file=sys.stderr)
    print(f"padt import: {result.summary} written to {args.output}")
    return 0 if result.complete else IMPORT_INCOMPLETE


def _convert(args: argparse.Namespace) -> int:
    from backend.engineering.drawing_to_text import convert_project, write_conversion
    from backend.engineering.project import ProjectError, load_project

    if not args.path.is_dir():
        print(f"padt convert: {args.path}: not a project folder", file=sys.stderr)
        return 2
    try:
        conversion = convert_project(load_project([args.path]), set(args.pou or []) or None)
    except (ProjectError, ValueError) as exc:
        print(f"padt convert: {exc}", file=sys.stderr)
        return 2
    for diagnostic in conversion.diagnostics:
        print(diagnostic, file=sys.stderr)
    if not conversion.ok:
        print("padt convert: nothing written", file=sys.stderr)
        return 1
    write_conversion(args.path, conversion)
    for pou in conversion.converted:
        print(f"{pou.file}: {pou.pou} ({pou.language}, {pou.elements} elements) is now ST")
    if not conversion.converted:
        print("padt convert: no drawn POU in the project")
    return 0


def _check_twice(args: argparse.Namespace) -> int:
    from backend.engineering.check_twice import check_twice

    result = check_twice(args.paths)
    for number, compiled in enumerate((result.first, result.second), 1):
        where = f"compile {number} (PYTHONHASHSEED={compiled.seed})"
        if compiled.configuration is not None:
            print(f"{where}: configuration CRC {compiled.configuration}")
        else:
            print(f"{where}: no configuration (compile failed)")
    if not result.compiled:
        for compiled in (result.first, result.second):
            if compiled.failure is not None:
                print(f"padt check-twice: {compiled.failure}", file=sys.stderr)
        first = result.first if result.first.failure is None else result.second
        for diagnostic in first.diagnostics:
            print(diagnostic, file=sys.stderr)
        print("padt check-twice: the project does not compile", file=sys.stderr)
        return 1
    if result.mismatches:
        for mismatch in result.mismatches:
            print(f"padt check-twice: {mismatch}", file=sys.stderr)
        print("padt check-twice: the two compiles differ", file=sys.stderr)
        return 1
    print(
        f"check-twice: OK, {len(result.first.pous)} POU and "
        f"{len(result.first.programs)} program CRCs agree"
    )
    return 0


def _positive(text: str) -> int:
    try:
        number = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if number < 1:
        raise argparse.ArgumentTypeError(f"{number} is not at least 1")
    return number


def _whole(text: str) -> int:
    """A whole number, 0 or more."""
    return 0 if text.strip() == "0" else _positive(text)


def _tier_argument(parser: argparse.ArgumentParser) -> None:
    """`--tier` of the commands that run the programs offline: by default the tier that
    `padt runtime` runs by default, so that they run what the controller runs."""
    parser.add_argument(
        "--tier",
        choices=("native", "python"),
        default="native",
        help="run the bodies of programs, function blocks, FUNCTIONs and methods as C "
        "compiled here where they translate, as padt runtime does (native, the default; "
        "without a C compiler or "
        "Python.h all run as Python, said on stderr), or all as Python",
    )


def _tcp_address(text: str) -> tuple[str, int]:
    """HOST:PORT, or PORT alone on 127.0.0.1."""
    host, _, port = text.rpartition(":")
    try:
        number = int(port)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not HOST:PORT or PORT") from None
    if not 0 < number < 65536:
        raise argparse.ArgumentTypeError(f"{number} is no TCP port")
    return host.strip("[]") or "127.0.0.1", number


def _lsp(args: argparse.Namespace) -> int:
    if args.project is not None and not args.project.is_dir():
        print(f"padt lsp: {args.project} is no folder", file=sys.stderr)
        return 2
    from padt.lsp_server import serve

    return serve(args.project, args.tcp)


def _runtime(args: argparse.Namespace) -> int:
    from runtime.main import run

    return run(args)


def _ui(args: argparse.Namespace) -> int:
    from frontend.main import run

    return run(args)


def _demo(args: argparse.Namespace) -> int:
    from padt.demo import run

    return run(args)


def _lazy(module: str, function: str) -> Callable[[argparse.Namespace], int]:
    """A subcommand whose module is imported only when it runs."""

    def run(args: argparse.Namespace) -> int:
        command: Callable[[argparse.Namespace], int] = getattr(
            importlib.import_module(module), function
        )
        return command(args)

    return run


def _rename(text: str) -> tuple[str, str]:
    from padt.configuration import parse_rename

    return parse_rename(text)


def _parameter(text: str) -> tuple[str, bool | int | str]:
    from padt.operation import parse_setting

    return parse_setting(text)


def _resource_options(parser: argparse.ArgumentParser) -> None:
    """What every command that talks to a running resource needs."""
    parser.add_argument(
        "--resource",
        required=True,
        type=resource_argument,
        metavar="NAME",
        help="name of the running resource",
    )
    add_zenoh_options(parser, "Zenoh router the resource is connected to")
    parser.add_argument(
        "--user",
        metavar="NAME",
        help="log in to the resource as NAME (password from PADT_PASSWORD, else asked for)",
    )


def _backup_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--backup-dir",
        type=Path,
        default=Path("padt-backups"),
        metavar="DIR",
        help="folder for the backup archive of what was loaded (default ./padt-backups)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="padt",
        description="Web PADT and Python PES for IEC 61131-3 (not certified for safety use).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    compile_ = sub.add_parser("compile", help="compile a project folder or .st files")
    compile_.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    compile_.add_argument("--json", action="store_true", help="print one JSON object")
    compile_.add_argument(
        "-o", "--output", type=Path, help="write the compiled artifact (JSON) to this file"
    )
    compile_.add_argument(
        "--as-resource",
        type=resource_argument,
        metavar="NAME",
        help="compile the project for resource NAME in place of its [resource] name (as "
        "padt fleet load does for each resource)",
    )
    compile_.set_defaults(func=_compile)

    docs = sub.add_parser(
        "docs", help="printable documentation of a project: DIR/<project>.html and .pdf"
    )
    docs.add_argument(
        "paths",
        nargs="+",
        type=Path,
        metavar="PROJECT",
        help="project folders, .st files, or backup zips written by padt load/reload: a "
        "document each, the loose .st files together one",
    )
    docs.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="DIR",
        help="the folder for <project>.html and <project>.pdf (created when missing)",
    )
    docs.add_argument(
        "--compare",
        type=Path,
        metavar="OLD",
        help="a previous version (project folder or backup zip) to compare with",
    )
    docs.add_argument(
        "--each",
        action="store_true",
        help="every PROJECT a document of its own (loose .st files otherwise form one project)",
    )
    docs.add_argument(
        "-j",
        "--jobs",
        type=_positive,
        metavar="N",
        help="documents made at once, each in a process of its own (default: the CPUs)",
    )
    docs.set_defaults(func=_docs)

    exec_ = sub.add_parser(
        "exec", help="compile one .st file and run its FUNCTION main (or --entry) once"
    )
    exec_.add_argument("file", type=Path, metavar="FILE.st")
    exec_.add_argument("--entry", default="main", help="FUNCTION or PROGRAM to run")
    _tier_argument(exec_)
    exec_.set_defaults(func=_exec)

    sim = sub.add_parser(
        "sim",
        help="run the user programs on virtual time; print one JSON line per cycle",
        epilog="exit codes: 0 ran, 1 compile errors, 2 bad options or project, 3 a program "
        "went to ERROR, 4 the resource went to ERROR STOP (watchdog)",
    )
    sim.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    sim.add_argument(
        "--cycles", type=_positive, default=10, metavar="N", help="cycles to run (default 10)"
    )
    sim.add_argument(
        "--cycle-ms",
        type=_positive,
        metavar="MS",
        help="virtual time per cycle (default: the target cycle time, or 100 ms without one)",
    )
    sim.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE[@CYCLE]",
        help="write an ST literal to a variable before cycle CYCLE (default 1); repeatable",
    )
    sim.add_argument(
        "--trace",
        action="append",
        metavar="NAME,...",
        help="print only these variables (or everything below an instance); repeatable",
    )
    _tier_argument(sim)
    sim.set_defaults(func=_sim)

    replay = sub.add_parser(
        "replay",
        help="run a recording made with --all-inputs again on virtual time; compare each cycle",
        epilog="exit codes: 0 identical, 1 a cycle differs (the first is named), 2 the "
        "recording cannot be replayed or the project not read, 3 compile errors",
    )
    replay.add_argument(
        "recording",
        type=Path,
        metavar="FILE.mcap",
        help="the recording (its rotated parts FILE-2.mcap, ... are read after it)",
    )
    replay.add_argument(
        "paths",
        nargs="+",
        type=Path,
        metavar="PROJECT",
        help="the project to replay with: the recorded version or a new one",
    )
    _tier_argument(replay)
    replay.set_defaults(func=_replay)

    import_ = sub.add_parser(
        "import",
        help="a PLCopen TC6 XML file (Beremiz, OpenPLC, CODESYS export) into a project folder",
        epilog="exit codes: 0 imported, 1 written but POUs in IL or with a drawing that "
        "cannot be read (or a CODESYS structure's EXTENDS) not imported, named in an error, 2 "
        "nothing written (the file cannot be imported, or DIR cannot take it)",
    )
    import_.add_argument("file", type=Path, metavar="FILE.xml")
    import_.add_argument(
        "-o", "--output", type=Path, required=True, metavar="DIR", help="the project folder"
    )
    import_.add_argument(
        "--force",
        action="store_true",
        help="replace the project in a project folder DIR (its padt.toml and .st files; "
        "its tests stay)",
    )
    import_.set_defaults(func=_import)

    convert = sub.add_parser(
        "convert",
        help="rewrite drawn bodies (FBD, LD) of a project as ST, in their files",
        epilog="exit codes: 0 converted (the project still compiles), 1 nothing written "
        "(a drawing that does not lower, or the project would not compile), 2 bad options "
        "or project",
    )
    convert.add_argument("path", type=Path, metavar="DIR", help="the project folder")
    convert.add_argument(
        "--pou",
        action="append",
        metavar="NAME",
        help="convert only this POU (repeatable; default: every drawn POU)",
    )
    convert.set_defaults(func=_convert)

    from padt.testing import add_arguments as test_arguments

    test = sub.add_parser(
        "test",
        help="run the project's unit tests (ST, in its test/ folder) on both tiers",
        epilog="exit codes: 0 all passed, 1 a test failed, 2 the project or its tests do not "
        "compile (or bad options), 5 no test found. docs/testing.md",
    )
    test_arguments(test)
    test.set_defaults(func=_lazy("padt.testing", "run"))

    from padt.new_project import add_arguments as new_arguments

    new = sub.add_parser(
        "new",
        help="a new project folder from a template (empty, tank, sequence, conveyor)",
        epilog="exit codes: 0 made, 2 not made (the name, the folder or the template)",
    )
    new_arguments(new)
    new.set_defaults(func=_lazy("padt.new_project", "run"))

    check = sub.add_parser(
        "check-twice", help="compile in two processes with different hash seeds; compare CRCs"
    )
    check.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    check.set_defaults(func=_check_twice)

    from frontend.main import add_arguments as ui_arguments
    from padt.demo import add_arguments as demo_arguments
    from runtime.main import add_arguments as runtime_arguments

    lsp = sub.add_parser(
        "lsp",
        help="a Language Server (LSP) for editors: diagnostics, completion, navigation",
        description="Serve the language services of a project to one LSP client (VS Code, "
        "Neovim, ...) on stdin/stdout, or on a TCP port: diagnostics as the compiler gives "
        "them, completion, hover, definition, references, rename, outline and formatting. "
        "docs/editors.md shows how to set up an editor.",
    )
    lsp.add_argument(
        "project",
        nargs="?",
        type=Path,
        metavar="PROJECT_DIR",
        help="the project folder (padt.toml and .st files); default the client's workspace",
    )
    lsp.add_argument(
        "--tcp",
        type=_tcp_address,
        metavar="[HOST:]PORT",
        help="listen on a TCP port for one client instead of stdio (host 127.0.0.1 unless given)",
    )
    lsp.set_defaults(func=_lsp)

    dap = sub.add_parser(
        "dap",
        help="a Debug Adapter (DAP) for VS Code: breakpoints and steps in a running resource",
        description="Serve the Debug Adapter Protocol to one client at a time on stdin/stdout, "
        "or on a TCP port of 127.0.0.1 (VS Code's debugServer): the client attaches to a running "
        "resource (its launch configuration names the resource, the Zenoh router, the user and "
        "the project folder; the password comes from PADT_PASSWORD) and sets breakpoints and "
        "logpoints, steps, shows the stack and the variables. docs/debugging.md shows the setup.",
    )
    dap.add_argument(
        "--port",
        type=int,
        metavar="N",
        help="listen on 127.0.0.1:N for clients, one after the other, instead of stdio",
    )
    dap.set_defaults(func=_lazy("padt.dap_server", "run"))

    runtime = sub.add_parser("runtime", help="run one resource (the PES) as this process")
    runtime_arguments(runtime)
    runtime.set_defaults(func=_runtime)

    ui = sub.add_parser("ui", help="serve the browser UI for a running resource")
    ui_arguments(ui)
    ui.set_defaults(func=_ui)

    demo = sub.add_parser("demo", help="router + runtime with the demo project + browser UI")
    demo_arguments(demo)
    demo.set_defaults(func=_demo)

    from padt.router import add_arguments as router_arguments

    router = sub.add_parser(
        "router", help="a Zenoh router (TLS, usrpwd, access control; a mesh with --connect)"
    )
    router_arguments(router)
    router.set_defaults(func=_lazy("padt.router", "run"))

    from runtime.contract.accounts import LEVELS

    load = sub.add_parser(
        "load",
        help="compile twice, download to a resource in STOP (cold start), store a backup",
    )
    load.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    _resource_options(load)
    load.add_argument(
        "--setup-secret-file",
        type=Path,
        metavar="FILE",
        help="the first download to a runtime without a configuration: log in as 'setup' "
        "with the setup secret in FILE (the runtime's state folder has it, setup-secret; "
        "or from PADT_SETUP_SECRET)",
    )
    _backup_option(load)
    load.set_defaults(func=_lazy("padt.configuration", "load"))

    for name, does in (("start", "start"), ("stop", "stop")):
        command = sub.add_parser(name, help=f"{does} a resource, or one of its programs")
        _resource_options(command)
        command.add_argument("--program", help=f"{does} only this user program")
        command.set_defaults(func=_lazy("padt.operation", name))

    status = sub.add_parser("status", help="show a resource's state, CRC, cycle and programs")
    _resource_options(status)
    status.add_argument("--json", action="store_true", help="print the status object as JSON")
    status.add_argument(
        "--io",
        action="store_true",
        help="also list every Modbus point with its value on the wire now",
    )
    status.set_defaults(func=_lazy("padt.operation", "status"))

    reload = sub.add_parser(
        "reload",
        help="compile twice, show the reload plan, change the running resource online",
    )
    reload.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    _resource_options(reload)
    reload.add_argument("--preview", action="store_true", help="only show the plan; change nothing")
    reload.add_argument(
        "--rename",
        action="append",
        default=[],
        type=_rename,
        metavar="OLD=NEW",
        help="carry the values of OLD (variable, FB instance or program) over to NEW; repeatable",
    )
    reload.add_argument(
        "--yes",
        action="store_true",
        help="confirm the reload (without it, only the plan is shown and exit code is 1)",
    )
    reload.add_argument(
        "--watchdog-ms",
        type=_positive,
        metavar="MS",
        help="a higher watchdog time for the switch-over cycle only",
    )
    reload.add_argument(
        "--target-cycle-ms",
        type=_positive,
        metavar="MS",
        help="a longer target cycle time for the switch-over cycle only",
    )
    reload.add_argument(
        "--keep-online",
        action="append",
        default=[],
        metavar="PARAM",
        help="set PARAM's online value again right after the reload, which resets it to the "
        "project's (the preview lists them); repeatable",
    )
    reload.add_argument(
        "--compile-for-resource",
        action="store_true",
        help="compile the project for --resource NAME in place of its [resource] name, as "
        "padt fleet load did (without it, a project of another name is refused)",
    )
    _backup_option(reload)
    reload.set_defaults(func=_lazy("padt.configuration", "reload"))

    _fleet_commands(sub)
    _online_test_commands(sub)
    _recording_commands(sub)
    _debug_commands(sub)

    passwd = sub.add_parser(
        "passwd",
        help="print a [[resource.user]] entry with the salted hash of a password",
    )
    passwd.add_argument("user", metavar="NAME")
    passwd.add_argument("--level", default="read", choices=LEVELS, help="access level")
    passwd.set_defaults(func=_passwd)

    from backend.api.options import add_arguments as api_arguments
    from backend.api.options import add_user_arguments

    api = sub.add_parser("api", help="serve the REST API (OpenAPI at /docs)")
    api_arguments(api)
    api.set_defaults(func=_api)

    api_user = sub.add_parser(
        "api-user", help="add, change or delete an account of the PADT (REST API)"
    )
    add_user_arguments(api_user)
    api_user.set_defaults(func=_api_user)
    return parser


def _wait_seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number of seconds") from None
    if not 0.1 <= seconds <= 60:
        raise argparse.ArgumentTypeError("the wait is 0.1 to 60 seconds")
    return seconds


def _fleet_targets(parser: argparse.ArgumentParser, what: str) -> None:
    """The project, the resources in their order, the mesh and the login of a fleet command."""
    parser.add_argument("paths", nargs="+", type=Path, metavar="PATH")
    parser.add_argument(
        "--resource",
        action="append",
        required=True,
        type=resource_argument,
        metavar="NAME",
        help=f"a resource to {what}, in this order; repeat for each",
    )
    add_zenoh_options(parser, "Zenoh router of the mesh")
    parser.add_argument(
        "--user",
        metavar="NAME",
        help="log in to each resource as NAME (password from PADT_PASSWORD, else asked for once)",
    )


def _fleet_commands(sub: Any) -> None:
    """fleet status, fleet load, fleet reload (docs/cli.md)."""
    fleet = sub.add_parser(
        "fleet",
        help="every resource on the router mesh: one status table; one project into several, "
        "loaded or changed online",
    )
    verbs = fleet.add_subparsers(dest="verb", required=True, metavar="VERB")
    status = verbs.add_parser(
        "status",
        help="one table of every resource online: host, state, CRC, project, cycle time",
        description="Every resource whose liveliness token is on the bus, with its status "
        "when it is signed with the resource's known key (pinned at an earlier login, or "
        "proved now by --user); the others are 'not yet verified'.",
        epilog="exit codes: 0 every resource found is RUN (and verified), 1 one is not, or "
        "none is online, or no router answers, 2 bad options",
    )
    add_zenoh_options(status, "Zenoh router of the mesh")
    status.add_argument(
        "--user",
        metavar="NAME",
        help="log in as NAME to each resource whose key is not known yet (the password from "
        "PADT_PASSWORD, else asked for once)",
    )
    status.add_argument("--json", action="store_true", help="print a JSON list, a resource each")
    status.add_argument(
        "--wait",
        type=_wait_seconds,
        default=2.5,
        metavar="S",
        help="how long to wait for the signed statuses (default 2.5 s; each comes every second)",
    )
    status.set_defaults(func=_lazy("padt.fleet", "status"))

    load = verbs.add_parser(
        "load",
        help="compile the project for each resource and download it, one after another",
        description="Load one project into several resources in STOP, in the order given: "
        "each gets the project compiled for it (its name in place of the project's [resource] "
        "name) through the compile-twice gate, downloaded, and backed up. The first resource "
        "that refuses (or gives no answer, or whose backup cannot be written) ends it: those "
        "after it are not tried.",
        epilog="exit codes: 0 every resource done, 1 one refused (the others after it not "
        "tried), 2 bad options or the project cannot be read",
    )
    _fleet_targets(load, "load")
    load.add_argument(
        "--setup-secret-file",
        type=Path,
        metavar="FILE",
        help="a runtime without a configuration: log in as 'setup' with the secret in FILE "
        "(or PADT_SETUP_SECRET); only for runtimes that share it",
    )
    load.add_argument("--json", action="store_true", help="print one JSON object at the end")
    _backup_option(load)
    load.set_defaults(func=_lazy("padt.fleet", "load"))

    reload = verbs.add_parser(
        "reload",
        help="compile the project for each resource, show each reload plan, change them "
        "online one after another",
        description="An online change of several running resources, in the order given: "
        "each gets the project compiled for it (as fleet load) and its reload plan against "
        "what it runs. --preview only shows the plans; without --yes nothing changes; with "
        "--yes each is reloaded in turn, and the first whose plan needs STOP and a download, "
        "that refuses, gives no answer or whose backup cannot be written ends it: those "
        "after it are not tried.",
        epilog="exit codes: 0 every resource done (--preview: every plan possible), 1 one "
        "refused (the others after it not tried), a plan not possible, or no --yes, 2 bad "
        "options or the project cannot be read",
    )
    _fleet_targets(reload, "change online")
    reload.add_argument(
        "--preview", action="store_true", help="only show each plan; change nothing"
    )
    reload.add_argument(
        "--yes",
        action="store_true",
        help="confirm the reloads (without it, only the plans are shown and exit code is 1)",
    )
    reload.add_argument(
        "--rename",
        action="append",
        default=[],
        type=_rename,
        metavar="OLD=NEW",
        help="carry the values of OLD over to NEW in each resource; repeatable",
    )
    reload.add_argument(
        "--keep-online",
        action="append",
        default=[],
        metavar="PARAM",
        help="where the reload resets PARAM to the project's value, set its online value "
        "again right after the switch-over; repeatable",
    )
    reload.add_argument("--json", action="store_true", help="print one JSON object at the end")
    _backup_option(reload)
    reload.set_defaults(func=_lazy("padt.fleet", "reload"))


def _online_test_commands(sub: Any) -> None:
    """values, write, force, freeze / step / unfreeze, events, params."""
    values = sub.add_parser("values", help="show values of a running resource (or follow them)")
    _resource_options(values)
    values.add_argument("variables", nargs="*", metavar="VAR", help="only these (default: all)")
    values.add_argument("--json", action="store_true", help="print JSON (a line per message)")
    values.add_argument("--follow", action="store_true", help="print every update until Ctrl-C")
    values.add_argument(
        "--period-ms", type=_positive, default=500, metavar="MS", help="with --follow (500)"
    )
    values.set_defaults(func=_lazy("padt.online_test", "values"))

    write = sub.add_parser("write", help="write a value once (an ST literal; not forcing)")
    _resource_options(write)
    write.add_argument("variable", metavar="VAR")
    write.add_argument("value", metavar="VALUE", help="an ST literal: TRUE, 42, T#2s, 'text'")
    write.set_defaults(func=_lazy("padt.online_test", "write"))

    force = sub.add_parser("force", help="forcing: start, stop, set, clear, show")
    actions = force.add_subparsers(dest="action", required=True, metavar="ACTION")
    for action, does in (("start", "start forcing"), ("stop", "stop forcing")):
        level = actions.add_parser(action, help=f"{does} (global, or --program's local level)")
        level.add_argument("--program", metavar="P", help="a program's local forcing")
        if action == "start":
            level.add_argument("--timeout-ms", type=_positive, metavar="MS", help="time limit")
    set_ = actions.add_parser("set", help="set a force value and its switch")
    set_.add_argument("variable", metavar="VAR")
    set_.add_argument("value", metavar="VALUE", help="an ST literal of the variable's type")
    set_.add_argument("--off", action="store_true", help="the force switch OFF (prepared only)")
    clear = actions.add_parser("clear", help="remove a force value")
    clear.add_argument("variable", metavar="VAR")
    actions.add_parser("show", help="the force levels and values")
    for parser in actions.choices.values():
        _resource_options(parser)
        parser.add_argument("--json", action="store_true", help="print the forcing state as JSON")
        parser.set_defaults(func=_lazy("padt.online_test", "force"))

    for verb, does in (
        ("freeze", "freeze a program for single step (RUN_FREEZE)"),
        ("step", "run program cycles of a frozen program"),
        ("unfreeze", "leave single step: the program runs again"),
    ):
        command = sub.add_parser(verb, help=does)
        _resource_options(command)
        command.add_argument("--program", required=True, metavar="P", help="the user program")
        if verb == "step":
            command.add_argument(
                "--cycles", type=_positive, default=1, metavar="N", help="program cycles (1)"
            )
            command.add_argument(
                "--interval-ms",
                type=_positive,
                metavar="MS",
                help="time per cycle (default: the target cycle time)",
            )
        command.set_defaults(func=_lazy("padt.operation", "single_step"), verb=verb)

    events = sub.add_parser("events", help="the resource's event log (or follow it)")
    _resource_options(events)
    events.add_argument("--json", action="store_true", help="one JSON line per event")
    events.add_argument("--follow", action="store_true", help="then every new event until Ctrl-C")
    events.add_argument("--after", type=int, default=0, metavar="SEQ", help="only after SEQ")
    events.set_defaults(func=_lazy("padt.online_test", "events"))

    params = sub.add_parser("params", help="resource and program parameters; change online")
    _resource_options(params)
    params.add_argument(
        "--set",
        action="append",
        default=[],
        type=_parameter,
        metavar="NAME=VALUE",
        help="change a resource parameter online (ON/OFF, a number, a word); repeatable",
    )
    params.add_argument("--json", action="store_true", help="print the parameters as JSON")
    params.set_defaults(func=_lazy("padt.operation", "params"))


def _recording_commands(sub: Any) -> None:
    """record, recordings (docs/recording.md)."""
    record = sub.add_parser(
        "record",
        help="record variables of a running resource into an MCAP file",
        description="Record variables of a running resource every CPU cycle (or from a "
        "trigger on) into MCAP files, wait until it is done (--cycles or --seconds reached, "
        "or Ctrl-C), then download its files (FILE.mcap, FILE-2.mcap... as they rotated).",
    )
    _resource_options(record)
    record.add_argument(
        "--var",
        action="append",
        default=[],
        metavar="PATH",
        help="a variable, or PREFIX* for every variable whose path starts so; repeatable",
    )
    record.add_argument(
        "--all-inputs",
        action="store_true",
        help="also every input of every cycle (for padt replay)",
    )
    record.add_argument(
        "--trigger",
        metavar="EXPR",
        help="start writing when EXPR becomes true: 'Main.level > 80', Main.alarm, "
        "'NOT Main.alarm' (ops = <> < <= > >=, the value an ST literal)",
    )
    record.add_argument(
        "--pre-cycles",
        type=_whole,
        default=0,
        metavar="N",
        help="with --trigger: also the N cycles before it (default 0)",
    )
    until = record.add_mutually_exclusive_group()
    until.add_argument("--cycles", type=_positive, metavar="N", help="end after N cycles")
    until.add_argument("--seconds", type=_positive, metavar="S", help="end after S seconds")
    record.add_argument(
        "--rotate-mb",
        type=_positive,
        default=256,
        metavar="N",
        help="begin a new file every N megabytes (default 256)",
    )
    record.add_argument(
        "--rotate-s", type=_positive, metavar="N", help="begin a new file every N seconds"
    )
    record.add_argument(
        "--keep",
        action="store_true",
        help="leave the recording on the resource (by default it is deleted there once downloaded)",
    )
    record.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="FILE.mcap",
        help="where the recording goes (the next parts beside it: FILE-2.mcap, ...)",
    )
    record.set_defaults(func=_lazy("padt.recording", "record"))

    kept = sub.add_parser(
        "recordings", help="the recordings kept on a running resource; download or delete one"
    )
    _resource_options(kept)
    kept.add_argument("--json", action="store_true", help="print them as JSON")
    what = kept.add_mutually_exclusive_group()
    what.add_argument(
        "--download", metavar="ID", help="download recording ID's files (with -o FILE.mcap)"
    )
    what.add_argument("--delete", metavar="ID", help="delete recording ID (it has ended)")
    kept.add_argument(
        "-o",
        "--output",
        type=Path,
        metavar="FILE.mcap",
        help="with --download: where it goes (the next parts beside it: FILE-2.mcap, ...)",
    )
    kept.set_defaults(func=_lazy("padt.recording", "kept_recordings"))


def _debug_commands(sub: Any) -> None:
    """debug set / list / clear / continue / step / run-to / stack / vars / wait / timeout
    (docs/debugging.md)."""
    debug = sub.add_parser(
        "debug",
        help="breakpoints, logpoints and stepping in a running resource's ST code",
        description="Debugging in the code (docs/debugging.md). FILE is a path relative to "
        "the current folder or to --project (default: the current folder when it holds "
        "padt.toml), or the file's name in the project as the artifact has it (tank.st).",
    )
    verbs = debug.add_subparsers(dest="verb", required=True, metavar="VERB")
    parsers = {}
    for verb, does in (
        ("set", "add a breakpoint (or with --log a logpoint) at FILE:LINE"),
        ("list", "the breakpoints, their hits, and the program in BKPT"),
        ("clear", "clear every breakpoint, a file's, or those at FILE:LINE"),
        ("continue", "let the program in BKPT run on"),
        ("step", "one statement (over, into, out) or to the end of the program cycle"),
        ("run-to", "let the program in BKPT run until FILE:LINE"),
        ("stack", "the call stack of the program in BKPT, innermost first"),
        ("vars", "the variables of a frame of the program in BKPT"),
        ("wait", "wait until a program stands in BKPT and print where"),
        ("timeout", "after how long without a debug command a program in BKPT continues"),
    ):
        parsers[verb] = verbs.add_parser(verb, help=does, description=does)
    for verb in ("continue", "step", "run-to", "stack", "vars"):
        parsers[verb].add_argument("program", metavar="PROGRAM", help="the program in BKPT")
    set_ = parsers["set"]
    set_.add_argument("location", metavar="FILE:LINE", help="a statement at or after LINE")
    set_.add_argument("--program", metavar="P", help="only while program P runs")
    set_.add_argument("--instance", metavar="PATH", help="only in this FB instance (Main.valve1)")
    set_.add_argument("--condition", metavar="EXPR", help="only when this ST condition holds")
    set_.add_argument("--hit-count", type=_positive, metavar="N", help="stop from hit N on")
    set_.add_argument(
        "--log",
        action="extend",
        nargs="+",
        metavar="EXPR",
        help="a logpoint: record these ST expressions as an event at each hit; never stops",
    )
    parsers["clear"].add_argument("location", nargs="?", metavar="FILE[:LINE]")
    kind = parsers["step"].add_mutually_exclusive_group()
    for name, does in (
        ("over", "to the next statement, over calls (the default)"),
        ("into", "into the call of this statement"),
        ("out", "out of the current POU to its caller"),
        ("cycle", "to the end of the program cycle"),
    ):
        kind.add_argument(f"--{name}", dest="kind", action="store_const", const=name, help=does)
    parsers["step"].set_defaults(kind="over")
    parsers["run-to"].add_argument("location", metavar="FILE:LINE", help="the cursor")
    vars_ = parsers["vars"]
    vars_.add_argument(
        "path", nargs="?", default="", metavar="PATH", help="a member's children: a, a.sub, arr[2]"
    )
    vars_.add_argument(
        "--frame", type=_whole, default=0, metavar="N", help="frame N of the stack (0 innermost)"
    )
    parsers["wait"].add_argument(
        "--timeout", type=_positive, metavar="S", help="give up after S seconds (exit code 1)"
    )
    parsers["timeout"].add_argument(
        "seconds", type=_debug_timeout, metavar="SECONDS", help="5 to 3600 (default 120)"
    )
    functions = {"set": "set_", "list": "list_", "continue": "continue_", "run-to": "run_to"}
    functions["vars"] = "vars_"
    for verb, parser in parsers.items():
        _resource_options(parser)
        if verb in ("set", "clear", "run-to"):
            parser.add_argument(
                "--project", type=Path, metavar="DIR", help="the project FILE is relative to"
            )
        parser.add_argument("--json", action="store_true", help="print one JSON object")
        function = functions.get(verb, verb)
        parser.set_defaults(func=_lazy("padt.debugging", function))


def _debug_timeout(text: str) -> int:
    from runtime.contract.protocol import MAX_DEBUG_TIMEOUT_S, MIN_DEBUG_TIMEOUT_S

    seconds = _whole(text)
    if not MIN_DEBUG_TIMEOUT_S <= seconds <= MAX_DEBUG_TIMEOUT_S:
        raise argparse.ArgumentTypeError(
            f"the timeout is {MIN_DEBUG_TIMEOUT_S} to {MAX_DEBUG_TIMEOUT_S} seconds"
        )
    return seconds


def _api(args: argparse.Namespace) -> int:
    from backend.api.server import run

    return run(args)


def _new_password(user: str) -> str | None:
    """From PADT_PASSWORD, or asked for twice (never an option: it would stay in shell
    histories and process lists); None when the two differ."""
    import getpass
    import os

    password = os.environ.get("PADT_PASSWORD")
    if password is None:
        password = getpass.getpass(f"password of {user}: ")
        if getpass.getpass("again: ") != password:
            return None
    return password


def _api_user(args: argparse.Namespace) -> int:
    from backend.engineering.padt_accounts import (
        AccountsError,
        read_accounts,
        with_account,
        without_account,
        write_accounts,
    )

    try:
        accounts = read_accounts(args.accounts)
        if args.delete:
            changed = without_account(accounts, args.user)
        else:
            password = _new_password(args.user)
            if password is None:
                print("padt api-user: the two passwords differ", file=sys.stderr)
                return 1
            changed = with_account(accounts, args.user, args.level, password)
        write_accounts(args.accounts, changed)
    except (AccountsError, OSError) as exc:
        print(f"padt api-user: {exc}", file=sys.stderr)
        return 2
    done = "deleted" if args.delete else f"set ({args.level})"
    print(f"padt api-user: account {args.user} {done} in {args.accounts}")
    return 0


def _passwd(args: argparse.Namespace) -> int:
    """Only the hash of the password is printed."""
    from backend.engineering.project import user_entry
    from runtime.contract.accounts import account_problems, hash_password
    from runtime.contract.artifact import UserAccount

    password = _new_password(args.user)
    if password is None:
        print("padt passwd: the two passwords differ", file=sys.stderr)
        return 1
    try:
        hashed = hash_password(password)
    except ValueError as exc:
        print(f"padt passwd: {exc}", file=sys.stderr)
        return 2
    problems = account_problems(args.user, args.level, hashed)
    if problems:
        print(f"padt passwd: {problems[0]}", file=sys.stderr)
        return 2
    print(user_entry(UserAccount(args.user, args.level, hashed)), end="")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        code: int = args.func(args)
    except KeyboardInterrupt:  # Ctrl-C before a command took over the signal: no traceback
        return 130
    except BrokenPipeError:
        # the reader stopped reading (`padt status | head -1`): end quietly, and keep the
        # interpreter's last flush at exit from failing on the closed pipe again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141  # as a process ended by SIGPIPE
    except RouterUnreachable as exc:
        print(f"padt {args.command}: {exc}", file=sys.stderr)
        return 1
    return code


if __name__ == "__main__":
    sys.exit(main())
