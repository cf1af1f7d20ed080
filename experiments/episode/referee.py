"""The referee's side of an episode: everything the log knows that the car must not.

The referee reads everything (``info``, the env's unattacked readings, the car's outputs) and
feeds nothing back. Per step it runs:
- the reference braker that defines t*: the same braking controller fed d_true while the
  target is in view, on every step, without delay;
- the ``d_clean`` pass: the protocol's pseudo ground truth, the car's detector and depth
  pipeline on the env's own readings before any attack, and whether that detector finds the
  target there at all (``clean_detected``: a frame the detector misses clean is no attack's loss);
- the ground-truth log columns (pose, speed, distance to the line, d_true, visibility, what
  the car touched), then every column the world's managers declare, copied from ``info`` by name
  (the referee knows none of them).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from racf.controllers import BrakingConfig, Perception, StopSignBraker
from racf.experiments.car.software import CarCalibration, CarStep, sign_depth_at_line
from racf.sim.world.drives import RouteTarget

__all__ = ["Referee"]


class Referee:
    """Grades the car on the target the car is serving.

    Args:
        calibration: the car's build (where its line is, for the reference braker).
        braking: the braking controller's parameters (the reference uses the car's).
        dt: the env's step, s.
        attacked: whether an attack wrapper sits between the env and the car.
        clean_pass: under attack, run the ``d_clean`` pass (a diagnostic: without it the
            log's ``d_clean`` is NaN under attack and nothing else changes).
        world_columns: the columns the world's managers declare (``record.world_columns``), logged from ``info``.
    """

    def __init__(self, calibration: CarCalibration, braking: BrakingConfig, dt: float, attacked: bool,
                 clean_pass: bool = True, world_columns: tuple[str, ...] = ()) -> None:
        self.world_columns = world_columns
        self.calibration = calibration
        self.braking = braking
        self.dt = dt
        self.attacked = attacked
        self.clean_pass = clean_pass
        self._slot = -1
        self._ideal: StopSignBraker | None = None
        self._d_clean = math.nan
        self._clean_detected = False

    def _begin(self, target: RouteTarget) -> None:
        self._ideal = StopSignBraker(self.braking, sign_depth_at_line(self.calibration, target))

    def observe(self, env: gym.Env, obs: dict, info: dict, car: CarStep, target: RouteTarget,
                perception: Perception) -> dict:
        """The referee's columns for one step, after the car has decided.

        ``perception`` is the car's pipeline for the target: the clean pass uses its detector
        and depth estimator (both stateless) and, where the attack left the image alone,
        the detection it just made.
        """
        if car.slot != self._slot:
            self._slot = car.slot
            self._begin(target)
        if car.control and car.frame_new:  # d_clean is of the frame, like the car's d_meas
            self._d_clean, self._clean_detected = self._clean_pass(env, obs, car, perception, info)
        # Where no target stands in the world (the map's sign was removed; a phantom may look like one),
        # there is nothing to brake for.
        stands = bool(info["target_stands"])
        in_view = bool(info["sign_in_view"]) and stands
        ideal = self._ideal.step(in_view, float(info["d_true"]) if in_view else math.nan, float(info["speed"]), self.dt)
        x, y, yaw = (float(v) for v in info["pose"])
        return {
            "d_true": info["d_true"], "d_clean": self._d_clean, "clean_detected": self._clean_detected and in_view,
            "sign_in_view": in_view, "sign_stands": stands,
            "ideal_brake": ideal.brake, "x": x, "y": y, "yaw": yaw, "speed": info["speed"],
            "dist_to_stop_line": info["dist_to_stop_line"], "lateral_error": info["lateral_error"],
            "attack_active": bool(info.get("attack_active", False)), "attack": "+".join(info.get("attack", ())),
            "collision_with": info.get("collision_with") or "",
            "radio_sent": int(info.get("radio_sent", 0)), "radio_delivered": int(info.get("radio_delivered", 0)),
            "radio_injected": int(info.get("radio_injected", 0)), "radio_genuine_slots": _genuine_slots(env, obs),
            **{name: info[name] for name in self.world_columns},
        }

    def _clean_pass(self, env: gym.Env, obs: dict, car: CarStep, perception: Perception, info: dict
                    ) -> tuple[float, bool]:
        """``d_clean`` (NaN under attack without the clean pass) and whether the car's detector finds the
        target on the unattacked frame (run under attack whatever ``clean_pass`` says: ``lost_frames``
        counts only the frames it finds)."""
        if not self.attacked:
            return car.sample.d_meas, _on_target(perception.last_raw_detection, info)
        clean = env.unwrapped.sensor_observation()
        unchanged = np.array_equal(clean["rgb"], obs["rgb"])
        detection = perception.last_raw_detection if unchanged else perception.detector.detect(clean["rgb"])
        distance = perception.depth.estimate(clean["depth"][..., 0], detection)[0] if self.clean_pass else math.nan
        return distance, _on_target(detection, info)


def _on_target(detection, info: dict) -> bool:
    """Whether a detection's box holds some of the target's pixels (the referee's mask), so that a red
    car or a picture found instead of the sign is no detection of it."""
    if detection is None:
        return False
    mask = info.get("sign_mask")
    if mask is None:
        return True
    x0, y0, x1, y1 = detection.box
    return bool(np.asarray(mask)[y0:y1, x0:x1].any())


def _genuine_slots(env: gym.Env, obs: dict) -> int:
    """Which of the car's ``radio`` slots this step hold a message the world's radio delivered this step
    (a bit mask; the others are an attacker's: forged, replayed, held back)."""
    from racf.sim.radio.channel import slots_holding

    radio = getattr(env.unwrapped, "radio", None)
    if radio is None or "radio" not in obs:
        return 0
    return slots_holding(obs["radio"], radio.delivered_now)
