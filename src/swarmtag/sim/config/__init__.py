"""The scenario and what it is built from: its parts, sensors, warehouse floors, profiles."""
