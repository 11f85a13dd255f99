"""Many queries at once: regression runs and Dask batches."""


def __getattr__(name: str):
    # the package's modules, loaded on first use (`gfuzzy.runs.X` after `import gfuzzy`,
    # as the package's eager imports once made them)
    from .. import submodule

    return submodule(__name__, name)
