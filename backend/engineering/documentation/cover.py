"""The cover: project, version, author and date as the project gives them, and the CRCs
that identify what a test authority accepts: the configuration's, each program's and each
POU's."""

from __future__ import annotations

from backend.engineering.documentation.markup import code, escape, table
from backend.engineering.documentation.subject import Subject


def cover(subject: Subject, compared_with: Subject | None) -> str:
    artifact = subject.artifact
    facts = [
        ("Project", escape(subject.name)),
        ("Version", escape(subject.version or "-")),
        ("Author", escape(subject.author or "-")),
        ("Date", escape(subject.date or "-")),
        ("Resource", escape(artifact.resource.name)),
        ("Configuration CRC", code(artifact.crc)),
    ]
    if compared_with is not None:
        facts.append(
            (
                "Compared with",
                f"version {escape(compared_with.version or '-')}, CRC {code(compared_with.crc)}",
            )
        )
    rows = "".join(f"<tr><th>{name}</th><td>{value}</td></tr>" for name, value in facts)
    programs = table(
        ["program", "ID", "POU", "CRC"],
        (
            [escape(p.name), str(p.program_id), escape(p.pou), code(p.crc)]
            for p in sorted(artifact.programs, key=lambda p: p.program_id)
        ),
    )
    return (
        '<section class="cover">'
        '<p class="kind">Project documentation</p>'
        f'<h1 class="title">{escape(subject.name)}</h1>'
        f'<table class="facts">{rows}</table>'
        f"<h3>User programs of resource {escape(artifact.resource.name)}</h3>{programs}"
        "</section>"
    )
