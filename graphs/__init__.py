"""Bundled graphs and scenes (data)."""
