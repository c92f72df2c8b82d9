"""Topic names of the planner's interface, without any message library: which topics are maps or requests."""

from __future__ import annotations

__all__ = ["MAP_TOPICS", "REQUEST_TOPICS", "topic_base"]

#: Topics whose latest message is the map (replayed reliable + transient_local, depth 1).
MAP_TOPICS = frozenset({"obstacles", "terrain", "robot_description"})
#: Topics that are planning requests.
REQUEST_TOPICS = frozenset({"goal_pose", "goal_joints"})


def topic_base(topic: str) -> str:
    """The last name of a topic (``/robot1/obstacles`` -> ``obstacles``)."""
    return topic.rstrip("/").rsplit("/", 1)[-1]
