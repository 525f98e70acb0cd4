"""Independent references raycast is checked against: the object-space quadric tracer,
mpmath truths, outside readings of the files (usd-core, trimesh, Open3D), Embree and
trimesh's ray casts."""
