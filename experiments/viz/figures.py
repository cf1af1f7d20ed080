"""Matplotlib pictures of the map, the camera, depth and LiDAR (imported lazily by the CLI)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from racf.sim.world import map_facts  # noqa: E402
from racf.sim.world.mat_texture import render_mat  # noqa: E402
from racf.sim.world.road_graph import qcar2_road_graph  # noqa: E402
from racf.sim.world.stop_signs import stop_signs  # noqa: E402

__all__ = ["top_view", "camera_views", "save_figure"]


def top_view(path: Path, pose: tuple[float, float, float] | None = None,
             trajectory: np.ndarray | None = None, title: str = "QCar 2 indoor map") -> Path:
    """Top view: the mat, the road graph with node ids, signs, lights, and the car."""
    x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
    fig, ax = plt.subplots(figsize=(7.5, 9))
    ax.imshow(render_mat(px_per_m=100), extent=(x0, x1, y0, y1), origin="upper")
    graph = qcar2_road_graph()
    for (a, b), p in graph.paths.items():
        ax.plot(p.points[:, 0], p.points[:, 1], color="#3a8dde", lw=0.8, alpha=0.9)
        mid = len(p.points) // 2
        ax.annotate("", xy=p.points[mid + 1], xytext=p.points[mid - 1],
                    arrowprops=dict(arrowstyle="-|>", color="#3a8dde", lw=0.8))
    for n, (x, y, h) in graph.nodes.items():
        ax.plot(x, y, "o", ms=3, color="#1b4f8a")
        ax.text(x + 0.04, y + 0.04, str(n), fontsize=7, color="#1b4f8a")
    for s in stop_signs():
        ax.plot(*s.position, marker="8", ms=11, color="#c81414", mec="white", mew=1.2)
        ax.arrow(*s.position, 0.18 * math.cos(s.face_yaw), 0.18 * math.sin(s.face_yaw),
                 width=0.012, color="#c81414")
        ax.text(s.position[0] + 0.06, s.position[1] - 0.14, f"stop {s.index}", fontsize=8, color="#c81414")
        ax.plot(*s.stop_line, "s", ms=4, color="white", mec="k")
    for x, y, _ in map_facts.TRAFFIC_LIGHTS:
        ax.plot(x, y, marker="s", ms=6, color="#222", mec="#2c2")
    for x, y, _ in map_facts.YIELD_SIGNS:
        ax.plot(x, y, marker="v", ms=9, color="white", mec="#c81414", mew=1.5)
    if trajectory is not None and len(trajectory):
        ax.plot(trajectory[:, 0], trajectory[:, 1], color="#ff8c00", lw=2, label="trajectory")
    if pose is not None:
        x, y, yaw = pose
        ax.arrow(x, y, 0.25 * math.cos(yaw), 0.25 * math.sin(yaw), width=0.03, color="#ff8c00")
    ax.set_xlim(x0 - 0.05, x1 + 0.05)
    ax.set_ylim(y0 - 0.05, y1 + 0.05)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def camera_views(out_dir: Path, rgb: np.ndarray, depth: np.ndarray, lidar: np.ndarray,
                 sign_mask: np.ndarray | None = None, prefix: str = "") -> list[Path]:
    """Writes the camera image, the depth image and the LiDAR scan as PNGs."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.imshow(rgb)
    if sign_mask is not None and sign_mask.any():
        ax.contour(sign_mask, levels=[0.5], colors="cyan", linewidths=1)
    ax.set_title("D435 colour (cyan: ground-truth sign mask)")
    ax.axis("off")
    paths.append(save_figure(fig, out_dir / f"{prefix}camera_rgb.png"))

    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    shown = np.where(depth > 0, depth, np.nan)
    im = ax.imshow(shown, cmap="turbo", vmin=0, vmax=max(1.0, float(np.nanpercentile(shown, 99))))
    fig.colorbar(im, ax=ax, label="depth (m), white = no return")
    ax.set_title("D435 aligned depth")
    ax.axis("off")
    paths.append(save_figure(fig, out_dir / f"{prefix}camera_depth.png"))

    angles = np.arange(len(lidar)) * (2 * np.pi / len(lidar))
    ok = np.isfinite(lidar)
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    ax.scatter(lidar[ok] * np.cos(angles[ok]), lidar[ok] * np.sin(angles[ok]), s=4, c=lidar[ok], cmap="viridis")
    ax.plot(0, 0, marker=(3, 0, -90), ms=12, color="#ff8c00")
    ax.set_aspect("equal")
    ax.set_xlabel("x forward (m)")
    ax.set_ylabel("y left (m)")
    ax.set_title(f"RPLIDAR A2M12 scan ({ok.sum()}/{len(lidar)} returns), body frame")
    ax.grid(alpha=0.3)
    paths.append(save_figure(fig, out_dir / f"{prefix}lidar.png"))
    return paths


def save_figure(fig, path: Path, dpi: int = 100) -> Path:
    """Lays ``fig`` out, writes it to ``path`` (making its folder) and closes it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
