"""The detector-and-sticker results page (``docs/results/detector-and-sticker.md``), from the stored
detector benchmarks, the sticker's transfer and the loop sweeps with the printed sticker."""

from __future__ import annotations

from racf.experiments.pages.results_format import StoredResults as _Data
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import missing as _missing
from racf.experiments.pages.results_format import num as _num
from racf.experiments.pages.results_format import page_head as _page_head
from racf.experiments.pages.results_format import rate as _rate
from racf.experiments.pages.results_tables import by_estimator_table as _by_estimator_table
from racf.experiments.pages.results_tables import settings_table as _settings_table

__all__ = ["detector_markdown"]


def detector_markdown(d: _Data) -> str:
    lines = [*_page_head("The learned detector and the printed sticker"),
             "The paper detects the sign with YOLOv8-seg and attacks it with a physical patch. racf has a classical "
             "colour-and-shape detector (the default) and a small learned segmenter trained on the simulator's "
             "frames; the sticker is optimised against the segmenter and printed on the sign in the scene "
             "([the tutorial](../tutorials/detector.md)).", "",
             "![Near views, clean and with the sticker printed on the sign](../detector/patched_sign.png)", ""]
    lines += ["## The detectors, on held-out views and approach drives", ""]
    if "bench-detector" in d:
        data = d["bench-detector"]
        lines += _meta(data["meta"]) + [
            "Held-out views: rendered views with ground-truth masks (`racf detector data`); drives: every frame of "
            "the approach drives, recall over the frames with the sign 0.5-2.5 m away.", "",
            "| detector | held-out recall [CI] (N) | held-out false-positive frames [CI] (of N) | drive recall [CI] (N) | "
            "drive false-positive frames [CI] (of N) | ms per frame, one core |", "|---|---|---|---|---|---|"]
        for name, r in data["detectors"].items():
            h = r["heldout"]
            lines.append(f"| {name} | {_rate(h['recall'], h['recall_ci'], 3)} ({h['n_positive']}) | "
                         f"{_rate(h['fp_rate'], h['fp_rate_ci'], 4)} ({h['n_frames']}) | "
                         f"{_rate(r['recall'], r['recall_ci'], 3)} ({r['n_positive']}) | "
                         f"{_rate(r['fp_rate'], r['fp_rate_ci'], 4)} ({r['n_frames']}) | "
                         f"{_num(r['ms_per_frame_one_core'], 2)} |")
        lines.append("")
        lines += _default_verdict(data["detectors"]) + _heldout_breakdown(data["detectors"])
    else:
        lines += _missing("bench-detector", "racf bench detector --json")
    lines += _pose_grid(d)
    lines += ["## The sticker in the scene, per view", ""]
    if "bench-patch" in d:
        data = d["bench-patch"]
        lines += _meta(data["meta"]) + [
            f"The sticker ({data['texture']}, {data['size']:g} of the plate) in rendered views of a stop sign; recall "
            "over the views with the sign resolvable, the same views clean, with the sticker, and with an occluder "
            "of the same area.", "",
            "| detector | recall, clean [CI] | recall, sticker [CI] | recall, occluder [CI] | N |",
            "|---|---|---|---|---|"]
        for name, row in data["counts"].items():
            clean, sticker, occluder = (row.get(k, {}) for k in ("clean", "physical_patch", "patch_occlusion"))
            lines.append(f"| {name} | {_rate(clean.get('recall'), clean.get('recall_ci'), 3)} | "
                         f"{_rate(sticker.get('recall'), sticker.get('recall_ci'), 3)} | "
                         f"{_rate(occluder.get('recall'), occluder.get('recall_ci'), 3)} | {clean.get('n_positive', '-')} |")
        lines.append("")
        bands = sorted({b for row in data["by_band"].values() for r in row.values() for b in r})
        if bands:
            lines += ["By distance (recall, clean -> sticker):", "", "| detector | " + " | ".join(bands) + " |",
                      "|---|" + "---|" * len(bands)]
            for name, row in data["by_band"].items():
                cells = [f"{_num(row['clean'][b]['recall'], 2)} -> {_num(row['physical_patch'][b]['recall'], 2)} "
                         f"(N {row['clean'][b]['n_positive']})" for b in bands]
                lines.append(f"| {name} | " + " | ".join(cells) + " |")
            lines.append("")
    else:
        lines += _missing("bench-patch", "racf bench patch -n 300 --json")
    lines += ["## The sticker in the closed loop", ""]
    if "physical-patch" in d:
        data = d["physical-patch"]
        lines += _settings_table(data) + ["SCR by estimator:", ""] + _by_estimator_table(data)
    else:
        lines += _missing("physical-patch", "racf sweep physical-patch.toml")
    lines += ["## A sticker optimised over the loop", "",
              "Up on the sign from the start, 0.6 of the plate, no defence: the first sticker (optimised over any "
              "view) against the one optimised over the car's own approaches and weighted to the frames where "
              "detection decides the stop (`racf detector optimise-patch --views approach`). With the sticker up from the "
              "start every attack begins before t*.", ""]
    for name, detector in (("sticker-loop", "the default (classical) detector"),
                           ("sticker-loop-learned", "the learned segmenter")):
        lines += [f"### Against {detector}", ""]
        if name not in d:
            lines += _missing(name, f"racf sweep {name}.toml")
            continue
        data = d[name]
        lines += _meta(data["meta"]) + _sticker_rows(data)
    lines += _placement(d)
    return "\n".join(lines)


#: The placement study's stored results: (name, the sticker in words, its bench-patch flags).
_PLACEMENTS = (("sticker-place-centre", "0.6 of the plate, in the middle", "--size 0.6 --position centre"),
               ("sticker-place-top", "0.4 of the plate, at its top edge", "--size 0.4 --position top"))


def _placement(d: _Data) -> list[str]:
    """Where the sticker sits: recall on rendered approach views, then the chosen place in the loop."""
    lines = ["## Where the sticker sits", "",
             "The sticker `learned-approach` at two places, in rendered views on the car's approaches "
             "(`racf bench patch --views approach`). Which place works depends on the detector: the colour "
             "detector tests the red octagon's outline, which a sticker at the plate's edge breaks and one in the "
             "middle leaves whole; the segmenter, against which the texture was optimised in the middle, sees "
             "the whole face and what the sticker leaves of it. Recall [95 % CI] over the views with the sign "
             "resolvable, by its distance:", ""]
    rows = []
    for name, words, flags in _PLACEMENTS:
        if name not in d:
            lines += _missing(name, f"racf bench patch -n 200 --views approach --texture learned-approach {flags} --json")
            continue
        data = d[name]
        bands = sorted({b for row in data["by_band"].values() for r in row.values() for b in r})
        for det, row in data["counts"].items():
            cells = [f"{_num(data['by_band'][det]['physical_patch'][b]['recall'], 2)} "
                     f"(N {data['by_band'][det]['physical_patch'][b]['n_positive']})" for b in bands]
            rows.append(f"| {words} | {det} | {_rate(row['clean']['recall'], row['clean']['recall_ci'])} | "
                        f"{_rate(row['physical_patch']['recall'], row['physical_patch']['recall_ci'])} | "
                        + " | ".join(cells) + " |")
    if rows:
        lines += _meta(d[_PLACEMENTS[-1][0]]["meta"]) + [
            "| sticker | detector | recall, clean | recall, sticker | " + " | ".join(f"sticker, {b}" for b in bands)
            + " |", "|---|---|---|---|" + "---|" * len(bands), *rows, ""]
    lines += ["### The placed sticker in the loop, against the default detector", "",
              "Chosen on the views above, then measured on fresh episodes: up on the sign from the start, no "
              "defence, random draws of the sign and the speed. Every attack begins before t*.", ""]
    if "sticker-placed" not in d:
        return lines + _missing("sticker-placed", "racf sweep sticker-placed.toml")
    return lines + _meta(d["sticker-placed"]["meta"]) + _sticker_rows(d["sticker-placed"])


def _default_verdict(detectors: dict) -> list[str]:
    """Whether the learned segmenter earns the default: it must beat the classical detector on recall
    and on false-positive frames, on the held-out views and on the approach drives."""
    if not {"classical", "learned"} <= set(detectors):
        return []
    c, l = detectors["classical"], detectors["learned"]
    checks = {"held-out recall": (l["heldout"]["recall"], c["heldout"]["recall"], True),
              "held-out false-positive frames": (l["heldout"]["fp_rate"], c["heldout"]["fp_rate"], False),
              "drive recall": (l["recall"], c["recall"], True),
              "drive false-positive frames": (l["fp_rate"], c["fp_rate"], False)}
    lost = [name for name, (learned, classical, higher) in checks.items()
            if (learned <= classical if higher else learned >= classical)]
    if not lost:
        return ["The learned segmenter beats the classical detector on all four counts.", ""]
    return ["The learned segmenter becomes the default detector only when it beats the classical one on recall "
            "and on false-positive frames, on the held-out views and on the drives. Here it does not on: "
            + ", ".join(lost) + "; the classical detector stays the default.", ""]


def _heldout_breakdown(detectors: dict) -> list[str]:
    """Held-out recall per kind of view and per distance band, and the red-square negatives (stored
    by ``racf bench detector`` since the size witness's issue; older results have neither)."""
    first = next(iter(detectors.values()))
    if "by_kind" not in first["heldout"]:
        return []
    columns = [*first["heldout"]["by_kind"], *first["heldout"]["by_band"]]
    lines = ["Held-out recall by kind of view (`sign`: anywhere around a sign, 0.3-6 m; `approach`: on the "
             "car's lane towards it) and by the sign's distance, [95 % CI] (N):", "",
             "| detector | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns)]
    for name, r in detectors.items():
        cells = {**r["heldout"]["by_kind"], **r["heldout"]["by_band"]}
        lines.append(f"| {name} | " + " | ".join(
            f"{_rate(cells[c]['recall'], cells[c]['recall_ci'], 3)} ({cells[c]['n_positive']})"
            if cells[c]["recall"] is not None else "-" for c in columns) + " |")
    lines += ["", "False-positive frames with plain red squares (14-48 px) pasted into held-out views with no stop "
              "sign: red alone is not a stop sign.", "", "| detector | false-positive frames [95 % CI] (of N) |",
              "|---|---|"]
    for name, r in detectors.items():
        q = r["red_squares"]
        lines.append(f"| {name} | {_rate(q['fp_rate'], q['fp_rate_ci'], 4)} ({q['n_frames']}) |")
    return lines + [""]


def _sticker_rows(data: dict) -> list[str]:
    """Per sticker: SCR and the detector's recall by the sign's distance (a sweep's stealth and recall rows)."""
    recall = {r["params"]: r["bands"] for r in data.get("recall", [])}
    bands = list(next(iter(recall.values()))) if recall else []
    lines = ["| sticker | N | SCR [95 % CI] | " + " | ".join(f"recall {b} [CI] (frames)" for b in bands) + " |",
             "|---|---|---|" + "---|" * len(bands)]
    for row in data.get("stealth", []):
        sticker = dict(p.split("=", 1) for p in row["params"].split() if p.startswith("physical_patch."))
        texture = f"`{sticker.get('physical_patch.texture', row['params'])}`"
        if "physical_patch.size" in sticker or "physical_patch.position" in sticker:
            texture += f", {sticker.get('physical_patch.size', '')} at {sticker.get('physical_patch.position', 'centre')}"
        cells = [f"{_rate(c['recall'], c['recall_ci'])} ({c['n']})" if c["n"] else "-"
                 for c in (recall.get(row["params"], {}).get(b, {"n": 0}) for b in bands)]
        lines.append(f"| {texture} | {row['n']} | {_rate(row['scr'], row['scr_ci'])} | " + " | ".join(cells) + " |")
    return lines + [""]


def _pose_grid(d: _Data) -> list[str]:
    """The detectors' recall over the pose grid (``racf bench poses``): a table per detector, a row per lean
    and a column per turn, each cell pooled over the approach distances and the four signs."""
    lines = ["## The detectors over the poses real signs stand in", ""]
    if "bench-poses" not in d:
        return lines + _missing("bench-poses", "racf bench poses --json")
    data = d["bench-poses"]
    names = [k for k, v in data.items() if isinstance(v, dict) and "by_pose" in v]
    turns = sorted({float(k.split(",")[0]) for n in names for k in data[n]["by_pose"]})
    leans = sorted({float(k.split(",")[1]) for n in names for k in data[n]["by_pose"]})
    lines += _meta(data["meta"]) + [
        f"Real signs stand turned on their poles and leaned back. Recall over the grid ({data['grid']}; "
        f"{data['n_views']} views, of which those with the sign resolvable count: N per cell), each cell pooled over "
        "the distances and the signs; the camera on the lane's centre line, the room's light as built.", ""]
    for name in names:
        overall = data[name]["overall"]
        lines += [f"**{name}**: {_rate(overall['recall'], overall['ci'], 2)} over all {overall['n']} resolvable views.", "",
                  "| lean \\ turn | " + " | ".join(f"{t:g} deg" for t in turns) + " |",
                  "|---|" + "---|" * len(turns)]
        for lean in leans:
            cells = [data[name]["by_pose"].get(f"{t:g},{lean:g}") for t in turns]
            lines.append(f"| {lean:g} deg | " + " | ".join(
                "-" if c is None or c["recall"] is None else f"{_rate(c['recall'], c['ci'], 2)} ({c['n']})"
                for c in cells) + " |")
        lines.append("")
    worst = {n: min((c["recall"], k) for k, c in data[n]["by_pose"].items() if c["recall"] is not None) for n in names}
    lines += ["Where each falls shortest: " + "; ".join(f"`{n}` {r:.2f} at turn {k.split(',')[0]} deg, lean "
                                                     f"{k.split(',')[1]} deg" for n, (r, k) in worst.items()) + ".", ""]
    return lines
