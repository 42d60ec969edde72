"""The world's phases of a tick: sensing, motion and collisions, handling, orders, urgency."""
