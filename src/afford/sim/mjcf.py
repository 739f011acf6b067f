"""The MJCF of the tabletop, written from `constants` so every size has one source.

One model holds every object slot a scene can use (3 cups, 3 balls, 2 supports, 1 block);
a scene puts the slots it uses on the table and parks the rest far below it. One compiled
model therefore serves every scene, and any snapshot restores into any scene.

Collision classes (contype / conaffinity bit masks):
- world (table, floor, objects): contype 1, conaffinity 1|2, so they touch each other and
  the probes;
- probes (the gripper-shaped check body and copies of a held object, paper III.B): contype 2,
  conaffinity 0, so they touch the world but never each other;
- robot: 0 / 0. The arm is kinematic and passes through things; a held object is welded to
  the hand and does all the pushing, lifting and placing. This keeps every effect in the
  data a consequence of object physics, not of arm links brushing objects.
"""

from __future__ import annotations

import numpy as np

from afford.sim.constants import (
    BALL,
    BLOCK,
    CAMERA,
    CUP,
    GRIPPER,
    LIMITS,
    PARK_Z,
    PHYSICS,
    SUPPORT,
    TABLE,
    UR3_DH,
)

ARM_JOINTS = tuple(f"q{i}" for i in range(1, 7))
FINGER_JOINTS = ("finger_l", "finger_r")
PROBE_BODIES = {"empty": "probe_hand", "cup": "copy_cup", "ball": "copy_ball", "block": "copy_block"}

_WORLD = 'contype="1" conaffinity="3"'
_PROBE = 'contype="2" conaffinity="0" group="4"'
# A parked object's geoms are moved to this group while it waits, off in MuJoCo's default
# visual options as the probes' group 4 is: a renderer draws every geom it is given, in view or
# not, and a parked cup is 13 of them (a state image of the paper's scenes: 3.9 ms, not 4.3).
HIDDEN_GROUP = 5
_ROBOT = 'contype="0" conaffinity="0"'


def slot_names() -> list[tuple[str, str]]:
    """(name, kind) of every object slot, in body order."""
    slots = [(f"cup{i}", "cup") for i in range(LIMITS.cups)]
    slots += [(f"ball{i}", "ball") for i in range(LIMITS.balls)]
    slots += [(f"support{i}", "support") for i in range(LIMITS.supports)]
    slots += [(f"block{i}", "block") for i in range(LIMITS.blocks)]
    return slots


def park_position(index: int) -> np.ndarray:
    """Where slot `index` waits while not in the scene: in mid-air, far from the camera and
    from every other parked thing, so a parked object costs no contacts."""
    return np.array([3.0 + 0.5 * index, 3.0, PARK_Z])


def _v(values) -> str:
    return " ".join(f"{float(v):.6g}" for v in values)


def _rx(angle: float) -> str:
    return _v([np.cos(angle / 2), np.sin(angle / 2), 0.0, 0.0])


def _cup_geoms(attrs: str, rgba=CUP.rgba, with_mass: bool = True, inflate: float = 0.0) -> str:
    """A hollow, tapered cup: a foot disc and a ring of wall slabs leaning outwards.

    The body origin is the cup's centre (mid-height on its axis): the point a grasp targets.
    Walls stand on the foot rather than reaching the table, so an upright cup touches the
    table with one geom, not thirteen: contacts are most of the cost of a physics step.
    """
    h, n = CUP.height + 2 * inflate, CUP.n_wall
    w = CUP.wall + 2 * inflate
    r_top, r_bot = CUP.radius + inflate, CUP.bottom_radius + inflate
    fr = f' friction="{CUP.friction} {PHYSICS.friction[1]} {PHYSICS.friction[2]}"'
    m_base = f' mass="{CUP.base_mass_fraction * CUP.mass:.5g}"{fr}' if with_mass else ""
    m_wall = f' mass="{(1 - CUP.base_mass_fraction) * CUP.mass / n:.5g}"{fr}' if with_mass else ""
    out = [
        f'<geom type="cylinder" size="{CUP.foot_radius + inflate:.5g} {CUP.base / 2 + inflate:.5g}"'
        f' pos="0 0 {-h / 2 + CUP.base / 2 + inflate:.5g}" rgba="{_v(rgba)}"{m_base} {attrs}/>'
    ]
    wall_h = h - CUP.base
    lean = np.arctan2(r_top - r_bot, wall_h)
    r_mid = (r_top + r_bot) / 2 - w / 2
    slab = r_top * np.tan(np.pi / n) * 1.08  # a little overlap closes the ring
    for k in range(n):
        a = 2 * np.pi * k / n
        # Turn to the slab's direction about z, then lean its top outwards about its own y.
        qz = np.array([np.cos(a / 2), 0.0, 0.0, np.sin(a / 2)])
        quat = np.array(
            [
                qz[0] * np.cos(lean / 2),
                -qz[3] * np.sin(lean / 2),
                qz[0] * np.sin(lean / 2),
                qz[3] * np.cos(lean / 2),
            ]
        )
        out.append(
            f'<geom type="box" size="{w / 2:.5g} {slab:.5g} {wall_h / 2 / np.cos(lean):.5g}"'
            f' pos="{r_mid * np.cos(a):.5g} {r_mid * np.sin(a):.5g} {CUP.base / 2:.5g}" quat="{_v(quat)}"'
            f' rgba="{_v(rgba)}"{m_wall} {attrs}/>'
        )
    return "\n".join(out)


def _object_geoms(kind: str, attrs: str, with_mass: bool = True, inflate: float = 0.0) -> str:
    """An object's geoms; `inflate` grows them (probe copies demand clearance, paper III.B)."""
    if kind == "cup":
        return _cup_geoms(attrs, with_mass=with_mass, inflate=inflate)
    if kind == "ball":
        mass = f' mass="{BALL.mass}"' if with_mass else ""
        fr = f"{PHYSICS.friction[0]} {PHYSICS.friction[1]} {BALL.rolling_friction}"
        # Priority above the block's: the ball's rolling friction (condim 6) then governs its
        # contact with the block too, so a ball placed on the block comes to rest there.
        return (
            f'<geom type="sphere" size="{BALL.radius + inflate:.5g}" rgba="{_v(BALL.rgba)}" condim="6"'
            f' priority="2"'
            f' friction="{fr}"{mass} {attrs}/>'
        )
    if kind == "support":
        foot_mass = SUPPORT.mass * SUPPORT.foot_mass_fraction
        post = f' mass="{SUPPORT.mass - foot_mass:.5g}"' if with_mass else ""
        foot = f' mass="{foot_mass:.5g}"' if with_mass else ""
        # The post stands on the foot, which alone meets the table: one box's contacts with it,
        # as a post alone had (two boxes down there cost 9% of the simulator's speed). The
        # support's lowest and highest points are the post's alone.
        foot_z = SUPPORT.foot_half[2] - SUPPORT.half[2]
        post_half = (*SUPPORT.half[:2], SUPPORT.half[2] - SUPPORT.foot_half[2])
        return (
            f'<geom type="box" size="{_v(post_half)}" pos="0 0 {SUPPORT.foot_half[2]:.5g}"'
            f' rgba="{_v(SUPPORT.rgba)}"{post} {attrs}/>\n'
            f'<geom type="box" size="{_v(SUPPORT.foot_half)}" pos="0 0 {foot_z:.5g}"'
            f' rgba="{_v(SUPPORT.rgba)}"{foot} {attrs}/>'
        )
    if kind == "block":
        mass = f' mass="{BLOCK.mass}"' if with_mass else ""
        fr = f"{BLOCK.friction} {PHYSICS.friction[1]} {PHYSICS.friction[2]}"
        return (
            f'<geom type="box" size="{_v(np.add(BLOCK.half, inflate))}" rgba="{_v(BLOCK.rgba)}" priority="1"'
            f' friction="{fr}"{mass} {attrs}/>'
        )
    raise ValueError(f"unknown object kind {kind!r}; expected one of cup, ball, support, block")


def _gripper_geoms(attrs: str, inflate: float = 0.0, fingers_open: bool = False) -> str:
    """Palm and two fingers in the hand frame (z = tool axis, x = finger opening direction)."""
    g = GRIPPER
    ph = [v + inflate for v in g.palm_half]
    fh = [v + inflate for v in g.finger_half]
    palm = f'<geom type="box" size="{_v(ph)}" pos="0 0 {g.palm_z:.5g}" rgba=".25 .25 .28 1" {attrs}/>'
    if fingers_open:
        fingers = "\n".join(
            f'<geom type="box" size="{_v(fh)}" pos="{s * g.open_half_width:.5g} 0 {g.finger_z:.5g}" {attrs}/>'
            for s in (-1, 1)
        )
        return palm + "\n" + fingers
    return palm


def _arm() -> str:
    """The UR3 as a chain of DH frames: body i is frame i-1 turned by joint q_i about its z."""
    u = UR3_DH
    lim = f'range="{-u.joint_limit:.5g} {u.joint_limit:.5g}"'
    link = f'rgba=".62 .66 .72 1" {_ROBOT}'
    joint = f'type="hinge" axis="0 0 1" {lim} armature="0.1" damping="1"'
    g = GRIPPER
    fingers = "\n".join(
        f"""<body name="{name}" pos="0 0 {g.finger_z:.5g}">
  <joint name="{name}" type="slide" axis="{s} 0 0" range="0 {g.open_half_width:.5g}"/>
  <geom type="box" size="{_v(g.finger_half)}" rgba=".2 .2 .22 1" mass="0.02" {_ROBOT}/>
</body>"""
        for name, s in (("finger_l", -1), ("finger_r", 1))
    )
    return f"""
<body name="base" pos="0 0 0">
  <geom type="cylinder" size="0.06 0.03" pos="0 0 0.03" rgba=".3 .32 .36 1" {_ROBOT}/>
  <body name="link1" pos="0 0 0" gravcomp="1">
    <joint name="q1" {joint}/>
    <geom type="capsule" fromto="0 0 0.02 0 0 {u.d1:.5g}" size="0.045" mass="0.5" {link}/>
    <body name="link2" pos="0 0 {u.d1:.5g}" quat="{_rx(np.pi / 2)}" gravcomp="1">
      <joint name="q2" {joint}/>
      <geom type="capsule" fromto="0 0 0 {u.a2:.5g} 0 0" size="0.04" mass="0.5" {link}/>
      <body name="link3" pos="{u.a2:.5g} 0 0" gravcomp="1">
        <joint name="q3" {joint}/>
        <geom type="capsule" fromto="0 0 0 {u.a3:.5g} 0 0" size="0.032" mass="0.3" {link}/>
        <body name="link4" pos="{u.a3:.5g} 0 0" gravcomp="1">
          <joint name="q4" {joint}/>
          <geom type="capsule" fromto="0 0 0 0 0 {u.d4:.5g}" size="0.03" mass="0.2" {link}/>
          <body name="link5" pos="0 0 {u.d4:.5g}" quat="{_rx(np.pi / 2)}" gravcomp="1">
            <joint name="q5" {joint}/>
            <geom type="capsule" fromto="0 0 0 0 0 {u.d5:.5g}" size="0.03" mass="0.2" {link}/>
            <body name="link6" pos="0 0 {u.d5:.5g}" quat="{_rx(-np.pi / 2)}" gravcomp="1">
              <joint name="q6" {joint}/>
              <geom type="cylinder" fromto="0 0 0 0 0 {u.d6:.5g}" size="0.03" mass="0.1" {link}/>
              <body name="hand" pos="0 0 {u.d6:.5g}" gravcomp="1">
                <geom type="cylinder" fromto="0 0 0 0 0 {g.coupling:.5g}" size="0.028" rgba=".3 .3 .33 1"
                      mass="0.1" {_ROBOT}/>
                {_gripper_geoms(f'mass="0.1" {_ROBOT}')}
                <site name="tcp" pos="0 0 {g.tcp_depth:.5g}" size="0.005" rgba="1 0 1 0"/>
                {fingers}
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </body>
</body>"""


def build_mjcf() -> str:
    """The whole scene's MJCF (table, floor, robot, object slots, probes, camera)."""
    t = TABLE
    objects = []
    welds = []
    for index, (name, kind) in enumerate(slot_names()):
        pos = park_position(index)
        objects.append(
            f'<body name="{name}" pos="{_v(pos)}">\n<freejoint name="{name}"/>\n'
            f"{_object_geoms(kind, _WORLD)}\n</body>"
        )
        if kind != "support":
            welds.append(
                f'<weld name="hold_{name}" body1="hand" body2="{name}" active="false"'
                f' solref="{_v(PHYSICS.weld_solref)}"/>'
            )
    probes = [
        f'<body name="probe_hand" mocap="true" pos="5 0 1">\n'
        f"{_gripper_geoms(_PROBE, inflate=GRIPPER.check_clearance, fingers_open=True)}\n</body>"
    ]
    for k, kind in enumerate(("cup", "ball", "block")):
        probes.append(
            f'<body name="copy_{kind}" mocap="true" pos="5 {1 + k} 1">\n'
            f"{_object_geoms(kind, _PROBE, with_mass=False, inflate=GRIPPER.check_clearance)}\n</body>"
        )
    cx, cy, cz = CAMERA.pos
    return f"""<mujoco model="afford_tabletop">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{PHYSICS.timestep}" cone="elliptic" impratio="5"/>
  <visual>
    <quality shadowsize="0"/>
    <headlight ambient=".35 .35 .35" diffuse=".35 .35 .35" specular="0 0 0"/>
    <global offwidth="{CAMERA.size}" offheight="{CAMERA.size}"/>
  </visual>
  <default>
    <geom friction="{_v(PHYSICS.friction)}" solref="0.004 1" solimp="0.95 0.99 0.001"/>
  </default>
  <worldbody>
    <light pos="0.3 0.1 2" dir="-0.15 0.1 -1" diffuse=".3 .3 .3" specular="0 0 0" castshadow="false"/>
    <camera name="top" pos="{cx} {cy} {cz}" fovy="{CAMERA.fovy}"/>
    <geom name="floor" type="box" size="2 2 0.05" pos="0 0 {t.floor_z - 0.05}" rgba=".3 .3 .3 1" {_WORLD}/>
    <geom name="table" type="box" size="{t.half[0]} {t.half[1]} {t.thickness / 2}"
          pos="{t.centre[0]} {t.centre[1]} {-t.thickness / 2}" rgba=".72 .70 .64 1" {_WORLD}/>
    {_arm()}
    {"".join(objects)}
    {"".join(probes)}
  </worldbody>
  <equality>
    {"".join(welds)}
  </equality>
</mujoco>"""
