"""A screenshot of a recording's default layout, as a user opening it sees it (rerun's own viewer
on a virtual screen): ``python -m racf.experiments.viz.screenshot REC.rrd OUT.png``.

It needs what rerun's viewer needs without a display: ``xvfb-run`` and a Vulkan driver for the
CPU (Debian: ``apt-get install xvfb mesa-vulkan-drivers``). rerun's viewer opens a recording at a
time of its own choosing (0.41 cannot set its cursor from a blueprint), so the docs' pictures of a
moment are drawn from the episode instead (``racf moment``, :mod:`racf.experiments.viz.moment`).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path

__all__ = ["screenshot", "main", "WINDOW"]

#: The viewer's window, logical points.
WINDOW = "1920x1080"


def screenshot(recording: str | Path, out: str | Path, window: str = WINDOW, width_px: int = 1600,
               timeout_s: float = 120.0) -> Path:
    """Opens ``recording`` in rerun's viewer under Xvfb and saves the window to ``out`` (PNG).
    RuntimeError names what is missing or what the viewer said."""
    recording, out = Path(recording), Path(out)
    if not recording.is_file():
        raise FileNotFoundError(f"no recording at {recording}")
    missing = [tool for tool in ("xvfb-run",) if shutil.which(tool) is None]
    if missing:
        raise RuntimeError(f"{', '.join(missing)} not found: apt-get install xvfb mesa-vulkan-drivers")
    viewer = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    out.parent.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(["xvfb-run", "-a", viewer, str(recording), "--renderer", "vulkan", "--window-size", window,
                           "--screenshot-to", str(out)], capture_output=True, text=True, timeout=timeout_s)
    if done.returncode != 0 or not out.is_file():
        raise RuntimeError(f"rerun could not take the screenshot: {done.stderr.strip()[-300:]}")
    _fit(out, width_px)
    return out


def _fit(path: Path, width_px: int) -> None:
    """Scales the PNG down to ``width_px`` wide (the viewer draws at the screen's pixel ratio)."""
    from PIL import Image

    with Image.open(path) as image:
        if image.width > width_px:
            image = image.resize((width_px, round(image.height * width_px / image.width)), Image.LANCZOS)
            image.save(path, optimize=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m racf.experiments.viz.screenshot", description=__doc__.splitlines()[0])
    p.add_argument("recording", type=Path, help="the .rrd file")
    p.add_argument("out", type=Path, help="the PNG to write")
    p.add_argument("--window", default=WINDOW, help=f"viewer window, logical points (default {WINDOW})")
    args = p.parse_args(argv)
    try:
        print(screenshot(args.recording, args.out, args.window))
    except (FileNotFoundError, RuntimeError, subprocess.TimeoutExpired) as err:
        print(f"screenshot: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
