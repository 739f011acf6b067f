"""Pictures: state images, depth, and affordance overlays in the style of the paper's Fig. 6.

Markers sit at each affordance's point; a line from the marker shows the gripper angle,
white where the angle matters and black where the affordance is symmetric. Marker colour
gives the type. Turn affordances carrying a parameter get an arrow for their direction.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from afford.sim.affordance_types import REGISTRY
from afford.sim.camera import world_to_pixel

SCALE = 4


def to_pil(image: np.ndarray, scale: int = SCALE) -> Image.Image:
    """(H, W, 3|4) float image in [0, 1] -> RGB PIL image, upscaled; RGBD shows its RGB."""
    rgb = np.clip(image[..., :3], 0, 1)
    pil = Image.fromarray((rgb * 255).astype(np.uint8))
    return pil.resize((pil.width * scale, pil.height * scale), Image.NEAREST)


def depth_pil(image: np.ndarray, scale: int = SCALE) -> Image.Image:
    d = np.clip(image[..., 3], 0, 1)
    # Stretched to the image's own range for display: near = bright.
    near = (d.max() - d) / max(float(d.max() - d.min()), 1e-6)
    pil = Image.fromarray((near * 255).astype(np.uint8)).convert("RGB")
    return pil.resize((pil.width * scale, pil.height * scale), Image.NEAREST)


def draw_affordances(pil: Image.Image, affordances, scale: int = SCALE) -> Image.Image:
    pil = pil.copy()
    d = ImageDraw.Draw(pil)
    for a in affordances:
        col, row = world_to_pixel(np.asarray(a.position)) * scale
        colour = REGISTRY[a.type].colour
        angle = np.radians(a.angle)
        length = 5 * scale
        # Image rows grow downwards while world y grows upwards: flip the y component.
        tip = (col + length * np.cos(angle), row - length * np.sin(angle))
        d.line([(col, row), tip], fill=(0, 0, 0) if a.symmetric else (255, 255, 255), width=2)
        r = REGISTRY[a.type].marker * scale
        d.ellipse([col - r, row - r, col + r, row + r], outline=colour, width=2)
        if a.turn:  # an execution parameter: its direction as an arc
            sign = 1 if a.turn > 0 else -1
            arc = [col - 3 * r, row - 3 * r, col + 3 * r, row + 3 * r]
            start = -np.degrees(angle)
            d.arc(
                arc,
                start=min(start, start - sign * 90),
                end=max(start, start - sign * 90),
                fill=colour,
                width=2,
            )
    return pil


def hstack(images: list[Image.Image], gap: int = 4, background=(255, 255, 255)) -> Image.Image:
    w = sum(i.width for i in images) + gap * (len(images) - 1)
    h = max(i.height for i in images)
    out = Image.new("RGB", (w, h), background)
    x = 0
    for i in images:
        out.paste(i, (x, 0))
        x += i.width + gap
    return out


def vstack(images: list[Image.Image], gap: int = 4, background=(255, 255, 255)) -> Image.Image:
    w = max(i.width for i in images)
    h = sum(i.height for i in images) + gap * (len(images) - 1)
    out = Image.new("RGB", (w, h), background)
    y = 0
    for i in images:
        out.paste(i, (0, y))
        y += i.height + gap
    return out


def label(pil: Image.Image, text: str) -> Image.Image:
    out = Image.new("RGB", (pil.width, pil.height + 14), (255, 255, 255))
    out.paste(pil, (0, 14))
    ImageDraw.Draw(out).text((3, 1), text, fill=(0, 0, 0))
    return out


def scene_picture(image: np.ndarray, affordances, path: str | Path) -> None:
    """RGB | depth | affordance overlay, side by side, as a PNG."""
    panels = [
        label(to_pil(image), "RGB"),
        label(depth_pil(image), "depth"),
        label(draw_affordances(to_pil(image), affordances), f"affordances ({len(affordances)})"),
    ]
    hstack(panels).save(path)


def text_patch(text: str, width: int, line_px: int = 11) -> np.ndarray:
    """`text` wrapped to `width` px, black on white: (h, width, 3) floats in [0, 1], for a goal
    given in words where pictures show a goal image."""
    words, lines, line = text.split(), [], ""
    for w in words:
        trial = f"{line} {w}".strip()
        if ImageDraw.Draw(Image.new("RGB", (1, 1))).textlength(trial) > width - 4 and line:
            lines.append(line)
            line = w
        else:
            line = trial
    lines.append(line)
    im = Image.new("RGB", (width, line_px * len(lines) + 4), (255, 255, 255))
    draw = ImageDraw.Draw(im)
    for k, text_line in enumerate(lines):
        draw.text((2, 2 + k * line_px), text_line, fill=(0, 0, 0))
    return np.asarray(im, dtype=np.float32) / 255.0
