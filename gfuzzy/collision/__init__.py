"""The static collision model (python-fcl), robot shapes, certified motions, robot-mover distances."""
