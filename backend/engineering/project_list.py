"""The projects a PADT knows (`padt api --project`, `padt ui --project`, `--projects-dir`):
by name, each a folder. Apart from project.py so that the command line's parser loads no
compiler."""

from __future__ import annotations

import argparse
from pathlib import Path


def named_folder(text: str) -> tuple[str, Path]:
    """`--project` as a user gives it: `NAME=DIR`, or `DIR` named by its folder. A folder
    whose name holds `=` is given as `NAME=DIR`."""
    name, sep, folder = text.partition("=")
    if sep and name.strip() and not any(c in name for c in "/\\"):
        if not folder.strip():
            raise ValueError(f"'{text}': no folder after '='")
        return name.strip(), Path(folder.strip())
    return Path(text).resolve().name, Path(text)


def projects_by_name(entries: list[tuple[str, Path]]) -> dict[str, Path]:
    """The projects a PADT serves, by name; ValueError for a name given twice or a path that
    is no folder."""
    projects: dict[str, Path] = {}
    for name, folder in entries:
        if name in projects:
            raise ValueError(f"two projects are named {name}: {projects[name]} and {folder}")
        if not folder.is_dir():
            raise ValueError(f"{folder}: not a project folder")
        projects[name] = folder
    return projects


def add_shelf_options(parser: argparse.ArgumentParser) -> None:
    """`--projects-dir` and `--audit-log` of `padt ui` and `padt api`."""
    parser.add_argument(
        "--projects-dir",
        type=Path,
        metavar="DIR",
        help="a folder of projects: each sub-folder is a project, and new projects are made "
        "there from templates (without it, no new projects)",
    )
    parser.add_argument(
        "--audit-log",
        type=Path,
        default=Path("padt-audit.jsonl"),
        metavar="FILE",
        help="the PADT's audit log of every change to a project file (default ./padt-audit.jsonl)",
    )
