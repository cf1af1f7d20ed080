"""The results pages, written from stored results so that no number on them is typed by hand.

``docs/results/data/*.json`` holds what the commands printed, each with its ``meta`` (command,
commit, racf version, date, machine, sensor profile; ``racf.experiments.pages.results_store``
writes them), and :data:`RESULT_PAGES` lays each page out. The docs build writes the pages; a
test checks that the committed pages are the ones the data gives. The only numbers not from a
stored result are the paper's own, quoted with the table they come from.

To add a measurement: run its command with ``--json`` (or a sweep), store it with
``python -m racf.experiments.pages.results_store NAME SOURCE --command "..."``, and rebuild the docs.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from racf.experiments.pages.falsify_page import falsification_markdown
from racf.experiments.pages.existence_page import existence_markdown
from racf.experiments.pages.leaderboard_page import leaderboard_markdown
from racf.experiments.pages.following_page import following_markdown
from racf.experiments.pages.supervisor_page import supervisor_markdown
from racf.experiments.pages.broadcast_page import broadcast_markdown
from racf.experiments.pages.traffic_page import crossed_key, traffic_markdown
from racf.experiments.pages.detector_page import detector_markdown
from racf.experiments.pages.speed_page import speed_markdown
from racf.experiments.pages.results_format import StoredResults as _Data
from racf.experiments.pages.results_tables import by_estimator_table as _by_estimator_table
from racf.experiments.pages.results_tables import split_estimator as _split_estimator
from racf.experiments.pages.results_tables import settings_table as _settings_table
from racf.experiments.pages.results_format import page_head as _page_head
from racf.experiments.pages.results_format import ci as _ci
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import missing as _missing
from racf.experiments.pages.results_format import num as _num
from racf.experiments.pages.results_format import rate as _rate

__all__ = ["RESULT_PAGES", "PAPER", "paper_rows", "readme_table"]

_METHODS = ("raw", "lidar", "ekf", "chi2", "cusum", "chronos", "softs", "nhits", "dlinear", "nlinear", "odca")

#: The paper's numbers (racf-paper.tex: the real-car table, Table "attack persistence" and
#: Table "recovery", strong preset), quoted beside racf's measurements.
PAPER = {"clean_scr": 1.00, "clean_dt_brake": 0.1647, "attack_scr": 0.17, "odca_scr": 0.80, "odca_dt_brake": 0.19,
         "persistence_asr": {"0.5": 0.50, "1.0": 0.90, "3.0": 1.00}, "strong_rmse_odca": 0.323,
         "strong_rmse_chronos": 0.503, "strong_rmse_lidar": 0.600, "head_parameters": 921}

# --- tables ----------------------------------------------------------------------------------------------------

def _stealth_table(rows: list[dict]) -> list[str]:
    lines = ["| attack | settings | estimator | N | SCR [95% CI] | undetected error m, median [CI] | max | "
             "flagged [CI] | detection delay s, median |", "|---|---|---|---|---|---|---|---|---|"]
    for st in rows:
        lines.append(f"| `{st['attack']}` | {st['params'] or '-'} | {st['estimator']} | {st['n']} | "
                     f"{_rate(st['scr'], st['scr_ci'])} | {_rate(st.get('undetected_error_median'), st.get('undetected_error_ci'), 3)} | "
                     f"{_num(st.get('undetected_error_max'))} | {_rate(st.get('detected_share'), st.get('detected_share_ci'))} | "
                     f"{_num(st.get('detection_delay_median'))} |")
    return lines + [""]


def _bench_table(data: dict) -> list[str]:
    results = data["results"]
    presets = ("weak", "mid", "strong")
    lines = _meta(data["meta"]) + [
        "RMSE in metres against the clean depth, the mean over the corruption draws, with its 95 % interval "
        "(test drives and draws resampled together); N is the number of scored steps per draw.", ""]
    for split, per_preset in results.items():
        lines += [f"**{split.replace('_', ' ')}**", "", "| method | " + " | ".join(presets) + " | N (strong) |",
                  "|---|" + "---|" * len(presets) + "---|"]
        methods = [m for m in _METHODS if m in per_preset["strong"]] + sorted(set(per_preset["strong"]) - set(_METHODS))
        for m in methods:
            cells = [f"{per_preset[p][m]['rmse']:.3f} {_ci(per_preset[p][m]['rmse_ci'], 3)}" for p in presets]
            lines.append(f"| {m} | " + " | ".join(cells) + f" | {per_preset['strong'][m]['n']} |")
        lines.append("")
    return lines + _pass_through(data.get("clean") or {})


def _pass_through(clean: dict) -> list[str]:
    """ODCA's clean pass-through per split (Proposition 1: clean depth comes out unchanged)."""
    rows = [(split, row) for split, row in clean.items() if isinstance(row, dict) and "unchanged_share" in row]
    if not rows:
        return []
    cells = "; ".join(f"{split.replace('_', ' ')} {100 * row['unchanged_share']:.2f} % of {row['n_depth']:,} steps"
                      for split, row in rows)
    return [f"**Clean pass-through** (ODCA fed the clean test drives; the share of steps with a depth that come out "
            f"unchanged): {cells}.", ""]


# --- pages -----------------------------------------------------------------------------------------------------

def _closed_loop(d: _Data) -> str:
    lines = [*_page_head("ODCA in the closed loop: the paper's table"),
             "`racf trials --table`: the paper's settings, N = 30 each over the four signs and three speeds, the "
             "strong patch regime (rho ~ U(0.9, 1), T_atk ~ U(0.5, 3) s), the same episodes in every setting. "
             "Only an attack that begins before t* (the first braking command of the clean run) can test a "
             "defence: its column is the one to read. [The protocol](../protocol.md) defines every measure.", ""]
    for name, title, command in (
            ("closed-loop-table", "On the QCar 2's sensors (`qcar2`, the default)", "racf trials --table --json"),
            ("closed-loop-table-ideal", "On ideal sensors (an ablation)",
             "racf trials --table --sensor-profile ideal --json"),
            ("closed-loop-table-pole", "With pole-only signs (the LiDAR's plane misses the plate)",
             "racf trials --table --sign-geometry pole --json")):
        lines += [f"## {title}", ""] + (_settings_table(d[name]) if name in d else _missing(name, command))
    return "\n".join(lines)


_SWEEPS = {"strong-1000": "1,000 strong-regime episodes: 250 random draws, every estimator on each",
           "spoof-1000": "The same with the LiDAR spoofed too (patch + lidar_spoof)",
           "attack-types": "Every attack type alone and two combined"}


def _sweeps(d: _Data) -> str:
    lines = [*_page_head("Monte Carlo attack sweeps"),
             "`racf sweep SPEC` runs a shipped spec (`experiments/sweeps/specs/`) on a local pool or Ray and "
             "resumes when interrupted; [the sweeps tutorial](../tutorials/sweeps.md) shows how. Each draw runs "
             "with every estimator on the same episode (paired seeds).", ""]
    for name, title in _SWEEPS.items():
        lines += [f"## {title}", ""]
        if name not in d:
            lines += _missing(name, f"racf sweep {name}.toml")
            continue
        data = d[name]
        lines += _settings_table(data)
        if len({_split_estimator(k)[0] for k in data["settings"]}) > 1:
            lines += ["SCR by attack and estimator:", ""] + _by_estimator_table(data)
    return "\n".join(lines)


def _offline(d: _Data) -> str:
    lines = [*_page_head("The offline repair benchmark"),
             "`racf bench offline` scores every registered estimator step by step, beside the forecasting baselines "
             "(Chronos-2 forecast-only, SOFTS, NHITS, DLinear, NLinear) and the aligned LiDAR, on the test drives "
             "of two splits under the weak, mid and strong corruption presets. Each preset is drawn several times; "
             "[the protocol](../protocol.md) fixes the presets and the scoring.", ""]
    lines += ["## The QCar 2's sensors (`qcar2`)", ""]
    lines += _bench_table(d["offline-bench"]) if "offline-bench" in d else _missing("offline-bench", "racf bench offline --json")
    lines += ["## Ideal sensors (`ideal`: a one-instant 360-beam LiDAR, a 50 Hz camera, the true pose)", ""]
    lines += _bench_table(d["offline-bench-ideal"]) if "offline-bench-ideal" in d else _missing(
        "offline-bench-ideal", "racf collect --sensor-profile ideal --out data/ideal && racf bench offline --dataset data/ideal "
                               "--no-ablation --json")
    return "\n".join(lines)


def _adaptive(d: _Data) -> str:
    lines = [*_page_head("Adaptive attacks: an attacker who knows the defence"),
             "`racf sweep adaptive.toml`: four adaptive attacks at their strongest settings (the two ramps over "
             "their rate r), each over three durations at the four signs, two seeds per cell, every estimator on "
             "the same episode. The undetected error is the largest |d_fused - d_true| before the defence's first "
             "flag ([the protocol](../protocol.md#5-adaptive-attacks-and-stealth)); raw depth has no detector, so "
             "its error is the attack's whole effect.", ""]
    if "adaptive" not in d:
        return "\n".join(lines + _missing("adaptive", "racf sweep adaptive.toml"))
    data = d["adaptive"]
    lines += ["## Stop compliance per attack and estimator", ""] + _meta(data["meta"]) + _by_estimator_table(data)
    if data.get("stealth"):
        lines += ["## Stealth, per attack setting", ""] + _stealth_table(data["stealth"])
    figures = [f for f in ("undetected_vs_rate.png", "undetected_vs_t_atk.png")
               if (d.root.parent.parent / "adaptive" / f).exists()]
    if figures:
        lines += ["| " + " | ".join(f"![](../adaptive/{f})" for f in figures) + " |",
                  "|" + "---|" * len(figures), ""]
    lines += ["## A blackout from first sight, and the size witness", "",
              "`dropout_timed` (black box) blacks out the sign's depth once the LiDAR has no return from the sign. "
              "At sign 1 the A2M12's plane misses the plate on almost every approach, so no range witness is left; "
              "the box's size still is ([ODCA](../concepts/odca.md)). 200 random draws over the four signs and "
              "1-2 m/s.", ""]
    if "dropout-200" in d:
        data = d["dropout-200"]
        lines += _meta(data["meta"]) + _stealth_table(data.get("stealth", []))
    else:
        lines += _missing("dropout-200", "racf sweep dropout-200.toml")
    return "\n".join(lines)


def paper_rows(d: _Data, link: str = "") -> list[str]:
    """The paper's claims beside racf's measurements, as a Markdown table; ``link`` prefixes the
    links to the results pages (the README sits elsewhere than the pages)."""
    lines = ["| claim | paper (QCar 2) | racf | details |", "|---|---|---|---|"]
    if "closed-loop-table" in d:
        s = d["closed-loop-table"]["settings"]
        clean, attack, odca = s["clean"], s["attack"], s["attack+odca"]
        lines += [
            f"| clean: SCR, dt_brake s | {PAPER['clean_scr']:.2f}, {PAPER['clean_dt_brake']:.3f} | "
            f"{_rate(clean['scr'], clean['scr_ci'])}, {_num(clean['dt_brake_mean'])} (N {clean['n']}) | "
            f"[closed loop]({link}closed-loop.md) |",
            f"| patch attack, no defence: SCR | {PAPER['attack_scr']:.2f} | {_rate(attack['scr'], attack['scr_ci'])} "
            f"overall; {_rate(attack['scr_attack_before_t_star'], attack['scr_attack_before_t_star_ci'])} attacked "
            f"before t* (N {attack['n_attack_before_t_star']}) | [closed loop]({link}closed-loop.md) |",
            f"| attack + ODCA: SCR, dt_brake s | {PAPER['odca_scr']:.2f}, {PAPER['odca_dt_brake']:.3f} | "
            f"{_rate(odca['scr'], odca['scr_ci'])}, {_num(odca['dt_brake_mean'])} (N {odca['n']}) | "
            f"[closed loop]({link}closed-loop.md) |"]
    if "strong-1000" in d:
        s = d["strong-1000"]["settings"]
        cells = ", ".join(f"{name} {_rate(s[key]['scr'], s[key]['scr_ci'])}" for name, key in
                          (("ODCA", "attack+odca"), ("EKF", "attack+ekf"), ("Chronos-only", "attack+chronos"),
                           ("none", "attack")) if key in s)
        lines.append(f"| SCR over {s['attack']['n']} random strong draws | - | {cells} | [sweeps]({link}sweeps.md) |")
    if "dropout-200" in d:
        by = {r["estimator"]: r for r in d["dropout-200"].get("stealth", [])}
        cells = ", ".join(f"{name} {_rate(by[key]['scr'], by[key]['scr_ci'])}" for name, key in
                          (("ODCA", "odca"), ("EKF", "ekf"), ("none", "raw")) if key in by)
        n = next(iter(by.values()))["n"] if by else 0
        lines.append(f"| depth blacked out while the LiDAR misses the sign (`dropout_timed`), SCR over {n} draws | - | "
                     f"{cells} | [adaptive attacks]({link}adaptive-attacks.md) |")
    if "sticker-placed" in d:
        rows = d["sticker-placed"].get("stealth", [])
        if rows:
            r = rows[0]
            lines.append(f"| a printed sticker (0.4 of the plate, at its top edge), no defence: SCR | "
                         f"{PAPER['attack_scr']:.2f} (the paper's patch) | {_rate(r['scr'], r['scr_ci'])} (N {r['n']}, every "
                         f"attack before t*) | [the sticker]({link}detector-and-sticker.md) |")
    if "scorecard-racf-5" in d:
        cards = {c["defence"]: c["closed_loop"] for c in d["scorecard-racf-5"]["cards"]}
        vote, odca = cards.get("vote", {}).get("mapped_sticker"), cards.get("odca", {}).get("mapped_sticker")
        if vote and odca:
            lines.append(f"| the 0.6 sticker up from the start on mapped signs: SCR | - | existence vote "
                         f"{_rate(vote['scr'], vote['scr_ci'])}, ODCA alone {_rate(odca['scr'], odca['scr_ci'])} "
                         f"(N {vote['n']}) | [existence]({link}existence.md) |")
    if "cross-traffic" in d:
        s = d["cross-traffic"]["settings"]
        none, odca = s.get(crossed_key("attack")), s.get(crossed_key("attack+odca"))
        if none and odca and none.get("n_traffic_attack_before_t_star"):
            lines.append(
                f"| with cross-traffic at the conflict point, patch attack: collision rate | - (the paper's scenario; "
                f"not measured there) | none {_rate(none['collision_rate_attack_before_t_star'], none['collision_rate_attack_before_t_star_ci'])} "
                f"attacked before t* (N {none['n_traffic_attack_before_t_star']}), ODCA "
                f"{_rate(odca['collision_rate'], odca['collision_rate_ci'])} (N {odca['n_traffic']}) | "
                f"[cross-traffic]({link}traffic.md) |")
    if "following" in d:
        rows = d["following"]["rows"]
        none, odca = rows.get("clean+lead_patch|raw"), rows.get("clean+lead_patch|odca")
        if none and odca:
            lines.append(f"| following a car ahead, its depth read 1 m far: collision-free | - (not in the paper) | "
                         f"none {_rate(none['collision_free']['rate'], none['collision_free']['ci'])}, ODCA "
                         f"{_rate(odca['collision_free']['rate'], odca['collision_free']['ci'])} (N {odca['n']}) | "
                         f"[following]({link}following.md) |")
    if "persistence" in d:
        rows = d["persistence"]["persistence"]
        ours = " / ".join(f"{r['asr']:.2f} {_ci(r['asr_ci'])}" for r in rows)
        lines.append(f"| attack persistence 0.5 / 1 / 3 s: ASR | "
                     f"{' / '.join(f'{v:.2f}' for v in PAPER['persistence_asr'].values())} | {ours} "
                     f"(N {rows[0]['n']} each) | [paper]({link}paper.md) |")
    if "offline-bench" in d:
        for split, per in d["offline-bench"]["results"].items():
            strong = per["strong"]
            lines.append(f"| offline strong RMSE m, ODCA / Chronos-only / LiDAR ({split.replace('_', ' ')}) | "
                         f"{PAPER['strong_rmse_odca']:.3f} / {PAPER['strong_rmse_chronos']:.3f} / "
                         f"{PAPER['strong_rmse_lidar']:.3f} | {strong['odca']['rmse']:.3f} / "
                         f"{strong['chronos']['rmse']:.3f} / {strong['lidar']['rmse']:.3f} | "
                         f"[offline benchmark]({link}offline-benchmark.md) |")
    return lines


def _paper(d: _Data) -> str:
    lines = [*_page_head("Reproduced from the paper"),
             "The paper's numbers are from its real-car table, its attack-persistence table and its recovery table "
             "(strong preset). Here the car is simulated on the `qcar2` sensor profile.", ""]
    lines += paper_rows(d) + [""]
    if "persistence" in d:
        lines += ["## Attack persistence (no defence)", ""] + _meta(d["persistence"]["meta"]) + [
            "| T_atk s | N | ASR [95% CI] | lost frames, mean | paper ASR |", "|---|---|---|---|---|"]
        for r, paper in zip(d["persistence"]["persistence"], PAPER["persistence_asr"].values()):
            lines.append(f"| {r['label']} | {r['n']} | {_rate(r['asr'], r['asr_ci'])} | {r['lost_frames_mean']:.1f} | "
                         f"{paper:.2f} |")
        lines.append("")
    lines += ["What differs from the paper's set-up (see [what is modelled](../concepts/what-is-modelled.md)): "
              "the temporal prior is racf's own small Chronos-2-architecture checkpoint pretrained on synthetic "
              "series, because the Hugging Face hub cannot be reached at run time; the car, its sensors and the "
              "map are simulated; the default detector is classical (colour and shape), with a learned segmenter "
              "beside it; the offline data are simulated drives.", ""]
    return "\n".join(lines)


def readme_table(root: Path) -> str:
    """The README's headline table: :func:`paper_rows` with links into ``docs/results/``."""
    return "\n".join(paper_rows(_Data(root), link="docs/results/"))


def _index(d: _Data) -> str:
    lines = [*_page_head("Results"),
             "| page | what |", "|---|---|",
             "| [Leaderboard](leaderboard.md) | the built-in defences' scorecards, one table per battery |",
             "| [Reproduced from the paper](paper.md) | the paper's claims beside racf's measurements |",
             "| [Closed loop](closed-loop.md) | the paper's table on three sensor set-ups |",
             "| [Sweeps](sweeps.md) | 1,000-episode random sweeps and every attack type |",
             "| [Offline benchmark](offline-benchmark.md) | repair RMSE against forecasting baselines |",
             "| [Adaptive attacks](adaptive-attacks.md) | white- and black-box attacks that know the defence |",
             "| [Detector and sticker](detector-and-sticker.md) | the learned segmenter and the printed sticker |",
             "| [Falsification](falsification.md) | searched worst cases per defence, and the regression suite |",
             "| [Cross-traffic](traffic.md) | the paper's settings with another car at the conflict point |",
             "| [Following](following.md) | a car ahead that brakes, and the attacks on its distance |",
             "| [Existence](existence.md) | whether a sign stands: the vote against stickers, phantoms and stale maps |",
             "| [Speed](speed.md) | the simulator, whole episodes, ODCA's per-step cost, ROS 2 bags and the defence "
             "service |", "",
             "## Every stored result", "",
             "| result | command | commit | measured | machine |", "|---|---|---|---|---|"]
    for path in sorted(d.root.glob("*.json")):
        meta = json.loads(path.read_text())["meta"]
        lines.append(f"| `{path.stem}` | `{meta['command']}` | `{meta['commit']}` | {meta['measured']} | "
                     f"{meta['machine']} |")
    return "\n".join(lines + [""])


#: The generated results pages (relative to ``docs/``) and the function that writes each from the data folder.
RESULT_PAGES: dict[str, Callable[[Path], str]] = {
    f"results/{name}.md": (lambda make: lambda root: make(_Data(root)))(make)
    for name, make in (("index", _index), ("leaderboard", leaderboard_markdown), ("paper", _paper), ("closed-loop", _closed_loop), ("sweeps", _sweeps),
                       ("offline-benchmark", _offline), ("adaptive-attacks", _adaptive),
                       ("detector-and-sticker", detector_markdown), ("speed", speed_markdown))}
RESULT_PAGES["results/falsification.md"] = falsification_markdown
RESULT_PAGES["results/traffic.md"] = traffic_markdown
RESULT_PAGES["results/following.md"] = following_markdown
RESULT_PAGES["results/supervisor.md"] = supervisor_markdown
RESULT_PAGES["results/broadcast.md"] = broadcast_markdown
RESULT_PAGES["results/existence.md"] = existence_markdown
