"""The moment an episode is drawn at: where the attack acts and the defence answers, else where the
attack acts, else the brake; and the picture of it, for the sign and for the car ahead."""

import numpy as np
import pandas as pd
import pytest

from racf.experiments.viz.moment import LEAD, SIGN, choose_moment, target_of


def log(**columns):
    n = len(next(iter(columns.values())))
    base = {"t": np.arange(n) * 0.1, "d_true": np.linspace(2.0, 0.5, n), "sign_in_view": np.ones(n, bool)}
    return pd.DataFrame({**base, **columns})


def test_the_defence_answering_an_attack_is_the_moment():
    nan = np.nan
    m = choose_moment(log(attack_active=[0, 1, 1, 1, 1, 0], d_meas=[2.0, 1.9, 3.5, 3.0, 1.2, 1.0],
                          d_fused=[2.0, 1.7, 1.6, 1.4, 1.2, 1.0], brake=[0] * 6))
    assert (m.step, m.why) == (2, "the attack acts and the defence answers")  # the widest disagreement
    # The depth gone under a patch: a third of a second into the repair.
    m = choose_moment(log(attack_active=[0] + [1] * 9, d_meas=[2.0] + [nan] * 9, d_fused=np.linspace(2, 1, 10),
                          brake=[0] * 10))
    assert m.step == 4 and m.why == "the attack acts and the defence answers"


def test_without_an_answer_the_attack_acting_then_the_brake_then_the_nearest_point():
    m = choose_moment(log(attack_active=[0, 0, 1, 1, 1, 1, 1, 1], d_meas=[1.0] * 8, d_fused=[1.0] * 8, brake=[0] * 8))
    assert (m.step, m.why) == (5, "the attack acts")
    m = choose_moment(log(attack_active=[0] * 4, d_meas=[1.0] * 4, d_fused=[1.0] * 4, brake=[0, 0, 1, 1]))
    assert (m.step, m.why) == (2, "the car brakes")
    m = choose_moment(log(attack_active=[0] * 4, d_meas=[1.0] * 4, d_fused=[1.0] * 4, brake=[0] * 4))
    assert m.step == 3 and "nearest the sign" in m.why
    with pytest.raises(ValueError, match="empty"):
        choose_moment(pd.DataFrame(columns=["t"]))


def test_an_episode_that_follows_a_car_is_drawn_at_the_car_ahead():
    following = log(attack_active=[0, 1, 1], d_meas=[np.nan] * 3, d_fused=[np.nan] * 3, x=[0.0] * 3, y=[0.0] * 3,
                    yaw=[0.0] * 3, lead_x=[1.0, 1.1, 1.2], lead_y=[0.0] * 3, lead_d_meas=[0.7, 1.9, 2.0],
                    lead_d_fused=[0.7, 0.8, 0.9], brake=[0] * 3)
    from racf.sim.world.lead_manager import LeadManager
    from racf.sim.world.qcar2_body import QCar2Body

    declared = LeadManager().targets()
    target, with_gap = target_of(following, declared)
    from racf.sim.sensors.calibration import car_build

    # From the camera (where the depth and the defence measure from) to the lead's rear, along the camera's axis.
    camera_x = car_build(320, 240).camera_xy_m[0]
    assert target is LEAD and with_gap["lead_gap"].iloc[0] == pytest.approx(1.0 - camera_x - 0.425 / 2, abs=1e-9)
    assert choose_moment(with_gap, target).step == 2
    assert target_of(log(d_fused=[1.0], d_meas=[1.0]), declared)[0] is SIGN
    # Found through the world's declaration, whatever its columns are called; none declared: the sign.
    renamed = following.rename(columns={"lead_x": "van_x", "lead_y": "van_y"})
    assert target_of(renamed, (QCar2Body("van").target(("van_x", "van_y", "van_yaw")),))[0] is LEAD
    assert target_of(following)[0] is SIGN
    # A car in the world that the car's side never gave a distance to is not what the episode is about.
    undefended = following.assign(lead_d_fused=[np.nan] * 3)
    assert target_of(undefended, declared)[0] is SIGN


def test_the_outcome_is_the_first_contact_else_where_the_car_came_to_rest():
    from racf.experiments.viz.moment import episode_outcome

    hit = log(collision_with=["", "", "lead"], brake=[0, 1, 1], speed=[1.0, 0.5, 0.3])
    assert episode_outcome(hit) == (0.2, "collision with lead")
    rest = log(collision_with=[""] * 3, brake=[0, 1, 1], speed=[1.0, 0.5, 0.0], dist_to_stop_line=[1.0, 0.5, 0.12])
    assert episode_outcome(rest) == (0.2, "the car at rest, 0.12 m before the line")
    assert episode_outcome(log(brake=[0, 0, 0], speed=[1.0, 1.0, 1.0])) is None
    ran = log(brake=[0, 0, 0], speed=[1.0] * 3, dist_to_stop_line=[0.2, 0.05, -0.1])
    assert episode_outcome(ran) == (0.2, "the car passes the line without stopping")
    following = log(lead_gap=[0.9, 0.3, 0.5], speed=[1.0, 0.5, 0.0], collision_with=[""] * 3)
    assert episode_outcome(following, LEAD) == (0.1, "no contact: closest 0.30 m from the camera")


def test_a_gap_in_a_line_while_the_target_is_in_view_is_explained():
    from racf.experiments.viz.moment import gaps_caption

    steps = log(d_fused=[1.0, np.nan, np.nan, 0.8], d_meas=[1.0, 0.9, 0.85, 0.8], lidar=[np.nan] * 4)
    text = gaps_caption(steps, SIGN, np.ones(4, bool), {"d_fused": "the defence's distance", "d_meas": "the depth"})
    assert text.startswith("Gaps: the defence's distance has none for 0.20 s while the sign is in view")
    assert "no confirmed target" in text and "the depth has" not in text
    assert gaps_caption(steps, SIGN, np.zeros(4, bool), {"d_fused": "x"}) == ""


@pytest.mark.slow  # two episodes (about 5 s)
def test_racf_moment_draws_an_episode(tmp_path):
    from racf.experiments.cli import main

    out = tmp_path / "m.png"
    assert main(["moment", "--setting", "attack+odca", "--sign", "1", "--speed", "1.5", "--out", str(out)]) == 0
    from PIL import Image

    with Image.open(out) as picture:
        assert picture.width >= 1200 and picture.height >= 700
