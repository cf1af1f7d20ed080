"""The common part of the attack wrappers: schedule, seeding and the ``info`` marks."""

from __future__ import annotations

import inspect
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from racf.sim.attacks.schedule import SCHEDULE_PARAMS, AttackSchedule

__all__ = ["AttackWrapper", "attack_wrappers", "blank_env", "find_wrapper"]


class AttackWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Applies ``_attack`` to the observation on the steps its schedule makes active.

    Subclasses set ``name`` (their key in ``racf.sim.attacks.ATTACKS``) and implement ``_attack(obs, info) -> obs`` (and, for
    per-episode draws, ``_on_reset()``). Wrappers compose: ``info["attack"]`` is the tuple
    of the attacks active this step, ``info["attack_active"]`` whether there is any.
    Randomness comes from a generator drawn from the env's seeded one at each reset.
    """

    name = "attack"
    #: Marks the base of racf's attacks for the registries (``racf.plugins.PART_KIND``).
    racf_part: ClassVar[str] = "attack"
    #: Constructor arguments an experiment sets per episode (e.g. the patch's ``rho``); the
    #: others keep their defaults.
    episode_params: tuple[str, ...] = ()
    #: ``"black box"`` (the observations and where the sign is) or ``"white box"`` (also the
    #: defence: the runner hands it the car's estimator through ``attach_defence``).
    threat_model = "black box"
    #: The targets it can act on (``TrialSpec.target``): a stop sign approach, an obstacle crate's,
    #: a drive (which meets stop signs). An episode that asks for another is refused before it runs.
    targets: tuple[str, ...] = ("sign", "obstacle", "drive")
    #: The kind of declared target it aims at (``racf.sim.world.manager.TARGET_KINDS``: a vehicle, a
    #: person), found through the world's ``WorldManager.targets()``; None: the map's sign or crate.
    #: An episode whose world declares no target of this kind is refused before it runs.
    acts_on: str | None = None
    #: Why it cannot act on a recording (empty: it reads only the observation and ``info``): an
    #: attack that places things in the scene or aims from the simulator's geometry says so here.
    needs_simulator: str = ""
    defence: Any = None

    @classmethod
    def settable_params(cls) -> tuple[str, ...]:
        """The constructor arguments an experiment may set (``TrialSpec.attack_params``): every
        named one but the env and the ``episode_params``, and, for an attack that takes the
        schedule's keywords, the schedule's :data:`~racf.sim.attacks.schedule.SCHEDULE_PARAMS`."""
        skip = {"self", "env", *cls.episode_params}
        params = inspect.signature(cls.__init__).parameters
        own = tuple(name for name, p in params.items()
                    if name not in skip and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))
        takes_schedule = any(p.kind == p.VAR_KEYWORD for p in params.values())
        return own + tuple(name for name in SCHEDULE_PARAMS if takes_schedule and name not in own)

    @classmethod
    def check_params(cls, params: dict[str, Any]) -> None:
        """Fails before any episode runs on a parameter the attack does not take, or a value it
        refuses (it is built once on a blank env to ask); the error names what is allowed."""
        if not isinstance(params, dict):
            raise ValueError(f"{cls.name} parameters must be a table of name = value, got {params!r}")
        allowed = cls.settable_params()
        unknown = sorted(set(params) - set(allowed))
        if unknown:
            raise ValueError(f"{cls.name} has no parameter(s) {unknown}; it takes {list(allowed)}")
        try:
            cls(_BlankEnv(), **params)
        except ValueError as err:
            raise ValueError(f"{cls.name}: {err}") from None

    def __init__(self, env: gym.Env, schedule: AttackSchedule | None) -> None:
        gym.Wrapper.__init__(self, env)
        for key in ("rgb", "depth", "lidar"):
            if not isinstance(env.observation_space, gym.spaces.Dict) or key not in env.observation_space.spaces:
                raise ValueError(f"{type(self).__name__} needs a Dict observation space with 'rgb', 'depth' and "
                                 f"'lidar' (the racf env), got {env.observation_space}")
        self.schedule = schedule or AttackSchedule()
        self.rng = np.random.default_rng(0)
        self.active = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        self.rng = np.random.default_rng(self.np_random.integers(2**63))
        self.schedule.reset(np.random.default_rng(self.rng.integers(2**63)))
        self._on_reset()
        self.active = False
        return obs, self._mark(info)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.active = self.schedule.update(info)
        if self.active:
            obs = self._attack(dict(obs), info)
        return obs, reward, terminated, truncated, self._mark(info)

    def _mark(self, info: dict) -> dict:
        info = dict(info)
        attacks = tuple(info.get("attack", ())) + ((self.name,) if self.active else ())
        info["attack"] = attacks
        info["attack_active"] = bool(attacks)
        return info

    def attach_defence(self, defence: Any) -> None:
        """A white-box attack is given the defence it faces (its thresholds and state)."""
        if self.threat_model != "white box":
            raise ValueError(f"{type(self).__name__} is a {self.threat_model} attack: it may not read the defence")
        self.defence = defence

    def _on_reset(self) -> None:
        """Per-episode draws (textures, signs of a bias, ...)."""

    def _attack(self, obs: dict, info: dict) -> dict:
        raise NotImplementedError

    def sign_region(self, info: dict, margin_px: int = 0) -> np.ndarray:
        """(H, W) bool: the target sign's pixels (ground truth, the attacker's knowledge), optionally grown."""
        mask = np.asarray(info["sign_mask"], bool)
        if margin_px > 0 and mask.any():
            import cv2

            k = 2 * margin_px + 1
            mask = cv2.dilate(mask.view(np.uint8), np.ones((k, k), np.uint8)).astype(bool)
        return mask

    def sign_range_m(self) -> float:
        """The LiDAR's horizontal distance to the target sign, m (ground truth)."""
        u = self.env.unwrapped
        lidar = u.data.site("lidar")
        return float(np.hypot(u.target_sign.position[0] - lidar.xpos[0], u.target_sign.position[1] - lidar.xpos[1]))

    def sign_beams(self, n_beams: int, extra_half_width_rad: float = 0.0) -> np.ndarray:
        """(n_beams,) bool: LiDAR beams that point at the target sign's plate (ground truth)."""
        u = self.env.unwrapped
        sign = u.target_sign
        lidar = u.data.site("lidar")
        yaw = float(np.arctan2(lidar.xmat[3], lidar.xmat[0]))
        dx, dy = sign.position[0] - lidar.xpos[0], sign.position[1] - lidar.xpos[1]
        dist = max(self.sign_range_m(), 1e-3)
        bearing = np.arctan2(dy, dx) - yaw
        half = np.arctan(0.05 / dist) + extra_half_width_rad
        angles = 2 * np.pi * np.arange(n_beams) / n_beams
        diff = (angles - bearing + np.pi) % (2 * np.pi) - np.pi
        beams = np.abs(diff) <= half
        if not beams.any():
            beams[int(np.argmin(np.abs(diff)))] = True
        return beams


def blank_env() -> gym.Env:
    """The smallest env an attack can be built on (its observation space only): to check an
    attack's parameters and schedule by building it, before any episode."""
    return _BlankEnv()


class _BlankEnv(gym.Env):
    """The smallest env an attack can be built on: its observation space, nothing else (to check parameters)."""

    observation_space = gym.spaces.Dict({
        "rgb": gym.spaces.Box(0, 255, (2, 2, 3), np.uint8), "depth": gym.spaces.Box(0.0, np.inf, (2, 2, 1), np.float32),
        "lidar": gym.spaces.Box(0.0, np.inf, (4,), np.float32)})
    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)


def find_wrapper(env: gym.Env, kind: type) -> gym.Env | None:
    """The outermost wrapper of ``kind`` around an env (None: none)."""
    while isinstance(env, gym.Wrapper):
        if isinstance(env, kind):
            return env
        env = env.env
    return None


def attack_wrappers(env: gym.Env) -> list[AttackWrapper]:
    """Every attack wrapper around an env, outermost first."""
    found = []
    while isinstance(env, gym.Wrapper):
        if isinstance(env, AttackWrapper):
            found.append(env)
        env = env.env
    return found
