"""Helpers shared by the tests: analytic meshes, model paths, result and page comparisons, the bad-input table,
reference systems and signals, real processes and servers."""
