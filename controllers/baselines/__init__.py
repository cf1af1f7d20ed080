"""Classical residual detectors, the scorecard's detection baselines, written as plug-ins:
they use nothing of racf but the ``DistanceEstimator`` contract and are registered through the
same entry points a user's package would use (``racf.estimators`` in pyproject.toml).

- ``chi2``: a windowed chi-square test on the depth's normalised innovation;
- ``cusum``: a two-sided CUSUM on the same innovation.

Both test the depth against one witness (:class:`Witness`): the LiDAR when it reports, else the
last distance moved on by odometry. On an alarm they drive on that witness instead of the depth.
"""

from racf.controllers.baselines.chi2 import Chi2Detector
from racf.controllers.baselines.cusum import CusumDetector
from racf.controllers.baselines.witness import Witness

__all__ = ["Chi2Detector", "CusumDetector", "Witness"]
