"""Builders and checks of the renderer's meshes, run by scripts/make_meshes.py."""
