"""Helpers shared by the tests: analytic meshes, model paths, result and page comparisons."""
