"""The cache of compiled modules in the state folder is bounded: the entries used longest
ago go first, and a unit whose module went is built again when it is next needed."""

from __future__ import annotations

import os
from pathlib import Path

from runtime.code.native.build import prune
from runtime.code.native.tier import NativeTier
from runtime.code.native.worker import make
from tests.support.native_runs import compiled


def _program(name: str, step: int) -> str:
    return f"PROGRAM {name}\nVAR n : DINT; END_VAR\nn := n + {step};\nEND_PROGRAM\n"


def _files(cache: Path) -> list[Path]:
    return sorted(path for path in cache.rglob("*") if path.is_file())


def test_the_entries_used_longest_ago_go_first_and_are_built_again(
    tmp_path: Path, native_tier: NativeTier
) -> None:
    cache = tmp_path / "native"
    old, new = compiled(_program("P", 1)), compiled(_program("P", 2))
    first = make(old, cache)["units"][0]
    files_of_old = _files(cache)
    for path in files_of_old:  # used an hour ago
        os.utime(path, (path.stat().st_atime, path.stat().st_mtime - 3600))
    second = make(new, cache)["units"][0]
    assert Path(second["path"]).is_file() and Path(first["path"]).is_file()

    size_of_new = sum(p.stat().st_size for p in _files(cache) if p not in files_of_old)
    assert prune(cache, limit=size_of_new) == len(files_of_old)
    assert not Path(first["path"]).exists() and Path(second["path"]).is_file()

    again = make(old, cache)["units"][0]  # not in the index any more: built again
    assert again["module"] == first["module"] and Path(again["path"]).is_file()


def test_a_use_marks_an_entry_so_that_it_stays(tmp_path: Path, native_tier: NativeTier) -> None:
    cache = tmp_path / "native"
    old, new = compiled(_program("P", 1)), compiled(_program("P", 2))
    first = make(old, cache)["units"][0]
    files_of_old = _files(cache)
    for path in files_of_old:
        os.utime(path, (path.stat().st_atime, path.stat().st_mtime - 3600))
    make(new, cache)
    for path in _files(cache):
        if path not in files_of_old:  # the new one is older now
            os.utime(path, (path.stat().st_atime, path.stat().st_mtime - 7200))
    make(old, cache)  # from the index: marked used
    size_of_old = sum(p.stat().st_size for p in files_of_old)
    prune(cache, limit=size_of_old)
    assert _files(cache) == files_of_old and Path(first["path"]).is_file()


def test_pruning_never_follows_a_link_out_of_the_cache(tmp_path: Path) -> None:
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "keep.so").write_bytes(b"x" * 100)
    cache = tmp_path / "native" / "abc"
    cache.mkdir(parents=True)
    (cache / "old.so").write_bytes(b"y" * 100)
    (cache / "link").symlink_to(outside)
    assert prune(tmp_path / "native", limit=0) == 1
    assert (outside / "keep.so").is_file() and not (cache / "old.so").exists()
