"""The simulated tabletop: one MuJoCo model, its state, and the objects in it.

A `Scene` is the whole simulator a user drives: put objects on the table (`reset`), look
(`observe`), list what can be done (`affordances`), do it (`execute`), and go back in time
(`snapshot` / `restore`). Affordance detection and execution live in their own modules;
this one owns the state.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from afford.sim import camera as cam
from afford.sim import validate
from afford.sim.constants import MOTION, PARK_Z, PHYSICS, TABLE
from afford.sim.kinematics import ArmKinematics
from afford.sim.mjcf import FINGER_JOINTS, HIDDEN_GROUP, build_mjcf, park_position, slot_names

# The records live in their own module (sim/specs.py); they are the scene's vocabulary, so
# `afford.sim.scene` offers them too.
from afford.sim.specs import (  # noqa: F401
    REST_HALF_HEIGHT,
    SCENE_FORMAT,
    ObjectSpec,
    SceneError,
    load_scene_file,
    read_json_file,
    save_scene_file,
    specs_from_json,
    specs_to_json,
)

PARK_CHECK_EVERY = 10


@dataclass
class ObjectState:
    """An object's true state: what the success predicates and the evaluation read."""

    name: str
    kind: str
    pos: np.ndarray
    quat: np.ndarray
    present: bool  # False once it has left the table (and so the view)
    held: bool = False

    @property
    def up_axis(self) -> np.ndarray:
        """The object's own z axis in the world (a cup's opening direction)."""
        m = np.zeros(9)
        mujoco.mju_quat2Mat(m, self.quat)
        return m.reshape(3, 3)[:, 2]

    @property
    def yaw_deg(self) -> float:
        m = np.zeros(9)
        mujoco.mju_quat2Mat(m, self.quat)
        x = m.reshape(3, 3)[:, 0]
        return float(np.degrees(np.arctan2(x[1], x[0])))


@dataclass
class Snapshot:
    """The full simulator state: restoring it and doing the same thing gives the same result."""

    physics: np.ndarray
    eq_data: np.ndarray
    held: str | None
    held_drop: float


class Scene:
    """The tabletop simulator. Build once, then `reset` to any arrangement of objects."""

    _STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION

    def __init__(self):
        self.model = mujoco.MjModel.from_xml_string(build_mjcf())
        self.data = mujoco.MjData(self.model)
        self.kin = ArmKinematics(self.model)
        self.slots = slot_names()
        self.kind_of = dict(self.slots)
        self._qadr = {n: self.model.joint(n).qposadr[0] for n, _ in self.slots}
        self._vadr = {n: self.model.joint(n).dofadr[0] for n, _ in self.slots}
        self._body = {n: self.model.body(n).id for n, _ in self.slots}
        self._zadr = np.array([self._qadr[n] + 2 for n, _ in self.slots])
        self._weld = {n: self.model.equality(f"hold_{n}").id for n, k in self.slots if k != "support"}
        self.arm_qadr = self.kin.qpos_adr
        self.arm_vadr = self.kin.dof_adr
        self.finger_qadr = np.array([self.model.joint(j).qposadr[0] for j in FINGER_JOINTS])
        self.finger_vadr = np.array([self.model.joint(j).dofadr[0] for j in FINGER_JOINTS])
        # The arm's and fingers' joints are consecutive in qpos/qvel: slices are cheap to write.
        self._arm_slice = slice(self.arm_qadr[0], self.arm_qadr[-1] + 1)
        self._arm_vslice = slice(self.arm_vadr[0], self.arm_vadr[-1] + 1)
        self._finger_slice = slice(self.finger_qadr[0], self.finger_qadr[-1] + 1)
        self._finger_vslice = slice(self.finger_vadr[0], self.finger_vadr[-1] + 1)
        assert np.all(np.diff(self.arm_qadr) == 1) and np.all(np.diff(self.finger_qadr) == 1)
        self._finger_open = self.model.jnt_range[self.model.joint("finger_l").id][1]
        self.home_q = self.kin.home(np.array(MOTION.home_tcp))
        self.held: str | None = None
        self.held_drop = 0.0  # TCP height above the held object's lowest point, gripper down
        self.steps = 0  # physics steps taken, for benchmarks
        # The arm's path during the last execution (`sim/arm_path.py`): read by the pose data,
        # where what an arm sweeps through is an input of the objects' dynamics.
        self.tcp_trace: list[tuple] | None = None
        self._tcp = self.model.site("tcp").id
        self.last_path: np.ndarray | None = None
        self._camera: cam.RGBDCamera | None = None
        self._eq_data0 = self.model.eq_data.copy()
        # Each geom's slot (-1: not an object's), to hide the parked ones from the camera.
        slot_of_body = np.full(self.model.nbody, -1)
        slot_of_body[[self._body[n] for n, _ in self.slots]] = np.arange(len(self.slots))
        self._geom_slot = slot_of_body[self.model.geom_bodyid]
        self._geom_group0 = self.model.geom_group.copy()
        self.reset([])

    # ------------------------------------------------------------------ set-up
    def reset(
        self, objects: list[ObjectSpec], settle: bool = True, check: bool = True, where: str = ""
    ) -> None:
        """Empty gripper at the default pose, `objects` on the table, every other slot parked.

        With `check` the start is validated first (`afford.sim.validate`: finite numbers, on the
        table and in view, nothing interpenetrating, sunk or floating), raising `SceneError`
        (a ValueError) that names the object and field, after `where` (a file, say). Callers
        that pose states of their own making (layouts built free of overlaps, canonical states
        teleported into place) pass check=False."""
        names = validate.check_numbers(objects, where)
        if check:
            validate.check_place(objects, names, where)
        mujoco.mj_resetData(self.model, self.data)
        self.model.eq_data[:] = self._eq_data0
        self.data.eq_active[:] = False
        self.held, self.held_drop = None, 0.0
        self.set_arm(self.home_q, fingers=1.0)
        assigned = dict(zip(names, objects, strict=True))
        for index, (name, _) in enumerate(self.slots):
            if name in assigned:
                spec = assigned[name]
                q = np.asarray(spec.quat, dtype=float)
                self._set_pose(name, np.asarray(spec.pos, dtype=float), q / np.linalg.norm(q))
            else:
                self._park(name, index)
        mujoco.mj_forward(self.model, self.data)
        if check:
            try:
                validate.check_contacts(self, names, where)
            except SceneError:
                self.reset([], settle=False, check=False)  # refused: leave an empty table, not the bad start
                raise
        if settle:
            self.settle()

    def _set_pose(self, name: str, pos: np.ndarray, quat: np.ndarray) -> None:
        self.data.xfrc_applied[self._body[name]] = 0.0
        a, v = self._qadr[name], self._vadr[name]
        self.data.qpos[a : a + 3] = pos
        self.data.qpos[a + 3 : a + 7] = quat
        self.data.qvel[v : v + 6] = 0.0

    def _park(self, name: str, index: int | None = None) -> None:
        """Take an object out of the scene: it floats, gravity cancelled, far from everything."""
        if index is None:
            index = [n for n, _ in self.slots].index(name)
        self._set_pose(name, park_position(index), np.array([1.0, 0.0, 0.0, 0.0]))
        body = self._body[name]
        self.data.xfrc_applied[body, 2] = -self.model.opt.gravity[2] * self.model.body_mass[body]

    def set_arm(self, q: np.ndarray, fingers: float, dq: np.ndarray | None = None) -> None:
        """Pose the kinematic arm: joints q, fingers opened to a fraction of their range."""
        d = self.data
        d.qpos[self._arm_slice] = q
        d.qvel[self._arm_vslice] = 0.0 if dq is None else dq
        d.qpos[self._finger_slice] = fingers * self._finger_open
        d.qvel[self._finger_vslice] = 0.0

    # ------------------------------------------------------------------ state
    def object(self, name: str) -> ObjectState:
        a = self._qadr[name]
        pos = self.data.qpos[a : a + 3].copy()
        return ObjectState(
            name=name,
            kind=self.kind_of[name],
            pos=pos,
            quat=self.data.qpos[a + 3 : a + 7].copy(),
            present=bool(TABLE.off_table_z < pos[2] < PARK_Z - 1.0),
            held=name == self.held,
        )

    def objects(self, present_only: bool = True) -> list[ObjectState]:
        states = [self.object(n) for n, _ in self.slots]
        return [s for s in states if s.present or not present_only]

    def body_id(self, name: str) -> int:
        return self._body[name]

    # ------------------------------------------------------------------ physics
    def step(self, n: int = 1) -> None:
        """Advance n physics steps, parking whatever has fallen off the table.

        The check runs every `PARK_CHECK_EVERY` steps: a fallen object is below the table,
        out of view and out of reach of everything else, so parking it a little later
        changes nothing in the scene. The phase comes from simulated time, which resets and
        snapshots carry, so a run never depends on what the Scene simulated before.
        """
        dt = self.model.opt.timestep
        for _ in range(n):
            mujoco.mj_step(self.model, self.data)
            self.steps += 1
            if round(self.data.time / dt) % PARK_CHECK_EVERY == 0:
                self._park_fallen()

    def _park_fallen(self) -> None:
        z = self.data.qpos[self._zadr]
        if np.any(z < TABLE.off_table_z):
            for index, (name, _) in enumerate(self.slots):
                if self.data.qpos[self._qadr[name] + 2] < TABLE.off_table_z:
                    self._park(name, index)

    def record_tcp(self) -> None:
        """Append the TCP's position, its x axis in the plane and the finger opening to
        `tcp_trace` (when recording); `sim/arm_path.key_points` turns the axis into a yaw."""
        if self.tcp_trace is None:
            return
        d = self.data
        m = d.site_xmat[self._tcp]
        self.tcp_trace.append(
            (*d.site_xpos[self._tcp], m[0], m[3], d.qpos[self._finger_slice][0] / self._finger_open)
        )

    def moving(self) -> bool:
        for name, _ in self.slots:
            v = self._vadr[name]
            a = self._qadr[name]
            if not TABLE.off_table_z < self.data.qpos[a + 2] < PARK_Z - 1.0 or name == self.held:
                continue
            if np.linalg.norm(self.data.qvel[v : v + 3]) > PHYSICS.settle_lin_vel:
                return True
            if np.linalg.norm(self.data.qvel[v + 3 : v + 6]) > PHYSICS.settle_ang_vel:
                return True
        return False

    def settle(self) -> int:
        """Step until every object on the table rests, at most `settle_max_steps`. Returns steps taken.

        The arm is held exactly where it is: left to the integrator, its joints and fingers
        drift while objects settle (by up to ~0.1 rad), so the arm at its default pose would
        render differently from state to state, noise that a prediction net is asked to learn.
        """
        q = self.data.qpos[self._arm_slice].copy()
        fingers = self.data.qpos[self._finger_slice].copy()
        taken = 0
        while taken < PHYSICS.settle_max_steps:
            for _ in range(PHYSICS.settle_check_every):
                self.step()
                self.data.qpos[self._arm_slice] = q
                self.data.qvel[self._arm_vslice] = 0.0
                self.data.qpos[self._finger_slice] = fingers
                self.data.qvel[self._finger_vslice] = 0.0
            taken += PHYSICS.settle_check_every
            if not self.moving():
                break
        mujoco.mj_forward(self.model, self.data)
        return taken

    # ------------------------------------------------------------------ holding
    def attach(self, name: str) -> None:
        """Weld `name` to the hand where it is now (a grasp)."""
        hand = self.model.body("hand").id
        hp, hq = self.data.xpos[hand], self.data.xquat[hand]
        body = self._body[name]
        op, oq = self.data.xpos[body], self.data.xquat[body]
        inv = np.zeros(4)
        mujoco.mju_negQuat(inv, hq)
        rel_pos = np.zeros(3)
        mujoco.mju_rotVecQuat(rel_pos, op - hp, inv)
        rel_quat = np.zeros(4)
        mujoco.mju_mulQuat(rel_quat, inv, oq)
        eq = self._weld[name]
        self.model.eq_data[eq, 3:6] = rel_pos
        self.model.eq_data[eq, 6:10] = rel_quat
        self.data.eq_active[eq] = True
        self.held = name
        tcp_z = self.data.site_xpos[self.model.site("tcp").id][2]
        self.held_drop = float(tcp_z - self.lowest_point(name))

    def release(self) -> None:
        if self.held is not None:
            self.data.eq_active[self._weld[self.held]] = False
        self.held = None
        self.held_drop = 0.0

    def carry_held(self) -> None:
        """Put the held object where its weld says, in the hand (after a kinematic arm move)."""
        rel_pos, rel_quat = self.held_relpose()
        hand = self.model.body("hand").id
        hp, hq = self.data.xpos[hand], self.data.xquat[hand]
        pos = np.zeros(3)
        mujoco.mju_rotVecQuat(pos, rel_pos, hq)
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, hq, rel_quat)
        self._set_pose(self.held, hp + pos, quat)
        mujoco.mj_forward(self.model, self.data)

    def held_relpose(self) -> tuple[np.ndarray, np.ndarray]:
        """The held object's pose in the hand frame (position, quaternion)."""
        eq = self._weld[self.held]
        return self.model.eq_data[eq, 3:6].copy(), self.model.eq_data[eq, 6:10].copy()

    def lowest_point(self, name: str) -> float:
        """World z of the lowest point of an object's geoms."""
        return self._z_extent(name)[0]

    def highest_point(self, name: str) -> float:
        """World z of the highest point of an object's geoms."""
        return self._z_extent(name)[1]

    def _z_extent(self, name: str) -> tuple[float, float]:
        """Lowest and highest world z of an object's geoms (boxes, cylinders, spheres)."""
        body = self._body[name]
        low, high = np.inf, -np.inf
        for g in range(
            self.model.body_geomadr[body], self.model.body_geomadr[body] + self.model.body_geomnum[body]
        ):
            size = self.model.geom_size[g]
            rot = self.data.geom_xmat[g].reshape(3, 3)
            gtype = self.model.geom_type[g]
            if gtype == mujoco.mjtGeom.mjGEOM_SPHERE:
                reach = size[0]
            elif gtype == mujoco.mjtGeom.mjGEOM_BOX:
                reach = np.abs(rot[2, :]) @ size
            else:  # cylinder: radius in the plane of the disc, half-height along its axis
                reach = size[0] * np.sqrt(max(0.0, 1 - rot[2, 2] ** 2)) + size[1] * abs(rot[2, 2])
            z = self.data.geom_xpos[g][2]
            low, high = min(low, z - reach), max(high, z + reach)
        return float(low), float(high)

    # ------------------------------------------------------------------ snapshots
    def snapshot(self) -> Snapshot:
        size = mujoco.mj_stateSize(self.model, self._STATE_SPEC)
        state = np.zeros(size)
        mujoco.mj_getState(self.model, self.data, state, self._STATE_SPEC)
        return Snapshot(state, self.model.eq_data.copy(), self.held, self.held_drop)

    def restore(self, snap: Snapshot) -> None:
        mujoco.mj_setState(self.model, self.data, snap.physics, self._STATE_SPEC)
        self.model.eq_data[:] = snap.eq_data
        self.held, self.held_drop = snap.held, snap.held_drop
        mujoco.mj_forward(self.model, self.data)

    # ------------------------------------------------------------------ observing
    def observe(self) -> np.ndarray:
        """The state image: (128, 128, 4) float32 RGBD, every channel in [0, 1]."""
        return self._cam().render(self.data)

    def visible_pixels(self, name: str) -> int:
        """How many pixels of the state image show the object `name`."""
        return int(np.count_nonzero(self._cam().segment(self.data) == self._body[name]))

    def instance_mask(self) -> np.ndarray:
        """(H, W) int8: the slot index (`self.slots`) of the object seen at each pixel of the state
        image, -1 where none is (table, arm, background): MuJoCo's segmentation rendering from
        the state camera, the ground truth that perception learns."""
        body = self._cam().segment(self.data)
        lookup = np.full(self.model.nbody + 1, -1, dtype=np.int8)
        for index, (name, _) in enumerate(self.slots):
            lookup[self._body[name]] = index
        return lookup[body]  # -1 (no geom) indexes the last entry, which is -1

    def _cam(self) -> cam.RGBDCamera:
        """The renderer, made on first use (it needs a GL context), with the parked objects
        hidden from it: they are far out of view, so every image is the same without them, and
        drawn faster. Which are parked is read from the state now, so a restored snapshot or
        an object that fell and was parked is seen as it is."""
        if self._camera is None:
            self._camera = cam.RGBDCamera(self.model)
        parked = self.data.qpos[self._zadr] >= PARK_Z - 1.0
        hide = (self._geom_slot >= 0) & parked[self._geom_slot]
        self.model.geom_group[:] = np.where(hide, HIDDEN_GROUP, self._geom_group0)
        return self._camera

    def affordances(self):
        """The ground-truth affordance list of the current state (paper III.B)."""
        from afford.sim.affordances import detect

        return detect(self)

    def execute(self, affordance):
        """Carry out an affordance with the arm, return to the default pose, let things settle."""
        from afford.sim.motion import execute

        return execute(self, affordance)

    def close(self) -> None:
        if self._camera is not None:
            self._camera.close()
            self._camera = None

    def __enter__(self) -> Scene:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ JSON
    def specs(self) -> list[ObjectSpec]:
        """The objects on the table now, as a scene description."""
        return [
            ObjectSpec(
                s.kind, tuple(round(float(v), 5) for v in s.pos), tuple(round(float(v), 6) for v in s.quat)
            )
            for s in self.objects()
            if not s.held
        ]
