"""What protected the car under the supervisor (the ``supervisor`` metric, scored where the spec runs
it): the steps the safe controller drove instead of the defence, the steps the stop rule fired, the
steps a broadcast or a defended distance was outvoted by the car's own witnesses, and the broadcast
messages the car heard. A served answer outvoted is the ``service`` metric's ``service_outvoted``."""

from __future__ import annotations

import numpy as np

from racf.experiments.metrics.base import Episode, Field, Metric

__all__ = ["SupervisorMeasures"]


def _steps(log, suffix: str) -> int:
    """Control steps on which any supervisor's column ending in ``suffix`` is true."""
    columns = [c for c in log.columns if c.startswith("sup_") and c.endswith(suffix)]
    if not columns:
        return 0
    control = log["control"].astype(bool).to_numpy()
    flags = np.zeros(len(log), bool)
    for column in columns:
        flags |= log[column].fillna(False).astype(bool).to_numpy()
    return int((flags & control).sum())


class SupervisorMeasures(Metric):
    """The supervisor's interventions, step by step."""

    name = "supervisor"
    meaning = "what the supervisor did: steps its safe controller drove, its stop rule fired, witnesses outvoted"
    order = 85
    fields = (
        Field("sup_safe_steps", 0, "steps", "steps a target was carried and the defence's distance not vouched: the "
                                            "safe controller's cap, or the defence's where lower, drove"),
        Field("sup_stop_steps", 0, "steps", "steps the stop rule told the car to stop (faster than the worst case "
                                            "allows, at any target)"),
        Field("sup_outvoted_steps", 0, "steps", "steps the car's own witnesses outvoted a distance: the lead's "
                                                "broadcast, or a defended or served distance farther than a vouched "
                                                "static target"),
        Field("sup_eased_steps", 0, "steps", "steps the defence's brake for what no LiDAR witness confirmed was eased "
                                             "off (never a hard brake)"),
        Field("bc_heard", 0, "", "broadcast messages the car accepted from the car ahead"),
    )

    def score(self, episode: Episode) -> dict:
        log = episode.log
        if not any(c.startswith("sup_") for c in log.columns):
            return {}
        heard = log["lead_bc_accepted"].to_numpy(float) if "lead_bc_accepted" in log else np.zeros(0)
        heard = heard[np.isfinite(heard)]
        return {"sup_safe_steps": _steps(log, "_safe"), "sup_stop_steps": _steps(log, "_stop"),
                "sup_outvoted_steps": _steps(log, "_outvoted"), "sup_eased_steps": _steps(log, "_eased"),
                "bc_heard": int(heard.max()) if heard.size else 0}
