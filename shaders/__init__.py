"""GLSL sources (data)."""
