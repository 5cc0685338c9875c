"""Integrations of skydome's exports into other programs (the Blender add-on, three.js)."""
