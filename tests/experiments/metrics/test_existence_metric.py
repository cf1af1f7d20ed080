"""Needless stops (racf.experiments.metrics.existence): scored only where no sign stands."""

import pandas as pd

from racf.experiments.metrics.existence import Existence


class _Episode:
    def __init__(self, log):
        self.log = log


def _log(stands: bool, stops: bool) -> pd.DataFrame:
    t = [i * 0.02 for i in range(100)]
    speed = [max(0.0, 1.0 - i * 0.02) if stops else 1.0 for i in range(100)]
    brake = [stops and i > 10 for i in range(100)]
    dist = [2.0 - sum(speed[:i]) * 0.02 for i in range(100)]
    return pd.DataFrame({"t": t, "slot": 0, "speed": speed, "brake": brake, "sign_stands": stands,
                         "dist_to_stop_line": dist, "ideal_brake": brake, "confirmed": brake})


def test_a_stop_where_no_sign_stands_is_needless():
    scored = Existence().score(_Episode(_log(stands=False, stops=True)))
    assert scored == {"sign_stands": False, "needless_stop": True}
    assert Existence().score(_Episode(_log(stands=False, stops=False)))["needless_stop"] is False


def test_where_a_sign_stands_there_is_no_needless_stop_to_score():
    scored = Existence().score(_Episode(_log(stands=True, stops=False)))
    assert scored == {"sign_stands": True}


def test_the_rate_counts_only_episodes_without_a_sign():
    rows = pd.DataFrame({"needless_stop": [True, False, None, None], "sign_stands": [False, False, True, True]})
    summary = Existence().summarize(rows, attacked=False)
    assert summary["n_needless_stop"] == 2 and summary["needless_stop_rate"] == 0.5
