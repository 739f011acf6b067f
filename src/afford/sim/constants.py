"""Every physical constant of the tabletop, in one place (metres, kilograms, degrees).

The world frame: the table top is z = 0, the robot base stands at the origin and faces +y,
the work area lies in front of it. The top-down camera looks along -z with image "up" = +y,
so the robot appears at the bottom of every state image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class UR3:
    """UR3 Denavit-Hartenberg parameters (Universal Robots' published values)."""

    d1: float = 0.1519
    a2: float = -0.24365
    a3: float = -0.21325
    d4: float = 0.11235
    d5: float = 0.08535
    d6: float = 0.0819
    joint_limit: float = 2 * np.pi  # every UR3 joint turns +-360 degrees


@dataclass(frozen=True)
class Gripper:
    """A parallel-jaw gripper on the UR3 flange; the TCP lies on the tool axis."""

    coupling: float = 0.03  # flange -> palm
    palm_half: tuple[float, float, float] = (0.055, 0.02, 0.015)
    finger_half: tuple[float, float, float] = (0.006, 0.012, 0.03)
    open_half_width: float = 0.05  # finger centre from the tool axis when open
    tcp_above_tip: float = 0.01
    # Extra clearance demanded around the open gripper when checking an affordance's
    # commencement pose: a neighbour closer than this blocks the pose (paper III.B).
    check_clearance: float = 0.004

    @property
    def palm_z(self) -> float:
        """Palm centre along the tool axis, from the flange."""
        return self.coupling + self.palm_half[2]

    @property
    def finger_z(self) -> float:
        return self.coupling + 2 * self.palm_half[2] + self.finger_half[2]

    @property
    def tcp_depth(self) -> float:
        """Flange -> TCP along the tool axis."""
        return self.coupling + 2 * self.palm_half[2] + 2 * self.finger_half[2] - self.tcp_above_tip


@dataclass(frozen=True)
class Cup:
    radius: float = 0.035  # at the rim
    bottom_radius: float = 0.026  # the walls taper: the turning block meets a cup high up
    height: float = 0.085
    wall: float = 0.004
    base: float = 0.006
    # The cup stands on a foot narrower than its rim, as many cups do; a low push from the
    # turning block then tips it over instead of sliding it along the table.
    foot_radius: float = 0.022
    n_wall: int = 12
    mass: float = 0.07
    rgba: tuple[float, float, float, float] = (0.15, 0.35, 0.95, 1.0)
    # Rubbery: a cup pushed low on its wall by the turning block tips over rather than slides.
    friction: float = 1.2
    base_mass_fraction: float = 0.25  # the rest is in the walls: a high centre of mass tips easily


@dataclass(frozen=True)
class Ball:
    radius: float = 0.025
    mass: float = 0.1  # heavier than a cup: a ball counterbalances a cup on the block (task 4)
    rgba: tuple[float, float, float, float] = (0.95, 0.15, 0.1, 1.0)
    # Small rolling friction lets a ball come to rest on the flat table but still roll
    # down the block when it lies at a slope (MuJoCo: rolling friction needs condim 6).
    rolling_friction: float = 0.0004


@dataclass(frozen=True)
class Support:
    """A post on a foot plate, one body. The post's top, narrower than the block, is what the
    block rests and tips on; the foot, wider than the block, is what the top-down camera sees
    of a support under the block (paper III.B: the support that decides a tip must show)."""

    half: tuple[float, float, float] = (0.025, 0.025, 0.03)  # 6 cm tall: a ball fits beneath an overhang
    # 9 x 9 cm: the perspective camera draws the block's top (11 cm up) 19% wider than its
    # footprint, so an 8 cm foot under it shows as little as 23 px where the block is nearest the
    # camera's axis; 9 cm shows at least 45 px at any yaw of either (tests/test_scene.py).
    # 6 mm thick, so validation's penetration margin still refuses an object that overlaps it.
    foot_half: tuple[float, float, float] = (0.045, 0.045, 0.003)
    mass: float = 0.6
    foot_mass_fraction: float = 0.15  # the foot's share of the mass (its volume beside the post's)
    rgba: tuple[float, float, float, float] = (0.05, 0.05, 0.05, 1.0)


@dataclass(frozen=True)
class Block:
    half: tuple[float, float, float] = (0.14, 0.03, 0.025)  # the paper's long side: 28 cm
    mass: float = 0.15
    # Smooth paint: an object on the block slides off once the block tilts past ~20 degrees.
    # The block's contacts take this value (geom priority), whatever touches it.
    friction: float = 0.35
    rgba: tuple[float, float, float, float] = (0.95, 0.75, 0.1, 1.0)
    place_offsets: tuple[float, ...] = (-0.09, 0.0, 0.09)  # the 3 place points along its length


@dataclass(frozen=True)
class Camera:
    """The top-down camera (the authors': perspective, fov 50 degrees)."""

    pos: tuple[float, float, float] = (0.0, 0.27, 0.70)
    fovy: float = 50.0
    size: int = 128
    # Depth channel = (distance along the optical axis - near) / (far - near), clipped to [0, 1].
    near: float = 0.15
    far: float = 0.75


@dataclass(frozen=True)
class Table:
    # The table top covers the whole camera view, so an object that leaves the table has
    # left the view too; whatever falls off is parked out of the scene (see Scene).
    half: tuple[float, float] = (0.335, 0.335)
    centre: tuple[float, float] = (0.0, 0.27)
    thickness: float = 0.04
    off_table_z: float = -0.05  # an object whose centre drops below this has fallen off
    floor_z: float = -0.8


@dataclass(frozen=True)
class WorkArea:
    """Where random scenes put objects: in front of the robot and within its reach."""

    x: tuple[float, float] = (-0.20, 0.20)
    y: tuple[float, float] = (0.16, 0.40)


@dataclass(frozen=True)
class Physics:
    timestep: float = 0.002
    friction: tuple[float, float, float] = (0.8, 0.005, 0.0001)
    weld_solref: tuple[float, float] = (0.005, 1.0)  # stiff enough that a held block does not lag
    settle_max_steps: int = 1500  # hard cap: 3 s simulated
    settle_check_every: int = 25
    settle_lin_vel: float = 0.004
    settle_ang_vel: float = 0.05


@dataclass(frozen=True)
class Motion:
    """Timing of the arm's moves (seconds simulated) and its waypoints."""

    hover: float = 0.12  # approach from this far above the target
    carry_height: float = 0.28  # TCP height when travelling with the gripper down
    place_clearance: float = 0.005  # a placed object is released this far above the surface
    turn_lift: float = 0.012
    t_travel: float = 0.45
    t_approach: float = 0.25
    t_close: float = 0.06
    t_turn: float = 0.7  # slow enough that a cup on the smooth block turns with it
    # Default pose (paper III.A): gripper pointing up, a held object visible above it.
    home_tcp: tuple[float, float, float] = (0.0, 0.12, 0.30)
    grasp_radius: float = 0.03  # an object centre this close to the TCP is what a grasp holds


@dataclass(frozen=True)
class Limits:
    """How many of each object a scene can hold (paper III.A)."""

    cups: int = 3
    balls: int = 3
    supports: int = 2
    blocks: int = 1


@dataclass(frozen=True)
class Tolerances:
    """How states are judged: one value each for the detector, the planners, the predicates
    and the evaluation."""

    upright_cos: float = 0.9  # an axis this close to vertical (cosine) is upright
    position: float = 0.03  # metres: an object this near where it should be is there
    merge_radius: float = 0.01  # metres: symmetric affordances of one type this close are one


@dataclass(frozen=True)
class EffectThresholds:
    """When an execution had a side effect (data/effects.py): read from true poses."""

    moved: float = 0.02  # metres across the table: another object pushed, a placed one slid
    topple_deg: float = 30.0  # a cup's or support's axis turned this far: toppled
    block_tip_deg: float = 10.0  # the block tilted this far: it tipped
    drop: float = 0.03  # metres: a placed object's centre this far below the place point fell
    rider_rise: float = 0.02  # an object this far above another's centre, and over its top
    rider_margin: float = 0.01  # ... face (within this margin of its edges), rode on it


@dataclass(frozen=True)
class WordThresholds:
    """When a sentence about a state is true (words/facts.py): read from true poses."""

    beside: float = 0.03  # metres: left of / in front of needs this much between the centres
    block_end: float = 0.05  # metres from the block's centre along it: on its left or right end
    yaw_tolerance: float = 30.0  # degrees: the block lies across or lengthwise within this
    table_rise: float = 0.015  # metres above its resting height: still on the table
    # Gone from the camera: at most this many pixels of its colour within this radius of where
    # its centre projects (a dataset keeps images, not the renderer's segmentation).
    hidden_pixels: int = 3
    hidden_radius_px: float = 8.0
    # Words are vague at their edges: a cup 3.1 cm left of a ball is barely "left of" it.
    # Sampled clauses (training, evaluation) keep this far from every threshold above.
    vague_m: float = 0.01
    vague_deg: float = 10.0


@dataclass(frozen=True)
class Visibility:
    """When the camera shows an object (data/visibility.py): read from instance masks."""

    min_pixels: int = 20  # fewer pixels than this: the object is hidden from the image


UR3_DH = UR3()
GRIPPER = Gripper()
CUP = Cup()
BALL = Ball()
SUPPORT = Support()
BLOCK = Block()
CAMERA = Camera()
TABLE = Table()
WORK_AREA = WorkArea()
PHYSICS = Physics()
MOTION = Motion()
LIMITS = Limits()
TOLERANCES = Tolerances()
EFFECTS = EffectThresholds()
WORDS = WordThresholds()
VISIBILITY = Visibility()

KINDS = ("cup", "ball", "support", "block")
GRASPABLE = ("cup", "ball", "block")
PARK_Z = 2.0  # objects not in the scene float here (gravity cancelled), far from the view
