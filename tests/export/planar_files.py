"""A planar machine file the export formats refuse: two single rods (the platform could turn)."""

TWO_RODS = """
[machine]
kind = "rod-legs"
dims = 2
home = [1.0, 0.0]
[[legs]]
base = [0, 0]
axis = [1, 0]
platform = [0, 0]
length = 0.5
branch = -1
[[legs]]
base = [1, -1]
axis = [0, 1]
platform = [0, 0]
length = 0.5
branch = -1
"""
