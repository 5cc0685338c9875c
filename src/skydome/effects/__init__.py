"""Atmospheric effects: aerial perspective, twilight, polarisation, aureole, ..."""
