"""A project's files as an editor reads and saves them, for every adapter (browser, REST
API, CLI) alike.

What may be edited: `padt.toml` and `.st` files, in the project's folder or a sub-folder
of it (not a hidden one), as UTF-8 text. Anything else is refused with the reason: a path
with `..`, an absolute path, a path through a symbolic link that leads out of the folder,
another kind of file. A save names the hash (SHA-256 of the bytes) of the text it was made
from; when the file has changed since (another browser, another tool on the disk), it is
refused as a conflict with the current hash, so that no edit is silently lost. Writes are
atomic (a temporary file in the same folder, then renamed over the file), within the
compiler's size limits, and each is recorded in the PADT's audit log.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import os
import stat
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from backend.compiler.limits import MAX_FILE_BYTES, MAX_PROJECT_BYTES, MAX_PROJECT_FILES, MiB
from backend.engineering.padt_audit_log import AuditEntry, PadtAuditLog
from backend.engineering.project import PROJECT_FILE
from backend.engineering.project_access import READ, WRITE, Editor, require
from backend.engineering.project_shelf import ProjectShelf
from runtime.contract.private_files import staged_private
from runtime.contract.refusal import Refusal

MAX_PATH_CHARS = 512
MAX_DEPTH = 8  # folders below the project's


@dataclass(frozen=True)
class ProjectFile:
    path: str  # relative to the project's folder, with `/`
    kind: str  # "config" (padt.toml) or "st"
    bytes: int


@dataclass(frozen=True)
class FileText:
    path: str
    text: str
    hash: str  # SHA-256 of the file's bytes, hex


@dataclass(frozen=True)
class Saved:
    path: str
    hash: str  # the file's hash now
    old_hash: str  # before ("" for a new file)


@dataclass(frozen=True)
class DiskState:
    """What `changed_on_disk` found: whether the file differs from the hash the editor
    knows, and its hash now ("" when it no longer exists)."""

    path: str
    changed: bool
    hash: str


def content_hash(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def editable_path(folder: Path, path: str) -> tuple[str, Path]:
    """`path` (relative, with `/`) checked: its normal form and the file it names in
    `folder`. Refused (`path`) with the reason otherwise."""
    if not isinstance(path, str) or not path or len(path) > MAX_PATH_CHARS:
        raise Refusal("path", f"a file path has 1 to {MAX_PATH_CHARS} characters")
    if "\\" in path or "\x00" in path or any(ord(c) < 32 for c in path):
        raise Refusal("path", f"'{path[:80]}': a path uses '/' and no control characters")
    pure = PurePosixPath(path)
    if pure.is_absolute():
        raise Refusal("path", f"'{path[:80]}': a path is relative to the project's folder")
    parts = pure.parts
    if any(part in ("..", ".") or part.startswith(".") for part in parts):
        raise Refusal("path", f"'{path[:80]}': no '..', '.' or hidden names in a path")
    if len(parts) > MAX_DEPTH + 1:
        raise Refusal("path", f"'{path[:80]}': deeper than {MAX_DEPTH} folders")
    name = parts[-1]
    if not (name == PROJECT_FILE and len(parts) == 1) and not name.endswith(".st"):
        raise Refusal(
            "path",
            f"'{path[:80]}': only padt.toml and .st files of a project are edited here",
        )
    root = folder.resolve()
    target = root.joinpath(*parts)
    # a symbolic link (of the file or a folder on its way) must stay inside the project
    resolved = target.resolve()
    if resolved != root and root not in resolved.parents:
        raise Refusal("path", f"'{path[:80]}' leads out of the project's folder")
    return "/".join(parts), target


def list_files(shelf: ProjectShelf, project: str, editor: Editor) -> list[ProjectFile]:
    """The editable files of a project, padt.toml first, then the .st files by path."""
    require(editor, READ)
    return folder_files(shelf.folder(project))


def read_file(shelf: ProjectShelf, project: str, path: str, editor: Editor) -> FileText:
    """A file's text and hash. Refused: not found, not UTF-8, larger than a file may be."""
    require(editor, READ)
    return folder_text(shelf.folder(project), path)


def folder_files(folder: Path) -> list[ProjectFile]:
    """The editable files in a project folder (no level checked: for the services)."""
    root = folder.resolve()
    found = []
    config = root / PROJECT_FILE
    if config.is_file():
        found.append(ProjectFile(PROJECT_FILE, "config", config.stat().st_size))
    for path in sorted(itertools.islice(root.rglob("*.st"), MAX_PROJECT_FILES + 1)):
        relative = path.relative_to(root)
        if any(part.startswith(".") for part in relative.parts) or not path.is_file():
            continue
        if root not in path.resolve().parents:
            continue  # a link out of the project: not the project's file
        found.append(ProjectFile(relative.as_posix(), "st", path.stat().st_size))
    return found


def folder_text(folder: Path, path: str) -> FileText:
    """A file of a project folder as text with its hash (no level checked)."""
    name, target = editable_path(folder, path)
    data = _read_bytes(name, target)
    if data is None:
        raise Refusal("not_found", f"the project has no file '{name}'")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise Refusal("bad_value", f"{name} is not UTF-8 text ({exc.reason})") from None
    return FileText(name, text, content_hash(data))


def changed_on_disk(
    shelf: ProjectShelf, project: str, path: str, known_hash: str, editor: Editor
) -> DiskState:
    """Whether the file is no longer what the editor has (`known_hash`): changed or
    deleted by another tool, or saved by another user. Cheap enough to poll."""
    require(editor, READ)
    name, target = editable_path(shelf.folder(project), path)
    data = _read_bytes(name, target)
    now = "" if data is None else content_hash(data)
    return DiskState(name, now != known_hash, now)


def save_file(
    shelf: ProjectShelf,
    project: str,
    path: str,
    text: str,
    base_hash: str | None,
    editor: Editor,
    action: str = "save",
) -> Saved:
    """Write `text` to the file. `base_hash`: the hash of the text the edit started from;
    None for a new file (refused when it exists). Refused as a `conflict`, with the current
    hash (`current_hash`, "" when the file is gone), when the file is not that any more."""
    require(editor, WRITE)
    audit = shelf.audit_log()
    name, target = editable_path(shelf.folder(project), path)
    data = _text_bytes(name, text)
    with shelf.lock:
        current = _read_bytes(name, target)
        current_hash = "" if current is None else content_hash(current)
        if base_hash is None and current is not None:
            raise Refusal("exists", f"{name} exists already", current_hash=current_hash)
        if base_hash is not None and base_hash != current_hash:
            how = "was deleted" if current is None else "was changed"
            raise Refusal(
                "conflict",
                f"{name} {how} since it was opened (by another user or another tool); "
                "reload it or compare before saving",
                current_hash=current_hash,
            )
        _check_project_size(shelf.folder(project), target, len(data))
        saved = Saved(name, content_hash(data), current_hash)
        try:
            staged = _staged(target, data)
        except OSError as exc:
            raise Refusal("project", f"{name} could not be saved: {exc.strerror}") from None
        try:
            with _audited(audit, editor, project, action, name, saved.old_hash, saved.hash):
                os.replace(staged, target)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(staged)  # still there when the audit or the rename failed
    return saved


def delete_file(
    shelf: ProjectShelf, project: str, path: str, base_hash: str, editor: Editor
) -> Saved:
    """Delete a .st file that is still what the editor knows (`base_hash`); audited."""
    require(editor, WRITE)
    audit = shelf.audit_log()
    name, target = editable_path(shelf.folder(project), path)
    if name == PROJECT_FILE:
        raise Refusal("bad_value", "padt.toml is the project itself: it is not deleted")
    with shelf.lock:
        current = _read_bytes(name, target)
        if current is None:
            raise Refusal("not_found", f"project {project} has no file '{name}'")
        if content_hash(current) != base_hash:
            raise Refusal(
                "conflict",
                f"{name} was changed since it was opened; it was not deleted",
                current_hash=content_hash(current),
            )
        with _audited(audit, editor, project, "delete", name, base_hash, ""):
            target.unlink()
    return Saved(name, "", base_hash)


def rename_file(
    shelf: ProjectShelf, project: str, path: str, new_path: str, editor: Editor
) -> Saved:
    """Move a .st file to a new name in the project (refused onto an existing file)."""
    require(editor, WRITE)
    audit = shelf.audit_log()
    folder = shelf.folder(project)
    name, target = editable_path(folder, path)
    new_name, new_target = editable_path(folder, new_path)
    if PROJECT_FILE in (name, new_name):
        raise Refusal("bad_value", "padt.toml keeps its name")
    with shelf.lock:
        current = _read_bytes(name, target)
        if current is None:
            raise Refusal("not_found", f"project {project} has no file '{name}'")
        if os.path.lexists(new_target) and new_target.resolve() != target.resolve():
            raise Refusal("exists", f"{new_name} exists already")
        digest = content_hash(current)
        with _audited(audit, editor, project, "rename", name, digest, digest, new_name):
            new_target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(target, new_target)
    return Saved(new_name, digest, digest)


def history(
    shelf: ProjectShelf, project: str, editor: Editor, file: str | None = None, limit: int = 200
) -> list[AuditEntry]:
    """The audit log's entries of a project (of one file, under its old or new name),
    newest first: who changed what, as an engineer reads a file's history."""
    require(editor, READ)
    shelf.folder(project)  # an unknown project is refused, not an empty history
    if shelf.audit is None:
        return []  # a PADT without an audit log changes nothing
    entries = [
        e
        for e in shelf.audit.entries()
        if e.project == project and (file is None or file in (e.file, e.new_file))
    ]
    return entries[::-1][: max(0, limit)]


def _read_bytes(name: str, target: Path) -> bytes | None:
    """The file's bytes; None when there is no file. A file larger than any file may be is
    refused rather than read whole."""
    try:
        with target.open("rb") as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                raise Refusal("path", f"{name} is not a file")
            data = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        return None
    except (IsADirectoryError, NotADirectoryError):
        raise Refusal("path", f"{name} is not a file") from None
    except OSError as exc:
        raise Refusal("project", f"{name} cannot be read: {exc.strerror}") from None
    if len(data) > MAX_FILE_BYTES:
        raise Refusal("too_large", f"{name} is larger than {MAX_FILE_BYTES // MiB} MiB")
    return data


def _text_bytes(name: str, text: str) -> bytes:
    if not isinstance(text, str):
        raise Refusal("bad_value", "a file's content is text")
    if len(text) > MAX_FILE_BYTES:  # each character is at least a byte
        raise Refusal("too_large", f"{name} would be larger than {MAX_FILE_BYTES // MiB} MiB")
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError:
        raise Refusal("bad_value", f"{name}: the text holds characters UTF-8 cannot") from None
    if len(data) > MAX_FILE_BYTES:
        raise Refusal("too_large", f"{name} would be larger than {MAX_FILE_BYTES // MiB} MiB")
    return data


def _check_project_size(folder: Path, target: Path, size: int) -> None:
    """The compiler's limits on the whole project, with the file as it would be."""
    root = folder.resolve()
    total, files = size, 1
    for path in itertools.islice(root.rglob("*.st"), MAX_PROJECT_FILES + 1):
        if path.resolve() == target.resolve() or not path.is_file():
            continue
        files += 1
        total += path.stat().st_size
    if files > MAX_PROJECT_FILES:
        raise Refusal("too_large", f"a project has at most {MAX_PROJECT_FILES:,} files")
    if total > MAX_PROJECT_BYTES:
        raise Refusal(
            "too_large",
            f"the project's sources would be larger than {MAX_PROJECT_BYTES // MiB} MiB",
        )


def _staged(target: Path, data: bytes) -> Path:
    """`data` in a new file beside `target`, synced, for `os.replace` onto it: a save is the
    whole new content or the old one, never half. The file keeps its mode; a new one is
    0644 as an editor makes it (the umask is not read: setting it to read it would race
    other threads)."""
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        mode = 0o644
    temporary = staged_private(target, data)  # owner-only until its mode is set
    try:
        os.chmod(temporary, mode)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
    return temporary


@contextlib.contextmanager
def _audited(
    audit: PadtAuditLog, editor: Editor, project: str, action: str, *what: str
) -> Iterator[None]:
    """The change in the `with` block, recorded first: a change the audit log cannot take
    is not made (refused, `audit`), and one that then fails is said as failed."""
    try:
        audit.record(editor.user, project, action, *what)
    except OSError as exc:
        raise Refusal(
            "audit", f"the audit log cannot be written ({exc.strerror}): nothing was changed"
        ) from None
    try:
        yield
    except OSError as exc:
        raise Refusal("project", f"{what[0]} could not be changed: {exc.strerror}") from None
