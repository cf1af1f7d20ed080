"""The RPLIDAR A2M12 as the QCar 2 delivers it: a sweeping scan through Quanser's driver.

The scanner spins clockwise (seen from above) at ``rev_hz`` and takes ``samples_per_rev``
samples a revolution, each at its own time and from wherever the car is then: the env calls
:meth:`A2M12Lidar.sweep` after every physics step and the sensor casts the samples whose time
has come. A revolution starts when the rotor points along the LiDAR's own forward, which is
the car's rear (the QCar 2 mounts it yawed 180 deg), so the road ahead is seen half a
revolution, 50 ms, before the scan is complete.

One sample, as modelled:

- **Footprint.** ``sub_rays`` rays spread over the angle the rotor turns during the sample.
  Where they straddle a depth jump the return mixes the surfaces, weighted by the light each
  sends back (1/r^2): the "mixed" points triangulation scanners give at edges.
- **Dropout.** A return comes back with probability (1 - the material's dropout) x a
  grazing factor: 1 up to ``grazing_start_deg`` of incidence, falling linearly to 0 at
  ``grazing_end_deg``. Materials are named by the map's geoms (sign plates, poles, walls,
  crates, anything else); their defaults follow what users of the A1/A2 report: bright
  matte surfaces return nearly always, dark ones lose up to a third.
- **Range.** Gaussian noise of ``noise_rel`` x range (the datasheet's 1 %), quantised to
  ``quantum_m`` (1 mm), no return below ``range_min_m`` (0.2 m) or above ``range_max_m``.

A finished revolution goes through :func:`racf.sim.sensors.lidar_driver.deliver` (Quanser's read
of 384 samples and ``filter_rplidar_data``'s 1-degree bins) and is turned into the car's
frame: bin i at i degrees counter-clockwise from the car's +x, ``inf`` for no return, like
the ideal LiDAR's. :attr:`A2M12Lidar.beam_times` says when the rotor was at each bin.

Noise and dropout of a revolution are drawn when it completes, all at once, so a swept scan
and a one-instant scan (``sweep=False``) of a static scene are the same bytes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from racf.sim._gl import ensure_gl_backend
from racf.sim.sensors.base import Sensor, check_range
from racf.sim.sensors.lidar_driver import filter_rplidar_data, quanser_read

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["A2M12Config", "A2M12Lidar", "MATERIALS", "material_of", "driver_scan", "VISIBLE_GROUPS"]

#: Material classes of the map's geoms, in the order of :attr:`A2M12Config.dropouts`.
MATERIALS = ("sign", "pole", "wall", "crate", "other")
#: Geom groups the beams can hit (the map and its props); the car is group 3. Public: a benchmark
#: casting the same rays alone (``racf bench sim``'s floor) uses it.
VISIBLE_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)


def material_of(geom_name: str) -> str:
    """The material class of a geom of the map, by its name (see ``racf.sim.world.scene``)."""
    if geom_name.endswith("_pole"):
        return "pole"
    if geom_name.startswith(("stop_sign_", "yield_")):
        return "sign"
    if geom_name.startswith("wall"):
        return "wall"
    if geom_name.startswith("obstacle_"):
        return "crate"
    return "other"


def driver_scan(ranges: np.ndarray, times: np.ndarray, read_per_rev: int = 384, n_bins: int = 360,
                max_gap_deg: float = 1.1, yaw_deg: float = 180.0) -> tuple[np.ndarray, np.ndarray]:
    """One revolution's samples as the car's software gets them: Quanser's read of ``read_per_rev``
    of them, ``filter_rplidar_data``'s bins, turned into the car's frame.

    Args:
        ranges: (n,) m in scan order, sample i at i * 360 / n deg clockwise from the LiDAR's
            forward; 0 = no return (NaN too: a sample the read skips).
        times: (n,) when each sample was taken, s.
        read_per_rev, n_bins, max_gap_deg: the driver's settings (``A2M12Config``).
        yaw_deg: the LiDAR's forward in the car's frame, deg counter-clockwise (the QCar 2 mounts
            it yawed 180: forward is the car's rear); a multiple of the bin width.

    Returns:
        ``(scan, beam_times)``: (n_bins,) float32 m, bin j at j deg counter-clockwise from the car's
        forward, ``inf`` = no return; (n_bins,) float64 s, when the rotor was at each bin.
    """
    ranges, times = np.asarray(ranges, float), np.asarray(times, float)
    n = ranges.size
    degrees = np.degrees(np.arange(n) * (2 * math.pi / n))
    _, picks = quanser_read(degrees, np.arange(n, dtype=float), read_per_rev)
    picked = picks.astype(np.int64)
    bins = filter_rplidar_data(degrees[picked], ranges[picked], n_bins, max_gap_deg)
    bin_times = np.interp(np.arange(n_bins) * (360.0 / n_bins), degrees[picked], times[picked])
    # LiDAR bin j (j bins clockwise from its forward) is car bin (yaw - j) mod n_bins.
    to_car = (int(round(yaw_deg * n_bins / 360.0)) - np.arange(n_bins)) % n_bins
    scan = np.full(n_bins, np.inf, np.float32)
    scan[to_car] = np.where(bins > 0, bins, np.inf)
    beam_times = np.empty(n_bins)
    beam_times[to_car] = bin_times
    return scan, beam_times


@dataclass(frozen=True)
class A2M12Config:
    """The A2M12's samples and Quanser's driver settings (defaults: the QCar 2's).

    Attributes:
        samples_per_rev: samples a revolution (16 k samples/s at 10 Hz: 1600).
        sub_rays: rays per sample footprint, over the angle the rotor turns in one sample.
        range_min_m, range_max_m: returns outside read as none (0.2 m; 12 m).
        noise_rel: range noise std as a share of range (1 %).
        quantum_m: range resolution, m (1 mm).
        dropout_sign, dropout_pole, dropout_wall, dropout_crate, dropout_other: probability
            that a sample on that material returns nothing at normal incidence: the sign
            plate's retroreflective sheeting, the thin metal pole, the matte light walls,
            the dark blue crates, anything else.
        grazing_start_deg, grazing_end_deg: incidence angles between which the chance of a
            return falls from full to none.
        read_per_rev: measurements Quanser's ``QCarLidar`` reads a revolution (384).
        n_bins: bins of ``filter_rplidar_data``'s grid (360: one degree); even, so the 180
            deg mounting maps bins onto bins.
        max_gap_deg: the driver's gap rule, degrees (1.1).
        sweep: cast each sample at its own time (True) or the whole revolution at the instant
            it completes (False, an ablation and a test oracle).
    """

    samples_per_rev: int = 1600
    sub_rays: int = 3
    range_min_m: float = 0.2
    range_max_m: float = 12.0
    noise_rel: float = 0.01
    quantum_m: float = 0.001
    dropout_sign: float = 0.01
    dropout_pole: float = 0.10
    dropout_wall: float = 0.02
    dropout_crate: float = 0.20
    dropout_other: float = 0.05
    grazing_start_deg: float = 60.0
    grazing_end_deg: float = 85.0
    read_per_rev: int = 384
    n_bins: int = 360
    max_gap_deg: float = 1.1
    sweep: bool = True

    def __post_init__(self) -> None:
        for name, lo, hi in (("samples_per_rev", 8, 20_000), ("sub_rays", 1, 9), ("n_bins", 8, 3600)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
                raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
        if self.n_bins % 2:
            raise ValueError(f"n_bins must be even (the LiDAR is mounted yawed 180 deg), got {self.n_bins}")
        rpr = self.read_per_rev
        if isinstance(rpr, bool) or not isinstance(rpr, (int, np.integer)) or not 1 <= rpr <= self.samples_per_rev:
            raise ValueError(f"read_per_rev must be an integer in [1, samples_per_rev={self.samples_per_rev}], got {rpr!r}")
        check_range("range_min_m", self.range_min_m, 0.0, 5.0)
        check_range("range_max_m", self.range_max_m, 0.5, 50.0)
        if self.range_min_m >= self.range_max_m:
            raise ValueError(f"range_min_m must be below range_max_m, got {self.range_min_m} >= {self.range_max_m}")
        check_range("noise_rel", self.noise_rel, 0.0, 0.2)
        check_range("quantum_m", self.quantum_m, 0.0, 0.1)
        for material in MATERIALS:
            check_range(f"dropout_{material}", getattr(self, f"dropout_{material}"), 0.0, 1.0)
        check_range("grazing_start_deg", self.grazing_start_deg, 0.0, 90.0)
        check_range("grazing_end_deg", self.grazing_end_deg, 0.0, 90.0)
        if self.grazing_end_deg <= self.grazing_start_deg:
            raise ValueError(f"grazing_end_deg must exceed grazing_start_deg, got {self.grazing_end_deg} <= "
                             f"{self.grazing_start_deg}")
        check_range("max_gap_deg", self.max_gap_deg, 0.0, 360.0, low_open=True)
        if not isinstance(self.sweep, bool):
            raise ValueError(f"sweep must be True or False, got {self.sweep!r}")

    @property
    def dropouts(self) -> np.ndarray:
        """(len(MATERIALS),) dropout probabilities at normal incidence, in ``MATERIALS`` order."""
        return np.array([getattr(self, f"dropout_{m}") for m in MATERIALS])

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


class A2M12Lidar(Sensor):
    """The delivered scan: (n_bins,) float32 metres in the car's frame, ``inf`` = no return.

    Args:
        config: the scanner and driver settings.
        rev_hz: revolutions per second (the env's ``lidar_hz``).
        physics_dt_s: the simulator's step; samples are cast after each one.
        site: the MJCF site at the scan centre (axes along the car's).
    """

    name = "lidar"
    dtype = np.float32
    low, high = 0.0, np.inf

    def __init__(self, config: A2M12Config, rev_hz: float, physics_dt_s: float, site: str = "lidar") -> None:
        self.config = config
        self.site = site
        self.shape = (config.n_bins,)
        self.rev_hz = float(rev_hz)
        self.physics_dt_s = float(physics_dt_s)
        n, k = config.samples_per_rev, config.sub_rays
        step = 2 * math.pi / n
        # LiDAR-frame angle of each sample, clockwise from the LiDAR's forward (the car's rear).
        self._theta = np.arange(n) * step
        spread = (np.arange(k) - (k - 1) / 2) * (step / k)
        phi = math.pi - (self._theta[:, None] + spread[None, :])  # car frame, counter-clockwise
        self._dirs = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1).reshape(-1, 3)
        # Quanser's read: which of the revolution's samples it keeps (fixed picks by index).
        _, picks = quanser_read(np.degrees(self._theta), np.arange(n, dtype=float), config.read_per_rev)
        self._picks = picks.astype(np.int64)
        bins = config.n_bins
        # What the picked samples returned, in pick order (filled by slices as the rotor turns; laid
        # out over the whole revolution, unread samples as never hit, once a revolution completes).
        self._pick_dirs = self._dirs.reshape(n, k, 3)[self._picks]
        self._dist = np.full((self._picks.size, k), -1.0)
        self._cos_inc = np.ones((self._picks.size, k))
        self._geom = np.full((self._picks.size, k), -1, np.int32)
        # Per-cast scratch, sized for the largest cast (a whole revolution), and where each sample
        # index falls among the picks: a cast is a few dozen rays, so its Python costs as much as they.
        self._pick_at = np.searchsorted(self._picks, np.arange(n + 1)).tolist()
        self._vec = np.empty((self._picks.size * k, 3))
        self._normal = np.empty(self._picks.size * k * 3)
        self._cos = np.empty(self._picks.size * k)
        self._site_id: tuple | None = None
        self._time = np.zeros(n)
        self._material: np.ndarray | None = None  # geom id -> MATERIALS index
        self._model_id = None
        self._done = 0  # samples cast since the episode began (after the first scan)
        self._complete = -1  # the revolution last completed (0: the first scan at reset)
        self._taken = -1
        self._scan_time = 0.0
        self._scan = np.full(bins, np.inf, np.float32)
        self._beam_times = np.zeros(bins)
        self._samples = (np.full(n, np.nan), np.zeros(n))
        self._pending = None

    # -- the env's calls ------------------------------------------------------------------
    def reset(self, rng: np.random.Generator) -> None:
        self._done = 0
        self._complete = self._taken = -1
        self._pending = None

    def begin(self, model, data, t: float) -> None:
        """The episode's first scan: the whole revolution cast at once at ``t`` (there is no past to sweep)."""
        n = self.config.samples_per_rev
        self._cast(model, data, 0, n, t)
        self._finish(0, t)

    def sweep(self, model, data, substep: int) -> None:
        """Casts the samples due by the end of physics step number ``substep`` (since the reset)."""
        n = self.config.samples_per_rev
        t = substep * self.physics_dt_s
        due = int(math.floor(substep * self.physics_dt_s * self.rev_hz * n + 1e-6))
        while self._done < due:
            rev, at = divmod(self._done, n)
            end = min(n, at + due - self._done)
            if self.config.sweep:
                self._cast(model, data, at, end, t)
            self._done += end - at
            if end == n:
                if not self.config.sweep:
                    self._cast(model, data, 0, n, t)
                self._finish(rev + 1, t)

    def has_new_scan(self) -> bool:
        """A revolution completed since the last :meth:`read`."""
        return self._complete > self._taken

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        """The latest complete revolution as the driver delivers it (noise drawn now, once per revolution)."""
        if self.has_new_scan():
            self._deliver(rng)
            self._taken = self._complete
        return self._scan.copy()

    @property
    def scan_time(self) -> float:
        """When the delivered scan's revolution completed, s."""
        return self._scan_time

    @property
    def beam_times(self) -> np.ndarray:
        """(n_bins,) when the rotor pointed at each bin of the delivered scan, s."""
        return self._beam_times.copy()

    @property
    def picked_directions(self) -> np.ndarray:
        """(picks, sub_rays, 3) the rays of the samples Quanser's read keeps, in the LiDAR's frame, in scan order."""
        return self._pick_dirs

    @property
    def samples(self) -> tuple[np.ndarray, np.ndarray]:
        """The delivered revolution before the driver's filter, in scan order: ``(ranges, times)``,
        each (samples_per_rev,) float64; sample i lies i * 360 / samples_per_rev deg clockwise from the
        LiDAR's forward. ``ranges`` is m, 0 = no return, NaN = a sample Quanser's read skips (never
        cast); ``times`` is when each was cast, s. What a recording of the raw scan holds."""
        return self._samples[0].copy(), self._samples[1].copy()

    # -- internals ------------------------------------------------------------------------
    def _materials(self, model) -> None:
        if self._material is None or self._model_id != id(model):
            self._material = np.array([MATERIALS.index(material_of(model.geom(g).name)) for g in range(model.ngeom)]
                                      + [MATERIALS.index("other")], np.int64)  # index -1: no hit
            self._model_id = id(model)

    def _cast(self, model, data, start: int, end: int, t: float) -> None:
        """Casts samples ``start`` to ``end`` (of the revolution) from the LiDAR's pose now, at time ``t``.

        Only the samples Quanser's read keeps are cast: the others never reach the car, and
        their rays are three quarters of the cost.
        """
        self._materials(model)
        self._time[start:end] = t
        a, b = self._pick_at[start], self._pick_at[end]
        if b == a:
            return
        k = self.config.sub_rays
        m = (b - a) * k
        if self._site_id is None or self._site_id[0] != id(model):
            self._site_id = (id(model), model.site(self.site).id)
        sid = self._site_id[1]
        # The results land in the revolution's buffers directly (contiguous row slices).
        vec = np.matmul(self._pick_dirs[a:b].reshape(-1, 3), data.site_xmat[sid].reshape(3, 3).T, out=self._vec[:m])
        normal = self._normal[:3 * m]
        mujoco.mj_multiRay(model, data, data.site_xpos[sid], vec.reshape(-1), VISIBLE_GROUPS, 1, -1,
                           self._geom[a:b].reshape(-1), self._dist[a:b].reshape(-1), normal, m,
                           self.config.range_max_m * 2)
        cos = np.einsum("ij,ij->i", vec, normal.reshape(-1, 3), out=self._cos[:m])
        np.abs(cos, out=self._cos_inc[a:b].reshape(-1))

    def _finish(self, revolution: int, t: float) -> None:
        # Keep what was cast, laid out over the revolution; the next revolution overwrites the buffers.
        n, k = self.config.samples_per_rev, self.config.sub_rays
        dist, geom, cos_inc = np.full((n, k), -1.0), np.full((n, k), -1, np.int32), np.ones((n, k))
        dist[self._picks], geom[self._picks], cos_inc[self._picks] = self._dist, self._geom, self._cos_inc
        self._pending = (dist, geom, cos_inc, self._time.copy(), t)
        self._complete = revolution

    def _deliver(self, rng: np.random.Generator) -> None:
        c = self.config
        dist, geom, cos_inc, times, t_end = self._pending
        n = c.samples_per_rev
        gauss = rng.standard_normal(n)
        uniform = rng.random(n)
        hit = dist >= 0
        with np.errstate(divide="ignore", invalid="ignore"):
            weight = np.where(hit, 1.0 / np.maximum(dist, 1e-6) ** 2, 0.0)
            total = weight.sum(axis=1)
            r = (weight * np.where(hit, dist, 0.0)).sum(axis=1) / total
        any_hit = total > 0
        # The footprint's material and incidence: the centre ray's, else the nearest hit's.
        centre = c.sub_rays // 2
        ref = np.where(hit[:, centre], centre, np.argmin(np.where(hit, dist, np.inf), axis=1))
        rows = np.arange(n)
        material = self._material[geom[rows, ref]]  # a miss (-1) reads the last entry, "other"
        cos_ref = cos_inc[rows, ref]
        incidence = np.degrees(np.arccos(np.clip(cos_ref, 0.0, 1.0)))
        grazing = np.clip((c.grazing_end_deg - incidence) / (c.grazing_end_deg - c.grazing_start_deg), 0.0, 1.0)
        p_return = (1.0 - c.dropouts[material]) * grazing
        r = np.where(any_hit, r * (1.0 + c.noise_rel * gauss), 0.0)
        if c.quantum_m > 0:
            r = np.round(r / c.quantum_m) * c.quantum_m
        valid = any_hit & (uniform < p_return) & (r >= c.range_min_m) & (r <= c.range_max_m)
        raw = np.where(valid, r, 0.0)
        read = np.full(n, np.nan)
        read[self._picks] = raw[self._picks]
        self._samples = (read, times.copy())
        self._scan, self._beam_times = driver_scan(read, times, c.read_per_rev, c.n_bins, c.max_gap_deg)
        self._scan_time = float(t_end)
