"""What the ego car touches: a contact of its chassis with anything, or of a wheel with anything but
the floor, named by the world manager that owns the body (``WorldManager.owner_of``) or by the geom."""

from __future__ import annotations

from racf.sim._gl import ensure_gl_backend

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["Contacts"]

_WHEELS = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")


class Contacts:
    """Reads the model's contacts for the ego car's (``chassis``, its wheels; the floor is ``mat`` and
    ``lab_floor``)."""

    def __init__(self, model: mujoco.MjModel, world: tuple) -> None:
        self.model, self.world = model, world
        self._chassis = model.geom("chassis").id
        self._wheels = {model.geom(w).id for w in _WHEELS}
        self._floor = {model.geom("mat").id, model.geom("lab_floor").id}

    def touching(self, data: mujoco.MjData) -> str | None:
        """The name of the first thing the car touches now (None: nothing)."""
        for i in range(data.ncon):
            g1, g2 = int(data.contact.geom1[i]), int(data.contact.geom2[i])
            other = g2 if g1 == self._chassis or g1 in self._wheels else g1
            if self._chassis in (g1, g2) or ((g1 in self._wheels or g2 in self._wheels) and other not in self._floor):
                return self.name_of(other)
        return None

    def name_of(self, geom: int) -> str:
        """What a geom belongs to: what a world manager calls its body, else the geom's (or its body's) name."""
        body = int(self.model.geom_bodyid[geom])
        root = int(self.model.body_rootid[body])
        for manager in self.world:
            owner = manager.owner_of(root)
            if owner is not None:
                return owner
        return self.model.geom(geom).name or self.model.body(body).name or f"geom{geom}"
