"""Random scene arrangements (paper III.A-B): counts and placements drawn from an injected RNG.

Besides objects scattered over the work area, a layout deliberately makes the arrangements
where non-canonical effects happen: the block resting on one support (overhanging, so a place
on its end can tip it), bridging two supports, propped on one support as a slope, objects
sitting on the block, and objects standing right beside it (in the path of a turn).

`LAYOUTS` names the configurations a dataset may be drawn from: `default`, every dataset's
unless asked otherwise, and `balances`, the block always on one support and often far off its
centre, held level by what stands on its other end: the arrangements whose outcome turns on
millimetres (a counterweight's lever against the load placed), which `default` makes rarely,
its supports no more than 2 cm off the block's centre.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.sim.constants import BLOCK, LIMITS, SUPPORT, WORK_AREA
from afford.sim.specs import FOOTPRINT, REST_HALF_HEIGHT, ObjectSpec

SUPPORT_TOP = 2 * SUPPORT.half[2]


@dataclass(frozen=True)
class LayoutConfig:
    """Probabilities of the arrangements a random scene is drawn from."""

    block_modes: tuple[str, ...] = ("table", "one_support", "two_supports", "propped")
    block_mode_p: tuple[float, ...] = (0.4, 0.3, 0.15, 0.15)
    p_on_block: float = 0.35  # chance that each cup/ball starts on a free place point of the block
    p_on_support: float = 0.15  # chance that it starts on a free support
    p_beside_block: float = 0.3  # chance that it starts right beside the block
    # How far the block's centre may lie from its one support (mode one_support), either way.
    # The support is 5 cm square: within 2.5 cm the bare block balances; beyond, it stays level
    # only with a weight on its other end, and otherwise tips as the scene settles.
    support_offset: float = 0.02
    # Draw the arrangement again (up to `tries` times) while the block settles tilted, so that
    # every start holds it level: a block that tipped as it settled is no balance left to tip.
    level_start: bool = False
    level_cos: float = 0.999  # the block's up axis this near vertical (cosine): level
    gap: float = 0.006  # minimum clearance between footprints
    tries: int = 60


LAYOUTS: dict[str, LayoutConfig] = {
    "default": LayoutConfig(),
    # The block on one support, up to 4.5 cm off its centre (the support still under it), with
    # the cups and balls drawn onto its place points twice as often as by default, and every
    # start level: a block far off its support stands only where a weight holds it.
    "balances": LayoutConfig(
        block_modes=("one_support",),
        block_mode_p=(1.0,),
        support_offset=0.045,
        p_on_block=0.7,
        level_start=True,
    ),
}


def _yaw_quat(yaw: float, pitch: float = 0.0) -> tuple[float, float, float, float]:
    """Quaternion of a yaw about z followed by a pitch about the body's y axis."""
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    return (cy * cp, -sy * sp, cy * sp, sy * cp)


def _block_circles(x: float, y: float, yaw: float) -> list[tuple[float, float, float]]:
    u = np.array([np.cos(yaw), np.sin(yaw)])
    r = BLOCK.half[1]
    return [(x + u[0] * t, y + u[1] * t, r) for t in np.linspace(-BLOCK.half[0] + r, BLOCK.half[0] - r, 5)]


class _Table:
    """Footprints already on the table, for rejection sampling."""

    def __init__(self, gap: float):
        self.circles: list[tuple[float, float, float]] = []
        self.gap = gap

    def free(self, circles) -> bool:
        for x, y, r in circles:
            if not (
                WORK_AREA.x[0] - 0.05 <= x <= WORK_AREA.x[1] + 0.05
                and WORK_AREA.y[0] - 0.03 <= y <= WORK_AREA.y[1] + 0.12
            ):
                return False
            for cx, cy, cr in self.circles:
                if np.hypot(x - cx, y - cy) < r + cr + self.gap:
                    return False
        return True

    def add(self, circles) -> None:
        self.circles.extend(circles)


@dataclass
class _Build:
    """A layout being built: the draws, the table's occupied circles, the objects so far."""

    rng: np.random.Generator
    config: LayoutConfig
    table: _Table
    specs: list[ObjectSpec] = field(default_factory=list)
    place_points: list[np.ndarray] = field(default_factory=list)  # free tops an object can start on
    block_frame: tuple | None = None  # (centre xy, long axis xy, centre z, mode) of the placed block

    def uniform_xy(self, margin: float = 0.0) -> tuple[float, float]:
        return (
            float(self.rng.uniform(WORK_AREA.x[0] + margin, WORK_AREA.x[1] - margin)),
            float(self.rng.uniform(WORK_AREA.y[0] + margin, WORK_AREA.y[1] - margin)),
        )


def random_layout(rng: np.random.Generator, config: LayoutConfig | None = None) -> list[ObjectSpec]:
    """A random arrangement: 0-3 cups, 0-3 balls, 0-2 supports and the block. Three phases:
    the block with the supports its mode needs, the other supports, then cups and balls."""
    config = LayoutConfig() if config is None else config
    n_cups = int(rng.integers(0, LIMITS.cups + 1))
    n_balls = int(rng.integers(0, LIMITS.balls + 1))
    mode = str(rng.choice(config.block_modes, p=config.block_mode_p))
    n_supports = int(rng.integers(0, LIMITS.supports + 1))
    n_supports = max(n_supports, {"table": 0, "one_support": 1, "two_supports": 2, "propped": 1}[mode])
    build = _Build(rng, config, _Table(config.gap))
    _place_block(build, mode)
    _place_supports(build, n_supports - sum(1 for s in build.specs if s.kind == "support"))
    _place_small(build, ["cup"] * n_cups + ["ball"] * n_balls)
    return build.specs


def _place_block(build: _Build, mode: str) -> None:
    """The block, with the supports its mode needs (none when no spot is free)."""
    rng = build.rng
    for _ in range(build.config.tries):
        x, y = build.uniform_xy(0.03)
        yaw = float(rng.uniform(-np.pi / 2, np.pi / 2))
        u = np.array([np.cos(yaw), np.sin(yaw)])
        supports, z, pitch = [], BLOCK.half[2], 0.0
        if mode == "one_support":
            s = np.array([x, y]) - u * rng.uniform(-build.config.support_offset, build.config.support_offset)
            supports, z = [s], SUPPORT_TOP + BLOCK.half[2]
        elif mode == "two_supports":
            d = rng.uniform(0.07, 0.11)
            supports, z = [np.array([x, y]) + u * d, np.array([x, y]) - u * d], SUPPORT_TOP + BLOCK.half[2]
        elif mode == "propped":
            # One end rests on a support, the other on the table: a slope of about 14 degrees.
            side = rng.choice([-1.0, 1.0])
            s = np.array([x, y]) + side * u * (BLOCK.half[0] - 0.02)
            supports = [s]
            pitch = -side * np.arctan2(SUPPORT_TOP, 2 * (BLOCK.half[0] - 0.02))
            z = SUPPORT_TOP / 2 + BLOCK.half[2] + 0.004
        circles = _block_circles(x, y, yaw) + [(sx, sy, FOOTPRINT["support"]) for sx, sy in supports]
        if build.table.free(circles):
            build.table.add(circles)
            for sx, sy in supports:
                build.specs.append(ObjectSpec.upright("support", sx, sy, np.degrees(yaw)))
            build.specs.append(ObjectSpec("block", (x, y, z), _yaw_quat(yaw, pitch)))
            build.block_frame = (np.array([x, y]), u, z, mode)
            return


def _place_supports(build: _Build, n: int) -> None:
    """The remaining supports, free on the table; their tops are place points."""
    for _ in range(n):
        for _ in range(build.config.tries):
            x, y = build.uniform_xy()
            c = [(x, y, FOOTPRINT["support"])]
            if build.table.free(c):
                build.table.add(c)
                build.specs.append(ObjectSpec.upright("support", x, y, float(build.rng.uniform(0, 90))))
                build.place_points.append(np.array([x, y, SUPPORT_TOP]))
                break


def _place_small(build: _Build, kinds: list[str]) -> None:
    """Cups and balls: on the block, on a support, beside the block, or anywhere."""
    rng, config, frame = build.rng, build.config, build.block_frame
    block_points = []
    if frame is not None and frame[3] != "propped":
        centre, u, z, _ = frame
        top = z + BLOCK.half[2]
        block_points = [np.array([*(centre + u * dx), top]) for dx in BLOCK.place_offsets]
    for kind in kinds:
        r = FOOTPRINT[kind]
        spot = None
        roll = rng.random()
        if roll < config.p_on_block and block_points:
            spot = block_points.pop(int(rng.integers(len(block_points))))
        elif roll < config.p_on_block + config.p_on_support and build.place_points:
            spot = build.place_points.pop(int(rng.integers(len(build.place_points))))
        if spot is not None:
            pos = (float(spot[0]), float(spot[1]), float(spot[2] + REST_HALF_HEIGHT[kind]))
            build.specs.append(ObjectSpec(kind, pos, _yaw_quat(float(rng.uniform(0, 2 * np.pi)))))
            continue
        for attempt in range(config.tries):
            if frame is not None and attempt == 0 and rng.random() < config.p_beside_block:
                centre, u, _, _ = frame
                n = np.array([-u[1], u[0]]) * rng.choice([-1.0, 1.0])
                along = rng.uniform(-BLOCK.half[0], BLOCK.half[0])
                dist = BLOCK.half[1] + r + rng.uniform(config.gap, 0.03)
                x, y = centre + u * along + n * dist
            else:
                x, y = build.uniform_xy()
            c = [(float(x), float(y), r)]
            if build.table.free(c):
                build.table.add(c)
                build.specs.append(ObjectSpec.upright(kind, float(x), float(y)))
                break
