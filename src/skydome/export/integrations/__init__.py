"""Integrations of skydome's exports into other programs (the Blender add-on)."""
