"""The oracle and the canonical-symbolic planner on small real tasks, and their CLI."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import GOOD

from afford.planning.run import PlannerConfig, solve
from afford.planning.symbolic import CanonicalWorld, plan_symbolic
from afford.planning.tasks import load_task, task_from_json
from afford.planning.tree import SearchConfig
from afford.sim.affordances import Affordance
from afford.sim.scene import ObjectSpec

ROOT = Path(__file__).parents[1]
PAPER = ROOT / "tasks" / "paper"


def test_oracle_solves_a_two_step_task(scene):
    task = task_from_json(GOOD, scene=scene)
    o = solve(task, "oracle", scene, PlannerConfig(search=SearchConfig(progress=False)))
    assert o.success and [a.type for a in o.plan] == ["grasp", "place"]
    assert o.nodes == 2 and len(o.planned) == 3 and len(o.executed) == 3


def test_canonical_effects(scene):
    specs = [
        ObjectSpec.upright("cup", 0.09, 0.3, z=0.05),
        ObjectSpec.upright("block", 0.0, 0.3),
        ObjectSpec.upright("support", 0.12, 0.2),
    ]
    world = CanonicalWorld(scene, specs, ["cup0", "block0", "support0"])
    assert dict(world.start.hosts) == {"cup0": "block0"}
    turned = world.apply(world.start, Affordance("turn", (0.0, 0.3, 0.025), 90.0, False, 90))
    np.testing.assert_allclose(turned.pose("cup0").pos[:2], [0.0, 0.39], atol=1e-6)  # rides along
    held = world.apply(turned, Affordance("grasp", turned.pose("cup0").pos, 0.0, True))
    assert held.held == "cup0"
    placed = world.apply(held, Affordance("place", (0.12, 0.2, 0.06), 0.0, True))
    assert placed.held is None and dict(placed.hosts)["cup0"] == "support0"
    np.testing.assert_allclose(placed.pose("cup0").pos, [0.12, 0.2, 0.06 + 0.0425], atol=2e-3)


def test_symbolic_plans_task_1_and_cannot_make_a_ball_vanish(scene):
    t1 = load_task(PAPER / "01-order.json", scene)
    r = plan_symbolic(scene, t1.scene, t1.object_names(), t1.success, t1.max_steps)
    assert [a.type for a in r.plan] == ["grasp", "place", "grasp", "place"]
    t10 = load_task(PAPER / "10-hide.json", scene)
    assert plan_symbolic(scene, t10.scene, t10.object_names(), t10.success, t10.max_steps).plan is None


def afford(*args):
    return subprocess.run(
        [sys.executable, "-m", "afford.cli.main", *args], capture_output=True, text=True, cwd=ROOT
    )


def here(capsys, *args):
    """The CLI in this process (no interpreter start-up): the same result as `afford`."""
    from afford.cli.main import main

    capsys.readouterr()
    code = main(list(args))
    out = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out.out, out.err)


def test_plan_cli_symbolic_writes_picture_and_record(tmp_path):
    r = afford(
        "plan",
        "--task",
        str(PAPER / "03-stable-base.json"),
        "--planner",
        "symbolic",
        "--out",
        str(tmp_path),
        "--json",
    )
    assert r.returncode == 1, r.stderr  # planned, executed, and the block tipped
    record = json.loads(r.stdout)
    assert record["solved"] is False and "non-canonical" in record["reason"]
    assert Path(record["picture"]).stat().st_size > 1000


def test_plan_cli_rejects_bad_task_in_one_line(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({**GOOD, "max_steps": "four"}))
    r = afford("plan", "--task", str(bad))
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "max_steps" in r.stderr


def test_bench_tasks_cli_tables_a_folder(tmp_path, capsys):
    (tmp_path / "toy.json").write_text(json.dumps(GOOD))
    r = here(capsys, "bench", "tasks", "--planner", "oracle", "--tasks", str(tmp_path), "--json")
    assert r.returncode == 0, r.stderr
    table = json.loads(r.stdout)["oracle"]
    assert table["solved"] == 1 and table["tasks"][0]["plan_length"] == 2
    assert table["tasks"][0]["nodes"] > 0 and table["tasks"][0]["reason"] == ""
    empty = here(capsys, "bench", "tasks", "--tasks", str(tmp_path / "none"))
    assert empty.returncode == 2 and "no task files" in empty.stderr


def test_bench_tasks_counts_each_folder_apart(tmp_path, capsys):
    for name, steps in (("a", 2), ("b", 1)):  # one step cannot both grasp and place
        (tmp_path / name).mkdir()
        (tmp_path / name / "toy.json").write_text(json.dumps({**GOOD, "max_steps": steps}))
    folders = f"{tmp_path / 'a'},{tmp_path / 'b'}"
    r = here(capsys, "bench", "tasks", "--planner", "oracle", "--tasks", folders, "--json")
    assert r.returncode == 0, r.stderr
    counts = json.loads(r.stdout)["oracle"]["folders"]
    assert counts == {
        str(tmp_path / "a"): {"solved": 1, "tasks": 1},
        str(tmp_path / "b"): {"solved": 0, "tasks": 1},
    }


def test_random_tasks_are_not_solved_by_doing_nothing(scene):
    from afford.planning.judge import execute_plan
    from afford.planning.random_tasks import random_task

    made = [t for t in (random_task(scene, seed, max_steps=2) for seed in range(4)) if t is not None]
    assert made
    for task in made:
        scene.reset(task.scene)
        assert not task.success.holds(scene)  # the start is not already the goal
        assert task.goal.patch.shape[0] >= 16 and task.goal.patch.shape[2] == 4
        # The root image is scored against the goal like any other state: a finite loss.
        assert np.isfinite(task.goal.loss(scene.observe()[None])[0])
        assert execute_plan(scene, task.scene, (), task.success).success is False


def test_long_random_tasks_hold_at_least_min_steps_executions(scene):
    from afford.planning.random_tasks import random_task

    made = [t for t in (random_task(scene, seed, max_steps=6, min_steps=5) for seed in range(3)) if t]
    assert made and all(5 <= t.max_steps <= 6 for t in made)


def test_a_random_start_the_scene_checks_refuse_makes_no_task(scene):
    """Seed 49 settles with a ball at rest on a lying cup's side, which the checks' rays miss:
    the seed is skipped, not a crash of the whole benchmark."""
    from afford.planning.random_tasks import random_task
    from afford.sim.layout import random_layout
    from afford.sim.specs import SceneError

    scene.reset(random_layout(np.random.default_rng([49, 7])), check=False)
    with pytest.raises(SceneError, match="floats"):
        scene.reset(scene.specs())
    assert random_task(scene, 49, max_steps=3) is None


@pytest.mark.slow
def test_symbolic_baseline_is_judged_by_all_its_equally_short_plans(scene):
    # Task 4 (ball first, then cup): canonically the two orders are equally short, and only one
    # keeps the block balanced. The baseline is judged by both, whatever the scan order.
    t4 = load_task(PAPER / "04-counterbalance-ball-first.json", scene)
    r = plan_symbolic(scene, t4.scene, t4.object_names(), t4.success, t4.max_steps)
    assert r.total == 2 and len(r.plans) == 2 and len(set(r.plans)) == 2
    assert r.plans[0][0].position != r.plans[1][0].position  # ball first in one, cup in the other
    o = solve(t4, "symbolic", scene)
    assert o.success_rate == 0.5 and o.tried == 2 and o.total == 2
    # The seed picks which one is reported, not the score.
    other = plan_symbolic(scene, t4.scene, t4.object_names(), t4.success, t4.max_steps, seed=1)
    assert set(other.plans) == set(r.plans)


def test_wilson_interval():
    from afford.planning.random_bench import wilson

    lo, hi = wilson(50, 100)
    assert lo < 0.5 < hi and abs((0.5 - lo) - (hi - 0.5)) < 1e-9 and abs(hi - lo - 0.1924) < 1e-3
    assert wilson(0, 20)[0] == 0.0 and wilson(20, 20)[1] == 1.0 and wilson(20, 20)[0] > 0.8


def test_bench_random_cli_gives_intervals(tmp_path, capsys):
    out = tmp_path / "random.json"
    r = here(
        capsys,
        "bench", "random", "--n", "2", "--max-steps", "1", "--planner", "symbolic",
        "--workers", "1", "--json", "--out", str(out),
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)["summary"]["symbolic"]
    assert 0 <= summary["ci95"][0] <= summary["success"] <= summary["ci95"][1] <= 1
    assert json.loads(out.read_text())["n"] == 2
    bad = here(capsys, "bench", "random", "--time-limit", "0")
    assert bad.returncode == 2 and "--time-limit" in bad.stderr


def test_plan_cli_refuses_a_huge_tree_in_one_line(tmp_path, capsys):
    deep = tmp_path / "deep.json"
    deep.write_text(json.dumps({**json.loads((PAPER / "01-order.json").read_text()), "max_steps": 8}))
    r = here(capsys, "plan", "--task", str(deep), "--max-nodes", "30", "--out", str(tmp_path), "--json")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "would add" in r.stderr and "--max-nodes" in r.stderr


def test_search_options_out_of_range_are_refused_in_one_line(capsys):
    task = str(PAPER / "01-order.json")
    for args, named in (
        (("plan", "--task", task, "--search", "beam", "--beam-width", "0"), "--beam-width"),
        (("plan", "--task", task, "--budget", "0"), "--budget"),
        (("plan", "--task", task, "--planner", "hybrid", "--accept", "1.5"), "--accept"),
        (("bench", "random", "--min-steps", "3", "--max-steps", "2"), "--min-steps"),
        (("bench", "tasks", "--planner", "learned,psychic"), "psychic"),
    ):
        r = here(capsys, *args)
        assert r.returncode == 2 and named in r.stderr and r.stderr.count("\n") == 1, args


@pytest.mark.slow
def test_bench_random_gives_the_same_tasks_and_results_on_two_workers():
    import torch

    from afford.planning.random_bench import BenchSpec, run

    threads = torch.get_num_threads()
    spec = BenchSpec(max_steps=1, planners=("symbolic",))
    one = list(run(spec, 3, first_seed=0, workers=1))  # in this process: it sets torch's threads
    torch.set_num_threads(threads)
    two = list(run(spec, 3, first_seed=0, workers=2))
    assert [r["seed"] for r in one] == [r["seed"] for r in two]
    assert [r["symbolic"]["score"] for r in one] == [r["symbolic"]["score"] for r in two]


def test_closed_loop_oracle_plans_acts_and_stops_on_an_empty_plan(scene):
    task = task_from_json(GOOD, scene=scene)
    config = PlannerConfig(search=SearchConfig(progress=False), closed_loop=True)
    o = solve(task, "oracle", scene, config)
    assert o.success and [a.type for a in o.plan] == ["grasp", "place"]
    rounds = o.to_dict()["closed_loop"]["rounds"]
    assert [r["action"]["type"] for r in rounds] == ["grasp", "place"]
    assert all(r["gap"] < 1e-6 for r in rounds)  # the simulator foresees itself
    assert len(o.planned) == len(o.executed) == 3 and o.loop.stopped == "budget"


def test_closed_loop_refuses_the_symbolic_planner_in_one_line():
    r = afford("plan", "--task", str(PAPER / "10-hide.json"), "--planner", "symbolic", "--closed-loop")
    assert r.returncode == 2 and "no world model" in r.stderr and "Traceback" not in r.stderr


def test_every_planner_name_has_one_record_and_the_command_line_takes_its_names_from_it():
    from afford.cli.main import build_parser
    from afford.cli.options import planners, planners_help
    from afford.planning.run import CLOSED_LOOP, PLANNER_REGISTRY, PLANNERS, USES_NETS, Planner
    from afford.shipped import KINDS, Nets

    assert PLANNERS == tuple(PLANNER_REGISTRY) and len(set(PLANNERS)) == len(PLANNERS)
    for name, record in PLANNER_REGISTRY.items():
        assert isinstance(record, Planner) and record.about, name
        assert set(record.needs) <= set(KINDS) and all(hasattr(Nets, k) for k in record.needs), name
        # what the registry's derived lists say agrees with the record
        assert (name in CLOSED_LOOP) == (record.closed_loop is not None), name
        assert (name in USES_NETS) == bool(record.needs), name
    # the planners that grow a learned world model are the ones that need nets
    assert {"learned", "objects", "objects-true", "perceived-sim"} <= {
        n for n, p in PLANNER_REGISTRY.items() if p.needs
    }
    for name in PLANNERS:  # `afford plan` takes every name, and no other
        assert build_parser().parse_args(["plan", "--task", "t.json", "--planner", name]).planner == name
    with pytest.raises(SystemExit):
        build_parser().parse_args(["plan", "--task", "t.json", "--planner", "nope"])
    assert planners("all") == PLANNERS and all(n in planners_help() for n in PLANNERS)
