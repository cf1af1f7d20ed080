"""Provenance: whole files or none, and a code version that follows the code."""

import os

import pandas as pd
import pytest

from racf.provenance import atomic_write, code_version, source_version


def test_atomic_write_writes_every_kind_and_leaves_no_temporary(tmp_path):
    atomic_write(tmp_path / "a.txt", "text")
    atomic_write(tmp_path / "b.bin", b"\x00\x01")
    atomic_write(tmp_path / "c.parquet", pd.DataFrame({"x": [1, 2]}))
    atomic_write(tmp_path / "d.txt", lambda path: path.write_text("by a writer"))
    assert (tmp_path / "a.txt").read_text() == "text" and (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    assert pd.read_parquet(tmp_path / "c.parquet")["x"].tolist() == [1, 2]
    assert (tmp_path / "d.txt").read_text() == "by a writer"
    assert not list(tmp_path.glob("*.tmp"))


def test_a_failed_write_keeps_the_old_file_whole(tmp_path):
    target = tmp_path / "result.json"
    atomic_write(target, "old")

    def crash(path):
        path.write_text("half")
        raise RuntimeError("killed mid-write")

    with pytest.raises(RuntimeError):
        atomic_write(target, crash)
    assert target.read_text() == "old" and os.listdir(tmp_path) == ["result.json"]
    with pytest.raises(TypeError, match="str, bytes"):
        atomic_write(target, 3)


def test_code_version_follows_content_and_names(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "racf_test_pkg").mkdir()
    (tmp_path / "racf_test_pkg" / "__init__.py").write_text("")
    (tmp_path / "racf_test_pkg" / "a.py").write_text("x = 1\n")
    (tmp_path / "racf_test_pkg" / "notes.md").write_text("not code")
    first = code_version.__wrapped__("racf_test_pkg")
    by_path = source_version(str(tmp_path / "racf_test_pkg"))
    (tmp_path / "racf_test_pkg" / "notes.md").write_text("still not code")
    assert code_version.__wrapped__("racf_test_pkg") == first
    (tmp_path / "racf_test_pkg" / "a.py").write_text("x = 2\n")
    assert code_version.__wrapped__("racf_test_pkg") != first
    assert source_version(str(tmp_path / "racf_test_pkg")) != by_path
    (tmp_path / "racf_test_pkg" / "a.py").rename(tmp_path / "racf_test_pkg" / "b.py")
    assert code_version.__wrapped__("racf_test_pkg") != first
    with pytest.raises(ValueError, match="no module or package 'racf_missing'"):
        code_version.__wrapped__("racf_missing")
    with pytest.raises(ValueError, match="no file or folder"):
        code_version.__wrapped__(str(tmp_path / "nowhere"))


def test_code_version_names_files_relative_to_the_root_so_a_moved_checkout_agrees(tmp_path):
    for where in ("one", "two"):
        (tmp_path / where / "ckpt").mkdir(parents=True)
        (tmp_path / where / "ckpt" / "head.npz").write_bytes(b"weights")
    assert source_version(str(tmp_path / "one" / "ckpt")) == source_version(str(tmp_path / "two" / "ckpt"))
