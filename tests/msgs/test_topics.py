"""Topic names: base names under any namespace, and which topics are maps or requests."""

from __future__ import annotations

from drd_msgs_py.topics import MAP_TOPICS, REQUEST_TOPICS, topic_base


def test_the_base_name_ignores_namespaces_and_trailing_slashes() -> None:
    assert topic_base("/robot1/obstacles") == "obstacles"
    assert topic_base("terrain/") == "terrain"
    assert topic_base("goal_pose") == "goal_pose"
    assert {"obstacles", "terrain", "robot_description"} == MAP_TOPICS
    assert not MAP_TOPICS & REQUEST_TOPICS
