"""The scene on the CPU: procedural shapes, scene build, camera, deformation, GPU packing (NumPy only)."""
