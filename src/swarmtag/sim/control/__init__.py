"""The controller interface (three control steps a tick) and the rules controllers share."""
