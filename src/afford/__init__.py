"""afford: plan action sequences by recognising affordances in predicted futures."""

import os

# MuJoCo picks its OpenGL back end when it is first imported; default to headless EGL so
# rendering works on machines without a display. OSMesa also works: MUJOCO_GL=osmesa.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
