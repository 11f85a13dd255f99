# Everything a fresh machine needs: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test slow lint clean bench warm experiments roadmaps

# Python writes a module's bytecode (a __pycache__ folder beside it: in the virtualenv, and in
# the source tree, where git ignores it) the first time a process imports it, and every later
# process reads it, even where the calling shell sets PYTHONDONTWRITEBYTECODE: with it, every
# test process compiled gfuzzy's modules again (0.4 s of a `gfuzzy plan` process's 1.2 s) and
# each pytest worker rewrote every test module's asserts (15 s of the 23 s of its collection)
unexport PYTHONDONTWRITEBYTECODE

# --no-compile: pip compiles every .py file it installs to bytecode (6,500 files: 80 of the
# 110-145 s of a fresh install on the busy 2-core machine); Python writes the bytecode of the
# modules imported instead (above), a tenth of them
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --no-compile --upgrade pip
	$(BIN)/python -m pip install --quiet --no-compile -e '.[test]'
	touch $(STAMP)

$(VENV): $(STAMP)

# compiles the search kernels once (numba's on-disk cache) and builds them ahead of time
# (gfuzzy.timespace.precompile: an extension module loaded in ~1 ms instead of numba's 0.3-0.9 s),
# so no query pays for either; and numba's GA kernels and the navigator's priced search
# (soft_kernel, numba only: ~10 s to compile, paid by the first --soft-search run or test worker).
# The GA's kernels share nothing with the search's, so they compile on the other core while
# the search's are built (about 2 minutes); soft_kernel calls the search's (movers_kernel), so
# it compiles once numba has compiled those: --beside runs its warm in a second process during
# the ahead-of-time compile (the other core, idle then), and the line after it only loads
# what that cached (or compiles it, when the build failed)
warm: $(STAMP)
	$(BIN)/python -c 'import gfuzzy.ga.refine as r; r.warm()' & ga=$$!; \
	$(BIN)/python -m gfuzzy.timespace.precompile --beside gfuzzy.timespace.soft_kernel || echo "precompiled kernels not built (no C compiler?): numba's are used"; \
	wait $$ga
	$(BIN)/python -c 'import gfuzzy.timespace.soft_kernel as s; s.warm()'

demo: warm
	$(BIN)/python tools/demo.py

# the suite on every core (pytest-xdist; TEST_WORKERS=0 runs it in this one process); `warm`
# has built the kernels before the workers start. --dist worksteal: an idle worker takes tests
# from the other's queue, so a long file does not leave a core idle at the end (two idle
# cores: 385 s of pytest in a clone already run once, against 507 s with --dist loadfile,
# which kept each file on one worker; in a fresh clone 486 s against 488 s: no worse, the
# gain not shown there); tests/conftest.py puts the tests marked long first; the 25 slowest
# tests are listed at the end (where the suite's time goes, for the next cut)
# The collection beside `make warm` (which leaves a core idle for part of its time) writes
# the bytecode of the modules the workers import and of the test modules with their asserts
# rewritten: each worker's collection then takes 7 s, not 23 s. (`make -n test` runs `warm`
# and the collection: a line that calls $(MAKE) runs under -n.)
TEST_WORKERS ?= auto
test: $(STAMP)
	$(BIN)/python -m pytest -q --collect-only -p no:cacheprovider >/dev/null 2>&1 & c=$$!; \
	$(MAKE) --no-print-directory warm; w=$$?; wait $$c; exit $$w
	$(BIN)/ruff check gfuzzy tests tools
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist worksteal --durations=25

# the slow tests (@pytest.mark.slow, left out of `make test`): experiments over every bundled scene
slow: warm
	PYTHON=$(BIN)/python tools/run_slow.sh

# the bundled roadmaps (roadmaps/*.json) rebuilt with this code from the options each stores
# (tools/bundled_roadmaps.py; --check only compares); then `gfuzzy regress scenes/*.yaml`
roadmaps: $(STAMP)
	$(BIN)/python tools/bundled_roadmaps.py

lint: $(STAMP)
	$(BIN)/ruff check gfuzzy tests tools

bench: $(STAMP)
	$(BIN)/python tools/bench_roadmap.py
	$(BIN)/python tools/bench_plan.py

# The paper's experiments on Dask: rewrites docs/results.md and docs/img/{table1,fig12,fig14-*}.png
experiments: $(STAMP)
	$(BIN)/python -m tools.experiments

clean:
	rm -rf $(VENV) out build *.egg-info
