"""What the QCar 2's software gets from its RPLIDAR A2M12: Quanser's read, then its 1-degree filter.

The A2M12 at 10 Hz sends about 1600 (angle, range) samples a revolution, range 0 meaning no
return. Quanser's ``QCarLidar`` reads 384 of them and ``filter_rplidar_data`` resamples them
onto a fixed grid of 360 one-degree bins: it drops the no-returns, interpolates linearly
between the valid samples around each bin, and zero-fills a bin whose two valid neighbours
are more than 1.1 deg apart. The interpolation makes "mixed" ranges between a near object
and the background behind it; that is kept on purpose, because the real driver does it.

Not wired into the env yet (the sensors issue does that, with sensor profiles). One finding
for that work: 384 picks spread evenly over 1600 samples (0.225 deg apart) are 4 or 5 samples
apart, so 64 of the 384 gaps are 1.125 deg, just over the 1.1 deg rule, and a clean wall loses
80 of its 360 bins. Either the real read is not an even pick, or the real scan has such holes;
the tests pin the behaviour as modelled.

Units: angles are in degrees, as the driver's own are (in whatever sense the caller's angles
turn; nothing here depends on it); ranges are metres. Pure numpy: no simulator imports, so
the module can be checked on its own and fed from any ray caster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DriverConfig", "quanser_read", "filter_rplidar_data", "deliver"]

#: Angular slack, degrees, under which a sample counts as lying exactly on a bin (float
#: rounding from wrapping, not a physical width).
_ON_BIN_TOL_DEG = 1e-9


def _check_int(name: str, value: object, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
    if not lo <= value <= hi:
        raise ValueError(f"{name} must be in [{lo}, {hi}], got {value}")
    return int(value)


def _check_max_gap(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"max_gap_deg must be a number in (0, 360) degrees, got {value!r}")
    if not 0.0 < float(value) < 360.0:
        raise ValueError(f"max_gap_deg must be in (0, 360) degrees, got {value}")
    return float(value)


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
        max_gap_deg: degrees; bins inside a wider gap between valid samples read 0. In
            (0, 360): a gap of the whole circle (one lone sample) is never bridged.
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


def _wrap_deg(x: np.ndarray) -> np.ndarray:
    """Angles into [0, 360): np.mod can round a tiny negative up to 360.0 itself."""
    w = np.mod(x, 360.0)
    w[w >= 360.0] = 0.0
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
    angles_deg: np.ndarray, ranges_m: np.ndarray, n_bins: int = 360, max_gap_deg: float = 1.1
) -> np.ndarray:
    """(n_bins,) float ranges on the fixed grid (bin j at j * 360 / n_bins deg); 0 = no return.

    Angles are degrees in any order and are wrapped into [0, 360); the grid wraps round, so
    a gap across 359 -> 0 deg is a gap like any other. A range that is 0, negative, NaN or
    infinite, or has a non-finite angle, is no return (so the simulator's ``inf`` can be fed
    in as it is). Each bin then reads:

    - the range of a valid sample lying on it (several at one angle, e.g. 0 and 360: the
      first in the order given, as the real driver's de-duplication keeps);
    - else 0 if its two valid neighbours (the nearest below and above it, round the circle)
      are more than ``max_gap_deg`` apart, the driver's "missed measurements" rule;
    - else the linear interpolation between them, which may mix a near object with the
      background behind it.

    No valid sample gives all zeros. One valid sample fills only the bin it lies on: with no
    second sample there is no pair to interpolate between, and the gap round it is the whole
    circle, so the rule zero-fills every other bin rather than inventing a beam width.
    """
    n_bins = _check_int("n_bins", n_bins, 1, 36_000)
    max_gap = _check_max_gap(max_gap_deg)
    angles, ranges = _as_scan(angles_deg, ranges_m)
    out = np.zeros(n_bins)

    with np.errstate(invalid="ignore"):
        valid = np.isfinite(angles) & np.isfinite(ranges) & (ranges > 0.0)
    if not valid.any():
        return out
    a = _wrap_deg(angles[valid])
    r = ranges[valid]
    # Sort by angle; at a repeated angle keep the first in the order given (stable sort).
    order = np.argsort(a, kind="stable")
    a, r = a[order], r[order]
    first = np.r_[True, np.diff(a) > 0.0]
    a, r = a[first], r[first]
    m = a.size

    bins = np.arange(n_bins) * (360.0 / n_bins)
    above = np.searchsorted(a, bins, side="right")  # samples at or below each bin
    prev = (above - 1) % m
    nxt = above % m
    d_prev = _wrap_deg(bins - a[prev])  # degrees back to the neighbour below
    d_next = _wrap_deg(a[nxt] - bins)  # degrees on to the neighbour above
    gap = d_prev + d_next
    on_prev = d_prev <= _ON_BIN_TOL_DEG
    on_next = ~on_prev & (d_next <= _ON_BIN_TOL_DEG)
    between = ~on_prev & ~on_next & (gap <= max_gap)

    out[on_prev] = r[prev[on_prev]]
    out[on_next] = r[nxt[on_next]]
    r0, r1 = r[prev[between]], r[nxt[between]]
    t = d_prev[between] / gap[between]
    # Clip so float rounding never takes a mixed range outside its two neighbours.
    out[between] = np.clip(r0 + (r1 - r0) * t, np.minimum(r0, r1), np.maximum(r0, r1))
    return out


def deliver(angles_deg: np.ndarray, ranges_m: np.ndarray, config: DriverConfig | None = None) -> np.ndarray:
    """quanser_read then filter_rplidar_data: the (n_bins,) scan the car's software gets.

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
