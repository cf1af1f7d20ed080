"""Sparse labelling gives OpenCV's full-frame components, to the bit (racf.controllers.components)."""

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers.components import sparse_components


@st.composite
def sparse_masks(draw):
    h, w = draw(st.integers(1, 60)), draw(st.integers(1, 80))
    mask = np.zeros((h, w), np.uint8)
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    for _ in range(draw(st.integers(0, 6))):  # blobs of random density, anywhere (edges included)
        y, x = rng.integers(0, h), rng.integers(0, w)
        bh, bw = rng.integers(1, 12), rng.integers(1, 12)
        patch = mask[y:y + bh, x:x + bw]
        patch[rng.random(patch.shape) < rng.uniform(0.2, 1.0)] = 255
    return mask


def _assert_same(mask):
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    n2, labels2, stats2, centroids2 = sparse_components(mask)
    assert n2 == n
    assert np.array_equal(labels2, labels)
    assert np.array_equal(stats2[1:], stats[1:])
    assert centroids2[1:].tobytes() == centroids[1:].tobytes()


@settings(max_examples=300, deadline=None)
@given(sparse_masks())
def test_every_component_is_the_full_calls(mask):
    _assert_same(mask)


def test_a_blob_starting_on_an_odd_row_right_of_one_on_the_row_below():
    # On the frame's block grid the right blob (row 11) is met first; a box cut at row 11 would
    # put both first pixels in one 2 x 2 block row and meet the left blob first.
    mask = np.zeros((40, 60), np.uint8)
    mask[11:20, 30:35] = 255  # first pixel on row 11 (odd), to the right
    mask[12:20, 5:9] = 255  # first pixel on row 12, to the left
    _assert_same(mask)


def test_an_empty_mask_has_only_the_background():
    n, labels, _, _ = sparse_components(np.zeros((24, 32), np.uint8))
    assert n == 1 and not labels.any()
