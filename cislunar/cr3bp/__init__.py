"""The circular restricted three-body problem: dynamics, propagation, periodic orbits and quasi-periodic tori."""
