"""Navigation when the movers' future is unknown: the Navigator, sensing, its simulation, simulated people, crowd benchmarks and social metrics, populating scenes with people."""


def __getattr__(name: str):
    # the package's modules, loaded on first use (`gfuzzy.navigation.X` after `import gfuzzy`,
    # as the package's eager imports once made them)
    from .. import submodule

    return submodule(__name__, name)
