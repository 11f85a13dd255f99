"""The static collision model (python-fcl), robot shapes, certified motions, robot-mover distances."""


def __getattr__(name: str):
    # the package's modules, loaded on first use (`gfuzzy.collision.X` after `import gfuzzy`,
    # as the package's eager imports once made them)
    from .. import submodule

    return submodule(__name__, name)
