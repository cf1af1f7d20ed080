"""Chooses MuJoCo's offscreen GL backend before ``mujoco`` is first imported."""

import os


def ensure_gl_backend() -> None:
    """Default ``MUJOCO_GL`` to EGL (headless, Mesa on CPU) unless the user chose one."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    # PyOpenGL must agree with MuJoCo on the platform, or context creation fails.
    if os.environ["MUJOCO_GL"] in ("egl", "osmesa"):
        os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])


def gl_context_class():
    """MuJoCo's GL context class for the chosen backend.

    Chosen from ``MUJOCO_GL`` at call time rather than at ``import mujoco`` time, so a
    program that imported mujoco before racf still renders headless.
    """
    ensure_gl_backend()
    backend = os.environ["MUJOCO_GL"].lower()
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    elif backend in ("glfw", "glx"):
        from mujoco.glfw import GLContext
    else:
        raise ValueError(f"MUJOCO_GL={backend!r} is not supported; use 'egl' (headless), 'osmesa' or 'glfw'")
    return GLContext
