"""Build hook (the project is configured in pyproject.toml): the bundled examples, the
repository's ``scenes/``, ``roadmaps/`` and ``data/`` folders, go into the wheel as
``gfuzzy/examples/``, so that ``gfuzzy examples DIR`` can copy them for a user who installed
the package without the repository. An editable install reads them from the repository."""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

EXAMPLES = ("scenes", "roadmaps", "data")


class BuildWithExamples(build_py):
    def run(self):
        editable = getattr(self, "editable_mode", False)
        if not editable:
            # `pip install .` and `pip wheel .` build in ./build, and a file an earlier build
            # put there stayed in every later wheel: a module since moved or deleted, a scene
            # since removed from scenes/ (found by s39-newuser): the package is built afresh
            shutil.rmtree(Path(self.build_lib) / "gfuzzy", ignore_errors=True)
        super().run()
        if editable:
            return
        here = Path(__file__).resolve().parent
        target = Path(self.build_lib) / "gfuzzy" / "examples"
        for name in EXAMPLES:
            if (here / name).is_dir():
                shutil.copytree(here / name, target / name, dirs_exist_ok=True,
                                ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))


setup(cmdclass={"build_py": BuildWithExamples})
