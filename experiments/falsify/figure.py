"""The worst case found, as people look at it: what the car's camera saw when the attack struck,
beside the episode's trace (the true distance, the depth the car measured, the distance it acted
on, and the bumper's gap to the stop line, with the attack's steps shaded)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from racf.experiments.episode import TrialSpec

__all__ = ["worst_case_figure"]


def worst_case_figure(spec: TrialSpec, path: str | Path, title: str = "") -> Path:
    """Runs ``spec`` (the worst case's episode) and writes its picture and trace to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from racf.experiments.episode import run_trial
    from racf.experiments.sweeps.executors import single_thread

    single_thread()
    frames: dict[str, np.ndarray] = {}

    def keep_frame(env, obs, info, row) -> None:
        # The frame as the attack first acts on a sign in view (else the last one with the sign in view).
        if info.get("sign_in_view") and ("struck" not in frames):
            frames["seen"] = np.array(obs["rgb"])
            if info.get("attack_active"):
                frames["struck"] = frames["seen"]

    result, log = run_trial(spec, on_step=keep_frame)
    fig, (pic, trace) = plt.subplots(1, 2, figsize=(11, 3.8), gridspec_kw={"width_ratios": [1, 1.4]})
    frame = frames.get("struck", frames.get("seen"))
    if frame is not None:
        pic.imshow(frame)
    pic.set_title("camera as the attack struck" if "struck" in frames else "camera, sign in view", fontsize=9)
    pic.axis("off")
    t = log["t"].to_numpy()
    trace.plot(t, log["d_true"], color="k", lw=1.2, label="true distance")
    trace.plot(t, log["d_meas"], color="tab:red", lw=0.8, alpha=0.7, label="depth measured")
    trace.plot(t, log["d_fused"], color="tab:blue", lw=1.2, label="distance acted on")
    trace.plot(t, log["dist_to_stop_line"], color="tab:green", lw=1.0, ls="--", label="bumper to stop line")
    trace.axhline(0.0, color="tab:green", lw=0.6)
    active = log["attack_active"].to_numpy(bool)
    if active.any():
        trace.fill_between(t, 0, 1, where=active, color="tab:red", alpha=0.12, transform=trace.get_xaxis_transform(),
                           label="attack on")
    speed = trace.twinx()
    speed.plot(t, log["speed"], color="tab:grey", lw=0.8)
    speed.set_ylabel("speed (m/s, grey)", fontsize=8)
    trace.set(xlabel="time (s)", ylabel="m")
    trace.legend(fontsize=7, loc="upper right")
    rule = getattr(result, "robustness_m", None)
    if rule is not None:
        trace.set_title(f"robustness {rule:+.3f} m, {result.failure or 'stopped'}", fontsize=9)
    else:  # a scenario with no stop rule: the car ahead's smallest gap
        touched = getattr(result, "no_lead_collision", True) is False
        trace.set_title(f"smallest gap to the car ahead {getattr(result, 'min_gap_m', float('nan')):+.3f} m"
                        f"{', contact' if touched else ''}", fontsize=9)
    if title:
        fig.suptitle(title, fontsize=10)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
