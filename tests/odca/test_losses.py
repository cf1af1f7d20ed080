"""The four training losses: each measures what it claims."""

import torch

from racf.odca.losses import LossWeights, odca_losses


def _batch(delta, d, l_al, v=None, clean=None):
    n = len(d)
    t = lambda x: torch.tensor(x, dtype=torch.float32)  # noqa: E731
    return dict(delta=t(delta), base=t(d), d=t(d), c=t([0.9] * n), l_al=t(l_al), v=t(v or [0.0] * n),
                clean=torch.tensor(clean if clean is not None else [True] * n), valid_pair=torch.tensor([False] + [True] * (n - 1)))


def test_zero_correction_on_agreeing_clean_steps_costs_nothing_but_kinematics():
    b = _batch([0.0] * 4, [2.0, 1.98, 1.96, 1.94], [2.0, 1.98, 1.96, 1.94], v=[1.0] * 4)
    total, parts = odca_losses(**b, dt=0.02, tau_low=0.1, weights=LossWeights())
    assert parts["identity"] == 0 and parts["minimal_change"] == 0 and parts["consistency"] == 0
    assert float(parts["kinematics"]) < 1e-10  # Delta d = -v dt exactly
    assert float(total) < 1e-10


def test_consistency_pulls_towards_the_lidar_only_where_sensors_disagree():
    b = _batch([0.0, 0.0], [2.0, 3.0], [2.0, 2.0], clean=[True, False])
    _, parts = odca_losses(**b, dt=0.02, tau_low=0.1, weights=LossWeights())
    assert float(parts["consistency"]) > 0.9  # the biased step, 1 m off
    b["delta"] = torch.tensor([0.0, -1.0])
    _, fixed = odca_losses(**b, dt=0.02, tau_low=0.1, weights=LossWeights())
    assert float(fixed["consistency"]) == 0.0 and float(fixed["identity"]) == 0.0
    assert float(fixed["minimal_change"]) > 0  # any correction costs a little


def test_identity_applies_on_clean_steps_and_low_confidence_weighs_more():
    b = _batch([0.1, 0.1], [2.0, 2.0], [2.0, 2.0])
    _, hi = odca_losses(**b, dt=0.02, tau_low=0.5, weights=LossWeights())
    b["c"] = torch.tensor([0.1, 0.1])
    _, lo = odca_losses(**b, dt=0.02, tau_low=0.5, weights=LossWeights())
    assert float(hi["identity"]) > 0 and float(lo["identity"]) > float(hi["identity"])
