"""Benchmarks run by ``mcgeom bench``: timings against references, printed as ratios."""
