"""Several documents at once, in worker processes: one document is one process's work
from start to end (WeasyPrint lays out on one core), so a library of chapters or a plant
of projects takes the cores it is given. Each document is made exactly as alone, so its
bytes do not depend on the number of workers; the outcomes come back in the order asked."""

from __future__ import annotations

import gc
import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.documentation.export import (
    Document,
    DocumentError,
    document,
    write_document,
)

__all__ = [
    "DocumentError",
    "Outcome",
    "Request",
    "default_jobs",
    "document_all",
    "requests_of",
    "write_all",
]


@dataclass(frozen=True)
class Request:
    """One document: a project folder, a backup zip, or loose .st files forming one project."""

    paths: tuple[Path, ...]
    compare: Path | None = None

    @property
    def origin(self) -> str:
        return " ".join(str(path) for path in self.paths)


@dataclass(frozen=True)
class Outcome:
    request: Request
    made: Document | None
    error: str = ""  # why there is no document, naming the project


def requests_of(
    paths: list[Path], each: bool = False, compare: Path | None = None
) -> list[Request]:
    """A document per folder and per backup zip; the loose .st files form one project
    together (in the place of the first), or one each when `each`. A comparison is of one
    document with its previous version."""
    requests: list[Request] = []
    loose: list[Path] = []
    for path in paths:
        if each or path.is_dir() or path.suffix.lower() == ".zip":
            requests.append(Request((path,)))
        else:
            if not loose:
                requests.append(Request(()))  # its place; filled below
            loose.append(path)
    requests = [request if request.paths else Request(tuple(loose)) for request in requests]
    if compare is None:
        return requests
    if len(requests) > 1:
        raise DocumentError(f"--compare compares one project, not {len(requests)}")
    return [Request(requests[0].paths, compare)]


def default_jobs() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def document_all(requests: list[Request], jobs: int) -> list[Outcome]:
    """The document of each request, in the order given; `jobs` worker processes at most
    (1: in this process, which then must be one that makes documents only, as the command
    is). A project that cannot be documented is an outcome with its error, the others are
    made all the same."""
    workers = max(1, min(jobs, len(requests)))
    if workers == 1:
        return [_outcome(request) for request in requests]
    # spawned, not forked: the caller may be a server with threads of its own
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        # the biggest first, so that no large project starts last and runs alone
        order = sorted(range(len(requests)), key=lambda i: -_size(requests[i]))
        futures: dict[int, Future[Outcome]] = {i: pool.submit(_outcome, requests[i]) for i in order}
        return [_collect(requests[i], futures[i]) for i in range(len(requests))]


def write_all(outcomes: list[Outcome], folder: Path) -> list[tuple[bool, str]]:
    """Each document written in `folder` (`<project>.html`, `<project>.pdf`), in order:
    (written, what to tell), its paths and CRC or why it was not written. A second
    document of the same name (two backups of one project) is refused rather than written
    over the first."""
    told: list[tuple[bool, str]] = []
    names: dict[str, str] = {}
    for outcome in outcomes:
        made, origin = outcome.made, outcome.request.origin
        try:
            if made is None:
                raise DocumentError(outcome.error)
            if made.name in names:
                raise DocumentError(
                    f"its document is named {made.name}, as that of {names[made.name]}"
                )
            html_path, pdf_path = write_document(made, folder)
        except DocumentError as exc:
            told.append((False, _named(origin, str(exc))))
            continue
        names[made.name] = origin
        told.append((True, f"{html_path}\n{pdf_path}\nconfiguration CRC {made.crc}"))
    return told


def _outcome(request: Request) -> Outcome:
    try:
        with _no_cycle_collection():
            return Outcome(request, document(list(request.paths), request.compare))
    except DocumentError as exc:
        return Outcome(request, None, _named(request.origin, str(exc)))


@contextmanager
def _no_cycle_collection() -> Iterator[None]:
    """WeasyPrint makes hundreds of thousands of objects that all live until the PDF is
    written: the cycle collector's passes over them find nothing and took a fifth of the
    time. Off while one document is made (its memory is held to the end anyway), in a
    process that makes documents only (the command, a worker): it is the process's
    switch, not this thread's."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _named(origin: str, message: str) -> str:
    """The message naming the project it is about (most do already)."""
    return message if message.startswith(origin) else f"{origin}: {message}"


def _collect(request: Request, future: Future[Outcome]) -> Outcome:
    try:
        return future.result()
    except Exception as exc:  # a fault of the worker: still this project's, the others go on
        return Outcome(request, None, f"{request.origin}: {type(exc).__name__}: {exc}")


def _size(request: Request) -> int:
    total = 0
    for path in request.paths:
        try:
            files = path.rglob("*.st") if path.is_dir() else [path]
            total += sum(file.stat().st_size for file in files)
        except OSError:
            pass  # a path that is not there is refused by its worker, with its name
    return total
