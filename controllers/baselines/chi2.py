"""A windowed chi-square detector (the residual test of the stealthy-attack literature): the
sum of the depth's squared normalised innovations over the last ``window`` steps, tested
against the chi-square quantile at ``false_alarm`` for that many degrees of freedom.

innovation z = (depth - witness) / sqrt(depth_std^2 / confidence + witness_std^2); the
statistic's ratio to its threshold is the ``score`` (> 1: ``flag``). While flagged, the
defence drives on the witness; with no witness it has no distance (NaN), not a guess.
"""

from __future__ import annotations

from collections import deque

from racf.controllers.baselines.witness import Witness, valid

__all__ = ["Chi2Detector"]


class Chi2Detector:
    """Windowed chi-square test on the depth's innovation; the witness replaces a flagged depth.

    Args:
        window: steps in the test's window.
        false_alarm: the test's false-alarm probability on Gaussian innovations.
        depth_std_m: depth noise at full confidence, m.
        lidar_std_m, drift_per_m, max_carry_s: the witness's (:class:`Witness`).
    """

    name = "chi2"
    n_parameters = 0  # hand-set noise models and a textbook threshold: nothing trained

    def __init__(self, window: int = 10, false_alarm: float = 0.01, depth_std_m: float = 0.03,
                 lidar_std_m: float = 0.03, drift_per_m: float = 0.02, max_carry_s: float = 1.5) -> None:
        from scipy.stats import chi2

        if not (isinstance(window, int) and window >= 1 and 0 < false_alarm < 1 and depth_std_m > 0):
            raise ValueError(f"need an int window >= 1, 0 < false_alarm < 1, depth_std_m > 0; got {window!r}, "
                             f"{false_alarm!r}, {depth_std_m!r}")
        self.window, self.depth_std_m = window, float(depth_std_m)
        self._threshold = [float(chi2.ppf(1.0 - false_alarm, k)) for k in range(window + 1)]
        self.witness = Witness(lidar_std_m, drift_per_m, max_carry_s)
        self.reset()

    def reset(self) -> None:
        self.witness.reset()
        self._z2: deque[float] = deque(maxlen=self.window)
        self.score, self.flagged, self._stepped = 0.0, False, False

    def _score(self, z2: deque) -> float:
        return sum(z2) / self._threshold[len(z2)] if z2 else 0.0

    def estimate(self, sample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self._stepped = True
        depth, lidar = sample.d_meas, sample.lidar_m
        reference, ref_std = self.witness.predict(lidar, speed_mps, dt)
        if valid(depth) and valid(reference):
            self._z2.append(self.witness.innovation(depth, sample.c_meas, self.depth_std_m, reference, ref_std) ** 2)
        self.score = self._score(self._z2)
        self.flagged = self.score > 1.0
        return self.witness.step_output(depth, reference, self.flagged, lidar, speed_mps, dt)

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.flagged), "score": self.score} if self._stepped else {}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        reference, ref_std = self.witness.next_reference(speed_mps, dt, lidar_shift)
        if not (valid(depth) and valid(reference)):
            return True
        z2 = deque(self._z2, maxlen=self.window)
        z2.append(self.witness.innovation(depth, 1.0, self.depth_std_m, reference, ref_std) ** 2)
        return self._score(z2) <= 1.0
