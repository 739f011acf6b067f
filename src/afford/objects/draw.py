"""D over objects: the next state image, drawn from the current one and the objects' next
states.

Each object is drawn by the simulator's renderer from its kind and pose (the scene's own
meshes and colours, the arm at its default pose with the fingers as the held object needs):
an honest drawing only where the project knows its objects' shapes and colours, which a
tabletop of known kinds does. A per-kind appearance model learned from renders would drop
that assumption; it is not here.

eq. (3) on images: the pixels where the drawing of the current state and the drawing of the
next state differ are taken from the next state's drawing; every other pixel is copied
exactly from the current image. A moved object is so erased (what the drawing shows beneath
it fills in) and drawn at its new pose, composited by depth (the renderer's depth test), and
an unchanged image stays exactly the image it was.
"""

from __future__ import annotations

import numpy as np

from afford.objects.state import KINDS, N_SLOTS, SLOT_KIND
from afford.sim.arm import GRIP_HALF_WIDTH, finger_fraction
from afford.sim.scene import ObjectSpec, Scene

CHANGED = 1e-6  # a pixel whose drawings differ by more than this in any channel changed
WIDEN_PX = 2  # eq. (3)'s mask grown by this many pixels


class Drawer:
    """Draws object states as state images, in a simulator of its own."""

    def __init__(self, scene: Scene | None = None):
        self.scene = scene if scene is not None else Scene()

    def render(self, poses: np.ndarray, held: int) -> np.ndarray:
        """(H, W, 4) RGBD of a state: pose rows per slot (NaN: none), the held slot or -1."""
        specs, names, counts = [], {}, dict.fromkeys(KINDS, 0)
        for slot in range(N_SLOTS):
            if np.isnan(poses[slot, 0]):
                continue
            kind = KINDS[SLOT_KIND[slot]]
            q = np.asarray(poses[slot, 3:7], dtype=float)
            specs.append(
                ObjectSpec(kind, tuple(float(v) for v in poses[slot, :3]), tuple(q / np.linalg.norm(q)))
            )
            names[slot] = kind
            counts[kind] += 1
        s = self.scene
        s.reset(specs, settle=False, check=False)
        # A held slot of a kind the gripper cannot hold (the dynamics may say so of a support)
        # is drawn as the arm at rest, open: what the gripper can show.
        if held >= 0 and names.get(held) in GRIP_HALF_WIDTH:
            s.set_arm(s.home_q, finger_fraction(names[held]))
            import mujoco

            mujoco.mj_forward(s.model, s.data)
        return s.observe()

    def draw(
        self,
        image: np.ndarray,
        drawn_now: np.ndarray,
        drawn_next: np.ndarray,
        seen: np.ndarray | None = None,
    ) -> np.ndarray:
        """The next state image: `image` where the two drawings agree, the next drawing elsewhere.
        `seen` (H, W) bool: pixels where `image` still shows the moved objects as they were
        perceived; they are redrawn too, since a drawing at a perceived pose misses what the
        pose is off by."""
        changed = np.abs(drawn_next - drawn_now).max(-1) > CHANGED
        if seen is not None:
            changed |= seen
        # A perceived pose is off by a pixel or so, so the drawing of the object where it was
        # misses a rim of the real one; widening the mask takes that rim with it.
        for _ in range(WIDEN_PX):
            changed = _widen(changed)
        return np.where(changed[..., None], drawn_next, image).astype(np.float32)


def _widen(mask: np.ndarray) -> np.ndarray:
    """The mask and its 4-neighbours."""
    out = mask.copy()
    out[1:] |= mask[:-1]
    out[:-1] |= mask[1:]
    out[:, 1:] |= mask[:, :-1]
    out[:, :-1] |= mask[:, 1:]
    return out
