"""The detectors' recall over posed signs: the referee's mask follows the turned and leaned body, the
grid is the same on every run, and a detector that sees nothing has recall 0 where one that sees
the truth has 1."""

import numpy as np

from racf.experiments.detector.pose_grid import pose_recall, pose_views


class _Truth:
    """Detects exactly the target's pixels of the view it was last shown."""

    def __init__(self):
        self.mask = None

    def detect(self, rgb):
        return None if not self.mask.any() else type("D", (), {"mask": self.mask})()


def test_the_mask_follows_the_turned_sign_and_recall_counts_resolvable_views():
    views = list(pose_views(turns=(0.0, 60.0), leans=(0.0, 30.0), distances=(1.0,), signs=(2,)))
    by_pose = {(v.turn_deg, v.lean_deg): v for v in views}
    assert len(views) == 4
    upright, turned = by_pose[(0.0, 0.0)].target.sum(), by_pose[(60.0, 0.0)].target.sum()
    assert upright > 0 and 0 < turned < 0.8 * upright  # a sign turned 60 degrees shows about half its face
    assert not np.array_equal(by_pose[(0.0, 30.0)].target, by_pose[(0.0, 0.0)].target)
    truth = _Truth()

    def shown():
        for view in views:
            truth.mask = view.target
            yield view
    blind = type("Blind", (), {"detect": lambda self, rgb: None})()
    result = pose_recall({"truth": truth, "blind": blind}, shown())
    assert result["n_views"] == 4 and result["truth"]["overall"]["recall"] == 1.0
    assert result["blind"]["overall"]["recall"] == 0.0 and result["blind"]["overall"]["n"] >= 2
    assert set(result["truth"]["by_pose"]) <= {"0,0", "0,30", "60,0", "60,30"} and "grid" in result
