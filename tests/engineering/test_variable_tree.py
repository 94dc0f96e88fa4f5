"""Finding variables: the instance tree of the paths and the search, best match first."""

from __future__ import annotations

from backend.engineering import variable_tree

PATHS = [
    "TankControl.level",
    "TankControl.lowLevel",
    "TankControl.refillDelay.ET",
    "TankControl.refillDelay.Q",
    "TankControl.pump",
    "Mixer.steps.Fill.X",
    "gPoints[2].x",
    "gLevel",
]


def test_the_instances_are_every_path_with_members_parents_first() -> None:
    assert variable_tree.instances(PATHS) == [
        "gPoints[2]",
        "Mixer",
        "Mixer.steps",
        "Mixer.steps.Fill",
        "TankControl",
        "TankControl.refillDelay",
    ]


def test_below_an_instance_are_its_variables_at_any_depth() -> None:
    assert variable_tree.below(PATHS, "TankControl.refillDelay") == [
        "TankControl.refillDelay.ET",
        "TankControl.refillDelay.Q",
    ]
    assert len(variable_tree.below(PATHS, "TankControl")) == 5
    assert variable_tree.below(PATHS, "Tank") == []  # a prefix of a name is no instance


def test_search_puts_the_variable_named_so_first_and_counts_all() -> None:
    assert variable_tree.search(PATHS, "level", 10) == (
        ["TankControl.level", "gLevel", "TankControl.lowLevel"],
        3,
    )
    assert variable_tree.search(PATHS, "refill q", 10) == (["TankControl.refillDelay.Q"], 1)
    assert variable_tree.search(PATHS, "LEV", 1) == (["TankControl.level"], 3)
    assert variable_tree.search(PATHS, "   ", 10) == ([], 0)


def test_a_search_of_megabytes_reads_only_its_start() -> None:
    found, count = variable_tree.search(PATHS * 1000, "level " + "x " * 500_000, 10)
    assert (found, count) == ([], 0)  # the words after the first 200 characters are ignored
    assert variable_tree.search(PATHS, "level" + " " * 300 + "nothing", 10)[1] == 3
