"""Where a setting of padt.toml is written: the line of each table and key, so that a
diagnostic about a setting points at it (`padt.toml:14:1`). Python's TOML reader keeps no
positions; this reads the plain structure padt.toml uses (`[table]`, `[[array.of.tables]]`,
`key = value`, one per line), which is all a diagnostic needs.

A path names tables of an array by their index: `modbus.device.0.point.2.area`.
"""

from __future__ import annotations


def key_lines(text: str) -> dict[str, int]:
    """The first line (from 1) of every table and key path in `text`."""
    lines: dict[str, int] = {}
    counts: dict[str, int] = {}  # tables of each array seen so far, by resolved path
    current = ""
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if line.startswith("[["):
            parent, _, name = line[2:].split("]]", 1)[0].rpartition(".")
            path = _resolved(parent, counts) + "." + name.strip() if parent else name.strip()
            index = counts.get(path, 0)
            counts[path] = index + 1
            current = f"{path}.{index}"
        elif line.startswith("["):
            current = _resolved(line[1:].split("]", 1)[0], counts)
        elif "=" in line and not line.startswith("#"):
            name = line.split("=", 1)[0].strip().strip("\"'")
            lines.setdefault(f"{current}.{name}" if current else name, number)
            continue
        else:
            continue
        lines.setdefault(current, number)
    return lines


def _resolved(header: str, counts: dict[str, int]) -> str:
    """A table header with the index of the latest table of every array on its way."""
    path = ""
    for part in (p.strip().strip("\"'") for p in header.split(".")):
        path = f"{path}.{part}" if path else part
        if path in counts:
            path = f"{path}.{counts[path] - 1}"
    return path


def line_of(lines: dict[str, int], path: str) -> int:
    """The line of `path`, or of the nearest table around it that has one (else 1)."""
    while path:
        if path in lines:
            return lines[path]
        path = path.rpartition(".")[0]
    return 1
