"""The car's build: the size witness measures what the car's detector outlines against the map."""

import pytest

from racf.controllers.detectors import make_detector
from racf.experiments.episode.stack import outlined_size_m
from racf.sim.world.stop_signs import SIGN_FACE_ACROSS_FLATS_M, SIGN_RED_FACE_ACROSS_FLATS_M


def test_each_detector_is_measured_against_the_part_of_the_sign_it_outlines():
    assert outlined_size_m(make_detector("classical")) == SIGN_RED_FACE_ACROSS_FLATS_M  # the red pixels
    assert outlined_size_m(make_detector("learned")) == SIGN_FACE_ACROSS_FLATS_M  # the whole face, as trained


def test_a_plug_in_detector_that_does_not_say_outlines_the_red_face_and_a_bad_outline_is_named():
    class Quiet:
        def detect(self, rgb):
            return None

    class Odd(Quiet):
        outline = "pole"

    assert outlined_size_m(Quiet()) == SIGN_RED_FACE_ACROSS_FLATS_M
    with pytest.raises(ValueError, match="outlines 'pole'; allowed: red_face, face"):
        outlined_size_m(Odd())
