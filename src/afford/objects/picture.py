"""Pictures of the object world model: what perception sees, and where the dynamics put things."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from afford.objects.perceive import SeenObject
from afford.sim.camera import world_to_pixel
from afford.viz.draw import SCALE, to_pil

KIND_COLOUR = {
    "cup": (0, 220, 255),
    "ball": (255, 80, 255),
    "support": (120, 255, 120),
    "block": (255, 140, 0),
}


def perceived(image: np.ndarray, objects: list[SeenObject]) -> Image.Image:
    """The image with each perceived object's mask outline, centre, kind and posture; a held
    object's label says so."""
    pil = to_pil(image)
    d = ImageDraw.Draw(pil)
    for o in objects:
        colour = KIND_COLOUR[o.kind]
        edge = o.mask & ~(
            np.roll(o.mask, 1, 0) & np.roll(o.mask, -1, 0) & np.roll(o.mask, 1, 1) & np.roll(o.mask, -1, 1)
        )
        for r, c in np.argwhere(edge):
            d.rectangle([c * SCALE, r * SCALE, c * SCALE + SCALE - 1, r * SCALE + SCALE - 1], outline=colour)
        x, y = o.pixel * SCALE
        d.ellipse([x - 4, y - 4, x + 4, y + 4], fill=colour, outline=(0, 0, 0))
        label = o.kind if o.kind == "ball" else f"{o.kind} {o.posture}"
        label += " held" if o.held > 0.5 else ""
        d.text((x + 6, y - 6), label, fill=(255, 255, 255))
    return pil


def moved(image: np.ndarray, before: np.ndarray, after: np.ndarray, predicted: np.ndarray) -> Image.Image:
    """The start image with, per object, where it was (white), where it went (green) and where
    the dynamics put it (red), joined by lines."""
    pil = to_pil(image)
    d = ImageDraw.Draw(pil)
    for k in range(len(before)):
        if np.isnan(before[k, 0]):
            continue
        start = world_to_pixel(before[k, :3].astype(float)) * SCALE
        for pose, colour in ((after[k], (0, 255, 0)), (predicted[k], (255, 0, 0))):
            if np.isnan(pose[0]):
                continue
            end = world_to_pixel(pose[:3].astype(float)) * SCALE
            if np.linalg.norm(end - start) > SCALE:
                d.line([tuple(start), tuple(end)], fill=colour, width=2)
                d.ellipse([end[0] - 4, end[1] - 4, end[0] + 4, end[1] + 4], outline=colour, width=2)
        d.ellipse([start[0] - 3, start[1] - 3, start[0] + 3, start[1] + 3], fill=(255, 255, 255))
    return pil


def grid(pictures: list[Image.Image], columns: int) -> Image.Image:
    w, h = pictures[0].size
    columns = min(columns, len(pictures))
    rows = -(-len(pictures) // columns)
    out = Image.new("RGB", (w * columns, h * rows), (255, 255, 255))
    for i, p in enumerate(pictures):
        out.paste(p, ((i % columns) * w, (i // columns) * h))
    return out
