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


# A corridor with two static discs on the line y = 1 and a mover crossing it: a robot
# driving straight along y = 1 hits the first disc at x = 3, the second at x = 6.
LINE = """
version: 1
name: line
bounds: [0, 0, 10, 3]
robot: {disc: 0.2, vmax: 1.0, amax: 1.5}
obstacles:
  - disc: {center: [3.0, 1.0], radius: 0.1}
  - disc: {center: [6.0, 1.0], radius: 0.3}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[8, 0.2], [8, 2.8]], mode: bounce}
queries:
  - {name: up, start: [1.0, 2.5], goal: [9.0, 2.5]}
"""


# a room with a door 0.8 wide in a wall at x = 3
DOOR = """
version: 1
name: door
bounds: [0, 0, 6, 3]
robot: {disc: 0.2, vmax: 1.0, clearance: 0.05}
obstacles:
  - box: {center: [3, 0.55], size: [0.2, 1.1]}
  - box: {center: [3, 2.45], size: [0.2, 1.1]}
  - disc: {center: [1.5, 1.5], radius: 0.3}
queries:
  - {name: q, start: [0.5, 1.5], goal: [5.5, 1.5]}
"""


CROSSING = """
version: 1
name: crossing
bounds: [0, 0, 6, 6]
robot: {disc: 0.25, vmax: 1.0}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[3, 0.5], [3, 5.5]], mode: bounce}
  - {name: ped, disc: 0.3, trajectory: [[0, 0.2, 1.0], [10, 5.8, 4.0]]}
queries:
  - {name: across, start: [0.5, 3.0], goal: [5.5, 3.0]}
"""


# a person walks east along y = 1.0 at 1.3 m/s; at t0 = 2 it is at x = 2.6
PERSON = """
version: 1
name: person
bounds: [0, 0, 6, 6]
robot: {disc: 0.25, vmax: 1.0}
movers:
  - {name: ped, disc: 0.3, trajectory: [[0, 0.0, 1.0], [4.6, 5.98, 1.0]]}
"""
