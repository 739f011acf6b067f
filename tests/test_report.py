"""The plan report (viz/report.py): one HTML node per state grown, each with its image."""

from html.parser import HTMLParser

from helpers import StepWorld, bar
from test_closed_loop import Reach, SlipWorld

from afford.planning.closed_loop import closed_loop
from afford.planning.goal import Goal
from afford.planning.run import Outcome
from afford.planning.strategies import search
from afford.planning.tree import SearchConfig
from afford.viz.report import report_html


class Nodes(HTMLParser):
    """Collects each state's summary: its node index, whether it has an image, chosen or not."""

    def __init__(self):
        super().__init__()
        self.nodes: list[dict] = []
        self.open: list[bool] = []  # the enclosing details' "chosen" marks
        self.scripts = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "details":
            self.open.append(a.get("class") == "chosen")
        elif tag == "summary" and "data-node" in a:
            self.nodes.append({"index": int(a["data-node"]), "image": False, "chosen": self.open[-1]})
        elif tag == "img" and self.nodes and a.get("src", "").startswith("data:image/jpeg;base64,"):
            if not self.nodes[-1]["image"]:
                self.nodes[-1]["image"] = True
        elif tag == "script":
            self.scripts += 1

    def handle_endtag(self, tag):
        if tag == "details":
            self.open.pop()


def outcome_of(result, **extra):
    return Outcome(
        "toy", "learned", result.plan, [bar(0)], [bar(0)], True, len(result.nodes) - 1, 0.1, **extra
    )


def test_the_report_holds_every_state_grown_with_its_image_and_marks_the_chosen_path():
    goal = Goal(bar(4))
    result = search(StepWorld(), goal, 2, SearchConfig(progress=False))
    parser = Nodes()
    parser.feed(report_html(outcome_of(result, search=result), goal))
    assert sorted(n["index"] for n in parser.nodes) == list(range(len(result.nodes)))
    assert all(n["image"] for n in parser.nodes)
    chosen = {n["index"] for n in parser.nodes if n["chosen"]}
    assert chosen == {
        0,
        *(i for i, n in enumerate(result.nodes) if n.plan and n.plan == result.plan[: n.depth]),
    }
    assert parser.scripts == 1


def test_a_closed_loop_report_has_one_tree_per_round():
    goal = Goal(bar(4))
    world = SlipWorld()
    loop = closed_loop(
        world, lambda steps: search(Reach(world.p), goal, steps, SearchConfig(progress=False)), 5
    )
    html = report_html(outcome_of(loop.last, loop=loop), goal)
    assert html.count('<div class="tree">') == len(loop.steps) + 1
    assert html.count('<div class="observed">') == len(loop.steps)
