"""The online module: Proposition 1 end to end, no NaN/inf out, clear errors, step == run."""

import json
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.odca import ODCA, Alignment, CheckpointError, GateConfig, LastValuePrior, ODCAConfig
from racf.odca.features import MAX_RANGE_M
from racf.odca.head import head_parameters, make_head
from racf.odca.online import SHIPPED_HEAD


def _stub(alignment=Alignment(1.0, 0.0)) -> ODCA:
    """ODCA with the shipped head and a cheap stub prior (the Protocol makes it swappable)."""
    shipped = ODCA.load(prior=LastValuePrior())
    config = ODCAConfig.from_json({**shipped.config.to_json(), "alignment": {"alpha": alignment.alpha,
                                                                             "beta": alignment.beta}})
    return ODCA(config, shipped.head, LastValuePrior())


wild = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just(0.0), st.floats(-5, 0),
                 st.floats(0.1, 5))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(wild, wild, wild, wild, wild, wild), min_size=1, max_size=40))
def test_no_inf_out_and_nan_only_for_no_target(rows):
    m = _stub()
    for depth, conf, lidar, speed, yaw_rate, bearing in rows:
        out = m.step(depth=depth, confidence=conf, lidar=lidar, speed=speed, yaw_rate=yaw_rate, bearing=bearing)
        assert out.has_target == (out.source_name != "none")
        if out.has_target:
            assert 0.0 <= out.d_fused <= MAX_RANGE_M and 0.0 <= out.d_rep <= MAX_RANGE_M
        assert math.isfinite(out.r_delta) and out.w in (0.0, 1.0)


def test_no_target_reads_as_no_distance_not_zero_metres():
    m = _stub()
    for _ in range(5):
        out = m.step(depth=float("nan"), confidence=0.0, speed=1.0)
        assert math.isnan(out.d_fused) and not out.has_target and out.source_name == "none"
    out = m.step(depth=1.8, confidence=0.9, speed=1.0)
    assert out.d_fused == 1.8 and out.has_target


class _BlownUpPrior(LastValuePrior):
    """Forecasts no distance can have (as the tiny prior did on one test drive)."""

    def forecast(self, context, horizon):
        mean, std = super().forecast(context, horizon)
        return np.where(np.isfinite(mean), -15.0, mean), np.where(np.isfinite(std), 25.0, std)


class _NoPrior(LastValuePrior):
    def forecast(self, context, horizon):
        mean, std = super().forecast(context, horizon)
        return np.full_like(mean, np.nan), np.full_like(std, np.nan)


def test_a_forecast_that_is_no_distance_counts_as_no_forecast():
    shipped = _stub()
    blown, none = (ODCA(shipped.config, shipped.head, prior) for prior in (_BlownUpPrior(), _NoPrior()))
    frame = pd.DataFrame({"d_meas": [2.0 - 0.02 * t if t < 40 else np.nan for t in range(60)],
                          "c_meas": [0.9 if t < 40 else 0.0 for t in range(60)],
                          "lidar": [2.0 - 0.02 * t for t in range(60)], "speed": 1.0})
    pd.testing.assert_frame_equal(blown.run(frame), none.run(frame))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-0.05, 0.05), st.booleans(), st.floats(-0.01, 0.01)), min_size=1, max_size=40),
       st.floats(0.5, 2.0))
def test_clean_depth_passes_through_exactly(rows, speed):
    """Proposition 1: depth that agrees with the LiDAR (or, without it, with the car's motion) is never changed."""
    m = _stub()
    truth = 3.0
    for offset, lidar_seen, noise in rows:
        truth -= speed * 0.02
        depth = truth + noise
        lidar = depth + offset * m.config.gate.tau_m / 0.05 * 0.999 if lidar_seen else float("nan")
        out = m.step(depth=depth, confidence=0.9, lidar=lidar, speed=speed)
        assert out.w == 0.0 and out.d_fused == depth and out.source_name == "depth"


def _approach(n=100, speed=1.5, blackout=(40, 90)):
    """A straight approach: the true distance and the depth with a blackout."""
    truth = 3.5 - speed * 0.02 * np.arange(n)
    depth = truth.copy()
    depth[blackout[0]:blackout[1]] = np.nan
    return truth, depth


def test_kinematics_carries_a_blackout_without_lidar():
    m = _stub()
    truth, depth = _approach()
    out = [m.step(depth=d, confidence=0.0 if np.isnan(d) else 0.9, speed=1.5) for d in depth]
    fused = np.array([o.d_fused for o in out])
    assert {o.source_name for o in out[40:90]} == {"kinematics"}
    assert np.abs(fused - truth).max() <= m.config.gate.tau_m + 1e-9  # the head bends it by at most tau


@settings(max_examples=40, deadline=None)
@given(st.integers(10, 50), st.integers(5, 40), st.floats(-1.5, 1.5).filter(lambda b: abs(b) > 0.5),
       st.booleans(), st.floats(0.6, 3.0))
def test_a_spoofed_lidar_that_disagrees_with_depth_and_kinematics_cannot_move_the_output(start, length, bias,
                                                                                          blackout, spoof):
    """The same drive with the LiDAR silent, and with it spoofed (far from the depth and from d_kin,
    a depth that is blacked out or honest): d_fused is the same number. Perception reports the
    spoofed track as one no depth ever confirmed, as it is."""
    truth, depth = _approach(n=100, blackout=(start, start + length) if blackout else (0, 0))
    quiet, spoofed = _stub(), _stub()
    for t, (d, true_d) in enumerate(zip(depth, truth)):
        conf = 0.0 if np.isnan(d) else 0.9
        a = quiet.step(depth=d, confidence=conf, speed=1.5)
        l = true_d + spoof if start <= t < start + length and true_d + spoof > 0.2 else float("nan")
        k = spoofed._witnesses.branch
        if not np.isnan(l):  # the spoof disagrees with both witnesses (as the gate will see them this step)
            expected_k = k.distance - 1.5 * 0.02 if k.alive else np.nan
            if abs(l - expected_k) <= k.tolerance(spoofed.config.gate.tau_m) + 0.01 or abs(l - d) <= 0.2:
                l = float("nan")
        b = spoofed.step(depth=d, confidence=conf, lidar=l, speed=1.5, lidar_confirmed=False)
        assert a.d_fused == b.d_fused or (np.isnan(a.d_fused) and np.isnan(b.d_fused))



@pytest.mark.parametrize("lidar_from", [0, 1, 15])
@pytest.mark.parametrize("bias", [-0.8, 0.6])
def test_a_depth_biased_from_first_sight_loses_to_a_confirmed_lidar_whenever_it_arrives(lidar_from, bias):
    """A depth wrong from the first frame anchors a d_kin that only echoes it: that is no second
    witness. Whether the LiDAR reports with the first frame or later, the output rests on it."""
    m = _stub()
    truth = 2.5 - 1.5 * 0.02 * np.arange(40)
    outs = [m.step(depth=d + bias, confidence=0.95, lidar=d if t >= lidar_from else math.nan, speed=1.5)
            for t, d in enumerate(truth)]
    after = outs[lidar_from + 12:]
    assert all(o.source_name.startswith("lidar") for o in outs[lidar_from + 1:])
    assert max(abs(o.d_fused - d) for o, d in zip(after, truth[lidar_from + 12:])) <= m.config.gate.tau_m


def test_an_unconfirmed_lidar_track_does_not_outvote_a_first_sight_depth():
    """The same, but perception says no depth ever agreed with the track (the scan plane may miss
    the plate and range the wall behind): the confident depth goes on passing."""
    m = _stub()
    truth = 2.5 - 1.5 * 0.02 * np.arange(40)
    outs = [m.step(depth=d, confidence=0.95, lidar=d + 0.9 if t >= 10 else math.nan, speed=1.5,
                   lidar_confirmed=False) for t, d in enumerate(truth)]
    assert all(o.source_name == "depth" and o.d_fused == d for o, d in zip(outs, truth))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(wild, st.floats(0, 1), wild, st.floats(0, 3)), min_size=2, max_size=60))
def test_a_repair_moves_no_further_per_step_than_the_car_plus_the_tolerance_and_a_pass_is_the_depth(rows):
    m = _stub()
    prev = float("nan")
    for depth, conf, lidar, speed in rows:
        out = m.step(depth=depth, confidence=conf, lidar=lidar, speed=speed)
        if out.w == 0.0:
            assert out.d_fused == depth  # Proposition 1 holds for the output, not only the vote
        elif math.isfinite(prev) and out.has_target:
            assert abs(out.d_fused - (prev - speed * 0.02)) <= m.config.step_bound_m + 1e-9
        prev = out.d_fused


def test_a_depth_that_passes_right_after_a_repair_is_not_bounded_towards_it():
    """A blackout long enough to lose the kinematic branch, so the repair rests on the prior's
    stale forecast; then the depth is back and the LiDAR confirms it. That first passing depth
    is output as it is, though it lies far beyond the step bound from the repair before it."""
    m = _stub()
    m.config = ODCAConfig.from_json({**m.config.to_json(), "kinematics": {"max_std_m": 0.05}})
    d = 2.0
    for _ in range(10):
        m.step(depth=d, confidence=0.9, lidar=d, speed=1.0)
        d -= 0.02
    for _ in range(30):
        before = m.step(depth=float("nan"), confidence=0.0, speed=1.0)
        d -= 0.02
    assert before.source_name == "prior" and abs(before.d_fused - d) > m.config.step_bound_m
    back = m.step(depth=d, confidence=0.9, lidar=d, speed=1.0)
    assert back.w == 0.0 and back.d_fused == d


def test_an_unconfirmed_depth_is_flagged_but_not_corrected():
    """First sight with a confidence under the gate's trust: nothing to vote against, so the
    step is flagged (w = 1) and rests on the depth; the head does not guess a correction."""
    m = _stub()
    low = m.config.gate.trust_confidence / 2
    out = m.step(depth=1.7, confidence=low, speed=1.0)
    assert out.source_name == "depth (unconfirmed)" and out.w == 1.0
    assert out.d_fused == 1.7 and out.r_delta == 0.0


def test_wrong_shapes_and_columns_are_clear_errors():
    m = _stub()
    with pytest.raises(ValueError, match="scalar per step"):
        m.step(depth=np.ones(3), confidence=1.0)
    with pytest.raises(ValueError, match="d_meas"):
        m.run(pd.DataFrame({"x": [1.0]}))
    with pytest.raises(ValueError, match="dt"):
        m.step(depth=1.0, confidence=1.0, dt=0.0)


def _series(n, seed):
    rng = np.random.default_rng(seed)
    d = np.linspace(2.5, 0.5, n) + rng.normal(0, 0.005, n)
    d[rng.random(n) < 0.1] = np.nan
    d[n // 2:n // 2 + 20] += 0.7
    lidar = np.where(rng.random(n) < 0.5, d + 0.12, np.nan)
    return pd.DataFrame({"d_meas": d, "c_meas": rng.uniform(0.3, 1, n), "lidar": lidar, "speed": 1.0,
                         "yaw_rate": rng.normal(0, 0.3, n), "bearing": rng.normal(0, 0.3, n),
                         "slot": (np.arange(n) >= n - 15).astype(int)})


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_batched_run_matches_step_exactly_with_the_shipped_prior():
    m = ODCA.load()
    a, b = _series(90, 0), _series(70, 1)
    df = pd.concat([a.assign(series_id="a"), b.assign(series_id="b")], ignore_index=True)
    batched = m.run(df)
    for sid, part in (("a", a), ("b", b)):
        m.reset()
        rows = []
        for r in part.itertuples():
            if r.Index and r.slot != part["slot"].iloc[r.Index - 1]:
                m.reset()  # the car resets its estimator when the track changes target
            rows.append(vars(m.step(depth=r.d_meas, confidence=r.c_meas, lidar=r.lidar, speed=r.speed,
                                    yaw_rate=r.yaw_rate, bearing=r.bearing)))
        got = batched[df["series_id"] == sid].reset_index(drop=True)
        pd.testing.assert_frame_equal(got, pd.DataFrame(rows), check_exact=True)


def test_head_size_and_checkpoint_errors(tmp_path):
    assert head_parameters(make_head()) == 917  # the paper's head has 921
    m = ODCA.load(prior=LastValuePrior())
    assert m.head.n_parameters == 917
    with pytest.raises(CheckpointError, match="no ODCA checkpoint"):
        ODCA.load(tmp_path / "nothing")
    m.save(tmp_path / "ok")
    assert ODCA.load(tmp_path / "ok", prior=LastValuePrior()).config == m.config
    (tmp_path / "ok" / "head.npz").write_bytes(b"garbage")
    with pytest.raises(CheckpointError, match="corrupt"):
        ODCA.load(tmp_path / "ok", prior=LastValuePrior())
    m.save(tmp_path / "bad_cfg")
    (tmp_path / "bad_cfg" / "odca.json").write_text(json.dumps({"refresh_steps": 99}))
    with pytest.raises(CheckpointError, match="corrupt or from an older racf"):
        ODCA.load(tmp_path / "bad_cfg", prior=LastValuePrior())
    old = json.loads((tmp_path / "ok" / "odca.json").read_text())
    old["gate"] = {"tau_low": 0.1, "tau_high": 0.4, "gamma": 1.0, "trust_confidence": 0.4}  # before the vote
    (tmp_path / "bad_cfg" / "odca.json").write_text(json.dumps(old))
    with pytest.raises(CheckpointError, match="retrain it with `racf odca train`"):
        ODCA.load(tmp_path / "bad_cfg", prior=LastValuePrior())
    assert (SHIPPED_HEAD / "train_report.json").exists()


def test_calibrate_fits_the_alignment_from_paired_arrays():
    m = _stub()
    l = np.linspace(0.5, 3, 100)
    a = m.calibrate(1.02 * l - 0.1, l)
    assert a.alpha == pytest.approx(1.02, abs=1e-3) and m.config.alignment == a
    assert isinstance(m.config.gate, GateConfig)


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 5.0), st.floats(1.0, 2.0))
def test_a_drift_of_depth_and_lidar_together_is_caught_by_the_kinematic_baseline(rate, speed):
    """A frustum spoof: depth and LiDAR agree with each other and drift from the truth at
    ``rate`` m/s. Re-anchoring follows them, the odometry-only baseline does not: the drift
    is flagged before it passes the baseline's tolerance, and the output stays near the truth."""
    m = _stub()
    n, start = 150, 30
    truth = 6.5 - speed * 0.02 * np.arange(n)  # >= 0.5 m to the end
    drift = rate * 0.02 * np.clip(np.arange(n) - start, 0, None)
    out = [m.step(depth=t + b, confidence=0.9, lidar=t + b, speed=speed, bearing=0.0) for t, b in zip(truth, drift)]
    flagged = np.array([o.w for o in out]) == 1.0
    assert flagged.any() and not flagged[:start].any()
    first = int(np.argmax(flagged))
    kin = m.config.kinematics
    travelled = speed * 0.02 * first
    bound = m.config.gate.tau_m + kin.n_sigma * (kin.anchor_std_m + kin.drift_travel_std * travelled
                                                 + kin.time_std_mps * 0.02 * first)
    # Caught within one step of the tolerance; where the drift cancels the car's motion the
    # depth repeats exactly, which reads as a held camera frame: one frame's travel more.
    held = speed * kin.camera_frame_s if rate == speed else 0.0
    assert drift[first] <= bound + rate * 0.02 + held + 1e-9
    assert {out[i].source_name for i in np.flatnonzero(flagged)} == {"kinematic baseline"}
    fused = np.array([o.d_fused for o in out])
    assert np.abs(fused - truth)[flagged].max() <= bound + m.config.gate.tau_m + 1e-6


def test_a_depth_that_passed_on_the_branchs_word_alone_does_not_re_anchor_it():
    m = _stub()
    truth = 4.0 - 1.5 * 0.02 * np.arange(120)
    for t in truth[:20]:
        m.step(depth=t, confidence=0.9, lidar=t, speed=1.5)
    for i, t in enumerate(truth[20:], 1):  # no LiDAR: a depth ramp inside d_kin's tolerance
        o = m.step(depth=t + 0.002 * i, confidence=0.9, speed=1.5)
        assert abs(o.d_kin - t) < 1e-6  # the branch stays where odometry puts the target


@pytest.mark.parametrize("confirmed", [False, True])
def test_a_lidar_track_no_depth_confirmed_is_one_witness_against_a_confident_depth(confirmed):
    """The depth blacked out at first sight: the LiDAR alone (perhaps the background behind
    the sign) carries the target. When the depth comes back 0.6 m nearer, an unconfirmed
    LiDAR (and the branch anchored on it alone) does not outvote it; a confirmed one does."""
    m = ODCA.load(prior=LastValuePrior())
    for i in range(20):
        m.step(depth=math.nan, confidence=0.0, lidar=2.6 - 0.02 * i, speed=1.0, lidar_confirmed=confirmed)
    out = m.step(depth=1.6, confidence=0.9, lidar=2.2, speed=1.0, lidar_confirmed=confirmed)
    if confirmed:
        assert out.source_name in ("lidar", "lidar+kinematics")
    else:
        assert out.source_name == "depth" and out.w == 0.0
        out = m.step(depth=1.58, confidence=0.9, lidar=math.nan, speed=1.0, lidar_confirmed=confirmed)
        assert out.source_name == "depth"  # the branch now rests on the depth, not on the LiDAR


def _size_std(d: np.ndarray) -> np.ndarray:
    return 0.04 * d  # about a size witness's at 10-20 px


def test_the_size_witness_carries_a_blackout_from_first_sight_with_no_lidar():
    """dropout_timed at a sign the scan plane misses: no depth and no LiDAR ever; the box's
    size anchors the branch, later sizes refine it, and the output follows the truth."""
    m = _stub()
    truth = 3.0 - 1.5 * 0.02 * np.arange(80)
    rng = np.random.default_rng(0)
    size = truth * (1 + rng.normal(0, 0.03, truth.size))
    out = [m.step(depth=np.nan, confidence=0.0, speed=1.5, size=s, size_std=e)
           for s, e in zip(size, _size_std(truth))]
    assert out[0].source_name == "size" and {o.source_name for o in out[1:]} == {"kinematics"}
    d_kin = np.array([o.d_kin for o in out])
    assert np.abs(d_kin - truth)[40:].max() < 0.1  # the fused sizes beat one size's 3 % (9 cm at 3 m)
    fused = np.array([o.d_fused for o in out])
    assert np.abs(fused - d_kin)[1:].max() <= m.config.gate.tau_m + 1e-9  # the head bends a repair by <= tau
    without = _stub()
    assert all(np.isnan(without.step(depth=np.nan, confidence=0.0, speed=1.5).d_fused) for _ in range(10))


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 5.0), st.floats(1.0, 2.0))
def test_a_frustum_spoof_pushing_farther_is_held_by_the_size_witness(rate, speed):
    """Depth and LiDAR pushed away together: the output never goes beyond the box's bound."""
    m = _stub()
    n, start = 150, 30
    truth = 6.5 - speed * 0.02 * np.arange(n)
    drift = rate * 0.02 * np.clip(np.arange(n) - start, 0, None)
    out = [m.step(depth=t + b, confidence=0.9, lidar=t + b, speed=speed, size=t, size_std=e)
           for t, b, e in zip(truth, drift, _size_std(truth))]
    fused = np.array([o.d_fused for o in out])
    tol = np.array([m.config.gate.size_tolerance(e) for e in _size_std(truth)])
    assert (fused - truth <= tol + m.config.gate.tau_m + 1e-9).all()  # the head bends a repair by <= tau
    assert all(o.w == 0.0 for o in out[:start])


def test_clean_depth_that_the_size_allows_passes_through_exactly():
    m = _stub()
    truth = 4.0 - 1.5 * 0.02 * np.arange(100)
    rng = np.random.default_rng(1)
    size = truth * (1 + rng.normal(0, 0.03, truth.size))
    out = [m.step(depth=t, confidence=0.9, lidar=t + 0.02, speed=1.5, size=s, size_std=e)
           for t, s, e in zip(truth, size, _size_std(truth))]
    assert [o.d_fused for o in out] == list(truth)


def test_batched_run_matches_step_exactly_with_a_size_witness():
    m = _stub()
    df = _series(90, 2)
    rng = np.random.default_rng(3)
    df["d_size"] = np.where(rng.random(len(df)) < 0.8, df["d_meas"].fillna(2.0) * rng.uniform(0.9, 1.2, len(df)),
                            np.nan)
    df["size_std"] = 0.05 * df["d_size"]
    batched = m.run(df)
    m.reset()
    rows = []
    for r in df.itertuples():
        if r.Index and r.slot != df["slot"].iloc[r.Index - 1]:
            m.reset()
        rows.append(vars(m.step(depth=r.d_meas, confidence=r.c_meas, lidar=r.lidar, speed=r.speed,
                                yaw_rate=r.yaw_rate, bearing=r.bearing, size=r.d_size, size_std=r.size_std)))
    pd.testing.assert_frame_equal(batched.reset_index(drop=True), pd.DataFrame(rows), check_exact=True)
    assert not batched.equals(m.run(df.drop(columns=["d_size", "size_std"])))  # the size witness took part


def test_a_depth_held_from_the_last_frame_is_as_old_as_its_frame_and_no_older():
    """The camera runs at 30 Hz, the loop at 50 Hz: a depth equal to the last step's is that
    frame's, and the drift check gives it the distance driven since. A depth frozen for longer
    than a frame period is not a held frame (a freeze attack gets nothing)."""
    from racf.odca.witnesses import Witnesses as _Witnesses

    w = _Witnesses(_stub().config)
    assert w.depth_age(1.50, -0.04, 0.02) == 0.0  # a fresh frame
    assert w.depth_age(1.50, -0.04, 0.02) == pytest.approx(0.04)  # held one step: 0.04 m driven since
    assert w.depth_age(1.50, -0.04, 0.02) == 0.0  # held past the 33 ms frame: a freeze, no allowance
    assert w.depth_age(1.46, -0.04, 0.02) == 0.0
    assert w.depth_age(float("nan"), -0.04, 0.02) == 0.0 and w.depth_age(float("nan"), -0.04, 0.02) == 0.0
