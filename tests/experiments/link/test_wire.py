"""The wire form of a perception sample: what the car sends a defence service comes back whole."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.controllers import PerceptionSample
from racf.controllers.detector import Detection
from racf.controllers.existence import NO_WITNESSES
from racf.experiments.link.wire import decode_sample, encode_sample, pack, unpack

finite_or_nan = st.one_of(st.floats(-50, 50), st.just(math.nan))


@given(st.booleans(), st.booleans(), finite_or_nan, st.floats(0, 1), finite_or_nan, finite_or_nan,
       st.integers(1, 30), st.integers(1, 30), st.integers(0, 2**32 - 1))
def test_a_sample_survives_the_wire(detected, witnessed, d, c, lidar, bearing, h, w, seed):
    mask = np.random.default_rng(seed).random((h, w)) < 0.3
    detection = Detection(mask, (0, 1, w, h), 0.8, int(mask.sum()), (w / 2, h / 2)) if detected else None
    sample = PerceptionSample(detection, d, c, lidar, bearing, lidar_confirmed=False, d_size=d, size_std=0.1,
                              witnesses=NO_WITNESSES if witnessed else None)
    back = decode_sample(unpack(pack(encode_sample(sample))))
    for name in ("d_meas", "c_meas", "lidar_m", "bearing_rad", "d_size", "size_std", "lidar_confirmed"):
        a, b = getattr(sample, name), getattr(back, name)
        assert a == b or (math.isnan(a) and math.isnan(b)), name
    assert (back.detection is None) == (detection is None)
    if detection is not None:
        assert np.array_equal(back.detection.mask, mask) and back.detection.box == detection.box
        assert back.detection.centroid == detection.centroid and back.detection.area_px == detection.area_px
    if witnessed:
        assert back.witnesses.source == NO_WITNESSES.source and back.witnesses.seen == NO_WITNESSES.seen
        assert math.isnan(back.witnesses.depth_m)
    else:
        assert back.witnesses is None


def test_unpack_refuses_a_message_over_the_limit_itself():
    """Not only ZeroMQ's MAXMSGSIZE: a message read by any other path is measured too."""
    import pytest

    from racf.experiments.link.wire import MAX_MESSAGE_BYTES, WireError

    with pytest.raises(WireError, match=f"message of {MAX_MESSAGE_BYTES + 1} bytes"):
        unpack(pack({"op": "x"}) + b"\0" * (MAX_MESSAGE_BYTES + 1 - len(pack({"op": "x"}))))
    assert unpack(pack({"op": "x"})) == {"op": "x"}


def test_a_mask_whose_bits_do_not_fill_its_shape_is_refused():
    import pytest

    from racf.experiments.link.wire import WireError

    sample = encode_sample(PerceptionSample(Detection(np.ones((4, 8), bool), (0, 0, 8, 4), 0.9, 32, (4.0, 2.0)),
                                            1.0, 0.9, 1.0, 0.0))
    assert decode_sample(unpack(pack(sample))).detection.area_px == 32
    for bad in (np.zeros(3, np.uint8), np.zeros(4, np.int32), [0, 0, 0, 0]):
        sample["detection"]["mask"] = bad
        with pytest.raises(WireError, match="the mask's bits do not fill its shape 4x8"):
            decode_sample(unpack(pack(sample)))


def test_a_msgpack_extension_that_carries_bytes_is_never_read():
    """(An empty one reads as an ExtType, which no field's check takes for a value.)"""
    import msgpack
    import pytest

    from racf.experiments.link.wire import WireError

    for ext in (msgpack.ExtType(1, b"x"), msgpack.ExtType(5, b"\0" * 8)):
        with pytest.raises(WireError, match="not a msgpack message"):
            unpack(msgpack.packb({"op": "ping", "id": 1, "x": ext}))


def test_a_mask_is_1_to_4096_pixels_a_side():
    import pytest

    from racf.experiments.link.wire import WireError

    def sample(h, w):
        mask = np.ones((h, w), bool)
        return encode_sample(PerceptionSample(Detection(mask, (0, 0, w, h), 0.9, h * w, (w / 2, h / 2)),
                                              1.0, 0.9, 1.0, 0.0))

    for h, w in ((1, 1), (4096, 1), (1, 4096)):
        assert decode_sample(unpack(pack(sample(h, w)))).detection.mask.shape == (h, w)
    for h, w in ((4097, 1), (1, 4097)):
        with pytest.raises(WireError, match="outside 1..4096 a side"):
            decode_sample(unpack(pack(sample(h, w))))


def test_a_message_of_exactly_the_limit_is_read_and_an_array_has_at_most_4_axes():
    import pytest

    from racf.experiments.link.wire import MAX_MESSAGE_BYTES, WireError

    head = len(pack({"op": "x", "d": b""}))
    for n in range(MAX_MESSAGE_BYTES - head - 8, MAX_MESSAGE_BYTES - head + 1):  # msgpack's size header grows
        raw = pack({"op": "x", "d": b"\0" * n})
        if len(raw) == MAX_MESSAGE_BYTES:
            break
    assert len(raw) == MAX_MESSAGE_BYTES and unpack(raw)["op"] == "x"
    assert unpack(pack({"a": np.zeros((1, 1, 1, 2))}))["a"].shape == (1, 1, 1, 2)
    with pytest.raises(WireError, match="not a list of at most 4 sizes"):
        unpack(pack({"a": np.zeros((1, 1, 1, 1, 2))}))


def test_the_protocols_distance_is_0_to_50_m_and_a_message_at_most_1_mib():
    import pytest

    from racf.experiments.link.wire import InvalidAnswer, WireError, check_distance

    for d in (0.0, 1.25, 50.0):
        assert check_distance(d) == d
    assert check_distance(None) is None
    for d in (-1e-9, 50.000001, math.nan, math.inf):
        with pytest.raises(InvalidAnswer):
            check_distance(d)
    with pytest.raises(WireError, match="at most 1048576"):
        unpack(b"\0" * (2 ** 20 + 1))
    assert unpack(pack({"a": np.zeros(0)}))["a"].shape == (0,)  # an empty array is an array


def test_a_mask_with_no_rows_is_refused():
    import pytest

    from racf.experiments.link.wire import WireError

    sample = encode_sample(PerceptionSample(Detection(np.ones((1, 5), bool), (0, 0, 5, 1), 0.9, 5, (2.5, 0.5)),
                                            1.0, 0.9, 1.0, 0.0))
    sample["detection"]["shape"] = [0, 5]
    sample["detection"]["mask"] = np.zeros(0, np.uint8)
    with pytest.raises(WireError, match="outside 1..4096 a side"):
        decode_sample(unpack(pack(sample)))


def test_an_answer_s_id_must_be_the_request_s_int_never_a_bool():
    from racf.experiments.link.wire import InvalidAnswer, check_answer

    answer = {"distance": 1.0, "diagnostics": {}, "stands": None}
    assert check_answer("estimate", {**answer, "id": 1}, 1)["distance"] == 1.0
    for wrong in (True, 2, "1", None):  # True == 1 in Python: a bool is no request's id
        with pytest.raises(InvalidAnswer, match="not to request 1"):
            check_answer("estimate", {**answer, "id": wrong}, 1)


def test_a_refused_or_failed_hello_is_told_as_it_is_not_as_another_protocol():
    from racf.experiments.link.wire import InvalidAnswer, check_answer

    refused = {"refused": "this service serves raw, not 'odca'", "id": 1}
    assert check_answer("hello", refused, 1) == refused  # a refusal names no protocol: the car hears its words
    with pytest.raises(InvalidAnswer) as err:
        check_answer("hello", {"error": "bad request: hello needs estimator", "id": 1}, 1)
    assert err.value.kind == "error" and "speaks protocol" not in str(err.value)
