"""Simulation-based sky models (single scattering, Nishita, Bruneton-style, Monte Carlo, ...)."""
