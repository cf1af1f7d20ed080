"""The supervisor's results page (``docs/results/supervisor.md``): each following row with a defence
alone and under the supervisor, what the issue asked of it, and the falsification of its guarantee.

Its data: the ``following-supervisor`` stored result (``following_page.summarise`` over the sweep
``following-supervisor.toml``, the defence alone and supervised on the same seeds), and the
``falsify-guarantee`` and ``falsify-guarantee-outside`` stored reports of ``racf falsify`` over the
guarantee's assumptions and beyond them (``experiments/falsify/spaces/guarantee*.toml``).
"""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.pages.following_page import ATTACK_LABELS
from racf.experiments.pages.results_format import meta_lines, missing, page_head, rate, stored
from racf.experiments.pages.sign_rows import sign_rows_markdown

__all__ = ["supervisor_markdown", "SUPERVISOR_COMMAND", "GUARANTEE_RESULTS", "INSIDE", "checks"]

SUPERVISOR_COMMAND = ("racf sweep following-supervisor.toml; python -m racf.experiments.pages.following_page "
                      "outputs/sweeps/following-supervisor")
OTHERS_COMMAND = ("racf sweep following-supervisor-others.toml; python -m racf.experiments.pages.following_page "
                  "outputs/sweeps/following-supervisor-others")
#: The falsifications of the guarantee: (stored result, what it searched, inside the assumptions?, the command).
GUARANTEE_RESULTS = (
    ("falsify-guarantee", "the car ahead, inside the assumptions: every range witness moved by at most the "
     "attacker's 0.05 m (delta 0.17 m = 0.12 m of the witnesses' own + 0.05 m), the lead's whole parameter "
     "space (profile, gap, speed, deceleration up to a_max, brake time, the error's start)", True,
     "racf falsify --defence odca --attack lead_range_error --objective gap --space "
     "experiments/falsify/spaces/guarantee.toml --sampler random tpe --seeds 3 --budget 100 --json"),
    ("falsify-guarantee-sign", "the stop sign, inside the assumptions: the patch hides the sign from the camera "
     "and the depth, on each sign, at any speed, run-up, coverage and duration", True,
     "racf falsify --defence odca --attack patch_occlusion --objective rule --space "
     "experiments/falsify/spaces/guarantee-sign.toml --sampler random tpe --seeds 4 --budget 60 --json"),
    ("falsify-guarantee-outside", "the car ahead, outside them: delta doubled (the attacker's share 0.2 m)", False,
     "racf falsify --defence odca --attack lead_range_error --objective gap --space "
     "experiments/falsify/spaces/guarantee-outside.toml --sampler random --seeds 1 --budget 120 --json"),
)
#: Whether an attack lies inside the guarantee's assumptions (``docs/concepts/guarantee.md``).
INSIDE = {"clean": "—", "clean+lead_patch": "yes", "clean+lead_frustum[depth]": "yes",
          "clean+lead_frustum[adaptive]": "no", "clean+lead_hide": "yes", "clean+lead_phantom": "yes"}
_ORDER = tuple(INSIDE)


def _pair(rows: dict) -> list[tuple[str, str, dict, dict]]:
    """(attack, defence, alone, supervised) for each attack and defence run both ways."""
    out = []
    for key, row in rows.items():
        if row["estimator"].endswith(" + supervisor"):
            continue
        other = rows.get(f"{row['attack']}|{row['estimator']} + supervisor")
        if other is not None:
            out.append((row["attack"], row["estimator"], row, other))
    return sorted(out, key=lambda p: (_ORDER.index(p[0]) if p[0] in _ORDER else len(_ORDER), p[0], p[1]))


def _median(row: dict, name: str) -> str:
    value = row.get(f"{name}_median")
    return "—" if value is None or value["median"] is None else rate(value["median"], value["ci"], 2)


def checks(rows: dict) -> list[str]:
    """What issues 69 and 78 asked of the supervisor over ODCA, each with what was measured."""
    pairs = {(a, d): (alone, sup) for a, d, alone, sup in _pair(rows)}
    lines = []
    for attack, inside in INSIDE.items():
        pair = pairs.get((attack, "odca"))
        if pair is None or inside == "no":  # asked of every attack the issue put inside, as built or not
            continue
        cf = pair[1]["collision_free"]
        verdict = "met" if cf["rate"] is not None and cf["rate"] >= 0.95 else "**not met**"
        lines.append(f"- {ATTACK_LABELS.get(attack, attack)}: collision-free {rate(cf['rate'], cf['ci'])} "
                     f"(N {cf['n']}; asked >= 0.95): {verdict}.")
    for attack in ("clean", "clean+lead_phantom"):
        pair = pairs.get((attack, "odca"))
        if pair is None or "needless_hard_brake" not in pair[1]:
            continue
        nb = pair[1]["needless_hard_brake"]
        verdict = "met" if nb["rate"] is not None and nb["rate"] <= 0.05 else "**not met**"
        lines.append(f"- {ATTACK_LABELS.get(attack, attack)}: needless hard brakes in {rate(nb['rate'], nb['ci'])} "
                     f"of episodes (asked <= 0.05): {verdict}.")
    clean = pairs.get(("clean", "odca"))
    for name, words in (("mean_time_gap_s", "mean time gap"), ("finish_s", "time to finish")):
        if clean is None or f"{name}_median" not in clean[0]:
            continue
        alone, sup = clean[0][f"{name}_median"]["median"], clean[1][f"{name}_median"]["median"]
        change = sup / alone - 1.0
        verdict = "met" if abs(change) <= 0.25 else "**not met**"
        lines.append(f"- clean following's {words}: {sup:.2f} s under the supervisor, {alone:.2f} s alone "
                     f"(medians), {change:+.0%} (asked within 25 %): {verdict}.")
    return lines


def _table(rows: dict) -> list[str]:
    lines = ["| attack | inside the assumptions | defence | N | collision-free [95 % CI] | needless hard brake "
             "[95 % CI] | mean time gap s, median [95 % CI] | time to finish s, median [95 % CI] |",
             "|---|---|---|---|---|---|---|---|"]
    for attack, defence, alone, sup in _pair(rows):
        for label, row in ((defence, alone), (f"{defence} + supervisor", sup)):
            cf, nb = row["collision_free"], row.get("needless_hard_brake")
            lines.append(f"| {ATTACK_LABELS.get(attack, attack)} | {INSIDE.get(attack, '?')} | {label} | {row['n']} | "
                         f"{rate(cf['rate'], cf['ci'])} | {rate(nb['rate'], nb['ci']) if nb else '—'} | "
                         f"{_median(row, 'mean_time_gap_s')} | {_median(row, 'finish_s')} |")
    return lines + [""]


def _falsification(root: Path) -> list[str]:
    lines = ["## The guarantee, falsified", "",
             "`racf falsify` searches for a contact with the car ahead (`--objective gap`: the smallest clear gap; "
             "below zero, contact) and for a run of the stop sign's line (`--objective rule`: the stop rule's "
             "robustness; below zero, run) over the guarantee's assumptions, then beyond them "
             "([the dimensions and bounds](../concepts/guarantee.md#checking-it-falsification)). The episodes inside "
             "the assumptions are the ones the theorem covers; the random sampler's draw the whole parameter space "
             "(not only the shipped sweeps' profiles), a row of their own.", ""]
    inside = violated = 0
    commits: set[str] = set()
    for name, what, covered, command in GUARANTEE_RESULTS:
        path = root / f"{name}.json"
        lines += [f"**{what}**", ""]
        if not path.exists():
            lines += missing(name, command)
            continue
        data = json.loads(path.read_text())
        samplers = data["samplers"]
        found = sum(s["falsified"] for s in samplers.values())
        searches = sum(s["n_seeds"] for s in samplers.values())
        lowest = min((s["lowest_robustness_m"] for s in samplers.values() if s["lowest_robustness_m"] is not None),
                     default=None)
        episodes = data["episodes_evaluated"]
        random = samplers.get("random")
        lines += meta_lines(data["meta"])
        lines += [f"{episodes} episodes in {searches} searches ({', '.join(sorted(samplers))}): {found} of the "
                  f"searches found a violation; the lowest robustness any episode left: "
                  f"{'—' if lowest is None else f'{lowest:+.3f} m'}."
                  + (f" The random sampler alone (the parameter space drawn uniformly): {random['n_seeds']} searches, "
                     f"{random['falsified']} violated, lowest {random['lowest_robustness_m']:+.3f} m."
                     if random and random.get("lowest_robustness_m") is not None else ""), ""]
        if covered:
            inside += episodes
            violated += found
            commits.add(data["meta"].get("measured_on") or data["meta"].get("commit", "?"))
    if inside:
        verdict = "met" if inside >= 1000 and violated == 0 and len(commits) == 1 else "**not met**"
        at = (f"at one commit ({next(iter(commits))})" if len(commits) == 1
              else f"at {len(commits)} commits ({', '.join(sorted(commits))})")
        lines += [f"Inside the assumptions, all told: {inside} episodes {at}, {violated} searches with a violation (a "
                  f"contact, or the stop rule broken: the line run, or no rest within 3 s of the braking window) "
                  f"(asked: at least 1,000 episodes at one commit, none): {verdict}.", ""]
    return lines


SERVED_LIES_COMMAND = "python -m tests.experiments.link.served_lies"


def _served_lies(root: Path) -> list[str]:
    """The served lies at the stop sign (issue 78): stopped in N of N, alone and supervised."""
    lines = ["## A served lie at the stop sign", "",
             "A fake protocol-2 service that keeps the ids and lies in range (the check cannot see it) after its "
             "first 30 honest answers: always 4 m and nothing stands; the truth + 3 m and nothing stands; no "
             "target at all. The car runs its onboard ODCA beside the served answer; a served answer is one more "
             "reading, outvoted where the car's own defence puts the sign nearer or sees it stand.", ""]
    data, opening = stored(root, "served-lies", SERVED_LIES_COMMAND)
    lines += opening
    if data is None:
        return lines
    lines += ["| served lie | supervisor | N | stopped at the sign [95 % CI] | lies answered | steps outvoted | "
              "answers refused | fallback steps |", "|---|---|---|---|---|---|---|---|"]
    for row in data["rows"]:
        lines.append(f"| {row['lie']} | {'yes' if row['supervisor'] else 'no'} | {row['n']} | "
                     f"{row['stopped']} ({rate(row['scr'], row['scr_ci'])}) | {row['lies']} | {row['outvoted_steps']} | "
                     f"{row['invalid']} | {row['fallback_steps']} |")
    stopped, n = sum(r["stopped"] for r in data["rows"]), sum(r["n"] for r in data["rows"])
    verdict = "met" if stopped == n else "**not met**"
    lines += ["", f"Every lie leaves the car stopping: {stopped} of {n} episodes (asked: all): {verdict}.", ""]
    return lines + _link_spoof(data.get("link_spoof"))


def _link_spoof(rows: list[dict] | None) -> list[str]:
    """racf-link's plain-link spoof, alone and supervised (asked: supervised >= 0.95)."""
    lines = ["### racf-link's plain-link spoof", "",
             "A man in the middle answers 5 m for a real ODCA service (`racf serve`) under the strong patch, at the "
             "paper's 20 Hz offboard loop, the car's fallback raw depth (racf-link's row).", ""]
    if not rows:
        return lines + ["Not measured in the stored file.", ""]
    lines += ["| supervisor | N | stopped at the sign [95 % CI] | steps outvoted | answers refused | fallback steps |",
              "|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {'yes' if row['supervisor'] else 'no'} | {row['n']} | "
                     f"{row['stopped']} ({rate(row['scr'], row['scr_ci'])}) | {row['outvoted_steps']} | "
                     f"{row['invalid']} | {row['fallback_steps']} |")
    supervised = [r for r in rows if r["supervisor"]]
    met = bool(supervised) and all(r["scr"] >= 0.95 for r in supervised)
    counts = ", ".join(f"{r['stopped']} of {r['n']}" for r in supervised)
    return lines + ["", f"Supervised, the car stops in {counts} (asked: at least 0.95): {'met' if met else '**not met**'}.",
                    ""]


ROUTE_ERROR_COMMAND = "python -m tests.experiments.car.supervisor.route_error --json route-error.json"


def _route_error(root: Path) -> list[str]:
    """A6 measured: how far the car's own route distance to a line lies from the truth's."""
    lines = ["## A6: the car's route distance to a line", "",
             "The static supervisor's room is the car's own distance along its route to the line (its pose "
             "estimate against the map), less `route_error_m`. Measured each step the car moves on supervised "
             "clean stop-sign approaches (ODCA), four signs at 1, 1.5 and 2 m/s in turn.", ""]
    data, opening = stored(root, "route-error", ROUTE_ERROR_COMMAND)
    lines += opening
    if data is None:
        return lines
    summary = data["summary"]
    lines += ["| sign | N | largest error behind (more room than it has), m | largest error ahead, m | "
              "stopped for the sign |", "|---|---|---|---|---|"]
    for sign in sorted({r["sign"] for r in data["rows"]}):
        rows = [r for r in data["rows"] if r["sign"] == sign]
        lines.append(f"| {sign} | {len(rows)} | {max(r['behind_max_m'] for r in rows):.3f} | "
                     f"{max(r['ahead_max_m'] for r in rows):.3f} | {sum(r['success'] for r in rows)} of {len(rows)} |")
    from racf.experiments.car.supervisor.envelope import Envelope

    budget = Envelope().route_error_m
    verdict = "within it" if summary["behind_max_m"] <= budget else "**past it**"
    return lines + ["", f"At most {summary['behind_max_m']:.3f} m behind over {summary['episodes']} episodes, against "
                        f"the budget of {budget:g} m: {verdict}.", ""]


def supervisor_markdown(root: Path) -> str:
    root = Path(root)
    lines = page_head(
        "The supervisor",
        "Runtime assurance over every target the car publishes a track of (issues 69 and 78; [what it does and what "
        "it guarantees](../concepts/guarantee.md)): each following row of `racf-7` with ODCA alone and under the "
        "supervisor, "
        "on the same episodes (the `lead_vehicle` scenario on sign 1's approach, the lead in each of its four "
        "profiles, the attacks from 2 s for 6 s).")
    path = root / "following-supervisor.json"
    if not path.exists():
        lines += missing("following-supervisor", SUPERVISOR_COMMAND)
    else:
        data = json.loads(path.read_text())
        lines += meta_lines(data["meta"]) + _table(data["rows"])
        lines += ["What issues 69 and 78 asked of the supervisor over ODCA, measured:", "", *checks(data["rows"]), ""]
    lines += ["## Over raw depth and the EKF", "",
              "The supervisor takes any defence: the same rows over raw depth and the EKF, each beside itself alone "
              "on the same episodes (a third of the seeds: N 20 a row).", ""]
    path = root / "following-supervisor-others.json"
    if not path.exists():
        lines += missing("following-supervisor-others", OTHERS_COMMAND)
    else:
        data = json.loads(path.read_text())
        lines += meta_lines(data["meta"]) + _table(data["rows"]) + [""]
    return "\n".join(lines + _falsification(root) + _served_lies(root) + _route_error(root) + sign_rows_markdown(root)
                     + [""])
