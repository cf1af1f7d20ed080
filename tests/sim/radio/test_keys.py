"""A real fleet's keys as files: each vehicle's secret its owner's alone, the public keys a car loads, and
nothing loaded from a folder others may write or from a file that is no key."""

from __future__ import annotations

import os
import stat

import pytest
from nacl.signing import SigningKey

from racf.errors import UserError
from racf.sim.radio import Broadcast, V2VMessage, load_trust_store, open_signed, sign, write_fleet_keys


def test_written_keys_sign_what_the_loaded_trust_store_verifies(tmp_path):
    written = write_fleet_keys(tmp_path / "fleet", vehicles=(1, 2))
    assert [p.name for p in written] == ["1.signing_key", "1.verify_key", "2.signing_key", "2.verify_key"]
    assert stat.S_IMODE(os.stat(tmp_path / "fleet" / "vehicles" / "1.signing_key").st_mode) == 0o600
    assert stat.S_IMODE(os.stat(tmp_path / "fleet" / "vehicles").st_mode) == 0o700
    trusted = load_trust_store(tmp_path / "fleet" / "trusted")
    assert sorted(trusted) == [1, 2]
    key = SigningKey((tmp_path / "fleet" / "vehicles" / "2.signing_key").read_bytes().strip(),
                     encoder=__import__("nacl.encoding", fromlist=["HexEncoder"]).HexEncoder)
    raw = sign(V2VMessage(1, 0.0, Broadcast(2, 1.0, 0.0, 0.0, 0.5, 0.0, False)), key)
    assert open_signed(raw, trusted).message is not None
    assert open_signed(raw, {1: trusted[1]}).refused == "unknown sender"


def test_keys_are_never_overwritten_and_a_vehicle_outside_the_fleet_is_named(tmp_path):
    write_fleet_keys(tmp_path / "fleet", vehicles=(1,))
    with pytest.raises(FileExistsError, match="1.signing_key exists"):
        write_fleet_keys(tmp_path / "fleet", vehicles=(1,))
    with pytest.raises(ValueError, match="vehicle 99 is not in the fleet"):
        write_fleet_keys(tmp_path / "other", vehicles=(99,))
    assert not (tmp_path / "other").exists()  # nothing made before the names were checked


def test_a_trust_store_is_loaded_only_from_a_checked_folder_of_keys(tmp_path):
    folder = tmp_path / "fleet"
    write_fleet_keys(folder, vehicles=(3,))
    trusted = folder / "trusted"
    (trusted / "9.verify_key").write_text("00" * 32)
    with pytest.raises(ValueError, match="9.verify_key is no vehicle's public key"):
        load_trust_store(trusted)
    (trusted / "9.verify_key").unlink()
    (trusted / "4.verify_key").write_text("not hex")
    with pytest.raises(ValueError, match="4.verify_key is no vehicle's public key"):
        load_trust_store(trusted)
    (trusted / "4.verify_key").unlink()
    trusted.chmod(0o777)
    with pytest.raises(UserError, match="may be written by others"):
        load_trust_store(trusted)
    trusted.chmod(0o700)
    empty = tmp_path / "empty"
    empty.mkdir(mode=0o700)
    with pytest.raises(ValueError, match="no vehicle's public key"):
        load_trust_store(empty)
