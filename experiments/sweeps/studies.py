"""``racf attack-study``: what the patch attack does with no defence (the paper's Table 3 / Fig. 5).

Three studies, each a batch of closed-loop trials over the four signs and three speeds:

- persistence: rho = 1.0, T_atk in {0.5, 1.0, 3.0} s -> lost-detection frames and ASR;
- coverage: rho in {0.3, 0.6, 0.9, 1.0} with T_atk = 3.0 s (the longest, so coverage alone
  decides) -> ASR;
- strong: rho ~ U(0.9, 1.0), T_atk ~ U(0.5, 3.0) s -> SCR, ASR and latency, over at least
  ``STRONG_MIN_N`` trials (the protocol's N for the strong regime).

Lost-detection frames count the 50 Hz control steps during the attack window in which the
sign was in the camera's view but not detected (the paper counts camera frames at its
lower frame rate). Every trial is stored and reused, as with ``racf trials``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from racf.experiments.episode import STRONG_RHO, STRONG_T_ATK_S
from racf.experiments.sweeps.batches import batch_specs, run_batch
from racf.experiments.sweeps.executors import backend_session
from racf.experiments.sweeps.summary import summarize

__all__ = ["StudyRow", "STUDIES", "STRONG_MIN_N", "run_study"]

#: The fewest trials of the strong-regime row.
STRONG_MIN_N = 30


@dataclass(frozen=True)
class StudyRow:
    label: str
    rho: tuple[float, float]
    t_atk: tuple[float, float]


STUDIES: dict[str, tuple[StudyRow, ...]] = {
    "persistence": tuple(StudyRow(f"T_atk = {t} s", (1.0, 1.0), (t, t)) for t in (0.5, 1.0, 3.0)),
    "coverage": tuple(StudyRow(f"rho = {r}", (r, r), (3.0, 3.0)) for r in (0.3, 0.6, 0.9, 1.0)),
    "strong": (StudyRow("rho ~ U(0.9, 1.0), T_atk ~ U(0.5, 3.0) s", STRONG_RHO, STRONG_T_ATK_S),),
}


def run_study(name: str, n: int, out_dir: Path, seed: int = 0, workers: int = 2, progress: bool = True,
              backend: str = "local", address: str | None = None, sensor_profile: str = "qcar2",
              sign_geometry: str = "plate") -> list[dict]:
    """Runs one study, ``n`` trials a row (``max(n, STRONG_MIN_N)`` for the strong row), on
    ``sensor_profile``'s sensors and ``sign_geometry``'s signs; returns a summary dict per row
    (``label`` added)."""
    if name not in STUDIES:
        raise ValueError(f"study must be one of {sorted(STUDIES)}, got {name!r}")
    n = max(n, STRONG_MIN_N) if name == "strong" else n
    rows = []
    with backend_session(backend, workers, address):
        for row in STUDIES[name]:
            specs = batch_specs("attack", n, seed, rho=row.rho, t_atk=row.t_atk, sensor_profile=sensor_profile,
                                sign_geometry=sign_geometry)
            folder = Path(out_dir) / name / (f"rho{row.rho[0]:.2f}-{row.rho[1]:.2f}"
                                             f"_t{row.t_atk[0]:.2f}-{row.t_atk[1]:.2f}")
            results = run_batch(specs, folder, workers=workers, progress=progress, backend=backend, address=address,
                                desc=f"{name}: {row.label}")
            rows.append({"label": row.label, **summarize(results, attack=True)})
    return rows
