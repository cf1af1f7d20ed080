"""The broadcast's results page (``docs/results/broadcast.md``): the car ahead's signed broadcast as a
witness the sensor attacker does not reach, its attacks, and the car's onboard fallback.

Its data:

- ``following-broadcast``: ``following_page.summarise`` over the sweep ``following-broadcast.toml`` (the
  supervisor over ODCA, the lead broadcasting, clean and under the adaptive spoof with the broadcast
  honest, jammed, replayed, forged and lied);
- ``following-broadcast-off``: the same over ``following-broadcast-off.toml`` with ``--by
  scenario_broadcast`` (clean following, ODCA alone and supervised, the lead silent and broadcasting);
- ``following-broadcast-silent``: the same over ``following-broadcast-silent.toml`` (the supervisor over
  ODCA under the adaptive spoof, the lead silent: what the jammed row must give back);
- ``scorecard-racf-link-2`` and ``scorecard-racf-link``: ODCA's cards with and without the onboard fallback;
- ``bench-radio``: ``racf bench radio --json``, the receiver's check per message.
"""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.pages.results_format import meta_lines, missing, page_head, rate

__all__ = ["broadcast_markdown", "checks", "BROADCAST_COMMAND", "OFF_COMMAND", "SILENT_COMMAND", "LINK_COMMAND",
           "BENCH_COMMAND", "PROBES_COMMAND"]

BROADCAST_COMMAND = ("racf sweep following-broadcast.toml; python -m racf.experiments.pages.following_page "
                     "outputs/sweeps/following-broadcast")
OFF_COMMAND = ("racf sweep following-broadcast-off.toml; python -m racf.experiments.pages.following_page "
               "outputs/sweeps/following-broadcast-off --by scenario_broadcast")
SILENT_COMMAND = ("racf sweep following-broadcast-silent.toml; python -m racf.experiments.pages.following_page "
                  "outputs/sweeps/following-broadcast-silent --by scenario_broadcast")
LINK_COMMAND = "racf scorecard --defence odca --battery racf-link-2 --json"
BENCH_COMMAND = "racf bench radio --json"
PROBES_COMMAND = "python -m tests.sim.radio.radio_probes"
#: The adaptive spoof with the broadcast as each row has it.
LABELS = {"clean": "none",
          "clean+lead_frustum[adaptive]": "adaptive spoof; the broadcast honest",
          "clean+lead_frustum+radio_jam[adaptive]": "adaptive spoof; the broadcast jammed",
          "clean+lead_frustum+radio_replay[adaptive]": "adaptive spoof; old messages replayed",
          "clean+lead_frustum+radio_forge[adaptive]": "adaptive spoof; messages forged without the fleet's key",
          "clean+radio_lie": "the lead lies (its own key): away at 0.5 m/s to 2 m, 0.5 m/s faster; sensors honest",
          "clean+lead_frustum+radio_lie[adaptive]": "the lead lies and the adaptive spoof tells the same story"}
_ORDER = tuple(LABELS)
_SUPERVISED = "odca + supervisor"


def _rows(data: dict) -> list[dict]:
    rows = [r for r in data["rows"].values() if r["attack"] in LABELS]
    return sorted(rows, key=lambda r: (_ORDER.index(r["attack"]), r["estimator"], r.get("scenario_broadcast", "")))


def _median(row: dict, name: str) -> str:
    value = row.get(f"{name}_median")
    return "—" if value is None or value["median"] is None else rate(value["median"], value["ci"], 2)


def _table(rows: list[dict], by_broadcast: bool) -> list[str]:
    head = "| attack | defence |" + (" lead broadcasts |" if by_broadcast else "")
    lines = [head + " N | collision-free [95 % CI] | needless hard brake [95 % CI] | mean time gap s, median "
                    "[95 % CI] | forged/replayed refused (episodes) |",
             "|---|---|" + ("---|" if by_broadcast else "") + "---|---|---|---|---|"]
    for r in rows:
        cf, nb, refused = r["collision_free"], r.get("needless_hard_brake"), r.get("foreign_refused")
        label = LABELS[r["attack"]]
        if r.get("scenario_broadcast") == "off":  # the lead silent: no broadcast to be honest or not
            label = label.replace("the broadcast honest", "the lead silent")
        said = (f"{rate(refused['rate'], refused['ci'])} ({r['bc_refused']} of {r['bc_injected']} messages)"
                if refused else "—")
        lines.append(f"| {label} | {r['estimator']} |" + (f" {r['scenario_broadcast']} |" if by_broadcast
                                                                           else "")
                     + f" {r['n']} | {rate(cf['rate'], cf['ci'])} | {rate(nb['rate'], nb['ci']) if nb else '—'} | "
                       f"{_median(r, 'mean_time_gap_s')} | {said} |")
    return lines + [""]


def checks(broadcast: dict | None, off: dict | None, silent: dict | None = None) -> list[str]:
    """What issue 70 asked of the supervisor over ODCA with the broadcast, each with what was measured."""
    lines = []
    rows = {} if broadcast is None else {r["attack"]: r for r in broadcast["rows"].values()
                                         if r["estimator"] == _SUPERVISED}
    honest = rows.get("clean+lead_frustum[adaptive]")
    if honest is not None:
        cf = honest["collision_free"]
        lines.append(f"- The adaptive spoof, the broadcast honest: collision-free {rate(cf['rate'], cf['ci'])} (N {cf['n']}; "
                     f"asked >= 0.95): {'met' if cf['rate'] >= 0.95 else '**not met**'}.")
    jammed = rows.get("clean+lead_frustum+radio_jam[adaptive]")
    today = None if silent is None else next((r for r in silent["rows"].values() if r["estimator"] == _SUPERVISED
                                              and r["attack"] == "clean+lead_frustum[adaptive]"), None)
    if jammed is not None and today is not None:
        a, b = jammed["collision_free"], today["collision_free"]
        overlap = a["ci"][0] <= b["ci"][1] and b["ci"][0] <= a["ci"][1]
        lines.append(f"- The adaptive spoof, the broadcast jammed: collision-free {rate(a['rate'], a['ci'])}, against "
                     f"{rate(b['rate'], b['ci'])} with the lead silent (N {a['n']} and {b['n']}; asked: today's number): "
                     f"{'met (the intervals overlap)' if overlap else '**not met** (the intervals do not overlap)'}.")
    for attack in ("clean+lead_frustum+radio_replay[adaptive]", "clean+lead_frustum+radio_forge[adaptive]"):
        row = rows.get(attack)
        if row is not None and "foreign_refused" in row:
            share = row["foreign_refused"]
            lines.append(f"- {LABELS[attack]}: every forged or replayed message refused in {share['k']} of "
                         f"{share['n']} episodes ({row['bc_refused']} of {row['bc_injected']} messages; asked 100 %): "
                         f"{'met' if share['k'] == share['n'] else '**not met**'}.")
    lie = rows.get("clean+radio_lie")
    if lie is not None:
        cf = lie["collision_free"]
        lines.append(f"- The lying lead alone: collision-free {rate(cf['rate'], cf['ci'])} (N {cf['n']}; asked: no "
                     f"collision): {'met' if cf['k'] == cf['n'] else '**not met**'}.")
    if off is not None:
        pairs = {(r["estimator"], r.get("scenario_broadcast")): r for r in off["rows"].values() if r["attack"] == "clean"}
        on, silent = pairs.get((_SUPERVISED, "on")), pairs.get((_SUPERVISED, "off"))
        for who, row in (("the supervisor over ODCA", on), ("ODCA alone", pairs.get(("odca", "on")))):
            if row is not None and "needless_hard_brake" in row:
                nb = row["needless_hard_brake"]
                lines.append(f"- Clean following with the broadcast, {who}: needless hard brakes in "
                             f"{rate(nb['rate'], nb['ci'])} of episodes (asked <= 0.05): "
                             f"{'met' if nb['rate'] <= 0.05 else '**not met**'}.")
        for label, other in (("the supervisor without it", silent), ("ODCA alone without it", pairs.get(("odca", "off")))):
            if on is None or other is None:
                continue
            a, b = on["mean_time_gap_s_median"]["median"], other["mean_time_gap_s_median"]["median"]
            change = a / b - 1.0
            lines.append(f"- Clean following's mean time gap with the broadcast: {a:.2f} s, against {b:.2f} s for "
                         f"{label} (medians), {change:+.0%} (asked within 10 %): "
                         f"{'met' if abs(change) <= 0.10 else '**not met**'}.")
    return lines


def _fallback(root: Path) -> list[str]:
    lines = ["## The car's onboard fallback", "",
             "Where the served defence gives no answer the car may act on, `racf-link-2`'s car drives on its own "
             "ODCA (from the ONNX export, run every step beside the served one); `racf-link`'s drove on its raw "
             "depth. ODCA served, stop compliance per row:", ""]
    cards = {}
    for name in ("scorecard-racf-link", "scorecard-racf-link-2"):
        path = root / f"{name}.json"
        if path.exists():
            data = json.loads(path.read_text())
            card = next((c for c in data["cards"] if c["defence"] == "odca"), None)
            if card is not None:
                cards[name] = (data["meta"], card)
    if "scorecard-racf-link-2" not in cards:
        return lines + missing("scorecard-racf-link-2", LINK_COMMAND)
    meta, card = cards["scorecard-racf-link-2"]
    old = cards.get("scorecard-racf-link", (None, None))[1]
    lines += meta_lines(meta) + ["| row | N | SCR, raw-depth fallback (racf-link) | SCR, onboard ODCA (racf-link-2) | "
                                 "steps on the fallback, share of episodes |", "|---|---|---|---|---|"]
    for key, row in card["closed_loop"].items():
        before = old["closed_loop"].get(key) if old else None
        fell = next((m for m in row.get("measures", []) if m["measure"].startswith("service_fallback")), None)
        lines.append(f"| {row['title']} | {row['n']} | "
                     f"{rate(before['scr'], before.get('scr_ci')) if before else '—'} | {rate(row['scr'], row.get('scr_ci'))} | "
                     f"{rate(fell['value'], fell['ci']) if fell else '—'} |")
    spoof = card["closed_loop"].get("link_spoof_curve")
    if spoof is not None:
        lines += ["", f"Asked: the CurveZMQ spoof row with the onboard fallback, ODCA >= 0.95 (N 30). Measured "
                      f"{rate(spoof['scr'], spoof.get('scr_ci'))} (N {spoof['n']}): "
                      f"{'met' if spoof['scr'] >= 0.95 else '**not met**'}."]
    return lines + [""]


def _cost(root: Path) -> list[str]:
    lines = ["## What checking a message costs", ""]
    path = root / "bench-radio.json"
    if not path.exists():
        return lines + missing("bench-radio", BENCH_COMMAND)
    data = json.loads(path.read_text())
    r = data["result"] if "result" in data else data
    return lines + meta_lines(data["meta"]) + [
        f"The receiver's whole check of one message (parse, Ed25519 verification, number and age), one core, "
        f"{r['messages']} messages: p50 {r['p50_us']:.0f} us, p99 {r['p99_us']:.0f} us, max {r['max_us']:.0f} us. "
        f"The p99 is {100 * r['p99_share_of_period']:.2f} % of the {r['control_period_ms']:g} ms control period; "
        f"a 10 Hz sender's messages come one every five steps.", ""]


def _probes(root: Path) -> list[str]:
    """The radio's probes of issue 79 in a closed loop: messages an attacker could sign before, and a lock."""
    lines = ["## Keys no one derives, a radio no one locks out", "",
             "Issue 79's probes in a closed loop (the lead broadcasting, cruising): messages signed with the keys the "
             "fleet once derived from public names, and one message numbered 2^32 - 1 (signed with such a key, and "
             "with the lead's own key handed to an insider). On the code before, an independent probe had the car take "
             "80 of 80 messages from a made-up vehicle 5 0.6 m ahead, and a lock refuse the lead's next 46.", ""]
    path = root / "radio-probes.json"
    if not path.exists():
        return lines + missing("radio-probes", PROBES_COMMAND)
    data = json.loads(path.read_text())
    lines += meta_lines(data["meta"]) + ["| probe | episodes | attacker's messages | taken | the lead's own refused |",
                                         "|---|---|---|---|---|"]
    for kind, row in data["probes"].items():
        lines.append(f"| {kind} | {len(row['episodes'])} | {row['injected']} | {row['foreign_accepted']} | "
                     f"{row['genuine_refused']} |")
    return lines + [""]


def broadcast_markdown(root: Path) -> str:
    root = Path(root)
    lines = page_head(
        "The car ahead's broadcast",
        "The car ahead broadcasts its own state, signed ([how, and how the car uses it](../concepts/broadcast.md)); "
        "the supervisor over ODCA follows it on sign 1's approach, the lead in each of its four profiles, the "
        "attacks from 2 s for 6 s. The adaptive spoof moves the depth, the LiDAR's returns and the picture away "
        "together at 0.5 m/s up to 2 m: without the broadcast, [every defence falls to it](following.md).")
    data = {}
    for name, command in (("following-broadcast", BROADCAST_COMMAND), ("following-broadcast-silent", SILENT_COMMAND),
                          ("following-broadcast-off", OFF_COMMAND)):
        path = root / f"{name}.json"
        if not path.exists():
            lines += missing(name, command)
            continue
        data[name] = json.loads(path.read_text())
        lines += meta_lines(data[name]["meta"]) + _table(_rows(data[name]), name != "following-broadcast")
    measured = checks(data.get("following-broadcast"), data.get("following-broadcast-off"),
                      data.get("following-broadcast-silent"))
    if measured:
        lines += ["What issue 70 asked, measured:", "", *measured, "",
                  "With the broadcast jammed, the car has only its sensors again: the row's number is the supervisor's "
                  "without a broadcast, which the adaptive spoof defeats because every sensor witness tells its story. "
                  "The lead that lies together with the spoof is outside what the car can tell: every witness it has, "
                  "the broadcast included, says the same thing.", ""]
    return "\n".join(lines + _fallback(root) + _cost(root) + _probes(root) + [""])
