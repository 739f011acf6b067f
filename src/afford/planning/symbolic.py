"""The canonical-symbolic planner: the baseline the paper argues against (eq. (1) style).

Its state is symbolic: where each object is, what it rests on, what the gripper holds. Its
effects are canonical only:

    grasp(o)       -> o is held (with whatever rests on it)
    place(o at P)  -> o rests upright at P, on P's host; the gripper is empty
    turn(b, +-90)  -> the block turns about its centre, with whatever rests on it

Nothing falls, tips, rolls or is pushed. Which affordances exist in a state is read off that
state's canonical geometry with the ground-truth detector (reach and collision), so the
planner knows which actions free up which others (what tasks 1 and 2 need) but nothing of
dynamics. It searches breadth-first for the shortest plan after which the task's success
predicate holds on the canonical state. A symbolic state has no view: the predicate's
`hidden` reads as `gone`. The plan is then executed in the simulator, where physics decides.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from afford.planning.predicates import Predicate
from afford.planning.tree import edges
from afford.sim.affordance import Detection
from afford.sim.affordance_types import REGISTRY
from afford.sim.affordances import Affordance
from afford.sim.camera import world_to_pixel
from afford.sim.constants import MOTION, TOLERANCES
from afford.sim.resting import rests_on
from afford.sim.scene import ObjectSpec, Scene

SYMBOLIC_SAMPLES = 8  # shortest canonical plans executed to judge the baseline


@dataclass(frozen=True)
class Pose:
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]


@dataclass(frozen=True)
class SymbolicState:
    """What is where: each object's canonical pose and host; what is held and how."""

    poses: tuple[tuple[str, Pose], ...]
    hosts: tuple[tuple[str, str], ...]  # (object, the object it rests on); table if absent
    held: str | None = None
    grasp: tuple[float, float, float, float] | None = None  # grasp point (x, y, z) and angle

    def pose(self, name: str) -> Pose:
        return dict(self.poses)[name]

    def key(self) -> tuple:
        """Equal for states a planner should treat as the same (poses to the millimetre)."""
        rounded = tuple((n, tuple(np.round(p.pos, 3)), tuple(np.round(p.quat, 2))) for n, p in self.poses)
        return rounded, self.hosts, self.held


@dataclass
class SymbolicResult:
    plan: tuple[Affordance, ...] | None  # None: no canonical plan within max_steps
    expanded: int
    seconds: float
    predicted: SymbolicState | None = None  # the canonical end state of the plan
    trace: list[SymbolicState] = field(default_factory=list)
    # Every shortest canonical plan is equally good to this planner: `total` of them reach the
    # success predicate; `plans` is a seeded uniform sample of them (all when few), `plan` its
    # first. Judging the baseline by all of them keeps its score from hinging on which object
    # the detector lists first.
    plans: list[tuple[Affordance, ...]] = field(default_factory=list)
    total: int = 0


def _rot_z(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])


def _turn_quat(quat, deg: float) -> tuple[float, ...]:
    q = np.array([np.cos(np.radians(deg) / 2), 0.0, 0.0, np.sin(np.radians(deg) / 2)])
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, q, np.asarray(quat, dtype=float))
    return tuple(float(v) for v in out)


class CanonicalWorld:
    """Symbolic states, their canonical geometry in a Scene, and the canonical effects."""

    def __init__(self, scene: Scene, specs: list[ObjectSpec], names: list[str]):
        self.scene = scene
        self.names = names
        self.kinds = {n: s.kind for n, s in zip(names, specs, strict=True)}
        self._drops: dict[tuple, float] = {}
        scene.reset(specs)  # the true start, settled: its poses are the symbolic start
        hosts = []
        for n in names:
            for h in names:
                if h != n and rests_on(scene, n, h):
                    hosts.append((n, h))
                    break
        self.start = SymbolicState(
            tuple((n, Pose(tuple(scene.object(n).pos), tuple(scene.object(n).quat))) for n in names),
            tuple(hosts),
        )

    def realise(self, state: SymbolicState) -> None:
        """Put the scene in the state's canonical geometry (teleported, not simulated)."""
        specs = [ObjectSpec(self.kinds[n], p.pos, p.quat) for n, p in state.poses]
        self.scene.reset(specs, settle=False, check=False)
        if state.held is not None:
            # Close the hand on the held object where it was grasped, then bring the arm home:
            # the detector's probe then carries a copy of it as a real grasp would.
            gx, gy, gz, angle = state.grasp
            q = self.scene.kin.solve(np.array([gx, gy, gz]), angle)
            if q is not None:
                self.scene.set_arm(q, fingers=1.0)
                mujoco.mj_forward(self.scene.model, self.scene.data)
            self.scene.attach(state.held)
            self.scene.set_arm(self.scene.home_q, fingers=1.0)
            mujoco.mj_forward(self.scene.model, self.scene.data)
            self.scene.carry_held()

    def _held_drop(self, state: SymbolicState) -> float:
        """TCP height above the held object's lowest point; every place edge of a state
        needs it, so it is measured once per state."""
        key = state.key()
        if key not in self._drops:
            self.realise(state)
            self._drops[key] = self.scene.held_drop
        return self._drops[key]

    def riders(self, state: SymbolicState, name: str) -> list[str]:
        """Everything resting on `name`, directly or on something that does."""
        hosts = dict(state.hosts)
        out = []
        for n in self.names:
            h = hosts.get(n)
            while h is not None and h != name:
                h = hosts.get(h)
            if h == name:
                out.append(n)
        return out

    def apply(self, state: SymbolicState, aff: Affordance) -> SymbolicState | None:
        """The canonical effect of `aff` (its type's `canonical`); None where it acts on nothing."""
        return REGISTRY[aff.type].canonical(self, state, aff)

    # The canonical effects' parts, for the affordance types (sim/affordance_types/).
    def object_at(self, state: SymbolicState, point: np.ndarray) -> str | None:
        """The graspable object whose centre is within grasp reach of `point`, if any."""
        poses = dict(state.poses)
        target = min(
            (n for n in self.names if self.kinds[n] != "support"),
            key=lambda n: np.linalg.norm(np.asarray(poses[n].pos) - point),
        )
        return (
            target if np.linalg.norm(np.asarray(poses[target].pos) - point) <= MOTION.grasp_radius else None
        )

    def held(self, state: SymbolicState, name: str, aff: Affordance) -> SymbolicState:
        """`name` lifted off its host and held where `aff` grasped it."""
        hosts = dict(state.hosts)
        hosts.pop(name, None)
        grasp = (*(float(v) for v in aff.position), aff.angle)
        return SymbolicState(state.poses, tuple(hosts.items()), name, grasp)

    def turned(self, state: SymbolicState, name: str, degrees: float) -> SymbolicState:
        """`name` and everything on it turned about its centre."""
        poses = dict(state.poses)
        centre = np.asarray(poses[name].pos)
        moved = [name, *self.riders(state, name)]
        return self._moved(poses, dict(state.hosts), moved, centre, centre, degrees)

    def placed(self, state: SymbolicState, aff: Affordance) -> SymbolicState:
        """The held object (and its riders) turned by the change of gripper angle about the
        grasp point, which moves to above the place point; it rests on the point's host."""
        poses = dict(state.poses)
        hosts = dict(state.hosts)
        point = np.asarray(aff.position)
        name = state.held
        gx, gy, gz, angle = state.grasp
        target = point + np.array([0.0, 0.0, self._held_drop(state)])
        hosts[name] = self._host_at(state, point, name)
        moved = [name, *self.riders(state, name)]
        return self._moved(poses, hosts, moved, np.array([gx, gy, gz]), target, aff.angle - angle)

    def _moved(self, poses, hosts, moved, pivot, to, turn_deg) -> SymbolicState:
        """Move `moved` rigidly: turn by `turn_deg` about `pivot`, which goes to `to`. The
        gripper ends empty (a place or a turn)."""
        rot = _rot_z(turn_deg)
        for n in moved:
            p = poses[n]
            pos = to + rot @ (np.asarray(p.pos) - pivot)
            poses[n] = Pose(tuple(float(v) for v in pos), _turn_quat(p.quat, turn_deg))
        hosts = {k: v for k, v in hosts.items() if v is not None}
        return SymbolicState(tuple((n, poses[n]) for n in self.names), tuple(sorted(hosts.items())))

    def _host_at(self, state: SymbolicState, point: np.ndarray, held: str) -> str | None:
        candidates = [n for n in self.names if self.kinds[n] in ("support", "block") and n != held]
        if not candidates:
            return None
        return min(candidates, key=lambda n: np.linalg.norm(np.asarray(state.pose(n).pos)[:2] - point[:2]))


def scan_order(affs: list[Affordance]) -> list[Affordance]:
    """Affordances in image order (row by row, left to right), the order a reader or a
    grid-cell recogniser meets them; ties keep the detector's order."""
    return sorted(affs, key=lambda a: tuple(np.floor(world_to_pixel(np.asarray(a.position))[::-1])))


@dataclass
class _Entry:
    """A state of one BFS level and every (parent key, action) that reaches it from the level above."""

    state: SymbolicState
    parents: list[tuple[tuple, Affordance]] = field(default_factory=list)
    paths: int = 0  # shortest plans from the start to this state


def plan_symbolic(
    scene: Scene,
    specs: list[ObjectSpec],
    names: list[str],
    success: Predicate,
    max_steps: int,
    samples: int = SYMBOLIC_SAMPLES,
    seed: int = 0,
) -> SymbolicResult:
    """Breadth-first search over canonical effects for the shortest plans to `success`.

    The search finishes the level where the predicate first holds, keeping every way into each
    state of a level, so it knows all shortest plans; it returns `samples` of them drawn
    uniformly with `seed` (a state seen on an earlier level is not a way to a shortest plan)."""
    start_time = time.perf_counter()
    world = CanonicalWorld(scene, specs, names)
    levels = [{world.start.key(): _Entry(world.start, paths=1)}]
    seen = set(levels[0])
    expanded = 0
    for depth in range(max_steps + 1):
        goals = []
        for key, entry in levels[depth].items():
            world.realise(entry.state)
            if success.holds(scene, see=False):
                goals.append(key)
        if goals:
            seconds = time.perf_counter() - start_time
            return _sampled(levels, goals, expanded, seconds, samples, seed)
        if depth == max_steps:
            break
        nxt: dict[tuple, _Entry] = {}
        for key, entry in levels[depth].items():
            world.realise(entry.state)
            actions = edges([Detection(a) for a in scan_order(scene.affordances())], TOLERANCES.merge_radius)
            expanded += 1
            for aff in actions:
                child = world.apply(entry.state, aff)
                if child is None or child.key() in seen:
                    continue
                e = nxt.setdefault(child.key(), _Entry(child))
                e.parents.append((key, aff))
                e.paths += entry.paths
        if not nxt:
            break
        seen |= set(nxt)
        levels.append(nxt)
    return SymbolicResult(None, expanded, time.perf_counter() - start_time)


def _sampled(levels, goals, expanded, seconds, samples, seed) -> SymbolicResult:
    """Up to `samples` distinct shortest plans, uniform over all of them, from the BFS levels
    (the goal states `goals` are on the last)."""
    depth = len(levels) - 1
    total = sum(levels[depth][k].paths for k in goals)
    rng = np.random.default_rng(seed)

    def draw() -> tuple[tuple[Affordance, ...], list[SymbolicState]]:
        weights = np.array([levels[depth][k].paths for k in goals], dtype=float)
        key = goals[int(rng.choice(len(goals), p=weights / weights.sum()))]
        plan: list[Affordance] = []
        trace = [levels[depth][key].state]
        for d in range(depth, 0, -1):
            parents = levels[d][key].parents
            w = np.array([levels[d - 1][k].paths for k, _ in parents], dtype=float)
            key, aff = parents[int(rng.choice(len(parents), p=w / w.sum()))]
            plan.append(aff)
            trace.append(levels[d - 1][key].state)
        return tuple(plan[::-1]), trace[::-1]

    plans: list[tuple[Affordance, ...]] = []
    traces = []
    tries = 0
    while len(plans) < min(samples, total) and tries < 20 * samples:
        plan, trace = draw()
        tries += 1
        if plan not in plans:
            plans.append(plan)
            traces.append(trace)
    return SymbolicResult(plans[0], expanded, seconds, traces[0][-1], traces[0], plans, total)
