"""The tree search of paper II.D on a toy world model: a marker on a line of cells."""

import numpy as np
import pytest

from afford.planning.goal import Goal
from afford.planning.strategies import search
from afford.planning.tree import SearchConfig, WorldModel, edges
from afford.sim.affordance import Affordance, Detection

CELLS = 8
QUIET = SearchConfig(progress=False)


def picture(p: int) -> np.ndarray:
    """A (8, 4 * CELLS, 4) image, white square in cell p."""
    img = np.zeros((8, 4 * CELLS, 4), dtype=np.float32)
    img[2:6, 4 * p : 4 * p + 4] = 1.0
    return img


class LineWorld(WorldModel):
    """State p; a 'grasp' at x moves the marker to cell x; a turn moves it by +-1. Every
    cell's grasp comes twice (symmetric duplicates at two gripper angles)."""

    def __init__(self, start: int = 0, blocked: int | None = None):
        self.start, self.blocked = start, blocked
        self.recognised = 0

    def root(self):
        return picture(self.start), self.start

    def recognise(self, nodes):
        self.recognised += len(nodes)
        out = []
        for n in nodes:
            p = n.state
            affs = []
            for q in (p - 2, p + 2):
                if 0 <= q < CELLS:
                    for angle, conf in ((0.0, 0.6), (90.0, 0.9)):
                        affs.append(Detection(Affordance("grasp", (float(q), 0.0, 0.0), angle, True), conf))
            affs.append(Detection(Affordance("turn", (float(p), 0.0, 0.0), 0.0, False)))
            out.append(affs)
        return out

    def predict(self, parents, actions):
        out = []
        for parent, a in zip(parents, actions, strict=True):
            p = int(a.position[0]) if a.type == "grasp" else parent.state + (1 if a.turn > 0 else -1)
            out.append(None if not 0 <= p < CELLS or p == self.blocked else (picture(p), p))
        return out


def test_edges_keep_most_confident_symmetric_duplicate_and_fill_in_turns():
    rec = LineWorld().recognise([type("N", (), {"state": 3})()])[0]
    e = edges(rec, merge_radius=0.01)
    grasps = [a for a in e if a.type == "grasp"]
    assert sorted(a.position[0] for a in grasps) == [1.0, 5.0]
    assert all(a.angle == 90.0 for a in grasps)  # the 0.9-confidence duplicate of each
    assert sorted(a.turn for a in e if a.type == "turn") == [-90, 90]


def test_search_finds_the_shortest_plan_to_a_positive_goal():
    world = LineWorld(start=0)
    goal = Goal(picture(5)[..., :3].copy())  # the whole picture: one window, one place
    r = search(world, goal, max_steps=4, config=QUIET)
    assert r.loss < 1e-9
    assert r.nodes[r.best].state == 5
    assert len(r.plan) == 3  # e.g. +2, +2, +1: no 2-step plan reaches an odd cell
    assert r.per_depth[1] == 2  # one grasp (its duplicate merged), one turn (the other is pruned)
    assert world.recognised == sum(r.per_depth[:-1])  # leaves are never recognised


def test_search_batches_and_prunes_impossible_children():
    world = LineWorld(start=0, blocked=1)
    r = search(
        world,
        Goal(picture(1)[:, :12, :3].copy()),
        max_steps=3,
        config=SearchConfig(batch_size=2, progress=False),
    )
    assert all(n.state != 1 for n in r.nodes)  # cell 1 cannot be entered
    assert r.nodes[r.best].state != 1


def test_negative_goal_takes_the_state_least_like_the_patch():
    world = LineWorld(start=2)
    patch = picture(2)[:, 4:16, :3].copy()  # the marker where it starts, with dark around it
    r = search(world, Goal(patch, negative=True), max_steps=2, config=QUIET)
    assert r.nodes[r.best].state != 2
    assert r.loss == max(n.loss for n in r.nodes)


def test_ties_go_to_the_shorter_plan():
    world = LineWorld(start=0)
    r = search(world, Goal(picture(2)[..., :3].copy()), max_steps=3, config=QUIET)
    assert r.nodes[r.best].state == 2 and len(r.plan) == 1
    assert [n.state for n in r.path()] == [0, 2]


class SlowWorld(LineWorld):
    """LineWorld whose every prediction takes a while: the time limit must stop the tree."""

    def predict(self, parents, actions):
        import time

        time.sleep(0.005 * len(parents))
        return super().predict(parents, actions)


def test_time_limit_stops_the_tree_and_still_plans():
    goal = Goal(picture(4))
    free = search(SlowWorld(), goal, 3, SearchConfig(progress=False, batch_size=1))
    assert not free.truncated and len(free.per_depth) == 4
    cut = search(SlowWorld(), goal, 3, SearchConfig(progress=False, batch_size=1, time_limit=0.02))
    assert cut.truncated and len(cut.nodes) < len(free.nodes)
    assert cut.best < len(cut.nodes)  # a plan from the states grown so far


def test_a_tree_past_its_node_limit_is_refused_before_it_is_grown():
    from afford.planning.tree import TreeTooLarge

    world = LineWorld()
    full = search(world, Goal(picture(4)), 3, SearchConfig(progress=False))
    limit = full.per_depth[0] + full.per_depth[1] + 1  # room for depth 1, not for depth 2
    world = LineWorld()
    with pytest.raises(TreeTooLarge, match=r"depth 2 would add .* states .*limit"):
        search(world, Goal(picture(4)), 3, SearchConfig(progress=False, max_nodes=limit))
    assert world.recognised <= 1 + full.per_depth[1]  # depth 2 was never predicted


def test_a_deep_tree_is_refused_after_two_depths_with_its_estimate():
    from afford.planning.strategies import whole_tree
    from afford.planning.tree import TreeTooLarge

    assert whole_tree([1, 5, 25], 4) == (1 + 5 + 25 + 125 + 625, 5.0)
    world = LineWorld()
    three = search(world, Goal(picture(4)), 3, SearchConfig(progress=False))
    estimate, _ = whole_tree(three.per_depth[:3], 8)
    world = LineWorld()
    with pytest.raises(TreeTooLarge, match=r"a tree of 8 steps would hold about [\d,]+ states .*depth 2"):
        search(world, Goal(picture(4)), 8, SearchConfig(progress=False, max_nodes=int(estimate / 2) - 1))
    assert world.recognised <= sum(three.per_depth[:2])  # refused once depth 2 was grown
    fits = search(
        LineWorld(), Goal(picture(4)), 3, SearchConfig(progress=False, max_nodes=len(three.nodes) + 2)
    )
    assert len(fits.nodes) == len(three.nodes)  # a tree that fits is grown whole
