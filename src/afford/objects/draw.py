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
# Resting: an object sunk deeper than this into what is under it is lifted out of it. The
# dynamics put a placed cup's centre a few millimetres off; sunk into the block it lands on, the
# block's top hides the cup's floor and the drawing shows the block through the cup.
SUNK_M = 0.0005
# ... and no deeper than this: a landing a little low, not two objects the dynamics put into one
# another (a block turned through a cup), which lifting one of them would not make right.
DEEPEST_M = 0.012
UPWARD = 0.7  # a contact whose normal is this close to vertical is one object resting on another
REST_ROUNDS = 3  # a stack is lifted from the bottom up, one object a round


class Drawer:
    """Draws object states as state images, in a simulator of its own."""

    def __init__(self, scene: Scene | None = None):
        self.scene = scene if scene is not None else Scene()

    def render(self, poses: np.ndarray, held: int) -> np.ndarray:
        """(H, W, 4) RGBD of a state: pose rows per slot (NaN: none), the held slot or -1."""
        self._pose(poses, held)
        return self.scene.observe()

    def rest(self, poses: np.ndarray, held: int, moved: np.ndarray) -> np.ndarray:
        """The pose rows with each moved object (`moved`, (slots,) bool) that sinks into what is
        under it lifted straight up until it rests on it; the held object stays in the gripper.
        Rigid objects do not pass into one another, and a drawing of one that does shows the
        wrong surface; the shapes are the simulator's, as in `render`."""
        out = np.array(poses, dtype=np.float32, copy=True)
        s = self.scene
        for _ in range(REST_ROUNDS):
            slot_of = {s.body_id(name): slot for slot, name in self._pose(out, held).items()}
            lift = np.zeros(N_SLOTS)
            for c in s.data.contact[: s.data.ncon]:
                if not -DEEPEST_M <= c.dist < -SUNK_M or abs(c.frame[2]) < UPWARD:
                    continue
                # The normal points from geom1 to geom2: the upper geom is the one it points to.
                upper = c.geom2 if c.frame[2] > 0 else c.geom1
                slot = slot_of.get(int(s.model.geom_bodyid[upper]))
                if slot is not None and moved[slot] and slot != held:
                    lift[slot] = max(lift[slot], -c.dist / abs(c.frame[2]))
            if not lift.any():
                break
            out[:, 2] += lift.astype(np.float32)
        return out

    def _pose(self, poses: np.ndarray, held: int) -> dict[int, str]:
        """Put the state into the drawing scene, contacts computed; {slot: scene name}."""
        import mujoco

        specs, kinds, names, counts = [], {}, {}, dict.fromkeys(KINDS, 0)
        for slot in range(N_SLOTS):
            if np.isnan(poses[slot, 0]):
                continue
            kind = KINDS[SLOT_KIND[slot]]
            q = np.asarray(poses[slot, 3:7], dtype=float)
            specs.append(
                ObjectSpec(kind, tuple(float(v) for v in poses[slot, :3]), tuple(q / np.linalg.norm(q)))
            )
            kinds[slot], names[slot] = kind, f"{kind}{counts[kind]}"  # as the scene names them
            counts[kind] += 1
        s = self.scene
        s.reset(specs, settle=False, check=False)
        # A held slot of a kind the gripper cannot hold (the dynamics may say so of a support)
        # is drawn as the arm at rest, open: what the gripper can show.
        if held >= 0 and kinds.get(held) in GRIP_HALF_WIDTH:
            s.set_arm(s.home_q, finger_fraction(kinds[held]))
            mujoco.mj_forward(s.model, s.data)
        return names

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
