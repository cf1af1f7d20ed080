"""The one declaration of an episode's step log: every column with its unit, meaning and side.

A step's row is the car's columns (what the car's software computed from the observation and
the map: perception, estimator, braker, steering, its pose estimate) beside the referee's
(ground truth and the reference braker, which the car never sees). The runner makes every row
through :func:`step_row`, which refuses a row that leaves out a declared column or adds an
undeclared one, so this table, the log, the scorer and the dataset cannot drift apart.

The car stages a mission engages add the columns they declare (``CarStage.columns``:
:func:`stage_columns`), on the car's side, after racf's own; a scenario's world managers add the
ground-truth columns they declare (``WorldManager.columns()``: :func:`world_columns`), on the
referee's side, after those.
An estimator adds its own columns through ``diagnostics()`` (ODCA: ``w``, ``flag``,
``odca_source``, ``d_kin``; a plug-in: whatever it reports). ``w``, ``flag`` and ``score`` are declared
(NaN when the estimator has none), the others ride along on the car's side.

Example:
    >>> from racf.experiments.episode.record import STEP_LOG
    >>> STEP_LOG["d_fused"].unit, STEP_LOG["d_fused"].side
    ('m', 'car')
"""

from __future__ import annotations

from dataclasses import dataclass

from racf.sim.sensors.state import STATE_FIELDS

__all__ = ["Column", "STEP_COLUMNS", "STEP_LOG", "CAR", "REFEREE", "step_row", "columns_of", "world_columns", "stage_columns"]

CAR, REFEREE, EPISODE = "car", "referee", "episode"
#: The unit of each field of the state sensor (a new field must be given one here).
_STATE_UNITS = {"speed_mps": "m/s", "steering_rad": "rad", "yaw_rate_radps": "rad/s", "accel_mps2": "m/s^2"}


@dataclass(frozen=True)
class Column:
    """One column of the step log.

    Attributes:
        name: the column's name.
        unit: SI unit (``m``, ``s``, ``rad``, ``m/s``, ...), ``bool``, ``1`` (a share) or ``""``.
        meaning: what it holds.
        side: ``car`` (the car's software made it), ``referee`` (ground truth, the reference
            braker: never seen by the car) or ``episode`` (the row's identity).
    """

    name: str
    unit: str
    meaning: str
    side: str


def _c(side: str, name: str, unit: str, meaning: str) -> Column:
    return Column(name, unit, meaning, side)


#: Every column, in the log's order.
STEP_COLUMNS: tuple[Column, ...] = (
    _c(EPISODE, "trial_id", "", "the episode's id (a hash of its spec, configs, code and plug-ins)"),
    _c(CAR, "t", "s", "time since the episode's start (the env's clock, which the car's own clock matches)"),
    _c(CAR, "slot", "", "which of the mission's targets the car is serving (0, 1, ...)"),
    _c(CAR, "target", "", "that target's name (sign0-sign3, obstacle0-obstacle1)"),
    _c(CAR, "control", "bool", "the controller ran this step (it runs every round(50 / control_hz) steps)"),
    _c(CAR, "d_meas", "m", "perception's depth distance: median valid depth in the detection's mask (NaN: none)"),
    _c(CAR, "c_meas", "1", "its confidence: detection confidence x valid-depth share"),
    _c(CAR, "lidar", "m", "the LiDAR reference: the tracked cluster's depth along the camera axis (NaN: none)"),
    _c(CAR, "d_size", "m", "the size witness: the distance the detection's box implies from the sign's known size "
                           "(NaN: none, or a box too broken or cut to measure)"),
    _c(CAR, "size_std", "m", "its std"),
    _c(CAR, "d_fused", "m", "the distance the car acted on: the estimator's output (NaN: no target)"),
    _c(CAR, "w", "1", "ODCA's gate weight (NaN for other estimators)"),
    _c(CAR, "flag", "bool", "the defence's detector flagged the step (1.0; NaN: it has no detector)"),
    _c(CAR, "score", "1", "the defence's detection statistic, higher is more suspicious (NaN: it reports none); "
                          "the scorecard sweeps a threshold over it"),
    _c(CAR, "detected", "bool", "the detector reported a target"),
    _c(CAR, "det_confidence", "1", "the detection's confidence (0: none)"),
    _c(CAR, "bearing", "rad", "the detection's bearing from the optical axis, left positive (NaN: none)"),
    _c(CAR, "det_x0", "px", "the detection's box, left (-1: none)"),
    _c(CAR, "det_y0", "px", "the detection's box, top (-1: none)"),
    _c(CAR, "det_x1", "px", "the detection's box, right (-1: none)"),
    _c(CAR, "det_y1", "px", "the detection's box, bottom (-1: none)"),
    _c(CAR, "confirmed", "bool", "the braker holds a confirmed track"),
    _c(CAR, "phase", "", "the braker's phase (cruise, approach, brake, hold, done)"),
    _c(CAR, "brake", "bool", "the braker commands the brake"),
    _c(CAR, "speed_cap", "m/s", "the braker's speed cap"),
    _c(CAR, "speed_cmd", "m/s", "the speed command that reached the car this step (after any delay)"),
    _c(CAR, "steer_cmd", "rad", "the steering command that reached the car this step"),
    _c(CAR, "x_est", "m", "the car's own pose estimate, map frame"),
    _c(CAR, "y_est", "m", "the car's own pose estimate, map frame"),
    _c(CAR, "yaw_est", "rad", "the car's own heading estimate, map frame"),
    _c(CAR, "fix_x", "m", "the localiser's last fix as the car received it (held between fixes)"),
    _c(CAR, "fix_y", "m", "the localiser's last fix"),
    _c(CAR, "fix_yaw", "rad", "the localiser's last fix, heading"),
    *(_c(CAR, f"state_{name}", _STATE_UNITS[name], f"the vehicle state as the car measures it: {name}")
      for name in STATE_FIELDS),
    _c(CAR, "frame_new", "bool", "a new camera frame arrived this step"),
    _c(CAR, "scan_new", "bool", "a new LiDAR scan arrived this step"),
    _c(CAR, "scan_fov", "m", "the LiDAR's forward sector, beams -40..+40 deg CCW from forward (inf: no return)"),
    _c(CAR, "track_x", "m", "the LiDAR track's point in the body frame, forward (NaN: no track)"),
    _c(CAR, "track_y", "m", "the LiDAR track's point in the body frame, left (NaN: no track)"),
    _c(REFEREE, "d_true", "m", "ground truth: the target's depth along the camera axis"),
    _c(REFEREE, "d_clean", "m", "the car's perception on the unattacked readings (the protocol's pseudo ground "
                                "truth; NaN under attack without the clean pass)"),
    _c(REFEREE, "clean_detected", "bool", "the car's detector finds the target on the unattacked frame (its box "
                                          "on the target's pixels): a frame an attack can be blamed for losing"),
    _c(REFEREE, "sign_in_view", "bool", "ground truth: some of the target is visible (never where no sign stands)"),
    _c(REFEREE, "sign_stands", "bool", "ground truth: a real target stands there (False: a removed sign, a phantom)"),
    _c(REFEREE, "ideal_brake", "bool", "the reference braker (fed d_true) brakes: its first step is t*"),
    _c(REFEREE, "x", "m", "ground truth: pose in the map frame"),
    _c(REFEREE, "y", "m", "ground truth: pose in the map frame"),
    _c(REFEREE, "yaw", "rad", "ground truth: heading in the map frame"),
    _c(REFEREE, "speed", "m/s", "ground truth: the body's speed"),
    _c(REFEREE, "dist_to_stop_line", "m", "ground truth: front bumper to the stop line along the route "
                                          "(negative past it)"),
    _c(REFEREE, "lateral_error", "m", "ground truth: distance from the lane's centre line"),
    _c(REFEREE, "attack_active", "bool", "some attack acted on this step's observation"),
    _c(REFEREE, "attack", "", "the attacks active this step, '+'-joined"),
    _c(REFEREE, "collision_with", "", "ground truth: what the car touched (a world manager's name for its body, "
                                      "else the geom's name; '' nothing)"),
    _c(REFEREE, "radio_sent", "", "the radio: messages the world's vehicles sent this step"),
    _c(REFEREE, "radio_delivered", "", "the radio: messages that arrived at the car this step, before any attack"),
    _c(REFEREE, "radio_injected", "", "the radio: messages an attacker put on the air this step, forged or "
                                      "replayed (an insider's lie is the sender's own message)"),
    _c(REFEREE, "radio_genuine_slots", "", "the radio: which of the car's radio slots this step hold a message the "
                                          "world's radio delivered this step (a bit mask; the others are an "
                                          "attacker's)"),
)
#: The columns by name.
STEP_LOG: dict[str, Column] = {c.name: c for c in STEP_COLUMNS}
_DECLARED = frozenset(STEP_LOG) - {"trial_id"}
_FROM_DIAGNOSTICS = {"w", "flag", "score"}


def columns_of(side: str) -> tuple[str, ...]:
    """The names of one side's columns (``car``, ``referee`` or ``episode``)."""
    if side not in (CAR, REFEREE, EPISODE):
        raise ValueError(f"side must be 'car', 'referee' or 'episode', got {side!r}")
    return tuple(c.name for c in STEP_COLUMNS if c.side == side)


def stage_columns(stages) -> tuple[Column, ...]:
    """The columns the car's stages declare (``CarStage.columns``), as step log columns on the car's
    side. ValueError names one that racf's own columns or an earlier stage already hold."""
    out: list[Column] = []
    for stage in stages:
        for column in stage.columns:
            taken = column.name in STEP_LOG or any(c.name == column.name for c in out)
            if taken:
                raise ValueError(f"car stage {stage.name!r} declares the column {column.name!r}, which the step log "
                                 "already holds; give it another name")
            out.append(Column(column.name, column.unit, column.meaning, CAR))
    return tuple(out)


def world_columns(managers) -> tuple[Column, ...]:
    """The ground-truth columns a world's managers declare (``WorldManager.columns()``), as step log
    columns on the referee's side. ValueError names one that racf's own columns already hold."""
    out = []
    for manager in managers:
        for column in manager.columns():
            if column.name in STEP_LOG:
                raise ValueError(f"world manager {manager.name!r} declares the column {column.name!r}, which racf's "
                                 "step log already holds; give it another name")
            out.append(Column(column.name, column.unit, column.meaning, REFEREE))
    return tuple(out)


def step_row(values: dict, diagnostics: dict, world: tuple[Column, ...] = ()) -> dict:
    """One step's row, in the declared order (racf's columns, then the ``world`` columns: the car
    stages' and the world managers', in that order), then the estimator's own diagnostics.

    ``values`` holds every declared column but ``trial_id`` (added per log) and ``w``/``flag``/``score``
    (from ``diagnostics`` when the estimator reports them, else NaN). ValueError names a
    column left out or not declared: a new column is declared here first (a world manager's, by
    its ``columns()``).
    """
    declared = _DECLARED | {c.name for c in world} if world else _DECLARED
    given = set(values) | _FROM_DIAGNOSTICS
    if given != declared:
        raise ValueError(f"step row: missing {sorted(declared - given)}, undeclared {sorted(given - declared)}; "
                         "declare a new column in racf.experiments.episode.record.STEP_COLUMNS (racf's), in its car "
                         "stage's columns or in its world manager's columns()")
    row = {name: values[name] if name in values else diagnostics.get(name, float("nan"))
           for name in STEP_LOG if name != "trial_id"}
    for column in world:
        row[column.name] = values[column.name]
    for name, value in diagnostics.items():
        if name not in _FROM_DIAGNOSTICS:
            if name in row:
                raise ValueError(f"an estimator's diagnostics may not overwrite the declared column {name!r}")
            row[name] = value
    return row
