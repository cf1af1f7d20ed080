"""The offline benchmark's ablation (``racf bench offline --ablation``): the head's loss terms and the
gate's kinematic witness taken out one at a time, each retrained and scored on the strong preset."""

from __future__ import annotations

from dataclasses import asdict, replace
from typing import Callable

from racf.experiments.offline.methods import split_arrays, with_fallback
from racf.experiments.offline.scoring import diagnostic_scores, mean_over_draws, recovery_scores

__all__ = ["ABLATION", "run_ablation"]


def _ablation_rows() -> dict[str, dict]:
    from racf.odca.losses import LossWeights

    full = LossWeights()
    off = {"minimal_change": 0.0, "consistency": 0.0, "kinematics": 0.0}
    weights = {
        "L_ID": asdict(replace(full, **off)),
        "L_ID + L_Delta0": asdict(replace(full, consistency=0.0, kinematics=0.0)),
        "L_ID + L_Delta0 + L_cons": asdict(replace(full, kinematics=0.0)),
        "L_ID + L_Delta0 + L_kin": asdict(replace(full, consistency=0.0)),
        "full": asdict(full),
    }
    rows = {name: {"loss_weights": w, "kinematics": {}} for name, w in weights.items()}
    # The parts of the gate: the kinematic witness out of the vote (the paper's two-witness
    # gate, kinematics only bases repairs), and no kinematic branch at all.
    rows["full, two-witness gate"] = {"loss_weights": asdict(full), "kinematics": {"witness": False}}
    rows["full, no kinematics"] = {"loss_weights": asdict(full), "kinematics": {"enabled": False}}
    return rows


#: The ablation rows under the strong preset: name -> the head's loss weights and the kinematic
#: branch's settings (``KinematicsConfig`` fields changed from the default).
ABLATION = _ablation_rows()


def run_ablation(ds, draws: int, full_scores: dict, full_report: dict, stage, bar,
                 train: Callable[[dict, dict], tuple]) -> list[dict]:
    """Each row retrains the head (and recalibrates the gate) with ``train(loss_weights, kinematics)``;
    scored on the strong preset's test series over ``draws`` draws (the mean, as the main table)."""
    frames = [ds.corrupted("strong", "test", draw) for draw in range(draws)]
    rows = []
    for objective, spec in ABLATION.items():
        if objective == "full":
            scores, report = full_scores, full_report
        else:
            stage(f"ablation: {objective}")
            model, report = train(spec["loss_weights"], spec["kinematics"])
            per_draw = []
            for frame in frames:
                a = split_arrays(frame, model.config.alignment)
                est = with_fallback(model.run(frame)["d_fused"].to_numpy(), a)
                per_draw.append({**recovery_scores(est, a), **diagnostic_scores(est, a)})
            scores = mean_over_draws(per_draw)
            bar.update()
        rows.append({"objective": objective, "loss_weights": spec["loss_weights"], "kinematics": spec["kinematics"],
                     "rmse": scores["rmse"], "mae": scores["mae"], "auroc_chg": scores["auroc_chg"],
                     "auprc_chg": scores["auprc_chg"], "n": scores["n"], "n_draws": draws, "gate": report["gate"]})
    base, full = rows[0]["rmse"], next(r["rmse"] for r in rows if r["objective"] == "full")
    for r in rows:
        r["delta_rmse"] = None if r is rows[0] else r["rmse"] - base
        r["delta_vs_full"] = r["rmse"] - full
    return rows
