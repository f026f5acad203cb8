"""Analysis of simulated or measured responses."""
