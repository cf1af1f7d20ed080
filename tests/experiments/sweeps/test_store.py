"""The store of finished episodes: rows back in the order asked."""

import pytest

from racf.experiments.sweeps.store import ResultStore


def test_rows_come_back_in_the_order_asked_and_a_missing_one_is_named(tmp_path):
    store = ResultStore(tmp_path)
    for i in ("b", "a"):
        store.write(i, {"trial_id": i, "success": True})
    assert store.rows()["trial_id"].tolist() == ["a", "b"]
    assert store.rows(["b", "a"])["trial_id"].tolist() == ["b", "a"]
    with pytest.raises(KeyError, match="'c'"):
        store.rows(["a", "c"])
