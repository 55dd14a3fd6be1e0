"""Populations of measured eyes: a run's files (each eye's numbers, their quantiles, the gap table, the figure)."""
