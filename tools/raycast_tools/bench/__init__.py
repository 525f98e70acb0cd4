"""Benchmarks against the peers (Embree, Open3D, trimesh, obvhs) and the reports they write,
with the machine description they share."""
