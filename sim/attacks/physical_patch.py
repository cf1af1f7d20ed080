"""``PhysicalPatch``: a sticker printed on the stop sign in the world (the scene renders it).

Unlike the image-space occluder (``patch_occlusion``), the sticker is part of the scene:
the env prints a texture on the target sign's plate (``QCar2Env.show_sign_patch``), and the
camera renders it in perspective, under the room's light and at the camera's resolution,
as every other surface; the depth camera and the LiDAR see the plate it is stuck on.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule
from racf.sim.world.sign_patch import PatchPlacement, load_patch_texture
from racf.sim.world.stop_signs import StopSign

__all__ = ["PhysicalPatch"]


class PhysicalPatch(AttackWrapper):
    """A sticker printed on the target stop sign: the paper's patch injection, in the world.

    The sticker (``texture``, ``size`` of the plate's area, at ``position``) goes up when the
    protocol's schedule opens the attack window (after a stable detection, inside the
    braking window): the sticker's geom swaps from hidden to printed. The step's frame was
    taken before it went up; frames from the next one on show it. A printed sticker does not
    come off (``stays``), so it stays until the episode ends; with ``stays=False`` it comes
    off when the window (``duration_s``) ends. With ``from_start`` it is on the sign from the
    episode's first frame (the reset's frame is taken again with it).

    Args:
        env: the racf env (or a wrapper of it).
        texture: a shipped sticker (``learned``: optimised against the learned segmenter by
            ``racf detector optimise-patch``; ``learned-approach``: the same over the car's approaches,
            ``--views approach``), ``natural`` (a naturalistic sticker drawn per episode), or a PNG path.
        size: the sticker's area over the plate's, in (0, 0.6].
        position: its centre (right, up) on the plate, across-flats units, or a name of
            ``racf.sim.world.sign_patch.POSITIONS`` (as far that way as it stays on the plate).
        from_start: on the sign from the episode's start.
        stays: once up, up until the episode ends.
        **schedule: ``AttackSchedule`` fields.
    """

    name = "physical_patch"
    needs_simulator = "it is a sticker on the sign in the scene, rendered by the simulator"
    #: It is drawn on a stop sign's face: a crate has none.
    targets = ("sign", "drive")

    def __init__(self, env: gym.Env, texture: str = "learned", size: float = 0.5, position: Any = "centre",
                 from_start: bool = False, stays: bool = True, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, texture=texture, size=size, position=position,
                                                 from_start=from_start, stays=stays, **schedule)
        for name, value in (("from_start", from_start), ("stays", stays)):
            if not isinstance(value, bool):
                raise ValueError(f"{name} must be true or false, got {value!r}")
        self.placement = PatchPlacement(area_share=size, centre=tuple(position) if isinstance(position, list)
                                        else position)
        self.texture_name = texture
        self._fixed_texture = None if texture == "natural" else load_patch_texture(texture)
        self.from_start, self.stays = from_start, stays
        super().__init__(env, AttackSchedule(**schedule))
        self._texture = self._fixed_texture
        self._shown = False

    def _on_reset(self) -> None:
        self._texture = self._fixed_texture if self._fixed_texture is not None else \
            load_patch_texture("natural", self.rng)
        self._shown = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = super().reset(seed=seed, options=options)
        if self.from_start:
            self._show()
            marks = info["attack"]  # the inner wrappers' marks on the first info
            self.schedule.windows = [(0.0, float(self.env.unwrapped.config.max_episode_s))]
            obs, info = self.env.unwrapped.retake_reset_frame()
            self.active = True
            info = self._mark({**info, "attack": marks})
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        window = self.schedule.update(info)
        if window and not self._shown:
            self._show()
            if self.stays:  # the window the results report is the sticker's time on the sign
                self.schedule.windows[-1] = (self.schedule.windows[-1][0],
                                             float(self.env.unwrapped.config.max_episode_s))
        elif self._shown and not window and not (self.stays or self.from_start):
            self.env.unwrapped.hide_sign_patches()
            self._shown = False
        self.active = self._shown
        return obs, reward, terminated, truncated, self._mark(info)

    def _show(self) -> None:
        u = self.env.unwrapped
        if not isinstance(u.target_sign, StopSign):
            raise ValueError(f"physical_patch prints on a stop sign; this episode's target is {u.target_sign!r}")
        u.show_sign_patch(u.target_sign.index, self._texture, self.placement)
        self._shown = True

    def _attack(self, obs: dict, info: dict) -> dict:
        return obs  # the world does the work
