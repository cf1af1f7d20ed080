"""Counterexamples that stay: a violation saved as a replayable episode spec, and its replay.

A case file (JSON) holds the episode's full ``TrialSpec``, the robustness and failure it gave,
the code it ran on (``code_version`` of the episode's packages) and what found it. Replaying
runs the same episode in this process, pinned to one thread as the search's workers are: on
the same code the robustness comes back to the bit. With another defence (``defence=``) the
same scenario and attack meet that defence instead, which is how the suite in
``experiments/falsify/cases/`` says which of the known failures an improved defence survives.
:func:`reseed_case` runs a case's parameters under other noise seeds: whether the failure belongs
to the parameters a search controls, or to one draw of the noise.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from racf.experiments.episode.spec import EPISODE_CODE, TrialSpec, setting_name
from racf.provenance import atomic_write, code_version

__all__ = ["Case", "save_case", "load_case", "replay_case", "reseed_case", "Replay", "SUITE", "distinct",
           "spec_from_json"]

#: The shipped regression suite.
SUITE = Path(__file__).with_name("cases")
_VERSION = 1


def spec_from_json(raw: dict) -> TrialSpec:
    """A ``TrialSpec`` from its ``asdict`` form (:meth:`TrialSpec.from_dict`)."""
    return TrialSpec.from_dict(raw)


@dataclass(frozen=True)
class Case:
    """One stored counterexample."""

    spec: TrialSpec
    robustness_m: float
    failure: str | None
    code: str
    found_by: dict
    name: str

    def to_json(self) -> dict:
        return {"version": _VERSION, "name": self.name, "setting": self.spec.setting, "trial_id": self.spec.trial_id,
                "robustness_m": self.robustness_m, "failure": self.failure, "code": self.code,
                "found_by": self.found_by, "spec": asdict(self.spec)}


def save_case(folder: str | Path, spec: TrialSpec, row: dict, found_by: dict) -> Path:
    """Writes the case of one violating episode (its result ``row``) into ``folder``; returns the file."""
    value = float(row["robustness_m"])
    name = f"{spec.estimator}-sign{spec.sign}-{row.get('failure') or 'violation'}-{spec.trial_id.rsplit('_', 1)[-1]}"
    case = Case(spec, value, row.get("failure"), code_version(*EPISODE_CODE), found_by, name)
    Path(folder).mkdir(parents=True, exist_ok=True)
    return atomic_write(Path(folder) / f"{name}.json", json.dumps(case.to_json(), indent=1, allow_nan=False))


def load_case(path: str | Path) -> Case:
    """Reads a case file; ValueError names what is wrong with it."""
    path = Path(path)
    try:
        raw = json.loads(path.read_text())
        if raw.get("version") != _VERSION:
            raise ValueError(f"case format {raw.get('version')!r}, this racf reads {_VERSION}")
        spec = spec_from_json(raw["spec"])
        return Case(spec, float(raw["robustness_m"]), raw.get("failure"), str(raw["code"]), dict(raw.get("found_by", {})),
                    str(raw.get("name", path.stem)))
    except OSError as err:
        raise ValueError(f"cannot read the case {path}: {err.strerror or err}") from None
    except (json.JSONDecodeError, KeyError, TypeError) as err:
        raise ValueError(f"{path} is not a racf case file ({type(err).__name__}: {err})") from None


@dataclass(frozen=True)
class Replay:
    """A case run again.

    Attributes:
        case: the case.
        spec: the episode that ran (the case's, or its scenario and attacks against ``defence``).
        robustness_m: what it gave now.
        same_code: whether this is the code the case was found on (and the same defence).
        identical: on the same code, whether the robustness came back to the bit (None otherwise).
        survived: whether the stop rule held this time (robustness >= 0).
    """

    case: Case
    spec: TrialSpec
    robustness_m: float
    same_code: bool
    identical: bool | None
    survived: bool
    failure: str | None


def _against(spec: TrialSpec, defence: str | None) -> TrialSpec:
    """The spec's scenario and attacks against ``defence`` (the spec itself when None or its own)."""
    if defence is None or defence == spec.estimator:
        return spec
    return replace(spec, setting=setting_name(spec.attacks, defence), estimator_options={})


def replay_case(case: Case, defence: str | None = None, rerun: str | Path | None = None) -> Replay:
    """Runs ``case`` again (against ``defence`` instead of its own, if given); with ``rerun``,
    records it to that ``.rrd`` file."""
    from racf.experiments.sweeps.executors import single_thread
    from racf.experiments.episode.rerun_log import recorded_trial

    single_thread()  # as the search's workers ran it: the same arithmetic, to the bit
    spec = _against(case.spec, defence)
    result, _ = recorded_trial(spec, rerun, f"racf case {case.name}", clean_pass=rerun is not None)
    value = result.robustness_m
    same = spec == case.spec and code_version(*EPISODE_CODE) == case.code
    identical = (value == case.robustness_m) if same else None
    return Replay(case, spec, value, same, identical, bool(math.isfinite(value) and value >= 0), result.failure)


#: The other noise seeds of :func:`reseed_case`: ``case seed + RESEED_STRIDE * k`` for k = 1..n. A prime
#: stride past any budget, so none is another trial's of the same search (search seed x 100000 + trial).
RESEED_STRIDE = 1_000_003


def reseed_case(case: Case, n: int, defence: str | None = None) -> list[float]:
    """The case's scenario and attack settings under ``n`` other noise seeds (the sensors' noise, the
    detector's draws: everything the episode seed decides): each episode's robustness, m. A
    failure that the parameters make recurs under most seeds; one that only its draw made
    recurs rarely, and no search over the parameters can aim at it."""
    from racf.experiments.episode import run_trial
    from racf.experiments.sweeps.executors import single_thread

    if not (isinstance(n, int) and 1 <= n <= 1000):
        raise ValueError(f"the number of other seeds must be an integer in [1, 1000], got {n!r}")
    single_thread()
    spec = _against(case.spec, defence)
    values = []
    for k in range(1, n + 1):
        result, _ = run_trial(replace(spec, seed=spec.seed + RESEED_STRIDE * k))
        values.append(float(result.robustness_m))
    return values


def distinct(rows: list[dict]) -> list[dict]:
    """The distinct failures among violating episodes' rows: one per (setting, sign, failure),
    the lowest robustness of each."""
    best: dict[tuple, dict] = {}
    for row in rows:
        key = (row["setting"], row["sign"], row.get("failure"))
        if key not in best or row["robustness_m"] < best[key]["robustness_m"]:
            best[key] = row
    return [best[k] for k in sorted(best, key=str)]
