"""Navigation when the movers' future is unknown: the Navigator, sensing, its simulation, simulated people, crowd benchmarks and social metrics, populating scenes with people."""
