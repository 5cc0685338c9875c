"""Drivers that make image sets, contact sheets, figures and CSV reports from the models and
effects below them: the day's timelapse, twilight, polarisation maps and model comparisons.

Nothing below this layer imports it.
"""
