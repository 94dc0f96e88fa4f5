"""Online change (spec section 9) as the engineer previews it before confirming, on top of
the resource's reload plan: what changed in the sources since the running configuration
(file by file, unified), the online parameter settings the reload will put back to the
project's values, and why a change that cannot be made online cannot, in words. The
browser, `padt reload --preview` and the REST API show this one preview."""

from __future__ import annotations

import dataclasses
import difflib
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from backend.compiler.test_functions import is_test_file
from backend.engineering.backup import (
    BackupError,
    project_files,
    restore_backup,
    safe_name,
)
from backend.engineering.compile_gate import CheckedCompile
from backend.engineering.project import ProjectError, compile_project, load_project
from backend.engineering.reload import (
    Reloaded,
    ReloadOptions,
    Risk,
    preview_reload,
    reload_checked,
    risks,
)
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.artifact import ResourceConfig
from runtime.contract.parameters import RESOURCE_BY_NAME
from runtime.contract.protocol import GetParameters, ReloadPlanInfo, SetParameter
from runtime.contract.refusal import Refusal

CONTEXT_LINES = 3  # of a unified diff, as `git diff` shows them
MAX_DIFF_LINES = 2_000  # per file: a whole library replaced is said, not shown line by line
# allow_online_settings first: the other settings are taken only while it is ON
_KEEP_ORDER = ("allow_online_settings",)


@dataclass(frozen=True)
class FileDiff:
    """One project file that differs from the running configuration's."""

    name: str  # relative to the project folder, `/`-separated
    change: str  # changed | added | removed
    lines: tuple[str, ...]  # the unified diff, without its two header lines
    cut: int = 0  # lines of the diff left out beyond MAX_DIFF_LINES


@dataclass(frozen=True)
class RunningSources:
    """The project files the running configuration was compiled from, and where they were
    found: a backup of what was loaded, or a project the PADT knows that compiles to it."""

    crc: str
    origin: str
    files: dict[str, str]  # relative path -> text


@dataclass(frozen=True)
class ParameterReset:
    """A resource parameter changed online that the reload puts back to the project's
    value, because a reload takes the new configuration's parameters whole."""

    name: str
    online: bool | int | str  # the value the resource runs with now
    project: bool | int | str  # the value after the reload
    keepable: str  # "" when the online value can be set again after the reload; else why not


@dataclass(frozen=True)
class OnlineChangePreview:
    resource: str
    project: str
    renames: dict[str, str]  # NEW -> OLD
    plan: ReloadPlanInfo
    check_crcs: tuple[str, str]  # the new configuration's CRC from each check compile
    risks: tuple[Risk, ...]  # what the user accepts one by one
    why_not: tuple[str, ...]  # why it cannot be made online, in words (empty: it can)
    resets: tuple[ParameterReset, ...]
    diff: tuple[FileDiff, ...]
    running_from: str  # where the running sources were found; "" when nowhere

    @property
    def possible(self) -> bool:
        return self.plan.possible


@dataclass(frozen=True)
class OnlineChanged:
    reloaded: Reloaded
    kept: tuple[str, ...]  # parameters whose online value was set again, "name value"
    not_kept: tuple[str, ...]  # "name: why" of those the resource refused to set again


# ---- the sources since the running configuration


def compiled_files(checked: CheckedCompile) -> dict[str, str]:
    """A compiled project's files by the names a backup keeps them under."""
    sources = {source.name: source.text for source in checked.project.sources}
    return _texts(project_files(sources, checked.config_text))


def _texts(files: Mapping[str, bytes]) -> dict[str, str]:
    return {
        name.split("/", 1)[1]: data.decode("utf-8", errors="replace")
        for name, data in files.items()
    }


def running_sources(
    crc: str, backups: Path, projects: Mapping[str, Path], project: str = ""
) -> RunningSources | None:
    """The sources of configuration `crc`: from the newest backup of it (what was loaded,
    proven by its CRC and digests), else from a project the PADT knows that still
    compiles to it. None when neither has it (loaded from elsewhere, backups gone)."""
    pattern = f"*_{crc.upper()}_*.zip"
    found = sorted(backups.glob(pattern), key=_newest_first) if backups.is_dir() else []
    # the project's own backups first: another project may compile to the same CRC
    found.sort(key=lambda path: not path.name.startswith(safe_name(project) + "_"))
    for archive in found:
        try:
            _, files = restore_backup(archive)
        except BackupError:
            continue  # a damaged or foreign archive proves nothing
        # the backup holds the project's tests too, which are no part of a configuration
        sources = {name: text for name, text in files.items() if not is_test_file(name)}
        return RunningSources(crc, f"backup {archive.name}", sources)
    for name, folder in sorted(projects.items()):
        try:
            loaded = load_project([folder])
        except (ProjectError, OSError):
            continue
        result = compile_project(loaded)
        if result.artifact is not None and result.artifact.crc == crc.upper():
            sources = {source.name: source.text for source in loaded.sources}
            config = folder / "padt.toml"
            text = config.read_text(encoding="utf-8") if config.is_file() else None
            return RunningSources(crc, f"project {name}", _texts(project_files(sources, text)))
    return None


def _newest_first(path: Path) -> tuple[int, str]:
    return (-path.stat().st_mtime_ns, path.name)


def source_diff(running: Mapping[str, str], new: Mapping[str, str]) -> list[FileDiff]:
    """Every file that differs, sorted by name, as a unified diff."""
    diffs = []
    for name in sorted(running.keys() | new.keys()):
        old_text, new_text = running.get(name), new.get(name)
        if old_text == new_text:
            continue
        change = "added" if old_text is None else "removed" if new_text is None else "changed"
        lines = list(
            difflib.unified_diff(
                (old_text or "").splitlines(),
                (new_text or "").splitlines(),
                lineterm="",
                n=CONTEXT_LINES,
            )
        )[2:]  # the ---/+++ header: the file is named by the FileDiff
        cut = max(0, len(lines) - MAX_DIFF_LINES)
        diffs.append(FileDiff(name, change, tuple(lines[:MAX_DIFF_LINES]), cut))
    return diffs


# ---- the online parameter settings a reload resets


def parameter_resets(online: ResourceConfig, project: ResourceConfig) -> list[ParameterReset]:
    """The online-changeable parameters whose running value differs from the project's
    (those not changeable online make the plan refuse the reload instead)."""
    resets = []
    for field in dataclasses.fields(ResourceConfig):
        spec = RESOURCE_BY_NAME.get(field.name)
        if spec is None or not spec.online:
            continue
        now, then = getattr(online, field.name), getattr(project, field.name)
        if now == then:
            continue
        keepable = ""
        if field.name != "allow_online_settings" and not (
            project.allow_online_settings or online.allow_online_settings
        ):
            keepable = "Allow Online Settings is OFF in the project: nothing is set online"
        resets.append(ParameterReset(field.name, now, then, keepable))
    resets.sort(key=lambda reset: (reset.name not in _KEEP_ORDER, reset.name))
    return resets


def parameter_words(reset: ParameterReset) -> str:
    return (
        f"{reset.name}: {_shown(reset.online)} online, {_shown(reset.project)} in the project; "
        f"the reload sets {_shown(reset.project)}"
    )


def _shown(value: bool | int | str) -> str:
    return ("ON" if value else "OFF") if isinstance(value, bool) else str(value)


# ---- why not online, in words

_WHY: tuple[tuple[re.Pattern[str], str], ...] = (
    (
        re.compile(r"the resource identity changes \((?P<old>.*) -> (?P<new>.*)\)"),
        "The project is for resource {new}, this resource is {old}: a configuration of "
        "another resource is only ever loaded by a download.",
    ),
    (
        re.compile(r"resource parameter (?P<name>\w+) changes \((?P<old>.*) -> (?P<new>.*)\)"),
        "{name} changes from {old} to {new}: it is fixed while the resource runs, only a "
        "download in STOP changes it. Keep {old} in the project for an online change.",
    ),
    (
        re.compile(r"no user program would remain"),
        "No program would remain: a running resource runs at least one program, so "
        "removing the last one needs STOP and a download.",
    ),
    (
        re.compile(r"Reload Allowed of the resource is OFF"),
        "The running configuration has Reload Allowed OFF: it accepts no online change at "
        "all. Download with Reload Allowed ON to make later changes online.",
    ),
    (
        re.compile(r"Reload Allowed of program (?P<name>\S+) is OFF"),
        "Program {name} changes or goes, and the running configuration has its Reload "
        "Allowed OFF: that program is changed only by a download.",
    ),
)


def why_not_online(refusals: Sequence[str]) -> list[str]:
    """Each reason the plan gives for needing STOP and a download, as a sentence that says
    what it means and what to do; a reason not known here is said as the resource said it."""
    words = []
    for refusal in refusals:
        for pattern, sentence in _WHY:
            match = pattern.fullmatch(refusal)
            if match is not None:
                words.append(sentence.format(**match.groupdict()))
                break
        else:
            words.append(f"{refusal[:1].upper()}{refusal[1:]}.")
    return words


# ---- the preview and the change


def preview_online_change(
    client: ResourceClient,
    checked: CheckedCompile,
    project: str,
    renames: Mapping[str, str],
    backups: Path,
    projects: Mapping[str, Path],
) -> OnlineChangePreview:
    """The reload plan of `checked` against the running state, with the source diff since
    the running configuration, the parameter resets and the reasons in words."""
    plan = preview_reload(client, checked.artifact, renames)
    online = client.ask(GetParameters()).resource
    running = running_sources(plan.old_crc, backups, projects, checked.project.name)
    diff = source_diff(running.files, compiled_files(checked)) if running is not None else []
    return OnlineChangePreview(
        resource=client.resource,
        project=project,
        renames=dict(renames),
        plan=plan,
        check_crcs=checked.check_crcs,
        risks=tuple(risks(plan)),
        why_not=tuple(why_not_online(plan.refusals)),
        resets=tuple(parameter_resets(online, checked.artifact.resource)),
        diff=tuple(diff),
        running_from=running.origin if running is not None else "",
    )


def chosen_resets(
    client: ResourceClient, checked: CheckedCompile, names: Sequence[str]
) -> list[ParameterReset]:
    """The resets of the parameters `names` (the user chose to keep their online values),
    read afresh from the resource; a name that is no reset now is refused."""
    online = client.ask(GetParameters()).resource
    resets = {r.name: r for r in parameter_resets(online, checked.artifact.resource)}
    unknown = sorted(set(names) - resets.keys())
    if unknown:
        raise Refusal(
            "bad_request",
            f"{', '.join(unknown)}: the reload does not reset it (the resource runs the "
            "project's value, or it is no online parameter)",
        )
    return [resets[name] for name in sorted(set(names))]


def online_change(
    client: ResourceClient,
    checked: CheckedCompile,
    options: ReloadOptions,
    keep: Sequence[ParameterReset],
    backups: Path,
    how: str,
) -> OnlineChanged:
    """Reload, then set again each online parameter value in `keep`: a reload takes the
    project's parameters whole, so a kept value is set by the same command as any online
    change (checked by the resource, an event in its log) right after the switch-over."""
    reloaded = reload_checked(client, checked, options, backups, how)
    kept, not_kept = [], []
    for reset in sorted(keep, key=lambda r: (r.name not in _KEEP_ORDER, r.name)):
        try:
            client.ask(SetParameter(reset.name, reset.online))
        except Refusal as refused:
            not_kept.append(f"{reset.name}: {refused.message}")
        except ResourceUnreachable as exc:
            not_kept.append(f"{reset.name}: {exc}")
        else:
            kept.append(f"{reset.name} {_shown(reset.online)}")
    return OnlineChanged(reloaded, tuple(kept), tuple(not_kept))
