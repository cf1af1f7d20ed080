"""The speed results page (``docs/results/speed.md``), from the stored timings: the simulator, whole
episodes, the speed guard, the paired timing, ODCA's per-step cost, ROS 2 bags and the service."""

from __future__ import annotations

from racf.experiments.pages.results_format import StoredResults as _Data
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import missing as _missing
from racf.experiments.pages.results_format import num as _num
from racf.experiments.pages.results_format import page_head as _page_head
from racf.experiments.pages.service_page import bags_and_service_markdown

__all__ = ["speed_markdown"]


def speed_markdown(d: _Data) -> str:
    lines = [*_page_head("Speed"),
             "The real-time factor is simulated seconds per wall-clock second at the 50 Hz control rate. This "
             "machine's speed drifts by 10-20 % from minute to minute: compare two versions in one run, in "
             "alternation, not across pages.", ""]
    lines += ["## The simulator alone (`racf bench sim`)", ""]
    if "bench-sim" in d:
        data = d["bench-sim"]
        lines += _meta(data["meta"]) + ["| setting | steps/s | real-time factor |", "|---|---|---|"]
        lines += [f"| {k} | {v['steps_per_s']:.1f} | {v['real_time_factor']:.2f} |" for k, v in data["settings"].items()
                  if isinstance(v, dict)]
        over = data["settings"].get("full_over_floor_320x240")
        if over is not None:
            lines += ["", f"The floor is MuJoCo's bare physics, one render and readback a camera frame and the A2M12's "
                      f"rays, each timed alone: what a step at 320 x 240 cannot cost less than without changing what it "
                      f"computes. The full sensor set takes {over:.2f} x the floor's time a step."]
        lines.append("")
    else:
        lines += _missing("bench-sim", "racf bench sim --json")
    lines += ["## Whole episodes, as a sweep runs them (`racf bench loop`)", ""]
    lines += _measures(d, "bench-loop", "loop", "racf bench loop --json", digits=2)
    lines += ["## ODCA's per-step cost (`racf bench odca-latency`)", ""]
    lines += _measures(d, "odca-latency", "latency", "racf bench odca-latency --json", digits=3)
    lines += _guard(d)
    lines += _paired(d)
    lines += bags_and_service_markdown(d)
    return "\n".join(lines)


def _guard(d: _Data) -> list[str]:
    """The speed guard's ratio per commit (``racf bench guard --store``; ``make check-speed``)."""
    lines = ["## The speed guard (`make check-speed`)", "",
             "The closed loop's step (attack + ODCA, one core) over MuJoCo's bare physics step, timed in "
             "alternating rounds in one run, so that the machine's drift moves both. `make check-speed` fails "
             "when a change makes it more than 15 % worse than the newest commit's.", ""]
    if "speed-guard" not in d:
        return lines + _missing("speed-guard", "racf bench guard --store")
    lines += ["| commit | measured | machine | ratio (median of rounds) | rounds | loop step ms | physics step ms | "
              "loop real-time factor |", "|---|---|---|---|---|---|---|---|"]
    for e in d["speed-guard"]["history"]:
        lines.append(f"| `{e['commit']}` | {e['measured']} | {e['machine']} | {e['ratio']:.2f} | "
                     f"{', '.join(f'{r:.2f}' for r in e['ratios'])} | {sorted(e['loop_step_ms'])[len(e['loop_step_ms']) // 2]:.2f} | "
                     f"{sorted(e['physics_step_ms'])[len(e['physics_step_ms']) // 2]:.3f} | {e['rtf_loop']:.2f} |")
    return lines + [""]


def _paired(d: _Data) -> list[str]:
    """The last speed change, old and new timed in alternation (``racf bench paired``)."""
    lines = ["## Old against new, in alternation (`racf bench paired`)", "",
             "The same episodes in a warm worker of each checkout, both on one core, old and new in turn; each "
             "round's ratio is new / old (below 1: faster).", ""]
    if "speed-paired" not in d:
        return lines + _missing("speed-paired", "racf bench paired --baseline DIR --json")
    data = d["speed-paired"]
    r = data["paired"]
    lines += _meta(data["meta"]) + ["| round | old ms a step | new ms a step | new / old |", "|---|---|---|---|"]
    lines += [f"| {i + 1} | {o:.3f} | {n:.3f} | {n / o:.3f} |" for i, (o, n) in enumerate(zip(r["old_ms"], r["new_ms"]))]
    against = f" against `{data['meta']['baseline']}`" if "baseline" in data["meta"] else ""
    lines += ["", f"{r['setting']}, {r['episodes']} episodes a round in each{against}: new / old {r['ratio']:.3f} (median of "
              f"{len(r['ratios'])} rounds, {min(r['ratios']):.3f}-{max(r['ratios']):.3f}); real-time factor "
              f"{r['old_rtf']:.2f} -> {r['new_rtf']:.2f}.", ""]
    return lines


def _measures(d: _Data, name: str, key: str, command: str, digits: int) -> list[str]:
    """A stored result's flat ``{measure: value}`` (under ``key``) as a two-column table."""
    if name not in d:
        return _missing(name, command)
    data = d[name]
    return _meta(data["meta"]) + ["| measure | value |", "|---|---|"] + [
        f"| {k.replace('_', ' ')} | {_num(v, digits) if isinstance(v, float) else v} |"
        for k, v in data[key].items()] + [""]
