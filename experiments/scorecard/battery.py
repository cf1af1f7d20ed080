"""The scorecard's battery: a named, versioned list of the episodes and measurements every
defence is rated on. A battery never changes once released: a change is a new name
(``racf-2``), so two cards of one battery always rate the same thing.

``racf-6`` rates following a car ahead (issue 59): the ``lead_vehicle`` scenario in its four
profiles, clean and under each attack on the car ahead, by the collision-free rate and needless
hard brakes.

``racf-link-2`` is ``racf-link`` with the car's onboard fallback (issue 70): its own ODCA, not raw
depth, where the service gives no answer.

``racf-link`` rates a defence served offboard, as the paper ran it, with its link attacked: delayed,
lost, spoofed, on a plain and on a CurveZMQ link (issue 58).

``racf-4`` is ``racf-3`` and one row with cross-traffic (issue 37): random strong patch draws
over the four signs, each with another car timed to reach the sign's conflict point when the
ego car would (``racf.sim.world.traffic``). The row reports its collision rate, and a driving
score with CARLA's vehicle-collision penalty (x 0.60) beside the stop-sign run's (x 0.80).

``racf-3`` is ``racf-2`` and one row: a smaller sticker placed where it breaks the sign's outline
(0.4 of the plate at its top edge, the place chosen on rendered approach views with
``racf bench patch --views approach``), against the default detector.

``racf-2`` is ``racf-1`` and two rows for the size witness (issue 35): the frustum spoof that
also scales the sign's image, and the printed sticker up from the start against the default
detector (then the classical one).

``racf-1`` (N per defence; ``--quick`` keeps every row at a small N, and says so):

- **closed loop**, each row a batch of ordinary episodes with ids, on the ``qcar2`` sensors:
  the paper's table (clean and the strong patch, ``racf trials --table``'s episodes); random
  strong patch draws; the same with the LiDAR spoofed too; each adaptive attack at its
  strongest; the printed sticker against the learned detector;
- **drives**: seeded drives past several targets, clean and with the patch;
- **offline**: the repair benchmark's presets on the dataset's by-series test drives;
- **detection** and **cost**, from the closed-loop rows' step logs and the offline run.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

from racf.experiments.episode import TrialSpec
from racf.experiments.episode.spec import setting_name
from racf.experiments.scorecard.battery_types import (CAR_DETECTOR, PENALTIES, Battery, LoopRow, drives_row,
                                                     paper_row, sweep_row)
from racf.experiments.sweeps.batches import batch_specs
from racf.experiments.sweeps.spec import SweepSpec

__all__ = ["LoopRow", "Battery", "BATTERIES", "DEFAULT_BATTERY", "PENALTIES", "OFFBOARD", "PAPER_LOOP_HZ"]

_RACF_1 = Battery(
    name="racf-1",
    loop=(
        LoopRow("paper_clean", "the paper's table: clean", 30, 4, paper_row("clean"), attacked=False),
        LoopRow("paper_attack", "the paper's table: the strong patch", 30, 4, paper_row("attack")),
        LoopRow("strong_random", "random strong patch draws", 60, 4, sweep_row("strong", "patch_occlusion")),
        LoopRow("patch_spoof", "random strong patch + LiDAR spoof", 60, 4,
                sweep_row("spoof", "patch_occlusion+lidar_spoof")),
        LoopRow("stealth_ramp", "stealth_ramp, r 3 m/s over 3 s (white box)", 24, 4,
                sweep_row("adaptive", "stealth_ramp", mode="grid", params={"stealth_ramp": {"rate_mps": [3.0]}})),
        LoopRow("ramp_rates", "stealth_ramp at r 0.1, 0.3 and 1 m/s over 3 s (for the undetected error against r)",
                8, 4, sweep_row("adaptive", "stealth_ramp", mode="grid",
                             params={"stealth_ramp": {"rate_mps": [0.1, 0.3, 1.0]}})),
        LoopRow("frustum_spoof", "frustum_spoof, r 3 m/s over 3 s (white box)", 24, 4,
                sweep_row("adaptive", "frustum_spoof", mode="grid", params={"frustum_spoof": {"rate_mps": [3.0]}})),
        LoopRow("dropout_timed", "dropout_timed, blackout after 1 empty scan (black box)", 24, 4,
                sweep_row("adaptive", "dropout_timed", mode="grid",
                       params={"dropout_timed": {"scans": [1], "effect": ["blackout"]}})),
        LoopRow("delay", "delay, the depth frozen for 3 s (black box)", 24, 4,
                sweep_row("adaptive", "delay", mode="grid", params={"delay": {"sensor": ["depth"], "frames": [50]}})),
        LoopRow("sticker", "the printed sticker against the learned detector", 30, 4,
                sweep_row("sticker", "physical_patch", detector="learned")),
    ),
    drives=(
        LoopRow("drives_clean", "seeded drives, clean", 6, 1, drives_row(False), attacked=False),
        LoopRow("drives_attack", "seeded drives, the strong patch at the first target", 6, 1, drives_row(True)),
    ),
)

_RACF_2 = replace(
    _RACF_1,
    name="racf-2",
    loop=_RACF_1.loop + (
        LoopRow("frustum_scaled", "frustum_spoof that also draws the sign smaller, r 3 m/s over 3 s (white box: "
                                  "every witness moved)", 24, 4,
                sweep_row("adaptive", "frustum_spoof", mode="grid",
                       params={"frustum_spoof": {"rate_mps": [3.0], "scale_box": [True]}})),
        LoopRow("sticker_default", "the sticker optimised over the approaches (0.6 of the plate), up from the "
                                   "start, against the default detector", 30, 4,
                sweep_row("sticker", "physical_patch", params={"physical_patch": {
                    "texture": ["learned-approach"], "size": [0.6], "from_start": [True]}})),
    ),
)

_RACF_3 = replace(_RACF_2, name="racf-3", loop=_RACF_2.loop + (
    LoopRow("sticker_placed", "a smaller sticker placed where it breaks the sign's outline (0.4 of the plate, at its "
                              "top edge), up from the start, against the default detector", 30, 4,
            sweep_row("sticker", "physical_patch", params={"physical_patch": {
                "texture": ["learned-approach"], "size": [0.4], "position": ["top"], "from_start": [True]}})),))

_RACF_4 = replace(_RACF_3, name="racf-4", loop=_RACF_3.loop + (
    LoopRow("traffic_strong", "random strong patch draws with cross-traffic timed to the conflict point", 60, 4,
            sweep_row("strong", "patch_occlusion", tables={"traffic": {"cars": [1], "gap_s": 0.0, "speed": 1.0}}), driving=True),))

_STICKER_06 = {"texture": "learned-approach", "size": 0.6, "from_start": True}
_STICKER_04_TOP = {"texture": "learned-approach", "size": 0.4, "position": "top", "from_start": True}
#: The strong patch from the second step the sign is in view (0.04 s), before any track is confirmed
#: (three frames, 0.1 s), and on until the car has stopped or passed: the braking window opened wide.
_EARLY_PATCH = {"patch_occlusion": {"window_s": 60.0}}


def _stale(case: str, attack: str = "clean", params: dict | None = None, *, stable_steps: int | None = None,
           t_atk: tuple[float, float] | None = None) -> Callable[[str, int], list[TrialSpec]]:
    """Stale-map approaches (``racf.experiments.scenarios.stale_map``), paired over defences: episode
    ``i`` approaches sign ``i % 4`` at a speed drawn in [1, 2] m/s (and, moved, a shift of 0.5-1.5 m
    either way) from its index alone."""
    import numpy as np

    def make(defence: str, n: int) -> list[TrialSpec]:
        specs = []
        for i in range(n):
            draw = np.random.default_rng([5, i])  # battery 5, episode i: the same draw for every defence
            speed, shift = round(float(draw.uniform(1.0, 2.0)), 2), round(float(draw.uniform(0.5, 1.5)), 2)
            values = {"case": case} | ({"shift_m": shift if i % 2 else -shift} if case == "moved" else {})
            setting = setting_name(() if attack == "clean" else tuple(attack.split("+")), defence)
            extra = {"t_atk": t_atk} if t_atk is not None else {}
            specs.append(TrialSpec(setting, i % 4, speed, i, target="stale_map", scenario_params=values,
                                   detector=CAR_DETECTOR, attack_params=params or {}, stable_steps=stable_steps, **extra))
        return specs
    return make


#: ``racf-5``: whether the car stops where a sign stands, and only there (issue 48). Stop-sign
#: approaches against a map that may be stale (``stale_map``): the stickers up from the start on
#: mapped signs, the strong patch before the track is confirmed, removed signs and phantoms
#: (needless stops), temporary signs the map does not list, clean and with the stickers, moved
#: signs, and the white-box attack on the vote (the sticker with the depth and the LiDAR blinded
#: at the sign). Closed-loop rows only: no drives, no offline rows (``racf-4`` rates the distance).
_RACF_5 = Battery(
    name="racf-5",
    loop=(
        LoopRow("mapped_clean", "mapped signs, clean", 60, 4, _stale("mapped"), attacked=False),
        LoopRow("mapped_sticker", "mapped signs, the 0.6 sticker up from the start", 60, 4,
                _stale("mapped", "physical_patch", {"physical_patch": _STICKER_06})),
        LoopRow("mapped_sticker_top", "mapped signs, the 0.4 top-edge sticker up from the start", 60, 4,
                _stale("mapped", "physical_patch", {"physical_patch": _STICKER_04_TOP})),
        LoopRow("mapped_early_patch", "mapped signs, the strong patch from 0.04 s after first sight, before the "
                                      "track is confirmed", 60, 4,
                _stale("mapped", "patch_occlusion", _EARLY_PATCH, stable_steps=2, t_atk=(10.0, 10.0))),
        LoopRow("removed", "a mapped sign that is gone (needless stops)", 60, 4, _stale("removed"), attacked=False),
        LoopRow("phantom", "a stop-sign picture on a wall, no sign, none mapped (needless stops)", 60, 4,
                _stale("phantom"), attacked=False),
        LoopRow("temporary_clean", "a temporary sign the map does not list, clean", 60, 4, _stale("temporary"),
                attacked=False),
        LoopRow("temporary_sticker", "a temporary sign, the 0.6 sticker up from the start", 60, 4,
                _stale("temporary", "physical_patch", {"physical_patch": _STICKER_06})),
        LoopRow("temporary_sticker_top", "a temporary sign, the 0.4 top-edge sticker up from the start", 60, 4,
                _stale("temporary", "physical_patch", {"physical_patch": _STICKER_04_TOP})),
        LoopRow("moved", "a sign standing 0.5-1.5 m off its map entry along the lane, clean", 60, 4, _stale("moved"),
                attacked=False),
        LoopRow("mapped_sticker_blind", "mapped signs, the 0.6 sticker with the sign's depth and the LiDAR's sector "
                                        "blinded from the start (white box on the vote)", 60, 4,
                _stale("mapped", "physical_patch+depth_blackout+lidar_dropout",
                       {"physical_patch": _STICKER_06, "depth_blackout": {"trigger": "always"},
                        "lidar_dropout": {"trigger": "always"}}, t_atk=(60.0, 60.0))),
        LoopRow("mapped_sticker_spoof", "mapped signs, the 0.6 sticker with the sign's depth and LiDAR returns moved "
                                        "away at 3 m/s from the start (white box on the vote)", 60, 4,
                _stale("mapped", "physical_patch+frustum_spoof",
                       {"physical_patch": _STICKER_06, "frustum_spoof": {"trigger": "always", "rate_mps": 3.0}},
                       t_atk=(60.0, 60.0))),
    ),
    drives=(),
    offline_presets=(),
)

#: The lead's four profiles (``lead_vehicle``), each in a quarter of a following row's episodes.
LEAD_PROFILES = ("cruise", "slow_down", "hard_brake", "stop_and_go")


def _following(attack: str, params: dict | None = None, supervisor: bool = False, broadcast: bool = False
               ) -> Callable[[str, int], list[TrialSpec]]:
    """Following episodes (the ``lead_vehicle`` scenario on sign 1's approach at 1 m/s, the lead braking
    at 3 s), paired over defences: ``n // 4`` seeds at each of the lead's profiles (below 4, one seed
    at each of the first ``n`` profiles: a quick card), the attack from 2 s
    for 6 s (the sweeps ``following*.toml``'s grid); ``supervisor``: the defence under the supervisor;
    ``broadcast``: the lead broadcasts its own state (``racf.sim.radio``)."""
    def make(defence: str, n: int) -> list[TrialSpec]:
        space = {"attack": [attack], "estimator": [defence], "rho": [0.95], "t_atk": [6.0], "speed": [1.0], "sign": [1]}
        profiles = list(LEAD_PROFILES)[:max(1, n)]
        situation = {"profile": profiles, **({"broadcast": ["on"]} if broadcast else {})}
        spec = SweepSpec(f"following-{attack}", mode="grid", repeats=max(1, n // len(profiles)), seed=0,
                         space=space, params=params or {}, log_steps=True, detector=CAR_DETECTOR, target="lead_vehicle",
                         scenario={"lead_vehicle": situation}, supervisor=(supervisor,))
        return spec.episodes()
    return make


#: ``racf-6``: the car ahead (issue 59). Following a second QCar 2 in the car's lane through its four
#: profiles, clean and under each attack on the car ahead from 2 s (before it brakes) for 6 s: the
#: patch reading its depth 1 m far, the frustum spoof moving the LiDAR's returns from it 1 m away
#: (alone, and with the depth), the lead hidden from camera and LiDAR, and a phantom car 0.5 m
#: ahead in the camera alone. Rated by the collision-free rate and needless hard brakes (no SCR:
#: the lead stops on the sign's line, and the car behind it).
_RACF_6 = Battery(
    name="racf-6",
    loop=(
        LoopRow("following_clean", "following the car ahead, clean", 60, 4, _following("none"), attacked=False),
        LoopRow("following_patch", "the lead's depth read 1 m far (patch on its rear)", 60, 4, _following("lead_patch")),
        LoopRow("following_frustum", "the LiDAR's returns from the lead moved 1 m away (frustum spoof)", 60, 4,
                _following("lead_frustum")),
        LoopRow("following_frustum_depth", "the frustum spoof with the depth moved too (the range sensors agree)", 60, 4,
                _following("lead_frustum", {"lead_frustum": {"depth": [True]}})),
        LoopRow("following_hide", "the lead hidden from camera and LiDAR", 60, 4, _following("lead_hide")),
        LoopRow("following_phantom", "a phantom car 0.5 m ahead, camera only (needless hard brakes)", 60, 4,
                _following("lead_phantom")),
    ),
    drives=(),
    offline_presets=(),
)


#: The paper's offboard loop: the control step at 20 Hz, the defence in a ``racf serve`` process
#: ("approximately 49 ms per frame (~20 Hz)"); the endpoint the card fills in for each row's link.
PAPER_LOOP_HZ = 20.0
OFFBOARD = "tcp://127.0.0.1:0"
_LINK_DELAY = {"link_delay": {"delay_ms": 60.0, "jitter_ms": 20.0}}
_LINK_SPOOF = {"link_spoof": {"distance_m": 5.0}}


def _offboard(setting: str, params: dict | None = None, fallback: str = "raw") -> Callable[[str, int], list[TrialSpec]]:
    """Offboard episodes; ``fallback``: what drives where the service gives no answer (``raw``, the car's own
    depth: racf-link's; ``odca``: its onboard ODCA, racf-link-2's)."""
    def make(defence: str, n: int) -> list[TrialSpec]:
        return batch_specs(setting + ("" if defence == "raw" else f"+{defence}"), n, detector=CAR_DETECTOR,
                           control_hz=PAPER_LOOP_HZ, estimator_endpoint=OFFBOARD, attack_params=params or {},
                           estimator_fallback=fallback)
    return make


#: ``racf-link``: the defence where the paper ran it, offboard, and its link attacked (issue 58).
#: The paper's loop clean and under the strong patch, then the patch with the link's answers
#: delayed (60 +- 20 ms, past the 50 ms period), lost, or spoofed (the sign 5 m away) on a plain
#: link, and spoofed on a CurveZMQ link. Each attack on the link keeps the protocol's window.
#: racf-link's rows: (key, title, setting, the attacks' parameters, the link).
_LINK_ROWS = (
    ("offboard_clean", "the paper's offboard loop (20 Hz, served), clean", "clean", None, "plain"),
    ("offboard_patch", "offboard, the strong patch", "attack", None, "plain"),
    ("link_delay", "offboard, the patch, the answers delayed 60 +- 20 ms", "attack+link_delay", _LINK_DELAY, "plain"),
    ("link_drop", "offboard, the patch, the answers lost", "attack+link_drop", None, "plain"),
    ("link_spoof_plain", "offboard, the patch, a man in the middle answering 5 m, plain link", "attack+link_spoof",
     _LINK_SPOOF, "plain"),
    ("link_spoof_curve", "offboard, the patch, a man in the middle answering 5 m, CurveZMQ link", "attack+link_spoof",
     _LINK_SPOOF, "curve"),
)


def _link_battery(name: str, fallback: str) -> Battery:
    return Battery(name=name, loop=tuple(
        LoopRow(key, title, 30, 4, _offboard(setting, params, fallback), attacked=setting != "clean", link=link)
        for key, title, setting, params, link in _LINK_ROWS), drives=(), offline_presets=())


_RACF_LINK = _link_battery("racf-link", fallback="raw")
#: ``racf-link-2``: racf-link's rows with the car's onboard fallback (issue 70): where the service gives no
#: answer the car may act on (lost, late, refused by the protocol or by CurveZMQ), its own ODCA, run every
#: step from the ONNX export beside the served one, drives; racf-link's fell back to raw depth.
_RACF_LINK_2 = _link_battery("racf-link-2", fallback="odca")

#: The following rows of ``racf-7``: (key, title, attack, its parameters).
_RACF_7_FOLLOWING = (
    ("following_clean", "following the car ahead, clean", "none", None),
    ("following_patch", "the lead's depth read 1 m far (patch on its rear)", "lead_patch", None),
    ("following_frustum_depth", "the frustum spoof with the depth moved too (the range sensors agree)",
     "lead_frustum", {"lead_frustum": {"depth": [True]}}),
    ("following_adaptive", "the adaptive spoof: depth, LiDAR and picture drawn away at 0.5 m/s to 2 m (outside the "
                           "supervisor's assumptions)", "lead_frustum",
     {"lead_frustum": {"depth": [True], "scale_box": [True], "rate_mps": [0.5], "bias_m": [2.0]}}),
    ("following_hide", "the lead hidden from camera and LiDAR", "lead_hide", None),
    ("following_phantom", "a phantom car 0.5 m ahead, camera only (needless hard brakes)", "lead_phantom", None),
)
_ADAPTIVE = _RACF_7_FOLLOWING[3][3]["lead_frustum"]
#: The broadcast rows of ``racf-7`` (issue 70), under the supervisor, the lead broadcasting: (key, title,
#: attack, its parameters). The lead's lie tells the adaptive spoof's story (away at 0.5 m/s to 2 m).
_LIE = {"bias_m": [2.0], "rate_mps": [0.5], "faster_mps": [0.5]}
_RACF_7_BROADCAST = (
    ("broadcast_clean", "following clean, the lead broadcasting", "none", None),
    ("broadcast_adaptive", "the adaptive spoof, the lead's broadcast honest", "lead_frustum", {"lead_frustum": _ADAPTIVE}),
    ("broadcast_jammed", "the adaptive spoof, the broadcast jammed", "lead_frustum+radio_jam",
     {"lead_frustum": _ADAPTIVE}),
    ("broadcast_replayed", "the adaptive spoof, old messages replayed", "lead_frustum+radio_replay",
     {"lead_frustum": _ADAPTIVE}),
    ("broadcast_forged", "the adaptive spoof, messages forged without the fleet's key", "lead_frustum+radio_forge",
     {"lead_frustum": _ADAPTIVE}),
    ("broadcast_lie", "the lead lies over the radio (its own key), the sensors honest", "radio_lie", {"radio_lie": _LIE}),
    ("broadcast_lie_spoofed", "the lead lies and the adaptive spoof tells the same story (outside the guarantee)",
     "lead_frustum+radio_lie", {"lead_frustum": _ADAPTIVE, "radio_lie": _LIE}),
)

#: ``racf-7``: the supervisor (issue 69). Each of racf-6's following rows that its guarantee speaks to,
#: and the adaptive spoof that lies outside it, with the defence alone and under the supervisor
#: (``*_supervised``: the same seeds), and the stop sign's two sustained attacks (a temporary sign
#: under the 0.6 sticker, the strong patch for the whole approach): the supervisor supervises the
#: following stage only, so those rows rate the defence alone (``racf-5``/``racf-4``'s episodes). Issue 70
#: added, before any card was made, the rows with the lead broadcasting (``broadcast_*_supervised``): clean,
#: and the adaptive spoof with the broadcast honest, jammed, replayed, forged and lied by the lead.
#: racf-7's following rows in a quick card: 2 episodes a row, so that the quick card of its 25 rows
#: takes under 3 minutes on 2 cores (4 a row took 219 s: a following episode runs about 4 s).
_QUICK_FOLLOWING = 2
_RACF_7 = Battery(
    name="racf-7",
    loop=(
        *(LoopRow(key, title, 60, _QUICK_FOLLOWING, _following(attack, params), attacked=attack != "none")
          for key, title, attack, params in _RACF_7_FOLLOWING),
        *(LoopRow(f"{key}_supervised", f"{title}, under the supervisor", 60, _QUICK_FOLLOWING,
                  _following(attack, params, supervisor=True), attacked=attack != "none")
          for key, title, attack, params in _RACF_7_FOLLOWING),
        *(LoopRow(f"{key}_supervised", f"{title}, under the supervisor", 60, _QUICK_FOLLOWING,
                  _following(attack, params, supervisor=True, broadcast=True), attacked=attack != "none")
          for key, title, attack, params in _RACF_7_BROADCAST),
        LoopRow("temporary_sticker", "a temporary sign, the 0.6 sticker up from the start", 60, 4,
                _stale("temporary", "physical_patch", {"physical_patch": _STICKER_06})),
        LoopRow("patch_whole_approach", "the strong patch for the whole approach (rho 1, 10 s)", 60, 4,
                sweep_row("patch_whole_approach", "patch_occlusion", mode="grid", t_atk=[10.0], rho=[1.0])),
    ),
    drives=(),
    offline_presets=(),
)

#: Every released battery, by name.
BATTERIES = {"racf-1": _RACF_1, "racf-2": _RACF_2, "racf-3": _RACF_3, "racf-4": _RACF_4, "racf-5": _RACF_5,
             "racf-link": _RACF_LINK, "racf-6": _RACF_6, "racf-7": _RACF_7, "racf-link-2": _RACF_LINK_2}
from racf.experiments.scorecard.battery_names import DEFAULT_BATTERY  # noqa: E402  (the names' one home)
