"""FCL scenes, terrain, wires, robot models and edge checkers (populated by the real-worlds work)."""
