"""Offline corruption presets: shares, segment kinds, labels and seeding."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.experiments.data.corruption import PRESETS, SEGMENT_KINDS, CorruptionPreset, corrupt_series, draw_seed

DT = 0.02


def _clean(n=3000):
    t = np.arange(n) * DT
    return 3.0 - 0.5 * t % 3.0 + 0.2, np.full(n, 0.9)


def _segments(kind):
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (kind > 0).astype(int), [0]])))
    return list(zip(edges[::2], edges[1::2]))


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_preset_share_lengths_kinds_and_effects(name):
    p = PRESETS[name]
    d, c = _clean()
    out = corrupt_series(d, c, name, seed=draw_seed(0, name))
    share = out.label.mean()
    assert abs(share - p.share) <= p.segment_s[0] / DT / len(d) + 1e-9
    np.testing.assert_array_equal(out.label, (out.kind > 0).astype(np.int8))
    segs = _segments(out.kind)
    for start, end in segs:
        kinds = set(out.kind[start:end])
        assert len(kinds) == 1, "a segment mixes kinds"
        length_s = (end - start) * DT
        assert length_s <= p.segment_s[1] + 1e-9
        k = SEGMENT_KINDS[kinds.pop()]
        seg_d, seg_c = out.depth[start:end], out.confidence[start:end]
        if k == "blackout":
            assert np.isnan(seg_d).all() and (seg_c == 0).all()
        elif k == "bias":
            offset = seg_d - d[start:end]
            assert np.allclose(offset, offset[0]) and p.bias_m[0] <= abs(offset[0]) <= p.bias_m[1]
            np.testing.assert_array_equal(seg_c, c[start:end])
        else:
            np.testing.assert_allclose(seg_c, c[start:end] * p.confidence_multiplier)
            assert np.std(seg_d - d[start:end]) < 3 * p.noise_std_m + 1e-9
    # Outside the segments nothing changes.
    clean = out.label == 0
    np.testing.assert_array_equal(out.depth[clean], d[clean])
    np.testing.assert_array_equal(out.confidence[clean], c[clean])


def test_strong_has_blackouts_bias_and_degradation_in_about_the_preset_mix():
    counts = {k: 0 for k in ("bias", "blackout", "degradation")}
    d, c = _clean(20000)
    for i in range(10):
        out = corrupt_series(d, c, "strong", seed=draw_seed(i, "strong"))
        for start, _ in _segments(out.kind):
            counts[SEGMENT_KINDS[out.kind[start]]] += 1
    total = sum(counts.values())
    assert abs(counts["blackout"] / total - 0.5) < 0.12
    assert counts["bias"] > 0.1 * total and counts["degradation"] > 0.1 * total


def test_same_seed_same_bytes_and_seeds_differ_per_series_and_preset():
    d, c = _clean()
    a = corrupt_series(d, c, "mid", seed=draw_seed(3, "mid"))
    b = corrupt_series(d, c, "mid", seed=draw_seed(3, "mid"))
    assert a.depth.tobytes() == b.depth.tobytes() and a.kind.tobytes() == b.kind.tobytes()
    assert len({draw_seed(3, "mid"), draw_seed(4, "mid"), draw_seed(3, "weak"), draw_seed(3, "mid", 1)}) == 4
    assert isinstance(draw_seed(3, "mid"), int)


@settings(max_examples=40, deadline=None)
@given(st.integers(10, 2000), st.sampled_from(sorted(PRESETS)), st.integers(0, 2**31))
def test_any_length_gives_labels_that_match_the_changes(n, name, seed):
    d, c = np.linspace(3, 0.3, n), np.linspace(1, 0.5, n)
    out = corrupt_series(d, c, name, seed=seed)
    assert out.depth.shape == out.confidence.shape == out.label.shape == (n,)
    changed = ~np.isclose(out.depth, d, equal_nan=False) | (out.confidence != c)
    assert not (changed & (out.label == 0)).any()
    assert ((out.confidence >= 0) & (out.confidence <= 1)).all()


def test_bad_inputs_are_clear_errors():
    d, c = _clean(100)
    with pytest.raises(ValueError, match="preset must be one of"):
        corrupt_series(d, c, "extreme", seed=0)
    with pytest.raises(ValueError, match="same length"):
        corrupt_series(d, c[:50], "weak", seed=0)
    with pytest.raises(ValueError, match="share"):
        CorruptionPreset("x", 1.5, (0.2, 1.0), (0.1, 0.2), 0.2, 0.7, 0.03)
