"""An attack's card: the attack against every registered defence on the same random draws
(paired seeds), on the ``qcar2`` sensors: per defence the SCR over all draws and over the
attacks that began before t*, and the undetected error (``scoring.stealth``)."""

from __future__ import annotations

from pathlib import Path

from racf.experiments.sweeps.spec import SweepSpec
from racf.experiments.sweeps.store import ResultStore
from racf.experiments.sweeps.summary import stealth_summary, summarize

__all__ = ["ATTACK_DRAWS", "run_attack_card", "attack_card_markdown"]

#: Random draws per defence: full and quick.
ATTACK_DRAWS = (60, 4)


def run_attack_card(attack: str, out: Path, *, quick: bool = False, backend: str = "local", workers: int = 2,
                    address: str | None = None, progress: bool = True) -> dict:
    from racf.experiments.sweeps.run import run_episodes
    from racf.plugins import ESTIMATORS

    defences = list(ESTIMATORS)
    spec = SweepSpec(f"attack-{attack}", mode="random", n=ATTACK_DRAWS[1] if quick else ATTACK_DRAWS[0], seed=0,
                     space={"attack": [attack], "estimator": defences, "rho": [0.9, 1.0], "t_atk": [0.5, 3.0],
                            "speed": [1.0, 2.0], "sign": [0, 1, 2, 3]})
    frame, _ = run_episodes(spec.episodes(), ResultStore(Path(out) / "episodes" / f"attack-{attack}"), backend,
                            workers, address, progress=progress, desc=f"attack {attack}")
    rows = {}
    for defence in defences:
        part = frame[frame["estimator"] == defence]
        s = summarize(part, attack=True)
        rows[defence] = {k: s.get(k) for k in ("n", "scr", "scr_ci", "n_attack_before_t_star",
                                                "scr_attack_before_t_star", "scr_attack_before_t_star_ci")}
        rows[defence].update(stealth_summary(part))
    return {"attack": attack, "quick": quick, "draws": spec.n, "sensor_profile": "qcar2", "defences": rows}


def attack_card_markdown(card: dict) -> str:
    def f(x, ci=None):
        return "-" if x is None else f"{x:.2f}" + ("" if not ci or ci[0] is None else f" [{ci[0]:.2f}, {ci[1]:.2f}]")

    lines = [f"# `{card['attack']}` against every defence" + (" (QUICK: small N)" if card["quick"] else ""), "",
             f"{card['draws']} random draws (rho, T_atk, speed, sign), each run with every defence; "
             f"`{card['sensor_profile']}` sensors. Lower SCR: a stronger attack.", "",
             "| defence | N | SCR [95% CI] | SCR, attack before t* (N) | undetected error m, median [CI] |",
             "|---|---|---|---|---|"]
    for name, r in card["defences"].items():
        lines.append(f"| {name} | {r['n']} | {f(r['scr'], r['scr_ci'])} | "
                     f"{f(r['scr_attack_before_t_star'], r['scr_attack_before_t_star_ci'])} "
                     f"({r['n_attack_before_t_star']}) | "
                     f"{f(r.get('undetected_error_median'), r.get('undetected_error_ci'))} |")
    return "\n".join(lines) + "\n"
