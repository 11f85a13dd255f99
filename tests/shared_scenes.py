"""Scene texts that several test modules use (importable: conftest puts tests/ on the path)."""

# the cart runs a loop through the goal (4, 3) every 10 s, first at t = 4, just after the
# earliest arrival (3 m at 1 m/s): a robot that parks there must wait, or is run over
LOOP = """
version: 1
name: loop
bounds: [0, 0, 6, 6]
robot: {disc: 0.25, vmax: 1.0}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[4, 1], [4, 5], [5, 5], [5, 1]], mode: loop, offset: 8.0}
queries:
  - {name: park, start: [1, 3], goal: [4, 3], hold: 2.0}
"""
