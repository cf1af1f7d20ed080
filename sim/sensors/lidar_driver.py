"""What the QCar 2's software gets from its RPLIDAR A2M12: Quanser's read, then its 1-degree filter.

The A2M12 at 10 Hz sends about 1600 (angle, range) samples a revolution, range 0 meaning no
return. Quanser's ``QCarLidar`` reads 384 of them and ``filter_rplidar_data`` resamples them
onto a fixed grid of 360 one-degree bins. Its steps, as the real code (Quanser's ``pal``
``QCarLidar.filter_rplidar_data``) does them, with angles counted in bins:

1. drop the no-returns and repeated angles, sort, and interpolate every bin linearly between
   the valid samples, round the circle (``np.interp`` with a period);
2. for each pair of consecutive valid samples a < b more than 1.1 bins apart, zero the bins
   ``ceil(a) <= k < floor(b)``: a half-open slice, so a bin lying on a is zeroed but bin
   ``floor(b)`` keeps its interpolated range when b is not whole. Put otherwise, a bin in a
   too-wide gap reads 0 only if the next valid sample is at least one bin above it;
3. zero the bins below ``round(first sample)`` and above ``round(last sample)`` (numpy's round,
   half to even): the gap from the last sample round to the first is never bridged, however
   narrow, but the one or two bins between a sample and its rounding keep the interpolation
   across it. ``filter_rplidar_data(..., wrap=True)`` instead treats that gap as one like any
   other (step 2 round the circle).

The interpolation makes "mixed" ranges between a near object and the background behind it;
that is kept on purpose, because the real driver does it.

Finding: 384 picks spread evenly over 1600 samples (0.225 deg apart) are 4 or 5 samples
apart, so 64 of the 384 gaps are 1.125 deg, just over the 1.1 deg rule. Under the half-open
slice such a gap zeroes a bin only where it holds two consecutive whole degrees k, k + 1
(its start a at most 0.125 deg below a whole degree, or on one), so a clean full-circle
scan (every sample valid, one range) loses 16 of its 360 bins through :func:`deliver` with
the default config: bins 14, 30, 59, 75, ... (14 and 30, then every 45 deg).

One difference is not modelled: the real code interpolates at ``np.linspace(0, 2 pi, 360)``
(bins 360/359 deg apart, the last on 360 = 0 deg) while it zeroes by whole-degree index;
here bin j is at j * 360 / n_bins deg for both.

Units: angles are in degrees, as the driver's own are (in whatever sense the caller's angles
turn; nothing here depends on it); ranges are metres. Pure numpy: no simulator imports, so
the module can be checked on its own and fed from any ray caster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DriverConfig", "deliver", "filter_rplidar_data", "quanser_read"]

#: Slack, in bins, under which a sample is put exactly on a whole bin (float rounding from
#: scaling and wrapping, e.g. 40 * 0.225 deg; not a physical width). The half-open slice turns
#: on whole bins, so 9 - 2e-15 and 9 must not differ.
_ON_BIN_TOL = 1e-9


def _check_int(name: str, value: object, lo: int, hi: int) -> int:
    """value as an int; ValueError (not TypeError, for callers' sake) unless an integer in [lo, hi]."""
    is_int = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if not (is_int and lo <= value <= hi):
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
    return int(value)


def _check_max_gap(value: object) -> float:
    """value as a float; ValueError unless a number in (0, 360) (NaN is not)."""
    is_num = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not (is_num and 0.0 < float(value) < 360.0):
        raise ValueError(f"max_gap_deg must be a number in (0, 360) degrees, got {value!r}")
    return float(value)


def _check_bool(name: str, value: object) -> bool:
    """value as a bool; ValueError unless a bool (or numpy bool): 0 and 1 are not."""
    if type(value) not in (bool, np.bool_):
        raise ValueError(f"{name} must be a bool, got {value!r}")
    return bool(value)


@dataclass(frozen=True)
class DriverConfig:
    """The read and filter settings; defaults are the A2M12 at 10 Hz and Quanser's driver.

    Attributes:
        samples_per_rev: samples the scanner sends a revolution, in [1, 100000] and at least
            ``read_per_rev`` (the A2M12 at 10 Hz: 1600).
        read_per_rev: measurements the driver reads a revolution, in [1, samples_per_rev]
            (Quanser's ``QCarLidar``: 384).
        n_bins: bins of the output grid, in [1, 36000]; bin j is at j * 360 / n_bins deg
            (360: one degree).
        max_gap_deg: degrees, in (0, 360); a wider gap between consecutive valid samples
            zeroes its bins that lie at least one bin below its far end (Quanser's half-open
            slice, see :func:`filter_rplidar_data`).
    """

    samples_per_rev: int = 1600
    read_per_rev: int = 384
    n_bins: int = 360
    max_gap_deg: float = 1.1

    def __post_init__(self) -> None:
        _check_int("samples_per_rev", self.samples_per_rev, 1, 100_000)
        _check_int("read_per_rev", self.read_per_rev, 1, self.samples_per_rev)
        _check_int("n_bins", self.n_bins, 1, 36_000)
        _check_max_gap(self.max_gap_deg)

    @property
    def sample_angles_deg(self) -> np.ndarray:
        """(samples_per_rev,) angles of one evenly sampled revolution, degrees from 0."""
        return np.arange(self.samples_per_rev) * (360.0 / self.samples_per_rev)


def _as_scan(angles_deg: np.ndarray, ranges_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both inputs as 1-D float arrays of one length (ValueError otherwise)."""
    angles = np.asarray(angles_deg, dtype=float)
    ranges = np.asarray(ranges_m, dtype=float)
    if angles.ndim != 1 or ranges.ndim != 1:
        raise ValueError(f"angles_deg and ranges_m must be 1-D, got shapes {angles.shape} and {ranges.shape}")
    if angles.size != ranges.size:
        raise ValueError(f"angles_deg has {angles.size} samples but ranges_m has {ranges.size}")
    return angles, ranges


def _wrap(x: np.ndarray, period: float) -> np.ndarray:
    """Values into [0, period): np.mod can round a tiny negative up to period itself."""
    w = np.mod(x, period)
    w[w >= period] = 0.0
    return w


def quanser_read(
    angles_deg: np.ndarray, ranges_m: np.ndarray, read_per_rev: int = 384
) -> tuple[np.ndarray, np.ndarray]:
    """The measurements the driver reads from one revolution, in scan order.

    Evenly spread picks by index: ``round(k * n / read_per_rev)`` for k = 0 .. read_per_rev-1,
    with n the number of samples given and round half to even (Python's ``round``). Needs
    ``n >= read_per_rev`` so that no sample is read twice. No-returns are kept: dropping
    them is the filter's job. Returns copies (angles in degrees, ranges in metres).
    """
    angles, ranges = _as_scan(angles_deg, ranges_m)
    n = angles.size
    read_per_rev = _check_int("read_per_rev", read_per_rev, 1, 100_000)
    if n < read_per_rev:
        raise ValueError(f"read_per_rev must be in [1, {n}] (the samples given), got {read_per_rev}")
    # Integer arithmetic so that ties (k * n / read_per_rev = x.5) round exactly, to even.
    q, rem = np.divmod(np.arange(read_per_rev, dtype=np.int64) * n, read_per_rev)
    idx = q + ((2 * rem > read_per_rev) | ((2 * rem == read_per_rev) & (q % 2 == 1)))
    return angles[idx].copy(), ranges[idx].copy()


def filter_rplidar_data(
    angles_deg: np.ndarray,
    ranges_m: np.ndarray,
    n_bins: int = 360,
    max_gap_deg: float = 1.1,
    wrap: bool = False,
) -> np.ndarray:
    """(n_bins,) float ranges on the fixed grid (bin j at j * 360 / n_bins deg); 0 = no return.

    Angles are degrees in any order and are wrapped into [0, 360). A range that is 0,
    negative, NaN or infinite, or has a non-finite angle, is no return (so the simulator's
    ``inf`` can be fed in as it is). Of several valid samples at one angle (e.g. 0 and 360)
    the first in the order given is kept, as the real driver's ``np.unique`` keeps.

    With the valid samples sorted, each bin k has a neighbour a at or below it and b above it
    (round the circle: past the last sample, b is the first; below the first, a is the last).
    The bin reads the linear interpolation between them (a's range if it lies on a; it may mix
    a near object with the background behind it), except that it reads 0 when:

    - b - a is more than ``max_gap_deg`` and b is at least one bin above k: the driver's
      "missed measurements" rule, a half-open slice ``ceil(a) <= k < floor(b)``. A bin lying
      on a sample is zeroed if the gap after it is too wide; one less than a bin below the
      next sample never is;
    - ``wrap=False`` (the default, Quanser's code): k is below ``round(first)`` or above
      ``round(last)`` (first and last valid sample, in bins; round half to even). The gap
      from the last sample round 360 -> 0 deg to the first is not tested for width: the bins
      beyond the rounded ends read 0 however narrow it is, the (at most two) bins between an
      end sample and its rounding keep the interpolation across it however wide;
    - ``wrap=True`` (a circular driver, not Quanser's): that gap is a gap like any other,
      zeroed by the same test and half-open slice.

    No valid sample gives all zeros. One valid sample: with ``wrap=False`` only the bin at its
    rounded angle reads its range (the rounded ends coincide); with ``wrap=True`` the gap round
    it is the whole circle, too wide, so only a bin less than one bin below it keeps the range
    (none when it lies on a bin).
    """
    n_bins = _check_int("n_bins", n_bins, 1, 36_000)
    max_gap = _check_max_gap(max_gap_deg)
    wrap = _check_bool("wrap", wrap)
    angles, ranges = _as_scan(angles_deg, ranges_m)
    out = np.zeros(n_bins)

    with np.errstate(invalid="ignore"):
        valid = np.isfinite(angles) & np.isfinite(ranges) & (ranges > 0.0)
    if not valid.any():
        return out
    # Everything below is in bins: bin k sits at k, the circle is n_bins long.
    u = _wrap(angles[valid] * (n_bins / 360.0), float(n_bins))
    whole = np.round(u)
    u = np.where(np.abs(u - whole) <= _ON_BIN_TOL, whole, u)
    u[u >= n_bins] = 0.0  # snapped up onto n_bins: that is bin 0
    r = ranges[valid]
    # Sort by angle; at a repeated angle keep the first in the order given (stable sort).
    order = np.argsort(u, kind="stable")
    u, r = u[order], r[order]
    first = np.r_[True, np.diff(u) > 0.0]
    u, r = u[first], r[first]
    m = u.size

    k = np.arange(n_bins, dtype=float)
    above = np.searchsorted(u, k, side="right")  # samples at or below each bin
    prev = (above - 1) % m
    nxt = above % m
    # Gap i runs from sample i to the next; the last one round the circle to the first.
    gaps = np.append(np.diff(u), n_bins - (u[-1] - u[0]))
    gap = gaps[prev]
    d_prev = np.where(above == 0, k + n_bins, k) - u[prev]  # bins back to a, unwrapped
    r0, r1 = r[prev], r[nxt]
    # Clip so float rounding never takes a mixed range outside its two neighbours.
    out = np.clip(r0 + (r1 - r0) * (d_prev / gap), np.minimum(r0, r1), np.maximum(r0, r1))

    # The half-open slice: zero k while floor(b) > k, b unwrapped past the last sample.
    floor_b = np.floor(u[nxt]) + np.where(above == m, n_bins, 0)
    zero = (gap > max_gap * (n_bins / 360.0)) & (k < floor_b)
    if not wrap:
        across = (above == 0) | (above == m)  # in the gap from the last sample to the first
        zero = (zero & ~across) | (k < np.round(u[0])) | (k > np.round(u[-1]))
    out[zero] = 0.0
    return out


def deliver(angles_deg: np.ndarray, ranges_m: np.ndarray, config: DriverConfig | None = None) -> np.ndarray:
    """quanser_read then filter_rplidar_data: the (n_bins,) scan the car's software gets.

    The filter runs as Quanser's does (``wrap=False``): no bridging from the last valid pick
    round 360 -> 0 deg to the first.

    Takes one full revolution of ``config.samples_per_rev`` samples (angles in degrees,
    ranges in metres, no return = 0, NaN, negative or inf); a different count raises
    ValueError, since the even picks assume a whole revolution of the stated size.
    """
    cfg = DriverConfig() if config is None else config
    angles, ranges = _as_scan(angles_deg, ranges_m)
    if angles.size != cfg.samples_per_rev:
        raise ValueError(f"deliver needs one revolution of samples_per_rev={cfg.samples_per_rev} samples, "
                         f"got {angles.size}")
    read_a, read_r = quanser_read(angles, ranges, cfg.read_per_rev)
    return filter_rplidar_data(read_a, read_r, cfg.n_bins, cfg.max_gap_deg)
