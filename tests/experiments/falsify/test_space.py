"""The search space: read from TOML, checked before anything runs, mapped onto an episode."""

import pytest

from racf.experiments.falsify.space import DEFAULT_SPACE, Dimension, load_space


def test_the_shipped_space_serves_every_attack_it_names():
    for attack in ("dropout_timed", "patch_occlusion", "lidar_spoof", "stealth_ramp", "frustum_spoof", "depth_bias"):
        space = load_space("odca", (attack,))
        assert space.dimensions and space.setting.endswith("+odca")


def test_the_patch_parameters_become_the_episodes_own_fields():
    space = load_space("raw", ("patch_occlusion",))
    spec = space.trial_spec({"sign": 2, "speed": 1.2, "run_up_m": 2.0, "stable_steps": 7,
                             "attack.patch_occlusion.rho": 0.8, "attack.patch_occlusion.t_atk": 1.5}, 5)
    assert spec.setting == "attack" and spec.rho == (0.8, 0.8) and spec.t_atk == (1.5, 1.5)
    assert spec.stable_steps == 7 and spec.run_up_m == 2.0 and spec.attack_params == {}


@pytest.mark.parametrize("text, message", [
    ("[weather]\nrain = [0, 1]\n", "unknown section"),
    ("[scenario]\nlane = [0, 1]\n", "may search"),
    ("[scenario]\nspeed = {low = 2.0, high = 1.0}\n", "A < B"),
    ("[scenario]\nsign = [0, 7]\n", "sign must lie"),
    ("[attack.dropout_timed]\nwhen = [1]\n", "takes"),
    ("[attack.warp_drive]\nx = [1]\n", "unknown attack"),
    ("[scenario\n", "not valid TOML"),
])
def test_a_bad_space_is_one_clear_error_before_anything_runs(tmp_path, text, message):
    path = tmp_path / "space.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_space("odca", ("dropout_timed",), path)


def test_an_unknown_defence_or_a_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="estimator must be one of"):
        load_space("tinfoil", ("dropout_timed",))
    with pytest.raises(ValueError, match="cannot read"):
        load_space("odca", ("dropout_timed",), tmp_path / "none.toml")
    assert DEFAULT_SPACE.exists()


def test_integer_dimensions_give_integers_back():
    dim = Dimension.parse("scans", {"low": 1, "high": 8, "int": True})
    assert dim.cast(3.0) == 3 and isinstance(dim.cast(3.0), int)
    with pytest.raises(ValueError, match="integer bounds"):
        Dimension.parse("scans", {"low": 1.5, "high": 8, "int": True})


@pytest.mark.parametrize("text, named", [
    ("[scenario]\nspeed = {low = 1.0, high = 9.0}\n", "speed = 9.0"),
    ("[scenario]\nstable_steps = {low = -5, high = 60, int = true}\n", "stable_steps = -5"),
    ("[attack.stealth_ramp]\nrate_mps = {low = 0.1, high = 30.0}\n", "attack.stealth_ramp.rate_mps = 30.0")])
def test_a_bound_the_episode_refuses_is_refused_before_a_draw_and_nothing_is_written(tmp_path, text, named):
    from racf.errors import UserError
    from racf.experiments.falsify.run import falsify

    (tmp_path / "space.toml").write_text(text)
    with pytest.raises(ValueError, match=named):
        load_space("odca", ("stealth_ramp",), tmp_path / "space.toml").extremes()
    with pytest.raises((ValueError, UserError), match=named):
        falsify("odca", ("stealth_ramp",), tmp_path / "out", budget=2, seeds=(0,), space_path=tmp_path / "space.toml",
                progress=False)
    assert not (tmp_path / "out").exists()  # no study file, no empty folders


def test_the_extremes_are_every_bound_of_every_dimension():
    space = load_space("odca", ("frustum_spoof",))
    specs = space.extremes()
    assert {s.sign for s in specs} == {0, 1, 2, 3} and {s.speed for s in specs} == {1.0, 2.0}
    assert {s.attack_params["frustum_spoof"]["scale_box"] for s in specs} == {False, True}
