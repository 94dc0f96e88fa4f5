"""`padt`: the command line. Each subcommand lives with the part it belongs to."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from backend.project import ProjectError, compile_project, load_project


def _compile(args: argparse.Namespace) -> int:
    try:
        project = load_project(args.paths)
    except ProjectError as exc:
        print(f"padt compile: {exc}", file=sys.stderr)
        return 2
    result = compile_project(project)
    artifact = result.artifact
    crc: dict[str, object] = {}
    if artifact is not None:
        crc = {
            "configuration": artifact.crc,
            "pous": {p.name: p.crc for p in artifact.pous},
            "programs": {p.name: p.crc for p in artifact.programs},
        }
    if args.json:
        report = {
            "ok": result.ok,
            "diagnostics": [d.as_json() for d in result.diagnostics],
            "crc": crc,
        }
        print(json.dumps(report, indent=2, sort_keys=True))
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


def _exec(args: argparse.Namespace) -> int:
    from backend.run_once import run_entry

    return run_entry(args.file, args.entry)


def _runtime(args: argparse.Namespace) -> int:
    from runtime.main import run

    return run(args)


def _ui(args: argparse.Namespace) -> int:
    from frontend.main import run

    return run(args)


def _demo(args: argparse.Namespace) -> int:
    from padt.demo import run

    return run(args)


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
    compile_.set_defaults(func=_compile)

    exec_ = sub.add_parser(
        "exec", help="compile one .st file and run its FUNCTION main (or --entry) once"
    )
    exec_.add_argument("file", type=Path, metavar="FILE.st")
    exec_.add_argument("--entry", default="main", help="FUNCTION or PROGRAM to run")
    exec_.set_defaults(func=_exec)

    from frontend.main import add_arguments as ui_arguments
    from padt.demo import add_arguments as demo_arguments
    from runtime.main import add_arguments as runtime_arguments

    runtime = sub.add_parser("runtime", help="run one resource (the PES) as this process")
    runtime_arguments(runtime)
    runtime.set_defaults(func=_runtime)

    ui = sub.add_parser("ui", help="serve the browser UI for a running resource")
    ui_arguments(ui)
    ui.set_defaults(func=_ui)

    demo = sub.add_parser("demo", help="router + runtime with the demo project + browser UI")
    demo_arguments(demo)
    demo.set_defaults(func=_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    code: int = args.func(args)
    return code


if __name__ == "__main__":
    sys.exit(main())
