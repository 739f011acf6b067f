"""The premises of the risk tasks in tasks/uncertain/ (01, 04, 05): the plan the goal
image asks for holds unperturbed, and a few millimetres off it the side effect follows."""

from afford.planning.tasks import load_task
from afford.sim.resting import rests_on
from afford.sim.scene import ObjectSpec


def _shifted(specs, kinds, dx: float, dy: float = 0.0):
    return [
        ObjectSpec(s.kind, (s.pos[0] + dx, s.pos[1] + dy, s.pos[2]), s.quat) if s.kind in kinds else s
        for s in specs
    ]


def test_the_tipping_edge_task_holds_unperturbed_and_tips_when_the_pile_shifts(scene):
    """The premise of tasks/uncertain/01: the cup placed at the block's right end stays up as
    planned, but lands too far out when the pile stands 6 mm left of where the plan aimed: the
    block tips under it and throws it off (the task's success check fails)."""
    task = load_task("tasks/uncertain/01-cup-near-a-tipping-edge.json", scene)
    scene.reset(task.scene)
    grasp = next(a for a in scene.affordances() if a.type == "grasp")
    scene.execute(grasp)
    end = next(a for a in scene.affordances() if a.type == "place" and a.position[0] > 0.08)
    shifted = [
        s if s.kind == "cup" else ObjectSpec(s.kind, (s.pos[0] - 0.006, *s.pos[1:]), s.quat)
        for s in task.scene
    ]
    for start, holds in ((task.scene, True), (shifted, False)):
        scene.reset(start)
        assert scene.execute(grasp).executed and scene.execute(end).executed
        assert (rests_on(scene, "cup0", "block0") and rests_on(scene, "block0", "support0")) == holds


def test_the_ball_aboard_rolls_off_when_the_cup_tips_the_block(scene):
    task = load_task("tasks/uncertain/04-ball-aboard-a-tipping-block.json", scene)
    scene.reset(task.scene)
    grasp = next(a for a in scene.affordances() if a.type == "grasp" and a.position[1] < 0.25)
    scene.execute(grasp)
    end = next(a for a in scene.affordances() if a.type == "place" and a.position[0] > 0.08)
    centre = next(a for a in scene.affordances() if a.type == "place" and abs(a.position[0]) < 0.01)
    pile = ("support", "block", "ball")
    for start, place, holds in (
        (task.scene, end, True),
        (_shifted(task.scene, pile, -0.006), end, False),
        (_shifted(task.scene, pile, -0.006), centre, True),
    ):
        scene.reset(start)
        assert scene.execute(grasp).executed and scene.execute(place).executed
        assert rests_on(scene, "cup0", "block0") == holds
        assert rests_on(scene, "ball0", "block0") == holds
        if not holds:
            assert scene.object("ball0").pos[0] > 0.1  # rolled down the tipped block, off its right end


def test_the_cup_in_the_sweep_topples_one_way_round_only(scene):
    task = load_task("tasks/uncertain/05-cup-in-a-turning-block-s-sweep.json", scene)
    scene.reset(task.scene)
    turn = next(a for a in scene.affordances() if a.type == "turn")
    start = next(s for s in task.scene if s.kind == "cup").pos
    closer = _shifted(task.scene, ("cup",), -0.002, -0.0035)  # 4 mm nearer the block's centre
    for specs, angle, stays in ((task.scene, 90, True), (closer, 90, False), (closer, -90, True)):
        scene.reset(specs)
        assert scene.execute(turn.with_turn(angle)).executed
        assert abs(abs(scene.object("block0").yaw_deg) - 90) < 5
        cup = scene.object("cup0")
        moved = ((cup.pos[0] - start[0]) ** 2 + (cup.pos[1] - start[1]) ** 2) ** 0.5
        assert (cup.up_axis[2] > 0.9 and moved < 0.01) == stays
