"""What a run leaves behind: trajectories, pictures and MCAP files."""
