"""Test pass implementations: a compute scale and a full-screen raster blit (real shaders)."""
