"""Falsification: searching each defence's worst case on the stop rule's STL robustness, and
keeping what the search finds as replayable cases (``racf falsify``, ``racf replay-case``)."""
