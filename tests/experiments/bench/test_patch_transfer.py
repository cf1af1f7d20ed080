"""The sticker-transfer bench: seeded views around the sign or on the car's approaches."""

import pytest

from racf.experiments.bench.patch_transfer import bench_patch


def test_approach_views_with_a_named_place_score_every_rendering_and_are_seeded():
    a, _ = bench_patch(4, "learned-approach", 0.4, "top", detectors=("classical",), progress=False, views="approach")
    b, _ = bench_patch(4, "learned-approach", 0.4, "top", detectors=("classical",), progress=False, views="approach")
    assert a.to_dict() == b.to_dict()
    assert a.position[0] == 0.0 and a.position[1] > 0.1  # pushed up as far as it stays on the plate
    assert set(a.counts["classical"]) == {"clean", "physical_patch", "patch_occlusion"}
    assert a.counts["classical"]["clean"].n_frames == 4


def test_an_unknown_kind_of_view_is_refused_before_any_work():
    with pytest.raises(ValueError, match="views must be one of"):
        bench_patch(1, views="random", progress=False)
