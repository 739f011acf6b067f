"""What the goal grammar's words mean, table by table: nouns by the kind of object they name,
order words by the place they pick, determiners by how many they name, turns by their angle.

The grammar (`grammar.py`) says where each word may stand; `parses.py` builds a parse's
meaning from these tables, and `reference.py` resolves it in a scene.
"""

from __future__ import annotations

# Nouns by the kind they name; None: any kind ("the red one", "everything").
KINDS = {
    "cup": "cup",
    "mug": "cup",
    "ball": "ball",
    "sphere": "ball",
    "support": "support",
    "pillar": "support",
    "pedestal": "support",
    "block": "block",
    "brick": "block",
    "plank": "block",
    "beam": "block",
    "bar": "block",
    "board": "block",
    "slab": "block",
    "post": "support",
    "stand": "support",
    "column": "support",
    "pole": "support",
    "cylinder": "support",
    "glass": "cup",
    "marble": "ball",
    "one": None,
    "thing": None,
    "object": None,
}
# Order words, each an (axis, rank) among the objects a noun phrase fits, the axis from the
# camera: "x" counts from the left (a negative rank from the right), "y" from the front.
# "middle" is the middle one of an odd number.
ORDER = {
    "left": ("x", 0),
    "leftmost": ("x", 0),
    "first": ("x", 0),
    "second": ("x", 1),
    "third": ("x", 2),
    "fourth": ("x", 3),
    "right": ("x", -1),
    "rightmost": ("x", -1),
    "last": ("x", -1),
    "middle": ("x", None),
    "mid": ("x", None),
    "centre": ("x", None),
    "center": ("x", None),
    "central": ("x", None),
    "front": ("y", 0),
    "near": ("y", 0),
    "nearest": ("y", 0),
    "closest": ("y", 0),
    "nearer": ("y", 0),
    "closer": ("y", 0),
    "back": ("y", -1),
    "rear": ("y", -1),
    "far": ("y", -1),
    "farthest": ("y", -1),
    "furthest": ("y", -1),
    "farther": ("y", -1),
    "further": ("y", -1),
    "outer": ("x", "ends"),
    "outside": ("x", "ends"),
    "outermost": ("x", "ends"),
}
PLACES = {  # "the cup on the left": an order word said after the noun
    "left": "left",
    "right": "right",
    "middle": "middle",
    "centre": "middle",
    "center": "middle",
    "front": "front",
    "back": "back",
}
COLOUR_WORDS = ("blue", "red", "black", "yellow")
# Plural nouns by their singular: "glasses" is not "glasse".
PLURAL_NOUNS = {"glasses": "glass", "marbles": "marble"}
# A turn by its angle in degrees: a quarter turn changes how the block lies, a half turn
# leaves it as it was; no angle ("turn the block") is a quarter turn.
TURNS = {"quarter": 90, "half": 180, "around": 180, "ninety": 90}


# Determiners by the quantity they give a singular and a plural noun ("the cup": one, "the
# cups": every); a number word among them ("the two cups") counts the plural.
DETERMINERS = {
    **dict.fromkeys(("the", "this", "that", "my"), ("one", "every")),
    **dict.fromkeys(("a", "an", "any"), ("some", "every")),
    "one of the": ("some", "some"),
    **dict.fromkeys(("every", "each"), ("every", "every")),
    **dict.fromkeys(("all", "all the", "all of the", "each of the", "any of the"), ("every", "every")),
    **dict.fromkeys(("both", "both the", "both of the"), ("both", "both")),
    **dict.fromkeys(("no", "none of the", "neither"), ("none", "none")),
    "either": ("every", "every"),
    "the other": ("one", "every"),
    **dict.fromkeys(("its", "their"), ("one", "every")),
}
