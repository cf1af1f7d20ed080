"""Key folders checked as OpenSSH's StrictModes checks them: a folder others may write, a link, a file
not the user's own or open to others is refused in one line naming the fix, before anything is read
or written; every folder racf makes is its owner's alone whatever the umask."""

from __future__ import annotations

import os
import stat

import pytest

from racf.errors import UserError
from racf.experiments.link.curve import CarKeys, ServerKeys, make_keys
from tests.conftest import run_cli


def _mode(path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def test_a_folder_others_may_write_is_refused_and_its_planted_key_never_admitted(tmp_path, capsys):
    folder = tmp_path / "keys"
    make_keys(folder)
    (folder / "admitted" / "intruder.key").write_text((folder / "admitted" / "car.key").read_text())
    folder.chmod(0o777)
    code, _ = run_cli(["serve", "keys", str(folder), "--car", "other"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert f"key folder {folder} may be written by others (mode 777)" in err and f"chmod 700 {folder}" in err
    assert _mode(folder) == 0o777 and not (folder / "cars" / "other.key_secret").exists()  # left as it was
    with pytest.raises(UserError, match="may be written by others"):
        ServerKeys.load(folder)
    folder.chmod(0o700)
    (folder / "admitted").chmod(0o777)
    with pytest.raises(UserError, match=r"admitted may be written by others \(mode 777\)"):
        ServerKeys.load(folder)


def test_a_linked_folder_is_refused_and_what_it_points_to_is_left_alone(tmp_path):
    target = tmp_path / "elsewhere"
    target.mkdir(mode=0o755)
    target.chmod(0o755)
    (tmp_path / "keys").symlink_to(target)
    with pytest.raises(UserError, match="is a symbolic link"):
        make_keys(tmp_path / "keys")
    assert _mode(target) == 0o755 and not any(target.iterdir())
    # A linked admitted/ in a real folder: refused where the service loads it.
    real = tmp_path / "real"
    make_keys(real)
    (real / "admitted").rename(tmp_path / "open")
    (tmp_path / "open").chmod(0o777)
    (real / "admitted").symlink_to(tmp_path / "open")
    with pytest.raises(UserError, match=r"admitted is a symbolic link"):
        ServerKeys.load(real)


def test_every_folder_made_is_the_owner_s_alone_under_the_widest_umask(tmp_path):
    old = os.umask(0)
    try:
        make_keys(tmp_path / "a" / "b" / "keys")
    finally:
        os.umask(old)
    for folder in (tmp_path / "a", tmp_path / "a" / "b", tmp_path / "a" / "b" / "keys",
                   tmp_path / "a" / "b" / "keys" / "cars", tmp_path / "a" / "b" / "keys" / "admitted"):
        assert _mode(folder) == 0o700, folder


def test_a_link_where_a_key_would_go_leaves_nothing_half_written(tmp_path):
    folder = tmp_path / "keys"
    (folder / "cars").mkdir(parents=True, mode=0o700)
    (folder / "cars" / "car.key_secret").symlink_to(tmp_path / "nowhere")  # dangling
    with pytest.raises(UserError, match="car.key_secret exists; keys are never overwritten"):
        make_keys(folder)
    assert not (folder / "server.key_secret").exists() and not (folder / "admitted").exists()


def test_a_secret_others_may_read_and_a_key_not_the_user_s_are_refused(tmp_path):
    folder = tmp_path / "keys"
    make_keys(folder)
    secret = folder / "cars" / "car.key_secret"
    secret.chmod(0o640)
    with pytest.raises(UserError, match=r"may be read or written by others \(mode 640\); `chmod 600"):
        CarKeys.load(folder)
    secret.chmod(0o600)
    assert CarKeys.load(folder).name == "car"
    (folder / "admitted" / "car.key").chmod(0o666)
    with pytest.raises(UserError, match=r"car.key may be written by others \(mode 666\); `chmod 644"):
        ServerKeys.load(folder)
