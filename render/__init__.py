"""Mesh rendering with the global SHRM through a pyvista/VTK GLSL shader (DESIGN §5)."""
