"""The top-down RGBD camera: rendering, and the one mapping between pixels and the world.

State images are (H, W, 4) float32 arrays, RGB then depth, every channel in [0, 1]. The
camera looks straight down (-z) with image "up" = +y, so row 0 is the far edge of the table.
Depth is the distance along the optical axis, mapped linearly from [near, far] to [0, 1].
"""

from __future__ import annotations

import mujoco
import numpy as np

from afford.sim.constants import CAMERA

SIZE = CAMERA.size
FOCAL_PX = (SIZE / 2) / np.tan(np.radians(CAMERA.fovy) / 2)


def depth_to_unit(depth_m: np.ndarray) -> np.ndarray:
    return np.clip((depth_m - CAMERA.near) / (CAMERA.far - CAMERA.near), 0.0, 1.0)


def unit_to_depth(depth_unit: np.ndarray | float) -> np.ndarray | float:
    return CAMERA.near + np.asarray(depth_unit) * (CAMERA.far - CAMERA.near)


def world_to_pixel(points):
    """World (..., 3) -> continuous pixel coordinates (..., 2) as (column, row).

    Takes a NumPy array or a torch tensor (the prediction net projects affordances with it)
    and returns the same kind.
    """
    p = points if hasattr(points, "detach") else np.asarray(points, dtype=float)
    cx, cy, cz = CAMERA.pos
    depth = cz - p[..., 2]
    col = SIZE / 2 + FOCAL_PX * (p[..., 0] - cx) / depth
    row = SIZE / 2 - FOCAL_PX * (p[..., 1] - cy) / depth
    if hasattr(points, "detach"):
        import torch

        return torch.stack([col, row], dim=-1)
    return np.stack([col, row], axis=-1)


def pixel_to_world(pixels: np.ndarray, depth_unit: np.ndarray | float) -> np.ndarray:
    """Continuous pixel coordinates (..., 2) as (column, row) plus depth in [0, 1] -> world (..., 3)."""
    px = np.asarray(pixels, dtype=float)
    depth = unit_to_depth(depth_unit)
    cx, cy, cz = CAMERA.pos
    x = cx + (px[..., 0] - SIZE / 2) * depth / FOCAL_PX
    y = cy - (px[..., 1] - SIZE / 2) * depth / FOCAL_PX
    return np.stack([x, y, cz - depth * np.ones_like(x)], axis=-1)


def pixel_index(points: np.ndarray) -> np.ndarray:
    """World (..., 3) -> integer (row, column) of the pixel each point falls in, clipped to the image."""
    colrow = np.floor(world_to_pixel(points)).astype(int)
    colrow = np.clip(colrow, 0, SIZE - 1)
    return colrow[..., ::-1]


class RGBDCamera:
    """Renders the model's `top` camera as an RGBD state image."""

    def __init__(self, model: mujoco.MjModel):
        self._renderer = mujoco.Renderer(model, SIZE, SIZE)
        self._cam = model.camera("top").id
        self._geom_body = model.geom_bodyid.copy()

    def render(self, data: mujoco.MjData) -> np.ndarray:
        r = self._renderer
        r.disable_depth_rendering()
        r.update_scene(data, self._cam)
        rgb = r.render().astype(np.float32) / 255.0
        r.enable_depth_rendering()
        r.update_scene(data, self._cam)
        depth = depth_to_unit(r.render()).astype(np.float32)
        r.disable_depth_rendering()
        return np.concatenate([rgb, depth[..., None]], axis=-1)  # (H, W, 4)

    def segment(self, data: mujoco.MjData) -> np.ndarray:
        """(H, W) int array: the body id seen at each pixel, -1 where no geom is seen."""
        r = self._renderer
        r.enable_segmentation_rendering()
        r.update_scene(data, self._cam)
        seg = r.render()
        r.disable_segmentation_rendering()
        ids, types = seg[..., 0], seg[..., 1]
        geom = (types == mujoco.mjtObj.mjOBJ_GEOM) & (ids >= 0)
        body = np.full(ids.shape, -1, dtype=int)
        body[geom] = self._geom_body[ids[geom]]
        return body

    def close(self) -> None:
        self._renderer.close()
