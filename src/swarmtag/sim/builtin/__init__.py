"""The built-in controller: every robot of a batch decides at once, in numpy."""
