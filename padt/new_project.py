"""`padt new NAME`: a project folder from a template, as the browser's New project makes
one (docs/cli.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("name", metavar="NAME", help="the project's name: its folder's name")
    parser.add_argument(
        "--template",
        default="empty",
        metavar="T",
        help="what it starts from: empty (default), tank (the demo), sequence (SFC) or "
        "conveyor (LD and FBD)",
    )
    parser.add_argument("--dir", default=".", metavar="DIR", help="where its folder goes")
    parser.add_argument("--resource", metavar="NAME", help="the resource's name")


def run(args: argparse.Namespace) -> int:
    # imported here: building the command line's parser loads no compiler
    from backend.engineering.project_shelf import make_project
    from runtime.contract.refusal import Refusal

    try:
        folder = make_project(Path(args.dir), args.name, args.template, args.resource)
    except Refusal as refused:
        print(f"padt new: {refused.message}", file=sys.stderr)
        return 2
    print(f"padt new: {folder} from template {args.template}")
    return 0
