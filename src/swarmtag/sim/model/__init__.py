"""The simulation's data and its step: parameters, state, scenes, random streams, events."""
